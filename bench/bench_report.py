"""Benchmark: `campaign report` on a synthetic index of 1000 cases (target < 30 s).

Synthetic summaries (interphase.report.synthetic: the study-default trends + noise), input tables from
campaigns/group4.toml, lab overlay from tests/data/lab_example.csv, 199 bootstrap refits per fit. No
case folders, so no stress curves or force networks (those read one case at a time and scale with the
number of groups, not cases). Prints the stage times; the result goes in BENCHMARKS.md ("report").

    .venv/bin/python bench/bench_report.py [N]
"""

import cProfile
import pstats
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main(n: int = 1000) -> None:
    from interphase.analysis.correlations import fit_study, prepare_points
    from interphase.campaign.schema import load_campaign
    from interphase.report.build import report_from_summaries
    from interphase.report.synthetic import synthetic_summaries

    summ = synthetic_summaries(n, seed=0)
    camp = load_campaign(ROOT / "campaigns" / "group4.toml")
    t = time.perf_counter()
    fits = fit_study(prepare_points(summ), n_boot=199)
    t_fit = time.perf_counter() - t
    best = float("inf")
    for _ in range(2):
        with tempfile.TemporaryDirectory() as tmp:
            t = time.perf_counter()
            res = report_from_summaries(summ, tmp, campaign=camp, lab=ROOT / "tests" / "data" / "lab_example.csv",
                                        n_boot=199)
            best = min(best, time.perf_counter() - t)
            nfiles = len(res.files)
    print(f"cases {n}: correlations ({len(fits)} fits, 199 bootstrap each) {t_fit:.2f} s; "
          f"whole report best of 2 {best:.2f} s; {nfiles} files")
    if "--profile" in sys.argv:
        with tempfile.TemporaryDirectory() as tmp:
            cProfile.runctx("report_from_summaries(summ, tmp, campaign=camp, n_boot=199)", globals(),
                            {"report_from_summaries": report_from_summaries, "summ": summ, "tmp": tmp, "camp": camp},
                            "/tmp/bench_report.prof")
        pstats.Stats("/tmp/bench_report.prof").sort_stats("cumulative").print_stats(15)


if __name__ == "__main__":
    main(int(next((a for a in sys.argv[1:] if a.isdigit()), 1000)))
