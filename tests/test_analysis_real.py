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


def test_stress_force_fabric_matches_average_stress(row):
    """q/p from the anisotropy coefficients (stress–force–fabric) within 10 % of the q/p of the
    average stress tensor in the sampling region."""
    assert row["qp_sff"] == pytest.approx(row["qp_region"], rel=0.10), (row["qp_sff"], row["qp_region"])


def test_summed_surface_force_angle_is_atan_of_contact_ratio(row):
    assert row["surface_force_angle_deg"] == pytest.approx(
        math.degrees(math.atan(row["stress_ratio_surface_contacts"])), abs=1e-9)
