"""analysis.findings on points whose answer is known by construction."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from interphase.analysis.findings import filter_collapse, rnc_uniqueness, spaced_theta_a
from interphase.report.tables import findings_tables


def _line(theta):
    return 0.1 + 0.012 * np.minimum(theta, 35.0)


@pytest.fixture
def points():
    rng = np.random.default_rng(3)
    rows = []
    for mu in (0.05, 0.2):
        for t in np.linspace(3, 75, 9):            # Group 1: on the line with ~0.005 of scatter
            rows.append(dict(group="group1", friction_ps=mu, theta_a_deg_90=t - 0.5, theta_a_deg_92=t,
                             rnc=t / 50, peak_stress_ratio=_line(t) + rng.normal(0, 0.005), sr=0.0,
                             theta_r_surface_deg=t))
        for sr in (0.5, 2, 5, 10):                 # Group 2: θa > 92° fixed at 40°, ≥ 90° falls with Sr
            t90 = 40 / (1 + sr)
            rows.append(dict(group="group2", friction_ps=mu, theta_a_deg_90=t90, theta_a_deg_92=40.0,
                             rnc=0.8 / (1 + sr), peak_stress_ratio=_line(40.0) + rng.normal(0, 0.005), sr=sr,
                             theta_r_surface_deg=38.0))
    df = pd.DataFrame(rows)
    df["efficiency"] = df["peak_stress_ratio"] / 0.5
    return df


def test_the_92_filter_brings_spaced_surfaces_onto_the_line(points):
    fc = filter_collapse(points).set_index(["friction_ps", "x", "group"])["rms_residual"]
    for mu in (0.05, 0.2):
        own = fc[(mu, "θa > 92°", "group1")]
        assert own < 0.01
        assert fc[(mu, "θa > 92°", "group2")] < 3 * own + 0.01       # joins with > 92°
        assert fc[(mu, "θa ≥ 90°", "group2")] > 0.1                  # scatters with every normal


def test_rnc_is_not_unique_when_spaced_surfaces_leave_its_line(points):
    rn = rnc_uniqueness(points).set_index(["friction_ps", "x", "group"])["rms_residual"]
    assert rn[(0.05, "Rnc(D50)", "group2")] > 5 * rn[(0.05, "θa > 92°", "group2")]


def test_spaced_theta_a_one_row_per_spacing(points):
    sp = spaced_theta_a(points)
    assert list(sp["sr"]) == [0.5, 2, 5, 10]
    assert (sp["theta_a_deg_92"] == 40.0).all() and sp["theta_a_deg_90"].is_monotonic_decreasing
    assert {"peak_stress_ratio_mu0.05", "theta_r_surface_deg_mu0.2"} <= set(sp.columns)


def test_no_group1_no_findings(points):
    assert findings_tables(points[points["group"] != "group1"]) == []
    assert [t.name for t in findings_tables(points)] == ["finding_filter_collapse", "finding_rnc",
                                                         "finding_spaced_theta_a"]
