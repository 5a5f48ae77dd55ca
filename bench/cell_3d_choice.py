"""Which 3D interface cell buys E ± 0.1 for the fewest core-hours? The cell study's price list
(issue 38 item 1: studies/kfs_3d_cell/cell_3d.toml, docs/3d.md).

    PYTHONPATH=src python bench/cell_3d_choice.py [studies/kfs_3d_cell/cell_3d.toml]

Reads the campaign's finished runs (or, without its runs folder, the committed tables in
studies/kfs_3d_cell/results/: summaries.csv, curves.parquet). Per cell (depth × length in
D50) and per physical case, from each run's leave-one-out peak (campaign.compare.seed_values, read
within the cell): seeds, the seed mean and its sd of tan φ (soil test) or tan δ, the mean wall time
per run (`elapsed`: one run on one core, two at a time on the 2-core VM). Then, per cell, the
interface seeds n a case needs for E's 95 % half-width (analysis.ensemble.ratio_interval: the
delta method on log E, Welch–Satterthwaite t) to reach ± 0.1 and ± 0.05 at the measured scatters
(the mean of the cell's interface sds, its soil sd) with m soil seeds shared by every case, and what
Group 1 (18 interface cases + m soil seeds) would cost in core-hours at that n. A projection from
3-seed sds, which are themselves uncertain by a factor ~2 (χ² with 2 degrees of freedom): it ranks
cells, it does not promise a precision. A measurement: exit 0 whatever it finds.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).parent))
from sequential_coverage import _Curves  # noqa: E402

from interphase.analysis.ensemble import ratio_interval  # noqa: E402
from interphase.campaign.compare import seed_values  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
COMMITTED = ROOT / "studies" / "kfs_3d_cell" / "results"
CELL = ["box_depth_d50", "box_length_d50"]
CASES = 18          # Group 1: 6 heights × 3 frictions


def open_runs(campaign: Path):
    """(summaries, store) of the campaign's runs, else of the committed tables."""
    from interphase.campaign.results import open_campaign
    from interphase.errors import InputError

    try:
        _, store, summ = open_campaign(campaign)
        return summ, store
    except InputError:
        return pd.read_csv(COMMITTED / "summaries.csv", dtype={"case_id": str}), _Curves(COMMITTED / "curves.parquet")


def seeds_for(half: float, a: float, sa: float, b: float, sb: float, m: int, cap: int = 200) -> float:
    """Interface seeds n (≥ 2) for E = a/b's 95 % half-width (the larger side of its interval) ≤
    `half`, with m soil seeds; NaN when the soil's term alone exceeds it within `cap`."""
    for n in range(2, cap + 1):
        lo, hi = ratio_interval(a, sa, n, b, sb, m)
        if max(hi - a / b, a / b - lo) <= half:
            return float(n)
    return float("nan")


def table(summ: pd.DataFrame, store) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(per cell and case: seeds, mean, sd, run time; per cell: the projection)."""
    rows, cells = [], []
    for key, g in summ.groupby(CELL, sort=True):
        v = seed_values(g, store)
        t = g.set_index("case_id")["elapsed"].astype(float)
        for case, c in v.groupby("case", sort=True):
            rows.append({"depth": key[0], "length": key[1], "case": case, "test": c["test"].iloc[0],
                         "seeds": int(c["peak"].notna().sum()), "mean": c["peak"].mean(), "sd": c["peak"].std(ddof=1),
                         "E": c["E"].mean() if "E" in c else np.nan,
                         "run_s": float(t.reindex(c["case_id"]).mean())})
    per = pd.DataFrame(rows)
    for (depth, length), g in per.groupby(["depth", "length"], sort=True):
        box, iface = g[g["test"].eq("box")], g[g["test"].eq("interface") & (g["seeds"] >= 2)]
        if box.empty or box["seeds"].iloc[0] < 2 or iface.empty:
            continue
        b, sb = float(box["mean"].iloc[0]), float(box["sd"].iloc[0])
        a, sa = float(iface["mean"].mean()), float(np.sqrt((iface["sd"] ** 2).mean()))
        t_box, t_if = float(box["run_s"].iloc[0]), float(iface["run_s"].mean())
        out = {"depth": depth, "length": length, "interface_cases": len(iface), "tan_phi": b, "sd_tan_phi": sb,
               "sd_tan_delta": sa, "run_s_box": t_box, "run_s_interface": t_if}
        for m in (6, 12):
            for half in (0.1, 0.05):
                n = seeds_for(half, a, sa, b, sb, m)
                out[f"n_E{half:g}_m{m}"] = n
                out[f"core_h_E{half:g}_m{m}"] = (CASES * n * t_if + m * t_box) / 3600 if n == n else np.nan
        cells.append(out)
    return per, pd.DataFrame(cells)


def _md(df: pd.DataFrame) -> str:
    fmt = lambda v: f"{v:.4g}" if isinstance(v, (float, np.floating)) else str(v)
    return "\n".join(["| " + " | ".join(map(str, df.columns)) + " |", "|" + "---|" * len(df.columns)]
                     + ["| " + " | ".join(fmt(v) for v in row) + " |" for row in df.itertuples(index=False)])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("campaign", nargs="?", default=str(ROOT / "studies" / "kfs_3d_cell" / "cell_3d.toml"))
    args = ap.parse_args(argv)
    summ, store = open_runs(Path(args.campaign))
    try:
        per, cells = table(summ, store)
    finally:
        getattr(store, "close", lambda: None)()
    print(_md(per))
    print()
    print(_md(cells) if not cells.empty else "no cell has both tests at ≥ 2 seeds and an interface case")
    return 0


if __name__ == "__main__":
    sys.exit(main())
