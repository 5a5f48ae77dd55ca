"""Laboratory files (interphase.lab) and `campaign validate`: the reader's checks name file, CSV line
and field; the rebuilt surfaces; the criterion and both baselines per row."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tests.conftest import need_binary

from interphase.cli import main
from interphase.errors import InputError
from interphase.lab import profile_of, read_lab

ROOT = Path(__file__).resolve().parents[1]
HEAD = ("soil,d50_mm,surface,asperity_height_mm,asperity_width_mm,root_spacing_mm,normal_stress_kpa,"
        "delta_peak_deg,soil_phi_peak_deg,source,table_or_figure")
# synthetic rows (no laboratory's numbers): shapes and checks only
GOOD = [
    "Ottawa 20/30 sand (synthetic),0.72,sawtooth,0.5,1.0,0,100,30,36,synthetic test row,none",
    "Ottawa 20/30 sand (synthetic),0.72,flat,,,,100,12,36,synthetic test row,none",
    "Ottawa 20/30 sand (synthetic),0.72,ramp,0.3,2.0,0,100,25,36,synthetic test row,none",
]


def _write(tmp_path: Path, lines, head=HEAD) -> Path:
    p = tmp_path / "lab.csv"
    p.write_text("\n".join([head, *lines]) + "\n")
    return p


def test_reader_converts_units_and_keeps_lines(tmp_path):
    head = HEAD.replace("d50_mm", "d50_um").replace("normal_stress_kpa", "normal_stress_pa")
    rows = [GOOD[0].replace(",0.72,", ",720,").replace(",100,", ",100000,")]
    t = read_lab(_write(tmp_path, rows, head))
    r = t.rows.iloc[0]
    assert r["row"] == 2 and r["d50"] == pytest.approx(0.72e-3) and r["normal_stress"] == pytest.approx(1e5)
    assert r["asperity_height"] == pytest.approx(0.5e-3)


@pytest.mark.parametrize("change, field", [
    (lambda h, r: (h, [r.replace("synthetic test row,none", ",none")]), "source"),
    (lambda h, r: (h.replace("asperity_height_mm", "asperity_height_in"), [r]), "asperity_height_in"),
    (lambda h, r: (h, [r.replace("sawtooth", "knurled")]), "surface"),
    (lambda h, r: (h, [r.replace("sawtooth,0.5", "sawtooth,")]), "asperity_height"),
    (lambda h, r: (h, [r.replace(",100,30,", ",100 kPa,30,")]), "normal_stress_kpa"),
])
def test_bad_rows_exit_2_naming_file_line_and_field(tmp_path, capsys, change, field):
    head, rows = change(HEAD, GOOD[0])
    p = _write(tmp_path, [GOOD[1], *rows], head)
    with pytest.raises(InputError) as exc:
        read_lab(p)
    msg = str(exc.value)
    assert str(p) in msg and field in msg
    if field != "asperity_height_in":          # a header problem has no row
        assert f"{p}:3" in msg
    # the CLI in-process (an exception would fail the test): exit 2 and the field named on stderr
    assert main(["validate", str(p)]) == 2
    err = capsys.readouterr().err
    assert field in err and str(p) in err and "Traceback" not in err


def test_rebuilt_surfaces(tmp_path):
    from interphase.surface.normals import theta_a

    t = read_lab(_write(tmp_path, GOOD))
    saw, flat, ramp = (profile_of(t.rows.iloc[i]) for i in range(3))
    d50 = 0.72e-3
    assert math.isnan(theta_a(flat, d50).theta_a_deg)
    # teeth 0.5 mm high on a 1 mm base: faces at 45°; the centroid trace rounds them, θa below 45°
    assert 20 < theta_a(saw, d50).theta_a_deg < 45
    # a ramp resists more against its vertical face than up its slope
    r = t.rows.iloc[2].copy()
    r["direction"] = "-"
    assert theta_a(profile_of(r), d50).theta_a_deg > theta_a(ramp, d50).theta_a_deg + 10


def test_validate_prints_criterion_and_baselines(tmp_path, capsys, monkeypatch):
    p = _write(tmp_path, GOOD)
    monkeypatch.chdir(ROOT)
    code = main(["validate", str(p), "-o", str(tmp_path / "v"), "--json"])
    out = capsys.readouterr()
    assert code == 0, out.err
    res = json.loads(out.out)
    rows = res["table"]
    assert [r["row"] for r in rows] == [2, 3, 4]
    flat = rows[1]
    assert flat["delta_rule_deg"] == pytest.approx(math.degrees(math.atan(0.2)))   # sand: tan φμ 0.2 (seed §6.4.6)
    assert all(r["delta_soil_deg"] == 36 for r in rows)
    for r in rows:
        assert r["error_predicted_deg"] == pytest.approx(r["delta_predicted_deg"] - r["delta_measured_deg"])
    fitted = "δ = min(φμ + θa − a, atan(b tan φ)), a, b fitted with the criterion"
    assert {s["prediction"] for s in res["skill"]} == {"criterion", "δ = φ (soil)", "δ = min(φμ + θa, φ)", fitted}
    from interphase.criterion_fits import REPRODUCTION, load_criterion

    a, b = load_criterion(REPRODUCTION).rule           # the shipped criterion's two constants
    assert flat["delta_fitted_rule_deg"] == pytest.approx(
        min(math.degrees(math.atan(0.2)) + flat["theta_a_deg"] - a, math.degrees(math.atan(b * math.tan(math.radians(36))))))
    assert res["largest_miss"]["row"] in (2, 3, 4)
    assert (tmp_path / "v" / "validation.png").stat().st_size > 10_000


#: the tiny cell both --simulate tests run the suite's tiny card in: 1 mm of shear holds the peaks they
#: read (seed 1's box tan φ 0.702 over 1 mm and over 2 mm, the saw-tooth row's δ 39.8° and 39.3°, the
#: flat row's 11.3° in both; the profile's 3 seeds 35.8° [30.0°, 42.0°] against 33.7° [22.1°, 47.6°])
TINY_PROTOCOL = {"box_length_d50": 12.0, "box_height_d50": 8.0, "shear_velocity": 0.05, "shear_distance": 0.001}


@pytest.fixture(scope="module")
def simulated_rows(tmp_path_factory):
    """`simulate` of one synthetic saw-tooth row and one flat row (GOOD[:2]) on the suite's tiny card,
    seed 1, run once for this module: (table, card, output, protocol, result). Its paired soil test
    (the card's box at 100 kPa, seed 1) is also the profile test's seed 1: that test reuses it."""
    from interphase.campaign.validate import PROTOCOL, simulate
    from interphase.soil import load_card

    need_binary("liggghts")
    tmp = tmp_path_factory.mktemp("simulate")
    table = read_lab(_write(tmp, GOOD[:2]))
    card = load_card(ROOT / "tests" / "data" / "soils" / "tiny_card.toml")
    tiny = PROTOCOL | TINY_PROTOCOL
    return table, card, tmp / "sim", tiny, simulate(table, card, [1], output=tmp / "sim", protocol=tiny)


@pytest.mark.liggghts
def test_simulate_runs_each_row_on_the_card_and_resumes(simulated_rows):
    """--simulate's machinery with real LIGGGHTS on the suite's tiny card and a tiny cell: one
    synthetic saw-tooth row and one flat row, one seed each; a second call reruns nothing."""
    from interphase.analysis.validation import predict_rows
    from interphase.campaign.validate import simulate, with_dem
    from interphase.criterion_fits import criterion_model

    table, card, out, tiny, dem = simulated_rows
    assert sorted(dem["row"]) == [2, 3]
    d = dem.set_index("row")
    assert (d["dem_seeds"] == 1).all() and d["delta_dem_deg"].between(1, 60).all()
    assert d.loc[2, "delta_dem_deg"] > d.loc[3, "delta_dem_deg"]       # teeth grip more than a flat plate
    done = sorted(out.rglob("DONE"))
    again = simulate(table, card, [1], output=out, protocol=tiny)
    assert sorted(out.rglob("DONE")) == done
    pd.testing.assert_frame_equal(again, dem)
    df = with_dem(predict_rows(table, lambda mu: criterion_model(mu, None), card), dem)
    assert df["error_dem_deg"].to_numpy() == pytest.approx((df["delta_dem_deg"] - df["delta_measured_deg"]).to_numpy())


def test_the_simulated_protocol_is_the_studys_in_d50_units():
    from interphase.campaign.validate import PROTOCOL, protocol_for

    assert protocol_for(0.0007) == PROTOCOL                      # the study's 0.7 mm grains: as it was
    sand = protocol_for(0.00014)                                  # the Karlsruhe fine sand's D50
    assert sand["shear_distance"] == 0.0012 and sand["snapshot_every"] == 0.0001
    assert sand["shear_velocity"] == PROTOCOL["shear_velocity"] and sand["box_length_d50"] == 40.0


@pytest.mark.liggghts
def test_predict_simulate_runs_a_profile_on_the_card(simulated_rows, tmp_path):
    """`predict --simulate`'s machinery (campaign.validate.simulate_profile) with real LIGGGHTS: a
    measured-style profile (x, z in m: saw-teeth one D50 high, two D50 apart) on the suite's tiny card
    in a tiny cell, 3 seeds (the fewest with an interval): δ with its interval, and a second call reruns
    nothing. The card's soil test of seed 1 is the same case (the same case id) as the rows'
    simulation's (simulated_rows): its finished folder is copied in, as a campaign reuses any finished
    case in its output, and the soil tests of seeds 2 and 3 and the three interface cases run here."""
    import shutil

    from interphase.campaign.validate import simulate_profile

    _, card, rows_out, tiny, _ = simulated_rows
    d = float(card.soil["d50"])
    x = np.linspace(0, 24 * d, 481)
    z = d * np.abs(((x / (2 * d)) % 1) - 0.5) * 2            # triangle wave: height d, period 2 d
    (box,) = [f for f in rows_out.iterdir() if (f / "DONE").exists()
              and json.loads((f / "case.json").read_text())["inputs"]["test"] == "box"]
    shutil.copytree(box, tmp_path / "p" / box.name)
    out = simulate_profile(card, (x, z), 0.5, [1, 2, 3], output=tmp_path / "p", protocol=tiny)
    assert out["seeds"] == 3 and out["delta_deg_lo"] <= out["delta_deg"] <= out["delta_deg_hi"]
    assert 5 < out["delta_deg"] < 60 and out["tan_phi"] > 0
    assert out["E"] == pytest.approx(out["tan_delta"] / out["tan_phi"], rel=0.05)
    done = sorted((tmp_path / "p").rglob("DONE"))
    assert len(done) == 6                                     # 3 interface cases, 3 soil tests (one copied)
    assert simulate_profile(card, (x, z), 0.5, [1, 2, 3], output=tmp_path / "p", protocol=tiny) == out
    assert sorted((tmp_path / "p").rglob("DONE")) == done
