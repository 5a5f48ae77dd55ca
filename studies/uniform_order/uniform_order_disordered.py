"""Intervention for studies/uniform_order/uniform_order.py: the same cases started from a DISORDERED packing.

Every run of the tool starts from `engines.packing.lattice_packing`: staggered rows of pitch
1.02·d_max, i.e. a slightly expanded triangular lattice with rows parallel to the shear. Uniform
discs (±5 %) consolidate from it into a crystal with those rows kept (studies/uniform_order/uniform_order.py). Here
the lattice is replaced, for this process only (a monkeypatch of `engines.device.lattice_packing`;
the tool's code is unchanged), by: row 0 exactly as the lattice has it (so the soil test's frozen bed,
its lowest row, is the study's), every other grain placed by random sequential addition (no two
centres closer than 1.02·d_max, x periodic) in a taller region whose exclusion-disc fraction is 0.40
(a random, loose start; the engine's consolidation then packs it under gravity and the servo platen).
Grain diameters are the lattice's own draw (same seed, same sizes, same order).
`--bed irregular` (box only) also replaces the soil test's frozen bed: BED_KEEP (70 %) of row 0's
grains, at random x along the row (1D random sequential addition, no two centres closer than
1.02·d_max, periodic), still at row 0's height (the device freezes every grain at the lowest
height): a bed with gaps from 0 to more than a grain and no period for a crystal to copy; with
`--start lattice` the soil above it stays the tool's lattice (row 0's other grains moved to the
lattice's next free slots at its top), so the bed alone changes.

The run folders carry the case id of the unpatched case (the id hashes the inputs, not the
packing): keep them OUT of any campaign's runs folder. Default: /tmp/uni_runs/disordered/<label>.

Run:  PYTHONPATH=src .venv/bin/python studies/uniform_order/uniform_order_disordered.py --gradation mono --test box \
          --seeds 1 2 3 [--out /tmp/uni_runs/disordered]
then  PYTHONPATH=src .venv/bin/python studies/uniform_order/uniform_order.py /tmp/uni_runs/disordered
"""

from __future__ import annotations

import argparse
import functools
import math
import sys
from pathlib import Path

import numpy as np

import interphase as ip
import interphase.engines.device as device_mod
from interphase.engines.packing import Packing, lattice_packing

RSA_FRACTION = 0.40      # area fraction of the exclusion discs (diameter 1.02 d_max) in the random region
SEED_OFFSET = 7919       # the placement's random stream, apart from the lattice's


BED_KEEP = 0.70          # --bed irregular: this share of row 0's grains, at random x (1D random addition; its jamming limit is 0.748)


def irregular_row(rng, n_keep: int, x_min: float, L: float, pitch: float) -> np.ndarray:
    """n_keep centres on [x_min, x_min + L), periodic, no two closer than pitch: random sequential
    addition in 1D (gaps from 0 to a grain and more: no period for a crystal to copy)."""
    xs = np.empty(0)
    while xs.size < n_keep:
        c = rng.uniform(x_min, x_min + L)
        d = np.abs(xs - c)
        if np.all(np.minimum(d, L - d) >= pitch):
            xs = np.append(xs, c)
    return xs


def disordered_packing(case, x_min: float, x_max: float, z_floor: float, *, irregular_bed: bool = False,
                       lattice_start: bool = False) -> Packing:
    """The start this bench swaps in for `lattice_packing` (the module doc): irregular_bed, row 0 made
    irregular (--bed irregular); lattice_start, the tool's lattice kept above it (--start lattice)."""
    lat = lattice_packing(case, x_min, x_max, z_floor)
    pitch = 1.02 * case.gradation.d_max
    per_row = int(math.floor((x_max - x_min) / pitch - 0.5))
    n = lat.n
    L = x_max - x_min
    x, z = lat.x.copy(), lat.z.copy()
    if irregular_bed:          # the bed (row 0, every grain at its height) made irregular: fewer, at random x
        keep = int(round(BED_KEEP * per_row))
        x[:keep] = irregular_row(np.random.default_rng(case.seed + 2 * SEED_OFFSET), keep, x_min, L, pitch)
        if lattice_start:      # row 0's other grains go to the next free slots of the lattice, at its top
            slots = np.arange(n, n + per_row - keep)
            row, col = slots // per_row, slots % per_row
            x[keep:per_row] = x_min + pitch * (col + 0.5 + 0.5 * (row % 2))
            z[keep:per_row] = z_floor + pitch * (0.5 + row * math.sqrt(3) / 2)
            z[keep:] += 0.15 * pitch   # a bed grain may now sit under a row-1 grain: lift the lattice clear
            return Packing(x, z, lat.diameter, float(np.max(z + lat.diameter / 2)))
        per_row = keep
    rest = n - per_row
    z0 = z_floor + pitch * (0.5 + math.sqrt(3) / 2)        # row 1's height in the lattice
    height = rest * math.pi * pitch ** 2 / 4 / RSA_FRACTION / L
    rng = np.random.default_rng(case.seed + SEED_OFFSET)
    px, pz = list(x[:per_row]), list(z[:per_row])
    placed_x, placed_z = np.array(px), np.array(pz)
    k = per_row
    tries = 0
    while k < n:
        cx = rng.uniform(x_min, x_max, 256)
        cz = rng.uniform(z0, z0 + height, 256)
        for xi, zi in zip(cx, cz):
            dx = np.abs(placed_x - xi)
            dx = np.minimum(dx, L - dx)
            if np.all(dx * dx + (placed_z - zi) ** 2 >= pitch * pitch):
                placed_x = np.append(placed_x, xi)
                placed_z = np.append(placed_z, zi)
                k += 1
                if k == n:
                    break
        tries += 1
        if tries > 20000:
            raise RuntimeError(f"random placement stalled at {k} of {n} grains")
    d = lat.diameter
    return Packing(placed_x, placed_z, d, float(np.max(placed_z + d / 2)))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--campaign", default="studies/uniform_order/uniform_order.toml")
    ap.add_argument("--gradation", default="mono")
    ap.add_argument("--test", default="box", choices=["box", "interface"])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--out", type=Path, default=Path("/tmp/uni_runs/disordered"))
    ap.add_argument("--bed", choices=["lattice", "irregular"], default="lattice",
                    help="irregular: the box's frozen bed (row 0) made of BED_KEEP of its grains at random x")
    ap.add_argument("--start", choices=["random", "lattice"], default="random",
                    help="lattice (with --bed irregular only): keep the tool's lattice above the bed")
    args = ap.parse_args(argv)
    irregular, lattice_start = args.bed == "irregular", args.start == "lattice"
    if lattice_start and not irregular:
        ap.error("--start lattice is the tool's own start: use `campaign run` (only --bed irregular changes it here)")
    device_mod.lattice_packing = functools.partial(disordered_packing, irregular_bed=irregular,
                                                   lattice_start=lattice_start)   # this process only
    planned = [p for p in ip.plan(ip.load_campaign(args.campaign))
               if p.role == args.test and p.case.gradation.name == args.gradation and p.case.seed in args.seeds]
    from interphase.campaign.runner import run_single
    for p in sorted(planned, key=lambda p: p.case.seed):
        tag = ("lattice" if lattice_start else "disordered") + ("-irregular-bed" if irregular else "")
        folder = args.out / f"{tag}-{p.label}"
        res = run_single(p.case, "liggghts", folder)
        s = res.get("summary", {})
        print(p.label, res["status"], f"peak {s.get('peak_stress_ratio', float('nan')):.4f}",
              f"residual {s.get('residual_stress_ratio', float('nan')):.4f}",
              f"solid fraction {s.get('solid_fraction', float('nan')):.4f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
