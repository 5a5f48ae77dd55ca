"""Planning a campaign of 10⁶ cases (issue 32 item 4; results go to BENCHMARKS.md, "Planning 10⁶
cases"; never asserted in tests).

A sweep of 100 × 100 × 100 values (profile.rt × friction_ps × seed, 10⁶ interface cases and their
100 box tests, one engine) in a temporary folder, each step in a fresh process so that its peak
memory (ru_maxrss) is its own:

1. load:      load_campaign — the count (schema.EAGER_MAX exceeded: lazy, one case per swept value
              built and checked, 300 here)
2. dry run:   `campaign run FILE --dry-run` (no --yes): count, a sample of 10, stop — what a user
              sees first (time to its last line)
3. plan:      every planned case's id, read one at a time (plan.iter_plan), kept in nothing but a
              counter: the full lazy plan (what `--dry-run --yes` walks)

    .venv/bin/python bench/bench_plan_large.py [--per-axis 100]
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CAMPAIGN = """[campaign]
name = "big"
[case]
test = "interface"
device = "periodic"
profile = {{kind = "sawtooth", rt = 1, sw = 2, sr = 0}}
shear_velocity = 0.02
shear_modulus = 50e6
shear_distance = 0.006
box_height_d50 = 25
[sweep]
profile.rt = {rt}
friction_ps = {mu}
seed = {seed}
"""

STEPS = {
    "load": """
from interphase.campaign.schema import load_campaign
c = load_campaign(FILE)
RESULT = {"cases": c.size, "lazy": c.lazy}
""",
    "dry run": """
import io
from interphase.campaign.run import run_campaign
buf = io.StringIO()
run_campaign(FILE, dry_run=True, stream=buf)
RESULT = {"lines": len(buf.getvalue().splitlines())}
""",
    "plan": """
from interphase.campaign.schema import load_campaign
from interphase.campaign.plan import iter_plan
n = boxes = 0
for p in iter_plan(load_campaign(FILE)):
    n += 1
    boxes += p.role == "box"
RESULT = {"planned": n, "boxes": boxes}
""",
}

RUNNER = """
import json, resource, sys, time
FILE = sys.argv[1]
t = time.perf_counter()
{body}
RESULT["seconds"] = time.perf_counter() - t
RESULT["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(RESULT))
"""


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--per-axis", type=int, default=100, help="values per swept key (cases = this³)")
    args = ap.parse_args()
    k = args.per_axis
    rt = [round(0.01 * (i + 1), 4) for i in range(k)]
    mu = [round(0.005 * (i + 1), 4) for i in range(k)]
    seed = list(range(1, k + 1))
    with tempfile.TemporaryDirectory() as tmp:
        f = Path(tmp) / "big.toml"
        f.write_text(CAMPAIGN.format(rt=rt, mu=mu, seed=seed))
        rows = []
        for name, body in STEPS.items():
            out = subprocess.run([sys.executable, "-c", RUNNER.format(body=body), str(f)], capture_output=True,
                                 text=True, check=True)
            rows.append((name, json.loads(out.stdout.strip().splitlines()[-1])))
    print(f"{k ** 3:,} cases ({k} × {k} × {k}); {platform.node()}, {platform.processor() or platform.machine()}, "
          f"Python {platform.python_version()}, {time.strftime('%Y-%m-%d')}\n")
    print("| step | time [s] | peak memory [MB] | result |\n|---|---|---|---|")
    for name, r in rows:
        extra = {k2: v for k2, v in r.items() if k2 not in ("seconds", "peak_mb")}
        print(f"| {name} | {r['seconds']:.2f} | {r['peak_mb']:.0f} | {extra} |")


if __name__ == "__main__":
    main()
