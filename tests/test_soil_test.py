"""The soil test read on the box's plane and as the specimen's Mohr circle (analysis.soil_test)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
from hypothesis import given
from hypothesis import strategies as st

from interphase.analysis.soil_test import plane_ratio, soil_test_readings

ROOT = Path(__file__).resolve().parents[1]
KFS_2D = ROOT / "studies" / "kfs_group1_2d" / "results" / "summaries.csv"
BIAXIAL_2D = ROOT / "docs" / "soils" / "karlsruhe-fine-sand-2d" / "verification_tmd17_6seeds.csv"


@given(st.floats(5.0, 60.0))
def test_plane_ratio_at_the_two_orientations(phi):
    s = math.sin(math.radians(phi))
    # the plane of maximum obliquity: σ1 at 45° + φ/2 from the vertical reads tan φ
    assert abs(plane_ratio(s, 45 + phi / 2) - math.tan(math.radians(phi))) < 1e-12
    # σ1 at 45°: the zero-extension plane at zero dilatancy reads sin φ
    assert abs(plane_ratio(s, 45.0) - s) < 1e-12
    # no other orientation reads more than tan φ
    alphas = np.linspace(0, 90, 181)
    assert plane_ratio(s, alphas).max() <= math.tan(math.radians(phi)) + 1e-12


def test_readings_group_seeds_per_box_case():
    rows = [{"test": "box", "label": f"box-a-s{i}", "physical_id": "a", "peak_stress_ratio": 0.6 + 0.01 * i,
             "qp_region": 0.6, "principal_stress_deg_region": 45.0} for i in range(1, 4)]
    rows += [{"test": "box", "label": "box-b-s1", "physical_id": "b", "peak_stress_ratio": 0.5,
              "qp_region": math.nan, "principal_stress_deg_region": 40.0},
             {"test": "interface", "label": "x-s1", "physical_id": "x", "peak_stress_ratio": 0.4,
              "qp_region": 0.5, "principal_stress_deg_region": 30.0}]
    r = soil_test_readings(pd.DataFrame(rows))
    assert list(r["case"]) == ["box-a"]          # b has no tensor at its peak, the interface is no soil test
    two = soil_test_readings(pd.DataFrame([dict(x, engine=e) for x in rows[:3] for e in ("liggghts", "yade")]))
    assert list(two["case"]) == ["box-a (liggghts)", "box-a (yade)"] and list(two["seeds"]) == [3, 3]
    assert r["seeds"].iloc[0] == 3
    assert abs(r["phi_mob_deg"].iloc[0] - math.degrees(math.asin(0.6))) < 1e-9
    assert abs(r["phi_sin_deg"].iloc[0] - math.degrees(math.atan(0.6))) < 1e-9
    assert r["phi_plane_deg_lo"].iloc[0] < r["phi_plane_deg"].iloc[0] < r["phi_plane_deg_hi"].iloc[0]
    assert soil_test_readings(pd.DataFrame({"test": ["interface"]})).empty


def test_the_discs_box_is_as_strong_as_their_biaxial_cell():
    """Committed Group 1 quasi-2D soil tests (12 seeds) against the same card's biaxial test (6 seeds):
    the box's plane reads several degrees under the biaxial φ_peak, its specimen's Mohr circle does not."""
    r = soil_test_readings(pd.read_csv(KFS_2D)).iloc[0]
    bx = pd.read_csv(BIAXIAL_2D).iloc[0]
    assert r["seeds"] == 12
    assert r["phi_plane_deg_hi"] < bx["phi_peak_deg_lo"] - 3
    assert r["phi_mob_deg_lo"] <= bx["phi_peak_deg_hi"] and bx["phi_peak_deg_lo"] <= r["phi_mob_deg_hi"]
    assert abs(r["principal_deg"] - 45) < 3                   # σ1 near 45°: the box reads ≈ sin φ_mob
    assert abs(r["phi_sin_deg"] - r["phi_plane_deg"]) < 2


def test_report_table_prints_each_reading_with_its_interval():
    from interphase.report.tables import soil_tests_table

    t = soil_tests_table(soil_test_readings(pd.read_csv(KFS_2D)))
    assert t.name == "soil_tests" and len(t.df) == 1
    assert t.df.filter(like="φ_mob").iloc[0, 0].startswith("36.") and "[" in t.df.filter(like="φ_mob").iloc[0, 0]
