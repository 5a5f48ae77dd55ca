"""The fault suite (issue 17, item 5; docs/reliability.md): every fault injected for real into tiny real
LIGGGHTS campaigns (75 grains, a few seconds per case). For each: no finished case lost, no
half-written case counted as done, and a message that names the case and the cause.

Faults already covered elsewhere are not repeated here (docs/reliability.md lists them): SIGKILL of
the campaign's process group, Ctrl-C, SIGTERM to the campaign, a lock held by another run
(tests/test_campaign_run.py); a corrupt Parquet, an edited case.json, a deleted or broken index
(tests/test_store_verify.py); a SLURM time-out (tests/test_campaign_slurm.py); a truncated dump read
by the engine's reader (tests/test_liggghts.py).

Processes are found by their working folder under this test's tmp path (runner.stale_engine_pids)
and signalled by PID: nothing else on the machine is touched.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import pytest

from tests.conftest import need_binary
from tests.campaign_files import write_toml
from tests.test_campaign_run import TABLES, _folders, _group_ends, _no_engine_left, _starts, _wait_for

from interphase.campaign.run import campaign_status
from interphase.campaign.runner import stale_engine_pids
from interphase.campaign.store import folder_status

pytestmark = pytest.mark.liggghts


def _campaign(tmp_path: Path, seeds=(1, 2, 3), jobs: int = 1, name: str = "faults") -> Path:
    """Tiny real cases (test_campaign_run's): μs 0.2, one seed each, ~8 s of LIGGGHTS per case."""
    return write_toml(tmp_path / f"{name}.toml", **(TABLES | {
        "campaign": TABLES["campaign"] | {"name": name}, "execution": {"jobs": jobs},
        "sweep": {"friction_ps": [0.2], "seed": list(seeds)}}))


def _start(toml: Path, env: dict | None = None, *args) -> tuple[subprocess.Popen, Path]:
    """`campaign run` in its own session (like a shell job); its output to a file read while it runs."""
    log = toml.with_suffix(f".{time.monotonic_ns()}.log")
    proc = subprocess.Popen([sys.executable, "-m", "interphase.cli", "run", str(toml), "--plain", *args],
                            cwd=toml.parent, stdout=open(log, "w"), stderr=subprocess.STDOUT, text=True,
                            start_new_session=True, env=env)
    return proc, log


@contextmanager
def _running(toml: Path, env: dict | None = None, *args):
    """`campaign run` started as by `_start`, yielding (proc, log); on leaving the block (a failed
    assertion or wait included) its whole process group is killed if the campaign still runs."""
    proc, log = _start(toml, env, *args)
    try:
        yield proc, log
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def _finish(proc: subprocess.Popen, log: Path, timeout: float = 240) -> str:
    proc.wait(timeout=timeout)
    return log.read_text()


def _seed(folder: Path) -> int | None:
    try:
        return json.loads((folder / "case.json").read_text())["inputs"]["seed"]
    except (OSError, ValueError, KeyError):
        return None


def _by_seed(out: Path) -> dict[int, Path]:
    return {_seed(f): f for f in _folders(out) if _seed(f) is not None}


def _engine(folder: Path) -> int | None:
    """PID of the LIGGGHTS process running in `folder` (not its MPI helper), None if none."""
    for pid in stale_engine_pids(folder):
        try:
            if Path(f"/proc/{pid}/comm").read_text().strip() == "liggghts":
                return pid
        except OSError:
            continue
    return None


def _worker_pid(folder: Path) -> int:
    starts = [json.loads(x) for x in (folder / "attempts.jsonl").read_text().splitlines() if '"start"' in x]
    return starts[-1]["pid"]


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _status(toml: Path) -> dict[str, dict]:
    _, _, df = campaign_status(toml)
    return {r["case_id"]: r for r in df.to_dict("records")}


def _failure(folder: Path) -> dict:
    return json.loads((folder / "failure.json").read_text())


def _no_traceback(text: str) -> None:
    assert "Traceback" not in text, text


# ---- the campaign process and its workers ----------------------------------------------------
def test_sigkill_of_the_campaign_process_alone_stops_its_worker(tmp_path):
    """`kill -9` of the campaign process alone (what the out-of-memory killer does): its pool worker
    used to live on, finish the running case unwatched, start the next one it had been handed, then
    idle forever. Now the worker notices (parent gone), records its case interrupted, kills its
    engine and exits; the finished case is untouched."""
    need_binary("liggghts")
    toml = _campaign(tmp_path, jobs=1)
    out = tmp_path / "out"
    with _running(toml) as (proc, log):
        _wait_for(lambda: any(folder_status(f) == "done" for f in _folders(out)) and
                  any(_engine(f) for f in _folders(out) if folder_status(f) == "incomplete"), 150,
                  "one finished case and a running engine")
        proc.send_signal(signal.SIGKILL)                 # the campaign process only, not its group
        proc.wait()
    (done,) = [f for f in _folders(out) if folder_status(f) == "done"]
    done_mtime = (done / "DONE").stat().st_mtime_ns
    (running,) = [f for f in _folders(out) if f != done]
    worker = _worker_pid(running)
    _wait_for(lambda: not _alive(worker), 20, f"worker {worker} to end after its campaign process died")
    _group_ends(proc.pid)                                 # no process left that could take the next case
    _no_engine_left(out)
    assert len(_folders(out)) == 2, "a case was started after the campaign process died"
    fail = _failure(running)
    assert folder_status(running) == "interrupted" and not (running / "DONE").exists()
    assert fail["cause"] == "interrupted" and f"campaign process (pid {proc.pid}) died" in fail["message"]
    assert (done / "DONE").stat().st_mtime_ns == done_mtime and (done / "history.parquet").exists()
    st = _status(toml)
    assert st[done.name]["status"] == "done" and st[running.name]["status"] == "interrupted"
    assert "campaign process" in st[running.name]["message"]
    assert sum(r["status"] == "pending" for r in st.values()) == 1


def test_sigkill_of_a_worker_mid_case(tmp_path):
    """`kill -9` of one pool worker while its engine runs. A dead worker breaks the whole pool, which
    used to stop the local run (issue 32: one dead worker stopped everything). Now: the dead
    worker's case is recorded (worker_died, its engine killed), a new pool runs the case the broken
    pool stopped and the queued one, both finish; exit 1 (one case unfinished), no traceback; the next
    `campaign run` runs the dead worker's case."""
    need_binary("liggghts")
    toml = _campaign(tmp_path, jobs=2)
    out = tmp_path / "out"
    with _running(toml) as (proc, log):
        _wait_for(lambda: sum(bool(_engine(f)) for f in _folders(out)) == 2, 150, "two running engines")
        victim = sorted(_folders(out), key=lambda f: f.name)[0]
        other = [f for f in _folders(out) if f != victim][0]
        worker = _worker_pid(victim)
        os.kill(worker, signal.SIGKILL)
        text = _finish(proc, log, 240)
    assert proc.returncode == 1, text
    _no_traceback(text)
    _no_engine_left(out)
    line = next(ln for ln in text.splitlines() if victim.name in ln and "interrupted" in ln)
    assert "[worker_died]" in line and f"worker process (pid {worker}) died" in line, text
    assert "a new pool of workers runs the 2 case(s)" in text, text
    fail = _failure(victim)
    assert fail["cause"] == "worker_died" and folder_status(victim) == "interrupted"
    assert folder_status(other) == "done" and len(_folders(out)) == 3, text
    st = _status(toml)
    assert st[victim.name]["cause"] == "worker_died"
    assert sorted(r["status"] for r in st.values()) == ["done", "done", "interrupted"]
    again = subprocess.run([sys.executable, "-m", "interphase.cli", "run", str(toml), "--plain"], cwd=toml.parent,
                           capture_output=True, text=True, timeout=240)
    assert again.returncode == 0, again.stdout + again.stderr
    assert sorted(r["status"] for r in _status(toml).values()) == ["done"] * 3


# ---- the engine --------------------------------------------------------------------------------
WRAPPER = """#!/bin/bash
# the real LIGGGHTS; in the seed-3 case its contact dump is then cut to half its size
if [[ " $* " == *" -in "* ]] && grep -q '"seed": 3' case.json 2>/dev/null; then
  {binary} "$@"; rc=$?
  f=contacts_pair.dump; truncate -s $(( $(stat -c %s "$f") / 2 )) "$f"
  exit $rc
fi
exec {binary} "$@"
"""


def test_engine_killed_crashed_or_truncated_dump(tmp_path):
    """Three cases at once: LIGGGHTS killed (SIGKILL) mid-run, LIGGGHTS segfaulting (SIGSEGV sent to
    the real engine mid-run), and a run whose contact dump is truncated after the engine ended
    (a wrapper on INTERPHASE_LIGGGHTS_BINARY). Each is a failed case with its own cause and a
    message naming it; none is done, none left a table behind."""
    binary = need_binary("liggghts")
    wrapper = tmp_path / "liggghts-wrapper"
    wrapper.write_text(WRAPPER.format(binary=binary))
    wrapper.chmod(0o755)
    toml = _campaign(tmp_path, jobs=2)
    out = tmp_path / "out"
    signalled = {}
    with _running(toml, dict(os.environ, INTERPHASE_LIGGGHTS_BINARY=str(wrapper))) as (proc, log):
        def engines_up():
            by = _by_seed(out)
            return all(s in by and _engine(by[s]) for s in (1, 2))
        _wait_for(engines_up, 150, "the engines of seeds 1 and 2")
        time.sleep(1.0)                                   # mid-run
        by = _by_seed(out)
        for seed, sig in ((1, signal.SIGKILL), (2, signal.SIGSEGV)):
            pid = _engine(by[seed])
            assert pid, f"seed {seed}'s engine ended before it could be signalled"
            os.kill(pid, sig)
            signalled[seed] = pid
        text = _finish(proc, log)
    assert proc.returncode == 1, text
    _no_traceback(text)
    _no_engine_left(out)
    by = _by_seed(out)
    expect = {1: ("killed", "LIGGGHTS was killed by SIGKILL"),
              2: ("crashed", "LIGGGHTS crashed (SIGSEGV, Segmentation fault)"),
              3: ("read_error", "contacts_pair.dump")}
    st = _status(toml)
    for seed, (cause, words) in expect.items():
        folder = by[seed]
        fail = _failure(folder)
        assert fail["status"] == "failed" and fail["cause"] == cause and words in fail["message"], (seed, fail)
        assert not (folder / "DONE").exists() and not list(folder.glob("*.parquet"))
        assert st[folder.name]["status"] == "failed" and st[folder.name]["cause"] == cause
        line = next(ln for ln in text.splitlines() if folder.name in ln and "failed" in ln)
        assert f"[{cause}]" in line, line            # the progress line cuts messages at 120 characters
        assert words in line or seed == 3, line
    assert "truncated or corrupt" in _failure(by[3])["message"]
    # kept as failed: a plain rerun does not retry them (--rerun-failed does)
    again = subprocess.run([sys.executable, "-m", "interphase.cli", "run", str(toml), "--plain", "--dry-run"],
                           cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert sum(ln.split()[:2] == ["skip", "(failed)"] for ln in again.stdout.splitlines()) == 3, again.stdout


def test_engine_hung_past_its_time_limit(tmp_path):
    """The real engine hangs (SIGSTOP mid-run) past its time limit (INTERPHASE_LIGGGHTS_TIMEOUT):
    it is killed with its process group, the case fails with cause timeout, nothing left running."""
    need_binary("liggghts")
    toml = _campaign(tmp_path, seeds=(1,))
    out = tmp_path / "out"
    with _running(toml, dict(os.environ, INTERPHASE_LIGGGHTS_TIMEOUT="6")) as (proc, log):
        _wait_for(lambda: any(_engine(f) for f in _folders(out)), 150, "a running engine")
        (folder,) = _folders(out)
        os.kill(_engine(folder), signal.SIGSTOP)         # hung: alive, never ending
        t0 = time.monotonic()
        text = _finish(proc, log, 120)
    assert proc.returncode == 1, text
    assert time.monotonic() - t0 < 60, "the time limit did not stop the hung engine"
    _no_engine_left(out)
    fail = _failure(folder)
    assert fail["status"] == "failed" and fail["cause"] == "timeout"
    assert "LIGGGHTS ran longer than 6 s" in fail["message"] and not (folder / "DONE").exists()
    assert "[timeout] LIGGGHTS ran longer than 6 s" in next(ln for ln in text.splitlines() if folder.name in ln
                                                             and "failed" in ln)


# ---- the disk ----------------------------------------------------------------------------------
@pytest.fixture
def small_disk(tmp_path):
    """A 700 kB tmpfs: room for one finished tiny case (~400 kB), not two. Skipped where mounting is
    not permitted (not root, or a container without CAP_SYS_ADMIN)."""
    mnt = tmp_path / "out"
    mnt.mkdir()
    try:
        r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=700k", "tmpfs", str(mnt)], capture_output=True,
                           text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired) as exc:
        pytest.skip(f"cannot mount a small tmpfs to fill: {exc}")
    if r.returncode != 0:
        pytest.skip(f"cannot mount a small tmpfs to fill (needs root / CAP_SYS_ADMIN): {r.stderr.strip()}")
    try:
        yield mnt
    finally:
        for folder in _folders(mnt):
            for pid in stale_engine_pids(folder):
                os.kill(pid, signal.SIGKILL)
        subprocess.run(["umount", "-l", str(mnt)], capture_output=True, timeout=30)


def test_disk_fills_mid_case(tmp_path, small_disk):
    """The output file system fills while the second case runs. LIGGGHTS does not notice (its dumps
    are cut short, return code 0); the run used to crash with a traceback (ENOSPC writing
    failure.json, then 'database or disk is full'). Now: the finished case is kept, each case that
    ran out of space is recorded interrupted with cause disk_full (its partial engine output removed
    to make room for the record), the run stops there (the next case would fill the disk too), exit
    1, no traceback; with space again, a rerun finishes them."""
    toml = _campaign(tmp_path, jobs=1)
    out = small_disk
    with _running(toml) as (proc, log):
        text = _finish(proc, log, 240)
    assert proc.returncode == 1, text
    _no_traceback(text)
    _no_engine_left(out)
    done = [f for f in _folders(out) if folder_status(f) == "done"]
    full = [f for f in _folders(out) if folder_status(f) != "done"]
    assert len(done) == 1 and full, text
    assert "stopped: the disk is full" in text and "Free some space" in text
    # the pool may have handed the worker its next case already: stopped at once, not run
    cut = [f for f in full if _failure(f)["cause"] != "disk_full"]
    assert len(full) - len(cut) == 1 and all(_failure(f)["status"] == "interrupted" for f in cut), text
    full = [f for f in full if f not in cut]
    for f in full:
        fail = _failure(f)
        assert fail["status"] == "interrupted" and fail["cause"] == "disk_full", fail
        assert "no space left on device" in fail["message"] and str(f) in fail["message"]
        assert not (f / "DONE").exists() and not list(f.glob("*.dump"))
        line = next(ln for ln in text.splitlines() if f.name in ln and "interrupted" in ln)
        assert "[disk_full] no space left on device" in line
    st = _status(toml)
    assert st[done[0].name]["status"] == "done"
    assert all(st[f.name]["status"] == "interrupted" and st[f.name]["cause"] == "disk_full" for f in full)
    assert len(_folders(out)) < 3 or cut
    # room again: the rerun finishes the rest, the finished case is not recomputed
    mtime, starts = (done[0] / "DONE").stat().st_mtime_ns, _starts(done[0])
    subprocess.run(["mount", "-o", "remount,size=3m", str(out)], check=True, capture_output=True, timeout=30)
    with _running(toml, None, "--jobs", "2") as (proc, log):      # the two left, side by side
        text = _finish(proc, log, 240)
    assert proc.returncode == 0, text
    assert (done[0] / "DONE").stat().st_mtime_ns == mtime and _starts(done[0]) == starts
    assert all(folder_status(f) == "done" for f in _folders(out)) and len(_folders(out)) == 3


# ---- concurrent commands -----------------------------------------------------------------------
def test_second_run_status_and_a_deleted_index_while_a_run_writes(tmp_path, capsys):
    """While one `campaign run` works: a second `campaign run` of the same campaign (a real process)
    stops at once (exit 2, one line naming the lock holder's folder); `campaign status` called over
    and over never shows a case done whose folder has no DONE; the index deleted mid-run is rebuilt
    from the folders by the next status, and the run finishes every case exactly once."""
    from interphase.cli import main

    need_binary("liggghts")
    toml = _campaign(tmp_path, seeds=(1, 2), jobs=1)      # one finished while the other runs: enough
    out = tmp_path / "out"
    seen: dict[str, set] = {}
    with _running(toml) as (proc, log):
        _wait_for(lambda: any(_engine(f) for f in _folders(out)), 150, "a running engine")
        second = subprocess.run([sys.executable, "-m", "interphase.cli", "run", str(toml), "--plain"],
                                cwd=tmp_path, capture_output=True, text=True, timeout=120)
        assert second.returncode == 2, second.stdout + second.stderr
        assert "another `campaign run` is using this campaign right now" in second.stderr
        assert str(out) in second.stderr and len(second.stderr.strip().splitlines()) == 1
        deleted = False
        while proc.poll() is None:
            # the index goes only after one status was read through it: on a loaded machine the first
            # case can finish while the second `campaign run` starts, before any status was read
            if not deleted and seen and any(folder_status(f) == "done" for f in _folders(out)):
                for name in ("index.sqlite", "index.sqlite-wal", "index.sqlite-shm"):
                    (out / name).unlink(missing_ok=True)
                deleted = True
            assert main(["status", str(toml), "--json"]) == 0
            cases = json.loads(capsys.readouterr().out)["cases"]
            for c in cases:
                # the run's word while its index is there (a deleted index is rebuilt from folders)
                if not deleted:
                    seen.setdefault(c["case_id"], set()).add(c["status"])
                if c["status"] == "done":          # never done before its DONE exists
                    assert (out / c["case_id"] / "DONE").exists(), c
            time.sleep(0.3)
        text = _finish(proc, log)
    assert proc.returncode == 0, text
    assert deleted, "the run ended before a case finished"
    assert len(_folders(out)) == 2 and all(_starts(f) == 1 for f in _folders(out))
    st = _status(toml)
    assert all(r["status"] == "done" for r in st.values()), st
    # the run's word while it runs, not the folders' (a started folder without DONE is not "incomplete")
    assert not any("incomplete" in v for v in seen.values()), seen
    assert any("running" in v for v in seen.values()), seen


# ---- SLURM -------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def slurm(tmp_path_factory):
    from tests.slurm_cluster import SlurmCluster

    need_binary("liggghts")
    with SlurmCluster(tmp_path_factory.mktemp("slurm")) as cluster:
        yield cluster


def _job_of(out: Path, folder: Path) -> str:
    return json.loads((out / ".submitit" / "jobs.json").read_text())[folder.name]


def _squeue(env: dict, job: str) -> str:
    return subprocess.run(["squeue", "--states=all", "--array", "--noheader", "--format=%i %T %r %S", "--jobs",
                           job.split("_")[0]], env=env, capture_output=True, text=True, timeout=30).stdout


@pytest.mark.slurm
def test_slurm_job_cancelled_and_requeued(slurm, tmp_path):
    """Two cases on a real one-node SLURM; while their engines run, one job is cancelled (scancel)
    and the other requeued (scontrol requeue). The cancelled case is killed with SLURM's cause
    (slurm_cancelled), kept, not done; the requeued one runs again and finishes (done once)."""
    toml = _campaign(tmp_path, seeds=(1, 2))
    toml.write_text(toml.read_text().replace("jobs = 1", 'executor = "slurm"\ntime_limit = 5\nmax_concurrent = 2'))
    out = tmp_path / "out"
    env = slurm.env()
    with _running(toml, env) as (proc, log):
        _wait_for(lambda: sum(bool(_engine(f)) for f in _by_seed(out).values()) == 2, 150, "two running engines")
        by = _by_seed(out)
        cancelled, requeued = by[1], by[2]
        subprocess.run(["scancel", _job_of(out, cancelled)], env=env, check=True, timeout=30)
        job = _job_of(out, requeued)
        subprocess.run(["scontrol", "requeue", job], env=env, check=True, timeout=30, capture_output=True)
        # SLURM holds a requeued job back (reason BeginTime) until the old credential expires (the
        # test cluster's cred_expire, 10 s; 120 s by default), then starts it again by itself; a job
        # released sooner (scontrol update StartTime=now) is refused by slurmd: "Job credential revoked"
        _wait_for(lambda: "BeginTime" in _squeue(env, job), 60, "the requeued job to be held pending")
        text = _finish(proc, log, 300)
    _no_traceback(text)
    st = _status(toml)
    fail = _failure(cancelled)
    assert fail["status"] == "killed" and fail["cause"] == "slurm_cancelled" and fail["slurm_state"] == "CANCELLED"
    assert f"SLURM job {_job_of(out, cancelled)} ended in state CANCELLED" in fail["message"]
    assert not (cancelled / "DONE").exists()
    assert st[cancelled.name]["status"] == "killed" and st[cancelled.name]["cause"] == "slurm_cancelled"
    line = next(ln for ln in text.splitlines() if cancelled.name in ln and "killed" in ln)
    assert "[slurm_cancelled] SLURM job" in line
    assert st[requeued.name]["status"] == "done", (st[requeued.name], text)
    assert (requeued / "DONE").exists() and (requeued / "history.parquet").exists()
    events = [json.loads(x)["event"] for x in (requeued / "attempts.jsonl").read_text().splitlines()]
    assert events == ["start", "end", "start", "end"]      # stopped once by the requeue, then finished
    assert proc.returncode == 1, text                     # one case killed
