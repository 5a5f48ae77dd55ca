"""The density scale fitted on several records of one stress (campaign/density_scale.py): where a
record sits on a sweep of preparations, and the line from the laboratory's Dr to the model's."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from interphase.campaign.density_scale import anchor_preparation, fit_scale, misfit, model_dr

# a sweep shaped like the 3D Karlsruhe card's at 200 kPa (docs/soils.md): stronger and more dilatant denser
PREP = [0.3, 0.5, 0.75, 1.0]
PHI = [44.0, 40.5, 38.0, 36.6]
PSI = [16.0, 11.5, 8.5, 6.9]


def test_a_record_on_the_sweep_is_anchored_where_both_lines_pass_through_it():
    # a record made from the lines at 0.6 itself: anchored there with no misfit
    phi, psi = np.interp(0.6, PREP, PHI), np.interp(0.6, PREP, PSI)
    p, m = anchor_preparation(PREP, PHI, PSI, phi, psi)
    assert p == pytest.approx(0.6, abs=1e-3) and m == pytest.approx(0.0, abs=1e-4)


def test_a_record_beyond_the_sweep_anchors_at_its_end_and_says_how_far_it_stayed():
    p, m = anchor_preparation(PREP, PHI, PSI, 34.0, 4.0)       # looser than the loosest
    assert p == 1.0 and m == pytest.approx(misfit(36.6, 6.9, 34.0, 4.0))
    p, _ = anchor_preparation(PREP[::-1], PHI[::-1], PSI[::-1], 47.0, 20.0)   # order of the points is free
    assert p == 0.3


def test_the_tolerances_weigh_the_two_angles_as_a_calibration_does():
    # φ met at 0.5, ψ at 0.75: with ψ's tolerance far looser the anchor goes to φ's preparation
    p_phi, _ = anchor_preparation(PREP, PHI, PSI, 40.5, 8.5, tolerances=(1.5, 1e3))
    p_psi, _ = anchor_preparation(PREP, PHI, PSI, 40.5, 8.5, tolerances=(1e3, 2.0))
    assert p_phi == pytest.approx(0.5, abs=1e-3) and p_psi == pytest.approx(0.75, abs=1e-3)


def test_the_model_dr_of_a_preparation_is_read_on_the_index_limits_given():
    prep, e = [0.0, 0.25, 0.5, 0.75, 1.0, 2.5], [0.53, 0.64, 0.73, 0.78, 0.83, 0.72]
    assert model_dr(prep, e, 0.0, (0.53, 0.83)) == pytest.approx(1.0)
    assert model_dr(prep, e, 1.0, (0.53, 0.83)) == pytest.approx(0.0)
    assert model_dr(prep, e, 0.5, (0.53, 0.83)) == pytest.approx((0.83 - 0.73) / 0.30)   # the point at 2.5 is not read
    # index limits looser than the map at this stress: the same specimen reads denser
    assert model_dr(prep, e, 0.5, (0.55, 0.86)) == pytest.approx((0.86 - 0.73) / 0.31)


@given(span=st.floats(0.2, 4.0), offset=st.floats(-3.0, 1.0),
       dr=st.lists(st.floats(0.0, 1.0), min_size=2, max_size=6, unique=True))
def test_the_line_through_exact_pairs_is_found_again(span, offset, dr):
    dr = np.asarray(dr)
    if np.ptp(dr) < 0.05:
        return
    s, o = fit_scale(dr, offset + span * dr)
    assert s == pytest.approx(span, rel=1e-6, abs=1e-6) and o == pytest.approx(offset, rel=1e-6, abs=1e-6)


def test_one_density_cannot_fix_a_line():
    with pytest.raises(ValueError, match="two or more"):
        fit_scale([0.78, 0.78], [0.5, 0.52])
