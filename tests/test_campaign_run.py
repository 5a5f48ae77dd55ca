"""`campaign run` locally with the real LIGGGHTS: resumable after SIGKILL, clean Ctrl-C, lock,
dry run, --rerun-failed, and an index rebuilt from the case folders."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.campaign_files import TINY_CASE, write_toml
from tests.conftest import need_binary

from interphase.campaign.runner import stale_engine_pids
from interphase.campaign.store import CampaignStore, folder_status
from interphase.cli import main

pytestmark = pytest.mark.liggghts

# six tiny real cases of a few seconds each (slow shear so that a run can be caught mid-way)
TABLES = dict(campaign={"name": "resume", "engines": ["liggghts"], "output": "out"},
              execution={"jobs": 2},
              case={**TINY_CASE, "shear_velocity": 0.01},
              sweep={"friction_ps": [0.05, 0.2, 0.5], "seed": [1, 2]},
              pairs={"box": False})


@pytest.fixture
def campaign(tmp_path):
    need_binary("liggghts")
    return write_toml(tmp_path / "resume.toml", **TABLES)


def _start(camp: Path, *args) -> subprocess.Popen:
    # own process group, like a shell job: the test signals the whole group
    return subprocess.Popen([sys.executable, "-m", "interphase.cli", "run", str(camp), "--plain", *args],
                            cwd=camp.parent, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True)


def _folders(out: Path) -> list[Path]:
    return [p for p in out.iterdir() if p.is_dir() and (p / "case.json").exists()] if out.exists() else []


def _starts(folder: Path) -> int:
    """Attempts started in a folder; 0 if the kill came between its case.json and attempts.jsonl."""
    path = folder / "attempts.jsonl"
    return sum('"event": "start"' in line for line in path.read_text().splitlines()) if path.exists() else 0


def _wait_for(cond, timeout: float, what: str):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if cond():
            return
        time.sleep(0.05)
    pytest.fail(f"timed out waiting for {what}")


def _group_ends(pgid: int, timeout: float = 60) -> None:
    """Wait until no process is left in the campaign's process group (its workers, and engines started
    in it): after that no late worker can start a case, however loaded the machine, so a check made
    then does not depend on how long one sleeps."""
    def gone() -> bool:
        try:
            os.killpg(pgid, 0)
        except ProcessLookupError:
            return True
        return False

    _wait_for(gone, timeout, f"every process of the campaign's group {pgid} to end")


def _no_engine_left(out: Path) -> None:
    # engines are killed and waited for before their worker reports the case, and the campaign waits
    # for its workers: an engine alive once the campaign has exited was left running (CI of stop 60:
    # a signal landing inside Popen did that, engines.base.run_logged holds it now)
    for folder in _folders(out):
        assert stale_engine_pids(folder) == [], f"engine still running in {folder}"


def test_sigkill_midway_then_rerun_recomputes_only_unfinished(campaign):
    out = campaign.parent / "out"
    proc = _start(campaign)
    try:
        def midway():
            done = [f for f in _folders(out) if (f / "DONE").exists()]
            running = [f for f in _folders(out) if not (f / "DONE").exists()]
            return len(done) >= 2 and running
        _wait_for(midway, 120, "two finished cases and one running")
    finally:
        os.killpg(proc.pid, signal.SIGKILL)          # the whole process group, no chance to clean up
        proc.wait()
    done_before = {f.name: ((f / "DONE").stat().st_mtime_ns, _starts(f)) for f in _folders(out)
                   if (f / "DONE").exists()}
    # a folder may exist before its case starts (0 attempts) or be cut mid-run (1 attempt)
    unfinished = {f.name: _starts(f) for f in _folders(out) if not (f / "DONE").exists()}
    assert len(done_before) >= 2 and unfinished
    # a finished folder is complete; an unfinished one never counts as done
    for cid in done_before:
        assert (out / cid / "summary.json").exists() and (out / cid / "history.parquet").exists()
    for cid in unfinished:
        assert folder_status(out / cid) == "incomplete"
    with CampaignStore(out) as store:
        st = store.status().set_index("case_id")["status"]
    assert all(st[cid] != "done" for cid in unfinished)

    rerun = subprocess.run([sys.executable, "-m", "interphase.cli", "run", str(campaign), "--plain"],
                           cwd=campaign.parent, capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stdout + rerun.stderr
    assert f"{len(done_before)} finished" in rerun.stdout
    for cid, (mtime, starts) in done_before.items():
        # not recomputed: DONE untouched, no new attempt
        assert (out / cid / "DONE").stat().st_mtime_ns == mtime
        assert _starts(out / cid) == starts
    for cid, starts in unfinished.items():
        assert (out / cid / "DONE").exists() and _starts(out / cid) == starts + 1   # recomputed once
    assert len(_folders(out)) == 6 and all((f / "DONE").exists() for f in _folders(out))
    _no_engine_left(out)

    # the index is a cache: lost, it is rebuilt from the folders
    (out / "index.sqlite").unlink()
    for extra in ("index.sqlite-wal", "index.sqlite-shm"):
        (out / extra).unlink(missing_ok=True)
    with CampaignStore(out) as store:
        df = store.summaries()
    assert len(df) == 6 and set(df["status"]) == {"done"}
    assert {"case_id", "engine", "group", "label", "friction_ps", "seed", "profile_kind", "rt", "shear_modulus",
            "peak_stress_ratio"} <= set(df.columns)
    assert sorted(df["friction_ps"].unique()) == [0.05, 0.2, 0.5]
    assert df["peak_stress_ratio"].notna().all()


def test_ctrl_c_stops_cleanly_and_records_interrupted(campaign):
    out = campaign.parent / "out"
    proc = _start(campaign)
    _wait_for(lambda: any(not (f / "DONE").exists() for f in _folders(out)) and
              any(stale_engine_pids(f) for f in _folders(out)), 120, "a running engine")
    os.killpg(proc.pid, signal.SIGINT)               # what a terminal's Ctrl-C does
    text, _ = proc.communicate(timeout=120)
    assert proc.returncode == 130, text
    assert "interrupted" in text
    interrupted = [f for f in _folders(out) if folder_status(f) == "interrupted"]
    assert interrupted, text
    for f in interrupted:
        assert not (f / "DONE").exists()
        assert json.loads((f / "failure.json").read_text())["cause"] == "interrupted"
    statuses = {f.name: folder_status(f) for f in _folders(out)}
    assert set(statuses.values()) <= {"done", "interrupted"}, (statuses, text)
    _no_engine_left(out)


def test_sigterm_to_the_campaign_alone_starts_no_case_after_it(campaign):
    # `kill PID` of the campaign (not its group): the pool has already handed a worker its next
    # task, which starts after the interruption; it must be stopped too, not run on unwatched
    out = campaign.parent / "out"
    proc = _start(campaign, "--jobs", "1")
    _wait_for(lambda: any(stale_engine_pids(f) for f in _folders(out)), 120, "a running engine")
    done_before = sum((f / "DONE").exists() for f in _folders(out))
    proc.send_signal(signal.SIGTERM)
    text, _ = proc.communicate(timeout=120)
    assert proc.returncode != 0 and "interrupted" in text, text
    _group_ends(proc.pid)                             # no worker left that could start a case late
    _no_engine_left(out)
    # nothing ran to its end after the signal: the running case and the queued one are interrupted
    assert sum((f / "DONE").exists() for f in _folders(out)) == done_before, text
    assert all(folder_status(f) in ("done", "interrupted") for f in _folders(out)), text
    assert not any((f / "DONE").exists() for f in _folders(out) if folder_status(f) == "interrupted")


def test_stop_lets_the_running_case_finish_and_starts_no_other(campaign, capsys):
    """`campaign stop`: the case running when it is asked runs to its end (DONE), no case after it
    runs to its end (the one the pool had already handed a worker is stopped as it starts), the run
    ends with 130 and says so, and the STOP file is gone, so the same command goes on."""
    out = campaign.parent / "out"
    assert main(["stop", str(campaign)]) == 2                  # no runs folder yet
    assert "does not exist" in capsys.readouterr().err
    proc = _start(campaign, "--jobs", "1")
    _wait_for(lambda: any(stale_engine_pids(f) for f in _folders(out)), 120, "a running engine")
    running = [f for f in _folders(out) if stale_engine_pids(f)]       # its engine runs before the stop
    assert main(["stop", str(campaign)]) == 0
    asked = time.time()
    text, _ = proc.communicate(timeout=180)
    assert proc.returncode == 130 and "stopped as asked" in text, text
    _no_engine_left(out)
    assert not (out / "STOP").exists()
    done = [f for f in _folders(out) if (f / "DONE").exists()]
    assert 1 <= len(done) < 6, text
    assert running and all(f in done for f in running), text  # the running case finished, not stopped
    assert all(folder_status(f) in ("done", "interrupted") for f in _folders(out)), text
    late = [f for f in done if json.loads((f / "case.json").read_text()).get("started", 0) > asked + 1]
    assert not late, text                                     # nothing started after the stop ran to its end
    assert main(["stop", str(campaign)]) == 2                  # nothing runs now
    assert "no `campaign run` is running" in capsys.readouterr().err
    # the dry run of what is left scales its time estimate by the runs that finished here
    assert main(["run", str(campaign), "--dry-run"]) == 0
    assert f"scaled by the {len(done)} finished run(s) here" in capsys.readouterr().out


def test_second_run_is_refused_while_the_first_holds_the_lock(campaign, capsys):
    out = campaign.parent / "out"
    with CampaignStore(out, create=True) as store, store.lock():
        rc = main(["run", str(campaign)])
    err = capsys.readouterr().err
    assert rc == 2 and "another `campaign run`" in err and len(err.strip().splitlines()) == 1
    assert _folders(out) == []


def test_dry_run_lists_and_renders_without_running(campaign, capsys):
    rc = main(["run", str(campaign), "--dry-run"])
    text = capsys.readouterr().out
    out = campaign.parent / "out"
    assert rc == 0 and text.count("  run  ") == 6 and "6 cases: 6 run" in text
    assert not (out / ".dry-run").exists()             # decks only when asked
    assert main(["run", str(campaign), "--dry-run", "--render"]) == 0
    decks = list((out / ".dry-run").glob("*/in.deck"))
    assert len(decks) == 6
    assert _folders(out) == []          # nothing ran, nothing indexed as started


def test_failed_cases_are_kept_until_rerun_failed(tmp_path):
    need_binary("liggghts")
    # valid Case, refused by LIGGGHTS at run time (Young's modulus below its hard-particle floor)
    f = write_toml(tmp_path / "hostile.toml", **(TABLES | {"case": TABLES["case"] | {"shear_modulus": 1e6},
                                                         "sweep": {"friction_ps": [0.2], "seed": [1]}}))
    cmd = [sys.executable, "-m", "interphase.cli", "run", str(f), "--plain"]
    first = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert first.returncode == 1, first.stdout + first.stderr
    (folder,) = _folders(tmp_path / "out")
    fail = json.loads((folder / "failure.json").read_text())
    assert fail["status"] == "failed" and fail["cause"] == "engine_error" and fail["log_tail"]
    con = sqlite3.connect(tmp_path / "out" / "index.sqlite")
    assert con.execute("SELECT status, cause FROM cases").fetchall() == [("failed", "engine_error")]
    con.close()
    again = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert again.returncode == 1 and "0 to run" in again.stdout and _starts(folder) == 1
    forced = subprocess.run(cmd + ["--rerun-failed"], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert forced.returncode == 1 and "1 to run" in forced.stdout and _starts(folder) == 2


@pytest.mark.yade
def test_a_case_waits_for_the_specimen_it_starts_from(tmp_path):
    """specimen_from: when the LIGGGHTS run fails, its YADE case does not run (no folder, a `wait`
    line naming the run and its status, exit 1); once the LIGGGHTS run finishes, the next `campaign
    run` runs the YADE case from its specimen."""
    need_binary("liggghts")
    need_binary("yade")
    f = write_toml(tmp_path / "pair.toml", **(TABLES | {
        "campaign": TABLES["campaign"] | {"engines": ["liggghts", "yade"], "specimen_from": "liggghts"},
        "case": {"device": "periodic", **TINY_CASE, "shear_velocity": 0.05},
        "sweep": {"friction_ps": [0.2], "seed": [1]}}))
    cmd = [sys.executable, "-m", "interphase.cli", "run", str(f), "--plain"]
    env = dict(os.environ, INTERPHASE_LIGGGHTS_BINARY=str(tmp_path / "no-liggghts"))
    first = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, timeout=300, env=env)
    assert first.returncode == 1, first.stdout + first.stderr
    (lig,) = _folders(tmp_path / "out")
    assert json.loads((lig / "failure.json").read_text())["cause"] == "not_installed"
    wait = [ln for ln in first.stdout.splitlines() if ln.startswith("wait ")]
    assert len(wait) == 1 and f"the liggghts run it starts from, {lig.name}, is failed" in wait[0], first.stdout
    second = subprocess.run(cmd + ["--rerun-failed"], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert second.returncode == 0, second.stdout + second.stderr
    folders = _folders(tmp_path / "out")
    assert len(folders) == 2 and all(folder_status(p) == "done" for p in folders)
    (yade,) = [p for p in folders if p != lig]
    assert json.loads((yade / "case.json").read_text())["inputs"]["start"] == {"engine": "liggghts",
                                                                                "case_id": lig.name}
