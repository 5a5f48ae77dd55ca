"""Bilinear correlations (docs/methods.md §7) and the study's correlation set (Figs 6.3, 6.7–6.10a).

Two models, both continuous at the breakpoint c (same units as x):
    hinge    y = b0 + b1·x + b2·(x − c)₊        coefficients (b0, b1, b2), slope b1 then b1 + b2
    plateau  y = b0 + b1·min(x, c)              coefficients (b0, b1), flat beyond c

Fitting: every admissible c — at least MIN_SIDE (3) points on each line, a point at c counting on
both (the lines meet there), and two distinct x on each: c from the 3rd smallest x to the 3rd
largest, `BilinearFit.c_range` —; least squares at each c (all candidates at once, normal equations batched in numpy); the best grid c is refined by
scipy.optimize.minimize_scalar (bounded) between its grid neighbours and kept only if it lowers the
RSS — so data with an exact breakpoint at a data x return that x exactly.
Breakpoint intervals: (1) profile likelihood — every c of the admissible range with
RSS(c) ≤ RSSmin·[1 + F0.95(1, n−p)/(n−p)], p = linear coefficients + 1 (c itself); when that
interval is the whole admissible range the data do not locate the break (`BilinearFit.located`
False; the tables say "not located"): any corner the design allows fits as well; (2) a seeded
residual bootstrap (refit on fitted + resampled centred residuals; percentile interval), which also
gives the coefficient intervals — or, when the caller passes `replicates` (fit_study with a
SeedEnsemble), a SEED bootstrap: each replicate's (x, y) are the physical cases' means over their
seeds drawn with replacement (seed_ensemble), so the interval measures the seed scatter of the points.
`BilinearFit.bootstrap` says which one ran. Bootstrap refits refine c on a vectorised 64-point grid
within the same bracket instead of minimize_scalar (speed; see _fit_fast).
Rows are sorted by (x, y) and x is shifted to start at 0 before fitting, so a fit is invariant to row
order and shifting x shifts c by the same amount.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import optimize, stats

from interphase.analysis.ensemble import MIN_SEEDS, physical_case, physical_ids, ratio_interval, seed_interval

MIN_SIDE = 3          # points on each side of the breakpoint (docs/methods.md §7)
MIN_POINTS = 7        # fewer points: no fit (a hinge has 4 parameters, c included)
MODELS = ("hinge", "plateau")
N_GRID_MAX = 400      # candidate breakpoints evaluated exactly (data x + midpoints, thinned beyond)


class FitError(ValueError):
    """Not enough (distinct, finite) points for a bilinear fit; str() says why."""


def _design(u: np.ndarray, c: np.ndarray, model: str) -> np.ndarray:
    """Design matrices for every c at once: shape (len(c), n, p)."""
    u = u[None, :]
    c = np.asarray(c, float)[:, None]
    one = np.ones_like(u + c)
    if model == "hinge":
        return np.stack([one, u + 0 * c, np.maximum(u - c, 0.0)], axis=-1)
    return np.stack([one, np.minimum(u, c)], axis=-1)


def _lstsq_many(u: np.ndarray, y: np.ndarray, c: np.ndarray, model: str) -> tuple[np.ndarray, np.ndarray]:
    """Least squares at every candidate c for u sorted ascending: (coefficients (C, p), RSS (C,)).

    The normal equations come from prefix/suffix sums of 1, u, u², y, u·y split at each c, so all C
    candidates cost O(n + C) rather than O(n·C); RSS = yᵀy − βᵀXᵀy (exact RSS of the final c is
    recomputed directly by the caller)."""
    c = np.asarray(c, float)
    k = np.searchsorted(u, c, side="right")          # u[:k] ≤ c < u[k:]
    z = np.zeros(1)
    cs = lambda v: np.concatenate([z, np.cumsum(v)])
    C0, C1, C2, Cy, Cuy = cs(np.ones_like(u)), cs(u), cs(u * u), cs(y), cs(u * y)
    n, s1, s2, sy, suy = u.size, C1[-1], C2[-1], Cy[-1], Cuy[-1]
    P0, P1, P2, Py, Puy = C0[k], C1[k], C2[k], Cy[k], Cuy[k]        # prefix (u ≤ c)
    S0, S1, S2, Sy, Suy = n - P0, s1 - P1, s2 - P2, sy - Py, suy - Puy   # suffix (u > c)
    if model == "hinge":
        h1 = S1 - c * S0                       # Σ (u−c)₊
        h2 = S2 - 2 * c * S1 + c * c * S0      # Σ (u−c)₊²
        uh = S2 - c * S1                       # Σ u·(u−c)₊
        yh = Suy - c * Sy                      # Σ y·(u−c)₊
        XtX = np.stack([np.stack([np.full_like(c, n), np.full_like(c, s1), h1], -1),
                        np.stack([np.full_like(c, s1), np.full_like(c, s2), uh], -1),
                        np.stack([h1, uh, h2], -1)], -2)
        Xty = np.stack([np.full_like(c, sy), np.full_like(c, suy), yh], -1)
    else:
        m1 = P1 + c * S0                       # Σ min(u, c)
        m2 = P2 + c * c * S0                   # Σ min(u, c)²
        ym = Puy + c * Sy                      # Σ y·min(u, c)
        XtX = np.stack([np.stack([np.full_like(c, n), m1], -1), np.stack([m1, m2], -1)], -2)
        Xty = np.stack([np.full_like(c, sy), ym], -1)
    # batched solve (pinv's SVD was 5× slower); singular systems (a side with one distinct x) get RSS = inf
    scale = np.einsum("cii->c", XtX) ** XtX.shape[-1]
    ok = np.abs(np.linalg.det(XtX)) > 1e-12 * scale
    beta = np.full(Xty.shape, np.nan)
    if ok.any():
        beta[ok] = np.linalg.solve(XtX[ok], Xty[ok][..., None])[..., 0]
    rss = np.where(ok, np.maximum(float(y @ y) - np.einsum("ci,ci->c", np.nan_to_num(beta), Xty), 0.0), np.inf)
    return beta, rss


def _rss_one(u, y, c, model) -> float:
    X = _design(u, np.array([c]), model)[0]
    beta, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ beta
    return float(r @ r)


def _candidates(u_sorted: np.ndarray) -> np.ndarray:
    """Admissible breakpoints: data x and midpoints with ≥ MIN_SIDE points on each line, a point at c
    counting on both (the lines meet at c)."""
    ux = np.unique(u_sorted)
    mids = 0.5 * (ux[1:] + ux[:-1])
    cand = np.unique(np.concatenate([ux, mids]))
    left = np.searchsorted(u_sorted, cand, side="right")              # points ≤ c
    right = u_sorted.size - np.searchsorted(u_sorted, cand, side="left")   # points ≥ c
    # and ≥ 2 distinct x on each line, or its slope is not identifiable
    dleft = np.searchsorted(ux, cand, side="right")
    dright = ux.size - np.searchsorted(ux, cand, side="left")
    cand = cand[(left >= MIN_SIDE) & (right >= MIN_SIDE) & (dleft >= 2) & (dright >= 2)]
    if cand.size > N_GRID_MAX:
        # thin evenly but keep every data x: exact breakpoints at data points stay reachable
        keep = np.unique(np.linspace(0, cand.size - 1, N_GRID_MAX).round().astype(int))
        cand = np.unique(np.concatenate([cand[keep], np.intersect1d(cand, ux)[:: max(1, ux.size // N_GRID_MAX)]]))
    return cand


def _fit_fast(u: np.ndarray, y: np.ndarray, model: str, cand: np.ndarray) -> tuple[float, np.ndarray]:
    """Bootstrap refit: grid, then a vectorised 64-point grid between the best one's neighbours in
    place of minimize_scalar (same bracket, ~30× cheaper; its resolution, bracket/64, is far below
    the bootstrap spread it feeds)."""
    _, rss = _lstsq_many(u, y, cand, model)
    k = int(np.argmin(rss))
    lo, hi = cand[max(k - 1, 0)], cand[min(k + 1, cand.size - 1)]
    fine = np.linspace(lo, hi, 65) if hi > lo else cand[k:k + 1]
    beta, rss_f = _lstsq_many(u, y, fine, model)
    j = int(np.argmin(rss_f))
    return float(fine[j]), beta[j]


def _fit_core(u: np.ndarray, y: np.ndarray, model: str, cand: np.ndarray) -> tuple[float, np.ndarray, float, np.ndarray]:
    """Best c (refined), its coefficients and RSS, and the grid RSS curve."""
    beta, rss = _lstsq_many(u, y, cand, model)
    k = int(np.argmin(rss))
    c_best = float(cand[k])
    rss_best = _rss_one(u, y, c_best, model)     # exact, not the normal-equation shortcut
    lo, hi = float(cand[max(k - 1, 0)]), float(cand[min(k + 1, cand.size - 1)])
    scale = max(float(u[-1] - u[0]), 1e-300)
    if hi > lo and rss_best > 1e-28 * max(float(y @ y), 1e-300):
        res = optimize.minimize_scalar(lambda c: _rss_one(u, y, c, model), bounds=(lo, hi), method="bounded",
                                       options={"xatol": 1e-9 * scale})
        if res.success and res.fun < rss_best * (1 - 1e-12):
            c_best, rss_best = float(res.x), float(res.fun)
    X = _design(u, np.array([c_best]), model)[0]
    beta, *_ = np.linalg.lstsq(X, y, rcond=None)
    return c_best, beta, rss_best, rss


@dataclass(frozen=True)
class BilinearFit:
    """A fitted bilinear correlation. x, y and c in the data's units (angles: degrees, ψ unless named)."""
    model: str                                  # "hinge" | "plateau"
    coef: tuple[float, ...]                     # (b0, b1, b2) hinge | (b0, b1) plateau, x NOT shifted
    c: float                                    # breakpoint, x units
    c_interval_profile: tuple[float, float]     # profile-likelihood interval at `level`
    c_interval_bootstrap: tuple[float, float]   # residual-bootstrap percentile interval
    coef_interval: tuple[tuple[float, float], ...]   # bootstrap percentile interval per coefficient
    r2: float
    rss: float
    n: int
    x_range: tuple[float, float]
    level: float = 0.95
    n_boot: int = 0
    bootstrap: str = "residual"                 # "residual" | "seed": what the refits resampled
    c_range: tuple[float, float] = (math.nan, math.nan)   # the admissible breakpoints (module doc)
    extra: dict = field(default_factory=dict, compare=False)

    @property
    def located(self) -> bool:
        """False when the profile interval is the whole admissible range: the data do not place the
        break anywhere the design allows it to be (True when the range is unknown: older files)."""
        lo, hi = self.c_range
        if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
            return True
        tol = 1e-6 * (hi - lo)
        return not (self.c_interval_profile[0] <= lo + tol and self.c_interval_profile[1] >= hi - tol)

    def predict(self, x) -> np.ndarray | float:
        x = np.asarray(x, dtype=float)
        if self.model == "hinge":
            b0, b1, b2 = self.coef
            out = b0 + b1 * x + b2 * np.maximum(x - self.c, 0.0)
        else:
            b0, b1 = self.coef
            out = b0 + b1 * np.minimum(x, self.c)
        return float(out) if out.ndim == 0 else out

    def predict_interval(self, x) -> tuple[float, float]:
        """Percentile band of the bootstrap refits at x (scalar)."""
        lo, hi = self.predict_band(np.array([float(x)]))
        return (float(lo[0]), float(hi[0]))

    def predict_band(self, x) -> tuple[np.ndarray, np.ndarray]:
        """Percentile band (lower, upper) of the bootstrap refits at every x (NaN without refits)."""
        x = np.atleast_1d(np.asarray(x, dtype=float))
        boots = self.extra.get("boot_params")
        if boots is None or len(boots) == 0:
            return np.full(x.shape, np.nan), np.full(x.shape, np.nan)
        b = np.asarray(boots, float)
        b = b[np.isfinite(b).all(axis=1)]
        if not len(b):
            return np.full(x.shape, np.nan), np.full(x.shape, np.nan)
        c = b[:, -1:]
        if self.model == "hinge":
            vals = b[:, :1] + b[:, 1:2] * x + b[:, 2:3] * np.maximum(x - c, 0.0)
        else:
            vals = b[:, :1] + b[:, 1:2] * np.minimum(x, c)
        a = (1 - self.level) / 2
        q = np.quantile(vals, [a, 1 - a], axis=0)
        return q[0], q[1]

    def to_dict(self) -> dict:
        d = {"model": self.model, "c": self.c, "c_lo_profile": self.c_interval_profile[0],
             "c_hi_profile": self.c_interval_profile[1], "c_lo_boot": self.c_interval_bootstrap[0],
             "c_hi_boot": self.c_interval_bootstrap[1], "r2": self.r2, "rss": self.rss, "n": self.n,
             "x_min": self.x_range[0], "x_max": self.x_range[1], "level": self.level, "n_boot": self.n_boot,
             "bootstrap": self.bootstrap, "c_lo_range": self.c_range[0], "c_hi_range": self.c_range[1],
             "located": self.located}
        if "c_interval_residual" in self.extra:     # fit_study's seed-bootstrap fits also carry this
            d["c_lo_resid"], d["c_hi_resid"] = self.extra["c_interval_residual"]
        for i, (b, (lo, hi)) in enumerate(zip(self.coef, self.coef_interval)):
            d[f"b{i}"], d[f"b{i}_lo"], d[f"b{i}_hi"] = b, lo, hi
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "BilinearFit":
        p = 3 if d["model"] == "hinge" else 2
        return cls(model=d["model"], coef=tuple(float(d[f"b{i}"]) for i in range(p)), c=float(d["c"]),
                   c_interval_profile=(float(d["c_lo_profile"]), float(d["c_hi_profile"])),
                   c_interval_bootstrap=(float(d["c_lo_boot"]), float(d["c_hi_boot"])),
                   coef_interval=tuple((float(d[f"b{i}_lo"]), float(d[f"b{i}_hi"])) for i in range(p)),
                   r2=float(d["r2"]), rss=float(d["rss"]), n=int(d["n"]),
                   x_range=(float(d["x_min"]), float(d["x_max"])), level=float(d.get("level", 0.95)),
                   n_boot=int(d.get("n_boot", 0)), bootstrap=str(d.get("bootstrap") or "residual"),
                   c_range=tuple(math.nan if d.get(k) is None else float(d[k]) for k in ("c_lo_range", "c_hi_range")))


def _predict_params(model: str, params: np.ndarray, x: float) -> float:
    if model == "hinge":
        b0, b1, b2, c = params
        return b0 + b1 * x + b2 * max(x - c, 0.0)
    b0, b1, c = params
    return b0 + b1 * min(x, c)


def _unshift(model: str, beta: np.ndarray, c_u: float, x0: float) -> tuple[tuple[float, ...], float]:
    """Coefficients fitted on u = x − x0 back to x: b0 changes, slopes and (c − x0) do not."""
    if model == "hinge":
        b0, b1, b2 = beta
        return (float(b0 - b1 * x0), float(b1), float(b2)), c_u + x0
    b0, b1 = beta
    # b0 + b1·min(u, cu) = b0 + b1·min(x, cu + x0) − b1·x0
    return (float(b0 - b1 * x0), float(b1)), c_u + x0


def _refit(x: np.ndarray, y: np.ndarray, model: str) -> np.ndarray:
    """(coefficients on x, c) of a fast refit of one bootstrap replicate; NaNs if it cannot be fitted."""
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    p = 4 if model == "hinge" else 3
    if x.size < MIN_POINTS:
        return np.full(p, np.nan)
    order = np.lexsort((y, x))
    x, y = x[order], y[order]
    x0 = float(x[0])
    u = x - x0
    cand = _candidates(u)
    if cand.size == 0:
        return np.full(p, np.nan)
    cb, bb = _fit_fast(u, y, model, cand)
    if not np.all(np.isfinite(bb)):
        return np.full(p, np.nan)
    cf, cc = _unshift(model, bb, cb, x0)
    return np.array([*cf, cc])


def fit_bilinear(x, y, model: str = "hinge", *, level: float = 0.95, n_boot: int = 199, seed: int = 0,
                 replicates=None) -> BilinearFit:
    """Fit `model` to (x, y); NaN rows are dropped. Raises FitError (with the reason) for too few points.

    Intervals of c and the coefficients: a residual bootstrap (`n_boot` refits, generator `seed`), or,
    when `replicates` is given — an array (B, 2, len(x)) of resampled (x, y) aligned with the input
    rows, e.g. SeedEnsemble.replicates — one refit per replicate (the seed bootstrap; `n_boot` and
    `seed` are then unused). A replicate that cannot be fitted is left out of the percentiles."""
    if model not in MODELS:
        raise ValueError(f"model must be one of {MODELS}, got {model!r}")
    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    if x.shape != y.shape:
        raise ValueError("x and y differ in length")
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    n = x.size
    if n < MIN_POINTS:
        raise FitError(f"no fit: n = {n} < {MIN_POINTS} points")
    order = np.lexsort((y, x))           # row-order invariance: one canonical order
    x, y = x[order], y[order]
    x0 = float(x[0])
    u = x - x0                          # shift invariance: fit on x − min(x)
    cand = _candidates(u)
    if cand.size == 0:
        raise FitError(f"no fit: {np.unique(x).size} distinct x values leave no breakpoint with "
                       f"{MIN_SIDE} points on each side")
    c_u, beta, rss, grid_rss = _fit_core(u, y, model, cand)
    p = beta.size + 1
    dof = n - p
    tss = float(((y - y.mean()) ** 2).sum())
    r2 = 1.0 - rss / tss if tss > 0 else math.nan
    # profile-likelihood interval: evaluate on the grid plus a fine even grid of the admissible range
    fine = np.unique(np.concatenate([cand, np.linspace(cand[0], cand[-1], 400), [c_u]]))
    _, fine_rss = _lstsq_many(u, y, fine, model)
    thresh = rss * (1.0 + stats.f.ppf(level, 1, dof) / dof)
    inside = fine[fine_rss <= thresh * (1 + 1e-12) + 1e-300]
    c_prof = (float(inside.min() + x0), float(inside.max() + x0)) if inside.size else (c_u + x0, c_u + x0)

    coef, c = _unshift(model, beta, c_u, x0)
    boot_params = np.empty((0, p))
    kind = "residual"
    if replicates is not None:
        reps = np.asarray(replicates, dtype=float)
        if reps.ndim != 3 or reps.shape[1] != 2 or reps.shape[2] != ok.size:
            raise ValueError(f"replicates must have shape (B, 2, {ok.size}), got {reps.shape}")
        kind, n_boot = "seed", int(reps.shape[0])
        boot_params = np.array([_refit(r[0], r[1], model) for r in reps]).reshape(-1, p)
        boot_params = boot_params[np.isfinite(boot_params).all(axis=1)]
    elif n_boot > 0:
        rng = np.random.default_rng(seed)
        X = _design(u, np.array([c_u]), model)[0]
        fitted = X @ beta
        resid = y - fitted
        resid = resid - resid.mean()
        rows = []
        for _ in range(n_boot):
            yb = fitted + rng.choice(resid, size=n, replace=True)
            cb, bb = _fit_fast(u, yb, model, cand)
            cf, cc = _unshift(model, bb, cb, x0)
            rows.append((*cf, cc))
        boot_params = np.asarray(rows)
    a = (1 - level) / 2
    if boot_params.size:
        q = np.quantile(boot_params, [a, 1 - a], axis=0)
        coef_iv = tuple((float(q[0, i]), float(q[1, i])) for i in range(p - 1))
        c_boot = (float(q[0, -1]), float(q[1, -1]))
    else:
        coef_iv = tuple((math.nan, math.nan) for _ in range(p - 1))
        c_boot = (math.nan, math.nan)
    return BilinearFit(model=model, coef=coef, c=float(c), c_interval_profile=c_prof, c_interval_bootstrap=c_boot,
                       coef_interval=coef_iv, r2=float(r2), rss=rss, n=int(n),
                       x_range=(float(x[0]), float(x[-1])), level=level, n_boot=n_boot, bootstrap=kind,
                       c_range=(float(cand[0] + x0), float(cand[-1] + x0)), extra={"boot_params": boot_params, "grid_c": cand + x0, "grid_rss": grid_rss})


def fit_hinge(x, y, **kw) -> BilinearFit:
    return fit_bilinear(x, y, "hinge", **kw)


def fit_plateau(x, y, **kw) -> BilinearFit:
    return fit_bilinear(x, y, "plateau", **kw)


# ---- the study's correlations --------------------------------------------------------------------
@dataclass(frozen=True)
class CorrelationSpec:
    """One of the study's correlations: y against x over a subset of the interface cases."""
    key: str            # file-name-safe id, e.g. "fig6_8"
    figure: str         # "6.8"
    x: str              # column of the points table (angles: degrees; ψ unless the name says ccw)
    y: str
    model: str
    subset: str         # "all" | "not_flat_spaced" | "flat_spaced"
    by: str | None      # fit separately per value of this column (None: pooled only)
    title: str
    x_label: str
    y_label: str
    gradation: str | None = None    # the study's text names the gradation: only those cases, when present


STUDY: tuple[CorrelationSpec, ...] = (
    CorrelationSpec("fig6_3a", "6.3a", "theta_n_surface_deg", "peak_stress_ratio", "plateau", "all", None,
                    "Peak stress ratio at the surface vs θn (surface)", "θn, surface [° from vertical]", "peak stress ratio tan δ [-]"),
    CorrelationSpec("fig6_3b", "6.3b", "theta_r_surface_deg", "peak_stress_ratio", "plateau", "all", None,
                    "Peak stress ratio at the surface vs θr (surface)", "θr, surface [° from vertical]", "peak stress ratio tan δ [-]"),
    CorrelationSpec("fig6_3c", "6.3c", "theta_n_region_deg", "stress_ratio_region", "plateau", "all", None,
                    "Average stress ratio (sampling region) vs θn (region)", "θn, region [° from vertical]", "average stress ratio −σxz/σzz, region [-]"),
    CorrelationSpec("fig6_3d", "6.3d", "theta_r_region_deg", "stress_ratio_region", "plateau", "all", None,
                    "Average stress ratio (sampling region) vs θr (region)", "θr, region [° from vertical]", "average stress ratio −σxz/σzz, region [-]"),
    CorrelationSpec("fig6_7a", "6.7 (≥ 90°)", "theta_a_deg_90", "peak_stress_ratio", "plateau", "all", "friction_ps",
                    "Peak stress ratio vs θa, all normals (≥ 90°)", "θa, filter ≥ 90° [° from vertical]", "peak stress ratio tan δ [-]", "poly"),
    CorrelationSpec("fig6_7b", "6.7 (> 92°)", "theta_a_deg_92", "peak_stress_ratio", "plateau", "all", "friction_ps",
                    "Peak stress ratio vs θa, normals > 92°", "θa, filter > 92° [° from vertical]", "peak stress ratio tan δ [-]", "poly"),
    CorrelationSpec("fig6_8", "6.8", "theta_a_deg_92", "theta_r_surface_deg", "hinge", "not_flat_spaced", "friction_ps",
                    "θr at the surface vs θa (> 92°), flat-spaced surfaces excluded", "θa, filter > 92° [° from vertical]", "θr, surface [° from vertical]", "poly"),
    CorrelationSpec("fig6_9", "6.9", "theta_a_ccw_deg_90", "theta_r_over_theta_a", "hinge", "flat_spaced", None,
                    "θr/θa vs θa (≥ 90°, ccw) for flat-spaced surfaces", "θa, filter ≥ 90° [° ccw from +x]", "θr/θa [-] (both ψ)"),
    CorrelationSpec("fig6_10a", "6.10a", "theta_r_surface_deg", "efficiency", "plateau", "all", "gradation",
                    "Peak efficiency vs θr at the surface", "θr, surface [° from vertical]", "efficiency E = tan δ / tan φ [-]"),
)
SPECS = {s.key: s for s in STUDY}


def _col(df, name, default=math.nan):
    return df[name] if name in df.columns else pd.Series(default, index=df.index)


def prepare_points(summaries: pd.DataFrame) -> pd.DataFrame:
    """Interface cases of a summaries table (one row per finished case, box rows included) with the
    derived columns the correlations need:
      tan_phi      peak stress ratio of the paired box test (via pair_id), NaN without one
      efficiency   E = tan δ / tan φ
      flat_spaced  regular triangles with flat spacing Sr > 0 (Group 2)
      non_dilative θa (> 92°) undefined: such surfaces enter the θa correlations at θa = 0, as the
                   study plots non-dilative systems (§6.4.6); the ≥ 90° θa likewise
      theta_a_ccw_deg_90      θa (≥ 90°) counterclockwise from +x (= ψ + 90°), Fig. 6.9's axis
      theta_r_over_theta_a    θr (surface, ψ) / θa (≥ 90°, ψ)
    Rows keep group, friction and gradation."""
    from interphase.analysis.strength import efficiency

    df = summaries
    test = _col(df, "test", "interface").astype(str)
    role = _col(df, "role", "interface").astype(str)
    box = df[(test == "box") | (role == "box")]
    pts = df[(test == "interface") & (role != "box")].copy()
    ratio_by_id = pd.Series(pd.to_numeric(_col(box, "peak_stress_ratio"), errors="coerce").to_numpy(),
                            index=_col(box, "case_id", "").astype(str).to_numpy())
    ratio_by_id = ratio_by_id[~ratio_by_id.index.duplicated()]
    pair = _col(pts, "pair_id", None)
    pts["tan_phi"] = pair.map(ratio_by_id).astype(float) if len(pts) else pd.Series(dtype=float)
    for c in ("peak_stress_ratio", "theta_a_deg_92", "theta_a_deg_90", "theta_r_surface_deg", "sr", "friction_ps"):
        pts[c] = pd.to_numeric(_col(pts, c), errors="coerce")
    pts["efficiency"] = efficiency(pts["peak_stress_ratio"].to_numpy(), pts["tan_phi"].to_numpy()) if len(pts) else []
    kind = _col(pts, "profile_kind", "").astype(str)
    pts["flat_spaced"] = kind.isin(["sawtooth", "asymmetric"]) & (pts["sr"].fillna(0) > 0)
    pts["non_dilative"] = pts["theta_a_deg_92"].isna() & (kind != "") & (kind != "None")
    pts.loc[pts["non_dilative"], "theta_a_deg_92"] = 0.0
    pts.loc[pts["non_dilative"] & pts["theta_a_deg_90"].isna(), "theta_a_deg_90"] = 0.0
    pts["theta_a_ccw_deg_90"] = pts["theta_a_deg_90"] + 90.0
    with np.errstate(divide="ignore", invalid="ignore"):
        pts["theta_r_over_theta_a"] = np.where(pts["theta_a_deg_90"] > 0,
                                               pts["theta_r_surface_deg"] / pts["theta_a_deg_90"], np.nan)
    pts["physical_case"] = _col(pts, "label", "").map(physical_case) if len(pts) else pd.Series(dtype=str)
    pts["physical_id"] = physical_ids(pts) if len(pts) else pd.Series(dtype=str)
    return pts.reset_index(drop=True)


# ---- seed ensembles: one point per physical case ---------------------------------------------------
#: run-level columns averaged over a physical case's seeds (each with a Student-t interval); E and tan φ
#: are handled apart (ratio of seed means; the paired box tests' seeds)
AVERAGED = ("peak_stress_ratio", "theta_r_surface_deg", "theta_n_surface_deg", "theta_r_region_deg",
            "theta_n_region_deg", "stress_ratio_region", "theta_a_deg_92", "theta_a_deg_90", "theta_a_ccw_deg_90",
            "theta_r_over_theta_a", "rnc", "rn", "lee_share_surface", "shear_disp_at_peak", "shear_band_d50",
            "inertial_number", "residual_stress_ratio", "dilation_at_peak")
#: columns of a physical case that its seeds share (taken from its first run)
SHARED = ("group", "friction_ps", "gradation", "profile_kind", "flat_spaced", "non_dilative", "rt", "sr", "sw", "au",
          "ar", "rtmax", "device", "d50", "test", "role")
#: quantities set by the surface alone: the same for every seed, drawn without an x error bar
SEED_INVARIANT = frozenset({"theta_a_deg_92", "theta_a_deg_90", "theta_a_ccw_deg_90", "rnc", "rn"})


def _group_sd(values: np.ndarray, codes: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per code 0..k−1: mean, sample sd (NaN below two values) and count of the finite values."""
    ok = np.isfinite(values)
    n = np.bincount(codes[ok], minlength=k).astype(float)
    s = np.bincount(codes[ok], weights=values[ok], minlength=k)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = s / n
        dev = np.where(ok, values - mean[codes], 0.0)
        sd = np.sqrt(np.bincount(codes, weights=dev * dev, minlength=k) / (n - 1))
    return mean, np.where(n >= 2, sd, np.nan), n


def _group_t(values: np.ndarray, codes: np.ndarray, k: int,
             quantity: str | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per code 0..k−1: mean of the finite values, the 95 % interval of that mean and the count. The
    interval is analysis.ensemble.seed_interval's: Student t, on the log scale for a positive ratio,
    clipped to an angle's range, NaN below MIN_SEEDS values (`quantity` names the column)."""
    mean, sd, n = _group_sd(values, codes, k)
    lo, hi = seed_interval(mean, sd, n, quantity)
    return mean, np.asarray(lo, float), np.asarray(hi, float), n


def _padded(values: np.ndarray, codes: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """(k, max count) matrix of each code's values (NaN padding) and the counts."""
    order = np.argsort(codes, kind="stable")
    c = codes[order]
    n = np.bincount(c, minlength=k)
    start = np.concatenate([[0], np.cumsum(n)[:-1]])
    pos = np.arange(c.size) - start[c]
    mat = np.full((k, max(int(n.max()) if n.size else 0, 1)), np.nan)
    mat[c, pos] = values[order]
    return mat, n


def _inflate(drawn: np.ndarray, mat: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Bootstrap means (n_boot, k) moved away from each row's own mean by √(n/(n − 1)): a mean of n
    values drawn with replacement varies by s²(n − 1)/n², not s²/n (a third too little at n = 3);
    scaling its deviation restores the variance of the mean (the adjusted bootstrap)."""
    with np.errstate(invalid="ignore", divide="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        centre = np.nanmean(mat, axis=1)
        factor = np.where(n >= 2, np.sqrt(n / np.maximum(n - 1, 1)), 1.0)
    return centre[None, :] + factor[None, :] * (drawn - centre[None, :])


def _draw_means(mat: np.ndarray, n: np.ndarray, rng, n_boot: int) -> np.ndarray:
    """(n_boot, k): each row's mean over n[row] of its values drawn with replacement, its spread
    about the row's mean restored to s²/n (`_inflate`)."""
    k, width = mat.shape
    idx = np.floor(rng.random((n_boot, k, width)) * n[None, :, None]).astype(int)
    idx = np.minimum(idx, np.maximum(n - 1, 0)[None, :, None])
    vals = mat[np.arange(k)[None, :, None], idx]
    vals = np.where(np.arange(width)[None, None, :] < n[None, :, None], vals, np.nan)
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return _inflate(np.nanmean(vals, axis=2), mat, n)


@dataclass
class SeedEnsemble:
    """A campaign's interface runs grouped by physical case (group, physical_id; named by the label without `-sN`).

    points  one row per physical case, index 0..K−1 (= column `case_index`): every AVERAGED column is
            the mean over its seeds, with `<col>_lo`/`<col>_hi` (95 %, analysis.ensemble.seed_interval:
            Student t over the seeds respecting the column's range, NaN below 3 seeds); `seeds` (runs), `box_seeds`; `peak_stress_ratio` = tan δ and `efficiency` = E
            are the seed ensemble's (the ensembles table's when it was given); `tan_phi` its box tests'.
    runs    the run-level points (prepare_points) with `case_index` and `tan_delta_seed` (each run's
            value that the ensemble's tan δ averages: its peak state, else its own peak).
    The seed bootstrap (`replicates`) resamples these runs within each physical case, and the box
    tests' seeds within each box ensemble (shared by every case paired with it)."""
    points: pd.DataFrame
    runs: pd.DataFrame
    box_values: np.ndarray          # (M, width) per box ensemble: its seeds' tan φ values (NaN padded)
    box_counts: np.ndarray          # (M,)
    box_of_case: np.ndarray         # (K,) box ensemble of each physical case, −1 without one
    _cache: dict = field(default_factory=dict, repr=False)

    def seeds_per_case(self) -> np.ndarray:
        return self.points["seeds"].to_numpy(int) if len(self.points) else np.zeros(0, int)

    def replicates(self, columns, n_boot: int, seed: int = 0) -> dict[str, np.ndarray]:
        """{column: (n_boot, K) seed-bootstrap values of the per-case points}. Each replicate draws every
        physical case's runs with replacement (as many as it has) and every box ensemble's seeds, once
        for all columns (common random numbers across the correlations); means as in `points`, their
        spread about the case's mean restored to s²/n (`_inflate`), E as the ratio of the drawn means."""
        key = (n_boot, seed)
        if key not in self._cache:
            rng = np.random.default_rng(seed)
            k = len(self.points)
            codes = self.runs["case_index"].to_numpy(int)
            vals = {c: pd.to_numeric(self.runs[c], errors="coerce").to_numpy(float)
                    for c in (*AVERAGED, "tan_delta_seed") if c in self.runs}
            # one draw of run positions for every column: draw indices into the padded per-case matrix
            mats = {c: _padded(v, codes, k) for c, v in vals.items()}
            width = max((m.shape[1] for m, _ in mats.values()), default=1)
            n = np.bincount(codes, minlength=k)
            idx = np.minimum(np.floor(rng.random((n_boot, k, width)) * n[None, :, None]).astype(int),
                             np.maximum(n - 1, 0)[None, :, None])
            live = np.arange(width)[None, None, :] < n[None, :, None]
            out = {}
            for c, (m, _) in mats.items():
                m = np.pad(m, ((0, 0), (0, width - m.shape[1])), constant_values=np.nan)
                v = np.where(live, m[np.arange(k)[None, :, None], idx], np.nan)
                with np.errstate(invalid="ignore"), warnings.catch_warnings():
                    warnings.simplefilter("ignore", RuntimeWarning)
                    out[c] = _inflate(np.nanmean(v, axis=2), m, np.isfinite(m).sum(axis=1))
            box = (_draw_means(self.box_values, self.box_counts, rng, n_boot) if self.box_counts.size
                   else np.zeros((n_boot, 0)))
            tan_phi = np.where(self.box_of_case[None, :] >= 0, box[:, np.maximum(self.box_of_case, 0)]
                               if box.shape[1] else np.nan, np.nan)
            out["peak_stress_ratio"] = out.get("tan_delta_seed", out.get("peak_stress_ratio"))
            out["tan_phi"] = tan_phi
            with np.errstate(invalid="ignore", divide="ignore"):
                out["efficiency"] = out["peak_stress_ratio"] / tan_phi
            self._cache[key] = out
        return {c: self._cache[key][c] for c in columns}


def seed_ensemble(runs: pd.DataFrame, states=None, ensembles: pd.DataFrame | None = None, *,
                  box_pools=None) -> SeedEnsemble:
    """Group run-level points (prepare_points) by physical case.

    states     optional {case_id: value}: each interface run's peak state and each box run's (the value
               its ensemble's peak averages, analysis.ensemble.seed_peak_states); without it each
               run's own peak stress ratio stands in.
    ensembles  optional table of analysis.ensemble_table (group, case, tan_delta…, tan_phi…, E…): its tan δ,
               tan φ and E with their intervals replace the ones computed here (they agree when
               `states` came from the same curves), so each E carries its box test's interval.
    box_pools  optional {pair_id: every box test of that soil}: a case's box ensemble is the union of
               its pair_ids' pools, so soil tests run on more seeds than the interface cases
               ([pairs] seeds) all count (analysis.ensemble_table.box_pools); without it, the pair_ids.
    Without `ensembles`, E's interval is that of a ratio of independent seed means
    (analysis.ensemble.ratio_interval), as analysis.ensemble.ensemble_efficiency."""
    runs = runs.copy().reset_index(drop=True)
    if "physical_case" not in runs:
        runs["physical_case"] = _col(runs, "label", "").map(physical_case)
    runs["physical_id"] = physical_ids(runs) if len(runs) else pd.Series(dtype=str)
    if "group" not in runs:
        runs["group"] = ""
    runs["group"] = runs["group"].astype(str)
    keys = runs[["group", "physical_case", "physical_id"]].astype(str)     # pooled by id, ordered by name
    names = keys.drop_duplicates().sort_values(["group", "physical_case", "physical_id"]).reset_index(drop=True)
    k = len(names)
    code_of = {tuple(r): i for i, r in enumerate(names.itertuples(index=False, name=None))}
    codes = np.array([code_of[tuple(r)] for r in keys.itertuples(index=False, name=None)], dtype=int)
    runs["case_index"] = codes
    state_of = pd.Series(states, dtype=float) if states is not None else None
    peak = pd.to_numeric(_col(runs, "peak_stress_ratio"), errors="coerce")
    if state_of is not None:
        runs["tan_delta_seed"] = runs["case_id"].astype(str).map(state_of).astype(float)
    else:
        runs["tan_delta_seed"] = peak.astype(float)
    box_values, box_counts, box_of_case = _box_ensembles(runs, codes, k, state_of, box_pools)
    m, width = box_values.shape

    pts = names.copy()
    first = runs.groupby("case_index", sort=True).first()
    for c in SHARED:
        if c in runs and c != "group":
            pts[c] = first[c].to_numpy()
    pts["label"] = pts["physical_case"]
    pts["case_index"] = np.arange(k)
    pts["seeds"] = np.bincount(codes, minlength=k)
    pts["box_seeds"] = np.where(box_of_case >= 0, box_counts[np.maximum(box_of_case, 0)] if m else 0, 0)
    for c in AVERAGED:
        if c not in runs:
            continue
        v = (runs["tan_delta_seed"] if c == "peak_stress_ratio" else pd.to_numeric(runs[c], errors="coerce"))
        mean, lo, hi, _ = _group_t(v.to_numpy(float), codes, k, c)
        pts[c], pts[f"{c}_lo"], pts[f"{c}_hi"] = mean, lo, hi
    bmean, blo, bhi, _ = (_group_t(box_values.ravel(), np.repeat(np.arange(m), width), m, "tan_phi") if m
                          else ([], [], [], []))
    has = box_of_case >= 0
    for suffix, arr in (("", bmean), ("_lo", blo), ("_hi", bhi)):
        pts[f"tan_phi{suffix}"] = np.where(has, np.asarray(arr, float)[np.maximum(box_of_case, 0)] if m else np.nan,
                                           np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        pts["efficiency"] = pts["peak_stress_ratio"] / pts["tan_phi"]
    ens = SeedEnsemble(pts, runs, box_values, box_counts, box_of_case)
    a_mean, a_sd, a_n = _group_sd(runs["tan_delta_seed"].to_numpy(float), codes, k)
    if m:
        b_mean, b_sd, b_n = (x[np.maximum(box_of_case, 0)] for x in
                             _group_sd(box_values.ravel(), np.repeat(np.arange(m), width), m))
    else:
        b_mean = b_sd = b_n = np.full(k, np.nan)
    lo, hi = ratio_interval(a_mean, a_sd, a_n, b_mean, b_sd, b_n)
    few = (a_n < MIN_SEEDS) | (b_n < MIN_SEEDS)            # as every other interval: none below 3 seeds a side
    lo, hi = np.where(few, np.nan, lo), np.where(few, np.nan, hi)
    pts["efficiency_lo"], pts["efficiency_hi"] = (np.where(has, lo, np.nan), np.where(has, hi, np.nan)) if k else ([], [])
    if ensembles is not None and len(ensembles) and k:
        _take_from_table(pts, ensembles)
    ens.points = pts
    return ens


def _box_ensembles(runs: pd.DataFrame, codes: np.ndarray, k: int, state_of, box_pools):
    """(box_values [m × width, NaN-padded], box_counts [m], box_of_case [k], −1 for none): the
    distinct box ensembles of the k physical cases, each the union of its pair_ids' pools."""
    pair = _col(runs, "pair_id", None)
    box_val = (pair.astype(object).map(lambda b: state_of.get(str(b), np.nan) if b is not None and b == b else np.nan)
               if state_of is not None else pd.to_numeric(_col(runs, "tan_phi"), errors="coerce"))
    box_sets, box_of_case = {}, np.full(k, -1)
    box_members: list[dict] = []
    for ids, vals in zip(pd.Series(pair.to_numpy()).groupby(codes), pd.Series(box_val.to_numpy()).groupby(codes)):
        pids = {str(b) for b in ids[1] if b is not None and b == b}
        pooled = sorted({m for p in pids for m in (box_pools.get(p, (p,)) if box_pools else (p,))})
        if state_of is not None:
            members = {b: float(state_of.get(b, np.nan)) for b in pooled}
        else:
            members = {str(b): float(v) for b, v in zip(ids[1], vals[1]) if b is not None and b == b}
        members = {b: v for b, v in members.items() if math.isfinite(v)}
        if not members:
            continue
        key = tuple(sorted(members))
        if key not in box_sets:
            box_sets[key] = len(box_members)
            box_members.append(members)
        box_of_case[ids[0]] = box_sets[key]
    width = max((len(b) for b in box_members), default=1)
    box_values = np.full((len(box_members), width), np.nan)
    for j, b in enumerate(box_members):
        box_values[j, :len(b)] = [b[x] for x in sorted(b)]
    return box_values, np.array([len(b) for b in box_members], dtype=int), box_of_case


def _take_from_table(pts: pd.DataFrame, ensembles: pd.DataFrame) -> None:
    """tan δ, tan φ and E with their intervals from the ensembles table (analysis.ensemble_table), by
    physical case (its physical_id; by name for a table without one), in place."""
    key = ("physical_id", "physical_id") if "physical_id" in ensembles else ("case", "physical_case")
    tab = ensembles.assign(group=ensembles["group"].astype(str), **{key[0]: ensembles[key[0]].astype(str)})
    tab = tab.set_index(["group", key[0]])
    idx = pd.MultiIndex.from_frame(pts[["group", key[1]]].astype(str))
    for mine, theirs in (("efficiency", "E"), ("peak_stress_ratio", "tan_delta"), ("tan_phi", "tan_phi")):
        for suffix in ("", "_lo", "_hi"):
            if theirs + suffix in tab:
                got = pd.to_numeric(tab[theirs + suffix], errors="coerce").reindex(idx).to_numpy(float)
                pts[mine + suffix] = np.where(np.isnan(got) & ~idx.isin(tab.index), pts[mine + suffix], got)


def of_gradation(points: pd.DataFrame, gradation: str | None) -> pd.DataFrame:
    """The cases of `gradation` where the points have any (and all of them where they have none)."""
    if gradation and "gradation" in points and (points["gradation"] == gradation).any():
        return points[points["gradation"] == gradation]
    return points


def subset(points: pd.DataFrame, spec: CorrelationSpec) -> pd.DataFrame:
    """The cases a correlation is fitted and drawn on. Figs. 6.7 and 6.8 are of well-graded material
    in the study: where a campaign has well-graded cases, its uniform ones stay out of those two (they
    enter Fig. 6.10a, which the study draws with both); a campaign of uniform grains alone keeps them."""
    points = of_gradation(points, spec.gradation)
    if spec.subset == "flat_spaced":
        return points[points["flat_spaced"]]
    if spec.subset == "not_flat_spaced":
        return points[~points["flat_spaced"]]
    return points


@dataclass
class FitResult:
    """A fit (or the reason there is none) for one correlation and one slice of the data."""
    spec: CorrelationSpec
    slice: str                     # "all" or e.g. "friction_ps=0.2"
    n: int
    fit: BilinearFit | None
    reason: str = ""

    def row(self) -> dict:
        base = {"correlation": self.spec.key, "figure": self.spec.figure, "x": self.spec.x, "y": self.spec.y,
                "model": self.spec.model, "slice": self.slice, "n": self.n}
        if self.fit is None:
            return base | {"reason": self.reason}
        return base | self.fit.to_dict() | {"reason": ""}


def fit_study(points: pd.DataFrame, specs=STUDY, *, n_boot: int = 199, seed: int = 0,
              ensemble: SeedEnsemble | None = None) -> list[FitResult]:
    """Fit every correlation pooled and, where the spec says, per value of its `by` column.

    With `ensemble` (points = ensemble.points, one row per physical case) the intervals come from the
    SEED bootstrap: `n_boot` replicates, each drawing every physical case's seeds (and its box tests')
    with replacement and refitting the means (SeedEnsemble.replicates; the same draws for every
    correlation). A slice in which fewer than half the cases have two seeds has no seed scatter to
    resample: it falls back to the residual bootstrap, and `BilinearFit.bootstrap` says which ran.
    Without `ensemble`: the residual bootstrap on whatever rows `points` has."""
    out: list[FitResult] = []
    reps = None
    if ensemble is not None and n_boot > 0:
        cols = sorted({c for sp in specs for c in (sp.x, sp.y)})
        reps = ensemble.replicates([c for c in cols if c in ensemble.points], n_boot, seed)
    for spec in specs:
        sub = subset(points, spec)
        slices = [("all", sub)]
        if spec.by and spec.by in sub.columns:
            slices += [(f"{spec.by}={v:g}" if isinstance(v, float) else f"{spec.by}={v}", g)
                       for v, g in sub.groupby(spec.by, sort=True)]
        for name, g in slices:
            if spec.x not in g.columns or spec.y not in g.columns:
                out.append(FitResult(spec, name, 0, None, f"no fit: column {spec.x if spec.x not in g.columns else spec.y} missing"))
                continue
            x = pd.to_numeric(g[spec.x], errors="coerce").to_numpy(float)
            y = pd.to_numeric(g[spec.y], errors="coerce").to_numpy(float)
            ok = np.isfinite(x) & np.isfinite(y)
            n = int(ok.sum())
            rep = None
            if reps is not None and spec.x in reps and spec.y in reps and "case_index" in g:
                ks = g["case_index"].to_numpy(int)
                if (g["seeds"].to_numpy()[ok] >= 2).sum() * 2 >= max(n, 1):
                    rep = np.stack([reps[spec.x][:, ks], reps[spec.y][:, ks]], axis=1)
            try:
                fit = fit_bilinear(x, y, spec.model, n_boot=n_boot, seed=seed, replicates=rep)
                if rep is not None:       # the residual bootstrap on the same points, for comparison
                    alt = fit_bilinear(x, y, spec.model, n_boot=n_boot, seed=seed)
                    fit.extra["c_interval_residual"] = alt.c_interval_bootstrap
                out.append(FitResult(spec, name, n, fit))
            except FitError as exc:
                out.append(FitResult(spec, name, n, None, str(exc)))
    return out
