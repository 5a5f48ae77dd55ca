"""LIGGGHTS: generated interface deck vs the same physics in plain form, and the driver's overhead.

- generated: the deck interphase-dem renders (computes, local dumps, history print, servo, meshes);
- plain: the same deck with every output line removed (computes, dumps, the history and
  grain-balance prints, thermo output), i.e. the physics alone as one would write it by hand.
Particle-steps per second of the shear stage come from LIGGGHTS's own "Loop time" of the last run.

Driver overhead: the case runs through the campaign's own `run_case` (render, write, execute, read
the dumps, write Parquet, summarise, bookkeeping); overhead = its wall time minus the engine's
`execute` stage, as a share of the wall time. The first case of the process pays the imports (once
per campaign worker); the warm cases after it are what every further case of a campaign pays.
Generated and plain decks alternate, `repeats` times each, so that both see the same load.

Run: .venv/bin/python bench/bench_liggghts.py [n_grains]
"""

from __future__ import annotations

import json
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from interphase.campaign.runner import run_case
from interphase.engines.base import engine_spec
from interphase.case import Case
from interphase.engines.liggghts import Liggghts
from interphase.surface.spec import ProfileSpec

# the consolidation loop's variables (pfc, kc) stay: they steer the run, not its output
OUTPUT_LINES = re.compile(r"^(compute |dump|fix hist|fix balance|variable (?!pfc |kc )|thermo_style|thermo )", re.M)


def loop_rate(log: Path, n_grains: int) -> float:
    loops = re.findall(r"Loop time of ([0-9.eE+-]+) on \d+ procs for (\d+) steps", log.read_text())
    seconds, steps = float(loops[-1][0]), int(loops[-1][1])
    return n_grains * steps / seconds


def driver_share(case: Case, folder: Path) -> tuple[float, dict]:
    t0 = time.perf_counter()
    out = run_case(case, engine_spec("liggghts"), folder)
    wall = time.perf_counter() - t0
    assert out["status"] == "done", out
    timings = json.loads((folder / "case.json").read_text())["timings"]
    return wall, timings


def main(n: int = 1000, repeats: int = 3):
    case = Case(test="interface", profile=ProfileSpec.make("sawtooth", rt=1, sw=2, sr=0), friction_ps=0.5,
                shear_modulus=50e6, n_grains=n, box_length_d50=50, box_height_d50=25,
                shear_distance=3e-3, snapshot_every=0.25e-3)
    eng = Liggghts()
    with tempfile.TemporaryDirectory() as tmp:
        cold = driver_share(case, Path(tmp, "cold"))
        warm, ratios = [], []
        for k in range(repeats):   # generated and plain alternate, so that both see the same load
            gen, plain = Path(tmp, f"warm{k}"), Path(tmp, f"plain{k}")
            warm.append(driver_share(case, gen))
            files = eng.write_input(case, plain)
            (plain / "in.deck").write_text(OUTPUT_LINES.sub("# (output removed) ", files["in.deck"]))
            subprocess.run(eng.command(), cwd=plain, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
            g, p = loop_rate(gen / "log.liggghts", n), loop_rate(plain / "log.liggghts", n)
            ratios.append((g, p, g / p))
    for g, p, r in ratios:
        print(f"grains {n}; shear stage particle-steps/s: generated {g:.3e}, plain {p:.3e}, ratio {r:.3f}")
    print(f"median ratio {statistics.median(r for *_, r in ratios):.3f}")
    for label, (wall, tm) in [("first case (cold: imports)", cold)] + [(f"warm case {k + 1}", w) for k, w in enumerate(warm)]:
        driver = wall - tm["execute"]
        stages = ", ".join(f"{k} {v:.3f} s" for k, v in tm.items())
        print(f"{label}: wall {wall:.2f} s ({stages}); driver {driver:.3f} s = {100 * driver / wall:.2f} %")
    shares = [100 * (w - tm["execute"]) / w for w, tm in warm]
    print(f"median warm driver share {statistics.median(shares):.2f} %")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 1000)
