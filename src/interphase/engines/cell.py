"""The element cell of the laboratory's tests (Case.test "triaxial" in 3D, "biaxial" in quasi-2D),
engine-neutral: grains, cell, clock and step counts (docs/soils.md, "The laboratory's test").

Why a cell periodic in every direction, not walls: the specimen has no boundary at all, so there is
no wall layering (the density next to a flat wall is lower over about one grain) to bias its void
ratio, and the stress is the contact stress of every grain, σ_ij = (1/V) Σ_c f_i l_j (the engine's
virial), not a wall force over a nominal area. The laboratory's membrane is flexible; a periodic cell is
the closest a DEM cell comes to it without modelling one. What it cannot do: a single inclined shear
band must be compatible with the periodicity, so localisation comes later and softening is milder
than in a laboratory specimen (said with the measurements in docs/soils.md).

Protocol (`interphase.recipe.CellRecipe`): the grains start on a loose jittered lattice; every axis'
length is servo-controlled to σ3′ (isotropic consolidation) with the grain–grain sliding and rolling
friction scaled by `Case.preparation` (0: frictionless, the densest this protocol makes); at rest on
σ3′ the grains' own friction is restored and the cell settles; then the axial length (z) shrinks at
`Case.strain_rate` (engineering) to `Case.axial_strain` while the lateral axes (x and y; biaxial: x)
hold σ3′. During the compression the box moves and the grains do not jump with it: the periodic images
carry the box's velocity, so the mean motion reaches the grains through contacts and each contact's
tangential spring sees its whole relative motion (moving the grains with the box, as in consolidation,
hides the affine part from it and lowers φ_peak by ~5° and φ at 40 % by ~8°: docs/soils.md).
Quasi-2D: one grain layer at y = 0 (forces in y set to 0, as in the shear devices), y not deformed;
stresses are per the thickness t = D50 (Case.thickness), so σ = virial/(Lx·Lz·t).

Frame: z the axial (major principal) direction, compression positive. Units SI.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from interphase.case import Case
from interphase.engines.packing import Packing
from interphase.material import rayleigh_time, youngs_modulus
from interphase.recipe import CELL_RECIPE, RECIPE, CellRecipe, RunRecord, Steps


@dataclass(frozen=True, eq=False)
class Cell:
    """Everything an engine builds a cell run from."""

    case: Case
    recipe: CellRecipe
    dt: float                     # [s]
    skin: float                   # [m]
    packing: Packing              # the loose lattice (3D: y set; 2D: y None, centres at y = 0)
    size: tuple[float, float, float]   # (Lx, Ly, Lz) of the start [m]; 2D: Ly = the slab's 2·d_max
    solid: float                  # Σ grain volume (3D) or Σ grain section area × t (2D) [m³]
    steps: Steps                  # n_consolidate, n_chunk, n_chunks_max, n_shear; n_snapshot = n_history
    n_settle: int                 # steps at rest on σ3′ with the grains' own friction, before the shear

    @property
    def three_d(self) -> bool:
        return self.case.three_d          # triaxial runs in the periodic3d cell (Case.CELL_TESTS)

    @property
    def thickness(self) -> float:
        """The stress's out-of-plane thickness [m]: 2D D50 (the shear devices' rule); 3D unused."""
        return self.case.d50

    def record(self, engine: str) -> RunRecord:
        return RunRecord(engine=engine, test=self.case.test, dt=self.dt, shear_velocity=0.0, shear_sign=1,
                         thickness=self.size[1] if self.three_d else self.thickness, n_grains=self.packing.n,
                         platen_force=0.0, window=None, steps=self.steps, recipe=RECIPE)


def cell_steps(case: Case, dt: float, r: CellRecipe = CELL_RECIPE) -> tuple[Steps, int]:
    """(Steps, settle steps): every count a multiple of the servo interval, the history interval
    dividing the shear into about history_points rows."""
    every = r.servo_every

    def steps(duration):
        n = max(1, math.ceil(duration / dt))
        return -(-n // every) * every

    n_shear = steps(case.axial_strain / case.strain_rate)
    n_history = max(every, (n_shear // r.history_points) // every * every)
    return Steps(n_consolidate=steps(r.consolidation_time), n_chunk=steps(r.chunk_time),
                 n_chunks_max=r.consolidation_chunks, n_shear=n_shear, n_snapshot=n_history,
                 n_history=n_history), steps(r.chunk_time)


def servo_gain(case: Case, dt: float, every: int, r: CellRecipe = CELL_RECIPE) -> float:
    """The servo's gain G [1/s] for an evaluation every `every` steps of `dt` [s]:
    servo_gain·(σ3′/E*)^(2/3)/(every·dt), E* = E/(2(1 − ν²)) (CellRecipe: the same relative stress
    change per update at any stress and stiffness)."""
    E = youngs_modulus(case.shear_modulus, case.poisson)
    return r.servo_gain * (case.normal_stress / (E / (2 * (1 - case.poisson ** 2)))) ** (2 / 3) / (every * dt)


def cell_lattice(case: Case, r: CellRecipe = CELL_RECIPE) -> tuple[Packing, tuple[float, float, float]]:
    """n_grains on a random subset of a cubic (3D) or square (2D, x–z) lattice of pitch
    lattice_pitch·d_max filling [0, L]³ (2D: [0, L]²), jittered; sizes from the gradation. The
    packing's random generator is seeded by Case.seed."""
    rng = np.random.default_rng(case.seed)
    n, d_max = case.n_grains, case.gradation.d_max
    pitch = r.lattice_pitch * d_max
    dim = 3 if case.test == "triaxial" else 2
    k = math.ceil(n ** (1 / dim) - 1e-9)
    sites = np.sort(rng.choice(k ** dim, size=n, replace=False))
    idx = np.stack(np.unravel_index(sites, (k,) * dim), axis=1)
    pos = (idx + 0.5 + rng.uniform(-r.lattice_jitter, r.lattice_jitter, idx.shape)) * pitch
    d = case.gradation.sample(n, rng)
    L = k * pitch
    if dim == 3:
        return Packing(pos[:, 0], pos[:, 2], d, L, pos[:, 1]), (L, L, L)
    return Packing(pos[:, 0], pos[:, 1], d, L), (L, 2 * d_max, L)


@functools.lru_cache(maxsize=8)
def cell(case: Case, r: CellRecipe = CELL_RECIPE) -> Cell:
    """The cell of a triaxial or biaxial case (cached; do not mutate its arrays)."""
    d_min = case.gradation.d_min
    dt = r.time_step_fraction * rayleigh_time(d_min / 2, case.density, case.shear_modulus, case.poisson)
    pack, size = cell_lattice(case, r)
    d = pack.diameter
    solid = float(np.sum(math.pi / 6 * d ** 3)) if case.test == "triaxial" \
        else float(np.sum(math.pi / 4 * d ** 2)) * case.d50
    steps, n_settle = cell_steps(case, dt, r)
    return Cell(case=case, recipe=r, dt=dt, skin=r.skin_fraction * d_min, packing=pack, size=size, solid=solid,
                steps=steps, n_settle=n_settle)


def inertial_number(strain_rate: float, d50: float, density: float, pressure: float) -> float:
    """I = γ̇ d50 √(ρ/p′) [-] with γ̇ the shear strain rate [1/s] (ε̇1 − ε̇3), p′ [Pa]."""
    return strain_rate * d50 * math.sqrt(density / pressure)
