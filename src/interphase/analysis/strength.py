"""Interface and box strength from History, Particles and ContactTable (docs/methods.md §6).

Stress ratio at the surface: μs(t) = ΣFx/Σ(−Fz), F = force ON the surface [N] from the grains in
the measuring window (History's window_fx, window_fz: Case.window, away from the side walls; or the
'ps' contacts, F = −f). In the analysis frame the soil moves +x relative to the
surface and the surface resists, so ΣFx > 0 and ΣFz < 0: μs > 0. Box test: τ/σ on the shear plane
= surface_fx/(−surface_fz), both the lower half's force.

Peak: DEM stress ratios are noisy at the scale of grain rearrangements, so the peak is the maximum
of a centred moving average over a shear-displacement window (`window` [m]; `summarise` uses
PEAK_WINDOW_D50 = 0.5 D50, i.e. 0.35 mm at D50 = 0.7 mm), not of the raw series; the raw maximum is
reported alongside. tan δ = peak μs (interface), tan φ = peak τ/σ (box), E = tan δ / tan φ.
Load check (`load_balanced`): the ratio measures strength only while the surface carries the
applied normal load. Rows where the surface's normal force −Fz and the platen force differ by more
than MAX_LOAD_MISMATCH (25 %) of the platen force — the servo still settling at the start, grains
wedged against the fixed side walls — are left out of the peak and the residual (and counted).
Residual: the mean of the raw series over the last RESIDUAL_FRACTION (20 %) of the shear displacement.
Dilation: platen_z at the peak minus platen_z at the first History row [m] (positive = dilation).

Inertial number I = γ̇·D50/√(σn/ρ); γ̇ [1/s] from the grains' velocity profile vx(z).
Shear band: U(z) = (u(z) − u_far)/(−Δs), u the grains' x displacement between two snapshots, u_far
that of the top layer, Δs the shear displacement between them (relative to the far soil the
surface moves −Δs in the analysis frame), so U = 1 where grains follow the surface and 0 in the
still soil; thickness = z(U = 0.1) − z_ref in D50, z_ref the top of the centroid trace.

Bad or degenerate input gives NaN with a reason (`reason` fields), never an exception, except a
table missing a column (`MissingColumnError` naming it).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from interphase.tables import require_columns

PEAK_WINDOW_D50 = 0.5
RESIDUAL_FRACTION = 0.2
BAND_LEVEL = 0.1
FAR_LAYER_D50 = 2.0
QUASI_STATIC_I = 1e-3
MAX_LOAD_MISMATCH = 0.25
PEAK_STATE_TOL = 0.05


# ---- series ---------------------------------------------------------------------------------

def surface_stress_ratio(history: pd.DataFrame) -> pd.Series:
    """μs(t) = window_fx/(−window_fz) per History row (the surface force from the grains in the
    measuring window); NaN where it carries no compressive normal force (−Fz ≤ 0)."""
    require_columns(history, ("window_fx", "window_fz"), "History")
    fx = history["window_fx"].to_numpy(float)
    nfz = -history["window_fz"].to_numpy(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        return pd.Series(np.where(nfz > 0, fx / nfz, np.nan), index=history.index, name="stress_ratio")


def box_stress_ratio(history: pd.DataFrame) -> pd.Series:
    """τ/σ on the shear plane of a box test: surface_fx/(−surface_fz), the lower half's force (what
    crosses the plane, plus the lower soil's weight, 0.1 % of it), NaN where −Fz ≤ 0. Not over the
    platen force: the upper half's walls carry part of the vertical load whenever they have friction
    (one seed of three at wall friction 0.9 read 0.60 over the platen where the plane carried 0.51,
    the mean of the last half; docs/strength.md)."""
    require_columns(history, ("surface_fx", "surface_fz"), "History")
    fx = history["surface_fx"].to_numpy(float)
    nf = -history["surface_fz"].to_numpy(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        return pd.Series(np.where(nf > 0, fx / nf, np.nan), index=history.index, name="stress_ratio")


def load_balanced(history: pd.DataFrame, tolerance: float | None = MAX_LOAD_MISMATCH) -> np.ndarray:
    """Mask of History rows where |−surface_fz − |normal_force|| ≤ tolerance·|normal_force|: the
    surface (box: the lower half) carries the platen's load; all True when tolerance is None.
    The whole surface, not the window's share of it: between frictionless side walls a crystal-like
    packing of uniform grains puts 94 % of the load on the central 70 % of a flat (20 × 10 D50, 200
    grains), a sound state that a share test rejected row by row."""
    require_columns(history, ("surface_fz", "normal_force"), "History")
    if tolerance is None:
        return np.ones(len(history), bool)
    nfz = -history["surface_fz"].to_numpy(float)
    nf = np.abs(history["normal_force"].to_numpy(float))
    with np.errstate(invalid="ignore"):
        return np.abs(nfz - nf) <= tolerance * nf


def moving_average(x, y, window: float) -> np.ndarray:
    """Centred moving average of y over |x' − x| ≤ window/2 (x [m], sorted ascending), NaNs
    skipped; window ≤ 0 returns y. O(N) with cumulative sums."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if not window > 0 or y.size == 0:
        return y.copy()
    good = np.isfinite(y)
    cs = np.concatenate([[0.0], np.cumsum(np.where(good, y, 0.0))])
    cn = np.concatenate([[0], np.cumsum(good)])
    # a hair of slack so that samples exactly window/2 away count on both sides alike
    eps = 1e-9 * window
    lo = np.searchsorted(x, x - 0.5 * window - eps, side="left")
    hi = np.searchsorted(x, x + 0.5 * window + eps, side="right")
    n = cn[hi] - cn[lo]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n > 0, (cs[hi] - cs[lo]) / n, np.nan)


# ---- peak, residual, dilation ---------------------------------------------------------------

@dataclass(frozen=True)
class Peak:
    value: float          # peak of the smoothed series [-]
    shear_disp: float     # shear displacement at the peak [m]
    index: int            # row of the peak (−1 if none)
    raw_max: float        # maximum of the unsmoothed series [-]
    window: float         # smoothing window [m]
    reason: str = ""

    def to_dict(self) -> dict:
        return asdict(self)


def find_peak(shear_disp, ratio, window: float) -> Peak:
    """Peak of `ratio` over the shear: the maximum of its centred moving average over `window` [m]
    of shear displacement (see the module doc). Rows are sorted by shear_disp first."""
    s = np.asarray(shear_disp, dtype=float)
    r = np.asarray(ratio, dtype=float)
    ok = np.isfinite(s)
    idx = np.flatnonzero(ok)
    order = idx[np.argsort(s[ok], kind="stable")]
    smooth = moving_average(s[order], r[order], window)
    if not np.any(np.isfinite(smooth)):
        return Peak(math.nan, math.nan, -1, math.nan, window, "no finite stress ratio in the series")
    k = int(np.nanargmax(smooth))
    return Peak(float(smooth[k]), float(s[order][k]), int(order[k]), float(np.nanmax(r[order])), window)


def residual_ratio(shear_disp, ratio, fraction: float = RESIDUAL_FRACTION) -> float:
    """Mean of the finite ratios over the last `fraction` of the shear-displacement range; NaN if none."""
    s = np.asarray(shear_disp, dtype=float)
    r = np.asarray(ratio, dtype=float)
    ok = np.isfinite(s) & np.isfinite(r)
    if not ok.any():
        return math.nan
    s, r = s[ok], r[ok]
    lo = s.max() - fraction * (s.max() - s.min())
    return float(np.mean(r[s >= lo]))


def dilation(history: pd.DataFrame, at_disp: float) -> float:
    """platen_z at the History row nearest `at_disp` [m] minus platen_z at the first row [m]."""
    require_columns(history, ("shear_disp", "platen_z"), "History")
    s = history["shear_disp"].to_numpy(float)
    z = history["platen_z"].to_numpy(float)
    if not (len(s) and math.isfinite(at_disp)) or not np.isfinite(z).any():
        return math.nan
    order = np.argsort(s, kind="stable")
    k = order[int(np.nanargmin(np.abs(s[order] - at_disp)))]
    return float(z[k] - z[order[0]])


def efficiency(tan_delta_value, tan_phi_value):
    """E = tan δ / tan φ (interface over box peak stress ratio); NaN where tan φ ≤ 0 or not finite."""
    td = np.asarray(tan_delta_value, dtype=float)
    tp = np.asarray(tan_phi_value, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(tp > 0, td / tp, np.nan)
    return float(out) if out.ndim == 0 else out


def efficiency_from_rows(interface_row: dict, box_row: dict) -> float:
    """E from an interface Summary row and the paired box Summary row (`peak_stress_ratio` of each)."""
    return efficiency(interface_row.get("peak_stress_ratio", math.nan), box_row.get("peak_stress_ratio", math.nan))


# ---- rate and shear band --------------------------------------------------------------------

def inertial_number(gamma_dot, d50, sigma_n, density):
    """I = γ̇·D50/√(σn/ρ): γ̇ [1/s], D50 [m], σn [Pa], ρ [kg/m³]. Arrays broadcast. NaN where an input
    is not finite, γ̇ < 0, or D50, σn, ρ ≤ 0. Quasi-static: I < QUASI_STATIC_I (1e−3)."""
    g, d, s, r = (np.asarray(v, dtype=float) for v in (gamma_dot, d50, sigma_n, density))
    good = np.isfinite(g) & np.isfinite(d) & np.isfinite(s) & np.isfinite(r) & (g >= 0) & (d > 0) & (s > 0) & (r > 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(good, g * d / np.sqrt(np.where(good, s / r, 1.0)), np.nan)
    return float(out) if out.ndim == 0 else out


def _select(particles: pd.DataFrame, snapshots) -> pd.DataFrame:
    if snapshots is None:
        return particles
    return particles[np.isin(particles["snapshot"].to_numpy(), np.atleast_1d(snapshots))]


def _bins(z: np.ndarray, bin_height: float, z_min: float | None, z_max: float | None):
    # default: the lowest grain sits mid-layer, so that regular layers never straddle a bin edge
    lo = float(np.min(z)) - 0.5 * bin_height if z_min is None else float(z_min)
    hi = float(np.max(z)) if z_max is None else float(z_max)
    nb = max(1, int(math.ceil((hi - lo) / bin_height - 1e-9)))
    b = np.floor((z - lo) / bin_height).astype(np.int64)
    inside = (z >= lo) & (z <= hi) & (b >= 0)
    b = np.minimum(b, nb - 1)
    centres = lo + (np.arange(nb) + 0.5) * bin_height
    return b, inside, centres, nb


def velocity_profile(particles: pd.DataFrame, snapshots=None, bin_height: float | None = None,
                     z_min: float | None = None, z_max: float | None = None) -> pd.DataFrame:
    """Mean vx [m/s] of the grains in horizontal layers of `bin_height` [m] (default: the median
    grain diameter), pooled over `snapshots` (default all). Columns z (layer centre [m]), vx, count."""
    require_columns(particles, ("snapshot", "z", "vx", "radius"), "Particles")
    p = _select(particles, snapshots)
    z, vx = p["z"].to_numpy(float), p["vx"].to_numpy(float)
    ok = np.isfinite(z) & np.isfinite(vx)
    z, vx = z[ok], vx[ok]
    if z.size == 0:
        return pd.DataFrame({"z": [], "vx": [], "count": []})
    h = float(bin_height) if bin_height else 2.0 * float(np.median(p["radius"].to_numpy(float)))
    b, inside, centres, nb = _bins(z, h, z_min, z_max)
    cnt = np.bincount(b[inside], minlength=nb)
    with np.errstate(invalid="ignore", divide="ignore"):
        v = np.bincount(b[inside], weights=vx[inside], minlength=nb) / cnt
    return pd.DataFrame({"z": centres, "vx": v, "count": cnt})


def shear_rate_from_profile(particles: pd.DataFrame, snapshots=None, bin_height: float | None = None,
                            z_min: float | None = None, z_max: float | None = None, min_count: int = 3,
                            method: str = "max") -> float:
    """Shear rate γ̇ [1/s] from the velocity profile vx(z) (`velocity_profile`, layers of
    `bin_height` m, default the median grain diameter, pooled over `snapshots`).

    method "max" (default): the largest |dvx/dz| of central differences between layers holding at
    least `min_count` grain rows — where the shear localises, the conservative choice for a
    quasi-static check (I < 1e−3). method "mean": |vx(top layer) − vx(bottom layer)|/(their distance),
    the band average (the docs/methods.md example: v = 1 mm/s over a 10 mm band → 0.1 1/s).
    NaN if fewer than two usable layers."""
    if method not in ("max", "mean"):
        raise ValueError(f"method must be 'max' or 'mean', got {method!r}")
    prof = velocity_profile(particles, snapshots, bin_height, z_min, z_max)
    prof = prof[(prof["count"] >= min_count) & np.isfinite(prof["vx"])]
    if len(prof) < 2:
        return math.nan
    z, v = prof["z"].to_numpy(), prof["vx"].to_numpy()
    if method == "mean":
        return float(abs(v[-1] - v[0]) / (z[-1] - z[0]))
    return float(np.max(np.abs(np.gradient(v, z))))


def displacement_profile(particles: pd.DataFrame, snapshot0, snapshot1, z_ref: float,
                         bin_height: float | None = None, far_d50: float = FAR_LAYER_D50,
                         period: float | None = None) -> pd.DataFrame:
    """Normalised x-displacement profile U(z) between two snapshots (see the module doc), in layers of
    `bin_height` [m] (default: the median grain diameter) from z_ref [m] up; z is each grain's height
    at snapshot0. u_far: mean u of the grains within `far_d50` diameters of the highest centre.
    `period` [m]: the cell's length when x is periodic; a grain that crossed the boundary between
    the snapshots is brought back by it (minimum image: valid while no grain moves half a period).
    Columns z [m], U [-], count. Empty if the snapshots share no grain or Δs = 0."""
    require_columns(particles, ("snapshot", "shear_disp", "id", "x", "z", "radius"), "Particles")
    a = particles[particles["snapshot"].to_numpy() == snapshot0]
    b = particles[particles["snapshot"].to_numpy() == snapshot1]
    m = a[["id", "x", "z", "radius", "shear_disp"]].merge(b[["id", "x", "shear_disp"]], on="id", suffixes=("0", "1"))
    m = m[np.isfinite(m[["x0", "x1", "z"]]).all(axis=1)]
    empty = pd.DataFrame({"z": [], "U": [], "count": []})
    if m.empty:
        return empty
    ds = float(m["shear_disp1"].iloc[0] - m["shear_disp0"].iloc[0])
    if not ds != 0 or not math.isfinite(ds):
        return empty
    d = 2.0 * float(np.median(m["radius"]))
    h = float(bin_height) if bin_height else d
    u = (m["x1"] - m["x0"]).to_numpy()
    if period:
        u = u - period * np.round(u / period)
    z = m["z"].to_numpy()
    far = z >= z.max() - far_d50 * d
    U = (u - u[far].mean()) / (-ds)
    bins, inside, centres, nb = _bins(z, h, z_ref, None)
    cnt = np.bincount(bins[inside], minlength=nb)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.bincount(bins[inside], weights=U[inside], minlength=nb) / cnt
    return pd.DataFrame({"z": centres, "U": mean, "count": cnt})


def shear_band(z, U, z_ref: float, d50: float, level: float = BAND_LEVEL) -> tuple[float, str]:
    """(z(U = level) − z_ref in D50, reason): the first downward crossing of `level` going up from
    the lowest sample, interpolated linearly between samples; NaN with a reason when U never
    reaches below `level` (band thicker than the profile) or is already below it at the lowest
    sample (slip at the surface, no band to measure)."""
    z = np.asarray(z, dtype=float)
    U = np.asarray(U, dtype=float)
    ok = np.isfinite(z) & np.isfinite(U)
    z, U = z[ok], U[ok]
    order = np.argsort(z)
    z, U = z[order], U[order]
    if z.size < 2 or not d50 > 0:
        return math.nan, "fewer than two layers in the displacement profile"
    if U[0] <= level:
        return math.nan, f"U ≤ {level:g} already at the lowest layer: the soil slips on the surface"
    below = np.flatnonzero(U <= level)
    if below.size == 0:
        return math.nan, f"U stays above {level:g} over the whole profile: the band is thicker than the sample"
    k = int(below[0])
    zc = z[k - 1] + (U[k - 1] - level) * (z[k] - z[k - 1]) / (U[k - 1] - U[k])
    return float((zc - z_ref) / d50), ""


def shear_band_thickness(z, U, z_ref: float, d50: float, level: float = BAND_LEVEL) -> float:
    """Shear-band thickness z(U = level) − z_ref [D50] (NaN when undefined; `shear_band` says why)."""
    return shear_band(z, U, z_ref, d50, level)[0]


def peak_snapshot(snapshot_disp, shear_disp, ratio, peak: Peak, tol: float = PEAK_STATE_TOL) -> int | None:
    """Position (in `snapshot_disp`) of the contact snapshot that stands for the peak state: the one
    nearest the peak in shear displacement among the snapshots where the smoothed stress ratio is
    within `tol` (relative) of the peak; the nearest overall if none is. None without a peak.

    Why not simply the nearest: on a sliding plateau (a flat surface) the maximum of the smoothed
    ratio sits anywhere on the plateau, and the nearest snapshot can be the start of shear, before
    the forces have tilted (flat μs 0.2: θr 0.8° there, 11.6° at every sheared snapshot)."""
    snaps = np.asarray(snapshot_disp, dtype=float)
    if not (snaps.size and math.isfinite(peak.shear_disp)):
        return None
    s = np.asarray(shear_disp, dtype=float)
    r = np.asarray(ratio, dtype=float)
    order = np.argsort(s, kind="stable")
    smooth = moving_average(s[order], r[order], peak.window)
    ok = np.isfinite(smooth) & np.isfinite(s[order])
    dist = np.abs(snaps - peak.shear_disp)
    if ok.sum() >= 2:
        at_snaps = np.interp(snaps, s[order][ok], smooth[ok], left=np.nan, right=np.nan)
        near_peak = at_snaps >= peak.value - tol * abs(peak.value)
        if near_peak.any():
            return int(np.flatnonzero(near_peak)[np.argmin(dist[near_peak])])
    return int(np.argmin(dist))
