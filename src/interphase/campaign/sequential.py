"""Sequential seeds ([seeds] in a campaign file): run each physical case on as many packing seeds as
its interval needs, between `start` and `max`.

The rule (a fixed-width sequential rule; its coverage is checked by resampling the study's runs in
studies/sequential_seeds/sequential_coverage.py, docs/methods.md "Sequential seeds"):
  - every physical case (a group's runs of one physical_id, interphase.case.physical_id: the case
    without its seed; per engine) runs seeds 1..start;
  - a round ends when every run it asked for has finished; then each physical case whose seeds
    1..k have all finished (and their paired box tests, for E) is judged: its 95 % interval of the
    target quantity, computed by the report's seed-ensemble code (analysis.ensemble_table.ensemble_tables
    on exactly the runs of that round), has half-width h = (hi − lo)/2 [-]. A case within the
    target (h ≤ target) runs one more round (`confirming`: seeds k+1..k+step); it stops (`reached`)
    when that round reads within the target too, and goes on adding seeds when it reads wide. A
    case wider than the target gets seeds k+1..k+step (at most max); at k = max it stops (`capped`,
    or `reached` if h ≤ target). So a case that stops before the cap reports an interval within
    the target, judged on two rounds in a row.
    An undefined interval (one seed, no box test) counts as too wide.
  - box tests (the soil's own test, for E): as [pairs] makes them today, one per seed that runs, so
    a soil runs as many seeds as its most-sampled interface case, plus its [pairs] seeds. Their
    scatter is in E's interval (ratio_interval), so a case whose E is wide because of its soil gets
    seeds, and those seeds bring the soil's test with them.
Resumable: `replay` recomputes every round from the finished runs (the rule is a function of them),
so a rerun continues where the last stopped and never reruns a finished run. A round's decision uses
only runs that round had asked for: the estimate a case stops on is the one its rule saw.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from interphase.analysis.ensemble import physical_case, physical_ids
from interphase.campaign.results import with_physical_ids

#: rounds a case runs once its interval is within the target, which must read within too before it
#: stops: stopping on one reading covered 92.4 % (nominal 95 %) at tan δ ± 0.02 in
#: studies/sequential_seeds/sequential_coverage.py, two in a row 93.3 % or more in every setting checked (docs/methods.md)
CONFIRM = 1

#: a physical case's key: (engine, group, physical_id)
Key = tuple[str, str, str]


@dataclass(frozen=True)
class CaseRound:
    """Where a physical case stands: seeds asked for (1..wanted), seeds finished, and its interval at
    the last round judged (`n` seeds; value, lo, hi and halfwidth in the quantity's units [-])."""

    engine: str
    group: str
    physical_id: str
    wanted: int
    finished: int
    n: int = 0
    value: float = math.nan
    lo: float = math.nan
    hi: float = math.nan
    halfwidth: float = math.nan
    state: str = "waiting"          # waiting (its first round runs) | adding | confirming | reached | capped
    case: str = ""                  # its name: the label without the seed (rounds_of)

    def to_dict(self) -> dict:
        return asdict(self)


def _halfwidth(lo: float, hi: float) -> float:
    return (hi - lo) / 2 if math.isfinite(lo) and math.isfinite(hi) else math.nan


def replay(rule, done: dict[Key, set[int]], evaluate) -> dict[Key, CaseRound]:
    """The rounds of `rule` (schema.SeedRule) replayed over the finished runs.

    `done`: {key: the seeds whose run (and paired box test) finished}; `evaluate({key: k})` gives
    {key: (value, lo, hi)} with each case on its seeds 1..k. Rounds advance together; a case is judged
    once its seeds 1..k are all done (a case waiting on a run stops only itself)."""
    k = {key: rule.start for key in done}
    judged: dict[Key, tuple] = {}
    settled: dict[Key, str] = {}
    confirming: set[Key] = set()
    for _ in range(rule.max + 2):           # k grows by ≥ 1 per round: at most max + 1 rounds
        ready = [key for key in k if key not in settled and all(s in done[key] for s in range(1, k[key] + 1))]
        if not ready:
            break
        est = evaluate(dict(k))
        for key in ready:
            value, lo, hi = est.get(key, (math.nan, math.nan, math.nan))
            h = _halfwidth(lo, hi)
            judged[key] = (k[key], value, lo, hi, h)
            if h <= rule.halfwidth and (key in confirming or k[key] >= rule.max):
                settled[key] = "reached"
            elif h <= rule.halfwidth:       # within: one more round (CONFIRM) must read within too
                confirming.add(key)
                k[key] = min(k[key] + rule.step * CONFIRM, rule.max)
            elif k[key] >= rule.max:
                settled[key] = "capped"
            else:                           # wide (a confirming round that reads wide goes on adding)
                confirming.discard(key)
                k[key] = min(k[key] + rule.step, rule.max)
    out = {}
    for key in k:
        n, value, lo, hi, h = judged.get(key, (0, math.nan, math.nan, math.nan, math.nan))
        ran = sum(1 for s in done[key] if s <= rule.max)
        state = settled.get(key) or ("confirming" if key in confirming else "adding" if n and k[key] > n
                                     else "waiting")
        out[key] = CaseRound(*key, wanted=k[key], finished=ran, n=n, value=value, lo=lo, hi=hi, halfwidth=h,
                             state=state)
    return out


def interface_key(p) -> Key:
    """The physical case of a planned interface run (PlannedCase)."""
    return p.engine, p.group, p.physical_id


def _done_seeds(planned, finished: set[str], quantity: str) -> dict[Key, set[int]]:
    """{key: seeds finished}; for E a seed counts once its paired box test has finished too."""
    done: dict[Key, set[int]] = {}
    for p in planned:
        if p.role != "interface":
            continue
        ok = p.case_id in finished and (not quantity.startswith("E") or p.pair_id is None or p.pair_id in finished)
        done.setdefault(interface_key(p), set()).update([p.case.seed] if ok else [])
    return done


def wanted_ids(rule, planned, rounds: dict[Key, CaseRound]) -> set[str]:
    """Case ids the rounds ask for: interface seeds 1..wanted, their paired box tests, the soils'
    [pairs] seeds, and a group's own box cases on seeds 1..start."""
    out = set()
    for p in planned:
        if p.role == "interface" and p.case.seed <= rounds[interface_key(p)].wanted:
            out.add(p.case_id)
            if p.pair_id:
                out.add(p.pair_id)
        elif p.role == "box" and (p.case.seed in rule.pair_seeds or (p.group != "box" and p.case.seed <= rule.start)):
            out.add(p.case_id)
    return out


class _CachedCurves:
    """A store's curves read once (CampaignStore.curve), for the rounds' repeated ensembles."""

    def __init__(self, store):
        self.store, self.cache = store, {}

    def curve(self, case_id):
        if case_id not in self.cache:
            self.cache[case_id] = self.store.curve(case_id)
        return self.cache[case_id]


def _evaluator(rule, summaries: pd.DataFrame, store):
    """evaluate({key: k}) for `replay`: the report's ensembles table (analysis.ensemble_table) on the
    interface runs of seeds 1..k of each case, the box tests paired with them and the [pairs] seeds."""
    from interphase.analysis.ensemble_table import ensemble_tables

    curves = _CachedCurves(store)
    s = summaries.assign(_key=[(str(e), str(g), str(pid)) for e, g, pid in
                               zip(summaries["engine"], summaries["group"], physical_ids(summaries))])
    seed = pd.to_numeric(s["seed"], errors="coerce")
    iface = s["test"].astype(str).eq("interface")

    def evaluate(k: dict) -> dict:
        keep_i = iface & np.array([kk in k and sd <= k[kk] for kk, sd in zip(s["_key"], seed)], bool)
        pairs = set(s.loc[keep_i, "pair_id"].dropna().astype(str))
        keep_b = ~iface & (s["case_id"].astype(str).isin(pairs) | seed.isin(rule.pair_seeds)
                           | (~s["group"].astype(str).eq("box") & (seed <= rule.start)))
        out = {}
        for engine, sub in s[keep_i | keep_b].groupby("engine", sort=False):
            table = ensemble_tables(sub.drop(columns="_key"), curves)[0]
            q = rule.quantity
            for r in table.itertuples(index=False):
                out[(str(engine), str(r.group), str(r.physical_id))] = (getattr(r, q), getattr(r, f"{q}_lo"),
                                                                 getattr(r, f"{q}_hi"))
        return out

    return evaluate


def rounds_of(campaign, planned, store) -> dict[Key, CaseRound]:
    """The rounds of `campaign.seeds` over the finished runs of `store` (a CampaignStore, or None
    before anything ran). `planned`: plan(campaign), every seed up to max."""
    rule = campaign.seeds
    ids = {p.case_id for p in planned}
    summ = store.summaries() if store is not None else pd.DataFrame()
    summ = summ[summ["case_id"].astype(str).isin(ids)] if not summ.empty else summ
    finished = set(summ["case_id"].astype(str)) if not summ.empty else set()
    done = _done_seeds(planned, finished, rule.quantity)
    if summ.empty:
        rounds = replay(rule, done, lambda k: {})
    else:
        rounds = replay(rule, done, _evaluator(rule, with_physical_ids(summ.copy(), planned), store))
    names = {interface_key(p): physical_case(p.label) for p in planned if p.role == "interface"}
    return {key: dataclasses.replace(r, case=names.get(key, "")) for key, r in rounds.items()}


def this_round(campaign, planned, store) -> tuple[list, dict[Key, CaseRound]]:
    """(the planned runs the rounds ask for now, in plan order; the rounds)."""
    rounds = rounds_of(campaign, planned, store)
    want = wanted_ids(campaign.seeds, planned, rounds)
    return [p for p in planned if p.case_id in want], rounds


def rounds_frame(rule, rounds: dict[Key, CaseRound]) -> pd.DataFrame:
    """One row per physical case: seeds asked for and finished, the interval reached, the state."""
    cols = ["engine", "group", "case", "physical_id", "wanted", "finished", "n", "value", "lo", "hi", "halfwidth",
            "state"]
    df = pd.DataFrame([r.to_dict() for r in rounds.values()], columns=cols)
    return df.assign(quantity=rule.quantity, target=rule.halfwidth, cap=rule.max)


def cap_notes(table: pd.DataFrame, rule) -> pd.Series:
    """For the report's ensembles table: 'hit the seed cap …' on the cases that ran `max` seeds and
    whose interval of the target quantity is still wider than the target, else ''."""
    q = rule.quantity
    h = (pd.to_numeric(table[f"{q}_hi"], errors="coerce") - pd.to_numeric(table[f"{q}_lo"], errors="coerce")) / 2
    capped = (pd.to_numeric(table["seeds"], errors="coerce") >= rule.max) & ~(h <= rule.halfwidth)
    return pd.Series([f"hit the seed cap ({rule.max}) at ± {x:.3g} in {q} (target ± {rule.halfwidth:g})"
                      if c else "" for c, x in zip(capped, h)], index=table.index)
