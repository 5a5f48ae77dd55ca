"""Average stress tensor in a sampling rectangle (docs/methods.md §6), principal direction, τ/σ and q/p.

σ_ij = (1/A) Σ_c f_i·l_j, f = force on body 2 [N], l = x2 − x1 the branch vector [m] (a wall contact:
from the contact point to the grain centre), of which only the part inside the rectangle counts
(vectorised Liang–Barsky clipping of every branch segment); then symmetrised. A is the rectangle's
area in the x–z plane [m²], so σ is a force per length [N/m] unless the quasi-2D layer's thickness
t [m] is given (then Pa: σ/t). Ratios and directions do not depend on it. Stress is positive in
compression.

Readings (analysis frame, soil moving +x relative to the surface): a resisting surface pushes the
soil toward −x, so σxz < 0 there. `stress_ratio` = τ/σ = −σxz/σzz is therefore positive when the
surface resists, like μs. q = √(¼(σxx−σzz)² + σxz²), p = ½(σxx+σzz). The major principal direction
`principal` = dir(σ) (radians ccw), reported as ψ in `principal_deg` (positive toward −x).

Sampling rectangle (`sampling_rectangle`): x over the measuring window (Case.window: the soil box
less 3 D50 at each side wall), z from the top of the centroid trace (= highest profile point + D50/2, the trace being a
half-disk dilation) up 20·D50 (14 mm at D50 = 0.7 mm), lowered to `soil_top` when the soil is
thinner than that (small test boxes): the region must not reach into the empty space under the
platen, which would dilute the stress (not the ratios).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from interphase.tables import require_columns
from interphase.tensor2d import ccw_deg, direction, psi_deg

REGION_HEIGHT_D50 = 20.0


def clip_fraction(x0, z0, lx, lz, rect) -> np.ndarray:
    """Share t1 − t0 ∈ [0, 1] of each segment p(t) = (x0, z0) + t·(lx, lz), t ∈ [0, 1], inside
    rect = (xmin, xmax, zmin, zmax) (Liang–Barsky, vectorised). A segment lying along an edge counts
    for the lower/left edge only (half-open rectangle). Zero-length segments give 0 or 1."""
    xmin, xmax, zmin, zmax = rect
    x0, z0, lx, lz = (np.asarray(v, dtype=float) for v in (x0, z0, lx, lz))
    t0 = np.zeros(np.broadcast(x0, z0, lx, lz).shape)
    t1 = np.ones_like(t0)
    inside = np.ones(t0.shape, bool)
    for p, q, upper in ((-lx, x0 - xmin, False), (lx, xmax - x0, True), (-lz, z0 - zmin, False),
                        (lz, zmax - z0, True)):
        with np.errstate(divide="ignore", invalid="ignore"):
            r = q / p
        # parallel to this edge and outside it; a segment lying on an upper edge belongs to the
        # neighbouring rectangle (half-open [min, max)), so that tiles never count it twice
        inside &= ~((p == 0) & ((q <= 0) if upper else (q < 0)))
        t0 = np.where(p < 0, np.maximum(t0, r), t0)
        t1 = np.where(p > 0, np.minimum(t1, r), t1)
    frac = np.clip(t1 - t0, 0.0, 1.0)
    return np.where(inside, frac, 0.0)


def stress_readings(sxx, szz, sxz) -> dict:
    """p, q, q/p, τ/σ = −σxz/σzz and the major principal direction (rad ccw, ψ deg, ccw deg)."""
    sxx, szz, sxz = (np.asarray(v, dtype=float) for v in (sxx, szz, sxz))
    p = 0.5 * (sxx + szz)
    q = np.sqrt(0.25 * (sxx - szz) ** 2 + sxz ** 2)
    with np.errstate(invalid="ignore", divide="ignore"):
        qp = np.where(p > 0, q / p, np.nan)
        ratio = np.where(szz > 0, -sxz / szz, np.nan)
    th = direction(sxx, szz, sxz)
    return dict(p=p, q=q, qp=qp, stress_ratio=ratio, principal=th, principal_deg=psi_deg(th),
                principal_ccw_deg=ccw_deg(th))


def average_stress(contacts: pd.DataFrame, rect, snapshots=None, kinds=("pp", "ps", "pw"),
                   max_branch: float | None = None, thickness: float | None = None) -> pd.DataFrame:
    """Average stress tensor in rect = (x0, x1, z0, z1) [m], one row per snapshot (the table's, or
    `snapshots`): [N/m], or [Pa] with the layer `thickness` [m].

    Branches longer than `max_branch` [m] (e.g. a contact wrapped across a periodic boundary) are
    dropped and counted. Columns: sxx, szz, sxz (symmetrised), n_contacts (branches meeting the
    rectangle), n_dropped, area, p, q, qp, stress_ratio, principal, principal_deg, principal_ccw_deg,
    reason (NaN readings when no branch meets the rectangle or p ≤ 0)."""
    require_columns(contacts, ("snapshot", "kind", "fx", "fz", "x1", "z1", "x2", "z2"))
    x0r, x1r, z0r, z1r = (float(v) for v in rect)
    area = (x1r - x0r) * (z1r - z0r) * (1.0 if thickness is None else float(thickness))
    keys = (np.asarray(snapshots) if snapshots is not None
            else np.unique(contacts["snapshot"].to_numpy()))
    c = contacts[contacts["kind"].isin(list(kinds)).to_numpy()]
    fx, fz = c["fx"].to_numpy(float), c["fz"].to_numpy(float)
    xa, za = c["x1"].to_numpy(float), c["z1"].to_numpy(float)
    lx, lz = c["x2"].to_numpy(float) - xa, c["z2"].to_numpy(float) - za
    ok = np.isfinite(fx) & np.isfinite(fz) & np.isfinite(xa) & np.isfinite(za) & np.isfinite(lx) & np.isfinite(lz)
    if max_branch is not None:
        ok &= np.hypot(lx, lz) <= max_branch
    snap = c["snapshot"].to_numpy()
    pos = np.searchsorted(keys, snap) if keys.size else np.zeros(snap.size, np.int64)
    known = (pos < keys.size) & (keys[np.minimum(pos, max(keys.size - 1, 0))] == snap) if keys.size else np.zeros(snap.size, bool)
    k = keys.size
    dropped = np.bincount(pos[known & ~ok], minlength=k)
    use = known & ok
    pos, fx, fz, xa, za, lx, lz = pos[use], fx[use], fz[use], xa[use], za[use], lx[use], lz[use]
    frac = clip_fraction(xa, za, lx, lz, (x0r, x1r, z0r, z1r)) if area > 0 else np.zeros(pos.size)
    lx, lz = lx * frac, lz * frac
    meets = frac > 0
    n = np.bincount(pos[meets], minlength=k)
    with np.errstate(invalid="ignore", divide="ignore"):
        sxx = np.bincount(pos, weights=fx * lx, minlength=k) / area
        szz = np.bincount(pos, weights=fz * lz, minlength=k) / area
        sxz = 0.5 * (np.bincount(pos, weights=fx * lz, minlength=k) + np.bincount(pos, weights=fz * lx, minlength=k)) / area
    bad_area = not area > 0
    empty = n == 0
    sxx, szz, sxz = (np.where(empty | bad_area, np.nan, v) for v in (sxx, szz, sxz))
    out = pd.DataFrame(dict(sxx=sxx, szz=szz, sxz=sxz, n_contacts=n, n_dropped=dropped, area=area),
                       index=pd.Index(keys, name="snapshot"))
    for name, v in stress_readings(sxx, szz, sxz).items():
        out[name] = v
    reasons = np.where(bad_area, "sampling rectangle has no area",
                       np.where(empty, "no branch vector meets the sampling rectangle",
                                np.where(~(out["p"].to_numpy() > 0), "mean stress p ≤ 0", "")))
    out["reason"] = reasons
    return out


def trace_top(case) -> float:
    """Top of the particle centroid trace [m] of an interface case's profile in the engine frame:
    the highest profile point + D50/2 (a half-disk dilation tops out right over the highest point)."""
    return float(np.max(case.surface().z)) + 0.5 * case.d50


def sampling_rectangle(case, z_bottom: float, soil_top: float | None = None,
                       height_d50: float = REGION_HEIGHT_D50) -> tuple[float, float, float, float]:
    """(x0, x1, z0, z1) [m]: the measuring window (Case.window: the soil box [0, L] less 3 D50 at each
    side wall — a departure from docs/methods.md's [0, L], see Case.window) × [z_bottom, z_bottom +
    20·D50], its top lowered to `soil_top` [m] when given and lower."""
    top = z_bottom + height_d50 * case.d50
    if soil_top is not None and np.isfinite(soil_top):
        top = min(top, float(soil_top))
    x0, x1 = case.window
    return (float(x0), float(x1), float(z_bottom), float(top))
