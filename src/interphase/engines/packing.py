"""Initial grain packing of a Case, engine-neutral: a loose monolayer in the x–z plane (y = 0), or
for the 3D device (Case.three_d) a loose body-centred lattice filling the cell's depth in y.

Grains are drawn from the case's gradation (seeded) and laid on a staggered lattice of pitch
1.02·d_max inside the soil region, lowest row just above the surface's highest point; the engine
then consolidates them under gravity and the servo platen at the final stiffness. Units: m.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from interphase.case import Case
from interphase.errors import InputError


@dataclass(frozen=True)
class Packing:
    x: np.ndarray        # centres [m]
    z: np.ndarray
    diameter: np.ndarray
    top: float           # highest grain top [m]
    y: np.ndarray | None = None   # 3D packings: centres in y [m]; None: the monolayer at y = 0

    @property
    def n(self) -> int:
        return int(self.x.size)


def grain_count(case: Case) -> int:
    """n_grains, or enough grains to fill box_length × box_height at a 2D solid fraction of ~0.82."""
    if case.n_grains is not None:
        return case.n_grains
    if case.three_d:        # 3D: box_length × box_depth × box_height at a solid fraction of ~0.6
        volume = case.box_length * case.box_depth * case.box_height
        return max(2, int(round(0.6 * volume / (math.pi * case.d50 ** 3 / 6))))
    area = case.box_length * case.box_height
    d = case.d50
    return max(2, int(round(0.82 * area / (math.pi * d * d / 4))))


def lattice_packing(case: Case, x_min: float, x_max: float, z_floor: float) -> Packing:
    """Grains in x ∈ [x_min, x_max], rows upward from z_floor (the region's bottom) [m]."""
    rng = np.random.default_rng(case.seed)
    n = grain_count(case)
    d = case.gradation.sample(n, rng)
    pitch = 1.02 * case.gradation.d_max
    per_row = int(math.floor((x_max - x_min) / pitch - 0.5))
    if per_row < 2:
        raise InputError(f"the box is {x_max - x_min:.4g} m long, less than three grains",
                         where="case.box_length_d50",
                         fix=f"make the box at least {math.ceil(25 * pitch / case.d50) / 10:g} D50 long: 2.5 lattice "
                             f"pitches of the largest grain ({case.gradation.d_max / case.d50:.2f} D50)")
    k = np.arange(n)
    row, col = k // per_row, k % per_row
    x = x_min + pitch * (col + 0.5 + 0.5 * (row % 2)) + rng.uniform(-0.01, 0.01, n) * pitch
    z = z_floor + pitch * (0.5 + row * math.sqrt(3) / 2)
    return Packing(x, z, d, float(np.max(z + d / 2)))


def lattice_packing_3d(case: Case, x_min: float, x_max: float, z_floor: float) -> Packing:
    """Grains in x ∈ [x_min, x_max], y ∈ [−W/2, W/2] (W = Case.box_depth, periodic), layers upward
    from z_floor [m]: a body-centred lattice of pitch 1.02·d_max in x and y, odd layers shifted
    half a pitch in both, layer spacing 0.72·pitch (no two grains touch, across the y boundary
    neither)."""
    rng = np.random.default_rng(case.seed)
    n = grain_count(case)
    d = case.gradation.sample(n, rng)
    pitch = 1.02 * case.gradation.d_max
    depth = case.box_depth
    per_x = int(math.floor((x_max - x_min) / pitch - 0.5))
    per_y = int(math.floor(depth / pitch - 0.5))
    if per_x < 2 or per_y < 2:
        raise InputError(f"the 3D cell ({x_max - x_min:.4g} × {depth:.4g} m) holds fewer than two grains in x or y",
                         where="case.box_depth_d50" if per_y < 2 else "case.box_length_d50",
                         fix=f"make the cell at least {math.ceil(25 * pitch / case.d50) / 10:g} D50 long and deep: "
                             f"2.5 lattice pitches of the largest grain ({case.gradation.d_max / case.d50:.2f} D50)")
    k = np.arange(n)
    layer, rest = k // (per_x * per_y), k % (per_x * per_y)
    row, col = rest // per_x, rest % per_x
    shift = 0.5 * (layer % 2)
    x = x_min + pitch * (col + 0.5 + shift) + rng.uniform(-0.01, 0.01, n) * pitch
    y = -depth / 2 + pitch * (row + 0.5 + shift) + rng.uniform(-0.01, 0.01, n) * pitch
    z = z_floor + pitch * (0.5 + 0.72 * layer)
    return Packing(x, z, d, float(np.max(z + d / 2)), y)


def start_packing(case: Case) -> tuple[Packing, float]:
    """(grains, platen height [m]) of the run `case.start` names (interphase.case.Start): its grains
    at its first contact snapshot — the start of its shear, after its consolidation — in grain id
    order, which is the lattice's (engines number grains 1…n in packing order), and its platen's
    reference height (history platen_z, the same reference as Device.platen_com) at its first row
    of the shear. Read from the run's particles.parquet and history.parquet (interphase.tables)."""
    import pandas as pd

    start = case.start
    folder = Path(start.folder)
    try:
        p = pd.read_parquet(folder / "particles.parquet", columns=["snapshot", "shear_disp", "id", "x", "z", "radius"])
        h = pd.read_parquet(folder / "history.parquet", columns=["shear_disp", "platen_z"])
    except (OSError, ValueError, KeyError) as exc:
        raise InputError(f"the {start.engine} run {start.case_id} this case starts from has no readable particle "
                         f"and history tables ({type(exc).__name__}: {exc})", where=str(folder),
                         fix=f"finish that run first: `campaign run` runs the {start.engine} cases before the others "
                             "when the campaign has specimen_from") from None
    first = p[p["snapshot"] == p["snapshot"].min()].sort_values("id")
    row = int(np.argmin(np.abs(h["shear_disp"].to_numpy() - float(first["shear_disp"].iloc[0]))))
    x, z, r = (first[c].to_numpy(float) for c in ("x", "z", "radius"))
    return Packing(x, z, 2 * r, float(np.max(z + r))), float(h["platen_z"].iloc[row])


def write_liggghts_data(p: Packing, density: float, box: tuple[float, ...]) -> str:
    """LIGGGHTS `atom_style granular` data file: `id type diameter density x y z`."""
    xlo, xhi, ylo, yhi, zlo, zhi = box
    head = (f"interphase-dem grains\n\n{p.n} atoms\n4 atom types\n\n"
            f"{xlo!r} {xhi!r} xlo xhi\n{ylo!r} {yhi!r} ylo yhi\n{zlo!r} {zhi!r} zlo zhi\n\nAtoms\n\n")
    ids = np.arange(1, p.n + 1)
    table = np.column_stack([ids, np.ones(p.n), p.diameter, np.full(p.n, density), p.x,
                             np.zeros(p.n) if p.y is None else p.y, p.z])
    buf = io.StringIO()
    np.savetxt(buf, table, fmt=["%d", "%d", "%.12g", "%.12g", "%.12g", "%.12g", "%.12g"])
    return head + buf.getvalue()
