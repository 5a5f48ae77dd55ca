"""Case folders and the campaign index.

Folder of one case (`<output>/<case_id>/`), the truth:
    case.json        inputs (canonical Case) + campaign metadata + provenance (package version,
                     engine version, template hash, host, start/end, SLURM job id)
    attempts.jsonl   one line per attempt (start, end, status, cause): never truncated
    <engine files>   rendered deck, meshes, engine.log, dumps
    contacts.parquet, history.parquet, particles.parquet
    summary.json     the analysis summary (one flat row)
    failure.json     a failed / interrupted / killed attempt: status, cause, message, log tail
    DONE             written LAST, by atomic rename; without it the case is not finished
A folder restored from a summaries table (interphase.campaign.restore) holds case.json (with
provenance.restored_from), summary.json, attempts.jsonl and DONE only: no dumps, by design.

The index (`<output>/index.sqlite`) is a cache of the folders for fast status and reports: case id,
engine, group, label, status, cause, timings, parameters and summary. It is rebuilt from the folders
when missing or unreadable, and re-read from the folders for any case whose folder changed state or
that it does not know.

Finished folders are verified when read (`verify_folder`): case.json must hash to the folder's name
(interphase.case.case_id of its inputs, engine and recipe id) and every Parquet table must read
(its footer: pyarrow.parquet.read_metadata). A folder that fails is `corrupt` (cause, and a message
naming the path, what is wrong and the fix), never counted as done. The verdict is cached in the
index with the sizes and mtimes of the files it read (`folder_fingerprint`): a folder is verified
again only when one of them changed.
"""

from __future__ import annotations

import contextlib
import json
import os
import sqlite3
import tempfile
import time
from pathlib import Path

import pandas as pd

from interphase.errors import InputError

DONE = "DONE"
CASE_JSON = "case.json"
SUMMARY_JSON = "summary.json"
FAILURE_JSON = "failure.json"
ATTEMPTS = "attempts.jsonl"
INDEX = "index.sqlite"
LOCK = ".campaign.lock"

#: statuses: pending (never started), queued/running (this run), done, failed (engine or analysis
#: error), killed (by SLURM: timeout, cancel, node failure), interrupted (Ctrl-C, SIGTERM, preempted),
#: incomplete (a folder that started and never finished: its run was killed hard), corrupt (DONE, but
#: the folder does not verify: case.json does not hash to its name, or a table does not read)
STATUSES = ("pending", "queued", "running", "done", "failed", "killed", "interrupted", "incomplete", "corrupt")
FAILED_STATUSES = ("failed", "killed")
#: kept as they are by `campaign run`; rerun with --rerun-failed
KEPT_STATUSES = FAILED_STATUSES + ("corrupt",)

#: the tables a finished folder holds (the runner writes them when the engine gave them); the first
#: two always
TABLES = ("contacts", "history", "particles", "series")
REQUIRED_TABLES = ("contacts", "history")
#: causes of a corrupt folder; "unverifiable" (a done folder of the older id scheme) is not one
CORRUPT_CAUSES = ("bad_case_json", "id_mismatch", "missing_table", "bad_parquet", "bad_summary")
UNVERIFIABLE = "unverifiable"

_COLUMNS = ("case_id", "engine", "grp", "label", "role", "pair_id", "status", "cause", "message", "started",
            "finished", "elapsed", "attempts", "host", "slurm_job", "params", "summary", "updated", "checked",
            "recipe_id", "engine_version", "physical_id")
_HIDDEN = ["params", "summary", "checked"]


# ---- folder helpers (used by the runner, in worker processes) -------------------------------
def write_json_atomic(path: Path, data: dict) -> None:
    """Write JSON through a temporary file and os.replace: readers never see half a file."""
    path = Path(path)
    # a name of its own per writer: two processes may write one file (a worker and the parent
    # recording its death), and a shared temporary name lets one replace the other's away
    fd, tmp = tempfile.mkstemp(prefix=path.name + ".", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w") as fh:
            json.dump(data, fh, indent=1, sort_keys=True, default=_json_default, allow_nan=True)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def _json_default(o):
    if hasattr(o, "item"):
        return o.item()
    if isinstance(o, (set, tuple)):
        return list(o)
    if isinstance(o, Path):
        return str(o)
    return str(o)


def mark_done(folder: Path) -> None:
    """The DONE marker, last of all: DONE.tmp, fsync, os.replace, fsync of the folder."""
    folder = Path(folder)
    tmp = folder / (DONE + ".tmp")
    with open(tmp, "w") as fh:
        fh.write(f"{time.time():.6f}\n")
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, folder / DONE)
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def append_attempt(folder: Path, record: dict) -> None:
    with open(Path(folder) / ATTEMPTS, "a") as fh:
        fh.write(json.dumps(record, sort_keys=True, default=_json_default) + "\n")
        fh.flush()
        os.fsync(fh.fileno())


def read_json(path: Path) -> dict | None:
    try:
        return json.loads(Path(path).read_text())
    except (OSError, ValueError):
        return None


def folder_status(folder: Path) -> str:
    """The case's status as its folder tells it (the truth)."""
    folder = Path(folder)
    if (folder / DONE).exists():
        return "done"
    fail = folder / FAILURE_JSON
    if fail.exists():
        data = read_json(fail) or {}
        return data.get("status", "failed")
    if (folder / CASE_JSON).exists():
        return "incomplete"
    return "pending"


class _StoredInputs:
    """A case as its case.json stores it (Case.canonical(), through JSON): what case_id hashes."""

    def __init__(self, inputs: dict):
        self._inputs = inputs

    def canonical(self) -> dict:
        return self._inputs


_RERUN = "`campaign run FILE.toml --rerun-failed` reruns the case (its folder is cleaned first)"


def folder_fingerprint(folder: Path) -> str:
    """Sizes and mtimes of the files `verify_folder` reads: a cached verdict holds while this does."""
    parts = []
    for name in (DONE, CASE_JSON, SUMMARY_JSON, *(f"{t}.parquet" for t in TABLES)):
        try:
            s = os.stat(Path(folder) / name)
            parts.append(f"{name}:{s.st_size}:{s.st_mtime_ns}")
        except OSError:
            parts.append(f"{name}:-")
    return "|".join(parts)


def verify_folder(folder: Path, meta: dict | None = None) -> tuple[str | None, str | None]:
    """What is wrong with a finished folder: (cause, message naming the path, what and the fix), or
    (None, None) when it checks out. Checks: case.json reads and its inputs, engine and recipe id
    hash to the folder's name (interphase.case.case_id); contacts/history.parquet exist and every
    table's Parquet footer reads (pyarrow.parquet.read_metadata: no data read); summary.json reads.
    A folder of the older id scheme (engine version + template hash, no recipe id) cannot be hashed:
    (UNVERIFIABLE, why) when its files check out — not a corruption."""
    import pyarrow.parquet as pq

    from interphase.case import case_id

    folder = Path(folder)
    if meta is None:
        meta = read_json(folder / CASE_JSON)
    cj = folder / CASE_JSON
    if not isinstance(meta, dict):
        return "bad_case_json", f"{cj}: does not read as a JSON object; fix: {_RERUN}"
    prov = meta.get("provenance") if isinstance(meta.get("provenance"), dict) else {}
    rid = prov.get("recipe_id") or meta.get("recipe_id")
    inputs, engine = meta.get("inputs"), meta.get("engine")
    note = None
    if rid:
        if not isinstance(inputs, dict) or not isinstance(engine, str):
            return "bad_case_json", f"{cj}: no 'inputs' table or 'engine' name; fix: {_RERUN}"
        try:
            expect = case_id(_StoredInputs(inputs), engine, str(rid))
        except (TypeError, ValueError) as exc:
            return "bad_case_json", f"{cj}: its inputs do not hash ({exc}); fix: {_RERUN}"
        if expect != folder.name:
            return "id_mismatch", (f"{cj}: its inputs, engine {engine!r} and recipe {rid} hash to {expect}, not to "
                                   f"the folder's name {folder.name} (case.json edited, or the folder renamed or "
                                   f"copied over); fix: {_RERUN}, or restore that folder's case.json")
    elif any(k in prov or k in meta for k in ("template_hash", "engine_version")):
        note = (f"{cj}: id of the older scheme (engine version + template hash, no recipe id): its inputs cannot be "
                "checked against the folder's name; its tables were checked")
    else:
        return "bad_case_json", f"{cj}: no recipe id (provenance.recipe_id) to check the folder's name with; fix: {_RERUN}"
    # a run restored from a summaries table (campaign.restore) holds no dumps, by design
    restored = bool(prov.get("restored_from"))
    for table in TABLES:
        path = folder / f"{table}.parquet"
        if not path.exists():
            if table in REQUIRED_TABLES and not restored:
                return "missing_table", f"{path}: missing from a finished folder; fix: {_RERUN}"
            continue
        try:
            pq.read_metadata(path)
        except Exception as exc:  # noqa: BLE001 — pyarrow raises ArrowInvalid, OSError, ...
            why = str(exc).split("\n", 1)[0][:160]
            return "bad_parquet", f"{path}: does not read as Parquet ({type(exc).__name__}: {why}); fix: {_RERUN}"
    summ = read_json(folder / SUMMARY_JSON)
    if not isinstance(summ, dict):
        return "bad_summary", f"{folder / SUMMARY_JSON}: missing or not a JSON object; fix: {_RERUN}"
    return (UNVERIFIABLE, note) if note else (None, None)


def discard_corrupt(folder: Path, cause: str | None = None, message: str | None = None) -> None:
    """Before a corrupt case is rerun: record why in attempts.jsonl and remove DONE, so that the
    runner treats the folder as unfinished and cleans it (attempts.jsonl kept)."""
    folder = Path(folder)
    append_attempt(folder, {"event": "discarded", "status": "corrupt", "cause": cause, "message": message,
                            "time": time.time()})
    with contextlib.suppress(FileNotFoundError):
        (folder / DONE).unlink()


def folder_record(folder: Path) -> dict | None:
    """An index row from a case folder alone (None if the folder holds no case.json). A finished
    folder is verified (`verify_folder`): status corrupt when it fails; `checked` is the fingerprint
    of the files the verdict was made from."""
    folder = Path(folder)
    checked = folder_fingerprint(folder)
    meta = read_json(folder / CASE_JSON)
    if meta is None:
        return None
    status = folder_status(folder)
    row = {"case_id": folder.name, "engine": meta.get("engine"), "grp": meta.get("group"),
           "label": meta.get("label"), "role": meta.get("role"), "pair_id": meta.get("pair_id"),
           "status": status, "cause": None, "message": None, "started": meta.get("started"),
           "finished": meta.get("finished"), "elapsed": meta.get("elapsed"), "host": meta.get("host"),
           "slurm_job": meta.get("slurm_job"), "params": json.dumps(meta.get("params", {}), sort_keys=True),
           "summary": None, "updated": time.time(), "checked": None, "physical_id": meta.get("physical_id")}
    row["recipe_id"], row["engine_version"] = run_identity(meta)
    try:
        row["attempts"] = sum(1 for line in open(folder / ATTEMPTS) if '"event": "start"' in line)
    except OSError:
        row["attempts"] = 0
    if status == "done":
        cause, message = verify_folder(folder, meta)
        row["checked"], row["cause"], row["message"] = checked, cause, message
        if cause in CORRUPT_CAUSES:
            row["status"] = "corrupt"
        else:
            summ = read_json(folder / SUMMARY_JSON)
            row["summary"] = json.dumps(summ.get("row", summ) if isinstance(summ, dict) else {}, sort_keys=True)
    elif status == "incomplete":
        row["cause"] = "killed_hard"
        row["message"] = (f"started {_when(meta.get('started'))} on {meta.get('host') or '?'}, never finished: its "
                          "run was killed hard (SIGKILL, power, node lost); `campaign run` runs it again")
    elif status in ("failed", "killed", "interrupted"):
        fail = read_json(folder / FAILURE_JSON) or {}
        row["cause"], row["message"] = fail.get("cause"), fail.get("message")
        row["finished"] = fail.get("finished", row["finished"])
        row["elapsed"] = fail.get("elapsed", row["elapsed"])
    return row


def _when(t) -> str:
    try:
        return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(float(t)))
    except (TypeError, ValueError):
        return "at an unknown time"


def run_identity(meta: dict) -> tuple[str | None, str | None]:
    """(recipe id, engine build) of a case folder's case.json. A folder of the older id scheme has no
    recipe id; its template hash stands for one ('template:<hash>'), so that its runs still group."""
    prov = meta.get("provenance") if isinstance(meta.get("provenance"), dict) else {}
    rid = prov.get("recipe_id") or meta.get("recipe_id")
    if not rid and (prov.get("template_hash") or meta.get("template_hash")):
        rid = f"template:{prov.get('template_hash') or meta.get('template_hash')}"
    return rid, prov.get("engine_version") or meta.get("engine_version")


# ---- the store --------------------------------------------------------------------------------
class CampaignStore:
    """A campaign's output folder: one folder per case and an SQLite index of them.

    Only one process writes the index (the `campaign run` holding the lock); workers write their
    case folders only. Readers (status, report) may open it any time."""

    def __init__(self, root: str | os.PathLike, create: bool = False):
        self.root = Path(root)
        if create:
            self.root.mkdir(parents=True, exist_ok=True)
        elif not self.root.is_dir():
            raise InputError(f"no campaign output folder {str(self.root)!r}", where="store",
                             fix="run `campaign run FILE.toml` first, or check [campaign].output")
        self.index_path = self.root / INDEX
        fresh = not self.index_path.exists()
        try:
            self._open()
        except sqlite3.DatabaseError:
            # not a database (truncated, overwritten): keep it aside and rebuild from the folders
            with contextlib.suppress(Exception):
                self._db.close()
            os.replace(self.index_path, self.index_path.with_name(f"{INDEX}.broken-{int(time.time())}"))
            for ext in ("-wal", "-shm"):
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(str(self.index_path) + ext)
            self._open()
            fresh = True
        if fresh:
            self.rebuild()

    def _open(self) -> None:
        self._db = sqlite3.connect(self.index_path, timeout=60, isolation_level=None)
        self._db.execute("PRAGMA journal_mode=WAL")   # readers do not block the running campaign
        self._db.execute(
            "CREATE TABLE IF NOT EXISTS cases (case_id TEXT PRIMARY KEY, engine TEXT, grp TEXT, label TEXT, "
            "role TEXT, pair_id TEXT, status TEXT, cause TEXT, message TEXT, started REAL, finished REAL, "
            "elapsed REAL, attempts INTEGER, host TEXT, slurm_job TEXT, params TEXT, summary TEXT, updated REAL, "
            "checked TEXT, recipe_id TEXT, engine_version TEXT, physical_id TEXT)")
        have = {r[1] for r in self._db.execute("PRAGMA table_info(cases)")}
        for col in ("checked", "recipe_id", "engine_version", "physical_id"):   # an index of an older version
            if col not in have:
                with contextlib.suppress(sqlite3.OperationalError):   # another reader added it first
                    self._db.execute(f"ALTER TABLE cases ADD COLUMN {col} TEXT")
                if col != "physical_id":   # (that one the plan fills in: register, results.one_run_per_case)
                    # its finished rows are read from their folders again by the next reconcile()
                    self._db.execute("UPDATE cases SET checked = NULL")

    def close(self) -> None:
        self._db.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ---- locking ---------------------------------------------------------------------------
    @contextlib.contextmanager
    def lock(self, what: str = "campaign run"):
        """Exclusive lock on the campaign (filelock: released by the OS if the holder dies)."""
        from filelock import FileLock, Timeout

        lk = FileLock(str(self.root / LOCK))
        try:
            lk.acquire(timeout=0)
        except Timeout:
            raise InputError(f"another `{what}` is using this campaign right now", where=str(self.root),
                             fix="wait for it to finish (see `campaign status`), or stop it first") from None
        try:
            yield lk
        finally:
            lk.release()

    def run_active(self) -> bool:
        """Whether a `campaign run` holds this campaign's lock now (its queued/running rows are real)."""
        from filelock import FileLock, Timeout

        lk = FileLock(str(self.root / LOCK))
        try:
            lk.acquire(timeout=0)
        except Timeout:
            return True
        lk.release()
        return False

    # ---- folders ---------------------------------------------------------------------------
    def case_folder(self, case_id: str) -> Path:
        return self.root / case_id

    def folder_ids(self) -> list[str]:
        # (hidden folders are not cases: .superseded/, a restore's .<id>.restoring)
        return sorted(p.name for p in self.root.iterdir()
                      if p.is_dir() and not p.name.startswith(".") and (p / CASE_JSON).exists())

    # ---- index -----------------------------------------------------------------------------
    def rebuild(self) -> int:
        """Refill the index from the case folders (after loss or corruption). Returns rows written."""
        rows = [r for r in (folder_record(self.root / cid) for cid in self.folder_ids()) if r]
        self._upsert(rows)
        return len(rows)

    def _upsert(self, rows: list[dict]) -> None:
        if not rows:
            return
        cols = ", ".join(_COLUMNS)
        marks = ", ".join("?" for _ in _COLUMNS)
        self._db.execute("BEGIN")
        try:
            self._db.executemany(f"INSERT OR REPLACE INTO cases ({cols}) VALUES ({marks})",
                                 [tuple(r.get(c) for c in _COLUMNS) for r in rows])
            self._db.execute("COMMIT")
        except BaseException:
            self._db.execute("ROLLBACK")
            raise

    def register(self, planned) -> None:
        """Add planned cases (status from their folders; pending if none). Existing rows keep their data
        unless the folder says otherwise."""
        have = {r[0]: (r[1], r[2]) for r in self._db.execute("SELECT case_id, status, summary FROM cases")}
        rows, physical = [], []
        now = time.time()
        for p in planned:
            physical.append((p.physical_id or None, p.case_id))
            folder = self.root / p.case_id
            status = folder_status(folder) if folder.exists() else "pending"
            known = have.get(p.case_id)
            if known and (known[0] == status or (status == "done" and known[0] == "corrupt")) \
                    and (known[0] != "done" or known[1]):
                continue   # a done folder's verdict is kept up to date by reconcile()
            if known and known[0] in ("queued", "running") and status != "done" and self.run_active():
                continue   # a run at work knows better than the folder (an older attempt's failure, say)
            rec = folder_record(folder) if status != "pending" else None
            if rec is None:
                rec = {"case_id": p.case_id, "status": status, "attempts": 0, "updated": now}
            rec.update(engine=p.engine, grp=p.group, label=p.label, role=p.role, pair_id=p.pair_id,
                       params=json.dumps(p.params, sort_keys=True), physical_id=p.physical_id)
            rows.append(rec)
        self._upsert(rows)
        # rows kept as they were, of an index or folders older than the physical id: the plan's
        self._db.executemany("UPDATE cases SET physical_id = ? WHERE case_id = ? AND physical_id IS NULL", physical)

    def reconcile(self, case_ids=None, stale_running: bool = False) -> int:
        """Re-read every case whose folder disagrees with its index row (e.g. after a crash, or a file
        changed by hand): a folder state other than the row's, a finished folder whose files changed
        since it was verified (or never verified), a case folder the index does not know (all cases
        only). Returns the rows rewritten.

        Rows marked queued/running are left alone (a run may be at work) unless `stale_running`:
        the caller holds the campaign lock, so nothing can be running."""
        rows = list(self._db.execute("SELECT case_id, status, checked, recipe_id, engine_version FROM cases"))
        wanted = set(case_ids) if case_ids is not None else None
        fix = []
        if wanted is None:
            known = {r[0] for r in rows}
            fix = [r for r in (folder_record(self.root / cid) for cid in self.folder_ids() if cid not in known) if r]
        for cid, status, checked, rid, build in rows:
            if wanted is not None and cid not in wanted:
                continue
            folder = self.root / cid
            fs = folder_status(folder) if folder.exists() else "pending"
            if not stale_running and status in ("queued", "running") and fs != "done":
                continue   # a queued rerun's folder still holds its last attempt's failure
            if fs == "done":
                # (no identity: indexed by a version that did not record it)
                stale = (status not in ("done", "corrupt") or checked != folder_fingerprint(folder)
                         or (rid is None and build is None))
            else:
                stale = fs != status
            if stale:
                rec = folder_record(folder)
                if rec is None:
                    self.set_status(cid, "pending")
                else:
                    old = self.row(cid) or {}
                    rec.update({k: old.get(k) for k in ("engine", "grp", "label", "role", "pair_id", "params", "physical_id")
                                if old.get(k) is not None})
                    fix.append(rec)
        self._upsert(fix)
        return len(fix)

    def statuses(self) -> dict[str, str]:
        """{case id: status} as the index has it (call reconcile() first for the folders' word)."""
        return dict(self._db.execute("SELECT case_id, status FROM cases").fetchall())

    def row(self, case_id: str) -> dict | None:
        cur = self._db.execute(f"SELECT {', '.join(_COLUMNS)} FROM cases WHERE case_id = ?", (case_id,))
        r = cur.fetchone()
        return dict(zip(_COLUMNS, r)) if r else None

    def set_status(self, case_id: str, status: str, **fields) -> None:
        assert status in STATUSES, status
        fields = {k: v for k, v in fields.items() if k in _COLUMNS}
        fields.update(status=status, updated=time.time())
        sets = ", ".join(f"{k} = ?" for k in fields)
        self._db.execute(f"UPDATE cases SET {sets} WHERE case_id = ?", (*fields.values(), case_id))

    def record_result(self, case_id: str) -> dict:
        """Index a case from its folder after a run (the folder is the truth). Returns the row."""
        rec = folder_record(self.root / case_id)
        old = self.row(case_id) or {}
        if rec is None:
            self.set_status(case_id, "pending")
            return self.row(case_id) or {}
        rec.update({k: old.get(k) for k in ("engine", "grp", "label", "role", "pair_id", "params", "physical_id")
                    if old.get(k) is not None})
        self._upsert([rec])
        return rec

    # ---- tables ----------------------------------------------------------------------------
    def _frame(self, where: str = "", args=()) -> pd.DataFrame:
        df = pd.read_sql_query(f"SELECT {', '.join(_COLUMNS)} FROM cases {where} ORDER BY grp, label, case_id",
                               self._db, params=args)
        return df.rename(columns={"grp": "group"})

    def status(self) -> pd.DataFrame:
        """One row per indexed case: id, engine, group, label, role, status, cause, message, timings.
        Rows a dead run left queued/running are corrected from their folders."""
        self.reconcile(stale_running=not self.run_active())
        return self._frame().drop(columns=_HIDDEN)

    def summaries(self) -> pd.DataFrame:
        """One row per FINISHED case: ids, group, label, status, flat Case parameters, summary fields,
        and pair_id (the case id of the paired box test, for E)."""
        self.reconcile()
        df = self._frame("WHERE status = 'done'")
        if df.empty:
            return df.drop(columns=_HIDDEN)
        params = pd.DataFrame([json.loads(p or "{}") for p in df["params"]], index=df.index)
        summ = pd.DataFrame([json.loads(s or "{}") for s in df["summary"]], index=df.index)
        base = df.drop(columns=[*_HIDDEN, "message"])
        summ = summ[[c for c in summ.columns if c not in base.columns and c not in params.columns]]
        return pd.concat([base, params, summ], axis=1)

    def curve(self, case_id: str):
        """(shear_disp [m], stress_ratio [-]) of a finished case's series.parquet, None if unreadable."""
        try:
            s = pd.read_parquet(self.case_folder(str(case_id)) / "series.parquet", columns=["shear_disp", "stress_ratio"])
        except (OSError, ValueError, KeyError):
            return None
        return s["shear_disp"].to_numpy(float), s["stress_ratio"].to_numpy(float)

    def counts(self) -> dict[str, int]:
        return dict(self._db.execute("SELECT status, COUNT(*) FROM cases GROUP BY status").fetchall())
