"""May the 3D Karlsruhe card's grains be softened from G 500 MPa to 50 MPa for the interface runs?
The stiffness pairs' tables from their committed runs (no engine).

    python studies/kfs_3d_stiffness/analyse.py [--check]

Reads results/<pair side>/summaries.csv and curves.parquet (the committed runs of g500_20x15x5.toml,
g50_20x15x5.toml, g500_30x15x10.toml, g50_30x15x10.toml) and writes:
  <side>/ensembles.csv                  the seed ensembles of each side
  compare_20x15x5.csv, compare_30x15x10.csv
                                        50 MPa against 500 MPa per case and metric in each cell
                                        (`campaign compare G500.toml G50.toml`: Welch 95 %, ±0.03 in
                                        tan δ and tan φ, ±0.05 in E, ±3° in θr)
  soil_test.csv                         each side's soil test on the box's plane and as the
                                        specimen's Mohr circle
  cost.csv                              wall time per run, per side and test (two at a time on the
                                        2 cores), and the 500/50 MPa ratio per cell
--check writes nothing and fails if a committed table differs from its re-derivation.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

from interphase.analysis.ensemble_table import ensemble_table
from interphase.analysis.soil_test import soil_test_readings
from interphase.campaign.compare import compare, seed_values
from interphase.campaign.results import read_committed, settle_tables

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
#: cell → (the card's own G 500 MPa side, the softened 50 MPa side): the reference first
PAIRS = {"20x15x5": ("g500_20x15x5", "g50_20x15x5"), "30x15x10": ("g500_30x15x10", "g50_30x15x10")}


def tables() -> dict[Path, pd.DataFrame]:
    out, readings, cost = {}, [], []
    for cell, sides in PAIRS.items():
        values = []
        for side in sides:
            summ, store = read_committed(RESULTS / side)
            out[RESULTS / side / "ensembles.csv"] = ensemble_table(summ, store)
            values.append(seed_values(summ, store))
            readings.append(soil_test_readings(summ).assign(side=side))
            for test, g in summ.groupby("test", sort=True):
                cost.append({"cell": cell, "side": side, "G_MPa": float(summ["shear_modulus"].iloc[0]) / 1e6,
                             "test": test, "runs": len(g), "run_s_mean": g["elapsed"].mean(),
                             "run_s_min": g["elapsed"].min(), "run_s_max": g["elapsed"].max()})
        out[RESULTS / f"compare_{cell}.csv"] = compare(*values)
    cost = pd.DataFrame(cost)
    stiff = cost.groupby(["cell", "test"])["run_s_mean"].transform(lambda s: s.iloc[0] / s.iloc[-1])
    cost["ratio_500_to_50"] = stiff.where(cost["G_MPa"].eq(500.0))
    soil = pd.concat(readings, ignore_index=True)
    out[RESULTS / "soil_test.csv"] = soil[["side", *[c for c in soil.columns if c != "side"]]].round(6)
    out[RESULTS / "cost.csv"] = cost.round(6)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="fail if a committed table differs from its re-derivation")
    args = ap.parse_args(argv)
    out = tables()
    with pd.option_context("display.width", 250, "display.max_columns", 30):
        for path, df in out.items():
            if path.name == "ensembles.csv":
                continue
            if path.name.startswith("compare_"):
                df = df[["case", "metric", "ref", "value", "change", "change_lo", "change_hi", "verdict", "n_ref",
                         "n_value", "seeds_needed"]]
            print(f"{path.name}:\n{df.to_string(index=False)}\n")
    return settle_tables(out, args.check, HERE)


if __name__ == "__main__":
    sys.exit(main())
