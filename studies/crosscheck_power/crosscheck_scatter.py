"""Scatter of the stress ratio in a cross-check's runs: what sizes a set that can decide.

    python studies/crosscheck_power/crosscheck_scatter.py OUTPUT_FOLDER [--after 0.001]

Per physical case and engine, from every finished run's series.parquet after `--after` metres of
shear: the sd of the ratio about the run's own mean and its integrated correlation length (the
autocorrelation summed up to its first zero crossing, times the sampling step, 1 + 2·Σρ_k); and the
sd over seeds of the paired difference YADE − LIGGGHTS at the start of the shear. A time average over
a window W then scatters by about sd·√(τ/W) (docs/crosscheck.md, "What the 15 minutes can judge").
"""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import numpy as np
import pandas as pd


def correlation_length(x: np.ndarray, r: np.ndarray) -> float:
    """Integrated correlation length [same unit as x] of the samples r(x) (uniform steps)."""
    r = r - r.mean()
    n = r.size
    acf = np.correlate(r, r, "full")[n - 1:] / (r.var() * np.arange(n, 0, -1))
    stop = int(np.argmax(acf < 0)) if (acf < 0).any() else n
    return float((1 + 2 * acf[1:stop].sum()) * np.median(np.diff(x)))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", type=Path)
    ap.add_argument("--after", type=float, default=1e-3, help="start of the steady part [m] (default 1 mm)")
    args = ap.parse_args(argv)
    rows, start = [], {}
    for case in sorted(args.folder.glob("*/DONE")):
        d = case.parent
        meta = json.loads((d / "case.json").read_text())
        s = pd.read_parquet(d / "series.parquet", columns=["shear_disp", "stress_ratio"]).dropna()
        late = s[s["shear_disp"] > args.after]
        if len(late) < 10:
            continue
        phys = re.sub(r"-s\d+$", "", meta["label"])
        rows.append(dict(case=phys, engine=meta["engine"], sd=late["stress_ratio"].std(),
                         tau_mm=1e3 * correlation_length(late["shear_disp"].to_numpy(), late["stress_ratio"].to_numpy())))
        start[(phys, meta["label"], meta["engine"])] = float(s["stress_ratio"].iloc[0])
    out = pd.DataFrame(rows).groupby(["case", "engine"])[["sd", "tau_mm"]].mean().unstack("engine")
    s0 = pd.Series(start).unstack()
    if {"liggghts", "yade"} <= set(s0.columns):
        out[("paired_sd_at_start", "")] = (s0["yade"] - s0["liggghts"]).groupby(level=0).std()
    print(out.round(4).to_string())


if __name__ == "__main__":
    main()
