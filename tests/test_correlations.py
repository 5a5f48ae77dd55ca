"""Bilinear fits (docs/methods.md §7): exact breakpoints, intervals, invariances, the study's set."""

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings, strategies as st

from interphase.analysis.correlations import (SPECS, BilinearFit, FitError, fit_bilinear, fit_hinge, fit_plateau,
                                              fit_study, prepare_points)
from interphase.report.synthetic import synthetic_summaries


def test_exact_hinge_breakpoint_is_22_exactly():
    x = np.arange(0.0, 50.0, 2.0)
    y = 0.2 + 0.5 * x - 0.5 * np.maximum(x - 22.0, 0.0)
    f = fit_hinge(x, y, n_boot=50)
    assert f.c == 22.0
    np.testing.assert_allclose(f.coef, (0.2, 0.5, -0.5), atol=1e-9)
    assert f.c_interval_profile == (22.0, 22.0)
    assert f.r2 == pytest.approx(1.0)
    np.testing.assert_allclose(f.predict(x), y, atol=1e-9)


def test_exact_hinge_breakpoint_between_data_points():
    x = np.arange(0.0, 40.0, 3.0)
    y = 1.0 - 0.2 * x + 0.7 * np.maximum(x - 20.5, 0.0)
    f = fit_hinge(x, y, n_boot=0)
    assert f.c == pytest.approx(20.5, abs=1e-6)
    np.testing.assert_allclose(f.coef, (1.0, -0.2, 0.7), atol=1e-6)


def test_noisy_plateau_interval_contains_30():
    rng = np.random.default_rng(3)
    x = rng.uniform(0, 60, 80)
    y = 0.1 + 0.02 * np.minimum(x, 30.0) + rng.normal(0, 0.02, x.size)
    f = fit_plateau(x, y, n_boot=199, seed=1)
    assert f.c_interval_profile[0] <= 30.0 <= f.c_interval_profile[1]
    assert f.c_interval_bootstrap[0] <= 30.0 <= f.c_interval_bootstrap[1]
    assert f.c_interval_profile[1] - f.c_interval_profile[0] < 10      # informative, not the whole range
    lo, hi = f.coef_interval[1]
    assert lo <= 0.02 <= hi
    assert f.n == 80 and 0.9 < f.r2 <= 1


def test_bootstrap_is_seeded():
    rng = np.random.default_rng(0)
    x = rng.uniform(0, 10, 30)
    y = np.minimum(x, 4) + rng.normal(0, 0.1, 30)
    a = fit_plateau(x, y, n_boot=40, seed=7)
    b = fit_plateau(x, y, n_boot=40, seed=7)
    c = fit_plateau(x, y, n_boot=40, seed=8)
    assert a.c_interval_bootstrap == b.c_interval_bootstrap
    assert a.c_interval_bootstrap != c.c_interval_bootstrap


def test_too_few_points_says_why():
    with pytest.raises(FitError, match="n = 6 < 7"):
        fit_hinge(np.arange(6.0), np.arange(6.0))
    with pytest.raises(FitError, match="distinct x"):
        fit_hinge(np.r_[np.zeros(5), np.ones(5)], np.arange(10.0))
    with pytest.raises(FitError):   # NaNs do not count
        fit_plateau(np.r_[np.arange(5.0), np.nan, np.nan], np.arange(7.0))


def test_breakpoint_keeps_three_points_each_side():
    x = np.arange(10.0)
    y = np.where(x < 1.5, 5.0 * x, 7.5)       # the "true" break is at 1.5: only 2 points left of it
    f = fit_plateau(x, y, n_boot=0)           # a point at c is on both lines
    assert (x <= f.c).sum() >= 3 and (x >= f.c).sum() >= 3 and f.c == 2.0


def test_roundtrip_dict():
    x = np.linspace(0, 10, 12)
    f = fit_hinge(x, np.abs(x - 5), n_boot=10)
    g = BilinearFit.from_dict(f.to_dict())
    np.testing.assert_allclose(g.predict(x), f.predict(x))
    assert g.c == f.c and g.c_interval_bootstrap == f.c_interval_bootstrap


_data = st.tuples(st.integers(8, 30), st.floats(-3, 3), st.floats(0.5, 3), st.floats(0.3, 0.7),
                  st.integers(0, 10_000), st.sampled_from(["hinge", "plateau"]))


@settings(max_examples=25, deadline=None)
@given(_data, st.randoms(use_true_random=False))
def test_invariant_to_row_order(params, rnd):
    n, b1, db, frac, seed, model = params
    rng = np.random.default_rng(seed)
    x = np.sort(rng.uniform(0, 10, n))
    c = 10 * frac
    y = b1 * x + (db if model == "hinge" else -b1) * np.maximum(x - c, 0) + rng.normal(0, 0.05, n)
    perm = list(range(n))
    rnd.shuffle(perm)
    a = fit_bilinear(x, y, model, n_boot=20, seed=1)
    b = fit_bilinear(x[perm], y[perm], model, n_boot=20, seed=1)
    assert a.c == b.c and a.coef == b.coef
    assert a.c_interval_profile == b.c_interval_profile and a.c_interval_bootstrap == b.c_interval_bootstrap


@settings(max_examples=25, deadline=None)
@given(_data, st.floats(-100, 100))
def test_shift_moves_c_by_the_shift(params, shift):
    n, b1, db, frac, seed, model = params
    rng = np.random.default_rng(seed)
    x = np.round(rng.uniform(0, 10, n), 3)       # exactly representable shifts of x keep the data the same
    c = 10 * frac
    y = b1 * x + (db if model == "hinge" else -b1) * np.maximum(x - c, 0) + rng.normal(0, 0.05, n)
    s = round(shift, 3)
    a = fit_bilinear(x, y, model, n_boot=0)
    b = fit_bilinear(x + s, y, model, n_boot=0)
    assert b.c == pytest.approx(a.c + s, abs=1e-6 * (1 + abs(s)))
    np.testing.assert_allclose(b.predict(x + s), a.predict(x), atol=1e-6)
    assert b.rss == pytest.approx(a.rss, rel=1e-6, abs=1e-12)


def test_prepare_points_pairs_boxes_and_flags():
    df = synthetic_summaries(60, seed=2)
    pts = prepare_points(df)
    assert len(pts) == 60                                       # box rows dropped
    np.testing.assert_allclose(pts["efficiency"], pts["peak_stress_ratio"] / 0.55)
    assert (pts["flat_spaced"] == (pts["group"] == "group2")).all()
    nd = pts["non_dilative"]
    assert nd.any() and (pts.loc[nd, "theta_a_deg_92"] == 0).all()
    for col in ("group", "friction_ps", "gradation"):
        assert col in pts


def test_study_fits_recover_the_synthetic_truth():
    pts = prepare_points(synthetic_summaries(300, seed=4, noise_deg=0.5, noise_e=0.01))
    res = {(r.spec.key, r.slice): r for r in fit_study(pts, n_boot=30)}
    e = res[("fig6_10a", "all")].fit
    assert e.c_interval_profile[0] - 1 <= 30 <= e.c_interval_profile[1] + 1
    assert e.predict(10.0) == pytest.approx(0.2 + 0.8 * 10 / 30, abs=0.03)
    t = res[("fig6_8", "friction_ps=0.05")].fit
    assert t.c == pytest.approx(40, abs=3)
    assert t.predict(0.0) == pytest.approx(math.degrees(math.atan(0.05)), abs=1.5)    # intercept ≈ φμ
    assert res[("fig6_9", "all")].fit is not None


def test_the_efficiency_criterion_is_also_fitted_per_gradation():
    pts = prepare_points(synthetic_summaries(600, seed=4, noise_deg=0.5, noise_e=0.01))
    mono = pts["gradation"] == "mono"
    # uniform grains mobilised later: their E plateau starts at θr 40° instead of 30°
    pts.loc[mono, "efficiency"] = 0.2 + 0.8 * np.minimum(pts.loc[mono, "theta_r_surface_deg"], 40.0) / 40.0
    res = {(r.spec.key, r.slice): r.fit for r in fit_study(pts, [SPECS["fig6_10a"]], n_boot=30)}
    assert res[("fig6_10a", "gradation=poly")].c == pytest.approx(30, abs=2)
    assert res[("fig6_10a", "gradation=mono")].c == pytest.approx(40, abs=3)
    assert res[("fig6_10a", "all")].n == len(pts)


def test_study_fit_without_enough_points_says_why():
    pts = prepare_points(synthetic_summaries(5, seed=1))
    out = fit_study(pts, n_boot=0)
    assert all(r.fit is None and r.reason.startswith("no fit") for r in out)
    assert pd.DataFrame([r.row() for r in out])["reason"].str.contains("< 7").any()


def test_break_search_covers_every_corner_with_three_points_a_line():
    # nine x: a break is admissible from the 3rd to the 7th x (a point at c is on both lines)
    x = np.array([5.7, 10.9, 24.2, 39.4, 43.7, 49.1, 56.0, 64.8, 73.7])
    y = 2.0 + 1.0 * x + 0.5 * np.maximum(x - 40.0, 0.0)
    f = fit_hinge(x, y, n_boot=0)
    assert f.c_range == (24.2, 56.0)
    assert f.c == pytest.approx(40.0, abs=1e-6) and f.located


def test_a_break_the_data_cannot_place_is_not_located():
    # a straight line with noise: every admissible corner fits as well, the interval is the range
    rng = np.random.default_rng(2)
    x = np.linspace(0, 60, 9)
    y = 1.0 + 0.8 * x + rng.normal(0, 3.0, x.size)
    f = fit_hinge(x, y, n_boot=0)
    assert f.c_interval_profile == pytest.approx(f.c_range)
    assert not f.located
    assert BilinearFit.from_dict(f.to_dict()).located is False
    old = {k: v for k, v in f.to_dict().items() if k not in ("c_lo_range", "c_hi_range")}
    assert BilinearFit.from_dict(old).located          # a file without the range: not judged
