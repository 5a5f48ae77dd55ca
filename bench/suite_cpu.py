"""CPU seconds per test of the suite, engines included: what `make test` spends, read so that it holds
on a loaded machine (wall-clock durations do not: they grow with whatever else runs).

As a pytest plugin, each test's CPU (the test process's own plus every child it waited for: engine
runs, CLI subprocesses, a local executor's workers) is appended to OUT/cpu-PID.jsonl:

    PYTHONPATH=bench .venv/bin/python -m pytest -n 2 --dist loadgroup -p suite_cpu -p no:cacheprovider
    .venv/bin/python bench/suite_cpu.py [OUT]          # the table: per file, then the slowest tests

OUT is $SUITE_CPU_DIR or /tmp/suite_cpu. Not counted: jobs run by SLURM's daemons (the cluster
tests' engine runs are slurmd's children, not the test's).
"""

from __future__ import annotations

import json
import os
import resource
import sys
import time
from pathlib import Path

import pytest

OUT = Path(os.environ.get("SUITE_CPU_DIR", "/tmp/suite_cpu"))


def _cpu() -> float:
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    cpu, wall = _cpu(), time.time()
    yield
    OUT.mkdir(parents=True, exist_ok=True)
    with open(OUT / f"cpu-{os.getpid()}.jsonl", "a") as f:
        f.write(json.dumps({"id": item.nodeid, "cpu": _cpu() - cpu, "wall": time.time() - wall, "start": wall,
                            "worker": os.environ.get("PYTEST_XDIST_WORKER", "master")}) + "\n")


def main(out: Path = OUT, top: int = 25) -> None:
    import pandas as pd

    runs = pd.concat([pd.read_json(p, lines=True) for p in sorted(out.glob("cpu-*.jsonl"))], ignore_index=True)
    runs["file"] = runs["id"].str.split("::").str[0]
    print(f"{len(runs)} tests, {runs.cpu.sum():.0f} CPU-s\n")
    by_file = runs.groupby("file").cpu.agg(["sum", "count"]).sort_values("sum", ascending=False)
    print(by_file.head(top).round(0).to_string(), "\n")
    print(runs.nlargest(top, "cpu")[["cpu", "wall", "id"]].round(0).to_string(index=False))
    if "start" in runs:
        # each worker's span from the first test's start to the last one's end, and the time it was in a test
        t0 = runs["start"].min()
        w = runs.assign(end=runs["start"] + runs["wall"]).groupby("worker").agg(
            first=("start", "min"), last=("end", "max"), in_tests=("wall", "sum"), cpu=("cpu", "sum"))
        w[["first", "last"]] -= t0
        print("\nper worker [s] (from the first test's start):\n" + w.round(0).to_string())


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else OUT)
