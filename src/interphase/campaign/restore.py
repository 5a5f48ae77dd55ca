"""Finished runs brought back from a committed summaries table (`campaign run --restore FILE`).

A campaign longer than one machine's life (a laptop, a CI box, a session on a fresh machine) keeps
its results as the small table `campaign report` writes (`tables/summaries.csv`: one row per
finished run, no dumps). On another machine, `campaign run FILE.toml --restore summaries.csv` turns
every row whose case id is one of the plan's into a finished case folder, then runs only the rest.

A row is restored only when its case id is a planned case's: the id hashes the canonical inputs,
the engine and the recipe id (interphase.case.case_id), so a row of other inputs, another engine or
another recipe version is never taken for this campaign's result; those rows are counted and named,
never used. A case that already has a folder here (finished, failed or under way) is left alone.

A restored folder holds case.json (the plan's inputs and metadata; provenance from the row: engine
build, recipe id, elapsed, `restored_from`), summary.json (the row's summary fields), DONE, and,
when a `curves.parquet` lies beside the table, series.parquet with the run's curve: the report's
(shear_disp, stress_ratio), from which the seed ensembles' tan δ, tan φ and E are made
(analysis.ensemble_table), or a pack's (campaign.pack: the series columns the element and cell tests
read). With a curves table, a row whose curve it lacks is not restored but run again
(it could not join its ensemble); without one, rows are restored without curves. It has no dumps:
force networks and animations are not available for it.
"""

from __future__ import annotations

import math
import shutil
import time
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from interphase.campaign import store as st
from interphase.campaign.results import BOOKKEEPING, RUN_COLUMNS
from interphase.errors import InputError

def _not_summary() -> set[str]:
    """Columns of the summaries table that are not the run's summary: the report's run columns and
    bookkeeping (campaign.results, which writes the table), its derived per-run ratio (`efficiency_run`;
    `efficiency` in tables written before it was renamed) and the index's own columns (the Case
    parameters are dropped by name per case)."""
    return {*RUN_COLUMNS, *BOOKKEEPING, *st._COLUMNS, "efficiency_run", "efficiency"}


@dataclass
class Restored:
    """What `restore_runs` did: ids restored, rows of no planned case, planned ids kept as they were."""

    source: Path
    restored: list[str] = field(default_factory=list)
    foreign: int = 0                 # rows whose id is no planned case (other inputs, engine or recipe)
    kept: list[str] = field(default_factory=list)   # planned ids in the table whose folder exists here
    curves: int = 0                  # restored runs that got their curve back (curves.parquet)
    no_curve: list[str] = field(default_factory=list)   # rows left to run: the curves table lacks them


def read_record(path: str | Path) -> pd.DataFrame:
    """The summaries table, with a clear error when it is not one."""
    path = Path(path)
    try:
        # pandas 3 reads every float back to the bit (round trip) by default
        df = pd.read_csv(path, dtype={"case_id": str, "pair_id": str, "recipe_id": str})
    except FileNotFoundError:
        raise InputError(f"no such file {str(path)!r}", where="--restore",
                         fix="give the summaries table a `campaign report` wrote (report/tables/summaries.csv) "
                             "or its committed copy") from None
    except (OSError, ValueError) as exc:
        raise InputError(f"{path}: does not read as CSV ({exc})", where="--restore",
                         fix="give the summaries table a `campaign report` wrote") from None
    missing = [c for c in ("case_id", "recipe_id") if c not in df.columns]
    if missing:
        raise InputError(f"{path}: no {', '.join(repr(c) for c in missing)} column: not a summaries table",
                         where="--restore", fix="give the summaries table a `campaign report` wrote "
                                                "(report/tables/summaries.csv)")
    dup = df["case_id"][df["case_id"].duplicated()]
    if len(dup):
        raise InputError(f"{path}: case id {dup.iloc[0]} appears more than once", where="--restore",
                         fix="keep one row per case id (the table `campaign report` writes has one)")
    return df


#: the report's curves table, looked for beside the summaries table (campaign.results.write_curves)
CURVES = "curves.parquet"


def _curves(path: Path) -> dict[str, pd.DataFrame]:
    """{case_id: series frame} of a curves table (every column but case_id; a column a case has no
    values in is left out of its frame); {} when there is none."""
    if not path.exists():
        return {}
    try:
        df = pd.read_parquet(path)
        df["case_id"] = df["case_id"].astype(str)
    except (OSError, ValueError, KeyError) as exc:
        raise InputError(f"{path}: does not read as the report's curves table ({exc})", where="--restore",
                         fix="copy report/tables/curves.parquet beside the summaries table, or remove it") from None
    return {cid: g.drop(columns="case_id").dropna(axis=1, how="all").astype(float).reset_index(drop=True)
            for cid, g in df.groupby("case_id", sort=False)}


def restorable_ids(path: str | Path) -> set[str]:
    """The case ids of a summaries table that `restore_runs` would restore (a plan and a folder
    permitting): every row, or with a curves table beside it only the rows it has a curve of."""
    path = Path(path)
    ids = set(read_record(path)["case_id"])
    curves = path.with_name(CURVES)
    if curves.exists():
        ids &= set(pd.read_parquet(curves, columns=["case_id"])["case_id"].astype(str))
    return ids


def _scalar(v):
    if isinstance(v, float) and math.isnan(v):
        return None
    return v.item() if hasattr(v, "item") else v


def restore_runs(planned, store: st.CampaignStore, path: str | Path, campaign_name: str = "") -> Restored:
    """Write a finished folder for every planned case whose id is a row of the summaries table at
    `path` and that has no folder here. The caller holds the campaign lock."""
    path = Path(path)
    df = read_record(path)
    by_id = {p.case_id: p for p in planned}
    out = Restored(path.resolve())
    out.foreign = int((~df["case_id"].isin(by_id)).sum())
    now = time.time()
    curves = _curves(path.with_name(CURVES))
    not_summary = _not_summary()
    for row in df[df["case_id"].isin(by_id)].to_dict("records"):
        p = by_id[row["case_id"]]
        folder = store.case_folder(p.case_id)
        if folder.exists():
            out.kept.append(p.case_id)
            continue
        if curves and p.case_id not in curves:
            # a run the table keeps without its curve cannot join its seed ensemble: run it again
            out.no_curve.append(p.case_id)
            continue
        if str(row["recipe_id"]) != p.recipe_id:   # an id collision would be a hashing bug: refuse loudly
            raise InputError(f"{path}: case {p.case_id} has recipe {row['recipe_id']}, the plan {p.recipe_id}",
                             where="--restore", fix="report this: a case id must fix its recipe")
        summary = {k: _scalar(v) for k, v in row.items() if k not in not_summary and k not in p.params}
        elapsed = _scalar(row.get("elapsed"))
        tmp = folder.with_name(f".{folder.name}.restoring")
        shutil.rmtree(tmp, ignore_errors=True)      # what a restore cut short left
        tmp.mkdir(parents=True)
        meta = {**p.meta(campaign_name), "inputs": p.case.canonical(), "name": p.case.name,
                "provenance": {"recipe_id": p.recipe_id, "engine_version": _scalar(row.get("engine_version")),
                               "restored_from": str(out.source), "restored": now},
                "started": None, "finished": None, "elapsed": elapsed, "status": "done"}
        st.write_json_atomic(tmp / st.CASE_JSON, meta)
        st.write_json_atomic(tmp / st.SUMMARY_JSON, {"row": summary})
        if p.case_id in curves:
            curves[p.case_id].to_parquet(tmp / "series.parquet", index=False)
            out.curves += 1
        st.append_attempt(tmp, {"event": "restored", "status": "done", "time": now, "source": str(out.source)})
        st.mark_done(tmp)
        # a whole folder or none: a restore cut short leaves only a hidden .restoring folder
        tmp.rename(folder)
        out.restored.append(p.case_id)
    return out


def is_restored(meta: dict) -> bool:
    """Whether a case.json is of a restored run (no dumps in its folder, by design)."""
    prov = meta.get("provenance") if isinstance(meta.get("provenance"), dict) else {}
    return bool(prov.get("restored_from"))


def describe(r: Restored) -> str:
    text = f"restored {len(r.restored)} finished run(s) from {r.source}"
    if r.restored:
        text += f" ({r.curves} with their curve from {CURVES})"
    if r.no_curve:
        text += f"; {len(r.no_curve)} row(s) without a curve in {CURVES} are run again"
    if r.kept:
        text += f"; {len(r.kept)} already here (kept as they are)"
    if r.foreign:
        text += (f"; {r.foreign} row(s) are no case of this plan (other inputs, engine or recipe version: "
                 "not used)")
    return text


# ---- restoring from a pack (campaign/pack.py writes it; `campaign calibrate --restore`) ---------------

#: (runs root, pack root) while a command restores the generated campaigns under a runs root from a pack
_PACK: ContextVar[tuple[Path, Path] | None] = ContextVar("restore_pack", default=None)


@contextmanager
def restoring(runs: str | Path, pack: str | Path | None):
    """While inside, a generated campaign whose output lies under `runs` restores its finished runs
    from the pack's table at the same relative path (`packed_table`), then runs the rest. A pack of
    another calibration's runs restores nothing: rows are taken by case id only."""
    if pack is not None and not Path(pack).is_dir():
        raise InputError(f"no pack folder {str(pack)!r}", where="--restore",
                         fix="give the folder `campaign pack RUNS -o FOLDER` wrote")
    token = _PACK.set(None if pack is None else (Path(runs).resolve(), Path(pack)))
    try:
        yield
    finally:
        _PACK.reset(token)


def packed_table(output: str | Path) -> Path | None:
    """The pack's summaries table for a campaign whose runs folder is `output`, None when no pack is
    being restored from or it has none for that folder."""
    got = _PACK.get()
    if got is None:
        return None
    runs, pack = got
    try:
        rel = Path(output).resolve().relative_to(runs)
    except ValueError:
        return None
    table = pack / rel / "summaries.csv"
    return table if table.exists() else None
