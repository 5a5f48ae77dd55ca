"""The 3D interface cell's depth and length on the Karlsruhe card: its tables from its committed runs
(no engine), and what each cell would cost Group 1.

    python studies/kfs_3d_cell/analyse.py [--check]

Reads results/summaries.csv and results/curves.parquet (the committed runs of cell_3d.toml) and
writes, beside them:
  ensembles.csv      the seed ensembles, one row per physical interface case and cell
  compare_cells.csv  every cell against the 10-deep, 20-long one (`campaign compare cell_3d.toml
                     --by box_depth_d50=10 --by box_length_d50=20`: Welch 95 %, ±0.03 in tan δ and
                     tan φ, ±0.05 in E, ±3° in θr)
  soil_by_cell.csv   per cell the soil test: the mean of its seeds' readings (each at its ensemble's
                     peak, what a seed's E divides by) with its 95 % t interval, as compare_cells
                     reads it, the sd of a seed's reading, the runs' own maxima, wall time per run
  cell_cases.csv     per cell and case: seeds, the mean and sd of the seeds' readings, E, wall time
  cell_choice.csv    per cell the interface seeds a case needs for E ± 0.1 and ± 0.05 at the scatter
                     measured, with 6 or 12 soil seeds, and what Group 1 (18 cases) costs at that
                     count in core-hours; a projection from 3-seed sds (uncertain by a factor ~2):
                     it ranks cells, it does not promise a precision
  bill_group1.csv    the bill as run in the chosen cell (studies/kfs_group1_3d/results/summaries.csv)
--check writes nothing and fails if a committed table differs from its re-derivation.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.analysis.ensemble import ratio_interval, t_interval
from interphase.analysis.ensemble_table import ensemble_table
from interphase.campaign.compare import compare_cells, seed_values
from interphase.campaign.results import read_committed, settle_tables

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
GROUP1_3D = HERE.parent / "kfs_group1_3d" / "results" / "summaries.csv"
CELL = ["box_depth_d50", "box_length_d50"]
REFERENCE = {"box_depth_d50": 10.0, "box_length_d50": 20.0}
GROUP1_CASES = 18          # 6 heights × 3 frictions: the Group 1 the choice was priced for


def seeds_for(half: float, a: float, sa: float, b: float, sb: float, m: int, cap: int = 200) -> float:
    """Interface seeds n (≥ 2) for E = a/b's 95 % half-width (the larger side of its interval) ≤
    `half`, with m soil seeds; NaN when the soil's term alone exceeds it within `cap`."""
    for n in range(2, cap + 1):
        lo, hi = ratio_interval(a, sa, n, b, sb, m)
        if max(hi - a / b, a / b - lo) <= half:
            return float(n)
    return float("nan")


def per_cell(summ: pd.DataFrame, store) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """(per cell and case, per cell the soil test, per cell the projection), each cell's seeds
    read within the cell (its own ensembles and soil test)."""
    rows, soil, cells = [], [], []
    for (depth, length), g in summ.groupby(CELL, sort=True):
        v = seed_values(g, store)
        t = g.set_index("case_id")["elapsed"].astype(float)
        for case, c in v.groupby("case", sort=True):
            rows.append({"depth": depth, "length": length, "case": case, "test": c["test"].iloc[0],
                         "seeds": int(c["peak"].notna().sum()), "mean": c["peak"].mean(), "sd": c["peak"].std(ddof=1),
                         "E": c["E"].mean(), "run_s": float(t.reindex(c["case_id"]).mean())})
        box = g[g["test"].eq("box")]
        peaks = v.loc[v["test"].eq("box"), "peak"].to_numpy(float)
        lo, hi = t_interval(peaks)
        soil.append({"depth": depth, "length": length, "seeds": len(peaks), "tan_phi": peaks.mean(),
                     "tan_phi_lo": lo, "tan_phi_hi": hi, "sd_seed": peaks.std(ddof=1),
                     "maxima_mean": box["peak_stress_ratio"].mean(), "maxima_sd": box["peak_stress_ratio"].std(ddof=1),
                     "run_s_mean": box["elapsed"].mean(), "run_s_min": box["elapsed"].min(),
                     "run_s_max": box["elapsed"].max()})
    per = pd.DataFrame(rows)
    for (depth, length), g in per.groupby(["depth", "length"], sort=True):
        box, iface = g[g["test"].eq("box")], g[g["test"].eq("interface") & (g["seeds"] >= 2)]
        b, sb = float(box["mean"].iloc[0]), float(box["sd"].iloc[0])
        a, sa = float(iface["mean"].mean()), float(np.sqrt((iface["sd"] ** 2).mean()))
        t_box, t_if = float(box["run_s"].iloc[0]), float(iface["run_s"].mean())
        out = {"depth": depth, "length": length, "interface_cases": len(iface), "tan_phi": b, "sd_tan_phi": sb,
               "sd_tan_delta": sa, "run_s_box": t_box, "run_s_interface": t_if}
        for m in (6, 12):
            for half in (0.1, 0.05):
                n = seeds_for(half, a, sa, b, sb, m)
                out[f"n_E{half:g}_m{m}"] = n
                out[f"core_h_E{half:g}_m{m}"] = (GROUP1_CASES * n * t_if + m * t_box) / 3600 if n == n else np.nan
        cells.append(out)
    soil = pd.DataFrame(soil)
    soil["maxima_minus_tan_phi"] = soil["maxima_mean"] - soil["tan_phi"]
    return per, soil, pd.DataFrame(cells)


def bill(path: Path = GROUP1_3D) -> pd.DataFrame:
    """Group 1 as it ran in the chosen cell: runs, mean wall time and core-hours per test."""
    s = pd.read_csv(path)
    rows = [{"test": t, "runs": len(g), "run_s_mean": g["elapsed"].mean(), "core_h": g["elapsed"].sum() / 3600}
            for t, g in s.groupby("test", sort=True)]
    rows.append({"test": "all", "runs": len(s), "run_s_mean": s["elapsed"].mean(), "core_h": s["elapsed"].sum() / 3600})
    return pd.DataFrame(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="fail if a committed table differs from its re-derivation")
    args = ap.parse_args(argv)
    summ, store = read_committed(RESULTS)
    per, soil, choice = per_cell(summ, store)
    out = {RESULTS / "ensembles.csv": ensemble_table(summ, store),
           RESULTS / "compare_cells.csv": compare_cells(summ, store, REFERENCE),
           RESULTS / "soil_by_cell.csv": soil.round(6),
           RESULTS / "cell_cases.csv": per.round(6),
           RESULTS / "cell_choice.csv": choice.round(6),
           RESULTS / "bill_group1.csv": bill().round(6)}
    with pd.option_context("display.width", 250, "display.max_columns", 40):
        for path, df in out.items():
            if path.name not in ("ensembles.csv", "compare_cells.csv"):
                print(f"{path.name}:\n{df.to_string(index=False)}\n")
        c = out[RESULTS / "compare_cells.csv"]
        print(c[["variant", "case", "metric", "change", "change_lo", "change_hi", "verdict", "seeds_needed"]]
              .to_string(index=False))
    return settle_tables(out, args.check, HERE)


if __name__ == "__main__":
    sys.exit(main())
