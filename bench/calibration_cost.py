"""What a calibration costs: runs, engine time and wall time of `campaign calibrate TARGET` on this
machine, from the runs folder it leaves (each case's recorded `elapsed`) and the card's
[calibration] table. Prints a Markdown table for BENCHMARKS.md.

    python bench/calibration_cost.py TARGET.toml [--quick]

Runs the calibration (resuming if its runs folder exists: delete runs/calibrate/<name> and
runs/element/<name> first for a cold measurement) in the current directory.
"""

from __future__ import annotations

import os
import platform
import sys
import time
from pathlib import Path

import pandas as pd


def main(argv: list[str]) -> int:
    from interphase.campaign.calibrate import calibrate, load_target
    from interphase.campaign.store import CampaignStore

    target = load_target(argv[0])
    quick = "--quick" in argv
    t0 = time.time()
    res = calibrate(argv[0], quick=quick, stream=sys.stderr)
    wall = time.time() - t0
    engine = 0.0
    for folder in (Path("runs") / "calibrate" / target.name, Path("runs") / "element" / target.name):
        with CampaignStore(folder) as st:
            s = st.summaries()
            engine += float(pd.to_numeric(s["elapsed"], errors="coerce").sum()) if len(s) else 0.0
    c = res["calibration"]
    print(f"| target | budget | runs | engine time [min] | wall time [min] | cores | date |")
    print("|---|---|---|---|---|---|---|")
    b = c["budget"]
    print(f"| {target.name} | {b['samples']} samples × {b['iterations']} iterations × {b['seeds']} seeds, final "
          f"{b['final_seeds']} seeds × {1 + len(target.verification)} stresses | {c['runs']} | {engine / 60:.1f} | "
          f"{wall / 60:.1f} | {os.cpu_count()} ({platform.machine()}) | {time.strftime('%Y-%m-%d')} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
