"""The laboratory's element test (triaxial / biaxial) of one soil at one confining stress, from its
seed runs together: angles by the laboratory's definitions (analysis/triaxial.py), each seed read as
the laboratory reads its specimen, intervals from the seeds.

Definitions (ε1 axial strain, εv volumetric strain, R = σ1′/σ3′, compression positive):
  - the seed-mean curves: each seed's R(ε1) and εv(ε1) interpolated on a common grid of GRID_STEP
    up to the shortest run's ε1, R smoothed over SMOOTH_EPS1 (analysis.cell_run), averaged over the
    seeds; `shear_state` of those curves gives the end state.
  - φ_peak: each seed's own maximum of its smoothed R, as the laboratory reads each specimen, the
    mean of those values mapped through asin((R − 1)/(R + 1)), interval Student t on them; ε1 at
    peak the mean of the seeds' own peak strains. Not the seed-mean curve's maximum, nor the
    cross-fitted peak of the interface (analysis.ensemble.peak_values): a laboratory specimen of
    millions of grains has no grain-scale fluctuation, and where model specimens' humps peak at
    different strains both read below every specimen's own peak. Measured (studies/peak_estimators/triaxial_peak.py,
    82 runs of the Karlsruhe card, a known hump plus real runs' fluctuation, 2–3 seeds): this
    estimator within ±0.06° of the specimens' mean peak, the leave-one-out −0.5 to −0.75° (rms up
    to 1.1°), the mean curve's maximum −0.04 to −0.22°.
  - ψ_max: likewise each seed's own, as the laboratory reads its specimen: its εv smoothed over
    SMOOTH_EPS1 like R, then the largest −dεv/dε1 of a straight line over a 1 % window; the mean of
    those rates mapped through asin(r/(2 + r)), interval Student t on them. Not the seed-mean
    curve's window: where seeds dilate fastest at different strains their mean curve dilates more
    slowly than any of them, so that reading fell with the number of seeds (docs/soils/kfs_best_sample,
    every subset of n of 6 seeds: 0.6–1.1° under the seeds' own at n = 2, 1.4–1.7° at 6 in 3D; in
    quasi-2D, docs/soils/kfs_2d_seeds, 3.1° at 2 and 6.5° at 6). Against a known hump plus real
    runs' fluctuation (studies/peak_estimators/triaxial_peak.py, hump = a Savitzky–Golay quadratic over 2–4 % of ε1,
    n = 2–6): the smoothed per-seed reading is within −0.3 to +0.2° in 3D (82 runs) and −1.4 to
    +0.9° in quasi-2D (114 runs), the same at every n; unsmoothed it read +0.2 to +0.7° and +0.8
    to +3.7° high (εv's fluctuation enters a slope); the mean curve's window −0.9 to +0.1° and
    −3.2 to +1.3°, falling with n. On the laboratory's 15 Karlsruhe records, already smooth, the
    smoothing moves ψ_max by −0.16 to +0.24°.
  - intervals (95 %, Student t over the seeds): φ_cs (the end state: mean R over the last END_SPAN of ε1) from each
    seed's end value; e from each seed's void ratio at the start of the compression.
  - relative density Dr = (e_max − e)/(e_max − e_min), e the mean void ratio at the start of the
    compression, e_min/e_max the card's own (its [density] table, soil.py); NaN without them.
`phi_cs_deg` is the end state's angle; `dilatancy_end` > 0 says the specimen was still dilating
there, so that angle is not yet a critical state (the laboratory's Karlsruhe records end so too).
Measured on the Karlsruhe card's spheres (docs/soils.md, "From dense to loose"): at 20 % of ε1 they
still dilate at 0.9–1.0 and their angle is 11° above the one they settle at by 35–40 %.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from interphase.analysis.cell_run import SMOOTH_EPS1
from interphase.analysis.ensemble import t_interval
from interphase.analysis.strength import moving_average
from interphase.analysis.triaxial import END_SPAN, WINDOW, friction_angle, psi_from_rate, shear_state, window_slopes

GRID_STEP = 0.001      # [-] the common ε1 grid of the seed-mean curves

#: |−dεv/dε1| over the end span above which the end state is not read as a critical state
CRITICAL_RATE = 0.05


def at_critical_state(dilatancy_end: float) -> bool:
    """Whether the volume has stopped changing at the end (|−dεv/dε1| ≤ CRITICAL_RATE); NaN is not."""
    return abs(dilatancy_end) <= CRITICAL_RATE


@dataclass(frozen=True)
class CellResult:
    """One soil at one confining stress: angles [°], strains [-], each with a 95 % interval over the
    seeds (NaN with fewer than two)."""

    test: str
    confining_stress: float          # [Pa]
    n_seeds: int
    phi_peak_deg: float
    phi_peak_deg_lo: float
    phi_peak_deg_hi: float
    eps1_at_peak: float
    psi_max_deg: float
    psi_max_deg_lo: float
    psi_max_deg_hi: float
    phi_cs_deg: float
    phi_cs_deg_lo: float
    phi_cs_deg_hi: float
    dilatancy_end: float             # −dεv/dε1 over the end span of the seed-mean curve
    void_ratio: float                # at the start of the compression (2D: the area void ratio)
    void_ratio_lo: float
    void_ratio_hi: float
    relative_density: float          # [-] on the card's e_min, e_max; NaN without them
    eps1_end: float                  # the shortest seed's axial strain
    preparation: float = math.nan
    note: str = ""

    def to_dict(self) -> dict:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}


def mean_curves(runs, step: float = GRID_STEP):
    """(grid, R (n, m), εv (n, m)) of `runs` = [(ε1, εv, R), ...] on a common ε1 grid."""
    end = min(float(np.nanmax(r[0])) for r in runs)
    grid = np.arange(0.0, end + 1e-12, step)
    R = np.array([np.interp(grid, *_sorted(x, r)) for x, _, r in runs])
    V = np.array([np.interp(grid, *_sorted(x, v)) for x, v, _ in runs])
    return grid, R, V


def _sorted(x, y):
    x, y = np.asarray(x, float), np.asarray(y, float)
    o = np.argsort(x, kind="stable")
    return x[o], y[o]


def _interval(values, fn=lambda v: v, floor: float = -math.inf):
    """The 95 % interval of `values` mapped through `fn`. Bounds below `floor` (where fn is
    defined: R ≥ 0, r ≥ −1) are held at it: two seeds far apart (t = 12.7) can reach below, and the
    angle's interval then ends at −90°, not NaN."""
    lo, hi = t_interval(np.asarray(values, float))
    return float(fn(max(lo, floor))), float(fn(max(hi, floor)))


def cell_result(test: str, confining_stress: float, runs, void_ratios, *, e_limits=(math.nan, math.nan),
                preparation: float = math.nan) -> CellResult:
    """`runs` = [(ε1, εv, R), ...] one per seed (a run's history columns); `void_ratios` each seed's
    e at the start of the compression; `e_limits` = (e_min, e_max) of the card's grains."""
    n = len(runs)
    if n == 0:
        nan = math.nan
        return CellResult(test, confining_stress, 0, *(nan,) * 16, preparation, "no finished run")
    grid, R, V = mean_curves(runs)
    smooth = np.array([moving_average(grid, r, SMOOTH_EPS1) for r in R])
    state = shear_state(grid, V.mean(axis=0), smooth.mean(axis=0))
    seed_peak = np.nanmax(smooth, axis=1)
    eps1_peak = float(np.mean(grid[np.nanargmax(smooth, axis=1)]))
    seed_rate = np.array([np.nanmax(-window_slopes(grid, moving_average(grid, v, SMOOTH_EPS1), WINDOW)[1]) for v in V])
    tail = grid >= grid[-1] - END_SPAN
    seed_end = R[:, tail].mean(axis=1)
    e = np.asarray(void_ratios, float)
    e_min, e_max = e_limits
    dr = (e_max - e.mean()) / (e_max - e_min) if np.isfinite([e_min, e_max]).all() else math.nan
    notes = [] if n >= 2 else ["one seed: no intervals (run ≥ 3 seeds)"]
    if not at_critical_state(state.dilatancy_end):
        notes.append(f"the volume still changes at ε1 = {grid[-1]:.0%} (−dεv/dε1 = {state.dilatancy_end:.2f}): φ_cs is "
                     "the end state's angle, not yet a critical state")
    return CellResult(
        test, confining_stress, n, float(friction_angle(np.mean(seed_peak))), *_interval(seed_peak, friction_angle, 0.0),
        eps1_peak,
        float(psi_from_rate(seed_rate.mean())), *_interval(seed_rate, psi_from_rate, -1.0), state.phi_end_deg,
        *_interval(seed_end, friction_angle, 0.0), state.dilatancy_end, float(e.mean()), *_interval(e), dr,
        float(grid[-1]), preparation, "; ".join(notes))


