"""Executors: where cases run. One interface, the same case runner (`runner.run_case`) in both.

    executor.run(tasks, on_event)     tasks: list[Task]; on_event(kind, case_id, info)
        kind "started"  — a case began (info: {"pid"} or {"slurm_job"})
        kind "finished" — a case ended (info: run_case's status dict)
    Interruption (KeyboardInterrupt / runner.Interrupted in the caller) stops running cases, records
    them as interrupted in their folders, reports them finished, and re-raises.

A Task carries its engine as a value (engines.base.EngineSpec: class, profile, Recipe, recipe
version), pickled to the worker as it is: a worker builds the very engine the plan hashed the case
id with, never looks a name up again.

`local`: a pool of worker processes (concurrent.futures, spawn), `jobs` at a time; each case runs its
engine as a subprocess. `slurm`: submitit job arrays, one per time-limit bucket, at most
`max_concurrent` tasks running per array, requeued on preemption (submitit + sbatch --requeue); a
case SLURM kills is recorded with the cause SLURM gives (timeout, cancel, node failure, memory).
"""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import signal
import subprocess
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from interphase.campaign import store as st
from interphase.campaign.runner import Interrupted, run_case
from interphase.case import Case
from interphase.engines.base import EngineSpec

OnEvent = Callable[[str, str, dict], None]


@dataclass(frozen=True)
class Task:
    case: Case
    engine: EngineSpec
    folder: Path
    meta: dict

    @property
    def case_id(self) -> str:
        return self.meta["case_id"]


def interrupted_result(case_id: str, message: str = "interrupted") -> dict:
    return {"case_id": case_id, "status": "interrupted", "skipped": False, "cause": "interrupted",
            "message": message, "elapsed": None}


def record_interrupted(folder: Path, message: str, cause: str = "interrupted") -> None:
    """Mark an unfinished case folder as interrupted (never touches a DONE or recorded failure)."""
    folder = Path(folder)
    if folder_terminal(folder):
        return
    if (folder / st.CASE_JSON).exists():
        now = time.time()
        st.write_json_atomic(folder / st.FAILURE_JSON, {"status": "interrupted", "cause": cause,
                                                        "message": message, "finished": now, "log_tail": ""})


def folder_terminal(folder: Path) -> bool:
    return st.folder_status(folder) in ("done", "failed", "killed", "interrupted")


# ---- local ----------------------------------------------------------------------------------
_EVENTS = None
_STOP_REASON: str | None = None      # why a worker stops itself (its campaign process died)


def _watch_parent(ppid: int) -> None:
    """A pool worker outlives a campaign process killed hard (SIGKILL, the out-of-memory killer): it
    would finish its case, start the next one it was handed, then idle forever. It stops instead:
    SIGTERM to itself, which records its running case as interrupted and ends the worker."""
    global _STOP_REASON
    while os.getppid() == ppid:
        time.sleep(0.5)
    _STOP_REASON = f"the campaign process (pid {ppid}) died"
    os.kill(os.getpid(), signal.SIGTERM)


def _worker_init(events, ppid: int | None = None) -> None:
    global _EVENTS
    _EVENTS = events
    # an idle worker ignores Ctrl-C; a running case turns it into a recorded interruption
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if ppid is not None:
        import threading

        threading.Thread(target=_watch_parent, args=(ppid,), name="watch-parent", daemon=True).start()


def _absorb(signum, frame):
    """A signal that arrives while an interruption is being recorded: nothing to do."""


def _raise_interrupted(signum, frame):
    # one interruption per case: further signals would cut the recording of this one short. They
    # are absorbed by a Python handler, not SIG_IGN: one that reached C while this handler ran would
    # find SIG_IGN when Python turns to it and CPython prints "Signal 15 ignored due to race
    # condition" as a traceback into the user's progress
    signal.signal(signal.SIGINT, _absorb)
    signal.signal(signal.SIGTERM, _absorb)
    name = signal.Signals(signum).name
    raise Interrupted(f"{name}: {_STOP_REASON}" if _STOP_REASON else name)


def _local_task(case: Case, engine: EngineSpec, folder: str, meta: dict) -> dict:
    # handlers before the "started" event: the parent signals a worker once it has heard it start
    signal.signal(signal.SIGINT, _raise_interrupted)
    signal.signal(signal.SIGTERM, _raise_interrupted)
    try:
        _EVENTS.put(("started", meta["case_id"], {"pid": os.getpid()}))
        return run_case(case, engine, folder, meta)
    except (Interrupted, KeyboardInterrupt, SystemExit) as exc:
        reason = getattr(exc, "reason", type(exc).__name__)
        if reason.startswith("SIGTERM"):
            # the pool tears its workers down (another worker died) or the campaign process is
            # gone: the case is recorded; this worker must not take another one
            os._exit(143)
        return interrupted_result(meta["case_id"], f"stopped: {reason}")
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _gone(pid: int | None, wait: float) -> bool:
    """Wait up to `wait` s for process `pid` to end (a zombie counts as ended)."""
    from interphase.campaign.runner import _not_zombie

    deadline = time.monotonic() + wait
    while pid:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        except PermissionError:
            pass
        if os.path.exists(f"/proc/{pid}") and not _not_zombie(pid):
            return True
        if time.monotonic() > deadline:
            return False
        time.sleep(0.05)
    return True


def lost_result(task: Task, exc: BaseException, pid: int | None) -> dict:
    """The verdict on a case whose worker gave no result (`exc`: BrokenProcessPool when a worker of
    the pool died, which fails every running and queued case of the pool). Waits for the case's
    worker to be gone (it may be recording its own end), kills an engine it left behind, then takes
    the folder's word, else records the case as interrupted with the cause."""
    from concurrent.futures.process import BrokenProcessPool

    from interphase.campaign.runner import disk_full, kill_stale_engines

    folder = Path(task.folder)
    _gone(pid, 30.0)
    if folder.is_dir():
        kill_stale_engines(folder)
    if folder_terminal(folder):
        fail = st.read_json(folder / st.FAILURE_JSON) or {}
        return {"case_id": task.case_id, "status": st.folder_status(folder), "cause": fail.get("cause"),
                "message": fail.get("message")}
    if pid is None and not (folder / st.CASE_JSON).exists():
        return {"case_id": task.case_id, "status": "pending", "skipped": True}   # never started
    if isinstance(exc, BrokenProcessPool):
        cause = "worker_died"
        message = (f"its worker process (pid {pid}) died mid-case without recording anything (killed by a "
                   "signal: SIGKILL, the out-of-memory killer); its engine was stopped, the case is rerun")
    else:
        cause = "disk_full" if disk_full(exc, folder) else "runner_error"
        message = f"{type(exc).__name__}: {str(exc).splitlines()[0][:300] if str(exc) else ''}"
    try:
        record_interrupted(folder, message, cause)
    except OSError as err:
        message += f" (could not be recorded in {folder}: {err})"
    return {"case_id": task.case_id, "status": "interrupted", "cause": cause, "message": message}


class StopAsked(Interrupted):
    """The campaign's STOP file was found: the cases running then finished, no other started."""


#: the file in a campaign's runs folder that asks its running `campaign run` to start no new case and
#: end when its running cases have finished (`campaign stop`); removed once honoured
STOP_FILE = "STOP"


class LocalExecutor:
    name = "local"

    def __init__(self, jobs: int = 0, stop_file: Path | None = None):
        self.jobs = jobs if jobs and jobs > 0 else (os.cpu_count() or 1)
        self.stop_file = stop_file

    def run(self, tasks: list[Task], on_event: OnEvent, grace: float = 30.0) -> None:
        """Run `tasks` in a pool of `jobs` workers. A worker that dies (SIGKILL, the out-of-memory
        killer) breaks a ProcessPoolExecutor for good: its case is recorded (worker_died, rerun by the
        next `campaign run`), the cases the broken pool stopped or never started go to a new pool,
        and the run goes on. Each new pool follows a death that ended at least one case, or at most
        `len(tasks)` times (a worker that dies idle ends none)."""
        remaining = list(tasks)
        for generation in range(len(tasks) + 1):
            if not remaining:
                return
            if generation:
                on_event("note", "", {"message": f"a worker process died; a new pool of workers runs the "
                                                  f"{len(remaining)} case(s) it stopped or had not started"})
            remaining = self._run_pool(remaining, on_event, grace)
        for t in remaining:    # workers kept dying without a case: record the rest as not run
            on_event("finished", t.case_id, {"case_id": t.case_id, "status": "pending", "skipped": True})

    def _run_pool(self, tasks: list[Task], on_event: OnEvent, grace: float) -> list[Task]:
        """One pool over `tasks`; returns the tasks to run again in a new pool (its pool broke)."""
        ctx = mp.get_context("spawn")   # no fork of a process that runs a display thread
        events = ctx.Queue()
        with ProcessPoolExecutor(max_workers=min(self.jobs, len(tasks)), mp_context=ctx,
                                 initializer=_worker_init, initargs=(events, os.getpid())) as pool:
            futures = {pool.submit(_local_task, t.case, t.engine, str(t.folder), t.meta): t for t in tasks}
            rnd = _PoolRound(futures, events, on_event)
            pending = set(futures)
            try:
                while pending:
                    done, pending = wait(pending, timeout=0.2, return_when=FIRST_COMPLETED)
                    rnd.drain()
                    for fut in done:
                        rnd.finish(fut)
                    if rnd.keep is None and self.stop_file is not None and self.stop_file.exists():
                        rnd.keep = set(rnd.workers)       # these finish; nothing else starts
                        for fut in pending:
                            fut.cancel()
                        on_event("note", "", {"message": f"{self.stop_file} found: the {len(rnd.keep)} running "
                                              "case(s) finish, no other starts"})
                    if rnd.keep is not None:
                        rnd.stop_started(spare=rnd.keep)
            except (KeyboardInterrupt, Interrupted):
                rnd.stop(pending, grace)
                pool.shutdown(wait=False, cancel_futures=True)
                raise
        if rnd.keep is not None:
            self.stop_file.unlink(missing_ok=True)
            raise StopAsked(f"{self.stop_file}")
        return rnd.again


class _PoolRound:
    """The bookkeeping of one pool's run: which worker (pid) runs which case, the events the workers
    send, each finished future reported once, the cases a broken pool stopped (`again`)."""

    def __init__(self, futures: dict, events, on_event: OnEvent):
        self.futures = futures          # future → Task
        self.events = events            # the workers' queue of (kind, case_id, info)
        self.on_event = on_event
        self.workers: dict[str, int] = {}   # case_id → pid of the worker running it
        self.again: list[Task] = []
        self.signalled: set[str] = set()
        self.keep: set[str] | None = None     # after a STOP: the cases that were running then

    def drain(self) -> None:
        """Pass on the workers' queued events, noting which worker runs which case."""
        while True:
            try:
                kind, cid, info = self.events.get_nowait()
            except Exception:   # queue.Empty (and a closed queue at shutdown)
                return
            self.workers[cid] = info.get("pid")
            self.on_event(kind, cid, info)

    def finish(self, fut) -> None:
        """Report a done future's case; one the broken pool stopped goes to `again` instead."""
        from concurrent.futures.process import BrokenProcessPool

        t = self.futures[fut]
        if fut.cancelled():          # never started (a STOP): it stays pending
            self.on_event("finished", t.case_id, {"case_id": t.case_id, "status": "pending", "skipped": True})
            return
        try:
            res = fut.result()
        except (KeyboardInterrupt, Interrupted):
            raise            # the campaign's own interruption, not this case's failure
        except BaseException as exc:  # a worker died (BrokenProcessPool) or a bug outside run_case
            res = lost_result(t, exc, self.workers.get(t.case_id))
            if isinstance(exc, BrokenProcessPool) and res.get("cause") != "worker_died" and \
                    res.get("status") in ("pending", "interrupted"):
                # stopped by the broken pool, not by its own fault: a new pool runs it
                self.workers.pop(t.case_id, None)
                self.again.append(t)
                return
        self.workers.pop(t.case_id, None)
        self.on_event("finished", t.case_id, res)

    def stop_started(self, spare: set[str] = frozenset()) -> None:
        """SIGINT to every worker running a case but those in `spare`, once each."""
        # the pool hands a worker its next task before the parent can cancel it (a queued call), so
        # a case may start after the interruption: stop it as well
        self.drain()
        for cid, pid in list(self.workers.items()):
            if cid not in self.signalled and cid not in spare:
                self.signalled.add(cid)
                try:
                    os.kill(pid, signal.SIGINT)
                except (ProcessLookupError, TypeError):
                    pass

    def stop(self, pending: set, grace: float) -> None:
        """On interruption: cancel what has not started, stop what runs, wait `grace` [s] for it,
        and record every case that did not end by itself (interrupted, or pending when never run)."""
        for fut in pending:
            fut.cancel()
        self.stop_started()
        running = {f for f in pending if not f.cancelled()}
        deadline = time.monotonic() + grace
        while running and time.monotonic() < deadline:
            done, running = wait(running, timeout=0.2, return_when=FIRST_COMPLETED)
            self.stop_started()
            for fut in done:
                self.finish(fut)
        for fut in running:   # did not stop within the grace period
            t = self.futures[fut]
            record_interrupted(t.folder, "stopped: did not end within the grace period")
            self.on_event("finished", t.case_id, interrupted_result(t.case_id))
        for fut in pending:
            if fut.cancelled():
                case_id = self.futures[fut].case_id
                self.on_event("finished", case_id, {"case_id": case_id, "status": "pending", "skipped": True})


# ---- slurm ----------------------------------------------------------------------------------
#: SLURM job states → (case status, cause) for jobs that ended without the runner's own verdict
SLURM_DEATH = {
    "TIMEOUT": ("killed", "slurm_timeout"),
    "CANCELLED": ("killed", "slurm_cancelled"),
    "NODE_FAIL": ("killed", "slurm_node_fail"),
    "OUT_OF_MEMORY": ("killed", "slurm_out_of_memory"),
    "BOOT_FAIL": ("killed", "slurm_boot_fail"),
    "DEADLINE": ("killed", "slurm_deadline"),
    "PREEMPTED": ("interrupted", "slurm_preempted"),
    "FAILED": ("failed", "slurm_job_failed"),
    "COMPLETED": ("failed", "slurm_no_result"),
}
ACTIVE_STATES = ("PENDING", "RUNNING", "REQUEUED", "RESIZING", "SUSPENDED", "CONFIGURING", "COMPLETING",
                 "REQUEUE_HOLD", "REQUEUE_FED", "SIGNALING", "STAGE_OUT")
#: states of a job SLURM requeued, which will run its task again (not REQUEUE_HOLD: held until released)
REQUEUED_STATES = ("PENDING", "REQUEUED", "REQUEUE_FED")
#: [s] how long a task that recorded an interruption may wait for SLURM's final job state (TIMEOUT,
#: CANCELLED, PREEMPTED), whose cause replaces the runner's 'interrupted'
SLURM_VERDICT_WAIT = 60.0


def _slurm_task(case: Case, engine: EngineSpec, folder: str, meta: dict) -> dict:
    """Body of one SLURM array task: the same runner as the local pool.

    SIGTERM (SLURM's time limit, scancel, preemption) becomes a recorded interruption: the engine is
    killed, failure.json written; the orchestrator then replaces the cause with SLURM's (from the job
    state: timeout, cancelled, ...). submitit's own handler would ignore SIGTERM."""
    signal.signal(signal.SIGTERM, _raise_interrupted)
    try:
        return run_case(case, engine, folder, meta)
    except Interrupted as exc:
        return interrupted_result(meta["case_id"], f"stopped by {exc.reason} (SLURM)")


class SlurmExecutor:
    name = "slurm"

    def __init__(self, root: Path, *, partition: str | None = None, max_concurrent: int = 16,
                 time_limit: Callable[[Case], int], job_name: str = "interphase", poll: float = 1.0):
        self.root = Path(root)
        self.partition = partition
        self.max_concurrent = max_concurrent
        self.time_limit = time_limit
        self.job_name = job_name
        self.poll = poll
        self.jobs_file = self.root / ".submitit" / "jobs.json"

    # submitted job ids survive a killed `campaign run`: a rerun adopts the jobs still alive
    def _load_jobs(self) -> dict:
        try:
            return json.loads(self.jobs_file.read_text())
        except (OSError, ValueError):
            return {}

    def _save_jobs(self, jobs: dict) -> None:
        self.jobs_file.parent.mkdir(parents=True, exist_ok=True)
        st.write_json_atomic(self.jobs_file, jobs)

    @staticmethod
    def _squeue_states(job_ids) -> dict[str, str]:
        ids = sorted({j.split("_")[0] for j in job_ids})
        if not ids:
            return {}
        out = subprocess.run(["squeue", "--states=all", "--noheader", "--array", "--format=%i|%T",
                              "--jobs", ",".join(ids)], capture_output=True, text=True)
        states = {}
        for line in out.stdout.splitlines():
            jid, _, state = line.partition("|")
            states[jid.strip()] = state.strip()
        return states

    def run(self, tasks: list[Task], on_event: OnEvent) -> None:
        if not tasks:
            return
        import submitit

        subfolder = self.root / ".submitit"
        known = self._load_jobs()
        alive = self._squeue_states([known[t.case_id] for t in tasks if t.case_id in known])
        active: dict[str, tuple] = {}      # case id → (job, task)
        to_submit = []
        for t in tasks:
            jid = known.get(t.case_id)
            if jid and alive.get(jid) in ACTIVE_STATES:
                active[t.case_id] = (submitit.SlurmJob(folder=subfolder / "%j", job_id=jid), t)
            else:
                to_submit.append(t)
        buckets: dict[int, list[Task]] = {}
        for t in to_submit:
            buckets.setdefault(self.time_limit(t.case), []).append(t)
        ex = submitit.SlurmExecutor(folder=subfolder / "%j")
        for minutes, bucket in sorted(buckets.items()):
            # use_srun=False: the task runs in the batch step itself. Inside an srun step the Debian
            # LIGGGHTS (OpenMPI) tries to join the step's PMIx and dies ("OPAL ERROR: Unreachable").
            # Then submitit's USR2 warning reaches no one; SLURM's SIGTERM at the limit does, and
            # preemption is SLURM's own requeue (--requeue).
            params = dict(time=minutes, array_parallelism=self.max_concurrent, cpus_per_task=1, ntasks_per_node=1,
                          job_name=self.job_name, use_srun=False, additional_parameters={"requeue": True})
            if self.partition:
                params["partition"] = self.partition
            ex.update_parameters(**params)
            with ex.batch():
                jobs = [ex.submit(_slurm_task, t.case, t.engine, str(t.folder), t.meta) for t in bucket]
            for job, t in zip(jobs, bucket):
                active[t.case_id] = (job, t)
                known[t.case_id] = job.job_id
            self._save_jobs(known)
        announced: set[str] = set()
        interrupted_at: dict[str, float] = {}
        try:
            while active:
                time.sleep(self.poll)
                states = self._squeue_states([job.job_id for job, _ in active.values()])
                for cid, (job, t) in list(active.items()):
                    state = states.get(job.job_id, "")
                    if state == "RUNNING" and cid not in announced:
                        announced.add(cid)
                        on_event("started", cid, {"slurm_job": job.job_id})
                    final = bool(state) and state not in ACTIVE_STATES
                    if not (final or job.paths.result_pickle.exists()):
                        continue
                    fs = st.folder_status(t.folder)
                    if not final and (state in REQUEUED_STATES or fs in ("pending", "incomplete")):
                        # requeued (scontrol requeue, preemption): the job runs the case again; the
                        # result pickle is the stopped run's. Wait for the new run, announce its start
                        interrupted_at.pop(cid, None)
                        if state != "RUNNING":
                            announced.discard(cid)
                        continue
                    if not final and fs == "interrupted":
                        # the task caught SIGTERM and returned before SLURM closed the job: its
                        # state (TIMEOUT, CANCELLED, ...) is the verdict, wait for it a while
                        since = interrupted_at.setdefault(cid, time.monotonic())
                        if time.monotonic() - since < SLURM_VERDICT_WAIT:
                            continue
                    on_event("finished", cid, self._collect(job, t, state))
                    del active[cid]
        except (KeyboardInterrupt, Interrupted):
            for cid, (job, t) in active.items():
                try:
                    job.cancel(check=False)
                except Exception:   # noqa: BLE001 — best effort; the job dies with its time limit anyway
                    pass
            for cid, (job, t) in active.items():
                record_interrupted(t.folder, f"stopped: SLURM job {job.job_id} cancelled by the user")
                on_event("finished", cid, interrupted_result(cid, f"SLURM job {job.job_id} cancelled"))
            raise

    def _collect(self, job, task: Task, state: str) -> dict:
        """The case's verdict: the runner's (from the folder) if it gave one, else SLURM's cause of death."""
        cid = task.case_id
        result = None
        try:
            result = job.result()
        except Exception as exc:  # noqa: BLE001 — FailedJobError, UncompletedJobError: decided below
            error = exc
        else:
            error = None
        fs = st.folder_status(task.folder)
        base_state = (state.split()[0] if state else "")
        slurm_killed = base_state in SLURM_DEATH and SLURM_DEATH[base_state][1] not in ("slurm_job_failed",
                                                                                       "slurm_no_result")
        if fs in ("done", "failed", "killed", "interrupted") and not (slurm_killed and fs != "done"):
            if isinstance(result, dict) and result.get("status") == fs:
                return result | {"slurm_job": job.job_id}
            fail = st.read_json(task.folder / st.FAILURE_JSON) or {}
            return {"case_id": cid, "status": fs, "cause": fail.get("cause"), "message": fail.get("message"),
                    "elapsed": fail.get("elapsed"), "slurm_job": job.job_id}
        # SLURM killed the job (its verdict wins over what the engine said as it died), or the job
        # died before the runner could say anything
        runner = st.read_json(task.folder / st.FAILURE_JSON) or {}
        if not base_state:
            try:
                base_state = job.watcher.get_state(job.job_id, mode="force").split()[0]
            except Exception:  # noqa: BLE001
                base_state = "UNKNOWN"
        status, cause = SLURM_DEATH.get(base_state, ("killed", f"slurm_{base_state.lower()}"))
        tail = ""
        try:
            tail = "\n".join((job.stderr() or "").splitlines()[-30:])
        except Exception:  # noqa: BLE001
            pass
        message = f"SLURM job {job.job_id} ended in state {base_state}"
        if error is not None:
            message += f": {str(error).splitlines()[0][:300]}"
        task.folder.mkdir(parents=True, exist_ok=True)
        if not (task.folder / st.CASE_JSON).exists():
            st.write_json_atomic(task.folder / st.CASE_JSON, {**task.meta, "inputs": task.case.canonical(),
                                                             "started": None})
        now = time.time()
        st.write_json_atomic(task.folder / st.FAILURE_JSON, {
            "status": status, "cause": cause, "message": message, "slurm_job": job.job_id,
            "slurm_state": base_state, "finished": now, "started": runner.get("started"),
            "elapsed": runner.get("elapsed"), "log_tail": runner.get("log_tail") or tail,
            "runner_cause": runner.get("cause"), "runner_message": runner.get("message")})
        st.append_attempt(task.folder, {"event": "end", "status": status, "cause": cause, "time": now,
                                        "slurm_job": job.job_id})
        return {"case_id": cid, "status": status, "cause": cause, "message": message, "elapsed": None,
                "slurm_job": job.job_id}
