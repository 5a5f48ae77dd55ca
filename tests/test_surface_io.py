"""Profile readers, the CLI's surface commands, bad input (exit code 2, one message), STL export."""

import json
import math

import meshio
import numpy as np
import pytest

from interphase.cli import main
from interphase.errors import InputError
from interphase.surface.builder import file_spec, from_spec
from interphase.surface.filters import centerline, gaussian_filter
from interphase.surface.mesh import write_stl
from interphase.surface.profiles import random_profile, sawtooth, tile
from interphase.surface.readers import read_profile, read_scan
from interphase.surface.spec import ProfileSpec

D50 = 0.7e-3


def test_dektak_reader(dektak_csv):
    p = read_profile(dektak_csv)           # units from the file's "Lateral um" header
    assert p.x.size == 9600
    assert p.length == pytest.approx(1499.8e-6)
    assert np.all(np.diff(p.x) > 0)
    assert p.z[-1] == pytest.approx(16.58112e-6)


def test_dektak_theta_a_cli_says_non_dilative(dektak_csv, capsys):
    assert main(["theta-a", str(dektak_csv), "--d50", "0.7", "--units", "um", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["dilative"] is False and out["theta_a_deg"] is None
    assert "non-dilative" in out["reason"]
    assert out["max_tilt_deg"] < 2.0         # every trace normal within the 92° filter's 2°
    assert out["rnc"] < 0.01


def test_a_file_read_again_is_the_same_scan_until_its_bytes_change(tmp_path):
    """read_scan keeps the last scans by path, units and content: the same bytes give the same Scan
    (read-only arrays, so no caller can change another's), new bytes or other units a new one."""
    f = tmp_path / "p.txt"
    f.write_text("0 0\n1 0.5\n2 0\n")
    a = read_scan(f)
    assert read_scan(f) is a and not a.heights.flags.writeable and not a.x.flags.writeable
    with pytest.raises(ValueError):
        a.heights[0] = 1.0
    assert read_scan(f, units="um") is not a and read_scan(f, units="um").heights[1] == pytest.approx(0.5e-6)
    f.write_text("0 0\n1 0.7\n2 0\n")
    b = read_scan(f)
    assert b is not a and b.heights[1] == pytest.approx(0.7e-3) and a.heights[1] == pytest.approx(0.5e-3)


def test_plain_text_with_header_and_units(tmp_path):
    f = tmp_path / "p.csv"
    x = np.linspace(0, 10, 101)
    f.write_text("x_mm,z_mm\n" + "\n".join(f"{a},{b}" for a, b in zip(x, np.sin(x))))
    p = read_profile(f, units="mm")
    assert p.x[-1] == pytest.approx(10e-3) and p.z.max() == pytest.approx(np.sin(x).max() * 1e-3)
    f2 = tmp_path / "p.txt"
    f2.write_text("# comment\n" + "\n".join(f"{a}\t{b}" for a, b in zip(x, np.sin(x))))
    assert read_profile(f2, units="um").x[-1] == pytest.approx(10e-6)


BAD = {
    "empty": ("", "empty"),
    "one_column": ("1\n2\n3\n", "one column"),
    "text": ("0 1\n1 2\n2 abc\n3 4\n", "line 3"),
    "non_monotonic": ("0 1\n1 2\n0.5 3\n2 4\n", "line 3"),
    "nan": ("0 1\n1 nan\n2 3\n", "NaN"),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_profile_files_exit_2(tmp_path, capsys, name):
    content, needle = BAD[name]
    f = tmp_path / f"{name}.txt"
    f.write_text(content)
    assert main(["theta-a", str(f), "--d50", "0.7"]) == 2
    err = capsys.readouterr().err
    assert str(f) in err and needle in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("args,needle", [
    (["--d50", "0"], "--d50"), (["--d50", "-1"], "--d50"), (["--d50", "0.7", "--units", "inch"], "--units"),
])
def test_bad_options_exit_2(tmp_path, capsys, args, needle):
    f = tmp_path / "ok.txt"
    f.write_text("\n".join(f"{i} {math.sin(i)}" for i in range(50)))
    assert main(["theta-a", str(f), *args]) == 2
    assert needle in capsys.readouterr().err


def test_profile_generate_then_theta_a(tmp_path, capsys):
    out = tmp_path / "saw.txt"
    assert main(["profile", "sawtooth", "--rt", "1", "--sw", "2", "--length", "14", "-o", str(out)]) == 0
    assert main(["theta-a", str(out), "--d50", "0.7", "--json"]) == 0
    res = json.loads(capsys.readouterr().out.split("\n", 1)[1])
    # an open (file) profile loses r at each end, so close to, not exactly, the periodic 39.35°
    assert res["theta_a_deg"] == pytest.approx(39.35, abs=1.0)
    png = tmp_path / "saw.png"
    assert main(["profile", "plot", str(out), "-o", str(png)]) == 0
    assert png.stat().st_size > 10_000


def test_random_profile_is_pure_and_bounded():
    a = random_profile(2, 1, 2, d50=D50, length=40 * D50, seed=11)
    b = random_profile(2, 1, 2, d50=D50, length=40 * D50, seed=11)
    c = random_profile(2, 1, 2, d50=D50, length=40 * D50, seed=12)
    np.testing.assert_array_equal(a.z, b.z)
    assert not np.array_equal(a.z[:5], c.z[:5])
    assert a.z.min() >= 0 and a.z.max() <= 2 * D50 + 1e-15 and a.length >= 40 * D50
    assert np.all(np.abs(np.diff(a.z)) > 0)      # bound rule never makes a flat segment
    dx = np.diff(a.x) / D50
    assert dx.max() <= 2 * 1.5 + 1e-12
    slope = np.abs(np.diff(a.z)) / np.diff(a.x)        # ar·k, k in [0.5, 1.5]: kept when clipped
    assert slope.min() >= 0.5 - 1e-9 and slope.max() <= 1.5 + 1e-9


def test_random_profile_longer_extends_shorter():
    # the engine asks for the box plus its travel, the analysis for less: one surface for both
    short = random_profile(2, 1, 2, d50=D50, length=20 * D50, seed=5)
    long = random_profile(2, 1, 2, d50=D50, length=70 * D50, seed=5)
    n = short.x.size
    np.testing.assert_array_equal(long.x[:n], short.x)
    np.testing.assert_array_equal(long.z[:n], short.z)


def test_random_profiles_differ_when_every_step_overshoots_the_band():
    # Table 6.2's D (Ar 2) and G (Ar 4) share Au = 4 and Rtmax = 4: every step is longer than the
    # band, so each segment is clipped; they must still differ by their slope
    d = random_profile(4, 2, 4, d50=D50, length=40 * D50, seed=1)
    g = random_profile(4, 4, 4, d50=D50, length=40 * D50, seed=1)
    slope_d = np.degrees(np.arctan(np.abs(np.diff(d.z) / np.diff(d.x)))).mean()
    slope_g = np.degrees(np.arctan(np.abs(np.diff(g.z) / np.diff(g.x)))).mean()
    assert 55 < slope_d < 68 and 70 < slope_g < 80


def test_from_spec_covers_length_and_tiles_measured(dektak_csv):
    for spec in (ProfileSpec.make("flat"), ProfileSpec.make("sawtooth", rt=1, sw=2, sr=1),
                 ProfileSpec.make("random", au=2, ar=1, rtmax=2, seed=1),
                 file_spec(dektak_csv, units="um")):
        p = from_spec(spec, D50, 30e-3)
        assert p.x[0] == 0 and p.length >= 30e-3
    t = tile(read_profile(dektak_csv), 5e-3)
    assert np.all(np.diff(t.x) > 0)


def test_a_spec_is_data_and_the_builder_hashes_the_file(tmp_path, dektak_csv):
    import hashlib

    digest = hashlib.sha256(dektak_csv.read_bytes()).hexdigest()
    # a spec reads nothing: a path that does not exist makes a spec all the same
    spec = ProfileSpec(kind="file", path=str(tmp_path / "nowhere.csv"), units="um", sha256=digest)
    assert spec.canonical()["sha256"] == digest and spec.label() == "nowhere"
    with pytest.raises(InputError, match="SHA-256"):
        ProfileSpec(kind="file", path=str(dektak_csv), units="um")
    with pytest.raises(InputError, match="unknown units 'nm'"):
        ProfileSpec(kind="file", path=str(dektak_csv), units="nm", sha256=digest)
    # the builder of specs from user input hashes the file: same content, same identity
    built = file_spec(dektak_csv, units="um")
    assert built.sha256 == digest
    copy = tmp_path / "copy.csv"
    copy.write_bytes(dektak_csv.read_bytes())
    assert file_spec(copy, units="um").canonical() == built.canonical()
    with pytest.raises(InputError, match="does not exist"):
        file_spec(tmp_path / "nowhere.csv")


def test_centerline_and_gaussian_filter():
    x = np.linspace(0, 10e-3, 5001)
    z = 1e-3 + 0.05 * x + 1e-6 * np.sin(2 * np.pi * x / 0.1e-3) + 20e-6 * np.sin(2 * np.pi * x / 5e-3)
    from interphase.surface.profiles import Profile
    c = centerline(Profile(x, z))
    assert abs(np.polyfit(c.x, c.z, 1)[0]) < 1e-9
    r = gaussian_filter(c, 0.8e-3)                 # λc = 0.8 mm keeps 0.1 mm, removes 5 mm waves
    mid = slice(1000, 4000)
    # ISO 16610-21 roughness transmission 1 − exp(−π (α λc/λ)²), α = sqrt(ln2/π): 50 % at λ = λc
    alpha2 = math.log(2) / math.pi
    t = lambda lam: 1 - math.exp(-math.pi * alpha2 * (0.8e-3 / lam) ** 2)  # noqa: E731
    expected = math.sqrt(0.5 * (1e-6 * t(0.1e-3)) ** 2 + 0.5 * (20e-6 * t(5e-3)) ** 2)
    assert np.std(r.z[mid]) == pytest.approx(expected, rel=0.02)
    assert t(0.8e-3) == pytest.approx(0.5)


# meshio first tries an ASCII STL as binary: its size check overflows a uint32 (harmless)
@pytest.mark.filterwarnings("ignore:overflow encountered in scalar multiply:RuntimeWarning")
def test_stl_roundtrip_normals_up(tmp_path):
    p = sawtooth(1, 2, 1, d50=D50, periods=2)
    f = write_stl(p, tmp_path / "s.stl", -0.5e-3, 0.5e-3)
    assert f.read_text().startswith("solid")
    m = meshio.read(f)
    tri = m.cells_dict["triangle"]
    assert tri.shape == (2 * (p.x.size - 1), 3)
    a, b, c = (m.points[tri[:, i]] for i in range(3))
    n = np.cross(b - a, c - a)
    assert np.all(n[:, 2] > 0)
    assert m.points[:, 1].min() == pytest.approx(-0.5e-3) and m.points[:, 1].max() == pytest.approx(0.5e-3)


def test_a_random_case_measures_the_surface_its_engine_shears():
    # the deck's surface (Case.surface, with margins and the shear's travel) and the stretch the
    # summary measures (Case.sheared_surface) come from one profile: same heights where they overlap
    from interphase.case import Case

    case = Case(profile=ProfileSpec.make("random", au=2, ar=0.5, rtmax=2, seed=3), box_length_d50=30,
                shear_distance=4e-3, snapshot_every=1e-3)
    whole, sheared = case.surface(), case.sheared_surface()
    assert whole.x[0] == pytest.approx(-case.surface_margin) and whole.x[-1] >= case.box_length + 4e-3
    assert sheared.x[0] == 0.0 and sheared.x[-1] == pytest.approx(case.box_length + 4e-3)
    np.testing.assert_allclose(np.interp(sheared.x, whole.x, whole.z), sheared.z, atol=1e-15)


def test_a_line_gives_theta_a_for_shear_both_ways(tmp_path, capsys):
    """A ratchet (steep flanks facing +x, gentle ones facing −x) resists differently in +x and −x;
    a symmetric saw-tooth the same both ways. −x is the mirrored line, as an independent check."""
    from interphase.surface.normals import theta_a
    from interphase.surface.profiles import Profile

    x = np.linspace(0, 14.0, 14001)                     # mm; teeth 2 mm long, 1 mm high
    ratchet = np.where((x % 2.0) < 1.6, (x % 2.0) / 1.6, (2.0 - x % 2.0) / 0.4)
    f = tmp_path / "ratchet.txt"
    f.write_text("\n".join(f"{a} {b}" for a, b in zip(x, ratchet)))
    assert main(["theta-a", str(f), "--d50", "0.7", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)["directions"]
    plus, minus = d["+x"]["theta_a_deg"], d["-x"]["theta_a_deg"]
    assert abs(plus - minus) > 5.0, (plus, minus)
    mirrored = theta_a(Profile(-x[::-1] * 1e-3, ratchet[::-1] * 1e-3), 0.7e-3)
    assert minus == pytest.approx(mirrored.theta_a_deg, abs=0.2)     # the reader levels the line first
    assert main(["theta-a", str(f), "--d50", "0.7"]) == 0
    text = capsys.readouterr().out
    assert "θa (+x)" in text and "θa (-x)" in text
