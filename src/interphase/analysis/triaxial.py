"""Strength and dilatancy of a drained element test from its curves: plain arrays in, a frozen
`ShearState` out. The same function serves laboratory triaxial records (io/lab_triaxial.py) and a
DEM triaxial or biaxial (plane-strain) curve; nothing here knows where the arrays came from.

Inputs (one value per sample, in test order): ε1 the major (axial) strain [-], εv the volumetric
strain [-], both compression positive (dilation: εv decreasing), R = σ1′/σ3′ [-]; optionally e [-].

Definitions (docs/soils.md, "Laboratory records"):

- **φ_peak** = asin((R − 1)/(R + 1)) at the largest R (Mohr–Coulomb on σ1′, σ3′; for triaxial
  compression the same number as asin(3η/(6 + η)), η = q/p′). **ε1 at peak** is the ε1 of that
  sample (on a flat peak, the sample of the largest recorded R, however small the margin).
- **Dilatancy rate** r = −dεv/dε1: the slope of a least-squares straight line εv(ε1) through every
  sample whose ε1 lies in [a, a + w] (w = 1 % by default), for every start a = a sample's ε1 whose
  window ends inside the record; r_max is the largest. Windows are by ε1 value, not by sample
  count, so a record's small ε1 reversals and uneven sampling change nothing.
- **ψ_max** = asin(r_max/(2 + r_max)), for both:
  triaxial compression (ε2 = ε3): the Vermeer & de Borst (1984) form sin ψ = −ε̇v/(2ε̇1 − ε̇v),
  which is 0 when the volume stops changing;
  plane strain / biaxial (ε2 = 0): sin ψ = −(ε̇1 + ε̇3)/(ε̇1 − ε̇3) (Mohr circle of strain rate).
  With ε2 = 0, εv = ε1 + ε3, so dε3 = dεv − dε1, dε1 + dε3 = dεv and dε1 − dε3 = 2dε1 − dεv:
  sin ψ = −dεv/(2dε1 − dεv) = r/(2 + r), the same expression of r. (Not the same as the triaxial
  Mohr form with dε3 = (dεv − dε1)/2, which gives (r − 1)/(3 + r) and is −19.5° at constant volume:
  not used.) `dilation_angle(deps1, deps3)` gives the plane-strain value from the two rates.
- **End state**: over the samples with ε1 ≥ ε1_last − s (s = 2 % by default): φ_end from the mean
  R, e_end the mean e, and r_end the dilatancy rate of a line fitted over that span (r_end > 0:
  still dilating, so φ_end is not a critical-state angle).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

WINDOW = 0.01        # the dilatancy window: 1 % of ε1
END_SPAN = 0.02      # the end state: the last 2 % of ε1


@dataclass(frozen=True)
class ShearState:
    phi_peak_deg: float
    ratio_peak: float            # largest σ1′/σ3′
    eps1_peak: float             # ε1 at that sample [-]
    psi_max_deg: float
    dilatancy_max: float         # r_max = largest −dεv/dε1 over a window
    eps1_psi: float              # start of that window [-]
    phi_end_deg: float
    e_end: float                 # NaN without e
    dilatancy_end: float         # −dεv/dε1 fitted over the end span
    eps1_end_from: float         # the end span [ε1_last − s, ε1_last] [-]
    eps1_last: float
    window: float
    end_span: float

    def to_dict(self) -> dict:
        return asdict(self)


def friction_angle(ratio) -> np.ndarray:
    """φ [°] = asin((R − 1)/(R + 1)) of the principal stress ratio R = σ1′/σ3′."""
    r = np.asarray(ratio, float)
    return np.degrees(np.arcsin((r - 1) / (r + 1)))


def psi_from_rate(r) -> np.ndarray:
    """ψ [°] = asin(r/(2 + r)) of the dilatancy rate r = −dεv/dε1 (triaxial and plane strain alike)."""
    r = np.asarray(r, float)
    return np.degrees(np.arcsin(r / (2 + r)))


def dilation_angle(deps1, deps3) -> np.ndarray:
    """Plane strain (ε2 = 0): ψ [°] = asin(−(dε1 + dε3)/(dε1 − dε3)), compression positive."""
    d1, d3 = np.asarray(deps1, float), np.asarray(deps3, float)
    return np.degrees(np.arcsin(-(d1 + d3) / (d1 - d3)))


def window_slopes(x, y, width: float) -> tuple[np.ndarray, np.ndarray]:
    """(starts, slopes): for every sample value a = x_i with a + width ≤ max x, the least-squares
    slope dy/dx of the samples with a ≤ x ≤ a + width (vectorised: sorted sums, no loop)."""
    o = np.argsort(np.asarray(x, float), kind="stable")
    xs, ys = np.asarray(x, float)[o], np.asarray(y, float)[o]
    xc, yc = xs - xs.mean(), ys - ys.mean()                  # centred: the sums keep their digits
    zero = np.zeros(1)
    sx, sy = np.concatenate([zero, np.cumsum(xc)]), np.concatenate([zero, np.cumsum(yc)])
    sxx, sxy = np.concatenate([zero, np.cumsum(xc * xc)]), np.concatenate([zero, np.cumsum(xc * yc)])
    start = np.flatnonzero(xs + width <= xs[-1] * (1 + 1e-12))
    start = start[np.r_[True, xs[start][1:] != xs[start][:-1]]]       # one window per distinct start
    end = np.searchsorted(xs, xs[start] + width, side="right")
    n = end - start
    ax, ay = sx[end] - sx[start], sy[end] - sy[start]
    axx, axy = sxx[end] - sxx[start], sxy[end] - sxy[start]
    den = n * axx - ax * ax
    with np.errstate(invalid="ignore", divide="ignore"):
        slope = np.where((n >= 2) & (den > 0), (n * axy - ax * ay) / np.where(den > 0, den, 1), np.nan)
    return xs[start], slope


def _line_slope(x: np.ndarray, y: np.ndarray) -> float:
    if len(x) < 2 or np.ptp(x) == 0:
        return float("nan")
    return float(np.polyfit(x, y, 1)[0])


def shear_state(eps1, epsv, ratio, e=None, *, window: float = WINDOW, end_span: float = END_SPAN) -> ShearState:
    """φ_peak, ε1 at peak, ψ_max and the end state of one drained compression curve (definitions
    in the module docstring). Arrays of equal length, test order, ε1 spanning at least `window`."""
    x, v, r = (np.asarray(a, float) for a in (eps1, epsv, ratio))
    ev = np.full_like(x, np.nan) if e is None else np.asarray(e, float)
    if not (len(x) == len(v) == len(r) == len(ev)):
        raise ValueError(f"arrays of unequal length: ε1 {len(x)}, εv {len(v)}, R {len(r)}, e {len(ev)}")
    if len(x) < 2 or np.ptp(x) < window:
        raise ValueError(f"ε1 spans {np.ptp(x) if len(x) else 0:.4g}, less than one window ({window:g})")
    i = int(np.nanargmax(r))
    starts, slopes = window_slopes(x, v, window)
    j = int(np.nanargmax(-slopes))
    rmax = float(-slopes[j])
    last = float(np.max(x))
    tail = x >= last - end_span
    return ShearState(
        phi_peak_deg=float(friction_angle(r[i])), ratio_peak=float(r[i]), eps1_peak=float(x[i]),
        psi_max_deg=float(psi_from_rate(rmax)), dilatancy_max=rmax, eps1_psi=float(starts[j]),
        phi_end_deg=float(friction_angle(np.mean(r[tail]))),
        e_end=float(np.mean(ev[tail])) if np.isfinite(ev[tail]).all() else math.nan,
        dilatancy_end=-_line_slope(x[tail], v[tail]), eps1_end_from=last - end_span, eps1_last=last,
        window=window, end_span=end_span)
