"""Seed ensembles of a campaign of triaxial/biaxial cells (the cell-size study, the pilot of the free
parameters), as Markdown for docs/soils.md and BENCHMARKS.md.

    PYTHONPATH=src python studies/soil_cells/cell_study.py campaigns/soils/cell_size.toml --by n_grains --save docs/soils/cell_size

Reads the campaign's finished runs (or, without them, the committed copy in --save: summaries.csv and
cell_curves.parquet, each run's ε1, εv, R, e every 0.2 % of ε1) and prints, per physical case (the
fields named by --by), the CellResult of its seeds (analysis.cell_ensemble: φ_peak, ψ_max, φ at the
end and e0 with 95 % intervals) and the mean wall time per run.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.analysis.cell_ensemble import cell_result

ROOT = Path(__file__).resolve().parents[2]
STEP = 0.002


def from_runs(campaign: Path):
    """(summaries, curves) of the campaign's finished runs; None when it has none."""
    from interphase.campaign.plan import plan
    from interphase.campaign.schema import load_campaign
    from interphase.campaign.store import CampaignStore

    c = load_campaign(campaign)
    planned = {p.case_id: p for p in plan(c)}
    if not Path(c.output).exists():
        return None
    with CampaignStore(c.output) as store:
        summ = store.summaries()
        if not len(summ):
            return None
        summ = summ[summ["case_id"].isin(planned)]
        curves = []
        for cid in summ["case_id"]:
            s = pd.read_parquet(store.case_folder(cid) / "series.parquet", columns=["eps1", "epsv", "ratio", "e"])
            grid = np.arange(0, s["eps1"].max() + 1e-12, STEP)
            o = np.argsort(s["eps1"].to_numpy(), kind="stable")
            curves.append(pd.DataFrame({"case_id": cid, "eps1": grid, **{
                k: np.interp(grid, s["eps1"].to_numpy()[o], s[k].to_numpy()[o]) for k in ("epsv", "ratio", "e")}}))
    return summ, pd.concat(curves, ignore_index=True)


def ensembles(summ: pd.DataFrame, curves: pd.DataFrame, by: list[str]) -> pd.DataFrame:
    rows = []
    for key, g in summ.groupby(by, dropna=False):
        runs, e0 = [], []
        for cid in g["case_id"]:
            c = curves[curves["case_id"] == cid]
            runs.append((c["eps1"].to_numpy(), c["epsv"].to_numpy(), c["ratio"].to_numpy()))
            e0.append(float(c["e"].iloc[0]))
        r = cell_result(str(g["test"].iloc[0]), float(g["normal_stress"].iloc[0]), runs, e0)
        key = key if isinstance(key, tuple) else (key,)
        # the group's keys last: a CellResult has fields of its own by some of those names (preparation)
        rows.append({**r.to_dict(), **dict(zip(by, key)), "wall_s": float(g["elapsed"].mean())})
    return pd.DataFrame(rows)


def iv(row, name, fmt=".1f"):
    v, lo, hi = (row[name + k] for k in ("", "_lo", "_hi"))
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "–"
    return f"{v:{fmt}} ({lo:{fmt}}–{hi:{fmt}})" if lo is not None and not math.isnan(lo) else f"{v:{fmt}}"


def markdown(df: pd.DataFrame, by: list[str]) -> str:
    head = "| " + " | ".join(by) + " | seeds | φ_peak [°] | ε1 at peak [%] | ψ_max [°] | φ at the end [°] | e0 | wall per run [s] |"
    lines = [head, "|" + "---|" * (len(by) + 7)]
    for _, r in df.iterrows():
        keys = " | ".join(f"{r[b]:g}" if isinstance(r[b], (int, float)) else str(r[b]) for b in by)
        lines.append(f"| {keys} | {r['n_seeds']} | {iv(r, 'phi_peak_deg')} | "
                     f"{100 * r['eps1_at_peak']:.1f} | {iv(r, 'psi_max_deg')} | {iv(r, 'phi_cs_deg')} | "
                     f"{iv(r, 'void_ratio', '.3f')} | {r['wall_s']:.0f} |")
    return "\n".join(lines)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("campaign", type=Path)
    ap.add_argument("--by", action="append", required=True, help="the field(s) that tell physical cases apart")
    ap.add_argument("--save", type=Path, default=None, help="folder of the committed copy")
    a = ap.parse_args(argv)
    got = from_runs(a.campaign)
    if got is not None and a.save:
        a.save.mkdir(parents=True, exist_ok=True)
        keep = ["case_id", "label", "physical_id", "test", "seed", *a.by, "normal_stress", "phi_peak_deg", "eps1_peak",
                "psi_max_deg", "phi_end_deg", "e0", "sigma3_departure_max", "inertial_number_max", "coordination_start",
                "elapsed"]
        got[0][[c for c in dict.fromkeys(keep) if c in got[0]]].to_csv(a.save / "summaries.csv", index=False,
                                                                     float_format="%.6g")
        got[1].astype({k: np.float32 for k in ("eps1", "epsv", "ratio", "e")}).to_parquet(
            a.save / "cell_curves.parquet", index=False, compression="zstd")
    if got is None:
        got = (pd.read_csv(a.save / "summaries.csv"), pd.read_parquet(a.save / "cell_curves.parquet"))
    print(markdown(ensembles(*got, a.by), a.by))


if __name__ == "__main__":
    main()
