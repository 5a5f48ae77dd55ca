"""Write again every committed seed-ensembles table from its committed summaries and curves (no runs
folder, no engine): what `campaign report` writes as tables/ensembles.csv (analysis.ensemble_table).

    PYTHONPATH=src python studies/reproduction/ensembles_tables.py [--check]

Tables: docs/reproduction/ensembles.csv (the study, 3 seeds), precision/ensembles.csv (Group 1 to
E ± 0.1), precision/study/ensembles.csv (the sequential study) and group1_sandlike/ensembles.csv. The
other reports' tables are `studies/reproduction/refit_reproduction.py`'s; a study's (studies/NAME/) its own
analysis script's.
The check campaigns' tables (stronger_soil, comb_stiffness, narrow_valleys) and docs/convergence/
have no committed curves: they keep the estimator they were written with, the seed-mean curve's
maximum (docs/reproduction.md and docs/convergence.md say so where they are quoted).
--check: print the largest change of tan δ, tan φ and E per table instead of writing.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd

from interphase.campaign.results import CommittedCurves as _Curves

from interphase.analysis.ensemble_table import ensemble_table  # noqa: E402

REPRO = Path(__file__).resolve().parents[2] / "docs" / "reproduction"
TABLES = {"": "%.5g", "precision/": None, "precision/study/": None, "group1_sandlike/": None}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args(argv)
    for sub, fmt in TABLES.items():
        d = REPRO / sub
        new = ensemble_table(pd.read_csv(d / "summaries.csv"), _Curves(d / "curves.parquet"))
        if args.check:
            old = pd.read_csv(d / "ensembles.csv").set_index(["group", "case"])
            n = new.set_index(["group", "case"])
            rel = {c: float(((n[c] / old[c]) - 1).abs().max()) for c in ("tan_delta", "tan_phi", "E")}
            print(sub or ".", len(new), "rows;", ", ".join(f"{c} {v:.2%}" for c, v in rel.items()))
            continue
        new.to_csv(d / "ensembles.csv", index=False, float_format=fmt)
        print("wrote", d / "ensembles.csv", len(new), "rows")


if __name__ == "__main__":
    main()
