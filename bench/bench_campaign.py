"""Campaign machinery costs (results go to BENCHMARKS.md, section "campaign"; never asserted in tests).

1. Planning + index for 10,000 cases: load_campaign (every Case built and validated) + plan (ids with
   the real LIGGGHTS version and template hash) + CampaignStore.register (SQLite), target < 2 s.
2. Scheduling overhead per case, local executor, target < 50 ms: a real campaign of tiny LIGGGHTS
   cases run with one worker; overhead = wall time − Σ (per-case time inside the runner, from
   case.json). Also reported: the runner's own work around the engine (write_input, read_results,
   parquet, summary, DONE) with a stand-in Engine whose execute runs `true` — a stand-in is allowed
   in a benchmark, never in the tests that prove the features.
3. Status of a 400-case campaign whose folders are all finished (stand-in engine, real Parquet
   tables): verification of every folder (case.json hashed against the folder's name, every table's
   Parquet footer) on an index rebuilt from scratch; then a status with every verdict cached (stat
   of the files only); then with one folder's table touched (that one verified again).

4. Loading shipped campaigns that name an instrument file in many cases (group5.toml; the study
   and its sequential rerun), each in a fresh process: CPU seconds of load_campaign, imports apart.

    .venv/bin/python bench/bench_campaign.py
    .venv/bin/python bench/bench_campaign.py status     # 3. only
    .venv/bin/python bench/bench_campaign.py load       # 4. only
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

from interphase.campaign.plan import plan
from interphase.campaign.run import run_campaign
from interphase.campaign.runner import run_case
from interphase.campaign.schema import load_campaign
from interphase.campaign.store import CampaignStore
from interphase.engines.base import Engine, EngineProfile
from interphase.tables import CONTACT_COLUMNS, HISTORY_COLUMNS, Results

BIG = """
[campaign]
name = "big"
[case]
profile = {kind = "sawtooth", rt = 1, sw = 2, sr = 0}
[sweep]
profile.rt = [%s]
friction_ps = [0.05, 0.2, 0.5, 0.8]
seed = [%s]
[pairs]
box = false
"""

TINY = """
[campaign]
name = "tiny"
engines = ["liggghts"]
output = "out"
[execution]
jobs = 1
[case]
profile = {kind = "sawtooth", rt = 1, sw = 2, sr = 0}
shear_modulus = 50e6
shear_distance = 0.0005
snapshot_every = 0.00025
box_length_d50 = 12.0
box_height_d50 = 6.0
[sweep]
friction_ps = [0.05, 0.1, 0.2, 0.3, 0.4, 0.5]
seed = [1, 2]
[pairs]
box = false
"""


def bench_planning(tmp: Path) -> dict:
    f = tmp / "big.toml"
    rts = ", ".join(f"{0.1 + 0.2 * i:.1f}" for i in range(25))
    seeds = ", ".join(str(i) for i in range(1, 101))
    f.write_text(BIG % (rts, seeds))
    t0 = time.perf_counter()
    camp = load_campaign(f, output=tmp / "big-out")
    t1 = time.perf_counter()
    planned = plan(camp)
    t2 = time.perf_counter()
    with CampaignStore(camp.output, create=True) as store:
        store.register(planned)
        t3 = time.perf_counter()
        n = len(store.status())
    t4 = time.perf_counter()
    return {"cases": len(planned), "load_validate_s": t1 - t0, "plan_ids_s": t2 - t1, "index_register_s": t3 - t2,
            "total_s": t3 - t0, "status_table_s": t4 - t3, "indexed": n}


class StandIn(Engine):
    """Benchmark-only engine: renders one file, runs `true`, returns small real-shaped tables."""

    name = "standin"

    @classmethod
    def default_profile(cls):
        return EngineProfile(binary="true")

    def version(self):
        return "standin 0"

    def recipe_id(self):
        return "0" * 16

    def render(self, case):
        return {"in.deck": "# stand-in\n"}

    def arguments(self, binary):
        return [binary]

    def diagnose(self, folder, returncode):
        return (None, "") if returncode == 0 else ("engine_error", f"return code {returncode}")

    def execute(self, folder):          # no recipe.json to estimate a timeout from
        subprocess.run(["true"], cwd=folder, check=True)

    def read_results(self, folder):
        hist = pd.DataFrame({c: [0.0, 1e-4, 2e-4] for c in HISTORY_COLUMNS})
        hist["surface_fx"] = [0.0, 0.1, 0.2]
        hist["surface_fz"] = [-1.0, -1.0, -1.0]
        cont = pd.DataFrame({c: [0.0] * 10 for c in CONTACT_COLUMNS})
        cont["kind"] = "pp"
        return Results(cont, hist)


def bench_runner_standin(tmp: Path, n: int = 200) -> dict:
    camp = load_campaign(_write(tmp / "tiny.toml", TINY), output=tmp / "standin-out")
    case = camp.cases[0].case
    eng = StandIn()
    t = time.perf_counter()
    for i in range(n):
        run_case(case, eng, tmp / "standin-out" / f"c{i}", {"case_id": f"c{i}"})
    return {"cases": n, "per_case_ms": 1e3 * (time.perf_counter() - t) / n}


def bench_local_pool(tmp: Path) -> dict:
    f = _write(tmp / "tiny.toml", TINY)
    out = tmp / "out"
    shutil.rmtree(out, ignore_errors=True)
    with open(tmp / "progress.txt", "w") as sink:
        t = time.perf_counter()
        rep = run_campaign(f, stream=sink, live=False)
        wall = time.perf_counter() - t
    inside, engine, stages = 0.0, 0.0, {}
    for p in out.iterdir():
        if (p / "case.json").exists():
            meta = json.loads((p / "case.json").read_text())
            inside += meta["elapsed"]
            engine += meta["timings"]["execute"]
            for k, v in meta["timings"].items():
                stages[k] = stages.get(k, 0.0) + v
    n = rep.count("done")
    return {"cases": n, "wall_s": wall, "inside_runner_s": inside, "engine_execute_s": engine,
            "scheduling_overhead_ms_per_case": 1e3 * (wall - inside) / n,
            "runner_work_besides_engine_ms_per_case": 1e3 * (inside - engine) / n,
            "stage_mean_ms": {k: 1e3 * v / n for k, v in stages.items()}}


def bench_status_verify(tmp: Path, n_seeds: int = 4) -> dict:
    import os

    from interphase.case import case_id

    f = tmp / "v.toml"
    rts = ", ".join(f"{0.1 + 0.2 * i:.1f}" for i in range(25))
    f.write_text(BIG % (rts, ", ".join(str(i) for i in range(1, n_seeds + 1))))
    camp = load_campaign(f, output=tmp / "verify-out")
    eng, rid = StandIn(), "0" * 16
    for c in camp.cases:
        cid = case_id(c.case, "standin", rid)
        run_case(c.case, eng, camp.output / cid, {"case_id": cid, "recipe_id": rid})
    n = len(camp.cases)
    t = time.perf_counter()
    with CampaignStore(camp.output) as store:       # no index: rebuilt, every folder verified
        t1 = time.perf_counter()
        df = store.status()
        t2 = time.perf_counter()
        assert (df["status"] == "done").all() and len(df) == n, df["status"].value_counts()
        df = store.status()                          # every verdict cached
        t3 = time.perf_counter()
        one = next(p for p in camp.output.iterdir() if (p / "DONE").exists()) / "contacts.parquet"
        os.utime(one)
        t4 = time.perf_counter()
        df = store.status()                          # one folder verified again
        t5 = time.perf_counter()
    return {"cases": n, "rebuild_verify_all_s": t1 - t, "first_status_s": t2 - t1, "status_cached_s": t3 - t2,
            "status_one_touched_s": t5 - t4, "verify_ms_per_folder": 1e3 * (t1 - t) / n}


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


SHIPPED = ("campaigns/group5.toml", "campaigns/study.toml", "studies/reproduction/study_sequential.toml")
LOAD = """import json, sys, time
from interphase.campaign.schema import load_campaign
import SurfaceTopography  # noqa: F401  (its import is not the load's cost)
t = time.process_time()
c = load_campaign(sys.argv[1])
print(json.dumps({"cases": len(c.cases), "cpu_s": round(time.process_time() - t, 3)}))
"""


def bench_load_shipped() -> dict:
    root = Path(__file__).resolve().parents[1]
    out = {}
    for name in SHIPPED:
        run = subprocess.run([sys.executable, "-c", LOAD, str(root / name)], capture_output=True,
                             text=True, check=True, env={**os.environ, "PYTHONPATH": str(root / "src")})
        out[name] = json.loads(run.stdout)
    return out


def main() -> None:
    tmp = Path(tempfile.mkdtemp(prefix="bench-campaign-"))
    try:
        if sys.argv[1:] == ["load"]:
            res = {"load_shipped": bench_load_shipped()}
        elif sys.argv[1:] == ["status"]:
            res = {"status_verify_400": bench_status_verify(tmp)}
        else:
            res = {"planning_10k": bench_planning(tmp), "runner_standin": bench_runner_standin(tmp),
                   "local_pool_liggghts": bench_local_pool(tmp), "status_verify_400": bench_status_verify(tmp),
                   "load_shipped": bench_load_shipped()}
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    json.dump(res, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
