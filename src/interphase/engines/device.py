"""The test device of a Case, engine-neutral: walls, platen, grains, bounds, clock and step counts.

`device(case)` computes it once; LIGGGHTS (engines/liggghts.py) and YADE (engines/yade.py) only
write it in their own formats, so the cross-check compares two engines on one device.

Frame: x = shear axis, z up into the soil, y out of plane (grain centres at y = 0); lengths m,
forces N, times s. Walls are segments (x0, z0, x1, z1): their normal is the direction of travel
turned +90° (left of it), which faces the soil. The moving wall group travels −x at the shear
velocity, so the soil moves +x relative to it (shear_sign = +1: the engine frame is the analysis
frame).
  interface: the rough surface (the profile, shifted to start `margin` before x = 0 and long
    enough for the whole shear) under the soil box [0, L] between two fixed side walls whose
    bottoms sit above the surface's highest point (`side_walls`); grains whose centres cross the
    exit planes x = 0 or x = L have left the box and are removed.
  box: a direct shear box of height H split at H/2; the lower half (bottom, sides, right flange)
    moves, the upper half (sides, left flange) is fixed; the flanges close the openings the
    slide uncovers.
A servo platen holds σ·L·t on top of the soil (t = D50, the quasi-2D thickness).
The 3D device (Case.three_d, docs/3d.md) is the periodic one made deep: also periodic in y over
[−W/2, W/2] (W = Case.box_depth = t), grains on a 3D lattice filling it, every wall (surface,
platen, the box test's floor) extruded over exactly that depth (`wall_reach` = W/2); a case with
relief across the shear (Case.profile_y) has the areal surface z = p(x) + q(y) as its mesh instead,
and a case on an areal scan its closed patch (Case.surface_patch: two triangles a grid cell).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from interphase.case import Case
from interphase.errors import InputError
from interphase.engines.packing import Packing, lattice_packing, lattice_packing_3d, start_packing
from interphase.material import rayleigh_time, youngs_modulus
from interphase.recipe import RECIPE, Recipe, RunRecord, Steps
from interphase.surface.mesh import separable_triangles

Segment = tuple[float, float, float, float]

# read by campaign/plan.py's run-time estimate
CONSOLIDATION_TIME = RECIPE.consolidation_time


@dataclass(frozen=True, eq=False)
class Device:
    """Everything both engines build a run from (see the module docstring for the frame)."""

    case: Case
    recipe: Recipe
    dt: float                          # time step [s]
    skin: float                        # neighbour-list skin [m]
    wall_reach: float                  # walls span |y| ≤ this [m], beyond any grain
    moving: tuple[Segment, ...]        # the moving wall group (interface: the surface's segments)
    fixed: tuple[Segment, ...]         # walled interface: side walls; walled box: the upper half
    exits: tuple[Segment, ...] | None  # walled interface: the planes x = 0 and x = L, full height
    platen: tuple[Segment, ...]        # flat (walled) or a saw-tooth with teeth down (periodic)
    platen_com: tuple[float, float]    # (x, z) of the platen's centre [m]
    platen_force: float                # target [N], σ·L·t
    bounds: tuple[float, float, float, float]   # (x_lo, x_hi, z_lo, z_hi): a grain outside is lost
    window: tuple[float, float, float] | None   # (x0, x1, z_top) measuring window; box: None
    packing: Packing
    steps: Steps
    periodic: bool = False             # x periodic over [x_lo, x_hi] = [0, L]
    bed: tuple[int, ...] = ()          # periodic box: grains (packing indices) frozen to the moving floor
    depth: float | None = None         # 3D device: y periodic over [−depth/2, depth/2] [m]; None: quasi-2D
    surface_mesh: tuple[np.ndarray, np.ndarray] | None = None   # 3D areal surface: (points, triangles) [m];
                                       # None: the moving segments extruded over the depth

    shear_sign = 1

    def __post_init__(self):
        for a in (self.packing.x, self.packing.y, self.packing.z, self.packing.diameter):   # shared through the cache
            if a is not None:
                a.flags.writeable = False

    @property
    def test(self) -> str:
        return self.case.test

    @property
    def wall_names(self) -> tuple[str, str]:
        """Names of the moving and the fixed wall group."""
        if self.periodic:
            return ("surface", "sides") if self.test == "interface" else ("floor", "sides")
        return ("surface", "sides") if self.test == "interface" else ("lower", "upper")

    @property
    def thickness(self) -> float:
        return self.case.thickness

    @property
    def n_grains(self) -> int:
        return self.packing.n

    @property
    def platen_band(self) -> tuple[float, float]:
        """Consolidation ends once the platen force lies strictly between these [N]."""
        tol = self.recipe.platen_tolerance
        return (1 - tol) * self.platen_force, (1 + tol) * self.platen_force

    @property
    def platen_speed_limit(self) -> float:
        """The fastest the platen may move [m/s]: half a skin per two steps, so that no contact
        is missed between neighbour-list builds (LIGGGHTS refuses vel_max ≥ skin/(2·dt))."""
        return 0.5 * self.skin / (2 * self.dt)

    @property
    def platen_servo(self) -> tuple[float, float]:
        """(v_max [m/s], saturation [-]) of the platen servo, one law in both engines: the platen moves
        at v_max × (relative force error) / saturation, capped at ±v_max, down when the grains push
        less than the target (LIGGGHTS: `servo/vel_max` v_max and `kp` = 1/saturation in proportional
        mode; YADE: engines.yade_driver.servo_velocity). In-band gain G = 0.1·ratio·r_min/dt per unit
        error, ratio = servo_gain·(σ/E*)^(2/3) (Hertz, E* = E/(2(1−ν²))): the platen moves the same
        fraction of the grains' overlap under σ per step at any stiffness (the in-band law of
        LIGGGHTS' `mode auto ratio`). v_max = G·servo_saturation (also the approach speed), never
        above the speed limit; not `mode auto`'s tenfold jump, which locked one well-graded packing
        into a two-step limit cycle (docs/liggghts.md)."""
        case, r = self.case, self.recipe
        e_star = youngs_modulus(case.shear_modulus, case.poisson) / (2 * (1 - case.poisson ** 2))
        ratio = r.servo_gain * (case.normal_stress / e_star) ** (2 / 3)
        gain = 0.1 * ratio * (case.gradation.d_min / 2) / self.dt
        return min(gain * r.servo_saturation, self.platen_speed_limit), r.servo_saturation

    def record(self, engine: str) -> RunRecord:
        """What recipe.json states about a run of this device by `engine`."""
        return RunRecord(engine=engine, test=self.test, dt=self.dt, shear_velocity=self.case.shear_velocity,
                         shear_sign=self.shear_sign, thickness=self.thickness, n_grains=self.n_grains,
                         platen_force=self.platen_force, window=self.window, steps=self.steps, recipe=self.recipe,
                         period=self.case.box_length if self.periodic else None, depth=self.depth)


def time_step(case: Case, recipe: Recipe = RECIPE) -> float:
    """dt = time_step_fraction × Rayleigh time of the smallest grain [s]."""
    return recipe.time_step_fraction * rayleigh_time(case.gradation.d_min / 2, case.density, case.shear_modulus,
                                                     case.poisson)


def steps_for(duration: float, dt: float, multiple: int = 1) -> int:
    """Time steps covering `duration` [s] at step `dt` [s], rounded up to a multiple of `multiple`."""
    n = max(1, int(math.ceil(duration / dt)))
    return -(-n // multiple) * multiple


def step_counts(case: Case, dt: float, recipe: Recipe = RECIPE) -> Steps:
    """The run's step counts. The snapshot interval is Case.snapshot_every of shear; the history
    interval divides it (about history_points rows over the shear), and the consolidation stretch
    and chunks are multiples of it, so the shear starts on a dump step."""
    n_shear = steps_for(case.shear_distance / case.shear_velocity, dt)
    n_snap = max(1, int(round(case.snapshot_every / case.shear_velocity / dt)))
    k = max(1, round(n_snap / max(1, n_shear // recipe.history_points)))
    n_history = max(1, n_snap // k)
    n_snap = n_history * k
    return Steps(n_consolidate=steps_for(recipe.consolidation_time, dt, n_snap),
                 n_chunk=steps_for(recipe.chunk_time, dt, n_snap), n_chunks_max=recipe.consolidation_chunks,
                 n_shear=n_shear, n_snapshot=n_snap, n_history=n_history)


@functools.lru_cache(maxsize=8)
def device(case: Case, recipe: Recipe = RECIPE) -> Device:
    """The device of `case` (cached: both engines rendering one case share it; do not mutate its
    arrays)."""
    if case.periodic:
        return _periodic(case, recipe)
    d_min, d_max = case.gradation.d_min, case.gradation.d_max
    L, D = case.box_length, case.shear_distance
    margin = case.surface_margin
    dt = time_step(case, recipe)
    if case.test == "interface":
        prof = case.surface()                     # starts `margin` before the box
        x, z = prof.x, prof.z
        top = float(z.max())
        pack = lattice_packing(case, 0.0, L, top + 0.02 * d_max)
        wall_top = pack.top + 3 * d_max
        z_lo = float(z.min()) - d_max
        moving = _segments(x, z)
        fixed = tuple(tuple(s) for s in side_walls(prof, L, d_min, d_max, case.d50, wall_top))
        exits = ((0.0, z_lo, 0.0, wall_top), (L, wall_top, L, z_lo))
        x_lo, x_hi = float(x.min()) - D - d_max, float(x.max()) + d_max     # the surface travels −D
        window = (*case.window, top + d_max)
    else:
        exits, window = None, None
        z_mid = case.box_height / 2
        gap = 0.05 * d_min
        pack = lattice_packing(case, 0.0, L, 0.0)
        wall_top = max(pack.top, case.box_height) + 3 * d_max
        far = D + margin
        moving = ((-far, 0.0, L + far, 0.0),                  # bottom
                  (0.0, z_mid - gap, 0.0, 0.0),               # left side
                  (L, 0.0, L, z_mid - gap),                   # right side
                  (L + far, z_mid - gap, L, z_mid - gap))     # right flange (faces down)
        fixed = ((0.0, wall_top, 0.0, z_mid), (L, z_mid, L, wall_top),
                 (0.0, z_mid, -far, z_mid))                   # left flange (faces up)
        z_lo = -d_max
        x_lo, x_hi = -far - D - d_max, L + far + d_max
    platen_z = pack.top + 0.5 * d_max
    pack, dz = _started(case, pack, platen_z)
    platen_z += dz
    inset = 0.02 * d_max
    return Device(case=case, recipe=recipe, dt=dt, skin=recipe.skin_fraction * d_min, wall_reach=case.wall_width / 2,
                  moving=moving, fixed=fixed, exits=exits,
                  platen=((L - inset, platen_z, inset, platen_z),), platen_com=(L / 2, platen_z),
                  platen_force=case.normal_stress * L * case.thickness, bounds=(x_lo, x_hi, z_lo, wall_top + 2 * d_max),
                  window=window, packing=pack, steps=step_counts(case, dt, recipe))


def _segments(x, z) -> tuple[Segment, ...]:
    return tuple(zip(x[:-1].tolist(), z[:-1].tolist(), x[1:].tolist(), z[1:].tolist()))


def _periodic(case: Case, recipe: Recipe) -> Device:
    """The wall-free device: x periodic over [0, L], no side walls, so nothing jams at an edge and
    the surface's shear force equals the platen's (exact equilibrium, no measuring window needed).
      interface: the surface is exactly [0, L] (a periodic profile, whole periods), sliding −x;
        the engines wrap it across the boundary;
      box (the soil's own test in this device): a bed of the soil's own grains — the lowest
        lattice row, frozen — rides −x on a flat floor just below it, so the soil shears against
        itself and its failure lies in the soil whatever a surface would do.
    Top: a saw-tooth platen, teeth of platen_tooth_d50·D50 pointing down at about 2 D50 spacing (a
    whole number over L), servo-held at σ·L·t: rough enough that the soil, not the platen, fails
    (docs/strength.md)."""
    d_max = case.gradation.d_max
    L, d50 = case.box_length, case.d50
    dt = time_step(case, recipe)
    bed: tuple[int, ...] = ()
    surface_mesh = None
    lattice = lattice_packing_3d if case.three_d else lattice_packing
    if case.test == "interface":
        prof, across, patch = case.surface(), case.surface_across(), case.surface_patch()
        top, z_lo = float(prof.z.max()), float(prof.z.min()) - d_max
        if across is not None:     # z(x, y) = p(x) + q(y): its highest and lowest points add
            top, z_lo = top + float(across.z.max()), z_lo + float(across.z.min())
            surface_mesh = separable_triangles(prof, across, -case.box_depth / 2)
        if patch is not None:      # a scan's patch: the lattice starts above its highest point
            top, z_lo = float(patch.z.max()), float(patch.z.min()) - d_max
            surface_mesh = patch.triangles(-case.box_depth / 2)
        pack = lattice(case, 0.0, L, top + 0.02 * d_max)
        moving = _segments(prof.x, prof.z)
        window = (0.0, L, top + d_max)
    else:
        pack = lattice(case, 0.0, L, 0.0)
        lowest = np.isclose(pack.z, pack.z.min())
        bed = tuple(int(i) for i in np.flatnonzero(lowest))
        floor = float(np.min(pack.z[lowest] - pack.diameter[lowest] / 2)) - 0.01 * d50
        moving, window, z_lo = ((0.0, floor, L, floor),), None, floor - d_max
    h = recipe.platen_tooth_d50 * d50
    n = max(1, round(L / (2 * d50)))
    base = pack.top + 0.5 * d_max + h          # the tips clear the highest grain by d_max/2
    top = base + 3 * d_max
    pack, dz = _started(case, pack, base)
    base += dz
    xs = np.linspace(L, 0.0, 2 * n + 1)        # right to left: the platen faces down
    zs = np.where(np.arange(2 * n + 1) % 2 == 1, base - h, base)
    depth = case.box_depth if case.three_d else None
    return Device(case=case, recipe=recipe, dt=dt, skin=recipe.skin_fraction * case.gradation.d_min,
                  wall_reach=case.wall_width / 2, moving=moving, fixed=(), exits=None,
                  platen=_segments(xs, zs), platen_com=(L / 2, base),
                  platen_force=case.normal_stress * L * case.thickness,
                  bounds=(0.0, L, z_lo, top), window=window, packing=pack,
                  steps=step_counts(case, dt, recipe), periodic=True, bed=bed, depth=depth,
                  surface_mesh=surface_mesh)


def _started(case: Case, lattice: Packing, platen_z: float) -> tuple[Packing, float]:
    """(grains, platen shift [m]) the run starts from: the lattice and 0, or, for a case with a
    Start, the source run's consolidated grains and its platen height less `platen_z` (the bounds
    and walls stay the lattice's, which lie above). The source must be this case's own lattice
    consolidated (same grains by id; the plan pairs a case with its run in the other engine)."""
    if case.start is None:
        return lattice, 0.0
    pack, z = start_packing(case)
    if pack.n != lattice.n or not np.allclose(pack.diameter, lattice.diameter, rtol=1e-6, atol=0.0):
        raise InputError(f"the {case.start.engine} run {case.start.case_id} is not a run of this case: its "
                         f"{pack.n} grains are not this case's {lattice.n} of the same sizes by id", where=case.start.folder,
                         fix="start a case only from a run of the same case (the plan does, with specimen_from)")
    return pack, z - platen_z


def wall_gap(profile, d_min: float, d_max: float, d50: float) -> float:
    """Height of the left side wall's bottom edge above the surface's highest point [m].

    A grain resting in a valley of the surface rides along with it; if it sticks out above the
    peaks by p, a wall edge lower than that catches it and the grain jams between the wall and the
    rising face (forces 10× typical, overlaps of 25 % D50, measured). So the edge sits p + 0.05·d_min
    above the peaks, p from the centroid trace of the largest grain (its highest local minimum),
    letting trapped grains leave with the surface as in the physical device. Free grains smaller
    than the gap can leave too; they are removed at the side planes and counted (`grains_left`).
    Only when that gap would let a free grain of median size through (p + 0.05·d_min ≥ D50: flat or
    shallow valleys, where grains ride on the peaks instead of in the valleys) the edge sits
    0.05·d_min above the peaks. A tighter bound (d_min/2) shut the 45° saw-tooth's 0.57 mm gap for
    well-graded grains (d_min = D50/2), and the largest grains jammed at the left wall in most seeds
    (max overlaps 0.31–0.63 D50, wall forces 7–20 N against a 2.9 N platen; with the gap
    0.09–0.28 D50 and 2–6 grains removed per run; docs/liggghts.md)."""
    from interphase.surface.trace import centroid_trace

    tr = centroid_trace(profile, d_max, dx=d_max / 1000)   # p to ~1e-3·d_max; the default step cost 0.15 s
    c = tr.z
    minima = (c[1:-1] <= c[:-2]) & (c[1:-1] <= c[2:])
    p = float(np.max(c[1:-1][minima]) + d_max / 2 - profile.z.max()) if minima.any() else d_max
    # p < 0: valleys deeper than the largest grain hold it below the peaks, and the edge only has to
    # clear them (it sat inside the teeth on 27 of the 198 interface cases of group1–5.toml)
    gap = max(p, 0.0) + 0.05 * d_min
    return gap if gap < d50 else 0.05 * d_min


def side_walls(profile, length: float, d_min: float, d_max: float, d50: float,
               wall_top: float) -> list[list[float]]:
    """The interface box's two side walls as segments [x0, z0, x1, z1] [m] (left normal +x, right −x).

    The surface moves −x: valleys leave the box under the LEFT wall, carrying the grains trapped in
    them, so that wall's bottom sits `wall_gap` above the peaks. Valleys enter under the RIGHT wall
    empty, so it sits 0.05·d_min above the peaks: with the left wall's gap there, grains on the
    flats of spaced profiles were pushed out under it by the soil, met the next tooth outside and
    were shot away (lost atoms in 2 of 3 seeds, spaced saw-tooth μs = 0.2, measured)."""
    top = float(profile.z.max())
    left = top + wall_gap(profile, d_min, d_max, d50)
    right = top + 0.05 * d_min
    return [[0.0, wall_top, 0.0, left], [length, right, length, wall_top]]
