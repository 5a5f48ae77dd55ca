"""Instrument files as they come (surface/readers.py, lines chosen by surface/lines.py), MDAnalysis style: one contract class,
inherited once per shipped format with that file's known answers (sizes, units, missing points, a θa).

The files are real instrument exports from SurfaceTopography's test corpus (tests/data/profiles/
README.md). Known θa values were computed once with this code (D50 chosen per file so that the
trace has normals beyond the 92° filter) and are pinned to 0.05°: a change in reading (units,
orientation, missing points) or in the θa rule moves them.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from interphase.case import Case
from interphase.cli import main
from interphase.engines.liggghts import Liggghts
from interphase.errors import InputError
from interphase.surface.builder import file_spec, from_spec
from interphase.surface.lines import line_profile, parse_line, spread_index
from interphase.surface.normals import theta_a_filters
from interphase.surface.profiles import selfaffine_profile
from interphase.surface.readers import read_profile, read_scan
from interphase.surface.spec import ProfileSpec

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"
PROFILES = DATA / "profiles"
FRT1 = ROOT / "campaigns" / "profiles" / "frt-1.frt"
D50 = 0.7e-3


class FormatContract:
    path: Path
    shape: tuple
    units: str
    extent_mm: tuple          # last grid position along x (and y), mm
    missing: int
    d50_mm: float
    theta_a: float            # ψa [deg] of `campaign theta-a --d50 d50_mm` (areal: +x)
    reader: str

    @pytest.fixture(scope="class")
    @classmethod
    def scan(cls):
        return read_scan(cls.path)

    @pytest.fixture(scope="class")
    @classmethod
    def cli(cls):
        import contextlib
        import io

        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            assert main(["theta-a", str(cls.path), "--d50", str(cls.d50_mm), "--json"]) == 0
        return json.loads(buf.getvalue())

    def test_sizes(self, scan):
        assert scan.shape == self.shape

    def test_units_from_the_file_in_metres(self, scan):
        assert scan.units == self.units
        assert scan.x[-1] * 1e3 == pytest.approx(self.extent_mm[0], rel=1e-3)
        if scan.areal:
            assert scan.y[-1] * 1e3 == pytest.approx(self.extent_mm[1], rel=1e-3)
        assert np.all(np.diff(scan.x) > 0)

    def test_missing_points_are_nan(self, scan):
        assert scan.n_missing == self.missing
        assert np.all(np.isfinite(scan.heights) | np.isnan(scan.heights))

    def test_reader(self, scan):
        assert self.reader in scan.reader

    def test_theta_a_known_answer(self, cli):
        assert cli["dilative"] is True
        assert cli["theta_a_deg"] == pytest.approx(self.theta_a, abs=0.05)
        assert cli["areal"] is (len(self.shape) == 2)


class TestDektakCSV(FormatContract):
    path = DATA / "dektak-1.csv"
    shape, units, extent_mm, missing, reader = (9600,), "µm", (1.4998,), 0, "SurfaceTopography"
    d50_mm, theta_a = 0.01, 3.469

    def test_same_points_as_the_former_project_parser(self, scan):
        # the project's own Dektak parser gave these (tests/test_surface_io.py): SurfaceTopography agrees
        assert scan.heights[-1] == pytest.approx(16.58112e-6)
        assert scan.heights[0] == pytest.approx(-0.00933e-6)


class TestOPDx(FormatContract):
    path = PROFILES / "opdx-3.opdx"
    shape, units, extent_mm, missing, reader = (3001,), "µm", (0.04997,), 0, "OPDx"
    d50_mm, theta_a = 0.002, 2.014


class TestHFM(FormatContract):
    path = PROFILES / "hfm-1.hfm"
    shape, units, extent_mm, missing, reader = (9600,), "mm", (4.7995,), 0, "SurfaceTopography"
    d50_mm, theta_a = 0.7, 2.321


class TestMitutoyo(FormatContract):
    path = PROFILES / "mitutoyo_2_mock.xlsx"
    shape, units, extent_mm, missing, reader = (6664,), "µm", (9.9945,), 0, "Mitutoyo"
    d50_mm, theta_a = 0.7, 4.526


class TestFRTSquare(FormatContract):
    path = FRT1
    shape, units, extent_mm, missing, reader = (500, 500), "m", (11.976, 11.976), 76456, "FRT"
    d50_mm, theta_a = 0.7, 3.851

    def test_four_directions(self, cli):
        d = cli["directions"]
        assert [d[k]["theta_a_deg"] for k in ("+x", "-x", "+y", "-y")] == pytest.approx(
            [3.851, 3.821, 5.455, 5.441], abs=0.05)
        assert d["+x"]["n_runs"] == 420 and d["+x"]["n_dropped"] == 38
        assert d["+y"]["n_runs"] == 421 and d["+y"]["n_dropped"] == 598


class TestFRTRectangular(FormatContract):
    path = PROFILES / "frt-2.frt"
    shape, units, extent_mm, missing, reader = (150, 300), "m", (29.8, 59.8), 12314, "FRT"
    d50_mm, theta_a = 0.2, 16.860

    def test_anisotropy_at_a_glance(self, cli):
        d = cli["directions"]
        assert d["+x"]["theta_a_deg"] - d["-x"]["theta_a_deg"] == pytest.approx(16.860 - 12.801, abs=0.1)
        assert d["+x"]["n_lines"] == 300 and d["+y"]["n_lines"] == 150


class TestSUR(FormatContract):
    path = PROFILES / "sur-2.sur"
    shape, units, extent_mm, missing, reader = (563, 484), "mm", (1.9580, 1.6828), 117, "SUR"
    d50_mm, theta_a = 0.05, 4.895


# ---- bad files: one message naming the file and the fix, exit 2 ---------------------------------
def _run(argv, capsys):
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    return code, err


def test_a_file_no_reader_takes(tmp_path, capsys):
    f = tmp_path / "scan.bin"
    f.write_bytes(bytes(range(256)) * 40)
    code, err = _run(["theta-a", f, "--d50", "0.7"], capsys)
    assert code == 2 and str(f) in err and "SurfaceTopography cannot read" in err and "export it" in err


def test_a_line_shorter_than_one_grain(capsys):
    f = PROFILES / "opdx-3.opdx"
    code, err = _run(["theta-a", f, "--d50", "0.7"], capsys)
    assert code == 2 and str(f) in err and "shorter than one grain" in err and "smaller --d50" in err


def test_a_scan_with_no_valid_run(capsys):
    f = PROFILES / "sur-2.sur"
    code, err = _run(["theta-a", f, "--d50", "0.7"], capsys)
    assert code == 2 and str(f) in err and "no valid run" in err and "3.5 mm" in err and "smaller --d50" in err


def test_unknown_units(tmp_path, capsys):
    f = tmp_path / "line.hfm"
    text = (PROFILES / "hfm-1.hfm").read_text().replace("[mm];[mm]", "[furlong];[furlong]", 1)
    f.write_text(text)
    code, err = _run(["theta-a", f, "--d50", "0.7"], capsys)
    assert code == 2 and str(f) in err and "units" in err and "--units" in err
    # the fix works: given units, the same file reads
    assert read_scan(f, units="mm").x[-1] == pytest.approx(4.7995e-3, rel=1e-3)


def test_cutoff_and_axis_refusals(capsys):
    code, err = _run(["theta-a", FRT1, "--d50", "0.7", "--cutoff", "2"], capsys)
    assert code == 2 and "--cutoff" in err
    code, err = _run(["theta-a", PROFILES / "hfm-1.hfm", "--d50", "0.7", "--axis", "y"], capsys)
    assert code == 2 and "--axis" in err


def test_an_areal_scan_is_not_a_line():
    with pytest.raises(InputError, match="areal scan"):
        read_profile(FRT1)


# ---- measured lines into simulations -----------------------------------------------------------
def test_line_choice_by_index_or_spread():
    assert [spread_index(500, k, 3) for k in (1, 2, 3)] == [83, 250, 416]
    assert parse_line("2/3", 500, "x") == 250 and parse_line(-1, 500, "x") == 499
    for bad in ("4/3", "a", 500, 1.5, True):
        with pytest.raises(InputError):
            parse_line(bad, 500, "line")


def test_spec_builds_the_levelled_longest_run_and_its_mirror():
    spec = file_spec(FRT1, units=None, axis="x", line="1/3")
    rev = file_spec(FRT1, units=None, axis="x", line="1/3", direction="-")
    assert spec.canonical() != rev.canonical() and spec.label() == "frt-1-x1of3" and rev.label().endswith("-rev")
    p, q = from_spec(spec, D50, 0.0), from_spec(rev, D50, 0.0)
    assert p.x[0] == 0 and abs(np.polyfit(p.x, p.z, 1)[0]) < 1e-9           # levelled
    np.testing.assert_allclose(q.z, p.z[::-1])                                # mirrored
    scan = read_scan(FRT1)
    _, Z = scan.lines("x")
    row = Z[83]
    ok = np.isfinite(row)
    runs = np.split(np.flatnonzero(ok), np.flatnonzero(np.diff(np.flatnonzero(ok)) > 1) + 1)
    assert p.x.size == max(len(r) for r in runs)                               # the longest valid run
    # θa of the line and of its mirror: the faces read are the other ones
    a, b = theta_a_filters(p, D50)[92], theta_a_filters(q, D50)[92]
    assert a.dilative and b.dilative and a.theta_a_deg == pytest.approx(3.88, abs=0.1)


def test_old_file_specs_keep_their_identity(dektak_csv):
    spec = file_spec(dektak_csv, units="um")
    assert set(spec.canonical()) == {"kind", "sha256", "units", "cutoff"}


def test_a_line_outside_the_scan_is_refused_at_load():
    with pytest.raises(InputError, match="outside the scan"):
        file_spec(FRT1, units=None, axis="y", line=500)


SMALL = dict(shear_modulus=50e6, n_grains=200, box_length_d50=20, box_height_d50=10, shear_distance=2e-3,
             snapshot_every=0.5e-3, friction_ps=0.5)


@pytest.mark.parametrize("path,axis,device", [
    (FRT1, "x", "walled"), (FRT1, "x", "periodic"), (PROFILES / "frt-2.frt", "y", "walled")])
def test_a_case_on_a_measured_line_renders(path, axis, device):
    spec = file_spec(path, units=None, axis=axis, line="2/3")
    case = Case(profile=spec, device=device, **SMALL)
    surf = case.surface()
    assert surf.periodic is (device == "periodic")
    files = Liggghts().render(case)
    assert "in.deck" in files and ("surface.stl" in files if device == "periodic" else True)


def test_a_line_with_an_edge_step_closes_at_its_mean_height():
    # frt-2's y line 2/3 starts on an edge value it never meets again: the periodic cell is cut
    # between crossings of the line's mean height instead (surface.profiles.close)
    spec = file_spec(PROFILES / "frt-2.frt", units=None, axis="y", line="2/3")
    case = Case(profile=spec, device="periodic", **SMALL)
    s = case.surface()
    assert s.periodic and s.z[0] == s.z[-1] and abs(case.box_length / case.d50 - SMALL["box_length_d50"]) < 5


def test_selfaffine_kind():
    spec = ProfileSpec.make("selfaffine", hurst=0.8, rms_slope=0.5, long_cutoff=10, short_cutoff=0.8, length=30,
                            seed=4)
    p = from_spec(spec, D50, 50 * D50)
    assert p.periodic and p.length == pytest.approx(60 * D50)               # two periods tiled
    q = selfaffine_profile(0.8, 0.5, 10, 0.8, 30, 4, d50=D50)
    np.testing.assert_array_equal(p.z[: q.z.size], q.z)                    # a pure function of the seed
    slope = np.diff(q.z) / np.diff(q.x)
    assert math.sqrt(np.mean(slope ** 2)) == pytest.approx(0.5, rel=0.25)
    other = selfaffine_profile(0.8, 0.5, 10, 0.8, 30, 5, d50=D50)
    assert not np.allclose(other.z, q.z)
    assert Case(profile=spec, device="periodic", **SMALL).surface().periodic
    with pytest.raises(InputError):
        ProfileSpec.make("selfaffine", hurst=1.2, rms_slope=0.5, long_cutoff=10, short_cutoff=0.8, length=30, seed=1)
    # a grid finer than the grains' contact scale (short_cutoff/8 < 0.1 D50) is refused, naming the fix
    with pytest.raises(InputError, match="finer than the 0.1 D50") as e:
        ProfileSpec.make("selfaffine", hurst=0.8, rms_slope=0.5, long_cutoff=10, short_cutoff=0.2, length=30, seed=4)
    assert "short_cutoff ≥ 0.8" in e.value.fix and e.value.where.endswith("short_cutoff")


@pytest.mark.liggghts
def test_a_measured_line_runs_through_the_engine(tmp_path):
    """Group 5's path for real: a grid line of a shipped FRT scan (mm relief, missing points) as the
    periodic device's surface, through LIGGGHTS, to a summary — tiny (16 × 8 D50, 1 mm of shear)."""
    from interphase.campaign.runner import run_single

    from .conftest import need_binary

    need_binary("liggghts")
    spec = file_spec(ROOT / "campaigns" / "profiles" / "frt-2.frt", units=None, axis="x", line="2/3",
                     direction="-")
    case = Case(profile=spec, device="periodic", box_length_d50=16, box_height_d50=8, shear_distance=1e-3,
                snapshot_every=5e-4, shear_modulus=50e6, friction_ps=0.5)
    res = run_single(case, "liggghts", tmp_path / "case")
    assert res["status"] == "done", res
    s = res["summary"]
    assert 0.05 < s["peak_stress_ratio"] < 1.5 and s["n_contacts_surface"] > 0 and s["grains_left"] == 0
    assert s["rn"] < 0.01               # the scan's line: nearly flat at D50 0.7 mm, as theta-a says
