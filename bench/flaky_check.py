"""Repeated fresh-clone runs of the test suite, to find a test whose verdict depends on chance.

Each run clones the repository's HEAD into a new folder and runs `make test` there (its own .venv,
its own temporary folders), optionally with N LIGGGHTS runs beside it as load, and records the run's
time, its counts and every failing test with the tail of its report. Results are appended as JSON
lines to --out and printed as a Markdown table for BENCHMARKS.md.

    python bench/flaky_check.py --runs 5                      # idle
    python bench/flaky_check.py --runs 5 --load 2             # two engine runs beside
    python bench/flaky_check.py --runs 10 --tier engine       # only the engine and SLURM tests
    make flaky-check                                          # 5 idle, then 5 with two engine runs

`--tier engine` runs only `-m "liggghts or yade or slurm"` with the main checkout's venv (no venv
built per clone, PYTHONPATH to the clone's src): the quick loop for hunting a flake; the record
of the issue is the full `make test`.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _load_deck(work: Path) -> Path:
    """A LIGGGHTS deck of a real quick-campaign case (Rt/D50 1, μs 0.2, 3 mm of shear: about a
    minute of one core), rendered once; the load loops run it again and again."""
    import tomllib

    import tomli_w

    deck_dir = work / "load-case"
    if not (deck_dir / "in.deck").exists():
        shutil.rmtree(deck_dir, ignore_errors=True)
        case = work / "load-case.toml"
        quick = tomllib.loads((ROOT / "campaigns" / "quick.toml").read_text())
        case.write_text(tomli_w.dumps({"case": quick["case"] | {"friction_ps": 0.2, "seed": 1}}))
        subprocess.run([sys.executable, "-m", "interphase.cli", "render", str(case), "-o", str(deck_dir)],
                       check=True, capture_output=True)
    return deck_dir


def _start_load(n: int, work: Path) -> list[subprocess.Popen]:
    """n shell loops, each running the deck's LIGGGHTS to the end and starting it again."""
    if n == 0:
        return []
    deck = _load_deck(work)
    procs = []
    for i in range(n):
        d = work / f"load-{i}"
        shutil.rmtree(d, ignore_errors=True)
        shutil.copytree(deck, d)
        procs.append(subprocess.Popen(["bash", "-c", "while true; do liggghts -in in.deck >/dev/null 2>&1; done"],
                                      cwd=d, start_new_session=True))
    return procs


def _stop_load(procs: list[subprocess.Popen]) -> None:
    for p in procs:
        try:
            os.killpg(p.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        p.wait()


def _failures(junit: Path) -> tuple[dict, list[dict]]:
    """Counts and the failing tests (id, message, tail) of a JUnit XML report."""
    if not junit.exists():
        return {}, []
    root = ET.parse(junit).getroot()
    counts = {"passed": 0, "failed": 0, "skipped": 0, "error": 0}
    failed = []
    for tc in root.iter("testcase"):
        bad = tc.find("failure") if tc.find("failure") is not None else tc.find("error")
        if bad is not None:
            counts["failed" if bad.tag == "failure" else "error"] += 1
            text = (bad.text or "").strip().splitlines()
            failed.append({"test": f"{tc.get('classname')}::{tc.get('name')}", "message": bad.get("message", "")[:500],
                           "tail": "\n".join(text[-25:])})
        elif tc.find("skipped") is not None:
            counts["skipped"] += 1
        else:
            counts["passed"] += 1
    return counts, failed


def one_run(i: int, work: Path, tier: str, load: int, keep: bool, beside: str = "") -> dict:
    clone = work / f"clone-{i}"
    shutil.rmtree(clone, ignore_errors=True)
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=clone, capture_output=True, text=True).stdout.strip()
    junit = work / f"junit-{i}.xml"
    env = os.environ | {"PYTEST_ADDOPTS": f"--junitxml={junit}"}
    if tier == "engine":
        env["PYTHONPATH"] = str(clone / "src")
        cmd = [str(ROOT / ".venv" / "bin" / "python"), "-m", "pytest", "-q", "-n", "auto", "--dist", "loadgroup",
               "-m", "liggghts or yade or slurm"]
    else:
        cmd = ["make", "test"]
    procs = _start_load(load, work)
    t0 = time.monotonic()
    loads = []
    try:
        proc = subprocess.Popen(cmd, cwd=clone, env=env, stdout=open(work / f"log-{i}.txt", "w"),
                                stderr=subprocess.STDOUT)
        while proc.poll() is None:
            time.sleep(5)
            loads.append(os.getloadavg()[0])
    finally:
        _stop_load(procs)
    wall = time.monotonic() - t0
    counts, failed = _failures(junit)
    rec = {"run": i, "commit": head, "tier": tier, "load": load, "beside": beside, "rc": proc.returncode,
           "wall_s": round(wall, 1), "mean_load1": round(sum(loads) / max(len(loads), 1), 2),
           "date": time.strftime("%Y-%m-%d %H:%M"), **counts, "failures": failed}
    if not keep and proc.returncode == 0:
        shutil.rmtree(clone, ignore_errors=True)
    return rec


def table(records: list[dict]) -> str:
    rows = ["| run | commit | tier | beside | result | time | mean load | failing test |",
            "|---|---|---|---|---|---|---|---|"]
    for r in records:
        m, s = divmod(int(round(r["wall_s"])), 60)
        res = f"{r.get('passed', 0)} passed, {r.get('failed', 0) + r.get('error', 0)} failed"
        bad = "; ".join(f["test"] for f in r["failures"]) or "—"
        beside = r.get("beside") or (f"{r['load']} LIGGGHTS loops" if r["load"] else "nothing")
        rows.append(f"| {r['run']} | {r['commit']} | {r['tier']} | {beside} | {res} | "
                    f"{m} min {s:02d} s | {r['mean_load1']} | {bad} |")
    return "\n".join(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--load", type=int, default=0, help="LIGGGHTS runs beside the suite (default 0: idle)")
    ap.add_argument("--tier", choices=("full", "engine"), default="full")
    ap.add_argument("--work", type=Path, default=Path(tempfile.gettempdir()) / "flaky-check")
    ap.add_argument("--out", type=Path, default=None, help="JSON lines appended here (default WORK/runs.jsonl)")
    ap.add_argument("--keep", action="store_true", help="keep every clone, not only those that failed")
    ap.add_argument("--beside", default="", help="what else runs on the machine meanwhile (recorded, e.g. "
                    "'campaign X, 2 jobs')")
    a = ap.parse_args(argv)
    a.work.mkdir(parents=True, exist_ok=True)
    out = a.out or a.work / "runs.jsonl"
    start = sum(1 for _ in open(out)) if out.exists() else 0
    records = []
    for k in range(a.runs):
        rec = one_run(start + k + 1, a.work, a.tier, a.load, a.keep, a.beside)
        records.append(rec)
        with open(out, "a") as fh:
            fh.write(json.dumps(rec) + "\n")
        print(table([rec]).splitlines()[-1], flush=True)
        for f in rec["failures"]:
            print(f"  FAILED {f['test']}: {f['message']}\n{f['tail']}", flush=True)
    print(table(records))
    return 0 if all(r["rc"] == 0 for r in records) else 1


if __name__ == "__main__":
    sys.exit(main())
