"""The study's cross-group findings as numbers, from the seed-ensemble points (one row per physical
case: SeedEnsemble.points, seed means of angles in degrees from the vertical, tan δ = the ensemble's
peak stress ratio).

    filter_collapse(points)   Fig. 6.7a vs 6.7b: does leaving out the flat normals (θa > 92° instead
                              of ≥ 90°) bring Groups 2 and 5 onto the others' tan δ–θa line?
    spaced_theta_a(points)    Group 2: θa (> 92°) ≈ 42° whatever the flat spacing Sr.
    rnc_uniqueness(points)    Fig. 6.5: is Rnc(D50) one correlation for every kind of surface?

Each answers with the scatter about a line fitted to the regular saw-teeth of Group 1 (the
reference every other kind of surface is held against, as the study's text does), per particle-
surface friction: rms residual per group, in the fitted quantity's units. A finding is reproduced
when the other groups' scatter about the reference line is of the order of Group 1's own.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from interphase.analysis.correlations import FitError, fit_bilinear

REFERENCE = "group1"


def _rms(v) -> float:
    v = np.asarray(v, float)
    v = v[np.isfinite(v)]
    return float(np.sqrt(np.mean(v ** 2))) if v.size else math.nan


def _scatter(points: pd.DataFrame, x: str, y: str, model: str, label: str) -> list[dict]:
    """Per friction: `model` fitted to Group 1's (x, y); rms residual of every group about it."""
    out = []
    for mu, sub in points.groupby("friction_ps", sort=True):
        ref = sub[sub["group"] == REFERENCE]
        try:
            fit = fit_bilinear(ref[x], ref[y], model, n_boot=0)
        except (FitError, ValueError):
            continue
        for group, g in sub.groupby("group", sort=True):
            ok = g[x].notna() & g[y].notna()
            if not ok.any():
                continue
            resid = g.loc[ok, y].to_numpy(float) - fit.predict(g.loc[ok, x].to_numpy(float))
            out.append(dict(friction_ps=float(mu), x=label, group=group, cases=int(ok.sum()),
                            rms_residual=_rms(resid), mean_residual=float(np.mean(resid)),
                            max_abs_residual=float(np.max(np.abs(resid)))))
    return out


def filter_collapse(points: pd.DataFrame) -> pd.DataFrame:
    """tan δ about Group 1's plateau fit against θa with every normal (≥ 90°) and with the flat
    ones left out (> 92°), per friction and group. The study (Fig. 6.7): Groups 2 and 5 scatter with
    ≥ 90° and join the others with > 92°."""
    rows = (_scatter(points, "theta_a_deg_90", "peak_stress_ratio", "plateau", "θa ≥ 90°")
            + _scatter(points, "theta_a_deg_92", "peak_stress_ratio", "plateau", "θa > 92°"))
    return pd.DataFrame(rows, columns=["friction_ps", "x", "group", "cases", "rms_residual", "mean_residual",
                                       "max_abs_residual"])


def rnc_uniqueness(points: pd.DataFrame) -> pd.DataFrame:
    """E about Group 1's plateau fit against Rnc(D50) and, for comparison, against θa (> 92°), per
    friction and group. The study (Fig. 6.5): Rnc gives no unique correlation; Groups 2, 4 and 5
    leave the line."""
    rows = (_scatter(points, "rnc", "efficiency", "plateau", "Rnc(D50)")
            + _scatter(points, "theta_a_deg_92", "efficiency", "plateau", "θa > 92°"))
    return pd.DataFrame(rows, columns=["friction_ps", "x", "group", "cases", "rms_residual", "mean_residual",
                                       "max_abs_residual"])


def spaced_theta_a(points: pd.DataFrame, group: str = "group2") -> pd.DataFrame:
    """The flat-spaced surfaces (Group 2) by spacing Sr/D50: θa with every normal and with the flat
    ones left out (profile geometry: the same at every friction), and tan δ and θr per friction."""
    g = points[points["group"] == group]
    if g.empty:
        return pd.DataFrame(columns=["sr", "theta_a_deg_90", "theta_a_deg_92"])
    geo = g.groupby("sr", sort=True)[["theta_a_deg_90", "theta_a_deg_92"]].median()
    wide = g.pivot_table(index="sr", columns="friction_ps",
                         values=["peak_stress_ratio", "theta_r_surface_deg"], aggfunc="mean")
    wide.columns = [f"{q}_mu{mu:g}" for q, mu in wide.columns]
    return geo.join(wide).reset_index()
