"""The bill of precision (issue 30 item 4), projected from the committed study: what the study would
cost at a stated precision under the sequential-seeds rule, against today's 3-seed study.

Ingredients, all measured: each physical case's seed scatter (the populations of
studies/sequential_seeds/sequential_coverage.py: interface seeds' peak states, the soil's 10 box seeds) and each run's
wall time on this machine (`elapsed` of docs/reproduction/summaries.csv: one run on one core, two at
a time on the 2-core VM). Per case, 4000 trials draw seeds from Normal(case mean, case sd) and apply
the rule campaign run applies (start 3, step 1, within the target two rounds in a row, a cap), with
the soil measured on a fixed number of box seeds m (`[pairs] seeds`, shared by every case on that soil). Reported:
the share of physical cases whose final interval reaches the target (mean over trials), the mean
interface seeds, and the core-hours: Σ over cases of mean seeds × the case's mean run time, plus
m × the mean box run time for each of the two soils. A projection, not a run of the study.

    PYTHONPATH=src python studies/sequential_seeds/sequential_bill.py [--trials 4000] [--ensembles docs/reproduction/ensembles.csv]

--ensembles writes today's ensembles table of the study (the report's, analysis.ensemble_table, on the
committed runs) and prints the share of physical cases already within ± 0.05 and ± 0.1 in E.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.analysis.ensemble_table import ensemble_table
from interphase.analysis.seed_draws import populations, project, run_times
from interphase.campaign.results import CommittedCurves

REPRO = Path(__file__).resolve().parents[2] / "docs" / "reproduction"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=4000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--ensembles", type=Path, help="write today's ensembles table here (CSV)")
    ap.add_argument("--group", help="project one group of the study only (e.g. group1), its soil's box seeds with it")
    ap.add_argument("--only", nargs=4, metavar=("QUANTITY", "HALFWIDTH", "CAP", "M"),
                    help="one setting instead of the table's, e.g. --only E 0.1 24 20")
    args = ap.parse_args(argv)
    if args.ensembles:
        table = ensemble_table(pd.read_csv(REPRO / "summaries.csv"), CommittedCurves(REPRO / "curves.parquet"))
        table.to_csv(args.ensembles, index=False, float_format="%.5g")
        half = (table["E_hi"] - table["E_lo"]) / 2
        print(f"today's ensembles ({len(table)} physical cases) → {args.ensembles}: E half-width median "
              f"{half.median():.3f}; within ± 0.05 {np.mean(half <= 0.05):.0%}, ± 0.1 {np.mean(half <= 0.1):.0%}")
    rng = np.random.default_rng(args.seed)
    summ = pd.read_csv(REPRO / "summaries.csv")
    pops = [p for p in populations(summ, CommittedCurves(REPRO / "curves.parquet")) if args.group in (None, p["group"])]
    times, box_time, today, runs = run_times(summ, args.group)
    soils = len({p["b"].tobytes() for p in pops})
    print(f"today{' (' + args.group + ')' if args.group else ''}: {runs} runs (3 seeds a case, 10 a soil), "
          f"{today:.1f} core-hours, {today / 2:.1f} h on 2 cores")
    print(f"{'target':<14} {'cap':>4} {'soil m':>6} {'cases reaching':>15} {'mean seeds':>10} {'core-h':>7} {'x today':>8}")
    settings = ([(args.only[0], float(args.only[1]), int(args.only[2]), int(args.only[3]))] if args.only else
                [(q, t, cap, m) for q, t in (("E", 0.05), ("E", 0.1), ("tan_delta", 0.05), ("tan_delta", 0.02))
                 for cap, m in ((12, 10), (12, 40), (24, 40), (24, 80)) if q == "E" or m == 10])
    for quantity, target, cap, m in settings:
        r = project(pops, times, quantity, target, cap, m, args.trials, rng)
        h = r["hours"] + soils * m * box_time / 3600
        print(f"{quantity + ' ± ' + format(target, 'g'):<14} {cap:>4} {m:>6} {r['reached']:>15.0%} "
              f"{r['seeds']:>10.1f} {h:>7.1f} {h / today:>8.1f}")


if __name__ == "__main__":
    main()
