"""YADE: the generated driver vs a plain script of the same physics, and LIGGGHTS on the same case.

The case is bench_liggghts.py's (45° saw-tooth, μs = 0.5, G = 50 MPa, 3 mm of shear; n grains).
- generated: the driver interphase-dem renders (engines/yade_driver.py: the platen servo, the
  grain–facet rolling update, history rows, contact and particle export, all in a PyRunner);
- plain: bench/yade_plain.py on the same params.json — the same grains, facets, contact law,
  rolling values, servo, consolidation checks and grain removal, with no output: the physics as one
  would write it by hand (`check`: it writes particles at the snapshot steps, which must equal the
  generated run's particles.csv byte for byte, i.e. the same physics; first pair only).
Both print the stage line (consolidation / shear: wall seconds and this process's CPU seconds).
Particle-steps per second of the shear stage from the CPU seconds (steadier than wall time when other
work shares the cores) and from wall time. Generated and plain alternate, `repeats` times each, so
that both see the same load; the ratio is taken per pair. One thread (INTERPHASE_YADE_THREADS to
change). LIGGGHTS: the generated deck, one rank, its "Loop time" of the shear run (wall time).

Run: .venv/bin/python bench/bench_yade.py [n_grains] [repeats] [--check] [--no-liggghts]
"""

from __future__ import annotations

import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from interphase.case import Case
from interphase.engines.device import device
from interphase.engines.liggghts import Liggghts
from interphase.engines.yade import Yade
from interphase.surface.spec import ProfileSpec

PLAIN = Path(__file__).with_name("yade_plain.py")
STAGES = re.compile(r"interphase: consolidation (\d+) steps ([0-9.]+) s; shear (\d+) steps ([0-9.]+) s; grains (\d+)"
                    r"(?:; cpu ([0-9.]+) s, ([0-9.]+) s)?")


def yade_rates(log: Path) -> dict:
    """Shear-stage particle-steps/s (wall, cpu) and the grain count from a run's stage line."""
    m = STAGES.search(log.read_text())
    if not m:
        raise SystemExit(f"{log}: no stage timing line (an older driver?)")
    ns, ts, n = int(m[3]), float(m[4]), int(m[5])
    cpu = n * ns / float(m[7]) if m[7] else float("nan")
    return dict(wall=n * ns / ts, cpu=cpu, grains=n, steps=ns)


def liggghts_rate(log: Path, n: int) -> float:
    loops = re.findall(r"Loop time of ([0-9.eE+-]+) on \d+ procs for (\d+) steps", log.read_text())
    seconds, steps = float(loops[-1][0]), int(loops[-1][1])
    return n * steps / seconds


def run_plain(yade: Yade, folder: Path, check: bool) -> None:
    cmd = [a if a != "driver.py" else str(PLAIN) for a in yade.command()] + (["check"] if check else [])
    with open(folder / "plain.log", "w") as log:
        subprocess.run(cmd, cwd=folder, stdout=log, stderr=subprocess.STDOUT, env=yade.environment(), check=True)


def main(n: int = 1000, repeats: int = 3, check: bool = False, liggghts: bool = True):
    case = Case(test="interface", profile=ProfileSpec.make("sawtooth", rt=1, sw=2, sr=0), friction_ps=0.5,
                shear_modulus=50e6, n_grains=n, box_length_d50=50, box_height_d50=25,
                shear_distance=3e-3, snapshot_every=0.25e-3)
    yade, lig = Yade(), Liggghts()
    pairs = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(repeats):          # generated, then plain, back to back
            gen, plain = Path(tmp, f"gen{k}"), Path(tmp, f"plain{k}")
            yade.write_input(case, gen)
            yade.write_input(case, plain)
            yade.execute(gen)
            run_plain(yade, plain, check and k == 0)      # the check's output only in the first pair
            g, p = yade_rates(gen / "engine.log"), yade_rates(plain / "plain.log")
            same = None
            if check and k == 0:
                same = (gen / "particles.csv").read_text().split("\n", 1)[1] == (plain / "particles_plain.csv").read_text()
            pairs.append((g, p, same))
            print(f"pair {k + 1}: generated {g['cpu']:.3e} (wall {g['wall']:.3e}), plain {p['cpu']:.3e} "
                  f"(wall {p['wall']:.3e}) particle-steps/s; ratio cpu {g['cpu'] / p['cpu']:.3f}, "
                  f"wall {g['wall'] / p['wall']:.3f}" + ("" if same is None else f"; same particles: {same}"),
                  flush=True)
        lrate = None
        if liggghts:
            fl = Path(tmp, "liggghts")
            lig.write_input(case, fl)
            lig.execute(fl)
            lrate = liggghts_rate(fl / "log.liggghts", pairs[0][0]["grains"])
    med = statistics.median
    g_cpu, p_cpu = med(g["cpu"] for g, _, _ in pairs), med(p["cpu"] for _, p, _ in pairs)
    g_wall, p_wall = med(g["wall"] for g, _, _ in pairs), med(p["wall"] for _, p, _ in pairs)
    print(f"grains {pairs[0][0]['grains']}, dt {device(case).dt:.3e} s, shear {pairs[0][0]['steps']} steps, "
          f"YADE threads {yade.profile.threads}, {repeats} pairs")
    print(f"median shear stage particle-steps/s: generated {g_cpu:.3e} cpu / {g_wall:.3e} wall; "
          f"plain {p_cpu:.3e} cpu / {p_wall:.3e} wall")
    print(f"median paired ratio generated/plain: cpu {med(g['cpu'] / p['cpu'] for g, p, _ in pairs):.3f}, "
          f"wall {med(g['wall'] / p['wall'] for g, p, _ in pairs):.3f}")
    if lrate:
        print(f"LIGGGHTS shear stage {lrate:.3e} particle-steps/s (wall); YADE generated/LIGGGHTS {g_wall / lrate:.2f} (wall)")


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    main(int(args[0]) if args else 1000, int(args[1]) if len(args) > 1 else 3,
         check="--check" in sys.argv, liggghts="--no-liggghts" not in sys.argv)
