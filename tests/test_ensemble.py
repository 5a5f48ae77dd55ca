"""Seed-ensemble strength (analysis.ensemble): exact cases and the property that motivates it."""

import math

import numpy as np
import pytest

from interphase.analysis.ensemble import ensemble_efficiency, ensemble_strength

D50 = 7e-4
X = np.linspace(0, 6e-3, 301)


def hump(x, peak=0.6, at=2e-3, late=0.45):
    """Rises from `late` − 0.45 to `peak` at `at` and relaxes to `late` (smooth: a 0.5 D50
    moving average lowers its top by < 0.003)."""
    base = np.where(x <= at, late - 0.45 * (1 - x / at) ** 2, late)
    return base + (peak - late) * np.exp(-0.5 * ((x - at) / 1e-3) ** 2)


def test_identical_seeds_give_the_curve_and_a_point_interval():
    s = ensemble_strength([(X, hump(X))] * 4, window=0.5 * D50)
    assert s.n_seeds == 4
    assert s.peak == pytest.approx(0.6, abs=0.003) and s.peak_disp == pytest.approx(2e-3, abs=0.1e-3)
    assert s.peak_lo == pytest.approx(s.peak) and s.peak_hi == pytest.approx(s.peak)
    assert s.critical == pytest.approx(np.mean(hump(X)[X >= 0.6 * X[-1]]), rel=1e-3)
    assert s.critical_lo == pytest.approx(s.critical) and s.critical_hi == pytest.approx(s.critical)


def test_critical_state_is_the_mean_of_seed_means_with_a_t_interval():
    levels = [0.40, 0.44, 0.47, 0.49]
    s = ensemble_strength([(X, np.full_like(X, c)) for c in levels], window=0.5 * D50)
    assert s.critical == pytest.approx(np.mean(levels))
    half = 3.182446305 * np.std(levels, ddof=1) / 2          # t(0.975, 3)·s/√4
    assert s.critical_hi - s.critical == pytest.approx(half, rel=1e-6)
    assert s.critical_lo < min(levels[1:]) and s.critical_hi > max(levels[:-1])


def _noisy_seeds(rng, trend, n, sd=0.035):
    """n runs of `trend` with the well-graded soil's run-to-run noise: sd 0.035 about the seed mean,
    correlated over ~0.5 D50 (Gaussian kernel of sd 0.25 D50; studies/peak_estimators/peak_estimators.py)."""
    step = X[1] - X[0]
    k = np.arange(-40, 41) * step
    kern = np.exp(-0.5 * (k / (0.25 * D50)) ** 2)
    out = []
    for _ in range(n):
        e = np.convolve(rng.normal(0, 1, X.size + k.size - 1), kern, mode="valid")
        out.append((X, trend + sd * e / np.sqrt((kern ** 2).sum())))
    return out


PLATEAU = 0.38 - 0.31 * np.exp(-X / 0.6e-3) - 0.015 * np.clip((X - 3.4e-3) / 2.6e-3, 0, 1) ** 2   # the weak soil's shape


def _biases(trend, n, trials, seed=7):
    """(bias of the tool's peak, bias of the seed-mean curve's maximum, coverage) over `trials`
    ensembles of n seeds of `trend` carrying the well-graded soil's noise; truth: the noise-free
    trend's maximum as the tool smooths it."""
    from interphase.analysis.strength import moving_average

    truth = moving_average(X, trend, 0.5 * D50).max()
    rng = np.random.default_rng(seed)
    new, old, cover = [], [], []
    for _ in range(trials):
        curves = _noisy_seeds(rng, trend, n)
        s = ensemble_strength(curves, window=0.5 * D50, quantity="tan_phi")
        new.append(s.peak)
        cover.append(s.peak_lo <= truth <= s.peak_hi)
        old.append(moving_average(X, np.mean([r for _, r in curves], axis=0), 0.5 * D50).max())
    return np.mean(new) / truth - 1, np.mean(old) / truth - 1, np.mean(cover)


@pytest.mark.parametrize("shape", ["hump", "plateau"])
def test_the_peak_reads_the_known_peak_within_two_percent_at_three_seeds_and_one_and_a_half_at_five(shape):
    # the bagged leave-one-out peak reads low by what the others' location costs (measured here −1.7 %
    # and −1.1 % at 3 seeds, −1.2 % and −0.9 % at 5); the seed-mean curve's maximum, the estimator
    # before issue 41, reads high (+1.2 % on the hump, +7 % on the plateau at 3 seeds)
    trend = hump(X) if shape == "hump" else PLATEAU
    bias3, old3, cover3 = _biases(trend, 3, 1000)
    bias5, _, _ = _biases(trend, 5, 600)
    assert -0.02 < bias3 < 0 and -0.015 < bias5 < 0
    assert old3 > (0.05 if shape == "plateau" else 0.008)
    assert 0.85 <= cover3 <= 0.99          # measured 89 % on both


def _plain_leave_one_out(S):
    """Each seed read at the maximum of the other seeds' mean curve (the tool's peak before issue 39)."""
    others = (S.sum(0)[None, :] - S) / (len(S) - 1)
    return S[np.arange(len(S)), np.argmax(others, axis=1)]


def test_bagging_the_locators_halves_the_scatter_on_a_plateau_at_no_cost_in_bias():
    # on a plateau the maximum of the others' mean hops between near-equal bumps as each seed is left
    # out, and the seed read there is read where it is low: the plain leave-one-out estimate scatters
    # twice as much as the bagged one at 20 seeds (measured 3.4 % against 1.7 %), its interval covering
    # 72 % against 80 %
    from interphase.analysis.ensemble import _grid, _on_grid, peak_values
    from interphase.analysis.strength import moving_average

    truth = moving_average(X, PLATEAU, 0.5 * D50).max()
    rng = np.random.default_rng(11)
    bagged, plain = [], []
    for _ in range(120):
        curves = _noisy_seeds(rng, PLATEAU, 20)
        grid = _grid(curves, 400)
        S = np.array([moving_average(grid, r, 0.5 * D50) for r in _on_grid(curves, grid)])
        bagged.append(peak_values(S)[0].mean() / truth - 1)
        plain.append(_plain_leave_one_out(S).mean() / truth - 1)
    assert np.std(bagged) < 0.7 * np.std(plain)
    assert -0.015 < np.mean(bagged) < 0 and abs(np.mean(bagged) - np.mean(plain)) < 0.005


def test_e_of_three_interface_seeds_over_twenty_soil_seeds_is_within_one_and_a_half_percent():
    # E divides a 3-seed peak by a 20-seed one; the biases of the two are alike in sign and mostly
    # cancel (measured −1.1 %: −1.7 % over −0.6 %; the seed-mean maximum's +7 % over +2 % left E
    # about +4 % high on this pair)
    from interphase.analysis.strength import moving_average

    truth = moving_average(X, hump(X), 0.5 * D50).max() / moving_average(X, PLATEAU, 0.5 * D50).max()
    rng = np.random.default_rng(5)
    e = [ensemble_efficiency(_noisy_seeds(rng, hump(X), 3), _noisy_seeds(rng, PLATEAU, 20), window=0.5 * D50).peak
         for _ in range(400)]
    assert abs(np.mean(e) / truth - 1) < 0.015


def test_the_peak_does_not_ride_the_noise_of_a_plateau():
    # a plateau at 0.45 with run-to-run noise (sd 0.08): the mean of the per-seed maxima sits far
    # above it, the bagged leave-one-out peak within its interval of it
    rng = np.random.default_rng(3)
    curves = _noisy_seeds(rng, np.full_like(X, 0.45), 12, sd=0.08)
    s = ensemble_strength(curves, window=0.5 * D50)
    per_seed = np.mean([ensemble_strength([c], window=0.5 * D50).peak for c in curves])
    assert per_seed - 0.45 > 0.1 and abs(s.peak - 0.45) < 0.04
    assert s.peak_lo < 0.45 < s.peak_hi


def test_one_seed_has_no_interval_and_says_so():
    s = ensemble_strength([(X, hump(X))], window=0.5 * D50)
    assert math.isnan(s.peak_lo) and "one seed" in s.reason and s.peak == pytest.approx(0.6, abs=0.003)


def test_efficiency_of_scaled_curves_is_the_scale():
    box = [(X, hump(X, late=0.40 + 0.02 * k)) for k in range(3)]
    iface = [(x, 1.2 * r) for x, r in box]
    e = ensemble_efficiency(iface, box, window=0.5 * D50)
    assert e.peak == pytest.approx(1.2) and e.critical == pytest.approx(1.2)
    assert e.peak_lo <= 1.2 + 1e-9 and e.peak_hi >= 1.2 - 1e-9
    assert e.critical_lo < 1.2 < e.critical_hi


def test_runs_of_different_length_use_the_common_shear():
    short, long = np.linspace(0, 3e-3, 151), np.linspace(0, 6e-3, 301)
    s = ensemble_strength([(short, hump(short)), (long, hump(long))], window=0.5 * D50)
    assert s.critical == pytest.approx(np.mean(hump(long)[(long >= 0.6 * 3e-3) & (long <= 3e-3)]), rel=0.02)


def test_ratio_interval_covers_the_true_ratio_about_95_percent_of_the_time_with_three_seeds():
    # 3 interface seeds and 3 box seeds, each side's scatter ~15 % (the study's 1000-grain cells):
    # the interval of E must contain the true ratio in ~95 % of trials. The percentile bootstrap it
    # replaced covered 80 % here (this one 96 %) (its resamples of 3 values ignore that the sd is estimated).
    from interphase.analysis.ensemble import ratio_interval

    rng = np.random.default_rng(11)
    trials, true_a, true_b = 4000, 0.40, 0.45
    a = rng.normal(true_a, 0.06, (trials, 3))
    b = rng.normal(true_b, 0.07, (trials, 3))
    lo, hi = ratio_interval(a.mean(1), a.std(1, ddof=1), 3, b.mean(1), b.std(1, ddof=1), 3)
    cover = np.mean((lo <= true_a / true_b) & (true_a / true_b <= hi))
    assert 0.93 <= cover <= 0.99
    # what the bootstrap gave on the same data (percentile, 400 resamples of each side)
    ia, ib = rng.integers(0, 3, (400, 3)), rng.integers(0, 3, (400, 3))
    boot = a[:, ia].mean(2) / b[:, ib].mean(2)                   # (trials, 400)
    blo, bhi = np.percentile(boot, [2.5, 97.5], axis=1)
    assert np.mean((blo <= true_a / true_b) & (true_a / true_b <= bhi)) < 0.85


def test_ratio_interval_edges():
    from interphase.analysis.ensemble import ratio_interval

    assert ratio_interval(0.4, 0.0, 3, 0.5, 0.0, 3) == pytest.approx((0.8, 0.8))     # no scatter: a point
    assert all(math.isnan(x) for x in ratio_interval(0.4, 0.05, 1, 0.5, 0.05, 3))    # one seed: none
    lo, hi = ratio_interval(0.4, 0.05, 3, 0.5, 0.05, 10)
    assert lo < 0.8 < hi and hi / 0.8 == pytest.approx(0.8 / lo)                       # symmetric in log
    lo10, hi10 = ratio_interval(0.4, 0.05, 3, 0.5, 0.05, 3)
    assert hi10 - lo10 > hi - lo                                                      # more box seeds: narrower
