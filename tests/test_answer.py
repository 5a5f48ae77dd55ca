"""`campaign predict --soil CARD`: the one answer (interphase.answer) — tan φ at the asked stress and
density from the card's strength table, two 95 % prediction intervals with their parts, and the
guards that catch a user's slip (exit 2 naming the fix; the API refuses the same)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

import interphase as ip
from interphase.answer import interval_coverage, residual
from interphase.cli import main
from interphase.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
DEKTAK = ROOT / "campaigns" / "profiles" / "dektak-1.csv"
CARD = ROOT / "soils" / "karlsruhe-fine-sand.toml"
FIT3D = ROOT / "studies" / "kfs_group1_3d" / "results" / "criterion.json"
RECORD = ROOT / "lab" / "soils" / "karlsruhe-fine-sand" / "drained-triaxial" / "TMD11.dat"


def _run(capsys, *argv) -> tuple[int, str, str]:
    code = main(list(map(str, argv)))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def card_with_table(tmp_path) -> Path:
    """The 3D card with a strength table over 50–400 kPa at two preparations: tan φ falling with
    stress and with the looser preparation (values of the kind the card's soil test reads)."""
    table = tmp_path / "strength.csv"
    table.write_text("normal_stress,preparation,tan_phi,tan_phi_lo,tan_phi_hi,seeds\n"
                     "50000,0.387,0.74,0.72,0.76,4\n100000,0.387,0.70,0.68,0.72,8\n400000,0.387,0.64,0.62,0.66,4\n"
                     "50000,0.62,0.68,0.66,0.70,4\n100000,0.62,0.65,0.63,0.67,4\n400000,0.62,0.60,0.58,0.62,4\n")
    card = tmp_path / "kfs.toml"
    card.write_text(CARD.read_text().split("\n[criterion]")[0]
                    + f'\n[criterion]\nfit = "{FIT3D}"\nstrength = "{table}"\n')
    return card


def test_stress_and_density_move_the_answer_where_the_sands_strength_moves(card_with_table, capsys):
    """The issue's command: δ with both intervals, their parts, the stress and φ used; at 50 and
    400 kPa δ differs as the card's tan φ does; a stress or density outside the table is refused."""
    got = {}
    for s in (50e3, 200e3, 400e3):
        code, out, err = _run(capsys, "predict", DEKTAK, "--soil", card_with_table, "--friction", 0.3,
                              "--normal-stress", s, "--json")
        assert code == 0, err
        got[s] = d = json.loads(out)
        assert d["normal_stress"] == s and d["phi_deg"] == pytest.approx(math.degrees(math.atan(d["tan_phi"])))
        assert d["delta_deg_lo"] < d["model_delta_deg_lo"] < d["delta_deg"] < d["model_delta_deg_hi"] < d["delta_deg_hi"]
        assert set(d["parts_deg"]) == {"fit", "residual", "tan_phi", "card"} and all(v > 0 for v in d["parts_deg"].values())
    assert got[50e3]["tan_phi"] > got[200e3]["tan_phi"] > got[400e3]["tan_phi"]
    assert got[50e3]["delta_deg"] > got[200e3]["delta_deg"] > got[400e3]["delta_deg"]
    # the same efficiency: only tan φ moved (E as fitted; whether it moves is the study's question)
    assert got[50e3]["efficiency"] == pytest.approx(got[400e3]["efficiency"], rel=1e-9)
    dense = got[200e3]
    code, out, _ = _run(capsys, "predict", DEKTAK, "--soil", card_with_table, "--friction", 0.3, "--normal-stress", 200e3,
                        "--relative-density", 0.65, "--json")
    loose = json.loads(out)
    assert code == 0 and loose["preparation"] > dense["preparation"] and loose["tan_phi"] < dense["tan_phi"]
    assert loose["relative_density"] == pytest.approx(0.65, abs=1e-9)
    code, _, err = _run(capsys, "predict", DEKTAK, "--soil", card_with_table, "--friction", 0.3, "--normal-stress", 800e3)
    assert code == 2 and "--normal-stress" in err and "50–400 kPa" in err
    code, _, err = _run(capsys, "predict", DEKTAK, "--soil", card_with_table, "--friction", 0.3, "--relative-density", 0.1)
    assert code == 2 and "--relative-density" in err


def test_the_paragraph_says_what_the_answer_stands_on(card_with_table, capsys):
    code, out, err = _run(capsys, "predict", DEKTAK, "--soil", card_with_table, "--friction", 0.3, "--normal-stress", 200e3)
    assert code == 0, err
    text = out.splitlines()[0]
    for needle in ("δ = ", "95 % prediction interval of the model", "for the sand itself", "at 200 kPa", "Dr 0.",
                   "3D card", "Interval parts", "residual ±", "card ±", "Holds in:", "interface runs"):
        assert needle in text, (needle, text)
    assert "laboratory interface test" in out          # what no data here bound, said


def test_the_residual_part_is_the_branch_own(capsys, tmp_path):
    """On the plateau (E ≈ 1) the chain's held-out error is smaller than on the rising branch, and the
    interval says so: a steep tooth's residual part is narrower than a low tooth's."""
    held = json.loads(FIT3D.read_text())["held_out"]
    rising, plateau = residual(held, branch="rising"), residual(held, branch="plateau")
    assert rising.n + plateau.n == held["n"] and plateau.half_width < rising.half_width
    parts = {}
    for rt in (0.25, 2):
        saw = tmp_path / f"saw{rt}.txt"
        assert main(["profile", "sawtooth", "--rt", str(rt), "--sw", "2", "--d50", "0.14", "--length", "6",
                     "-o", str(saw)]) == 0
        capsys.readouterr()
        code, out, err = _run(capsys, "predict", saw, "--soil", CARD, "--friction", 0.2, "--json")
        assert code == 0, err
        parts[rt] = json.loads(out)["parts_deg"]["residual"]
    assert parts[2] == pytest.approx(plateau.half_width) and parts[0.25] == pytest.approx(rising.half_width)


def test_coverage_is_nested_by_unit():
    """Each unit is judged by the other units' errors: one wild group is not covered by the others'
    scale, however wide it makes theirs."""
    cases = [{"group": g, "theta_a_deg_92": 10.0, "E_predicted": 0.5, "error_deg": e}
             for g, errs in (("a", (0.5, -0.4, 0.3)), ("b", (-0.5, 0.2, 0.4)), ("c", (9.0, 8.0, -7.0)))
             for e in errs]
    c = interval_coverage({"fold": "group held out", "n": 9, "cases": cases})
    assert c["units"] == 3 and c["all"]["n"] == 9
    assert c["all"]["covered"] == pytest.approx(6 / 9)       # a and b covered by scales that include c; c not


@pytest.mark.parametrize("argv, kwargs, where, fix", [
    (["--fit", "study", "--d50", "0.7", "--friction", "0.2", "--tan-phi", "36"],
     dict(fit="study", d50=0.7e-3, friction=0.2, tan_phi=36), "--tan-phi", "tan 36° = 0.727"),
    (["--soil", CARD, "--friction", "30"], dict(soil=CARD, friction=30), "--friction", "tan 30° = 0.577"),
    (["--fit", "study", "--friction", "0.2"], dict(fit="study", friction=0.2), "--d50", "--d50 MM"),
    (["--friction", "0.2", "--d50", "0.7"], dict(friction=0.2, d50=0.7e-3), "--soil", "--soil CARD"),
    (["--fit", "study", "--d50", "0.7", "--friction", "0.2", "--normal-stress", "200e3"],
     dict(fit="study", d50=0.7e-3, friction=0.2, normal_stress=200e3), "--normal-stress", "would be ignored"),
    (["--soil", RECORD, "--friction", "0.2"], dict(soil=RECORD, friction=0.2), "TMD11.dat", "campaign calibrate"),
    (["--soil", CARD, "--friction", "0.2", "--tan-phi", "0.7"], dict(soil=CARD, friction=0.2, tan_phi=0.7),
     "--tan-phi", "drop --tan-phi"),
    (["--soil", CARD], dict(soil=CARD), "--friction", "--smooth-delta"),
])
def test_a_slip_exits_2_with_the_fix_and_the_api_refuses_it_alike(capsys, argv, kwargs, where, fix):
    code, _, err = _run(capsys, "predict", DEKTAK, *argv)
    assert code == 2 and where in err and fix in err and "Traceback" not in err, err
    with pytest.raises(InputError) as exc:
        ip.predict(DEKTAK, **kwargs)
    assert str(exc.value) in err


def test_smooth_delta_is_the_friction_of_the_plate(capsys):
    code, out, _ = _run(capsys, "predict", DEKTAK, "--soil", CARD, "--smooth-delta", 16.7, "--json")
    by_angle = json.loads(out)
    code2, out2, _ = _run(capsys, "predict", DEKTAK, "--soil", CARD, "--friction", math.tan(math.radians(16.7)), "--json")
    assert code == code2 == 0 and json.loads(out2)["delta_deg"] == pytest.approx(by_angle["delta_deg"])


def test_an_instrument_line_sampled_coarser_than_the_grain_is_refused(tmp_path, capsys):
    """The shipped Dektak export thinned to every 500th sample (~0.08 mm steps: over half a D50 of the
    Karlsruhe sand) in its own format: refused, naming the step; the full file answers, and its
    length and relief as read are printed (a µm file read as mm shows)."""
    lines = DEKTAK.read_bytes().split(b"\n")
    head = next(i for i, ln in enumerate(lines) if ln.startswith(b"Lateral"))
    coarse = tmp_path / "coarse.csv"
    coarse.write_bytes(b"\n".join(lines[:head + 1] + lines[head + 1::500]))
    code, _, err = _run(capsys, "predict", coarse, "--soil", CARD, "--friction", 0.3)
    import re

    step = re.search(r"sampled every [\d.]+ mm, ([\d.]+) D50", err)
    assert code == 2 and step and float(step.group(1)) > 0.5 and "finer" in err, err
    code, out, err = _run(capsys, "predict", DEKTAK, "--soil", CARD, "--friction", 0.3)
    assert code == 0 and "1.5 mm long, relief 0.0166 mm" in out, out


def test_a_scan_whose_theta_a_rests_on_a_small_share_of_its_lines_is_refused(tmp_path, capsys):
    """The shipped FRT scan (31 % of its points missing) answers and says the share of its line length
    under the trace (64 % at D50 0.7 mm); the same scan with its first 300 of 500 rows blanked as well
    (written as NetCDF, read by SurfaceTopography like any instrument file) falls below half, and is refused
    naming the share and the fix."""
    import numpy as np
    from SurfaceTopography import Topography

    from interphase.surface.readers import read_scan

    frt = ROOT / "campaigns" / "profiles" / "frt-1.frt"
    args = ("--fit", "study", "--d50", 0.7, "--friction", 0.2, "--json")
    code, out, _ = _run(capsys, "predict", frt, *args)
    share = json.loads(out)["trace_share"]
    assert code == 0 and 0.5 < share < 0.8, out
    scan = read_scan(frt)
    h = np.array(scan.heights)
    h[:300] = np.nan
    holes = tmp_path / "holes.nc"
    Topography(np.ma.masked_invalid(h), physical_sizes=(float(np.ptp(scan.x)), float(np.ptp(scan.y))),
               unit="m").to_netcdf(str(holes))
    code, _, err = _run(capsys, "predict", holes, *args)
    assert code == 2 and "% of the scan's line length" in err and "crop the scan" in err, err


def test_theta_a_without_a_grain_size_says_so(capsys):
    code, _, err = _run(capsys, "theta-a", DEKTAK)
    assert code == 2 and "--d50" in err and "Traceback" not in err


def test_profile_onto_an_existing_file_leaves_it_byte_identical(tmp_path, capsys):
    target = tmp_path / "mine.csv"
    target.write_bytes(DEKTAK.read_bytes())
    code, _, err = _run(capsys, "profile", "sawtooth", "--rt", 1, "--sw", 2, "-o", target)
    assert code == 2 and "mine-2.csv" in err and target.read_bytes() == DEKTAK.read_bytes()


def test_a_3d_card_in_the_quasi_2d_device_is_refused(tmp_path):
    toml = tmp_path / "c.toml"
    toml.write_text(f'[campaign]\nname = "c"\n[case]\nsoil = "{CARD}"\ntest = "interface"\ndevice = "periodic"\n'
                    'profile = {kind = "flat"}\nfriction_ps = 0.2\nnormal_stress = 1e5\n')
    with pytest.raises(InputError, match="calibrated in 3D") as exc:
        ip.load_campaign(toml)
    assert "periodic3d" in str(exc.value)


@pytest.mark.liggghts
def test_report_onto_an_existing_folder_leaves_it_byte_identical(quick_campaign, tmp_path, capsys):
    import hashlib

    from tests.conftest import need_binary

    need_binary("liggghts")
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("my own notes")
    sums = lambda: {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in mine.iterdir()}
    before = sums()
    code, _, err = _run(capsys, "report", quick_campaign, "-o", mine, "--bootstrap", 0)
    assert code == 2 and "mine-2" in err and sums() == before, err


def test_validate_names_only_cards_that_ship_and_only_their_own_sand():
    from interphase.api.validation import SHIPPED_CARDS, _shipped_card

    assert all((ROOT / "soils" / card).is_file() for _, card in SHIPPED_CARDS)
    lab = ROOT / "lab" / "x.csv"
    assert _shipped_card(["Ottawa F-65"], lab) == ROOT / "soils" / "ottawa-f65.toml"
    assert _shipped_card(["Ottawa 20/30 sand"], lab) is None          # the study's sand, not the card's


def test_the_report_summary_reads_degrees_and_short_labels():
    import pandas as pd

    from interphase.report.build import short_label, summary_markdown

    assert short_label("interface-periodic3d-sawtooth-rt1-sr0-sw2-mu0.2-user-prep0.387") == \
        "sawtooth rt1 sr0 sw2 prep0.387, μs 0.2"
    ens = pd.DataFrame([{"group": "g", "case": "interface-periodic-flat-mu0.2-poly", "seeds": 4, "tan_delta": 0.2,
                         "tan_delta_lo": 0.19, "tan_delta_hi": 0.21, "tan_phi": 0.7, "tan_phi_lo": 0.68,
                         "tan_phi_hi": 0.72, "E": 0.286, "E_lo": 0.27, "E_hi": 0.30}])
    md = summary_markdown(ens, "prov")
    assert "| g | flat, μs 0.2 | 4 | 11.3 (10.8–11.9) | 35.0 (34.2–35.8) | 0.29 (0.27–0.30) |" in md, md
