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

The index (`<output>/index.sqlite`) is a cache of the folders for fast status and reports: case id,
engine, group, label, status, cause, timings, parameters and summary. It is rebuilt from the folders
when missing, and re-read from the folders for any case whose folder changed state.
"""

from __future__ import annotations

import contextlib
import json
import os
import sqlite3
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
#: incomplete (a folder that started and never finished: its run was killed hard)
STATUSES = ("pending", "queued", "running", "done", "failed", "killed", "interrupted", "incomplete")
FAILED_STATUSES = ("failed", "killed")

_COLUMNS = ("case_id", "engine", "grp", "label", "role", "pair_id", "status", "cause", "message", "started",
            "finished", "elapsed", "attempts", "host", "slurm_job", "params", "summary", "updated")


# ---- folder helpers (used by the runner, in worker processes) -------------------------------
def write_json_atomic(path: Path, data: dict) -> None:
    """Write JSON through a temporary file and os.replace: readers never see half a file."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "w") as fh:
        json.dump(data, fh, indent=1, sort_keys=True, default=_json_default, allow_nan=True)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


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


def folder_record(folder: Path) -> dict | None:
    """An index row from a case folder alone (None if the folder holds no case.json)."""
    folder = Path(folder)
    meta = read_json(folder / CASE_JSON)
    if meta is None:
        return None
    status = folder_status(folder)
    row = {"case_id": meta.get("case_id", folder.name), "engine": meta.get("engine"), "grp": meta.get("group"),
           "label": meta.get("label"), "role": meta.get("role"), "pair_id": meta.get("pair_id"),
           "status": status, "cause": None, "message": None, "started": meta.get("started"),
           "finished": meta.get("finished"), "elapsed": meta.get("elapsed"), "host": meta.get("host"),
           "slurm_job": meta.get("slurm_job"), "params": json.dumps(meta.get("params", {}), sort_keys=True),
           "summary": None, "updated": time.time()}
    try:
        row["attempts"] = sum(1 for line in open(folder / ATTEMPTS) if '"event": "start"' in line)
    except OSError:
        row["attempts"] = 0
    if status == "done":
        summ = read_json(folder / SUMMARY_JSON)
        row["summary"] = json.dumps(summ.get("row", summ) if isinstance(summ, dict) else {}, sort_keys=True)
    elif status in ("failed", "killed", "interrupted"):
        fail = read_json(folder / FAILURE_JSON) or {}
        row["cause"], row["message"] = fail.get("cause"), fail.get("message")
        row["finished"] = fail.get("finished", row["finished"])
        row["elapsed"] = fail.get("elapsed", row["elapsed"])
    return row


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
        self._db = sqlite3.connect(self.index_path, timeout=60, isolation_level=None)
        self._db.execute("PRAGMA journal_mode=WAL")   # readers do not block the running campaign
        self._db.execute(
            "CREATE TABLE IF NOT EXISTS cases (case_id TEXT PRIMARY KEY, engine TEXT, grp TEXT, label TEXT, "
            "role TEXT, pair_id TEXT, status TEXT, cause TEXT, message TEXT, started REAL, finished REAL, "
            "elapsed REAL, attempts INTEGER, host TEXT, slurm_job TEXT, params TEXT, summary TEXT, updated REAL)")
        if fresh:
            self.rebuild()

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

    # ---- folders ---------------------------------------------------------------------------
    def case_folder(self, case_id: str) -> Path:
        return self.root / case_id

    def folder_ids(self) -> list[str]:
        return sorted(p.name for p in self.root.iterdir() if p.is_dir() and (p / CASE_JSON).exists())

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
        rows = []
        now = time.time()
        for p in planned:
            folder = self.root / p.case_id
            status = folder_status(folder) if folder.exists() else "pending"
            if p.case_id in have and have[p.case_id][0] == status and (status != "done" or have[p.case_id][1]):
                continue
            rec = folder_record(folder) if status != "pending" else None
            if rec is None:
                rec = {"case_id": p.case_id, "status": status, "attempts": 0, "updated": now}
            rec.update(engine=p.engine, grp=p.group, label=p.label, role=p.role, pair_id=p.pair_id,
                       params=json.dumps(p.params, sort_keys=True))
            rows.append(rec)
        self._upsert(rows)

    def reconcile(self, case_ids=None, stale_running: bool = False) -> None:
        """Re-read every case whose folder state differs from its index row (e.g. after a crash).

        Rows marked queued/running are left alone (a run may be at work) unless `stale_running`:
        the caller holds the campaign lock, so nothing can be running."""
        rows = list(self._db.execute("SELECT case_id, status FROM cases"))
        wanted = set(case_ids) if case_ids is not None else None
        fix = []
        for cid, status in rows:
            if wanted is not None and cid not in wanted:
                continue
            folder = self.root / cid
            fs = folder_status(folder) if folder.exists() else "pending"
            if not stale_running and status in ("queued", "running") and fs in ("pending", "incomplete"):
                continue
            if fs != status:
                rec = folder_record(folder)
                if rec is None:
                    self.set_status(cid, "pending")
                else:
                    old = self.row(cid) or {}
                    rec.update({k: old.get(k) for k in ("engine", "grp", "label", "role", "pair_id", "params")
                                if old.get(k) is not None})
                    fix.append(rec)
        self._upsert(fix)

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
        rec.update({k: old.get(k) for k in ("engine", "grp", "label", "role", "pair_id", "params")
                    if old.get(k) is not None})
        self._upsert([rec])
        return rec

    # ---- tables ----------------------------------------------------------------------------
    def _frame(self, where: str = "", args=()) -> pd.DataFrame:
        df = pd.read_sql_query(f"SELECT {', '.join(_COLUMNS)} FROM cases {where} ORDER BY grp, label, case_id",
                               self._db, params=args)
        return df.rename(columns={"grp": "group"})

    def status(self) -> pd.DataFrame:
        """One row per indexed case: id, engine, group, label, role, status, cause, message, timings."""
        self.reconcile()
        return self._frame().drop(columns=["params", "summary"])

    def summaries(self) -> pd.DataFrame:
        """One row per FINISHED case: ids, group, label, status, flat Case parameters, summary fields,
        and pair_id (the case id of the paired box test, for E)."""
        self.reconcile()
        df = self._frame("WHERE status = 'done'")
        if df.empty:
            return df.drop(columns=["params", "summary"])
        params = pd.DataFrame([json.loads(p or "{}") for p in df["params"]], index=df.index)
        summ = pd.DataFrame([json.loads(s or "{}") for s in df["summary"]], index=df.index)
        base = df.drop(columns=["params", "summary", "message"])
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
