"""`campaign compare REF VARIANT`: what changing one setting does, physical case by physical case,
against the seed scatter (analysis.difference: agree / differ / undecided at a tolerance).

Physical cases are matched by label without the seed (`…-s3`), so the two campaigns must differ only
in what the labels do not name (stiffness, speed, box size, rolling friction, damping …). Per-seed
values, each at its own ensemble's reading (analysis.ensemble):
  tan_delta, tan_phi        the seed's mean ratio over the smoothing window at the peak of its
                            ensemble's seed-mean curve (interface: the surface; box: the shear plane)
  tan_delta_cs, tan_phi_cs  the seed's mean ratio over the last 40 % of the shear
  E, E_cs                   the seed's interface value over its own box test's (pair_id)
  theta_r_deg               θr at the surface at the run's peak snapshot [deg]
  surface_contacts          contacts on the surface at that snapshot [-]
The two campaigns' specimens are different after consolidation even on the same seed, so the
comparison is unpaired (Welch).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.analysis.difference import difference
from interphase.analysis.ensemble import CRITICAL_FRACTION, GRID_POINTS, _states
from interphase.analysis.strength import PEAK_WINDOW_D50

# what a change must stay within to count as "no effect" (docs/convergence.md says why)
TOLERANCES = {"tan_delta": 0.03, "tan_delta_cs": 0.03, "tan_phi": 0.03, "tan_phi_cs": 0.03,
              "E": 0.05, "E_cs": 0.05, "theta_r_deg": 3.0, "surface_contacts": 0.10}
RELATIVE = {"surface_contacts"}     # tolerance as a fraction of the reference mean
COLUMNS = ("case", "metric", "ref", "ref_lo", "ref_hi", "value", "value_lo", "value_hi", "change", "change_lo",
           "change_hi", "tol", "verdict", "n_ref", "n_value", "seeds_needed")


def physical(label: str) -> str:
    return re.sub(r"-s\d+$", "", str(label))


def _curve(store, case_id: str):
    try:
        s = pd.read_parquet(store.case_folder(str(case_id)) / "series.parquet", columns=["shear_disp", "stress_ratio"])
    except (OSError, ValueError, KeyError):
        return None
    x, r = s["shear_disp"].to_numpy(float), s["stress_ratio"].to_numpy(float)
    return (x, r) if np.isfinite(r).sum() >= 2 else None


def seed_values(summaries: pd.DataFrame, store) -> pd.DataFrame:
    """One row per finished run: physical case, seed, test, pair_id and the per-seed values above
    (E filled in for interface runs whose box test is present)."""
    done = summaries[summaries["status"].eq("done")] if "status" in summaries else summaries
    done = done.assign(_phys=done["label"].map(physical))
    rows = []
    for phys, g in done.groupby("_phys", sort=True):
        d50 = float(pd.to_numeric(g["d50"], errors="coerce").median())
        curves = [(_curve(store, cid), r) for cid, r in zip(g["case_id"], g.itertuples(index=False))]
        ok = [(c, r) for c, r in curves if c is not None]
        if not ok:
            continue
        peaks, _, crits = _states([c for c, _ in ok], PEAK_WINDOW_D50 * d50, CRITICAL_FRACTION, GRID_POINTS)
        for (_, r), p, c in zip(ok, peaks, crits):
            rows.append(dict(case=phys, case_id=str(r.case_id), seed=int(r.seed), test=r.test,
                             pair_id=getattr(r, "pair_id", None), peak=float(p), critical=float(c),
                             theta_r_deg=float(getattr(r, "theta_r_surface_deg", np.nan)),
                             surface_contacts=float(getattr(r, "n_contacts_surface", np.nan))))
    out = pd.DataFrame(rows, columns=["case", "case_id", "seed", "test", "pair_id", "peak", "critical",
                                      "theta_r_deg", "surface_contacts"])
    box = out[out["test"].eq("box")].set_index("case_id")
    iface = out["test"].eq("interface")
    pid = out.loc[iface, "pair_id"].astype(str)
    out.loc[iface, "E"] = out.loc[iface, "peak"].to_numpy() / box["peak"].reindex(pid).to_numpy()
    out.loc[iface, "E_cs"] = out.loc[iface, "critical"].to_numpy() / box["critical"].reindex(pid).to_numpy()
    return out


def _metrics(test: str) -> dict[str, str]:
    """metric name → seed_values column, per test."""
    if test == "box":
        return {"tan_phi": "peak", "tan_phi_cs": "critical"}
    return {"tan_delta": "peak", "tan_delta_cs": "critical", "E": "E", "E_cs": "E_cs",
            "theta_r_deg": "theta_r_deg", "surface_contacts": "surface_contacts"}


def compare(ref: pd.DataFrame, variant: pd.DataFrame, tolerances: dict | None = None) -> pd.DataFrame:
    """The comparison table of two `seed_values` frames: one row per shared physical case and metric."""
    tol = {**TOLERANCES, **(tolerances or {})}
    rows = []
    for case in sorted(set(ref["case"]) & set(variant["case"])):
        a, b = ref[ref["case"].eq(case)], variant[variant["case"].eq(case)]
        for metric, col in _metrics(str(a["test"].iloc[0])).items():
            va, vb = a[col].to_numpy(float), b[col].to_numpy(float)
            if not (np.isfinite(va).any() and np.isfinite(vb).any()):
                continue
            t = tol[metric] * (abs(float(np.nanmean(va))) if metric in RELATIVE else 1.0)
            d = difference(va, vb, t).to_dict()
            rows.append({"case": case, "metric": metric, **{k: d[k] for k in COLUMNS[2:]}})
    return pd.DataFrame(rows, columns=COLUMNS)


def compare_campaigns(ref_path: str | Path, variant_path: str | Path, tolerances: dict | None = None) -> pd.DataFrame:
    """Open both campaigns' finished runs and `compare` them."""
    from interphase.report.build import open_campaign

    frames = []
    for path in (ref_path, variant_path):
        _, store, summ = open_campaign(path)
        try:
            frames.append(seed_values(summ, store))
        finally:
            store.close()
    return compare(*frames, tolerances)
