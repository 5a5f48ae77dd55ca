"""Analysis on real LIGGGHTS output (tests/data/liggghts_sawtooth45: 45° saw-tooth, 1600 grains,
μs = 0.5; made by tests/data/make_liggghts_sawtooth45.py): the study's physical relations at the
peak snapshot, measured in the window away from the side walls (Case.window)."""

from __future__ import annotations

import math

import pytest

from interphase.analysis.summary import summarise
from tests.test_summary import real_case_and_results


@pytest.fixture(scope="module")
def summary():
    case, res = real_case_and_results()
    return summarise(case, res)


@pytest.fixture(scope="module")
def row(summary):
    return summary.row


@pytest.mark.xfail(strict=True, reason=(
    "not reproduced on the current deck (epsd2 rolling, μr = 0.1): on this 45° saw-tooth the surface is "
    "fully mobilised (tan δ ≈ tan φ of the box, φ ≈ 29°) while θr follows the faces (≈ θn ≈ 41–49°); "
    "θr − δ at the peak snapshot is 15.6°, 17.9°, 12.9° for seeds 1–3; with μr = 0.5 (φ ≈ 40°) it is 0.5–6.5° (docs/liggghts.md). The earlier "
    "fixture (cdt) met it at its peak snapshot by chance: its θr ranged 27–44° over the shear"))
def test_theta_r_at_surface_near_interface_friction_angle(row):
    """The study: θr at the surface ≈ the interface friction angle atan(peak stress ratio)."""
    delta = math.degrees(math.atan(row["peak_stress_ratio"]))
    assert abs(row["theta_r_surface_deg"] - delta) <= 10.0, (row["theta_r_surface_deg"], delta)


def test_mean_theta_r_at_surface_near_interface_friction_angle(summary):
    """The same relation on θr averaged over the snapshots where the surface carries the platen's
    load (the shear after the servo settled, before any wedging): within 10°."""
    s = summary.series
    theta = s.loc[s["load_balanced"] & s["theta_r_surface_deg"].notna(), "theta_r_surface_deg"]
    assert len(theta) >= 5
    delta = math.degrees(math.atan(summary.row["peak_stress_ratio"]))
    assert abs(theta.mean() - delta) <= 10.0, (theta.mean(), delta)


def test_stress_force_fabric_matches_average_stress(summary):
    """q/p from the anisotropy coefficients (stress–force–fabric) against the q/p of the average
    stress tensor in the sampling region, over the snapshots where the surface carries the platen's
    load: median difference within 10 %, none beyond 20 %. (The second-order relation is an
    approximation: at the peak snapshot of this fixture it is 13.4 % off, 0.139 vs 0.123.)"""
    s = summary.series
    s = s[s["load_balanced"] & s["qp_sff"].notna() & s["qp_region"].notna()]
    assert len(s) >= 5
    rel = (s["qp_sff"] / s["qp_region"] - 1).abs()
    assert rel.median() <= 0.10 and rel.max() <= 0.20, rel.round(3).tolist()


def test_summed_surface_force_angle_is_atan_of_contact_ratio(row):
    assert row["surface_force_angle_deg"] == pytest.approx(
        math.degrees(math.atan(row["stress_ratio_surface_contacts"])), abs=1e-9)
