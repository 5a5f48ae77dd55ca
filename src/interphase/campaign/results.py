"""The campaign's result format: what a finished campaign IS, for every reader (the report, the
comparison, the restore, the API).

- `open_campaign(file)`: (Campaign, CampaignStore, summaries) — the summaries being `one_run_per_case`:
  the finished runs the file asks for, of one recipe per engine.
- the summaries table (`write_summaries`, columns RUN_COLUMNS first, BOOKKEEPING left out): one row per
  finished run, what a reproduction commits (`campaign run --restore` reads it back, campaign.restore);
- the curves table (`write_curves`): every finished run's stress-ratio curve resampled to CURVE_POINTS,
  what the seed ensembles need on another machine.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.errors import InputError


#: first in summaries.csv: a run's identity and physical case (physical_id: interphase.case.physical_id,
#: what its seeds share); then every other column of the index (Case parameters, the summary's own
#: columns by their names, elapsed [s]) but its bookkeeping
RUN_COLUMNS = ("case_id", "label", "physical_id", "group", "test", "device", "profile_label", "friction_ps",
               "gradation", "seed", "pair_id")
BOOKKEEPING = ("status", "cause", "started", "finished", "attempts", "host", "slurm_job", "updated", "role",
               "case", "reasons", "engine")


def write_summaries(summaries: pd.DataFrame, path: Path) -> Path:
    """Every finished run as one row of a small CSV (what a reproduction commits: no dumps): the
    columns above, the rest by their own names, and `efficiency_run` = E_run, this run's peak stress
    ratio over its paired box test's (same packing seed; NaN for box tests): one run's ratio, not the
    physical case's E (the seed ensembles' ratio, tables `ensembles` and `results`; docs/methods.md).
    Sorted by group and label, so a rerun diffs cleanly."""
    df = summaries.copy()
    peak = pd.to_numeric(df.get("peak_stress_ratio"), errors="coerce")
    by_id = pd.Series(peak.to_numpy(), index=df["case_id"].astype(str))
    box_peak = df["pair_id"].astype(str).map(by_id) if "pair_id" in df else pd.Series(math.nan, index=df.index)
    df["efficiency_run"] = peak / pd.to_numeric(box_peak, errors="coerce")
    first = [c for c in RUN_COLUMNS if c in df]
    rest = [c for c in df.columns if c not in first and c not in BOOKKEEPING]
    df = df[first + rest].sort_values(["group", "label"], kind="stable")
    df.to_csv(path, index=False, float_format="%.6g")
    return path


#: points per run in curves.parquet: 200 over a 6 mm shear is one per 0.03 mm, 12 per peak window
#: (PEAK_WINDOW_D50 × D50 at D50 0.7 mm); the ensembles' tan δ, tan φ and E from them stay within 2 %
#: of their interval's width of the full curves' (measured: tests/test_restore.py); on the Karlsruhe
#: sand's quasi-2D Group 1 (24 cases, 4-8 seeds, studies/kfs_group1_2d/results/) up to 0.003 in E and
#: 0.010 at an end of its interval (5 % of that interval's width)
CURVE_POINTS = 200


def write_curves(summaries: pd.DataFrame, store, path: Path, points: int = CURVE_POINTS) -> Path | None:
    """Every finished run's stress-ratio curve (series.parquet: shear_disp [m], stress_ratio [-]),
    resampled linearly to `points` evenly spaced displacements between its first and last sample,
    as one long Parquet table (case_id, shear_disp, stress_ratio; float32): with summaries.csv, what
    a campaign needs to rebuild its seed ensembles on another machine (`campaign run --restore`).
    None when no run has a curve."""
    frames = []
    for cid in summaries["case_id"].astype(str):
        got = store.curve(cid) if store is not None else None
        if got is None:
            continue
        x, r = (np.asarray(a, float) for a in got)
        ok = np.isfinite(x) & np.isfinite(r)
        if ok.sum() < 2:
            continue
        order = np.argsort(x[ok], kind="stable")
        x, r = x[ok][order], r[ok][order]
        grid = np.linspace(x[0], x[-1], points)
        frames.append(pd.DataFrame({"case_id": cid, "shear_disp": grid.astype(np.float32),
                                    "stress_ratio": np.interp(grid, x, r).astype(np.float32)}))
    if not frames:
        return None
    df = pd.concat(frames, ignore_index=True)
    df["case_id"] = df["case_id"].astype("category")
    df.to_parquet(path, index=False, compression="zstd")
    return path


class CommittedCurves:
    """A store-like reader of committed tables: `.curve(case_id)` from a curves.parquet that
    write_curves wrote, for the report's analysis (report.build.analyse) and the seed ensembles
    without a runs folder. It has no case folders: `case_folder` names one that does not exist, so
    what is read from a run's folder (provenance, series) is taken from the summaries or left out."""

    def __init__(self, path: str | Path):
        c = pd.read_parquet(path)
        self.by_id = {str(cid): (g["shear_disp"].to_numpy(float), g["stress_ratio"].to_numpy(float))
                      for cid, g in c.groupby("case_id", sort=False, observed=True)}

    def curve(self, case_id):
        return self.by_id.get(str(case_id))

    def case_folder(self, case_id) -> Path:
        return Path("/nonexistent-runs-folder") / str(case_id)


def read_committed(folder: str | Path) -> tuple[pd.DataFrame, CommittedCurves]:
    """(summaries, curves) of a committed runs folder: its summaries.csv (identities as text) and
    curves.parquet, what every reader of committed runs starts from without a runs folder."""
    folder = Path(folder)
    summaries = pd.read_csv(folder / "summaries.csv", dtype={"case_id": str, "physical_id": str, "pair_id": str})
    return summaries, CommittedCurves(folder / "curves.parquet")


#: a re-derived table matches its committed copy within these (the fourth-last digit of a float64,
#: where the BLAS and the platform may move a bootstrap's or an interval's last bits)
TABLE_RTOL, TABLE_ATOL = 1e-6, 1e-9


def same_table(table: pd.DataFrame, path: str | Path) -> bool:
    """Whether `table`, written as CSV, reads back as the committed CSV at `path`: the same columns
    and rows, text equal, numbers within TABLE_RTOL/TABLE_ATOL."""
    import io

    path = Path(path)
    if not path.exists():
        return False
    text = table.to_csv(index=False)
    if text == path.read_text():
        return True
    new, old = pd.read_csv(io.StringIO(text)), pd.read_csv(path)
    if list(new.columns) != list(old.columns) or new.shape != old.shape:
        return False
    for c in new.columns:
        a, b = new[c], old[c]
        if pd.api.types.is_numeric_dtype(a) and pd.api.types.is_numeric_dtype(b):
            if not np.allclose(a.to_numpy(float), b.to_numpy(float), rtol=TABLE_RTOL, atol=TABLE_ATOL, equal_nan=True):
                return False
        elif not (a.astype(str).where(a.notna(), "") == b.astype(str).where(b.notna(), "")).all():
            return False
    return True


def write_or_check(tables: dict, check: bool) -> list[Path]:
    """A study's re-derived tables ({path: DataFrame}) against their committed CSVs: with `check`,
    write nothing and return the paths whose table differs (`same_table`) or is missing; else write
    each one that differs (a match is left as committed, so that a re-derivation does not churn the
    last digits) and return those written."""
    out = []
    for path, table in tables.items():
        path = Path(path)
        if same_table(table, path):
            continue
        out.append(path)
        if not check:
            path.parent.mkdir(parents=True, exist_ok=True)
            table.to_csv(path, index=False)
    return out


def settle_tables(tables: dict, check: bool, root: str | Path) -> int:
    """A study script's last step: `write_or_check` its tables, say which differ (check) or were written
    (paths relative to `root`, the study's folder), and return the exit code (1: a committed table
    differs from its re-derivation)."""
    import sys

    changed = write_or_check(tables, check)
    names = [str(p.relative_to(root)) for p in changed]
    if check and changed:
        print(f"differs from the committed table: {', '.join(names)}", file=sys.stderr)
        return 1
    for n in ([] if check else names):
        print(f"wrote {n}")
    return 0


def open_campaign(campaign_path: str | Path, output: str | Path | None = None, engines=None):
    """(Campaign, CampaignStore, summaries) of a campaign file whose cases have run (`output`: its
    runs' folder when not where the file says, as `campaign run --output` wrote them; `engines`: the
    engines whose recipes are this version's, names or EngineSpecs, default the file's)."""
    from interphase.campaign.schema import load_campaign
    from interphase.campaign.store import CampaignStore

    campaign = load_campaign(campaign_path, output=output)
    root = Path(campaign.output)
    if not (root / "index.sqlite").exists() and not any(root.glob("*/DONE")):
        raise InputError(f"no results in {root}", where=str(campaign_path),
                         fix=f"run `campaign run {campaign_path}` first")
    store = CampaignStore(root)
    return campaign, store, one_run_per_case(store.summaries(), campaign, engines=engines)


def one_run_per_case(summaries: pd.DataFrame, campaign, **plan_options) -> pd.DataFrame:
    """The finished runs a campaign file asks for, of ONE recipe per engine: this version's recipe
    when any of its runs has finished, else the recipe with the most finished runs (an earlier one,
    read where it was run). Runs of other recipes and folders of labels the file no longer asks for
    are left out, and counted: attrs `recipes` {engine: recipe id used}, `current` {engine: whether
    it is this version's}, `other_recipe` and `not_asked` (runs left out). Mixing recipes would put
    two protocols on one figure and count a case run again under a new recipe twice. `plan_options`
    go to campaign.plan.plan (the engines, a test's recipe identity)."""
    from interphase.campaign.plan import plan

    attrs = dict(recipes={}, current={}, other_recipe=0, not_asked=0)
    if summaries.empty:
        summaries.attrs.update(attrs)
        return summaries
    planned = plan(campaign, **plan_options)
    current = {p.engine: p.recipe_id for p in planned}
    ids = {p.case_id for p in planned}
    wanted = {(p.label, p.engine) for p in planned}
    keys = list(zip(summaries["label"].astype(str), summaries["engine"].astype(str)))
    asked = summaries[[k in wanted for k in keys]].copy()
    attrs["not_asked"] = len(summaries) - len(asked)
    rid = asked["recipe_id"] if "recipe_id" in asked else pd.Series(None, index=asked.index, dtype=object)
    # a planned id is this recipe's whatever its folder recorded
    asked["_recipe"] = rid.where(~asked["case_id"].astype(str).isin(ids), asked["engine"].map(current)).fillna("unknown")
    keep = []
    for engine, runs in asked.groupby("engine", sort=False):
        now = current.get(engine)
        counts = runs.groupby("_recipe")["finished"].agg(["size", "max"])
        use = now if now in counts.index else counts.sort_values(["size", "max"]).index[-1]
        attrs["recipes"][engine], attrs["current"][engine] = use, use == now
        keep.append(runs[runs["_recipe"] == use])
    out = pd.concat(keep).sort_index() if keep else asked
    attrs["other_recipe"] = len(asked) - len(out)
    out = with_physical_ids(out.drop(columns="_recipe"), planned)
    # the group is the file's as it reads now: a file reorganised into groups keeps each case's
    # seeds together (the index keeps the group a run was planned under)
    group = {(p.label, p.engine): p.group for p in planned}
    out["group"] = [group.get(k, g) for k, g in zip(zip(out["label"].astype(str), out["engine"].astype(str)),
                                                     out["group"] if "group" in out else [None] * len(out))]
    out.attrs.update(attrs)
    return out


def with_physical_ids(summaries: pd.DataFrame, planned) -> pd.DataFrame:
    """The runs with their `physical_id` (PlannedCase.physical_id) where the index has none (runs
    indexed before the column existed): the planned case's of the same id, else of the same label
    and engine (a run of an earlier recipe: the inputs the label names are the plan's)."""
    by_id = {p.case_id: p.physical_id for p in planned}
    by_key = {(p.label, p.engine): p.physical_id for p in planned}
    have = (summaries["physical_id"] if "physical_id" in summaries
            else pd.Series(None, index=summaries.index, dtype=object))
    engine = summaries["engine"].astype(str) if "engine" in summaries else pd.Series("", index=summaries.index)
    from_plan = [by_id.get(cid) or by_key.get((lb, e)) for cid, lb, e in
                 zip(summaries["case_id"].astype(str), summaries["label"].astype(str), engine)]
    summaries["physical_id"] = have.where(have.notna() & have.astype(str).ne(""),
                                          pd.Series(from_plan, index=summaries.index, dtype=object))
    return summaries


def recipe_notes(attrs: dict) -> list[str]:
    """What one_run_per_case used and left out, as report lines."""
    notes = []
    for engine, rid in attrs.get("recipes", {}).items():
        if not attrs["current"][engine]:
            notes.append(f"{engine}: no finished run of this version's recipe; the report uses recipe {rid} "
                         "(the one with most finished runs)")
    if attrs.get("other_recipe"):
        used = ", ".join(f"{e} {r}" for e, r in attrs["recipes"].items())
        notes.append(f"{attrs['other_recipe']} finished run(s) of another recipe left out (used: {used}); "
                     "`campaign status` lists the cases as stale, `campaign run --rerun-stale` reruns them")
    if attrs.get("not_asked"):
        notes.append(f"{attrs['not_asked']} finished folder(s) of cases the file no longer asks for left out")
    return notes


def campaign_ensembles(campaign_path: str | Path, output: str | Path | None = None) -> pd.DataFrame:
    """The seed-ensemble table (analysis.ensemble_table, one row per physical case) of a campaign
    file's finished runs, as open_campaign reads them. Raises InputError when nothing has run."""
    from interphase.analysis.ensemble_table import ensemble_tables

    _, store, rows = open_campaign(campaign_path, output)
    try:
        return with_inputs(ensemble_tables(rows, store)[0], rows)
    finally:
        store.close()


#: the physical inputs `ip.ensembles` carries beside each physical case (summaries' columns, SI)
ENSEMBLE_INPUTS = ("test", "device", "profile_kind", "profile_label", "rt", "sw", "sr", "friction_ps", "gradation",
                   "normal_stress", "d50")


def with_inputs(table: pd.DataFrame, rows: pd.DataFrame) -> pd.DataFrame:
    """The ensembles table with each physical case's inputs (ENSEMBLE_INPUTS: Rt, Sw, Sr [D50], μ,
    gradation, device, …) from its runs, after `case` (the label alone named them before)."""
    from interphase.analysis.ensemble import physical_ids

    if table.empty or rows.empty:
        return table
    cols = [c for c in ENSEMBLE_INPUTS if c in rows and c not in table]
    inputs = rows.assign(physical_id=physical_ids(rows).to_numpy()).groupby("physical_id")[cols].first()
    out = table.merge(inputs, left_on="physical_id", right_index=True, how="left")
    at = list(out.columns).index("case") + 1
    order = list(out.columns[:at]) + cols + [c for c in out.columns[at:] if c not in cols]
    return out[order]
