"""Strength of a physical case from its seed ensemble: its peak and its critical state, each with a
95 % interval over the seeds.

Definitions (shear displacement s [m], stress ratio r(s) [-] = τ/σ on the surface or shear plane):
  - each seed's curve r_i(s) linearly interpolated on a grid of `grid_points` over the shortest run's
    shear, then smoothed by a centred moving average of width `window` [m] (the summary's 0.5 D50):
    S_i(s). The quantity a peak estimates is μ* = max_s E[S(s)], the maximum of the expected curve.
  - peak (`peak_values`, the one estimator of a peak in the tool: tan δ, tan φ, E, the element
    test's φ_peak): bagged leave-one-out cross-fitting. Seed i's value is the mean of S_i read at
    the maxima of BAGS bootstrap means of the OTHER seeds; the peak is the mean of those values;
    interval: Student t on them (`seed_interval` with a quantity). Why cross-fit: the maximum of the
    seed-mean curve itself, the estimator before issue 41, takes the maximum of noise along with the
    curve (one run fluctuates by ±0.05–0.12 around its trend), so it reads high by about noise/√n:
    +6 % at 3 seeds of the weak soil's plateau, +14 % for the uniform soil. Reading each seed where
    the others put the maximum takes none of its own noise: its expected value is E[S] at a location
    ≤ μ*, so the estimator can only read low, by what the location's scatter costs on the curve. Why
    bag the locators: read at the single maximum of the others' mean, a seed on a plateau with
    near-equal bumps is read at whichever bump its own absence leaves highest, i.e. where it is low;
    that estimate scatters up to twice as much on a plateau at 5–40 seeds and its interval covers
    67–82 % at 10–40 (on 40 uniform soil-test seeds it read tan φ 0.281, under every block of the same
    seeds, 0.300–0.344). Averaging each seed over the others' bootstrap maxima removes the hop: on
    known curves with the committed runs' own noise the spread falls by 30–55 % on plateaus and the
    coverage rises to 80–92 %, for 0.2–1.4 % more low bias on peaked curves at 3–5 seeds
    (studies/peak_estimators/peak_estimators.py; BENCHMARKS.md "Bagged locators"). Every per-seed t-interval here is
    still too narrow on real data (real sd 1.0–1.7× the claimed standard error). One seed: its own maximum (the reason says so).
  - peak_disp: where the mean curve of all the seeds peaks (a location, not the estimate).
  - critical = mean over seeds of each seed's mean r over s ≥ (1 − critical_fraction)·s_end;
    interval: Student t on the seed means.
  - E = peak(interface)/peak(box) and critical(interface)/critical(box), from the seed values
    above; interval: `ratio_interval`, the delta method on log E with Welch–Satterthwaite degrees of
    freedom (the two tests' seeds are independent samples). Why not a percentile bootstrap of the
    ratio of means, as before 2026-11-23: with 3 seeds a side it resamples only 10 distinct means per
    side and ignores that the sd is estimated, so its "95 %" interval covered the true E in 80 % of
    synthetic trials at a 15 % scatter a side, this interval in 96 % (tests/test_ensemble.py).
A single seed gives the values with NaN intervals (and says so).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd
from scipy import stats

from interphase.analysis.strength import moving_average

CRITICAL_FRACTION = 0.4     # the last 40 % of the shear (3.6–6 mm of the convergence runs' 6 mm)
GRID_POINTS = 400
BAGS = 200                  # bootstrap locators per seed: the peak's Monte Carlo sd is 0.07–0.3 % of it
                            # on the committed curves (4–40 seeds), far under the seeds' own scatter


@dataclass(frozen=True)
class Estimates:
    """A peak and a critical-state value, each with its 95 % interval (NaN where undefined)."""
    peak: float
    peak_lo: float
    peak_hi: float
    critical: float
    critical_lo: float
    critical_hi: float
    reason: str = ""

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class EnsembleStrength(Estimates):
    """A seed ensemble's stress ratio [-] at the peak and the critical state."""
    n_seeds: int = 0
    peak_disp: float = math.nan        # [m] where the smoothed seed-mean curve of all the seeds peaks


class EnsembleEfficiency(Estimates):
    """E = tan δ / tan φ [-] at the peak and the critical state."""


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


def peak_values(smooth: np.ndarray, bags: int = BAGS) -> tuple[np.ndarray, int]:
    """Each seed's peak value by bagged leave-one-out cross-fitting (the module doc), and the grid
    index where the mean of all the seeds peaks. `smooth`: (n_seeds, n_grid) smoothed curves on one
    grid, NaN where a seed has no value. Seed i is read at the maxima of `bags` bootstrap means of the
    OTHER seeds (drawn by a generator of fixed seed, so the value is a function of the curves alone)
    and its value is the mean of those reads. Two seeds: each read where the other peaks. One seed:
    its own maximum."""
    smooth = np.asarray(smooth, float)
    n = len(smooth)
    ok = np.isfinite(smooth)
    filled = np.where(ok, smooth, 0.0)
    count = ok.sum(0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(count > 0, filled.sum(0) / count, np.nan)
    if not np.isfinite(mean).any():
        return np.full(n, np.nan), -1
    at = int(np.nanargmax(mean))
    if n == 1:
        return np.array([np.nanmax(smooth[0])]), at
    draw = np.random.default_rng(0).integers(0, n - 1, size=(n, bags, n - 1))
    draw = draw + (draw >= np.arange(n)[:, None, None])               # never seed i itself
    rows = np.repeat(np.arange(n * bags), n - 1)
    weights = np.bincount(rows * n + draw.ravel(), minlength=n * bags * n).reshape(n * bags, n).astype(float)
    located = weights @ filled                                        # n − 1 times each bootstrap mean
    if not ok.all():
        with np.errstate(invalid="ignore", divide="ignore"):
            located = located / (weights @ ok.astype(float))
        located = np.where(np.isfinite(located), located, -np.inf)
    where = np.argmax(located, axis=1).reshape(n, bags)
    with np.errstate(invalid="ignore"):
        return np.nanmean(smooth[np.arange(n)[:, None], where], axis=1), at


def _peak_states(mat: np.ndarray, grid: np.ndarray, window: float) -> tuple[np.ndarray, float]:
    """Each seed's peak value (`peak_values` on its curve smoothed over `window`) and s_peak."""
    smooth = np.array([moving_average(grid, r, window) for r in mat]).reshape(mat.shape)
    values, at = peak_values(smooth)
    return values, (float(grid[at]) if at >= 0 else math.nan)


def _critical_states(mat: np.ndarray, grid: np.ndarray, fraction: float) -> np.ndarray:
    late = grid >= (1 - fraction) * grid[-1]
    return np.nanmean(mat[:, late], axis=1)


def t_interval(values) -> tuple[float, float]:
    """95 % Student-t interval of the mean of `values` (NaN, NaN for fewer than two)."""
    n = len(values)
    if n < 2:
        return math.nan, math.nan
    half = stats.t.ppf(0.975, n - 1) * float(np.std(values, ddof=1)) / math.sqrt(n)
    m = float(np.mean(values))
    return m - half, m + half


#: fewer seeds than this give no interval: with 2 seeds Student's t is 12.7 and the "95 %" interval of
#: a stress ratio or an angle reaches far outside what the quantity can be (tan δ from −0.39, θr to 139°
#: on the quick campaign), which says nothing a reader can use
MIN_SEEDS = 3

#: the range a quantity's interval must respect: "log" for a positive ratio (its interval is taken on
#: the log scale, `seed_interval`), (lo, hi) for a bounded one (the t interval clipped to it). Angles ψ
#: are principal directions in [−90°, 90°) (analysis.anisotropy); a share lies in [0, 1].
QUANTITY_RANGE = {
    "peak_stress_ratio": "log", "tan_delta": "log", "tan_phi": "log", "residual_stress_ratio": "log",
    "stress_ratio_region": "log", "inertial_number": "log", "shear_band_d50": "log",
    "theta_r_surface_deg": (-90.0, 90.0), "theta_n_surface_deg": (-90.0, 90.0),
    "theta_r_region_deg": (-90.0, 90.0), "theta_n_region_deg": (-90.0, 90.0),
    "theta_a_deg_92": (0.0, 90.0), "theta_a_deg_90": (0.0, 90.0), "theta_a_ccw_deg_90": (0.0, 180.0),
    "friction_angle_deg": (0.0, 90.0),
    "lee_share_surface": (0.0, 1.0), "slide_share_surface": (0.0, 1.0), "shear_disp_at_peak": (0.0, math.inf), "dilation_at_peak": (-math.inf, math.inf),
}


def seed_interval(mean, sd, n, quantity: str | None = None, level: float = 0.95):
    """(lo, hi) of the 95 % interval of a mean of n seeds (mean, sample sd, n: scalars or arrays,
    elementwise), respecting `quantity`'s range (QUANTITY_RANGE; unlisted: the plain t interval).

    - fewer than MIN_SEEDS seeds: NaN (no interval; the tables say so);
    - a positive ratio ("log": tan δ, tan φ, the region's stress ratio …): the delta method on the
      log of the mean, mean·exp(±t·s/(mean·√n)), Student t with n − 1 degrees of freedom. Why: a
      ratio is positive and its scatter scales with it; the interval stays above 0, is asymmetric as
      a ratio's should be, equals the t interval to first order in s/mean (both ends move up by
      about h²/2 of the value, h = t·s/(mean·√n): 0.3 % at 3 seeds and a 3 % scatter, 1.1 % at 6 %),
      and is the method of E's interval (`ratio_interval`). NaN for a non-positive mean.
    - a bounded quantity ((lo, hi): angles ψ in [−90°, 90°), a share in [0, 1]): the t interval
      clipped to the range. Why not circular statistics: the summaries give each seed's ψ already
      reduced to [−90°, 90°) and the tables print the seeds' arithmetic mean, which the interval is
      about; a t interval of a case near the bound (θr ≈ 85° on the reproduction's steepest teeth)
      would reach past 90°, a direction the range writes as its negative, so the clip marks the
      bound instead."""
    m, s, k = (np.asarray(x, float) for x in (mean, sd, n))
    with np.errstate(invalid="ignore", divide="ignore"):
        t = stats.t.ppf(0.5 + level / 2, np.maximum(k - 1, 1))
        half = t * s / np.sqrt(np.maximum(k, 1))
        rng = QUANTITY_RANGE.get(quantity) if quantity else None
        if rng == "log":
            h = half / m
            lo, hi = np.where(m > 0, m * np.exp(-h), np.nan), np.where(m > 0, m * np.exp(h), np.nan)
        else:
            lo, hi = m - half, m + half
            if rng is not None:
                lo, hi = np.clip(lo, *rng), np.clip(hi, *rng)
        few = ~(k >= MIN_SEEDS) | ~np.isfinite(s)
        lo, hi = np.where(few, np.nan, lo), np.where(few, np.nan, hi)
    return (float(lo), float(hi)) if lo.ndim == 0 else (lo, hi)


def values_interval(values, quantity: str | None = None) -> tuple[float, float]:
    """`seed_interval` of the finite `values` (one per seed)."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    if v.size < 2:
        return math.nan, math.nan
    return seed_interval(float(v.mean()), float(np.std(v, ddof=1)), v.size, quantity)


def ratio_interval(mean_a, sd_a, n_a, mean_b, sd_b, n_b, level: float = 0.95):
    """(lo, hi) of the ratio of two independent means ā/b̄ (each of n samples with sd s), elementwise.

    Delta method on the log: var(log ā/b̄) ≈ s_a²/(n_a ā²) + s_b²/(n_b b̄²); Student t with the
    Welch–Satterthwaite degrees of freedom of those two terms; the interval is exp(log ā/b̄ ± t·se),
    asymmetric about the ratio as a ratio's should be. NaN where a side has fewer than two values or
    a non-positive mean; a point interval when both sds are 0."""
    a, sa, na, b, sb, nb = (np.asarray(x, float) for x in (mean_a, sd_a, n_a, mean_b, sd_b, n_b))
    with np.errstate(invalid="ignore", divide="ignore"):
        ua, ub = sa * sa / (na * a * a), sb * sb / (nb * b * b)
        u = ua + ub
        dof = u * u / (ua * ua / (na - 1) + ub * ub / (nb - 1))
        t = stats.t.ppf(0.5 + level / 2, np.where(np.isfinite(dof) & (dof > 0), dof, 1.0))
        half = np.where(u > 0, t * np.sqrt(u), 0.0)
        r = a / b
        ok = (na >= 2) & (nb >= 2) & (a > 0) & (b > 0) & np.isfinite(u)
        lo, hi = np.where(ok, r * np.exp(-half), np.nan), np.where(ok, r * np.exp(half), np.nan)
    return (float(lo), float(hi)) if lo.ndim == 0 else (lo, hi)


def _ratio_of_means(a: np.ndarray, b: np.ndarray) -> tuple[float, float, float]:
    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    sd = lambda v: float(np.std(v, ddof=1)) if v.size > 1 else math.nan
    return (float(a.mean() / b.mean()),
            *ratio_interval(a.mean(), sd(a), a.size, b.mean(), sd(b), b.size))


def _states(curves, window: float, critical_fraction: float, grid_points: int):
    grid = _grid(curves, grid_points)
    mat = _on_grid(curves, grid)
    peaks, at = _peak_states(mat, grid, window)
    return peaks, at, _critical_states(mat, grid, critical_fraction)


def ensemble_states(curves, window: float, *, critical_fraction: float = CRITICAL_FRACTION,
                    grid_points: int = GRID_POINTS):
    """(peak values, s_peak [m], critical states) of the seeds `curves`, each with ≥ 2 finite ratios:
    what `ensemble_strength` and `ensemble_efficiency` summarise (`strength_of_states`,
    `efficiency_of_states`), for a caller that reads one ensemble more than once."""
    return _states(curves, window, critical_fraction, grid_points)


def usable(curve) -> bool:
    """Whether a (shear_disp, ratio) curve can join an ensemble: present, with ≥ 2 finite ratios."""
    return curve is not None and np.isfinite(np.asarray(curve[1], float)).sum() >= 2


def _usable(curves) -> list:
    return [c for c in curves if usable(c)]


def ensemble_strength(curves, window: float, *, critical_fraction: float = CRITICAL_FRACTION,
                      grid_points: int = GRID_POINTS, quantity: str | None = None) -> EnsembleStrength:
    """Peak and critical state of the seed ensemble `curves` = [(shear_disp [m], ratio [-]), ...].
    Intervals: Student t over the seeds' values (`t_interval`); with `quantity` (e.g. "tan_delta")
    `seed_interval`'s, which respects the quantity's range and needs MIN_SEEDS seeds."""
    curves = _usable(curves)
    if not curves:
        nan = math.nan
        return EnsembleStrength(nan, nan, nan, nan, nan, nan, "no run with a stress ratio")
    return strength_of_states(*_states(curves, window, critical_fraction, grid_points), quantity=quantity)


def strength_of_states(peaks, at: float, crits, *, quantity: str | None = None) -> EnsembleStrength:
    """`ensemble_strength` from its seeds' states (`_states`: peak values, s_peak, critical states),
    for a caller that reads one ensemble more than once (analysis.ensemble_table)."""
    n = len(peaks)
    iv = t_interval if quantity is None else (lambda v: values_interval(v, quantity))
    least = 2 if quantity is None else MIN_SEEDS
    count = "one seed" if n == 1 else f"{n} seeds"
    reason = "" if n >= least else f"{count}: no interval (run ≥ {MIN_SEEDS} seeds)"
    if n == 1:
        reason += "; the peak is the run's own maximum (nothing to cross-fit: reads high)"
    return EnsembleStrength(float(np.mean(peaks)), *iv(peaks), float(np.mean(crits)), *iv(crits),
                            reason, n_seeds=n, peak_disp=at)


def ensemble_efficiency(interface_curves, box_curves, window: float, *,
                        critical_fraction: float = CRITICAL_FRACTION,
                        grid_points: int = GRID_POINTS) -> EnsembleEfficiency:
    """E = tan δ / tan φ from the two ensembles (peak over peak, critical over critical), with
    95 % intervals of a ratio of independent means (`ratio_interval`)."""
    a, b = _usable(interface_curves), _usable(box_curves)
    if not a or not b:
        nan = math.nan
        return EnsembleEfficiency(nan, nan, nan, nan, nan, nan, "no run with a stress ratio on a side")
    pa, _, ca = _states(a, window, critical_fraction, grid_points)
    pb, _, cb = _states(b, window, critical_fraction, grid_points)
    return efficiency_of_states(pa, ca, pb, cb)


def efficiency_of_states(pa, ca, pb, cb) -> EnsembleEfficiency:
    """`ensemble_efficiency` from the two sides' seed states (peak values, critical states)."""
    reason = "" if len(pa) > 1 and len(pb) > 1 else "fewer than two seeds on a side: no interval"
    return EnsembleEfficiency(*_ratio_of_means(pa, pb), *_ratio_of_means(ca, cb), reason)


# ---- additions for the report's per-case points (analysis.correlations.seed_ensemble) --------------
def physical_case(label: str) -> str:
    """A case label without its packing seed (`…-s3`): the NAME of the physical case its seeds share
    (tables and figures show it; runs are pooled by `physical_ids`)."""
    import re

    return re.sub(r"-s\d+$", "", str(label))


def physical_ids(runs: pd.DataFrame) -> pd.Series:
    """Each run's physical case: its `physical_id` (interphase.case.physical_id, set at plan time;
    campaign.results fills it in for runs indexed before it existed), else — a table without the
    column, as tests build them — its name (`physical_case` of the label) marked "name:"."""
    label = runs["label"] if "label" in runs else pd.Series("", index=runs.index)
    names = "name:" + label.map(physical_case).astype(str)
    if "physical_id" not in runs:
        return names
    have = runs["physical_id"]
    return have.where(have.notna() & have.astype(str).ne(""), names).astype(str)


def seed_states(curves, window: float, *, critical_fraction: float = CRITICAL_FRACTION,
                grid_points: int = GRID_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """Each seed's peak value (read where the other seeds' mean curve peaks, `peak_values`) and its
    critical state (mean over the last `critical_fraction`),
    aligned with `curves`; NaN for an entry that is None or has fewer than two finite ratios. Their
    means are `ensemble_strength(curves, window)`'s peak and critical; resampling them is how
    `ensemble_efficiency` and the correlations' seed bootstrap vary the strength."""
    peaks, crits = np.full(len(curves), np.nan), np.full(len(curves), np.nan)
    ok = [i for i, c in enumerate(curves) if usable(c)]
    if ok:
        p, _, c = _states([curves[i] for i in ok], window, critical_fraction, grid_points)
        peaks[ok], crits[ok] = p, c
    return peaks, crits


def seed_peak_states(curves, window: float, **kw) -> np.ndarray:
    """The peak half of `seed_states`."""
    return seed_states(curves, window, **kw)[0]
