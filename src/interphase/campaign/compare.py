"""`campaign compare REF VARIANT`: what changing one setting does, physical case by physical case,
against the seed scatter (analysis.difference: agree / differ / undecided at a tolerance).

Physical cases are matched by label without the seed (`…-s3`), so the two campaigns must differ only
in what the labels do not name (stiffness, speed, box size, rolling friction, damping …).
`campaign compare CAMPAIGN --by FIELD=VALUE …` does the same within one campaign whose sweep varies
such fields (a cell-size study): its runs are split into cells by the named fields' values, and every
cell is compared with the one where each field has the VALUE given (`compare_cells`). Per-seed
values, each at its own ensemble's reading (analysis.ensemble):
  tan_delta, tan_phi        the seed's bagged leave-one-out peak value: its smoothed ratio where
                            bootstrap means of its ensemble's OTHER seeds peak (analysis.ensemble.
                            peak_values; interface: the surface; box: the shear plane)
  tan_delta_cs, tan_phi_cs  the seed's mean ratio over the last 40 % of the shear
  E, E_cs                   the seed's interface value over its own box test's (pair_id)
  theta_r_deg               θr at the surface at the run's peak snapshot [deg]
  surface_contacts_per_d50  contacts on the surface at that snapshot per D50 of surface length
                            [1/D50]; in a 3D cell (device periodic3d) per D50² of surface area, the
                            length times the depth (box_depth_d50): a deeper cell has proportionally
                            more, so per length alone every depth would read 'differ'
The two campaigns' specimens are different after consolidation even on the same seed, so the
comparison is unpaired (Welch).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from interphase.analysis.difference import difference
from interphase.analysis.ensemble import physical_case, seed_states
from interphase.analysis.strength import PEAK_WINDOW_D50
from interphase.errors import InputError

# what a change must stay within to count as "no effect" (docs/convergence.md says why)
TOLERANCES = {"tan_delta": 0.03, "tan_delta_cs": 0.03, "tan_phi": 0.03, "tan_phi_cs": 0.03,
              "E": 0.05, "E_cs": 0.05, "theta_r_deg": 3.0, "surface_contacts_per_d50": 0.10}
RELATIVE = {"surface_contacts_per_d50"}     # tolerance as a fraction of the reference mean
COLUMNS = ("case", "metric", "ref", "ref_lo", "ref_hi", "value", "value_lo", "value_hi", "change", "change_lo",
           "change_hi", "tol", "verdict", "n_ref", "n_value", "seeds_needed")


def _numeric(rows: pd.DataFrame, col: str) -> pd.Series:
    """Column `col` of `rows` as numbers (NaN where it is not one, or where the table lacks it)."""
    return pd.to_numeric(rows[col], errors="coerce") if col in rows else pd.Series(np.nan, index=rows.index)


def surface_extent_d50(rows: pd.DataFrame, d50: float) -> pd.Series:
    """The surface under the soil of each summary row: its length in D50 (region_x1 − region_x0), and
    in a 3D cell (device periodic3d) that length times the depth box_depth_d50, in D50²."""
    num = lambda col: _numeric(rows, col)
    length = (num("region_x1") - num("region_x0")) / d50
    if "device" not in rows or "box_depth_d50" not in rows:
        return length
    return length * num("box_depth_d50").where(rows["device"].eq("periodic3d"), 1.0)


def seed_values(summaries: pd.DataFrame, store) -> pd.DataFrame:
    """One row per finished run: physical case, seed, test, pair_id and the per-seed values above
    (E filled in for interface runs whose box test is present)."""
    done = summaries[summaries["status"].eq("done")] if "status" in summaries else summaries
    done = done.assign(_phys=done["label"].map(physical_case))
    frames = []
    for phys, g in done.groupby("_phys", sort=True):
        d50 = float(pd.to_numeric(g["d50"], errors="coerce").median())
        peaks, crits = seed_states([store.curve(cid) for cid in g["case_id"]], PEAK_WINDOW_D50 * d50)
        num = lambda col: _numeric(g, col)
        cell_d50 = surface_extent_d50(g, d50)
        frames.append(pd.DataFrame({
            "case": phys, "case_id": g["case_id"].astype(str), "seed": g["seed"].astype(int), "test": g["test"],
            "pair_id": g["pair_id"] if "pair_id" in g else None, "peak": peaks, "critical": crits,
            "theta_r_deg": num("theta_r_surface_deg"),
            "surface_contacts_per_d50": num("n_contacts_surface") / cell_d50.where(cell_d50 > 0)}))
    cols = ["case", "case_id", "seed", "test", "pair_id", "peak", "critical", "theta_r_deg", "surface_contacts_per_d50"]
    out = pd.concat(frames, ignore_index=True)[cols] if frames else pd.DataFrame(columns=cols)
    out = out[out["peak"].notna() | out["critical"].notna()].reset_index(drop=True)
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
            "theta_r_deg": "theta_r_deg", "surface_contacts_per_d50": "surface_contacts_per_d50"}


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


def _cell_name(fields, key) -> str:
    return ", ".join(f"{f}={v:g}" for f, v in zip(fields, key))


def compare_cells(summaries: pd.DataFrame, store, by: dict[str, float], where: str = "",
                  tolerances: dict | None = None) -> pd.DataFrame:
    """Each cell of one campaign's runs (the runs sharing the values of the `by` fields, columns of
    the summaries) against the reference cell (each field at its value in `by`): the `compare` table
    with a first column `variant` naming the cell. Seed values are read within each cell (its own
    ensembles and its own soil tests for E), so that one label's runs in two cells are never pooled."""
    fields = list(by)
    missing = [f for f in fields if f not in summaries.columns]
    if missing:
        raise InputError(f"--by {missing[0]}: no such field in the runs' summaries", where=where,
                         fix="name a case field the campaign sweeps, e.g. --by box_depth_d50=10")
    num = summaries[fields].apply(pd.to_numeric, errors="coerce")
    if num.isna().any().any():
        bad = [f for f in fields if num[f].isna().any()]
        raise InputError(f"--by {bad[0]}: not a number on every run", where=where,
                         fix="split by a numeric case field (box size, stiffness, speed …)")
    groups = {(k if isinstance(k, tuple) else (k,)): g
              for k, g in summaries.groupby([num[f].round(9) for f in fields], sort=True)}
    ref_key = tuple(round(float(by[f]), 9) for f in fields)
    cells = list(groups)
    if ref_key not in cells:
        raise InputError(f"no finished run has {_cell_name(fields, ref_key)}", where=where,
                         fix="the reference cell's values are among: "
                             + "; ".join(_cell_name(fields, k) for k in cells))
    if len(cells) < 2:
        raise InputError(f"every finished run has {_cell_name(fields, ref_key)}: nothing to compare",
                         where=where, fix="name the fields the campaign varies")
    values = {k: seed_values(g, store) for k, g in groups.items()}
    frames = [compare(values[ref_key], values[k], tolerances).assign(variant=_cell_name(fields, k))
              for k in cells if k != ref_key]
    out = pd.concat(frames, ignore_index=True)
    out.attrs["reference"] = _cell_name(fields, ref_key)
    return out[["variant", *COLUMNS]]


def compare_campaigns(ref_path: str | Path, variant_path: str | Path, tolerances: dict | None = None) -> pd.DataFrame:
    """Open both campaigns' finished runs and `compare` them."""
    from interphase.campaign.results import open_campaign

    frames = []
    for path in (ref_path, variant_path):
        _, store, summ = open_campaign(path)
        try:
            frames.append(seed_values(summ, store))
        finally:
            store.close()
    return compare(*frames, tolerances)


def compare_within(campaign_path: str | Path, by: dict[str, float], tolerances: dict | None = None) -> pd.DataFrame:
    """Open one campaign's finished runs and `compare_cells` them."""
    from interphase.campaign.results import open_campaign

    _, store, summ = open_campaign(campaign_path)
    try:
        return compare_cells(summ, store, by, where=str(campaign_path), tolerances=tolerances)
    finally:
        store.close()
