"""Strength of a physical case from its seed ensemble: the seed-mean curve, its peak and its
critical state, each with a 95 % interval over the seeds.

Why not the mean of per-seed peaks: one run's stress ratio at 1000–3000 grains fluctuates by
±0.05–0.12 around its trend (rearrangements of a few force chains), so its maximum is the largest
fluctuation and grows with the shear distance; on a box test whose curve has a weak peak it
compares two extremes of noise. Averaging the seeds' curves first (on a common displacement grid)
shrinks the fluctuations as 1/√n before the maximum is taken.

Definitions (shear displacement s [m], stress ratio r(s) [-] = τ/σ on the surface or shear plane):
  - seed-mean curve: r̄(s) = mean over seeds of r_i(s), each r_i linearly interpolated on a grid
    of `grid_points` over the shortest run's shear; then smoothed by a centred moving average of
    width `window` [m] (the summary's 0.5 D50).
  - peak = max_s r̄_smooth(s), at s_peak; interval: percentile bootstrap over seeds (seeds drawn
    with replacement, the whole definition recomputed; `n_boot` resamples, fixed generator seed).
  - critical = mean over seeds of each seed's mean r over s ≥ (1 − critical_fraction)·s_end;
    interval: Student t on the seed means.
  - E = peak(interface)/peak(box) and critical(interface)/critical(box); interval: bootstrap,
    seeds of the two tests resampled independently.
A single seed gives the values with NaN intervals (and says so).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from scipy import stats

from interphase.analysis.strength import moving_average

CRITICAL_FRACTION = 0.4     # the last 40 % of the shear: past the peak in every run measured
GRID_POINTS = 400
N_BOOT = 2000


@dataclass(frozen=True)
class EnsembleStrength:
    n_seeds: int
    peak: float
    peak_lo: float
    peak_hi: float
    peak_disp: float        # [m] where the smoothed seed-mean curve peaks
    critical: float
    critical_lo: float
    critical_hi: float
    reason: str = ""

    def to_dict(self) -> dict:
        return asdict(self)


def _grid(curves, grid_points: int) -> np.ndarray:
    ends = [float(np.nanmax(x)) for x, _ in curves]
    return np.linspace(0.0, min(ends), grid_points)


def _on_grid(curves, grid) -> np.ndarray:
    """(n_seeds, n_grid) ratios on the grid; NaN samples are dropped before interpolating."""
    out = np.empty((len(curves), grid.size))
    for i, (x, r) in enumerate(curves):
        x, r = np.asarray(x, float), np.asarray(r, float)
        ok = np.isfinite(x) & np.isfinite(r)
        order = np.argsort(x[ok], kind="stable")
        out[i] = np.interp(grid, x[ok][order], r[ok][order]) if ok.sum() >= 2 else np.nan
    return out


def _peak(mat: np.ndarray, grid: np.ndarray, window: float) -> tuple[float, float]:
    mean = np.nanmean(mat, axis=0)
    smooth = moving_average(grid, mean, window)
    if not np.isfinite(smooth).any():
        return math.nan, math.nan
    k = int(np.nanargmax(smooth))
    return float(smooth[k]), float(grid[k])


def _critical_means(mat: np.ndarray, grid: np.ndarray, fraction: float) -> np.ndarray:
    late = grid >= (1 - fraction) * grid[-1]
    return np.nanmean(mat[:, late], axis=1)


def ensemble_strength(curves, window: float, *, critical_fraction: float = CRITICAL_FRACTION,
                      grid_points: int = GRID_POINTS, n_boot: int = N_BOOT, seed: int = 0) -> EnsembleStrength:
    """Peak and critical state of the seed ensemble `curves` = [(shear_disp [m], ratio [-]), ...]."""
    curves = [c for c in curves if np.isfinite(np.asarray(c[1], float)).sum() >= 2]
    n = len(curves)
    if n == 0:
        nan = math.nan
        return EnsembleStrength(0, nan, nan, nan, nan, nan, nan, nan, "no run with a stress ratio")
    grid = _grid(curves, grid_points)
    mat = _on_grid(curves, grid)
    peak, at = _peak(mat, grid, window)
    cm = _critical_means(mat, grid, critical_fraction)
    crit = float(np.mean(cm))
    if n < 2:
        return EnsembleStrength(1, peak, math.nan, math.nan, at, crit, math.nan, math.nan,
                                "one seed: no interval (run ≥ 3 seeds)")
    rng = np.random.default_rng(seed)
    boot = np.array([_peak(mat[rng.integers(0, n, n)], grid, window)[0] for _ in range(n_boot)])
    lo, hi = np.nanpercentile(boot, [2.5, 97.5])
    half = stats.t.ppf(0.975, n - 1) * float(np.std(cm, ddof=1)) / math.sqrt(n)
    return EnsembleStrength(n, peak, float(lo), float(hi), at, crit, crit - half, crit + half)


@dataclass(frozen=True)
class EnsembleEfficiency:
    peak: float
    peak_lo: float
    peak_hi: float
    critical: float
    critical_lo: float
    critical_hi: float
    reason: str = ""

    def to_dict(self) -> dict:
        return asdict(self)


def ensemble_efficiency(interface_curves, box_curves, window: float, *,
                        critical_fraction: float = CRITICAL_FRACTION, grid_points: int = GRID_POINTS,
                        n_boot: int = N_BOOT, seed: int = 0) -> EnsembleEfficiency:
    """E = tan δ / tan φ from the two ensembles (peak over peak, critical over critical), with
    bootstrap intervals (each test's seeds resampled on its own)."""
    a = ensemble_strength(interface_curves, window, critical_fraction=critical_fraction, grid_points=grid_points,
                          n_boot=1, seed=seed)
    b = ensemble_strength(box_curves, window, critical_fraction=critical_fraction, grid_points=grid_points,
                          n_boot=1, seed=seed)
    e_peak, e_crit = a.peak / b.peak, a.critical / b.critical
    if a.n_seeds < 2 or b.n_seeds < 2:
        nan = math.nan
        return EnsembleEfficiency(e_peak, nan, nan, e_crit, nan, nan, "fewer than two seeds on a side: no interval")
    ga, gb = _grid(interface_curves, grid_points), _grid(box_curves, grid_points)
    ma, mb = _on_grid(interface_curves, ga), _on_grid(box_curves, gb)
    ca, cb = _critical_means(ma, ga, critical_fraction), _critical_means(mb, gb, critical_fraction)
    rng = np.random.default_rng(seed)
    na, nb = len(ma), len(mb)
    peaks, crits = np.empty(n_boot), np.empty(n_boot)
    for k in range(n_boot):
        ia, ib = rng.integers(0, na, na), rng.integers(0, nb, nb)
        peaks[k] = _peak(ma[ia], ga, window)[0] / _peak(mb[ib], gb, window)[0]
        crits[k] = ca[ia].mean() / cb[ib].mean()
    (pl, ph), (cl, ch) = np.nanpercentile(peaks, [2.5, 97.5]), np.nanpercentile(crits, [2.5, 97.5])
    return EnsembleEfficiency(e_peak, float(pl), float(ph), e_crit, float(cl), float(ch))
