"""A committed study's seed scatter resampled under the sequential-seeds rule ([seeds],
campaign.sequential): what the rule covers and what a stated precision would cost
(studies/sequential_seeds/, studies/scatter_size/).

Conventions: a population is one physical case's seeds' peak states (analysis.ensemble.seed_states,
as the report's ensembles table computes them): `a` the interface seeds' tan δ, `b` its soil's box
seeds' tan φ [-]; E = mean a / mean b. A trial's seeds are drawn one by one; after n seeds the 95 %
interval is Student's t for tan δ and analysis.ensemble.ratio_interval for E. The rule stops at the
first n (from `start`, every `step`) whose half-width is within the target on `extra` + 1 rounds in a
row (campaign run: extra = CONFIRM = 1), else at the cap. Run times in seconds, bills in core-hours.
Physical cases are told apart by the label without its "-sN" seed suffix.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy import stats

from interphase.analysis.ensemble import ratio_interval
from interphase.analysis.ensemble_table import ensemble_tables

_SEED_SUFFIX = r"-s\d+$"


def populations(summaries: pd.DataFrame, curves) -> list[dict]:
    """Per physical case of a committed study (its summaries table and a store-like `curves` with
    `.curve(case_id)`): dict(group, case, a, b), a and b with at least 2 seeds each."""
    table, states, pools = ensemble_tables(summaries, curves)
    iface = summaries[summaries["test"] == "interface"].assign(
        _case=lambda d: d["label"].str.replace(_SEED_SUFFIX, "", regex=True))
    out = []
    for (group, case), g in iface.groupby(["group", "_case"]):
        boxes = sorted({b for p in g["pair_id"].dropna() for b in pools.get(p, ())})
        a = np.array([states[c] for c in g["case_id"] if c in states])
        b = np.array([states[c] for c in boxes if c in states])
        if a.size >= 2 and b.size >= 2:
            out.append(dict(group=group, case=case, a=a, b=b))
    return out


def draws(v: np.ndarray, shape, rng, how: str, pool: np.ndarray | None) -> np.ndarray:
    """`shape` seed values of a population `v`: "normal" Normal(mean, sd); "pooled" mean + sd × z, z
    drawn from `pool` (unit-variance deviations); otherwise `v`'s own values with replacement, moved
    away from their mean by √(N/(N−1)) so that the draws have the seeds' variance."""
    m, s = v.mean(), v.std(ddof=1)
    if how == "normal":
        return rng.normal(m, s, size=shape)
    if how == "pooled":
        return m + s * rng.choice(pool, size=shape)
    adj = m + (v - m) * math.sqrt(v.size / (v.size - 1))
    return rng.choice(adj, size=shape)


def running(x: np.ndarray, ns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Means and sds (ddof 1) of the first n columns of x, for each n in ns: (trials, len(ns))."""
    c1, c2 = np.cumsum(x, axis=1)[:, ns - 1], np.cumsum(x * x, axis=1)[:, ns - 1]
    mean = c1 / ns
    var = np.maximum(c2 - ns * mean * mean, 0) / (ns - 1)
    return mean, np.sqrt(var)


def apply_rule(lo, hi, ns, target: float, extra: int = 0) -> np.ndarray:
    """Column index (into ns) where the rule stops each trial: the first n whose half-width is within
    the target on `extra` + 1 rounds in a row, else the last (the cap)."""
    ok = (hi - lo) / 2 <= target
    run = ok.copy()
    for i in range(1, extra + 1):
        run[:, i:] &= ok[:, :-i]
        run[:, :i] = False
    return np.where(run.any(axis=1), run.argmax(axis=1), ns.size - 1)


def run_times(summaries: pd.DataFrame, group: str | None = None) -> tuple[dict[str, float], float, float, int]:
    """(mean run time [s] per physical case, mean box run time [s], the table's core-hours, runs), of
    one group and its soil's box tests when `group` is given."""
    s = summaries
    if group:
        mine = s[s["group"] == group]
        s = pd.concat([mine, s[(s["test"] == "box") & s["gradation"].isin(mine["gradation"])]])
    s = s.assign(_case=s["label"].str.replace(_SEED_SUFFIX, "", regex=True))
    iface = s[s["test"] == "interface"]
    return (iface.groupby("_case")["elapsed"].mean().to_dict(), float(s.loc[s["test"] == "box", "elapsed"].mean()),
            float(s["elapsed"].sum()) / 3600, len(s))


def project(pops, times, quantity: str, target: float, cap: int, m: int, trials: int, rng) -> dict:
    """The rule (start 3, step 1, two rounds in a row, `cap`) on Normal draws of each population, the
    soil on m box seeds: share of cases reaching the target, mean seeds, interface core-hours (run
    times `times` [s] per case)."""
    ns = np.arange(3, cap + 1)
    reached, seeds, hours = [], [], 0.0
    for pop in pops:
        a = draws(pop["a"], (trials, cap), rng, "normal", None)
        ma, sa = running(a, ns)
        if quantity == "tan_delta":
            half = stats.t.ppf(0.975, ns - 1) * sa / np.sqrt(ns)
            lo, hi = ma - half, ma + half
        else:
            b = draws(pop["b"], (trials, m), rng, "normal", None)
            mb, sb = b.mean(axis=1, keepdims=True), b.std(axis=1, ddof=1, keepdims=True)
            lo, hi = ratio_interval(ma, sa, ns, mb, sb, m)
        stop = apply_rule(lo, hi, ns, target, extra=1)
        rows = np.arange(trials)
        reached.append(((hi - lo)[rows, stop] / 2 <= target).mean())
        seeds.append(ns[stop].mean())
        hours += ns[stop].mean() * times[pop["case"]] / 3600
    return dict(reached=float(np.mean(reached)), seeds=float(np.mean(seeds)), hours=hours)
