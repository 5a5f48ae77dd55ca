"""The soil's element test: friction and dilatancy angles of a seed ensemble of periodic shear tests
of the soil alone (Case test = "box", device = "periodic": the soil sheared against a frozen bed of
its own grains under a servo platen, x periodic, no walls; engines/device.py).

Definitions (shear displacement u [m] of the bed relative to the platen, τ/σ the stress ratio on
the horizontal plane, h the platen height [m]):
  - φ_peak = atan of the seed ensemble's peak τ/σ (analysis.ensemble.peak_values, the tool's one
    peak: each seed's curve smoothed over 0.5 D50 and read where the OTHER seeds' mean curve peaks,
    the peak the mean of those values; interval: Student t on them, mapped through atan). Measured
    bias at 3 seeds on known curves with the committed soil tests' noise: −0.6 to −1.0 %
    (well-graded), −0.9 to −2.6 % (uniform); the seed-mean curve's maximum used before read +0.5 to
    +14 % (docs/methods.md "The peak of a seed ensemble").
  - φ_cs = atan of the mean τ/σ over the last 40 % of the shear (ensemble's critical state).
  - ψ_max = atan of the largest seed-mean dilation rate dh/du, each seed's rate being the slope of
    a local straight-line fit to h(u) over DILATANCY_WINDOW_D50 (Savitzky–Golay, order 1); interval:
    Student t on each seed's rate at that displacement.
These are the direct-shear angles a laboratory shear box reports (atan τ/σ on the horizontal plane,
atan of the vertical over the horizontal displacement rate), the quantities E = tan δ / tan φ uses.

A dense specimen peaks early and then softens toward its critical state. `has_peak` is true when
the mean curve of all the seeds peaks within the first PEAK_BEFORE (60 %) of the shear; when it does not,
the specimen never passed its critical state within the test (as loose or looser), φ_peak is still
the curve's maximum, and the result says so in `note`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from scipy.signal import savgol_filter

from interphase.analysis.ensemble import CRITICAL_FRACTION, GRID_POINTS, ensemble_strength, t_interval
from interphase.analysis.strength import PEAK_WINDOW_D50

PEAK_BEFORE = 0.6               # a peak must lie within this share of the shear
CRYSTALLINE_PSI6 = 0.7          # mean hexatic order above which a specimen is crystallised (measured:
                                # well-graded 0.50–0.52, uniform 0.84–0.88; docs/soils.md)
DILATANCY_WINDOW_D50 = 1.0      # [D50] the straight-line fit that gives the dilation rate


@dataclass(frozen=True)
class ElementResult:
    """The element test of one soil at one normal stress: angles in degrees, each with its 95 %
    interval over the seeds (NaN with fewer than two seeds); solid fraction [-] at the start of
    the shear (2D: grain sections over area)."""

    normal_stress: float            # [Pa]
    n_seeds: int
    phi_peak_deg: float
    phi_peak_deg_lo: float
    phi_peak_deg_hi: float
    phi_cs_deg: float
    phi_cs_deg_lo: float
    phi_cs_deg_hi: float
    psi_max_deg: float
    psi_max_deg_lo: float
    psi_max_deg_hi: float
    solid_fraction: float
    solid_fraction_lo: float
    solid_fraction_hi: float
    peak_disp: float                # [m] where the seed-mean curve peaks
    shear_distance: float           # [m] the shortest seed's shear
    has_peak: bool
    note: str = ""
    order_psi6: float = math.nan    # mean hexatic bond order |ψ6| of the grains at the start of the shear

    @property
    def crystallised(self) -> bool:
        return bool(self.order_psi6 > CRYSTALLINE_PSI6)

    def to_dict(self) -> dict:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}


def hexatic_order(x, z, radius, gap: float = 0.1) -> float:
    """Mean over grains of |ψ6| = |mean over neighbours of exp(6iθ)| [-], neighbours being grains
    closer than (r_i + r_j)(1 + gap), θ the bond's angle in the x–z plane. Equal discs in a
    triangular lattice give 1; a disordered packing about 0.3–0.5. Grains with fewer than two
    neighbours are left out. x-periodicity is ignored (edge grains lose a bond or two)."""
    from scipy.spatial import cKDTree

    pts = np.column_stack([x, z])
    r = np.asarray(radius, float)
    pairs = cKDTree(pts).query_pairs(2 * r.max() * (1 + gap), output_type="ndarray")
    if not len(pairs):
        return math.nan
    i, j = pairs[:, 0], pairs[:, 1]
    d = pts[j] - pts[i]
    near = np.hypot(d[:, 0], d[:, 1]) < (r[i] + r[j]) * (1 + gap)
    i, j, d = i[near], j[near], d[near]
    e = np.exp(6j * np.arctan2(d[:, 1], d[:, 0]))          # a bond and its reverse give the same e
    total = np.bincount(i, e.real, len(r)) + np.bincount(j, e.real, len(r)) \
        + 1j * (np.bincount(i, e.imag, len(r)) + np.bincount(j, e.imag, len(r)))
    count = np.bincount(i, minlength=len(r)) + np.bincount(j, minlength=len(r))
    ok = count >= 2
    return float(np.mean(np.abs(total[ok] / count[ok]))) if ok.any() else math.nan


def _deg(x: float) -> float:
    return math.degrees(math.atan(x)) if math.isfinite(x) else math.nan


def dilation_rates(curves, d50: float, grid_points: int = GRID_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """(grid [m], rates (n_seeds, n_grid) [-]): each seed's dh/du on a common grid over the shortest
    shear, the slope of a straight line fitted to h(u) over DILATANCY_WINDOW_D50 about each point.
    `curves` = [(u [m], h [m]), ...]."""
    end = min(float(np.nanmax(u)) for u, _ in curves)
    grid = np.linspace(0.0, end, grid_points)
    step = grid[1] - grid[0]
    width = max(3, int(round(DILATANCY_WINDOW_D50 * d50 / step)) | 1)     # odd, ≥ 3 points
    rates = np.empty((len(curves), grid.size))
    for i, (u, h) in enumerate(curves):
        u, h = np.asarray(u, float), np.asarray(h, float)
        ok = np.isfinite(u) & np.isfinite(h)
        order = np.argsort(u[ok], kind="stable")
        on_grid = np.interp(grid, u[ok][order], h[ok][order])
        rates[i] = savgol_filter(on_grid, min(width, grid.size - (1 - grid.size % 2)), 1, deriv=1, delta=step,
                                 mode="interp")
    return grid, rates


def element_result(runs, d50: float, normal_stress: float, order_psi6=()) -> ElementResult:
    """The element test from its seed runs: `runs` = [(u [m], τ/σ [-], h [m], solid fraction [-]),
    ...], one per seed (u, τ/σ, h arrays of one run's series); `order_psi6`: each seed's hexatic
    order at the start of the shear (`hexatic_order`), if known."""
    runs = [r for r in runs if np.isfinite(np.asarray(r[1], float)).sum() >= 2]
    n = len(runs)
    nan3 = (math.nan,) * 3
    if not n:
        return ElementResult(normal_stress, 0, *nan3, *nan3, *nan3, *nan3, math.nan, math.nan, False,
                             "no run with a stress ratio")
    strength = ensemble_strength([(u, r) for u, r, _, _ in runs], PEAK_WINDOW_D50 * d50,
                                 critical_fraction=CRITICAL_FRACTION)
    grid, rates = dilation_rates([(u, h) for u, _, h, _ in runs], d50)
    mean_rate = np.nanmean(rates, axis=0)
    at = int(np.nanargmax(mean_rate))
    psi = rates[:, at]
    sf = np.array([s for *_, s in runs], float)
    sf = sf[np.isfinite(sf)]
    end = float(grid[-1])
    has_peak = bool(strength.peak_disp <= PEAK_BEFORE * end)
    notes = []
    if not has_peak:
        notes.append(f"no peak before {PEAK_BEFORE:.0%} of the shear (the seed-mean curve is highest at "
                     f"{strength.peak_disp * 1e3:.2f} of {end * 1e3:.2f} mm): the specimen did not pass its critical "
                     "state, φ_peak is the curve's maximum")
    psi6 = np.asarray([v for v in order_psi6 if math.isfinite(v)], float)
    order = float(psi6.mean()) if psi6.size else math.nan
    if order > CRYSTALLINE_PSI6:
        notes.append(f"the grains crystallised (hexatic order {order:.2f} > {CRYSTALLINE_PSI6}): near-uniform discs in "
                     "one layer order into a triangular lattice whatever the preparation, and shear along its rows; "
                     "this is no sand (use a wider gradation)")
    if n < 2:
        notes.append("one seed: no intervals (run ≥ 3 seeds)")
    return ElementResult(
        normal_stress, n,
        _deg(strength.peak), _deg(strength.peak_lo), _deg(strength.peak_hi),
        _deg(strength.critical), _deg(strength.critical_lo), _deg(strength.critical_hi),
        _deg(float(np.mean(psi))), *(_deg(v) for v in t_interval(psi)),
        float(np.mean(sf)) if sf.size else math.nan, *t_interval(sf),
        float(strength.peak_disp), end, has_peak, "; ".join(notes), order)
