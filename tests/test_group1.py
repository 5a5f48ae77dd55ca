"""analysis.group1 (a Group 1 campaign read tooth by tooth), the two-soil E difference, and the
studies' committed-table check (campaign.results.same_table / write_or_check)."""

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from interphase.analysis.difference import e_difference, shared_soil_e_difference
from interphase.analysis.group1 import plateau, rule_efficiency, saturation, tooth_cases
from interphase.campaign.results import read_committed, same_table, write_or_check

ROOT = Path(__file__).resolve().parents[1]


def _cases(mu, rts, e, half):
    return pd.DataFrame({"friction_ps": mu, "rt": rts, "face_deg": np.degrees(np.arctan(rts)),
                         "theta_a_deg_92": np.degrees(np.arctan(rts)) * 0.9, "E": e,
                         "E_lo": np.asarray(e) - half, "E_hi": np.asarray(e) + half})


def test_saturation_is_the_first_tooth_reaching_1_and_names_a_later_dip():
    c = _cases(0.05, [0.1, 0.5, 0.7, 1.0, 5.0], [0.2, 0.8, 0.96, 1.0, 0.93], 0.04)
    row = saturation(c).iloc[0]
    assert row["from_rt"] == 0.7 and row["below_rt"] == 0.5 and row["below_E"] == pytest.approx(0.8)
    assert row["dips"].startswith("Rt/D50 5 (0.93")
    p = plateau(c).iloc[0]
    assert (p["cases"], p["above_1"], p["containing_1"], p["below_1"]) == (2, 0, 1, 1)


def test_saturation_not_reached_leaves_the_tooth_empty():
    row = saturation(_cases(0.2, [0.1, 0.5], [0.3, 0.6], 0.05)).iloc[0]
    assert row["teeth"] == 2 and math.isnan(row["from_rt"])


def test_the_rule_caps_at_phi():
    assert rule_efficiency(0.5, 60.0, 0.7) == pytest.approx(1.0)
    assert rule_efficiency(0.05, 5.0, 0.7) == pytest.approx(math.tan(math.radians(math.degrees(math.atan(0.05)) + 5)) / 0.7)


def test_e_difference_of_one_ensemble_with_itself_is_zero_and_agrees_when_tight():
    rng = np.random.default_rng(1)
    a, b = 0.6 + 0.005 * rng.standard_normal(8), 0.6 + 0.005 * rng.standard_normal(8)
    d, lo, hi, v = e_difference(a, b, a, b)
    assert d == 0 and lo < 0 < hi and v == "agree"
    d, lo, hi, v = shared_soil_e_difference(a, a + 0.3, b)
    assert d == pytest.approx(0.3 / b.mean()) and v == "differ"
    assert math.isnan(e_difference(a[:1], b, a, b)[0])


def test_a_committed_table_matches_within_its_last_digits_and_not_beyond(tmp_path):
    df = pd.DataFrame({"case": ["a", "b"], "E": [0.1234567890123, np.nan], "note": ["", "x"]})
    path = tmp_path / "t.csv"
    assert write_or_check({path: df}, check=True) == [path]            # missing: differs, nothing written
    assert not path.exists()
    assert write_or_check({path: df}, check=False) == [path] and same_table(df, path)
    noisy = df.assign(E=[0.1234567890124, np.nan])
    assert same_table(noisy, path) and write_or_check({path: noisy}, check=False) == []
    assert not same_table(df.assign(E=[0.1235, np.nan]), path)
    assert not same_table(df.assign(note=["", "y"]), path)
    assert not same_table(df.rename(columns={"E": "F"}), path)


def test_tooth_cases_on_the_committed_quasi_2d_card():
    summ, store = read_committed(ROOT / "studies" / "kfs_group1_2d" / "results")
    c = tooth_cases(summ, store)
    teeth = c.dropna(subset=["rt"])
    assert len(c) == 33 and len(teeth) == 24 and set(c["friction_ps"]) == {0.05, 0.2, 0.5}
    assert teeth.loc[teeth["rt"].eq(1.0), "face_deg"].round(6).eq(45.0).all()
    assert c["profile_kind"].isin(["sawtooth", "flat", "file"]).all()
