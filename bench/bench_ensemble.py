"""Benchmark: the seed-ensemble peak (analysis.ensemble.peak_values, bagged leave-one-out) per call,
and the ensembles table of the committed sequential study (analysis.ensemble_table).

Run: PYTHONPATH=src .venv/bin/python bench/bench_ensemble.py — prints a Markdown table for
BENCHMARKS.md. Synthetic smoothed curves on the tool's 400-point grid; best of 5 wall-clock runs.
"""

from __future__ import annotations

import timeit
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.analysis.ensemble import peak_values
from interphase.analysis.ensemble_table import ensemble_table
from interphase.campaign.results import CommittedCurves as _Curves


def best(fn, repeat=3) -> float:
    """The shortest wall time [s] of `repeat` calls of fn (timeit, the garbage collector left on as in a real run)."""
    return min(timeit.repeat(fn, setup="gc.enable()", number=1, repeat=repeat))


STUDY = Path(__file__).resolve().parents[1] / "docs" / "reproduction" / "precision" / "study"


def main() -> None:
    rng = np.random.default_rng(0)
    print("| step | seeds | wall [ms] |\n|---|---|---|")
    for n in (3, 5, 10, 20, 40):
        S = 0.35 + 0.05 * rng.standard_normal((n, 400)).cumsum(1) / 20
        print(f"| peak_values | {n} | {1e3 * best(lambda: peak_values(S), 5):.1f} |")
    summ = pd.read_csv(STUDY / "summaries.csv")
    store = _Curves(STUDY / "curves.parquet")
    print(f"| ensemble_table, the sequential study ({len(summ)} runs, "
          f"{summ['physical_id'].nunique()} physical ids) | 3–40 | {1e3 * best(lambda: ensemble_table(summ, store), 2):.0f} |")


if __name__ == "__main__":
    main()
