"""Group 1 on the quasi-2D Karlsruhe card: its tables from its committed runs (no engine).

    python studies/kfs_group1_2d/analyse.py [--check]

Reads results/summaries.csv and results/curves.parquet (the committed runs of group1_kfs_2d.toml)
and writes, beside them:
  ensembles.csv   the seed ensembles, one row per physical interface case (what `campaign report`
                  writes as tables/ensembles.csv)
  cases.csv       the same per case with its tooth (Rt/D50, Sw/D50, face angle) and friction
  saturation.csv  per friction: the first tooth whose E interval reaches 1, the one under it, and
                  any taller tooth decided below 1 again
  plateau.csv     E on the teeth at Rt/D50 >= 1 against 1
  soil_test.csv   the paired soil test read on the box's plane and as the specimen's Mohr circle
--check writes nothing and fails if a committed table differs from its re-derivation. The fits
(criterion.json, correlations.csv, criterion_check.md and the figures) are the report's:
`studies/reproduction/refit_reproduction.py --kfs2d`.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import pandas as pd

from interphase.analysis.ensemble_table import ensemble_table
from interphase.analysis.group1 import plateau, saturation, tooth_cases
from interphase.analysis.soil_test import soil_test_readings
from interphase.campaign.results import read_committed, settle_tables

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
#: the same discs' biaxial test at the calibration record's state, beside the box's Mohr circle
BIAXIAL = HERE.parents[1] / "docs" / "soils" / "karlsruhe-fine-sand-2d" / "verification_tmd17_6seeds.csv"


def tables(folder: Path = RESULTS) -> dict[Path, pd.DataFrame]:
    summ, store = read_committed(folder)
    cases = tooth_cases(summ, store)
    return {folder / "ensembles.csv": ensemble_table(summ, store),
            folder / "cases.csv": cases.round(6),
            folder / "saturation.csv": saturation(cases).round(6),
            folder / "plateau.csv": plateau(cases).round(6),
            folder / "soil_test.csv": soil_test_readings(summ).round(6)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="fail if a committed table differs from its re-derivation")
    args = ap.parse_args(argv)
    out = tables()
    with pd.option_context("display.width", 200, "display.max_columns", 30):
        for path, df in out.items():
            if path.name != "ensembles.csv":
                print(f"{path.name}:\n{df.to_string(index=False)}\n")
    soil = out[RESULTS / "cases.csv"]["tan_phi"].dropna()
    print(f"soil test tan φ {soil.iloc[0]:.3f}, φ {math.degrees(math.atan(soil.iloc[0])):.1f}°")
    if BIAXIAL.exists():
        v = pd.read_csv(BIAXIAL).iloc[0]
        print(f"the same discs' biaxial φ_peak ({v['record']}, {int(v['n_seeds'])} seeds): "
              f"{v['phi_peak_deg']:.1f}° ({v['phi_peak_deg_lo']:.1f}–{v['phi_peak_deg_hi']:.1f}°)")
    return settle_tables(out, args.check, HERE)


if __name__ == "__main__":
    sys.exit(main())
