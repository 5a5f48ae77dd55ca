"""The case runner: one Case, one engine, one folder → a finished case (DONE) or a recorded failure.

`run_case(case, engine, folder, meta)` is what both executors call (in a pool worker or in a
SLURM job), and what `campaign crosscheck` reuses; `engine` is a value (engines.base.EngineSpec,
built here, or an Engine), never a name. It never raises for an engine failure: the
failure goes to failure.json (cause, message, log tail) and the returned status dict. It re-raises
interruptions (Ctrl-C, SIGTERM, SLURM time-out signals) after recording them, so the caller stops.

Order of writes (a case killed at any point is never taken for finished):
  case.json (inputs + provenance) → engine inputs → engine run → contacts/history/particles.parquet
  → summary.json → case.json (end time) → DONE (atomic rename, last).
"""

from __future__ import annotations

import os
import platform
import shutil
import signal
import socket
import sys
import time
import traceback
from pathlib import Path

from interphase.campaign import store as st
from interphase.case import Case
from interphase.engines.base import Engine, EngineSpec, engine_spec
from interphase.version import __version__


class Interrupted(BaseException):
    """Raised by executors' signal handlers (SIGTERM, SIGINT) to stop a running case cleanly."""

    def __init__(self, reason: str = "interrupted"):
        super().__init__(reason)
        self.reason = reason


def _slurm_job() -> str | None:
    if "SLURM_ARRAY_JOB_ID" in os.environ:
        return f"{os.environ['SLURM_ARRAY_JOB_ID']}_{os.environ.get('SLURM_ARRAY_TASK_ID', '')}"
    return os.environ.get("SLURM_JOB_ID")


def stale_engine_pids(folder: Path) -> list[int]:
    """PIDs of this user's processes whose working directory is `folder`: engines orphaned by a run
    that was killed hard (engines run with cwd = the case folder and in their own session, so a
    SIGKILL of the campaign's process group does not reach them). Linux /proc; [] elsewhere."""
    target = os.path.realpath(folder)
    me, uid = os.getpid(), os.getuid()
    out = []
    try:
        entries = os.listdir("/proc")
    except OSError:
        return out
    for name in entries:
        if not name.isdigit() or int(name) == me:
            continue
        try:
            if os.stat(f"/proc/{name}").st_uid != uid:
                continue
            if os.readlink(f"/proc/{name}/cwd") == target:
                out.append(int(name))
        except OSError:
            continue
    return out


def kill_stale_engines(folder: Path, wait: float = 10.0) -> list[int]:
    """SIGKILL the orphaned engines of `folder` (by PID) and wait until they are gone."""
    pids = stale_engine_pids(folder)
    for pid in pids:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    deadline = time.monotonic() + wait
    while pids and time.monotonic() < deadline:
        pids = [p for p in pids if os.path.exists(f"/proc/{p}") and _not_zombie(p)]
        time.sleep(0.05)
    return pids


def _not_zombie(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _clean(folder: Path) -> None:
    """Remove what an unfinished earlier attempt left (never attempts.jsonl, the run history)."""
    for p in folder.iterdir():
        if p.name == st.ATTEMPTS:
            continue
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p)
        else:
            p.unlink()


def summarise(case: Case, results) -> tuple[dict, object]:
    """(flat summary row, series DataFrame) of a finished case (interphase.analysis.summary)."""
    # each summariser imported on its own path: a cell run never loads the shear-device analysis
    if case.cell:
        from interphase.analysis.cell_run import summarise_cell

        return summarise_cell(case, results)
    from interphase.analysis.summary import summarise as analysis_summarise

    summary = analysis_summarise(case, results)
    return dict(summary.row), summary.series


def _failure(folder: Path, status: str, cause: str, message: str, started: float, log_tail: str = "",
             **extra) -> dict:
    now = time.time()
    data = {"status": status, "cause": cause, "message": message, "log_tail": log_tail, "started": started,
            "finished": now, "elapsed": now - started, "host": socket.gethostname(), "slurm_job": _slurm_job(),
            **extra}
    st.write_json_atomic(folder / st.FAILURE_JSON, data)
    st.append_attempt(folder, {"event": "end", "status": status, "cause": cause, "time": now,
                               "elapsed": now - started})
    return data


def _start_record(case: Case, engine: Engine, meta: dict, cid: str, started: float) -> dict:
    """case.json at the start of a run: the case, its engine and recipe, and where it runs."""
    return {**meta, "case_id": cid, "engine": engine.name, "inputs": case.canonical(), "name": case.name,
            "provenance": {"package": "interphase-dem", "package_version": __version__,
                           "engine_version": engine.version(), "recipe_id": engine.recipe_id(),
                           "host": socket.gethostname(), "pid": os.getpid(), "python": sys.version.split()[0],
                           "platform": platform.platform(), "slurm_job": _slurm_job()},
            "host": socket.gethostname(), "slurm_job": _slurm_job(), "started": started, "finished": None}


def _record_exception(folder: Path, exc: Exception, stage: str, started: float) -> dict:
    """Record a run that raised during `stage` (its cause, message, log tail); returns the failure
    record. A SLURM time limit is recorded and raised again."""
    from interphase.engines.base import EngineError

    if type(exc).__name__ == "UncompletedJobError":
        # submitit's answer to SLURM's time-limit signal: the job is out of time
        _failure(folder, "killed", "slurm_timeout", f"SLURM time limit reached during {stage}: {exc}", started)
        raise
    if disk_full(exc, folder):
        data = _record_disk_full(folder, stage, exc, started)
    elif isinstance(exc, EngineError):
        d = exc.to_dict()
        data = _failure(folder, "failed", d["cause"], d["message"], started, d.get("log_tail") or "",
                        returncode=d.get("returncode"), command=d.get("command"), stage=stage)
    else:
        cause = {"write_input": "input_error", "read_results": "read_error",
                 "summarise": "analysis_error"}.get(stage, "runner_error")
        tb = traceback.format_exc(limit=8)
        try:
            data = _failure(folder, "failed", cause, f"{type(exc).__name__} during {stage}: {exc}", started,
                            st_tail(folder), traceback=tb, stage=stage)
        except OSError as rec:
            if not disk_full(rec, folder):
                raise
            data = _record_disk_full(folder, stage, exc, started)
    return data


def run_case(case: Case, engine: EngineSpec | Engine, folder: str | os.PathLike, meta: dict | None = None) -> dict:
    """Run one case in `folder` with `engine` (an EngineSpec, built here, or an Engine); returns
    {case_id, status, cause, message, elapsed, skipped, ...}.

    Skips a case whose folder already holds DONE. An earlier unfinished attempt's files are removed
    first (its engines, if still alive, are killed by PID); attempts.jsonl keeps the history."""
    folder = Path(folder)
    meta = dict(meta or {})
    cid = meta.get("case_id", folder.name)
    if (folder / st.DONE).exists():
        return {"case_id": cid, "status": "done", "skipped": True, "cause": None, "message": None,
                "elapsed": 0.0}
    started = time.time()
    stage = "setup"
    # the preparation is inside the try: an interruption that lands here (a case handed to a worker
    # just as the campaign is stopped is signalled at once) is recorded like one mid-run
    try:
        folder.mkdir(parents=True, exist_ok=True)
        kill_stale_engines(folder)
        _clean(folder)
        # a first case.json before anything can fail, so that the folder is always indexable
        st.write_json_atomic(folder / st.CASE_JSON, {**meta, "case_id": cid, "engine": engine.name,
                                                     "inputs": case.canonical(), "started": started})
        if isinstance(engine, EngineSpec):
            engine = engine.build()
        record = _start_record(case, engine, meta, cid, started)
        st.write_json_atomic(folder / st.CASE_JSON, record)
        st.append_attempt(folder, {"event": "start", "time": started, "host": socket.gethostname(),
                                   "pid": os.getpid(), "slurm_job": _slurm_job()})
        timings = {}   # seconds per stage: where a case's time goes (bench/bench_campaign.py)
        stage = "write_input"
        t = time.perf_counter()
        engine.write_input(case, folder)
        stage = "execute"
        timings["write_input"], t = time.perf_counter() - t, time.perf_counter()
        engine.execute(folder)
        stage = "read_results"
        timings["execute"], t = time.perf_counter() - t, time.perf_counter()
        results = engine.read_results(folder)
        for name in ("contacts", "history", "particles"):
            df = getattr(results, name, None)
            if df is not None:
                df.to_parquet(folder / f"{name}.parquet", index=False)
        stage = "summarise"
        timings["read_results"], t = time.perf_counter() - t, time.perf_counter()
        row, series = summarise(case, results)
        if series is not None and hasattr(series, "to_parquet"):
            series.to_parquet(folder / "series.parquet")
        st.write_json_atomic(folder / st.SUMMARY_JSON, {"row": row})
        timings["summarise"] = time.perf_counter() - t
        finished = time.time()
        record.update(finished=finished, elapsed=finished - started, status="done", timings=timings)
        st.write_json_atomic(folder / st.CASE_JSON, record)
        st.append_attempt(folder, {"event": "end", "status": "done", "time": finished,
                                   "elapsed": finished - started})
        st.mark_done(folder)   # last of all
        return {"case_id": cid, "status": "done", "skipped": False, "cause": None, "message": None,
                "elapsed": finished - started, "summary": row}
    except (KeyboardInterrupt, Interrupted, SystemExit) as exc:
        reason = getattr(exc, "reason", None) or type(exc).__name__
        _failure(folder, "interrupted", "interrupted", f"stopped during {stage}: {reason}", started)
        raise
    except Exception as exc:  # noqa: BLE001 — every failure is recorded, the campaign goes on
        data = _record_exception(folder, exc, stage, started)
        return {"case_id": cid, "status": data["status"], "skipped": False, "cause": data["cause"],
                "message": data["message"], "elapsed": data["elapsed"]}


#: below this many free bytes a failed case is taken for a full disk (an engine that cannot write
#: may end "successfully" with its dumps cut short: LIGGGHTS does, return code 0)
DISK_FULL_BYTES = 256 * 1024
_KEEP_ON_DISK_FULL = (st.ATTEMPTS, st.CASE_JSON, "engine.log")


def _free_bytes(folder: Path) -> int | None:
    try:
        s = os.statvfs(folder)
    except (OSError, AttributeError):
        return None
    return (s.f_bfree if os.geteuid() == 0 else s.f_bavail) * s.f_frsize


def disk_full(exc: BaseException, folder: Path) -> bool:
    """Did `exc` come of a full disk: an OSError ENOSPC/EDQUOT anywhere in its chain, or next to no
    space left on the folder's file system when it was raised."""
    import errno

    e = exc
    while e is not None:
        if isinstance(e, OSError) and e.errno in (errno.ENOSPC, errno.EDQUOT):
            return True
        e = e.__cause__ or e.__context__
    free = _free_bytes(folder)
    return free is not None and free < DISK_FULL_BYTES


def _record_disk_full(folder: Path, stage: str, exc: BaseException, started: float) -> dict:
    """A case that ran out of space is not finished, nor its own fault: its partial engine output
    (dumps, tables) is removed so that the failure can be written and the campaign go on; status
    'interrupted' (rerun by the next `campaign run`), cause disk_full. case.json, attempts.jsonl and
    engine.log are kept."""
    tail = st_tail(folder)
    for p in folder.iterdir():
        if p.name in _KEEP_ON_DISK_FULL:
            continue
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p, ignore_errors=True)
        else:
            p.unlink(missing_ok=True)
    why = str(exc).split("\n", 1)[0][:300]
    message = (f"no space left on device in {folder} during {stage} ({type(exc).__name__}: {why}); its partial "
               "engine output was removed. Free space, then run the same command again: the case is rerun")
    return _failure(folder, "interrupted", "disk_full", message, started, tail, stage=stage)


def run_single(case: Case, engine: str | EngineSpec, folder: str | os.PathLike) -> dict:
    """One case outside a campaign (`campaign run-case`): `run_case` in `folder` with `engine` (a
    name, made into this machine's EngineSpec, or an EngineSpec), whose result dict also carries the
    summary row (read back from summary.json when the folder had already finished).

    The folder is checked first (campaign.guard.check_run_folder): a folder of another case, or a
    non-empty folder that is no case folder, is refused (InputError); this same case's finished
    folder is read back, not rerun."""
    from interphase.campaign.guard import check_run_folder

    folder = Path(folder)
    engine = engine_spec(engine).build()
    check_run_folder(folder, case, engine.name, engine.recipe_id())
    result = run_case(case, engine, folder, {"label": case.label()})
    if result["status"] == "done" and "summary" not in result:
        result["summary"] = st.read_json(folder / st.SUMMARY_JSON)["row"]
    return result


def st_tail(folder: Path) -> str:
    from interphase.engines.base import log_tail

    return log_tail(folder / "engine.log")
