"""`campaign run --executor slurm` on a real single-node SLURM (munge + slurmctld + slurmd from Debian).

One small campaign, real LIGGGHTS in every job: two ordinary cases finish; one case the engine
rejects (a valid Case whose shear modulus is below LIGGGHTS's floor for hard particles: the engine
fails at run time, honestly); one with far too much shear for its tiny box (it used to lose grains; now
the grains that leave under the side wall are removed and the case finishes); one case far longer than
its 1-minute time limit, which SLURM kills. Each failure must be reported with its own cause; the
others finished. The long case's engine is stopped (SIGSTOP) once it runs: hung past its limit, it
fails the same way without holding a core for the minute the limit takes (the other tests run on
the same 2 cores meanwhile).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.campaign_files import TINY_CASE, write_toml
from tests.conftest import need_binary
from tests.slurm_cluster import SlurmCluster

pytestmark = [pytest.mark.slurm, pytest.mark.liggghts]

LONG_VELOCITY = 0.00005
TABLES = dict(
    campaign={"name": "slurm-test", "engines": ["liggghts"], "output": "out"},
    # time_limit [min]: the long case cannot make it
    execution={"executor": "slurm", "time_limit": 1, "max_concurrent": 2},
    case=TINY_CASE,
    pairs={"box": False},
    group=[{"name": "ok", "sweep": {"friction_ps": [0.2, 0.5]}},
           # valid Case, but LIGGGHTS refuses Young's modulus < 5 MPa for hard grains
           {"name": "hostile", "case": {"shear_modulus": 1e6}},
           # 20× the shear of the others (1.2 box lengths): grains leave the tiny box under the side wall
           # (7 removed, against 16 at 40× and 32 at 80×, measured without SLURM; 9 s of CPU
           # against 27 s at 80×: far inside the 1-minute limit even on a loaded machine)
           {"name": "long_shear", "case": {"shear_distance": 0.01}},
           # 1000× slower shear: minutes of engine time, far beyond the 1-minute limit
           {"name": "long", "case": {"shear_velocity": LONG_VELOCITY}}])


def _hang_engine_of(out: Path, proc: subprocess.Popen, velocity: float, timeout: float = 180) -> bool:
    """SIGSTOP the LIGGGHTS process of the case in `out` sheared at `velocity`, once it runs (its
    working directory is the case folder, runner.stale_engine_pids); False if it never ran."""
    from interphase.campaign.runner import stale_engine_pids

    deadline = time.monotonic() + timeout
    while proc.poll() is None and time.monotonic() < deadline:
        for meta in out.glob("*/case.json"):
            try:
                if json.loads(meta.read_text())["inputs"]["shear_velocity"] != velocity:
                    continue
            except (OSError, ValueError, KeyError):
                continue
            for pid in stale_engine_pids(meta.parent):
                try:
                    if Path(f"/proc/{pid}/comm").read_text().strip() == "liggghts":
                        os.kill(pid, signal.SIGSTOP)
                        return True
                except OSError:
                    continue
        time.sleep(0.5)
    return False


@pytest.fixture(scope="module")
def slurm(tmp_path_factory):
    """A real one-node SLURM for this module; fails loudly if the binaries are missing."""
    need_binary("liggghts")
    root = tmp_path_factory.mktemp("slurm")
    with SlurmCluster(root) as cluster:
        yield cluster


def test_slurm_campaign_reports_engine_failure_and_timeout(slurm, tmp_path):
    camp = write_toml(tmp_path / "slurm.toml", **TABLES)
    env = slurm.env()
    log = tmp_path / "run.log"
    with open(log, "w") as sink:        # a file, not a pipe: nobody reads while the engine is found
        proc = subprocess.Popen([sys.executable, "-m", "interphase.cli", "run", str(camp), "--plain"], cwd=tmp_path,
                                env=env, stdout=sink, stderr=subprocess.STDOUT, text=True)
        hung = _hang_engine_of(tmp_path / "out", proc, LONG_VELOCITY)
        proc.wait(timeout=300)
    stdout = log.read_text()
    assert hung, "the long case's engine never ran: " + stdout
    assert proc.returncode == 1, stdout     # some cases did not finish
    status = subprocess.run([sys.executable, "-m", "interphase.cli", "status", str(camp), "--json"], cwd=tmp_path,
                            env=env, capture_output=True, text=True, timeout=60)
    assert status.returncode == 0, status.stderr
    cases = {c["group"]: [] for c in json.loads(status.stdout)["cases"]}
    for c in json.loads(status.stdout)["cases"]:
        cases[c["group"]].append(c)
    out = tmp_path / "out"

    # the ordinary cases finished, through SLURM (job id recorded in case.json)
    assert [c["status"] for c in cases["ok"]] == ["done", "done"], stdout
    for c in cases["ok"]:
        folder = out / c["case_id"]
        assert (folder / "DONE").exists() and (folder / "history.parquet").exists()
        assert json.loads((folder / "case.json").read_text())["slurm_job"]

    # the engine failure: recorded by the runner with the engine's cause and log tail
    (bad,) = cases["hostile"]
    assert bad["status"] == "failed" and bad["cause"] == "engine_error", bad
    fail = json.loads((out / bad["case_id"] / "failure.json").read_text())
    assert "youngsModulus" in fail["log_tail"]
    assert not (out / bad["case_id"] / "DONE").exists()

    # far too much shear for the box: grains leave under the side wall and are removed at the
    # openings (engines.device); before the openings this case failed with Lost atoms
    (long_shear,) = cases["long_shear"]
    assert long_shear["status"] == "done", long_shear
    assert json.loads((out / long_shear["case_id"] / "summary.json").read_text())["row"]["grains_left"] > 0

    # the time-out: killed by SLURM, cause taken from the job state, not from the dying engine
    (slow,) = cases["long"]
    assert slow["status"] == "killed" and slow["cause"] == "slurm_timeout", slow
    fail = json.loads((out / slow["case_id"] / "failure.json").read_text())
    assert fail["slurm_state"] == "TIMEOUT"
    assert not (out / slow["case_id"] / "DONE").exists()

    # a second run skips everything (finished and failed are kept), submitting nothing
    again = subprocess.run([sys.executable, "-m", "interphase.cli", "run", str(camp), "--plain"], cwd=tmp_path,
                           env=env, capture_output=True, text=True, timeout=120)
    assert "0 to run" in again.stdout, again.stdout


SEQUENTIAL = dict(
    campaign={"name": "slurm-seq", "engines": ["liggghts"], "output": "out"},
    execution={"executor": "slurm", "time_limit": 5, "max_concurrent": 2},   # one time-limit bucket
    case={**TINY_CASE, "device": "periodic", "shear_velocity": 0.02, "friction_ps": 0.5},
    # a target out of reach: the case goes on to the cap
    seeds={"start": 3, "max": 4, "target": {"quantity": "E", "halfwidth": 1e-9}})


def test_sequential_rounds_run_as_one_slurm_array_each(slurm, tmp_path):
    """Sequential seeds on the real slurmctld: round 1 (seeds 1–3 of the interface case and their
    soil tests) is one job array, round 2 (seed 4 and its soil test, the target being out of reach)
    a second one; every run finished through SLURM, each under its round's array."""
    camp = write_toml(tmp_path / "seq.toml", **SEQUENTIAL)
    env = slurm.env()
    run = subprocess.run([sys.executable, "-m", "interphase.cli", "run", str(camp), "--plain"], cwd=tmp_path,
                         env=env, capture_output=True, text=True, timeout=400)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "round 2" in run.stdout, run.stdout
    out = tmp_path / "out"
    arrays: dict[str, set[int]] = {}
    for folder in out.iterdir():
        if not (folder / "DONE").exists():
            continue
        meta = json.loads((folder / "case.json").read_text())
        array, _, index = str(meta["slurm_job"]).partition("_")
        assert index.isdigit(), meta["slurm_job"]                 # an array task, not a lone job
        arrays.setdefault(array, set()).add(meta["inputs"]["seed"])
    assert len(arrays) == 2, arrays
    first, second = (arrays[a] for a in sorted(arrays, key=int))
    assert first == {1, 2, 3} and second == {4}, arrays
    assert sum(1 for f in out.iterdir() if (f / "DONE").exists()) == 8     # 4 interface + 4 soil tests
