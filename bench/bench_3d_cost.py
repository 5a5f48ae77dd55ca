"""Cost of the 3D device (device = "periodic3d", docs/3d.md): one interface case at a few cell sizes.

The case: a 45° saw-tooth (Rt/D50 1, Sw/D50 2) extruded in y, well-graded grains, μs 0.5, G = 50 MPa,
100 kPa, 1 mm of shear at 0.05 m/s (kept short: the machine is shared); the cell L × W × H in D50
varies. Each runs once, one after the other, through the campaign's own `run_case` (render, run,
read, summarise). Reported per size: grains, the engine's wall time, the shear stage's wall time
per mm of shear (LIGGGHTS' "Loop time" of its last run, the shear), its particle-steps per second,
and the whole case's wall time; plus the summary's stress ratio and θr as a sanity check.

Run: PYTHONPATH=src .venv/bin/python bench/bench_3d_cost.py [L,W,H ...]   (default 10,5,10 14,7,10 20,10,10)
     [--shear MM] [--velocity M_S]   (the campaigns' protocol: --shear 6 --velocity 0.02)
LIGGGHTS on several ranks: INTERPHASE_LIGGGHTS_LAUNCHER="mpirun -np 2" (engines.base.EngineProfile).
"""

from __future__ import annotations

import json
import re
import tempfile
import time
from pathlib import Path

from interphase.campaign.runner import run_case
from interphase.case import Case
from interphase.engines.base import engine_spec
from interphase.engines.device import device
from interphase.material import Gradation
from interphase.surface.spec import ProfileSpec

SHEAR = 1e-3        # [m], default
VELOCITY = 0.05     # [m/s], default


def case_of(length: float, depth: float, height: float, shear: float = SHEAR, velocity: float = VELOCITY) -> Case:
    return Case(profile=ProfileSpec.make("sawtooth", rt=1, sw=2, sr=0), device="periodic3d", gradation=Gradation("poly"),
                box_length_d50=length, box_depth_d50=depth, box_height_d50=height, friction_ps=0.5,
                shear_modulus=50e6, shear_velocity=velocity, shear_distance=shear,
                snapshot_every=max(0.25e-3, shear / 12))


def shear_loop(log: Path) -> tuple[float, int]:
    """(seconds, steps) of the last `run` (the shear) from LIGGGHTS' log."""
    loops = re.findall(r"Loop time of ([0-9.eE+-]+) on \d+ procs for (\d+) steps", log.read_text())
    return float(loops[-1][0]), int(loops[-1][1])


def main(sizes, shear: float = SHEAR, velocity: float = VELOCITY):
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for length, depth, height in sizes:
            case = case_of(length, depth, height, shear, velocity)
            n = device(case).n_grains
            t0 = time.perf_counter()
            out = run_case(case, engine_spec("liggghts"), Path(tmp, f"c{length}x{depth}x{height}"))
            wall = time.perf_counter() - t0
            assert out["status"] == "done", out
            folder = Path(tmp, f"c{length}x{depth}x{height}")
            timings = json.loads((folder / "case.json").read_text())["timings"]
            sec, steps = shear_loop(folder / "log.liggghts")
            s = out["summary"]
            rows.append(dict(cell=f"{length:g} × {depth:g} × {height:g}", grains=n, engine_s=timings.get("execute"),
                             shear_s_per_mm=sec / (shear * 1e3), rate=n * steps / sec, wall_s=wall,
                             peak=s["peak_stress_ratio"], theta_r=s["theta_r_surface_deg"], r_yy=s["r_yy_surface"]))
            print(json.dumps(rows[-1]), flush=True)
    print("\n| cell L × W × H [D50] | grains | engine [s] | shear [s per mm] | particle-steps/s | case wall [s] "
          "| peak τ/σ | θr [°] | R_yy |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['cell']} | {r['grains']} | {r['engine_s']:.1f} | {r['shear_s_per_mm']:.1f} | {r['rate']:.2e} "
              f"| {r['wall_s']:.1f} | {r['peak']:.3f} | {r['theta_r']:.1f} | {r['r_yy']:.3f} |")


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sizes", nargs="*", default=["10,5,10", "14,7,10", "20,10,10"], help="L,W,H in D50")
    ap.add_argument("--shear", type=float, default=SHEAR * 1e3, help="shear distance [mm]")
    ap.add_argument("--velocity", type=float, default=VELOCITY, help="shear velocity [m/s]")
    a = ap.parse_args()
    main([tuple(float(v) for v in x.split(",")) for x in a.sizes], a.shear * 1e-3, a.velocity)
