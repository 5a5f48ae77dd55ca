"""The seed-ensemble table (the report's `ensembles`, the sequential seeds' stopping rule, the
validation's DEM δ): each physical case's tan δ, its paired box tests' tan φ and E,
at the peak and at the critical state, each with its 95 % interval (analysis.ensemble).

Intervals respect their quantity (analysis.ensemble.seed_interval): tan δ and tan φ on the log scale
(never below 0), E by `ratio_interval` (log scale too), θr (ψ, degrees from vertical) a t interval
clipped to [−90°, 90°]; a side with fewer than MIN_SEEDS (3) seeds has no interval, and the note
column says so.

A physical case is a campaign group's runs of one `physical_id` (interphase.case.physical_id: the
case without its seed), named by its label without the seed (`…-s3`); its box tests are every box
test of the soil its seeds are paired with (`box_pools`, by the box tests' physical_id): the pair_id
rows, and the soil tests that `[pairs] seeds` ran on further seeds. Curves come from each finished case's series.parquet (shear_disp,
stress_ratio: the window ratio of an interface test, the shear plane's of a box test).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd

from interphase.analysis.ensemble import (MIN_SEEDS, efficiency_of_states, ensemble_efficiency, ensemble_states,
                                          ensemble_strength, physical_case, physical_ids, strength_of_states,
                                          usable, values_interval)
from interphase.analysis.strength import PEAK_WINDOW_D50

COLUMNS = ("group", "case", "physical_id", "seeds", "box_seeds", "tan_delta", "tan_delta_lo", "tan_delta_hi",
           "tan_delta_cs", "tan_delta_cs_lo", "tan_delta_cs_hi", "tan_phi", "tan_phi_lo", "tan_phi_hi", "tan_phi_cs", "tan_phi_cs_lo",
           "tan_phi_cs_hi", "E", "E_lo", "E_hi", "E_cs", "E_cs_lo", "E_cs_hi", "theta_r_deg", "theta_r_lo",
           "theta_r_hi", "theta_a_deg_92", "note")


__all__ = ["COLUMNS", "box_pools", "ensemble_table", "ensemble_tables", "physical_case"]

#: Case inputs that do not make a soil test another soil: its seed and the surface's fields
_NOT_SOIL = frozenset({"seed", "name", "profile", "test", "friction_ps"})


def box_pools(summaries: pd.DataFrame) -> dict[str, tuple[str, ...]]:
    """{box case_id: every finished box test of the same physical case and engine}: the seeds of one
    soil test (its `physical_id`). A row without one (a table written before it) is pooled by the
    Case inputs the summaries carry but the seed (and the surface's fields, empty for a box)."""
    test = summaries.get("test", pd.Series("", index=summaries.index)).astype(str)
    box = summaries[test.eq("box")]
    if box.empty:
        return {}
    engine = box["engine"].astype(str) if "engine" in box else pd.Series("", index=box.index)
    key = _soil_key(box) + "@" + engine
    ids = box["case_id"].astype(str)
    pools = ids.groupby(key.to_numpy()).agg(lambda v: tuple(sorted(v)))
    return {cid: pools[k] for cid, k in zip(ids, key)}


def _soil_key(box: pd.DataFrame) -> pd.Series:
    """Each box test's physical_id, or for a row without one its Case columns but the seed."""
    from interphase.case import Case

    cols = [c for c in Case.__dataclass_fields__ if c in box and c not in _NOT_SOIL]
    by_cols = (box[cols].astype(str).apply(lambda r: "cols:" + "|".join(map(str, r)), axis=1) if cols
               else pd.Series("cols:", index=box.index))
    if "physical_id" not in box:
        return by_cols
    have = box["physical_id"]
    return have.where(have.notna() & have.astype(str).ne(""), by_cols).astype(str)


def _mean_interval(values, quantity: str) -> tuple[float, float, float]:
    """Mean of the finite values and its interval (analysis.ensemble.values_interval)."""
    v = np.asarray([x for x in values if x is not None and math.isfinite(x)], float)
    if v.size == 0:
        return math.nan, math.nan, math.nan
    return (float(v.mean()), *values_interval(v, quantity))


def _why_high(e, rows: pd.DataFrame, e_note: float) -> str:
    """Why an interface reads stronger than its soil's own test, from what was measured."""
    walled = str(rows["device"].iloc[0]) not in ("periodic", "periodic3d") if "device" in rows else True
    if walled:
        return (f"E > {e_note:g}: the walled interface box's side walls confine the soil above a rough surface "
                "beyond the box test's state (docs/strength.md)")
    if math.isfinite(e.peak_lo) and e.peak_lo < e_note:
        return (f"E > {e_note:g} within seed scatter: its interval ({e.peak_lo:.2f}–{e.peak_hi:.2f}) reaches "
                f"below {e_note:g}; run more seeds (docs/strength.md)")
    return (f"E > {e_note:g} beyond its interval in the periodic device: not seen in the convergence runs "
            "(docs/convergence.md); check the case")


def _seed_states(ids, curve, window: float, memo: dict):
    """(the ids of `ids` with a usable curve, their `ensemble_states`, or None without one), computed
    once per (ids, window)."""
    key = (tuple(ids), window)
    if key not in memo:
        use = [(c, cv) for c, cv in ((c, curve(c)) for c in ids) if usable(cv)]
        memo[key] = ([c for c, _ in use], ensemble_states([cv for _, cv in use], window) if use else None)
    return memo[key]


def ensemble_table(summaries: pd.DataFrame, store, *, e_note: float = 1.2) -> pd.DataFrame:
    """One row per physical interface case (see the module doc); `note` says why a value is
    missing, and flags E above `e_note` (an interface stronger than its soil's box test)."""
    return ensemble_tables(summaries, store, e_note=e_note)[0]


def ensemble_tables(summaries: pd.DataFrame, store, *, e_note: float = 1.2) -> tuple[pd.DataFrame, dict, dict]:
    """(the ensembles table, {case_id: the run's peak state}, box_pools(summaries)) — the second for
    every interface run and box test with a curve: the value its ensemble's peak averages
    (analysis.ensemble.seed_peak_states reads the same values), which the correlations' seed bootstrap resamples
    (analysis.correlations.seed_ensemble, given the pools)."""
    if summaries is None or summaries.empty or store is None:
        return pd.DataFrame(columns=COLUMNS), {}, {}
    pools = box_pools(summaries)
    rows = summaries.assign(_case=summaries["label"].map(physical_case), _pid=physical_ids(summaries))
    iface = rows[rows.get("test", pd.Series("", index=rows.index)).eq("interface")]
    cache: dict = {}
    curve = lambda cid: cache[cid] if cid in cache else cache.setdefault(cid, store.curve(cid))
    memo: dict = {}                    # a soil test's seeds are read once, whatever shares them
    out, states = [], {}
    for (group, name, pid), g in iface.groupby(["group", "_case", "_pid"], sort=True):    # by name, then id
        d50 = float(pd.to_numeric(g["d50"], errors="coerce").median()) if "d50" in g else 0.7e-3
        window = PEAK_WINDOW_D50 * d50
        ids = [str(c) for c in g["case_id"]]
        paired = {str(p) for p in g.get("pair_id", pd.Series(dtype=object)).dropna().unique()}
        box_ids = sorted({b for p in paired for b in pools.get(p, ())})
        (ids_a, st_a), (ids_b, st_b) = (_seed_states(x, curve, window, memo) for x in (ids, box_ids))
        for got, st in ((ids_a, st_a), (ids_b, st_b)):
            states.update({c: float(v) for c, v in zip(got, st[0] if st else ()) if math.isfinite(v)})
        sa = strength_of_states(*st_a, quantity="tan_delta") if st_a else ensemble_strength([], window)
        sb = strength_of_states(*st_b, quantity="tan_phi") if st_b else ensemble_strength([], window)
        e = efficiency_of_states(st_a[0], st_a[2], st_b[0], st_b[2]) if st_a and st_b else ensemble_efficiency([], [], window)
        if len(ids_a) < MIN_SEEDS or len(ids_b) < MIN_SEEDS:      # E's interval needs as many seeds as its sides'
            e = dataclasses.replace(e, peak_lo=math.nan, peak_hi=math.nan, critical_lo=math.nan,
                                    critical_hi=math.nan)
        th = _mean_interval(pd.to_numeric(g.get("theta_r_surface_deg"), errors="coerce"), "theta_r_surface_deg")
        notes = []
        if not ids_b:
            notes.append("no finished box test: E undefined")
        if len(ids_a) < MIN_SEEDS or len(ids_b) < MIN_SEEDS:
            notes.append(f"fewer than {MIN_SEEDS} seeds ({len(ids_a)} interface, {len(ids_b)} box): no interval")
        if math.isfinite(e.peak) and e.peak > e_note:
            notes.append(_why_high(e, g, e_note))
        out.append(dict(group=group, case=name, physical_id=pid, seeds=sa.n_seeds, box_seeds=sb.n_seeds,
                        tan_delta=sa.peak, tan_delta_lo=sa.peak_lo, tan_delta_hi=sa.peak_hi,
                        tan_delta_cs=sa.critical, tan_delta_cs_lo=sa.critical_lo, tan_delta_cs_hi=sa.critical_hi,
                        tan_phi=sb.peak, tan_phi_lo=sb.peak_lo, tan_phi_hi=sb.peak_hi, tan_phi_cs=sb.critical,
                        tan_phi_cs_lo=sb.critical_lo, tan_phi_cs_hi=sb.critical_hi,
                        E=e.peak, E_lo=e.peak_lo, E_hi=e.peak_hi, E_cs=e.critical, E_cs_lo=e.critical_lo,
                        E_cs_hi=e.critical_hi, theta_r_deg=th[0], theta_r_lo=th[1], theta_r_hi=th[2],
                        theta_a_deg_92=float(pd.to_numeric(g.get("theta_a_deg_92"), errors="coerce").median()),
                        note="; ".join(notes)))
    return pd.DataFrame(out, columns=COLUMNS), states, pools


BOX_COLUMNS = ["physical_id", "case", "normal_stress", "preparation", "seeds", "tan_phi", "tan_phi_lo", "tan_phi_hi",
               "tan_phi_cs", "tan_phi_cs_lo", "tan_phi_cs_hi"]


def box_ensembles(summaries: pd.DataFrame, store) -> pd.DataFrame:
    """One row per physical box test (its seeds pooled, as an interface case's tan φ is: the bagged
    ensemble peak and the critical state with their 95 % intervals), with its normal stress [Pa] and
    preparation: a soil's strength over the states a campaign tested (interphase.card_state)."""
    if summaries is None or summaries.empty or store is None or "test" not in summaries:
        return pd.DataFrame(columns=BOX_COLUMNS)
    rows = summaries.assign(_case=summaries["label"].map(physical_case), _pid=physical_ids(summaries))
    box = rows[rows["test"].eq("box")]
    out, memo = [], {}
    for (name, pid), g in box.groupby(["_case", "_pid"], sort=True):
        d50 = float(pd.to_numeric(g["d50"], errors="coerce").median()) if "d50" in g else 0.7e-3
        got, st = _seed_states([str(c) for c in g["case_id"]], store.curve, PEAK_WINDOW_D50 * d50, memo)
        s = strength_of_states(*st, quantity="tan_phi") if st else ensemble_strength([], PEAK_WINDOW_D50 * d50)
        num = lambda c: float(pd.to_numeric(g[c], errors="coerce").median()) if c in g else math.nan
        out.append(dict(physical_id=pid, case=name, normal_stress=num("normal_stress"), preparation=num("preparation"),
                        seeds=s.n_seeds, tan_phi=s.peak, tan_phi_lo=s.peak_lo, tan_phi_hi=s.peak_hi,
                        tan_phi_cs=s.critical, tan_phi_cs_lo=s.critical_lo, tan_phi_cs_hi=s.critical_hi))
    return pd.DataFrame(out, columns=BOX_COLUMNS)
