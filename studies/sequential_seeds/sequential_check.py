"""The bill checked by a run (issue 30): a campaign run by the sequential-seeds rule against the
projection studies/sequential_seeds/sequential_bill.py makes for the same cases from the study's 3 seeds.

Reads the campaign's finished runs (its runs folder; on a fresh machine first
`campaign run FILE --restore docs/reproduction/precision/summaries.csv`, or give --summaries and
--curves to read the committed tables without a runs folder) and prints, per physical case, the
seeds it ran, E with its 95 % interval now and at the study's 3 seeds (docs/reproduction/
ensembles.csv), and whether the 3-seed interval holds the new mean; then the totals beside the
projection: share of cases within the target, mean and largest seed count, core-hours (Σ elapsed
of every run the campaign used, restored ones included).

    PYTHONPATH=src python studies/sequential_seeds/sequential_check.py [studies/sequential_seeds/group1_sequential.toml]
        [--group group1] [--summaries S.csv --curves C.parquet] [--out ensembles.csv]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

import interphase as ip
from interphase.analysis.ensemble_table import ensemble_table
from interphase.analysis.seed_draws import populations, project, run_times
from interphase.campaign.results import CommittedCurves

REPRO = Path(__file__).resolve().parents[2] / "docs" / "reproduction"


def tables(args) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(summaries, ensembles) of the campaign's finished runs."""
    if args.summaries:
        s = pd.read_csv(args.summaries)
        return s, ensemble_table(s, CommittedCurves(args.curves))
    return ip.summaries(args.campaign), ip.ensembles(args.campaign)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("campaign", nargs="?", default="studies/sequential_seeds/group1_sequential.toml")
    ap.add_argument("--group", default="group1", help="the study's group the campaign re-runs")
    ap.add_argument("--summaries", type=Path, help="a committed summaries table instead of the runs folder")
    ap.add_argument("--curves", type=Path, help="its curves table (with --summaries)")
    ap.add_argument("--out", type=Path, help="write the campaign's ensembles table here (CSV)")
    ap.add_argument("--trials", type=int, default=4000)
    args = ap.parse_args(argv)
    rule = ip.load_campaign(args.campaign).seeds
    summ, ens = tables(args)
    ens = ens[ens["group"] == args.group].copy()
    if args.out:
        ens.to_csv(args.out, index=False, float_format="%.5g")
    q, target = rule.quantity, rule.halfwidth
    before = pd.read_csv(REPRO / "ensembles.csv").set_index("case")
    ens["half"] = (ens[f"{q}_hi"] - ens[f"{q}_lo"]) / 2
    ens["half3"] = ens["case"].map((before[f"{q}_hi"] - before[f"{q}_lo"]) / 2)
    ens["held"] = [before.at[c, f"{q}_lo"] <= v <= before.at[c, f"{q}_hi"] for c, v in zip(ens["case"], ens[q])]
    print(f"{'physical case':<44} {'seeds':>5} {q + ' now (95 %)':>22} {'at 3 seeds':>22} {'held':>5}")
    for _, r in ens.iterrows():
        b = before.loc[r["case"]]
        print(f"{r['case'][-44:]:<44} {int(r['seeds']):>5} {r[q]:>8.3f} ({r[q + '_lo']:.3f}–{r[q + '_hi']:.3f})"
              f" {b[q]:>8.3f} ({b[q + '_lo']:.3f}–{b[q + '_hi']:.3f}) {'yes' if r['held'] else 'NO':>5}")
    boxes = int(ens["box_seeds"].max())
    used = summ[(summ["group"] == args.group) | (summ["test"] == "box")]
    hours = used["elapsed"].sum() / 3600
    study = pd.read_csv(REPRO / "summaries.csv")
    pops = [p for p in populations(study, CommittedCurves(REPRO / "curves.parquet")) if p["group"] == args.group]
    times, box_time, today, _ = run_times(study, args.group)
    proj = project(pops, times, q, target, rule.max, boxes, args.trials, np.random.default_rng(1))
    proj_h = proj["hours"] + boxes * box_time / 3600
    print(f"\n{len(ens)} physical cases, target ± {target:g} in {q}, cap {rule.max}, {boxes} soil seeds; "
          f"{len(used)} runs")
    print(f"{'':<26} {'run':>10} {'projected':>10}")
    print(f"{'cases within the target':<26} {np.mean(ens['half'] <= target + 1e-12):>10.0%} {proj['reached']:>10.0%}")
    print(f"{'mean interface seeds':<26} {ens['seeds'].mean():>10.1f} {proj['seeds']:>10.1f}")
    print(f"{'largest seed count':<26} {int(ens['seeds'].max()):>10d} {'':>10}")
    print(f"{'core-hours':<26} {hours:>10.1f} {proj_h:>10.1f}   (the study's 3 seeds: {today:.1f})")
    old = set(pd.read_csv(REPRO / "summaries.csv")["case_id"])
    new = used[~used["case_id"].isin(old)]
    for test in ("interface", "box"):
        n, o = new[new["test"] == test]["elapsed"], used[used["case_id"].isin(old) & (used["test"] == test)]["elapsed"]
        print(f"  {test}: {len(o)} restored runs (mean {o.mean():.0f} s as measured then), {len(n)} new "
              f"(mean {n.mean():.0f} s on this machine, {n.sum() / 3600:.2f} core-h)")
    print(f"3-seed intervals holding the new mean: {int(ens['held'].sum())}/{len(ens)}; half-width median "
          f"{ens['half3'].median():.3f} → {ens['half'].median():.3f}")


if __name__ == "__main__":
    main()
