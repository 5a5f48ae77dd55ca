"""Coverage of the sequential-seeds stopping rule ([seeds], campaign.sequential), by resampling the
study's committed runs (docs/reproduction/summaries.csv and curves.parquet: 126 physical cases on
seeds 1-3, two soils on seeds 1-10).

Per physical case, the seeds' peak states (analysis.ensemble.seed_states, as the report's ensembles
table computes them) are the population: tan δ of the interface seeds, tan φ of the soil's box
seeds; the case's "truth" is its full-data value (mean tan δ; E = mean tan δ / mean tan φ). A trial
draws seeds one by one and applies the rule exactly as campaign run does: seeds 1..start, then +step
while the 95 % interval's half-width (t interval for tan δ; analysis.ensemble.ratio_interval for E,
the box side on max(10, n) seeds as [pairs] seeds = 1-10 and the paired seeds give) is wider than the
target, up to max; a case within the target runs one more round (campaign.sequential.CONFIRM) and
stops when that round reads within too, else it goes on (rows "two in a row": the rule campaign run
uses; rows without it: the plain rule, stopping on the first reading within, for comparison).
Coverage = share of trials whose final 95 % interval contains the truth; "worst" the lowest case's
coverage; "seeds" the mean seeds used; "reached" the share of trials stopping at the target rather than at the cap.

Three ways of drawing a seed (the study has only 3 interface seeds per case):
  - normal: Normal(case mean, case sd) (the soil's from its 10 seeds). The fixed-n t interval is
    exact here, so what coverage is lost is the rule's. The primary check.
  - pooled: value = case mean + case sd × z, z drawn from the deviations of every case's seeds from
    their case's mean (378 interface, 20 box) divided by their group's pooled sd and scaled by
    √(N/(N−1)) to unit variance: the study's own shape of scatter (a mixture of the cases' scales,
    heavier-tailed than a normal). Not each case's own sd: three deviations over their own sd lie on
    a U-shaped (arcsine) law whatever the data, a bimodal population on which a 3-seed t interval
    covers 90 %.
  - per-case: the case's own seeds drawn with replacement, moved away from their mean by √(N/(N−1))
    so that the draws have the seeds' variance (the report's adjusted bootstrap). With 3 values a
    draw of 3 is all one seed 1 time in 9, a zero-width interval that stops the rule at once: a
    property of a 3-point population, not of the rule; shown beside the fixed-n intervals it is
    judged against.

    PYTHONPATH=src python studies/sequential_seeds/sequential_coverage.py [--trials 4000] [--seed 1]
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from interphase.analysis.ensemble import ratio_interval
from interphase.analysis.seed_draws import apply_rule, draws, populations, running
from interphase.campaign.results import CommittedCurves

ROOT = Path(__file__).resolve().parents[2]
REPRO = ROOT / "docs" / "reproduction"


def pooled_shape(pops: list[dict], side: str) -> np.ndarray:
    """Deviations of every case's seeds from their case's mean over their group's pooled sd, scaled
    to unit variance (√(N/(N−1)) undoes the deviations' ddof): the study's shape of scatter."""
    out = []
    for group in {p["group"] for p in pops}:
        mine = [p[side] for p in pops if p["group"] == group]
        sd = math.sqrt(np.mean([v.var(ddof=1) for v in mine]))
        out += [(v - v.mean()) / sd * math.sqrt(v.size / (v.size - 1)) for v in mine] if sd > 0 else []
    return np.concatenate(out)


def intervals(pop: dict, quantity: str, ns: np.ndarray, trials: int, rng, how: str, pools: dict):
    """(value, lo, hi) arrays (trials, len(ns)) of `quantity` after n seeds, and the truth."""
    a = draws(pop["a"], (trials, int(ns.max())), rng, how, pools["a"])
    ma, sa = running(a, ns)
    if quantity == "tan_delta":
        half = stats.t.ppf(0.975, ns - 1) * sa / np.sqrt(ns)
        return ma, ma - half, ma + half, pop["a"].mean()
    nb = np.maximum(ns, 10)
    b = draws(pop["b"], (trials, int(nb.max())), rng, how, pools["b"])
    mb, sb = running(b, nb)
    lo, hi = ratio_interval(ma, sa, ns, mb, sb, nb)
    return ma / mb, lo, hi, pop["a"].mean() / pop["b"].mean()


def coverage(pops, quantity, start, cap, step, target, trials, rng, how, pools, extra=0) -> dict:
    """Coverage, mean seeds, share reaching the target, and the fixed-n coverages beside them."""
    ns = np.arange(start, cap + 1, step)
    ns = np.unique(np.append(ns, cap))
    hit, seeds, reached, fixed_start, fixed_cap = [], [], [], [], []
    for pop in pops:
        v, lo, hi, truth = intervals(pop, quantity, ns, trials, rng, how, pools)
        cover = (lo <= truth) & (truth <= hi)
        stop = apply_rule(lo, hi, ns, target, extra)
        rows = np.arange(trials)
        hit.append(cover[rows, stop].mean())
        seeds.append(ns[stop].mean())
        reached.append(((hi - lo)[rows, stop] / 2 <= target).mean())
        fixed_start.append(cover[:, 0].mean())
        fixed_cap.append(cover[:, -1].mean())
    return dict(coverage=float(np.mean(hit)), worst_case=float(np.min(hit)), mean_seeds=float(np.mean(seeds)),
                reached=float(np.mean(reached)), fixed_start=float(np.mean(fixed_start)),
                fixed_cap=float(np.mean(fixed_cap)))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, default=4000)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    pops = populations(pd.read_csv(REPRO / "summaries.csv"), CommittedCurves(REPRO / "curves.parquet"))
    pools = {k: pooled_shape(pops, k) for k in ("a", "b")}
    print(f"{len(pops)} physical cases; {args.trials} trials each; {time.perf_counter() - t0:.1f} s to read")
    print(f"{'draw':<9} {'quantity':<10} {'rule':<33} {'target':>6} {'coverage':>9} {'worst':>6} {'seeds':>6} "
          f"{'reached':>8} {'fixed n=start':>14} {'fixed n=max':>12}")
    settings = [("E", 3, 12, 1, 0.05), ("E", 3, 12, 1, 0.1), ("tan_delta", 3, 12, 1, 0.02),
                ("tan_delta", 3, 12, 1, 0.05)]
    for how in ("normal", "pooled", "per-case"):
        for q, start, cap, step, target in settings:
            for extra in (0, 1):
                rng = np.random.default_rng(args.seed)
                r = coverage(pops, q, start, cap, step, target, args.trials, rng, how, pools, extra)
                rule = f"start {start}, max {cap}, step {step}" + (", two in a row" if extra else "")
                print(f"{how:<9} {q:<10} {rule:<33} {target:>6g} {r['coverage']:>9.3f} {r['worst_case']:>6.3f} "
                      f"{r['mean_seeds']:>6.2f} {r['reached']:>8.3f} {r['fixed_start']:>14.3f} {r['fixed_cap']:>12.3f}",
                      flush=True)
    print(f"{time.perf_counter() - t0:.0f} s in all")


if __name__ == "__main__":
    main()
