"""The recipe of a simulation as data, and recipe.json: what every case folder states about its run.

`Recipe` holds the protocol choices that are not physical inputs of a Case (those are Case fields,
restitution included): time step and neighbour skin rules, the consolidation loop, output rates,
the platen servos, the rolling model, the timeout estimate. Both engines read it through the device
(engines/device.py); docs/methods.md and docs/engines.md say why each value is what it is.

recipe.json (one schema for both engines, `RunRecord`) is written beside the engine's input files:
the recipe plus the numbers a reader needs to put engine output on the analysis clock and frame
(dt, shear velocity, step counts, shear sign, thickness, grain count, measuring window). The readers
(io/liggghts.py, io/yade.py) read it; folders written before it existed are read from their
engine.json (LIGGGHTS) or params.json (YADE). Units: SI (m, s, N).
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path

SCHEMA = "interphase-dem recipe 1"
FILE = "recipe.json"
#: per engine, the version of what it is given for a Case (templates, device, packing, rendering) and,
#: for YADE, of what the driver does with it. Part of every case id of that engine (Engine.recipe_id):
#: a change to one engine's inputs makes new ids for that engine only, so that, say, a faster YADE
#: driver leaves a LIGGGHTS campaign's finished cases current. Bump an engine's number with any change
#: that alters its rendered input files or the driver's behaviour: tests/test_recipe_version.py renders
#: reference cases of both engines and fails, naming the files and the engine, until the number is
#: bumped and the reference hashes (tests/data/recipe_renders.json) are written again.
RECIPE_VERSIONS = {"liggghts": 1, "yade": 3}


@dataclass(frozen=True)
class Recipe:
    """Protocol constants of both engines (which engine uses a value is said beside it)."""

    time_step_fraction: float = 0.2      # dt = this × Rayleigh time of the smallest grain
    skin_fraction: float = 0.2           # neighbour skin = this × d_min
    gravity: float = 9.81                # [m/s²], −z
    # consolidation under the servo platen: a first stretch, then chunks until the platen force lies
    # within ±platen_tolerance of its target; after consolidation_chunks chunks: 'not_consolidated'
    consolidation_time: float = 0.02     # [s] the first stretch
    chunk_time: float = 0.005            # [s] one chunk
    consolidation_chunks: int = 40
    platen_tolerance: float = 0.03       # relative
    history_points: int = 400            # history rows over the shear (at least; aligned to snapshots)
    thermo_points: int = 20              # LIGGGHTS thermo lines and grain-balance rows over the shear
    # the platen servo of both engines (Device.platen_servo): in-band gain and the relative force
    # error at which the platen reaches its top speed
    servo_gain: float = 2.4
    servo_saturation: float = 0.9
    # YADE's own servo until its recipe 3 (0.1 m/s, full speed at 10 % error); read by nothing now,
    # kept because every case id hashes the Recipe's values (removing them would renew LIGGGHTS' ids)
    servo_speed: float = 0.1
    servo_band: float = 0.1
    rolling_model: str = "epsd2"         # LIGGGHTS rolling friction model (YADE: its elastic–plastic law)
    platen_tooth_d50: float = 1.0        # periodic device: the platen's teeth [D50] (Rt/D50 1 and 3
                                         # surfaces failed in the soil under it: docs/strength.md)
    typical_overlap: float = 0.003       # δ/D50 that sizes YADE's rolling stiffness krot
    # timeout estimate: timeout_base + timeout_factor × steps × grains / throughput [s]
    timeout_base: float = 60.0
    timeout_factor: float = 5.0
    throughput_liggghts: float = 1.5e6   # particle-steps per second assumed (measured 2.5–4e6)
    throughput_yade: float = 0.5e6       # (measured ~1e6 with the driver's output)

    def throughput(self, engine: str) -> float:
        """Particle-steps per second assumed for `engine` ('liggghts' | 'yade')."""
        return getattr(self, f"throughput_{engine}")

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


RECIPE = Recipe()


@dataclass(frozen=True)
class Steps:
    """Step counts of a run [time steps]. Consolidation: n_consolidate, then up to n_chunks_max
    chunks of n_chunk; shear: n_shear. Contact snapshots every n_snapshot and history rows every
    n_history steps, counted from the shear start; n_history divides n_snapshot, which divides
    n_consolidate and n_chunk, so that every snapshot has a history row and the shear starts on one."""

    n_consolidate: int
    n_chunk: int
    n_chunks_max: int
    n_shear: int
    n_snapshot: int
    n_history: int

    @property
    def most(self) -> int:
        """The longest a run can be: every chunk used, then the shear."""
        return self.n_consolidate + self.n_chunks_max * self.n_chunk + self.n_shear


@dataclass(frozen=True)
class RunRecord:
    """The contents of a case folder's recipe.json. `recipe` is None for a folder written before
    recipe.json existed. window: (x0, x1, z_top) [m] of the measuring window, None for box tests."""

    engine: str
    test: str
    dt: float                    # [s]
    shear_velocity: float        # [m/s] of the moving wall group, in −x
    shear_sign: int              # +1: the engine frame is the analysis frame
    thickness: float             # [m] quasi-2D thickness: F = σ·L·t
    n_grains: int                # grains placed
    platen_force: float          # [N] target
    window: tuple[float, float, float] | None
    steps: Steps
    recipe: Recipe | None = None
    period: float | None = None  # [m] x period of a periodic device (contacts across it are unwrapped)
    depth: float | None = None   # [m] y period of the 3D device (docs/3d.md); None: quasi-2D

    def to_json(self) -> str:
        data = dataclasses.asdict(self)
        if data["depth"] is None:       # quasi-2D records stay as they were
            del data["depth"]
        return json.dumps({"schema": SCHEMA, **data}, indent=1, allow_nan=False)

    @classmethod
    def from_dict(cls, data: dict) -> "RunRecord":
        data = {k: v for k, v in data.items() if k != "schema"}
        window = data.get("window")
        return cls(**(data | dict(steps=Steps(**data["steps"]), window=tuple(window) if window else None,
                                  recipe=Recipe(**data["recipe"]) if data.get("recipe") else None)))


def read_record(folder: str | Path) -> RunRecord:
    """The RunRecord of a case folder: recipe.json, else the engine file an older folder has."""
    folder = Path(folder)
    if (folder / FILE).exists():
        return RunRecord.from_dict(json.loads((folder / FILE).read_text()))
    if (folder / "engine.json").exists():        # LIGGGHTS: the deck's values, flat
        m = json.loads((folder / "engine.json").read_text())
        engine, steps = "liggghts", m
    elif (folder / "params.json").exists():      # YADE: the driver's input, steps nested
        m = json.loads((folder / "params.json").read_text())
        engine, steps = "yade", m["steps"]
    else:
        from interphase.errors import InputError
        raise InputError(f"{FILE} is missing", where=str(folder / FILE), fix="rerun the case")
    return RunRecord(
        engine=engine, test=m.get("test", "interface" if m.get("exits") else "box"), dt=m["dt"],
        shear_velocity=m["shear_velocity"], shear_sign=m.get("shear_sign", 1), thickness=m.get("thickness", 0.0),
        n_grains=m.get("n_grains", 0), platen_force=m.get("platen_force", 0.0),
        window=tuple(m["window"]) if m.get("window") else None,
        steps=Steps(**{f.name: steps[f.name] for f in dataclasses.fields(Steps)}))


@dataclass(frozen=True)
class CellRecipe:
    """Protocol constants of the element cell (triaxial / biaxial, engines/cell.py). Hashed into the
    identity of every cell case (Case.canonical: `cell_recipe`), never into another case's, so that a
    change here renews the cell cases only. Why each value is what it is: docs/soils.md."""

    # 2: the axial compression moves the grains through their velocities (LIGGGHTS `remap v`), not by
    # remapping their positions with the box (`remap x`, version 1), which hid the affine part of every
    # contact's relative motion from its tangential spring: φ at 40 % 22° against 30° (docs/soils.md)
    version: int = 2
    time_step_fraction: float = 0.2      # dt = this × Rayleigh time of the smallest grain
    skin_fraction: float = 0.2           # neighbour skin = this × d_min
    lattice_pitch: float = 1.1           # the loose start: grains on a cubic (3D) or square (2D) lattice of
                                         # this × d_max, jittered by ±lattice_jitter of the pitch
    lattice_jitter: float = 0.04
    # the stress servo of every free cell axis: strain rate = G × (σ − σ_target)/σ_target, capped at
    # ±compaction_cap while consolidating and ±shear_cap while shearing [1/s]; the stress it reads is
    # the contact stress averaged over the last servo_window evaluations, every servo_every steps.
    # G = servo_gain × (σ_target/E*)^(2/3) / (servo_every·dt): a packing's stiffness over its stress
    # goes as the inverse of the Hertz overlap, ∝ (σ/E*)^(−2/3), so this keeps the relative stress change
    # per servo update the same at any stress and stiffness (a constant G oscillated at 10 kPa)
    servo_gain: float = 0.2
    compaction_cap: float = 100.0
    shear_cap: float = 50.0
    servo_every: int = 10
    servo_window: int = 5
    # consolidation: a first stretch, then chunks until every axis' stress lies within ±tolerance of σ3′
    # and the kinetic energy per grain is below settle_energy × (σ3′ d50³) (a packing at rest)
    consolidation_time: float = 0.004    # [s]
    chunk_time: float = 0.002            # [s]
    consolidation_chunks: int = 60
    tolerance: float = 0.01
    settle_energy: float = 1e-4
    history_points: int = 400            # history rows over the axial compression

    def identity(self) -> dict:
        return dataclasses.asdict(self)


CELL_RECIPE = CellRecipe()
