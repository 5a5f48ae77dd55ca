"""Contact anisotropy (docs/methods.md §5): Rothenburg–Bathurst second-order Fourier forms.

Model: E(θ) = (1/2π)[1 + a·cos2(θ−θa)], f̄n(θ) = f0[1 + an·cos2(θ−θn)], f̄t(θ) = −f0·at·sin2(θ−θt).

Tensor method (the default, `tensor_method`): fabric φ = Σw n⊗n/Σw, a = aniso(φ), A = 4(φ − ½I),
per-contact weight g = 1 + n·A·n; χn = Σw (fn/g) n⊗n/Σw → f0 = tr χn, an = aniso(χn)/f0, θn = dir(χn);
χt = sym Σw (ft/g) t⊗n/Σw → at = aniso(χt)/f0, θt = dir(χt). `w` is an optional per-contact weight
(1 for real contacts; the exact test uses it to weight a discrete set of directions).
Binning method (`binned_method`): 36 bins of 5° over [0°, 180°), least squares of the same forms, as a
cross-check. Directions are axial: every tensor is even in n, so pp directions fold onto [0, π) and
surface contacts (upper half plane) are unchanged.

θr (`resultant_direction`): m = f/|f|, R = Σ|f| m⊗m/Σ|f|, θr = dir(R), ar = aniso(R) = 2(R1 − R2).
At the surface (`surface_anisotropy`, 'ps' contacts) θn uses the force-weighted normal tensor
Σ fn n⊗n/Σ fn (no fabric correction: the surface geometry, not a random fabric, sets the directions)
and a_n_surface = aniso of that tensor; the angle of the summed force on the grains,
ψF = atan2(−Σfx, Σfz), is reported too (it equals atan(μs) at the same snapshot).

Sign (docs/methods.md §0): in the analysis frame the soil moves +x relative to the surface. For a 'ps'
contact n points from the surface into the grain and f is the force ON THE GRAIN; the surface pushes
the grains up and toward −x, so θr, θn and ψF come out positive (toward −x) when the surface resists.
R and the normal tensors are even in f, so using the force on the surface (−f) changes nothing.
Simulations that move the surface +x are mirrored first (`apply_shear_sign(df, -1)`).

Angles: radians ccw from +x inside; outputs name the reading: `*_deg` = ψ (degrees from vertical,
positive toward −x, in [−90°, 90°)), `*_ccw_deg` = θ (degrees ccw from +x, in [0°, 180°)).

3D (the periodic3d device, docs/3d.md): a ContactTable with ny and fy (tables.CONTACT_COLUMNS_3D)
gets `surface_anisotropy`'s 3D path: the 3D tensors R, φ and Nf, read in the shear plane through
their x–z blocks scaled to unit trace (identical to the 2D readings when nothing has a y part),
with the out-of-plane part stated (R_yy, Σ|fy|/Σ|f|, the major axis's tilt out of plane, φ_yy,
Nf_yy). The 2D functions are unchanged.

Degenerate input never raises: rows with a non-finite value or a zero normal are dropped (counted in
`n_dropped`); a group with fewer than MIN_CONTACTS contacts, zero forces, f0 ≤ 0 or a fabric too
anisotropic for the second-order model (a ≥ 1, some g ≤ 0) gives NaN and says why in `reason`.
A ContactTable missing a column is refused (`MissingColumnError` naming it).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from interphase.tables import require_columns
from interphase.tensor2d import aniso, ccw_deg, direction, psi_deg

MIN_CONTACTS = 2
BINS = 36

#: columns mirrored (x → −x) by `apply_shear_sign`; ft flips too: t = (−nz, nx) turns into (−nz, −nx)
_X_COLUMNS = ("cx", "nx", "fx", "ft", "x1", "x2", "x", "vx", "surface_fx", "window_fx")


def apply_shear_sign(df: pd.DataFrame, shear_sign: int) -> pd.DataFrame:
    """The table in the analysis frame: shear_sign = +1 returns it as is; −1 mirrors x (positions,
    normals, forces, velocities, ft; History's surface_fx). Works on Contact, Particle and History tables."""
    if shear_sign not in (1, -1):
        raise ValueError(f"shear_sign must be +1 or -1, got {shear_sign!r}")
    if shear_sign == 1:
        return df
    out = df.copy()
    for col in _X_COLUMNS:
        if col in out.columns:
            out[col] = -out[col]
    return out


# ---- grouped sums ---------------------------------------------------------------------------

def _grouping(n: int, group, keys):
    """(keys, inverse index) of a per-contact group label; `keys` adds groups with no contact."""
    if group is None:
        return np.array([0]), np.zeros(n, dtype=np.int64)
    group = np.asarray(group)
    if keys is None:
        keys, inv = np.unique(group, return_inverse=True)
        return keys, inv
    keys = np.asarray(keys)
    order = np.argsort(keys, kind="stable")
    pos = np.searchsorted(keys[order], group)
    pos = np.clip(pos, 0, keys.size - 1)
    inv = order[pos]
    if group.size and not np.array_equal(keys[inv], group):
        raise ValueError("group labels not in keys")
    return keys, inv


def _gsum(inv: np.ndarray, k: int, values) -> np.ndarray:
    return np.bincount(inv, weights=values, minlength=k).astype(float)


def _clean(nx, nz, *others, weight=None):
    """Float arrays with unit normals; mask of usable rows (finite, |n| > 0, weight ≥ 0)."""
    nx = np.asarray(nx, dtype=float)
    nz = np.asarray(nz, dtype=float)
    arrays = [np.asarray(o, dtype=float) for o in others]
    w = np.ones_like(nx) if weight is None else np.asarray(weight, dtype=float)
    norm = np.hypot(nx, nz)
    ok = np.isfinite(norm) & (norm > 0) & np.isfinite(w) & (w >= 0)
    for a in arrays:
        ok &= np.isfinite(a)
    with np.errstate(invalid="ignore", divide="ignore"):
        nx, nz = nx / norm, nz / norm
    return ok, nx, nz, arrays, w


def _frame(keys, cols: dict, reasons: np.ndarray) -> pd.DataFrame:
    out = pd.DataFrame(cols, index=pd.Index(keys, name="group"))
    out["reason"] = reasons
    return out


def _angles(out: pd.DataFrame, name: str, theta: np.ndarray) -> None:
    out[f"{name}_deg"] = psi_deg(theta)
    out[f"{name}_ccw_deg"] = ccw_deg(theta)


def _join(*parts: np.ndarray) -> np.ndarray:
    """Per-group '; '-join of reason strings, empty and repeated ones skipped (one pass per group,
    never per contact)."""
    cols = [np.asarray(p, dtype=object) for p in parts]
    out = np.empty(cols[0].shape, dtype=object)
    for i in range(out.size):
        seen = []
        for col in cols:
            text = col[i]
            if text and text not in seen:
                seen.append(text)
        out[i] = "; ".join(seen)
    return out


# ---- tensor method --------------------------------------------------------------------------

def tensor_method(nx, nz, fn, ft, weight=None, group=None, keys=None) -> pd.DataFrame:
    """Fabric and force anisotropy of docs/methods.md §5 by the tensor method, one row per group.

    nx, nz: contact normals (any length, renormalised); fn, ft [N]: normal and tangential force
    (fn = f·n, ft = f·t, t = (−nz, nx)); weight: optional per-contact weight ≥ 0; group: optional
    per-contact label (e.g. the snapshot), `keys` the labels to report (groups without contacts
    give NaN rows). Columns: n_contacts, n_dropped, a, theta_fabric, an, theta_n, at, theta_t
    (radians ccw), f0 [N], the same directions as *_deg (ψ) and *_ccw_deg, reason."""
    ok, nx, nz, (fn, ft), w = _clean(nx, nz, fn, ft, weight=weight)
    keys, inv = _grouping(nx.size, group, keys)
    k = keys.size
    dropped = _gsum(inv, k, ~ok).astype(int)
    inv, nx, nz, fn, ft, w = inv[ok], nx[ok], nz[ok], fn[ok], ft[ok], w[ok]
    count = np.bincount(inv, minlength=k)
    W = _gsum(inv, k, w)
    with np.errstate(invalid="ignore", divide="ignore"):
        p11, p22, p12 = (_gsum(inv, k, w * nx * nx) / W, _gsum(inv, k, w * nz * nz) / W,
                         _gsum(inv, k, w * nx * nz) / W)
        a = aniso(p11, p22, p12)
        theta_fab = direction(p11, p22, p12)
        A11, A22, A12 = 4 * p11 - 2, 4 * p22 - 2, 4 * p12
        g = 1 + A11[inv] * nx * nx + A22[inv] * nz * nz + 2 * A12[inv] * nx * nz
        gmin = np.full(k, np.inf)
        np.minimum.at(gmin, inv, g)
        wn, wt = w * fn / g, w * ft / g
        c11, c22, c12 = _gsum(inv, k, wn * nx * nx) / W, _gsum(inv, k, wn * nz * nz) / W, _gsum(inv, k, wn * nx * nz) / W
        t11, t22, t12 = (_gsum(inv, k, -wt * nx * nz) / W, _gsum(inv, k, wt * nx * nz) / W,
                         _gsum(inv, k, 0.5 * wt * (nx * nx - nz * nz)) / W)
        f0 = c11 + c22
        an = aniso(c11, c22, c12) / f0
        at = aniso(t11, t22, t12) / f0
        theta_n = direction(c11, c22, c12)
        theta_t = direction(t11, t22, t12)
    few = count < MIN_CONTACTS
    no_w = ~few & ~(W > 0)
    bad_fabric = ~few & ~no_w & ~(gmin > 0)
    bad_f0 = ~few & ~no_w & ~bad_fabric & ~(f0 > 0)
    fabric_nan = few | no_w
    force_nan = fabric_nan | bad_fabric | bad_f0
    a, theta_fab = np.where(fabric_nan, np.nan, a), np.where(fabric_nan, np.nan, theta_fab)
    an, at, f0 = (np.where(force_nan, np.nan, x) for x in (an, at, f0))
    theta_n, theta_t = np.where(force_nan, np.nan, theta_n), np.where(force_nan, np.nan, theta_t)
    reasons = _join(
        np.where(few, f"fewer than {MIN_CONTACTS} usable contacts", ""),
        np.where(no_w, "all contact weights are zero", ""),
        np.where(bad_fabric, "fabric too anisotropic for the second-order model (a ≥ 1, some g ≤ 0)", ""),
        np.where(bad_f0, "mean normal force f0 ≤ 0 (no compressive contact force)", ""),
        np.where(dropped > 0, np.char.add(dropped.astype(str), " row(s) with NaN or zero normal dropped"), ""),
    )
    out = _frame(keys, dict(n_contacts=count, n_dropped=dropped, a=a, theta_fabric=theta_fab, an=an,
                            theta_n=theta_n, at=at, theta_t=theta_t, f0=f0), reasons)
    for name in ("theta_fabric", "theta_n", "theta_t"):
        _angles(out, name, out[name].to_numpy())
    return out


def force_weighted_normals(nx, nz, fn, group=None, keys=None) -> pd.DataFrame:
    """Nf = Σ fn n⊗n / Σ fn (surface contacts): columns an = aniso(Nf), theta_n (rad ccw), *_deg, reason.
    Only compressive contacts (fn > 0) enter; NaN if fewer than MIN_CONTACTS or Σ fn = 0."""
    ok, nx, nz, (fn,), _ = _clean(nx, nz, fn)
    keys, inv = _grouping(nx.size, group, keys)
    k = keys.size
    use = ok & (fn > 0)
    inv, nx, nz, fn = inv[use], nx[use], nz[use], fn[use]
    count = np.bincount(inv, minlength=k)
    S = _gsum(inv, k, fn)
    with np.errstate(invalid="ignore", divide="ignore"):
        n11, n22, n12 = _gsum(inv, k, fn * nx * nx) / S, _gsum(inv, k, fn * nz * nz) / S, _gsum(inv, k, fn * nx * nz) / S
    bad = (count < MIN_CONTACTS) | ~(S > 0)
    an = np.where(bad, np.nan, aniso(n11, n22, n12))
    th = np.where(bad, np.nan, direction(n11, n22, n12))
    reasons = np.where(bad, f"fewer than {MIN_CONTACTS} contacts with a compressive normal force", "")
    out = _frame(keys, dict(n_compressive=count, an=an, theta_n=th), reasons)
    _angles(out, "theta_n", th)
    return out


def resultant_direction(fx, fz, group=None, keys=None) -> pd.DataFrame:
    """θr and ar of the average contact resultant force: R = Σ f⊗f/|f| / Σ|f| (= Σ|f| m⊗m/Σ|f|).
    Also the summed force Σfx, Σfz [N] and its tilt ψF = atan2(−Σfx, Σfz) [deg from vertical,
    positive toward −x]. Columns: n_contacts, ar, theta_r (rad), theta_r_deg (ψ), theta_r_ccw_deg,
    sum_fx, sum_fz, force_angle_deg, reason."""
    fx = np.asarray(fx, dtype=float)
    fz = np.asarray(fz, dtype=float)
    keys, inv = _grouping(fx.size, group, keys)
    k = keys.size
    ok = np.isfinite(fx) & np.isfinite(fz)
    dropped = _gsum(inv, k, ~ok).astype(int)
    inv, fx, fz = inv[ok], fx[ok], fz[ok]
    count = np.bincount(inv, minlength=k)
    mag = np.hypot(fx, fz)
    inv_mag = np.divide(1.0, mag, out=np.zeros_like(mag), where=mag > 0)
    S = _gsum(inv, k, mag)
    with np.errstate(invalid="ignore", divide="ignore"):
        r11, r22, r12 = (_gsum(inv, k, fx * fx * inv_mag) / S, _gsum(inv, k, fz * fz * inv_mag) / S,
                         _gsum(inv, k, fx * fz * inv_mag) / S)
    sfx, sfz = _gsum(inv, k, fx), _gsum(inv, k, fz)
    few = count < MIN_CONTACTS
    zero = ~few & ~(S > 0)
    bad = few | zero
    ar = np.where(bad, np.nan, aniso(r11, r22, r12))
    th = np.where(bad, np.nan, direction(r11, r22, r12))
    fang = np.where(bad, np.nan, np.degrees(np.arctan2(-sfx, sfz)))
    reasons = _join(np.where(few, f"fewer than {MIN_CONTACTS} usable contacts", ""),
                    np.where(zero, "all contact forces are zero", ""),
                    np.where(dropped > 0, np.char.add(dropped.astype(str), " row(s) with NaN force dropped"), ""))
    out = _frame(keys, dict(n_contacts=count, ar=ar, theta_r=th, sum_fx=np.where(bad, np.nan, sfx),
                            sum_fz=np.where(bad, np.nan, sfz), force_angle_deg=fang), reasons)
    _angles(out, "theta_r", th)
    return out


# ---- 3D (the periodic3d device, docs/3d.md) ----------------------------------------------------

def _stack3(inv, k, w, ax, ay, az, S):
    """Per-group 3×3 tensors Σ w·a⊗a / S, shape (k, 3, 3)."""
    comps = (ax, ay, az)
    T = np.empty((k, 3, 3))
    with np.errstate(invalid="ignore", divide="ignore"):
        for i in range(3):
            for j in range(i, 3):
                T[:, i, j] = T[:, j, i] = _gsum(inv, k, w * comps[i] * comps[j]) / S
    return T


def _in_plane(T):
    """(x11, z22, xz12) of the x–z block of 3×3 tensors, scaled to unit trace: the in-plane reading
    of a 3D tensor, which for tensors with no y part is the 2D tensor itself."""
    tr = T[:, 0, 0] + T[:, 2, 2]
    with np.errstate(invalid="ignore", divide="ignore"):
        return T[:, 0, 0] / tr, T[:, 2, 2] / tr, T[:, 0, 2] / tr


def _tilt_out_of_plane(T, bad):
    """Angle [deg] of each tensor's major principal axis out of the x–z plane (asin |v_y|)."""
    out = np.full(T.shape[0], np.nan)
    good = ~bad & np.all(np.isfinite(T), axis=(1, 2))
    if good.any():
        _, vec = np.linalg.eigh(T[good])
        out[good] = np.degrees(np.arcsin(np.clip(np.abs(vec[:, 1, -1]), 0.0, 1.0)))
    return out


def resultant_direction_3d(fx, fy, fz, group=None, keys=None) -> pd.DataFrame:
    """θr of the average contact resultant force in 3D: R = Σ f⊗f/|f| / Σ|f| (3×3, trace 1).
    In the shear plane: θr = dir and ar = aniso of R's x–z block scaled to unit trace (with fy = 0
    exactly `resultant_direction`'s). Out of plane: r_yy = R_yy, the share of Σ|f| the tensor puts
    along y (Σ fy²/|f| / Σ|f|); fy_share = Σ|fy| / Σ|f|; principal_tilt_y_deg, the major principal
    axis's angle out of the x–z plane. Σfx, Σfy, Σfz and ψF = atan2(−Σfx, Σfz) as in 2D."""
    fx, fy, fz = (np.asarray(a, dtype=float) for a in (fx, fy, fz))
    keys, inv = _grouping(fx.size, group, keys)
    k = keys.size
    ok = np.isfinite(fx) & np.isfinite(fy) & np.isfinite(fz)
    dropped = _gsum(inv, k, ~ok).astype(int)
    inv, fx, fy, fz = inv[ok], fx[ok], fy[ok], fz[ok]
    count = np.bincount(inv, minlength=k)
    mag = np.sqrt(fx * fx + fy * fy + fz * fz)
    inv_mag = np.divide(1.0, mag, out=np.zeros_like(mag), where=mag > 0)
    S = _gsum(inv, k, mag)
    R = _stack3(inv, k, inv_mag, fx, fy, fz, S)
    r11, r22, r12 = _in_plane(R)
    sfx, sfy, sfz = _gsum(inv, k, fx), _gsum(inv, k, fy), _gsum(inv, k, fz)
    few = count < MIN_CONTACTS
    zero = ~few & ~(S > 0)
    bad = few | zero
    nan = lambda v: np.where(bad, np.nan, v)   # noqa: E731
    with np.errstate(invalid="ignore", divide="ignore"):
        fy_share = _gsum(inv, k, np.abs(fy)) / S
    th = nan(direction(r11, r22, r12))
    reasons = _join(np.where(few, f"fewer than {MIN_CONTACTS} usable contacts", ""),
                    np.where(zero, "all contact forces are zero", ""),
                    np.where(dropped > 0, np.char.add(dropped.astype(str), " row(s) with NaN force dropped"), ""))
    out = _frame(keys, dict(n_contacts=count, ar=nan(aniso(r11, r22, r12)), theta_r=th, r_yy=nan(R[:, 1, 1]),
                            fy_share=nan(fy_share), principal_tilt_y_deg=_tilt_out_of_plane(R, bad),
                            sum_fx=nan(sfx), sum_fy=nan(sfy), sum_fz=nan(sfz),
                            force_angle_deg=nan(np.degrees(np.arctan2(-sfx, sfz)))), reasons)
    _angles(out, "theta_r", th)
    return out


def normal_tensors_3d(nx, ny, nz, fn, group=None, keys=None) -> pd.DataFrame:
    """The 3D surface fabric φ = Σ n⊗n / N and force-weighted normal tensor Nf = Σ fn n⊗n / Σ fn
    (compressive contacts). In-plane readings from their x–z blocks scaled to unit trace (a, θfabric;
    an, θn: with ny = 0 exactly the 2D fabric and `force_weighted_normals`), out of plane their yy
    components (fabric_yy, nf_yy)."""
    nx, ny, nz, fn = (np.asarray(a, dtype=float) for a in (nx, ny, nz, fn))
    norm = np.sqrt(nx * nx + ny * ny + nz * nz)
    ok = np.isfinite(norm) & (norm > 0) & np.isfinite(fn)
    with np.errstate(invalid="ignore", divide="ignore"):
        nx, ny, nz = nx / norm, ny / norm, nz / norm
    keys, inv = _grouping(nx.size, group, keys)
    k = keys.size
    inv, nx, ny, nz, fn = inv[ok], nx[ok], ny[ok], nz[ok], fn[ok]
    count = np.bincount(inv, minlength=k)
    phi = _stack3(inv, k, np.ones_like(nx), nx, ny, nz, count.astype(float))
    comp = fn > 0
    ncomp = np.bincount(inv[comp], minlength=k)
    S = _gsum(inv[comp], k, fn[comp])
    Nf = _stack3(inv[comp], k, fn[comp], nx[comp], ny[comp], nz[comp], S)
    few, bad_n = count < MIN_CONTACTS, (ncomp < MIN_CONTACTS) | ~(S > 0)
    p11, p22, p12 = _in_plane(phi)
    n11, n22, n12 = _in_plane(Nf)
    th_f = np.where(few, np.nan, direction(p11, p22, p12))
    th_n = np.where(bad_n, np.nan, direction(n11, n22, n12))
    out = _frame(keys, dict(a=np.where(few, np.nan, aniso(p11, p22, p12)), theta_fabric=th_f,
                            fabric_yy=np.where(few, np.nan, phi[:, 1, 1]),
                            an=np.where(bad_n, np.nan, aniso(n11, n22, n12)), theta_n=th_n,
                            nf_yy=np.where(bad_n, np.nan, Nf[:, 1, 1])),
                 np.where(bad_n, f"fewer than {MIN_CONTACTS} contacts with a compressive normal force", ""))
    _angles(out, "theta_fabric", th_f)
    _angles(out, "theta_n", th_n)
    return out


# ---- binning method -------------------------------------------------------------------------

def binned_method(nx, nz, fn, ft, weight=None, bins: int = BINS) -> dict:
    """Cross-check of `tensor_method` for one group: directions folded onto [0, π) and put in `bins`
    bins (36 of 5°); least-squares fits of the density (1/π)[1 + a cos2(θ−θa)] to the bins' weight
    shares, of f0[1 + an cos2(θ−θn)] to their mean fn and of −f0·at·sin2(θ−θt) to their mean ft.
    Abscissa of a bin: the weighted mean direction of its contacts (bin centre when empty); with a
    uniform spread inside a 5° bin the density fit understates a by ≤ 0.13 % (sinc of the bin).
    Returns a dict with a, theta_fabric, an, theta_n, at, theta_t (rad ccw), f0 [N], reason."""
    ok, nx, nz, (fn, ft), w = _clean(nx, nz, fn, ft, weight=weight)
    nx, nz, fn, ft, w = nx[ok], nz[ok], fn[ok], ft[ok], w[ok]
    nan = dict(a=math.nan, theta_fabric=math.nan, an=math.nan, theta_n=math.nan, at=math.nan,
               theta_t=math.nan, f0=math.nan)
    if nx.size < MIN_CONTACTS or not w.sum() > 0:
        return {**nan, "reason": f"fewer than {MIN_CONTACTS} usable contacts"}
    theta = np.mod(np.arctan2(nz, nx), np.pi)
    width = np.pi / bins
    # a direction a hair below a bin's lower edge (atan2 round-off of k·5°) counts into that bin;
    # bin `bins` is the same axis as bin 0
    b = np.floor(theta / width + 1e-9).astype(np.int64) % bins
    theta = np.where(theta > np.pi - 1e-9 * width, theta - np.pi, theta)
    Wb = np.bincount(b, weights=w, minlength=bins)
    full = Wb > 0
    centre = (np.arange(bins) + 0.5) * width
    safe = np.where(full, Wb, 1.0)
    tb = np.where(full, np.bincount(b, weights=w * theta, minlength=bins) / safe, centre)
    dens = Wb / (w.sum() * width)
    X = np.column_stack([np.ones(bins), np.cos(2 * tb), np.sin(2 * tb)])
    c = np.linalg.lstsq(X, dens, rcond=None)[0]
    out = dict(a=float(np.hypot(c[1], c[2]) / c[0]), theta_fabric=float(np.mod(0.5 * np.arctan2(c[2], c[1]), np.pi)))
    if full.sum() < 3:
        return {**nan, **out, "reason": "fewer than 3 occupied bins for the force fits"}
    mfn = np.bincount(b, weights=w * fn, minlength=bins)[full] / Wb[full]
    mft = np.bincount(b, weights=w * ft, minlength=bins)[full] / Wb[full]
    Xf = X[full]
    cn = np.linalg.lstsq(Xf, mfn, rcond=None)[0]
    ct = np.linalg.lstsq(Xf[:, 1:], mft, rcond=None)[0]
    f0 = float(cn[0])
    if not f0 > 0:
        return {**nan, **out, "reason": "mean normal force f0 ≤ 0"}
    out.update(f0=f0, an=float(np.hypot(cn[1], cn[2]) / f0), theta_n=float(np.mod(0.5 * np.arctan2(cn[2], cn[1]), np.pi)),
               at=float(np.hypot(ct[0], ct[1]) / f0), theta_t=float(np.mod(0.5 * np.arctan2(ct[0], -ct[1]), np.pi)),
               reason="")
    return out


# ---- stress–force–fabric --------------------------------------------------------------------

def qp_sff(a, theta_a, an, theta_n, at, theta_t):
    """Stress–force–fabric estimate of q/p (2D): |½(Â + Ân + Ât)|_dev / [1 + ½·a·an·cos2(θa−θn)],
    where X̂ = x·[[cos2θx, sin2θx], [sin2θx, −cos2θx]] and |·|_dev = ½·|X11 − X22, 2X12| (so that
    |X̂|_dev = x). Angles in radians. Exact for the model forms with equal branch lengths."""
    s = a * np.exp(2j * np.asarray(theta_a)) + an * np.exp(2j * np.asarray(theta_n)) + at * np.exp(2j * np.asarray(theta_t))
    return 0.5 * np.abs(s) / (1 + 0.5 * a * an * np.cos(2 * (np.asarray(theta_a) - theta_n)))


# ---- on a ContactTable ----------------------------------------------------------------------

def _snapshot_keys(contacts: pd.DataFrame, snapshots) -> np.ndarray:
    if snapshots is not None:
        return np.asarray(snapshots)
    return np.unique(contacts["snapshot"].to_numpy()) if len(contacts) else np.array([], dtype=np.int64)


def surface_anisotropy(contacts: pd.DataFrame, snapshots=None, shear_sign: int = 1) -> pd.DataFrame:
    """Anisotropy at the surface ('ps' contacts), one row per snapshot (all snapshots of the table,
    or `snapshots`; those without a surface contact give NaN with a reason). Columns: n_contacts,
    theta_r_deg / theta_r_ccw_deg / ar (resultant force), theta_n_deg / an (force-weighted normal
    tensor), fabric a with theta_fabric_deg, force_angle_deg (ψF of the summed force on the grains),
    lee_share (share of Σ|f| on lee-side contacts, `_lee_share`), stress_ratio = ΣFx/Σ(−Fz) with
    F = −f the force on the surface, reason."""
    require_columns(contacts, ("snapshot", "kind", "nx", "nz", "fn", "ft", "fx", "fz"))
    if "ny" in contacts.columns and "fy" in contacts.columns:
        return _surface_anisotropy_3d(contacts, snapshots, shear_sign)
    keys = _snapshot_keys(contacts, snapshots)
    c = apply_shear_sign(contacts, shear_sign)
    c = c[c["kind"].eq("ps").to_numpy()]
    snap = c["snapshot"].to_numpy()
    res = resultant_direction(c["fx"], c["fz"], snap, keys)
    nrm = force_weighted_normals(c["nx"], c["nz"], c["fn"], snap, keys)
    fab = tensor_method(c["nx"], c["nz"], c["fn"], c["ft"], group=snap, keys=keys)
    out = pd.DataFrame(index=pd.Index(keys, name="snapshot"))
    out["n_contacts"] = res["n_contacts"].to_numpy()
    for col in ("ar", "theta_r", "theta_r_deg", "theta_r_ccw_deg", "force_angle_deg", "sum_fx", "sum_fz"):
        out[col] = res[col].to_numpy()
    for col in ("an", "theta_n", "theta_n_deg", "theta_n_ccw_deg"):
        out[col] = nrm[col].to_numpy()
    out["a"] = fab["a"].to_numpy()
    out["theta_fabric_deg"] = fab["theta_fabric_deg"].to_numpy()
    out["lee_share"] = _lee_share(c, snap, keys, res["theta_r"].isna().to_numpy())
    with np.errstate(invalid="ignore", divide="ignore"):
        # F on the surface = −f: ΣFx/Σ(−Fz) = −Σfx/Σfz
        out["stress_ratio"] = -out["sum_fx"] / out["sum_fz"]
    out["reason"] = _join(np.where(out["n_contacts"].to_numpy() == 0, "no particle–surface contacts", ""),
                          res["reason"].to_numpy(), nrm["reason"].to_numpy())
    return out


#: the 3D surface table's out-of-plane columns (docs/3d.md)
SURFACE_3D_COLUMNS = ("r_yy", "fy_share", "principal_tilt_y_deg", "fabric_yy", "nf_yy")


def _surface_anisotropy_3d(contacts: pd.DataFrame, snapshots, shear_sign: int) -> pd.DataFrame:
    """`surface_anisotropy` of a 3D ContactTable (columns ny, fy, tables.CONTACT_COLUMNS_3D): the
    same columns, each the in-plane reading of the 3D tensor (θr, ar from R; θn, an from Nf; a,
    θfabric from φ: x–z blocks scaled to unit trace), plus SURFACE_3D_COLUMNS, the out-of-plane part.
    Mirroring (shear_sign −1) flips x only: ny and fy stay."""
    keys = _snapshot_keys(contacts, snapshots)
    c = apply_shear_sign(contacts, shear_sign)
    c = c[c["kind"].eq("ps").to_numpy()]
    snap = c["snapshot"].to_numpy()
    res = resultant_direction_3d(c["fx"], c["fy"], c["fz"], snap, keys)
    nrm = normal_tensors_3d(c["nx"], c["ny"], c["nz"], c["fn"], snap, keys)
    out = pd.DataFrame(index=pd.Index(keys, name="snapshot"))
    out["n_contacts"] = res["n_contacts"].to_numpy()
    for col in ("ar", "theta_r", "theta_r_deg", "theta_r_ccw_deg", "force_angle_deg", "sum_fx", "sum_fz"):
        out[col] = res[col].to_numpy()
    for col in ("an", "theta_n", "theta_n_deg", "theta_n_ccw_deg", "a", "theta_fabric_deg"):
        out[col] = nrm[col].to_numpy()
    mag = np.sqrt(c["fx"].to_numpy(float) ** 2 + c["fy"].to_numpy(float) ** 2 + c["fz"].to_numpy(float) ** 2)
    out["lee_share"] = _lee_share(c, snap, keys, res["theta_r"].isna().to_numpy(), mag)
    with np.errstate(invalid="ignore", divide="ignore"):
        out["stress_ratio"] = -out["sum_fx"] / out["sum_fz"]
    for col in ("r_yy", "fy_share", "principal_tilt_y_deg"):
        out[col] = res[col].to_numpy()
    for col in ("fabric_yy", "nf_yy"):
        out[col] = nrm[col].to_numpy()
    out["reason"] = _join(np.where(out["n_contacts"].to_numpy() == 0, "no particle–surface contacts", ""),
                          res["reason"].to_numpy(), nrm["reason"].to_numpy())
    return out


#: a surface contact is on the lee side when its normal leans toward +x by more than the θa filter's 2°
LEE_TILT = math.radians(2.0)


def _lee_share(c: pd.DataFrame, snap, keys, undefined, mag=None) -> np.ndarray:
    """Per snapshot, the share of Σ|f| over 'ps' contacts carried by lee-side contacts: normal
    tilted toward +x (ψn < −2°), i.e. on faces the soil moves away from. A lee force nearly
    orthogonal to the resisting faces' ones turns the axes of R (axial, force-weighted) little but
    cuts ΣFx: for two orthogonal families of forces the summed-force angle is θr − atan(s/(1 − s)),
    s this share; friction tilts real forces off that ideal (docs/liggghts.md: θr vs δ). NaN where
    θr is undefined."""
    nx, nz = c["nx"].to_numpy(float), c["nz"].to_numpy(float)
    if mag is None:         # 3D: |f| with its y part, given by the caller
        mag = np.hypot(c["fx"].to_numpy(float), c["fz"].to_numpy(float))
    ok = np.isfinite(mag) & np.isfinite(nx) & np.isfinite(nz)
    with np.errstate(invalid="ignore"):
        lee = ok & (nx > math.sin(LEE_TILT) * np.hypot(nx, nz))
    keys, inv = _grouping(mag.size, snap, keys)
    total = _gsum(inv, keys.size, np.where(ok, mag, 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        share = _gsum(inv, keys.size, np.where(lee, mag, 0.0)) / total
    return np.where(undefined, np.nan, share)


#: a surface contact slides when its tangential force reaches this share of μs·fn (a sticking contact
#: sits below; the dumped force at a sliding one can exceed μs·fn a little by its damping part)
SLIDE_FRACTION = 0.99


def sliding_share(contacts: pd.DataFrame, friction: float, snapshots=None) -> pd.Series:
    """Per snapshot (all of the table's, or `snapshots`), the share of loaded 'ps' contacts (fn > 0)
    that slide: |f_t| ≥ SLIDE_FRACTION · `friction` · fn, f_t the tangential force, in 3D the whole
    tangential part sqrt(|f|² − fn²) (the table's ft is its in-plane component). NaN where a snapshot
    has no loaded surface contact or the friction is not positive."""
    keys = _snapshot_keys(contacts, snapshots)
    c = contacts[contacts["kind"].eq("ps").to_numpy() & contacts["snapshot"].isin(keys).to_numpy()]
    fn = np.abs(c["fn"].to_numpy(float))
    if "fy" in c.columns and "ny" in c.columns:
        f2 = c["fx"].to_numpy(float) ** 2 + c["fy"].to_numpy(float) ** 2 + c["fz"].to_numpy(float) ** 2
        ft = np.sqrt(np.clip(f2 - fn ** 2, 0.0, None))
    else:
        ft = np.abs(c["ft"].to_numpy(float))
    loaded = np.isfinite(fn) & np.isfinite(ft) & (fn > 0)
    keys, inv = _grouping(fn.size, c["snapshot"].to_numpy(), keys)
    n = _gsum(inv, keys.size, loaded.astype(float))
    slide = _gsum(inv, keys.size, (loaded & (ft >= SLIDE_FRACTION * friction * fn)).astype(float))
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where((n > 0) & (friction > 0), slide / n, np.nan)
    return pd.Series(share, index=pd.Index(keys, name="snapshot"), name="slide_share")


def in_rectangle(x, z, rect) -> np.ndarray:
    """Mask of points inside rect = (x0, x1, z0, z1) [m], boundaries included."""
    x0, x1, z0, z1 = rect
    x = np.asarray(x)
    z = np.asarray(z)
    return (x >= x0) & (x <= x1) & (z >= z0) & (z <= z1)


def region_anisotropy(contacts: pd.DataFrame, rect, snapshots=None, shear_sign: int = 1,
                      kinds=("pp", "ps", "pw")) -> pd.DataFrame:
    """Tensor-method anisotropy and θr of every contact (of `kinds`) whose contact point (cx, cz)
    lies in rect = (x0, x1, z0, z1) [m], one row per snapshot. Columns of `tensor_method` plus
    ar, theta_r*, force_angle_deg; qp_sff (stress–force–fabric q/p); reason."""
    require_columns(contacts, ("snapshot", "kind", "cx", "cz", "nx", "nz", "fn", "ft", "fx", "fz"))
    keys = _snapshot_keys(contacts, snapshots)
    c = apply_shear_sign(contacts, shear_sign)
    if shear_sign == -1:
        rect = (-rect[1], -rect[0], rect[2], rect[3])
    keep = in_rectangle(c["cx"], c["cz"], rect) & c["kind"].isin(list(kinds)).to_numpy()
    c = c[keep]
    snap = c["snapshot"].to_numpy()
    fab = tensor_method(c["nx"], c["nz"], c["fn"], c["ft"], group=snap, keys=keys)
    res = resultant_direction(c["fx"], c["fz"], snap, keys)
    out = fab.rename_axis("snapshot").copy()
    for col in ("ar", "theta_r", "theta_r_deg", "theta_r_ccw_deg", "force_angle_deg"):
        out[col] = res[col].to_numpy()
    out["qp_sff"] = qp_sff(out["a"], out["theta_fabric"], out["an"], out["theta_n"], out["at"], out["theta_t"])
    out["reason"] = _join(out["reason"].to_numpy(), res["reason"].to_numpy())
    return out
