"""LIGGGHTS engine: the case's device (engines/device.py) → deck + data + STL files → `liggghts`.

The 3D device (docs/3d.md) uses the periodic deck with y periodic too (`boundary p p f`), no
y-fixing of grains, meshes extruded over exactly the cell's depth.

Grains crossing the exit planes are deleted (fix massflow/mesh) and counted in balance.txt. Contact
law: Hertz, tangential history, Hertz damping from case.restitution, and the `epsd2` rolling model
(elastic–plastic, kr = kt·R_eff², cap μr·R_eff·Fn), not `cdt` (a constant torque without static
resistance: 20–50 % weaker than YADE's elastic–plastic law wherever grains roll; docs/crosscheck.md).
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np

from interphase.case import Case
from interphase.engines.base import Engine, Results, log_tail, not_consolidated, register
from interphase.engines.cell import Cell, cell, servo_gain
from interphase.engines.device import Device, device, time_step
from interphase.engines.packing import write_liggghts_data
from interphase.engines.render import environment
from interphase.material import youngs_modulus
from interphase.recipe import FILE as RECIPE_FILE
from interphase.recipe import RECIPE
from interphase.recipe import read_record
from interphase.surface.mesh import segment_triangles, stl_text
from interphase.version import __version__

__all__ = ["Liggghts", "check_grain_balance", "classify", "time_step"]   # time_step: campaign/plan.py

MESH = {"surface": "surf"}       # fix ids of wall groups whose file name is not their id


def mesh_files(dev: Device) -> dict[str, str]:
    """The device's walls as ASCII STL, each segment extruded over |y| ≤ wall_reach as two triangles.
    LIGGGHTS joins triangles at shared vertices, so the surface is one connected mesh: a ridge vertex
    meets a grain once (a mesh split into in-plane triangles gave duplicate contacts there)."""
    walls = dict(zip(dev.wall_names, (dev.moving, dev.fixed)), platen=dev.platen)
    walls = {name: segs for name, segs in walls.items() if segs}
    if dev.exits:
        walls |= {"exit_left": dev.exits[:1], "exit_right": dev.exits[1:]}
    files = {f"{name}.stl": stl_text(*segment_triangles(segs, -dev.wall_reach, dev.wall_reach))
             for name, segs in walls.items()}
    if dev.surface_mesh is not None:      # an areal surface (3D): its own triangles
        files[f"{dev.wall_names[0]}.stl"] = stl_text(*dev.surface_mesh)
    return files


def deck_values(dev: Device) -> dict:
    """The deck template's values: numbers and validated names only."""
    case, r, s = dev.case, dev.recipe, dev.steps
    # type pairs (1 grain, 2 surface/lower box, 3 platen, 4 fixed side walls); walls never meet walls
    mu_s = case.friction_ps if case.test == "interface" else case.friction_pw
    grain_with = [case.friction_pp, mu_s, case.friction_pw, case.friction_side]
    vmax, saturation = dev.platen_servo
    kp = 1 / saturation
    lo, hi = dev.platen_band
    moving, fixed = (MESH.get(n, n) for n in dev.wall_names)
    # preparation: grain–grain sliding and rolling friction scaled while deposited and consolidated
    prep = case.preparation
    friction = grain_with + [v for mu in grain_with[1:] for v in (mu, 0.0, 0.0, 0.0)]   # symmetric 4 × 4
    rolling = [case.rolling_friction] * 16
    # (keys only when prepared: every other deck and engine.json stays as it was, and so do case ids)
    prepared = dict(prep_friction=[prep * friction[0], *friction[1:]],
                    prep_rolling=[prep * rolling[0], *rolling[1:]]) if prep != 1.0 else {}
    # (keys only in 3D: every quasi-2D deck and engine.json stays as it was)
    deep = dict(three_d=True, depth=dev.depth) if dev.depth is not None else {}
    return dict(**prepared, **deep, periodic=dev.periodic, meshes=[moving, *([fixed] if dev.fixed else []), "platen"],
                moving_file=f"{dev.wall_names[0]}.stl",
                bed=[i + 1 for i in dev.bed],                                  # LIGGGHTS atom ids
        version=__version__, title="interface_shear" if case.test == "interface" else "direct_shear",
        E=youngs_modulus(case.shear_modulus, case.poisson), nu=case.poisson, restitution=[case.restitution] * 16,
        friction=friction, rolling=rolling, rolling_model=r.rolling_model,
        dt=dev.dt, skin=dev.skin, moving=moving, fixed=fixed, window=dev.window, exits=dev.exits is not None,
        platen_com=dev.platen_com, platen_force=dev.platen_force, servo_vmax=vmax, servo_kp=kp,
        shear_velocity=case.shear_velocity, n_consolidate=s.n_consolidate, n_shear=s.n_shear, n_chunk=s.n_chunk,
        n_chunks_max=s.n_chunks_max, platen_force_lo=lo, platen_force_hi=hi, n_snapshot=s.n_snapshot,
        n_history=s.n_history, n_thermo=max(1, s.n_shear // r.thermo_points))


def cell_values(c: Cell) -> dict:
    """The cell deck's values (templates/liggghts/cell.in.j2): numbers and validated names only."""
    case, r = c.case, c.recipe
    tol, s3 = r.tolerance, case.normal_stress
    prep = case.preparation
    E = youngs_modulus(case.shear_modulus, case.poisson)
    gain = servo_gain(case, c.dt, r.servo_every, r)
    return dict(version=__version__, title=case.test, three_d=c.three_d,
                E=E, nu=case.poisson, restitution=case.restitution,
                friction=case.friction_pp, rolling=case.rolling_friction, prep_friction=prep * case.friction_pp,
                prep_rolling=prep * case.rolling_friction, rolling_model=RECIPE.rolling_model, dt=c.dt, skin=c.skin,
                every=r.servo_every, window=r.servo_window, servo_step=r.servo_every * c.dt,
                # quasi-2D: the engine divides by Lx·Ly·Lz, the stress is per Lx·Lz·t
                stress_scale=1.0 if c.three_d else c.size[1] / c.thickness,
                sigma3=s3, gain=gain, compaction_cap=r.compaction_cap, shear_cap=r.shear_cap,
                lo=(1 - tol) * s3, hi=(1 + tol) * s3, ke_max=r.settle_energy * s3 * case.d50 ** 3 * c.packing.n,
                size=c.size, n_consolidate=c.steps.n_consolidate, n_chunk=c.steps.n_chunk,
                n_chunks_max=c.steps.n_chunks_max, n_settle=c.n_settle, n_shear=c.steps.n_shear,
                n_history=c.steps.n_history, strain_rate=case.strain_rate,
                n_thermo=max(r.servo_every, c.steps.n_shear // 20 // r.servo_every * r.servo_every))


@register
class Liggghts(Engine):
    name, label = "liggghts", "LIGGGHTS"
    outputs = ("history.txt", "contacts_pair.dump", "contacts_wall.dump")
    version_args, version_pattern = ("-h",), r"(LIGGGHTS-PUBLIC \d+\.\d+\.\d+)"
    template_suffix = ".in.j2"

    def render(self, case: Case) -> dict[str, str | bytes]:
        if case.cell:
            return self._render_cell(case)
        dev = device(case, self.recipe)
        values = deck_values(dev)
        x_lo, x_hi, z_lo, z_hi = dev.bounds
        y_reach = case.gradation.d_max if dev.depth is None else dev.depth / 2     # 3D: the y period
        box = (x_lo, x_hi, -y_reach, y_reach, z_lo, z_hi)
        # engine.json: the deck's values as data, for people and scripts (the readers use recipe.json)
        meta = values | dict(thickness=dev.thickness, n_grains=dev.n_grains, shear_sign=dev.shear_sign)
        return {"in.deck": environment(self.templates).get_template(self.template_name(case)).render(**values),
                **mesh_files(dev), "grains.data": write_liggghts_data(dev.packing, case.density, box),
                "engine.json": json.dumps(meta, indent=1, default=float), RECIPE_FILE: dev.record(self.name).to_json()}

    def _render_cell(self, case: Case) -> dict[str, str]:
        """A triaxial or biaxial case: the cell deck (templates/liggghts/cell.in.j2), its grains and
        cell.json (the numbers the reader needs: solid volume, thickness)."""
        c = cell(case)
        values = cell_values(c)
        Lx, Ly, Lz = c.size
        box = (0.0, Lx, -Ly / 2 if not c.three_d else 0.0, Ly / 2 if not c.three_d else Ly, 0.0, Lz)
        meta = dict(test=case.test, solid=c.solid, thickness=c.thickness, three_d=c.three_d, n_grains=c.packing.n,
                    sigma3=case.normal_stress, strain_rate=case.strain_rate, d50=case.d50, density=case.density)
        return {"in.deck": environment(self.templates).get_template("cell.in.j2").render(**values),
                "grains.data": write_liggghts_data(c.packing, case.density, box),
                "cell.json": json.dumps(meta, indent=1), RECIPE_FILE: c.record(self.name).to_json()}

    def template_name(self, case: Case) -> str:
        if case.cell:
            return "cell.in.j2"
        return "periodic_shear.in.j2" if case.periodic else super().template_name(case)

    def arguments(self, binary: str) -> list[str]:
        stdbuf = shutil.which("stdbuf")
        # error->one text is lost when stdout is redirected unless unbuffered (docs/engines.md)
        prefix = [stdbuf, "-o0", "-e0"] if stdbuf else []
        return [*prefix, binary, "-in", "in.deck", "-log", "log.liggghts", "-echo", "none"]

    def diagnose(self, folder: Path, returncode: int) -> tuple[str | None, str]:
        text = log_tail(folder / "engine.log", 60)
        leak = check_grain_balance(folder)
        if leak:
            return "lost_atoms", leak
        unsettled = not_consolidated(text)
        if unsettled:
            # the deck skipped the shear: a platen that never settled on its target would shear
            # the soil under another stress (one well-graded seed: a servo limit cycle, 1.4 × σ)
            return "not_consolidated", unsettled
        cause = classify(returncode, text)
        first = next((ln for ln in text.splitlines() if "ERROR" in ln), f"return code {returncode}")
        return cause, first.strip() if cause else ""

    def required_outputs(self, folder: Path) -> tuple[str, ...]:
        """A cell run (cell.json, engines/cell.py) leaves its history only; a shear run also its dumps."""
        return ("history.txt",) if (Path(folder) / "cell.json").exists() else self.outputs

    def read_results(self, folder) -> Results:
        # each reader imported on its own path: a cell run never loads the dump reader (pyarrow.csv)
        if (Path(folder) / "cell.json").exists():
            from interphase.io.cell import read_cell_folder

            return read_cell_folder(folder)
        from interphase.io.liggghts import read_folder

        return read_folder(folder)


def check_grain_balance(folder: Path) -> str | None:
    """A message if grains vanished other than through the exit planes, else None: in balance.txt
    (interface decks, every thermo interval) grains in the run + grains deleted at the exits must
    stay ≥ grains placed ('>' while a counted grain awaits deletion). LIGGGHTS only warns (thermo_modify
    lost warn), because its atom total ignores the deletions."""
    path = folder / "balance.txt"
    if not path.exists():
        return None
    n0 = read_record(folder).n_grains
    rows = path.read_text().splitlines()[1:]      # below the title line
    if not rows:                                   # the engine stopped before its first print
        return None
    b = np.loadtxt(rows, ndmin=2)
    bad = np.flatnonzero(b[:, 1] + b[:, 2] < n0)
    if bad.size:
        step, na, nout = b[bad[0]]
        return (f"Lost atoms: {n0 - int(na) - int(nout)} grain(s) left the domain by step {int(step)} "
                f"(balance.txt: {int(na)} in the run + {int(nout)} removed at the side openings < {n0} placed)")
    return None


def classify(returncode: int, text: str) -> str | None:
    """Cause of a failed run from its return code and log text, None if it succeeded."""
    if re.search(r"ERROR: Lost atoms", text):
        return "lost_atoms"
    if re.search(r"ERROR.*(mesh|STL|stl|triangle|facet)|mesh.*ERROR", text):
        return "bad_mesh"
    if returncode is not None and (returncode < 0 or returncode in (137, 143)):
        return "killed"
    if "ERROR" in text or returncode != 0:
        return "engine_error"
    return None
