"""LIGGGHTS: generated interface deck vs the same physics in plain form, and the driver's overhead.

- generated: the deck interphase-dem renders (computes, local dumps, history print, servo, meshes);
- plain: the same deck with every output line removed (computes, dumps, fix print, thermo output),
  i.e. the physics alone as one would write it by hand.
Particle-steps per second of the shear stage come from LIGGGHTS's own "Loop time" of the last run.
Driver overhead = render + write + read_results (+ summarise when present) over the case wall time.

Run: .venv/bin/python bench/bench_liggghts.py [n_grains]
"""

from __future__ import annotations

import re
import sys
import tempfile
import time
from pathlib import Path

from interphase.case import Case
from interphase.engines.liggghts import Liggghts
from interphase.surface.spec import ProfileSpec

# the consolidation loop's variables (pfc, kc) stay: they steer the run, not its output
OUTPUT_LINES = re.compile(r"^(compute |dump|fix hist|variable (?!pfc |kc )|thermo_style|thermo )", re.M)


def loop_rate(log: Path, n_grains: int) -> float:
    loops = re.findall(r"Loop time of ([0-9.eE+-]+) on \d+ procs for (\d+) steps", log.read_text())
    seconds, steps = float(loops[-1][0]), int(loops[-1][1])
    return n_grains * steps / seconds


def main(n: int = 1000):
    case = Case(test="interface", profile=ProfileSpec.make("sawtooth", rt=1, sw=2, sr=0), friction_ps=0.5,
                shear_modulus=50e6, n_grains=n, box_length_d50=50, box_height_d50=25,
                shear_distance=3e-3, snapshot_every=0.25e-3)
    eng = Liggghts()
    with tempfile.TemporaryDirectory() as tmp:
        gen, plain = Path(tmp, "generated"), Path(tmp, "plain")
        t0 = time.perf_counter()
        files = eng.write_input(case, gen)
        t_render = time.perf_counter() - t0
        t0 = time.perf_counter()
        eng.execute(gen)
        t_run = time.perf_counter() - t0
        t0 = time.perf_counter()
        res = eng.read_results(gen)
        try:
            from interphase.analysis.summary import summarise
            summarise(case, res)
        except ImportError:
            pass
        t_read = time.perf_counter() - t0
        # plain: same files, output stripped; fix print/dumps gone, the physics untouched
        eng.write_input(case, plain)
        deck = OUTPUT_LINES.sub("# (output removed) ", files["in.deck"])
        (plain / "in.deck").write_text(deck)
        import subprocess
        subprocess.run(eng.command(), cwd=plain, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        g, p = loop_rate(gen / "log.liggghts", n), loop_rate(plain / "log.liggghts", n)
    driver = t_render + t_read
    print(f"grains {n}; shear stage particle-steps/s: generated {g:.3e}, plain {p:.3e}, ratio {g / p:.3f}")
    print(f"case wall time {t_run + driver:.1f} s: engine {t_run:.1f} s, render {t_render:.2f} s, "
          f"read+summarise {t_read:.2f} s, driver share {100 * driver / (t_run + driver):.2f} %")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 1000)
