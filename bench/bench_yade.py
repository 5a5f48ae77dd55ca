"""YADE vs LIGGGHTS on the same generated case: particle-steps per second of the shear stage.

The case is bench_liggghts.py's (45° saw-tooth, μs = 0.5, G = 50 MPa, 3 mm of shear; n grains).
- YADE: the generated driver (Python servo every step, history and contact export in PyRunner),
  `yade -n -x`, one thread (INTERPHASE_YADE_THREADS to change); the stage wall times come from the
  driver's own log line (consolidation / shear seconds, measured inside YADE).
- LIGGGHTS: the generated deck, one rank; the rate from LIGGGHTS's "Loop time" of the shear run.
Driver overhead = render + read_results over the case's wall time.

Run: .venv/bin/python bench/bench_yade.py [n_grains]   (1000 grains: about 1.5 min here)
"""

from __future__ import annotations

import re
import sys
import tempfile
import time
from pathlib import Path

from interphase.case import Case
from interphase.engines.device import device
from interphase.engines.liggghts import Liggghts
from interphase.engines.yade import Yade
from interphase.surface.spec import ProfileSpec

STAGES = re.compile(r"interphase: consolidation (\d+) steps ([0-9.]+) s; shear (\d+) steps ([0-9.]+) s; grains (\d+)")


def yade_rates(log: Path) -> tuple[float, float, int]:
    """(consolidation, shear) particle-steps/s and the grain count from the driver's log line."""
    m = STAGES.search(log.read_text())
    if not m:
        raise SystemExit(f"{log}: no stage timing line (an older driver?)")
    nc, tc, ns, ts, n = int(m[1]), float(m[2]), int(m[3]), float(m[4]), int(m[5])
    return n * nc / tc, n * ns / ts, n


def liggghts_rate(log: Path, n: int) -> float:
    loops = re.findall(r"Loop time of ([0-9.eE+-]+) on \d+ procs for (\d+) steps", log.read_text())
    seconds, steps = float(loops[-1][0]), int(loops[-1][1])
    return n * steps / seconds


def main(n: int = 1000):
    case = Case(test="interface", profile=ProfileSpec.make("sawtooth", rt=1, sw=2, sr=0), friction_ps=0.5,
                shear_modulus=50e6, n_grains=n, box_length_d50=50, box_height_d50=25,
                shear_distance=3e-3, snapshot_every=0.25e-3)
    yade, lig = Yade(), Liggghts()
    with tempfile.TemporaryDirectory() as tmp:
        fy, fl = Path(tmp, "yade"), Path(tmp, "liggghts")
        t0 = time.perf_counter()
        yade.write_input(case, fy)
        t_render = time.perf_counter() - t0
        t0 = time.perf_counter()
        yade.execute(fy)
        t_run = time.perf_counter() - t0
        t0 = time.perf_counter()
        res = yade.read_results(fy)
        t_read = time.perf_counter() - t0
        cons, shear, grains = yade_rates(fy / "engine.log")
        lig.write_input(case, fl)
        t0 = time.perf_counter()
        lig.execute(fl)
        t_lig = time.perf_counter() - t0
        lrate = liggghts_rate(fl / "log.liggghts", grains)
    driver = t_render + t_read
    print(f"grains {grains}, dt {device(case).dt:.3e} s, YADE threads {yade.profile.threads}")
    print(f"YADE shear stage {shear:.3e} particle-steps/s (consolidation {cons:.3e}); "
          f"LIGGGHTS shear stage {lrate:.3e}; YADE/LIGGGHTS {shear / lrate:.2f}")
    print(f"YADE case wall time {t_run + driver:.1f} s (engine {t_run:.1f} s, render {t_render:.2f} s, "
          f"read {t_read:.2f} s for {len(res.contacts)} contact rows); LIGGGHTS engine {t_lig:.1f} s")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 1000)
