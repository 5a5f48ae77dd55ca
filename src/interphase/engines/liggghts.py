"""LIGGGHTS engine: Case → deck + data + STL files → `liggghts` subprocess → Results.

Geometry (x = shear axis, z up, y out of plane; one grain layer, centres at y = 0):
  interface: the soil box [0, L] × [surface top, …] with fixed side walls whose bottoms sit above
    the surface's highest point (`engines.device.side_walls`: grains trapped in valleys pass under
    the left one, where the surface leaves the box); the rough
    surface (the profile extruded in y, one connected mesh) slides in −x beneath it at the shear
    velocity; a servo platen holds the normal force σ·L·t on top (consolidation runs until it does).
    History also carries window_fx/fz: the force on the surface from the grains in Case.window
    (per-grain wall forces, `store_force yes`), away from the side walls.
  box: a direct shear box of height H split at H/2; the lower half slides −x; flanges close the
    openings the slide uncovers.
Quasi-2D thickness t = D50 converts stress to force (F = σ·L·t). Time step dt = 0.2·T_R of the
smallest grain (Rayleigh). Rolling friction: the `epsd2` model (elastic–plastic spring: torque
increment kr·Δθ with kr = kt·R_eff², capped at μr·R_eff·Fn, no dashpot) with coefficient
case.rolling_friction at every contact. Not `cdt` (a constant torque opposing the rolling velocity,
with no static resistance): with cdt LIGGGHTS was 20–50 % weaker than YADE's elastic–plastic law
wherever grains roll (flat μs 0.5, spaced saw-tooth, box); with epsd2 those agree within ~5 % at
1000 grains (docs/crosscheck.md). Damping: LIGGGHTS's Hertz damping from the coefficient of
restitution case.restitution.
"""

from __future__ import annotations

import functools
import os
import re
import shlex
import shutil
import subprocess
from pathlib import Path

import numpy as np

from interphase import __version__
from interphase.case import Case
from interphase.engines.base import (Engine, EngineError, EngineProfile, Results, log_tail, not_consolidated, register,
                                     run_logged, steps_for)
from interphase.engines.device import CONSOLIDATION_CHUNKS, CONSOLIDATION_TIME, PLATEN_TOLERANCE, side_walls
from interphase.engines.packing import lattice_packing, write_liggghts_data
from interphase.engines.render import environment
from interphase.material import rayleigh_time, youngs_modulus
from interphase.surface.mesh import extruded_triangles, segment_triangles, stl_text
from interphase.surface.profiles import from_spec

THROUGHPUT = 1.5e6     # particle-steps per second assumed for the timeout estimate (measured 2.5–4e6)
HISTORY_POINTS = 400        # history rows over the shear
SERVO_GAIN = 2.4            # in-band servo gain: see platen_servo (measured)
SERVO_SATURATION = 0.9      # relative force error at which the platen reaches its top speed


def platen_servo(case: Case, dt: float) -> tuple[float, float]:
    """(vel_max [m/s], kp) of the platen servo, LIGGGHTS' proportional mode: the platen moves at
    vel_max·kp × the relative force error, at most vel_max (mesh_module_stress_servo).

    Gain: G = 0.1·ratio·r_min/dt per unit error with ratio = SERVO_GAIN·(σ/E*)^(2/3) (Hertz,
    E* = E/(2(1−ν²))), i.e. 0.1·ratio·r_min per step: it scales with the grains' overlap under σ, so
    the platen moves the same fraction of an overlap per step at any stiffness. This is exactly the
    in-band law of `mode auto ratio` that earlier decks used (0.99–1.00 × target, sd ≤ 2 % in box
    and interface tests; the former fixed ratio 1e-3 fell behind the box's dilation). What changes
    is outside the band: `mode auto` multiplies the speed by 10 once |error| ≥ 1 (ratio·r_min per
    step, a quarter of an overlap), which locked one well-graded packing into a two-step limit
    cycle (platen force 11 N / −2 N against 2.94 N; `not_consolidated`). Here the speed saturates
    at G·SERVO_SATURATION instead, a tenth of that step; also the approach speed before contact.
    Measured (docs/liggghts.md): that packing consolidates, tracking as before or better."""
    e_star = youngs_modulus(case.shear_modulus, case.poisson) / (2 * (1 - case.poisson ** 2))
    ratio = SERVO_GAIN * (case.normal_stress / e_star) ** (2 / 3)
    gain = 0.1 * ratio * (case.gradation.d_min / 2) / dt
    return gain * SERVO_SATURATION, 1 / SERVO_SATURATION


def time_step(case: Case) -> float:
    """dt = 0.2 × Rayleigh time of the smallest grain [s]."""
    return 0.2 * rayleigh_time(case.gradation.d_min / 2, case.density, case.shear_modulus, case.poisson)


@register
class Liggghts(Engine):
    name = "liggghts"

    @classmethod
    def default_profile(cls) -> EngineProfile:
        return EngineProfile(
            binary=os.environ.get("INTERPHASE_LIGGGHTS_BINARY", "liggghts"),
            launcher=tuple(shlex.split(os.environ.get("INTERPHASE_LIGGGHTS_LAUNCHER", ""))),
            threads=int(os.environ.get("INTERPHASE_LIGGGHTS_THREADS", "1")),
            timeout=float(os.environ["INTERPHASE_LIGGGHTS_TIMEOUT"]) if "INTERPHASE_LIGGGHTS_TIMEOUT" in os.environ else None,
        )

    def version(self) -> str:
        return _version(self.profile.binary)

    # ---- input -----------------------------------------------------------------------------
    def geometry(self, case: Case) -> dict:
        """Every derived size of the deck [m, N, s] and the mesh files' text."""
        d_min, d_max, d50 = case.gradation.d_min, case.gradation.d_max, case.d50
        L, H, D = case.box_length, case.box_height, case.shear_distance
        t = case.thickness
        y0, y1 = -0.45 * d_max * 2, 0.45 * d_max * 2          # meshes a little thinner than the box
        margin = 2 * d_max
        dt = time_step(case)
        files: dict[str, str] = {}
        if case.test == "interface":
            prof = from_spec(case.profile, d50, L + D + 2 * margin)
            x = prof.x - margin
            z = prof.z
            top = float(z.max())
            floor = top + 0.02 * d_max
            pack = lattice_packing(case, 0.0, L, floor)
            wall_top = pack.top + 3 * d_max
            # one connected extruded mesh (two triangles per segment): `inplane_triangles` shares
            # only vertices between segments, and LIGGGHTS then applied a ridge-vertex contact once
            # per triangle (36 of 182 surface contacts on a 45° saw-tooth were exact duplicates,
            # all in the mesh force); this mesh gave none (docs/liggghts.md)
            pts, tri = extruded_triangles(type(prof)(x, z, prof.periodic, prof.name), y0, y1)
            files["surface.stl"] = stl_text(pts, tri)
            sides = side_walls(prof, L, d_min, d_max, case.d50, wall_top)
            files["sides.stl"] = stl_text(*segment_triangles(sides, y0, y1))
            z_lo = float(z.min()) - d_max
            # the box's side planes, full height: a grain whose centre crosses one has left the box
            # and is deleted (fix massflow/mesh) before it can wedge outside (engines.device). Full
            # height, not only the openings under the walls: a large grain riding a valley can be
            # squeezed past a wall's bottom edge with its centre above it (well-graded soil, 1 of
            # 9 seeds lost it, shot up at 27 m/s, docs/liggghts.md)
            files["exit_left.stl"] = stl_text(*segment_triangles([[0.0, z_lo, 0.0, wall_top]], y0, y1))
            files["exit_right.stl"] = stl_text(*segment_triangles([[L, wall_top, L, z_lo]], y0, y1))
            x_lo, x_hi = float(x.min()) - D - d_max, float(x.max()) + d_max   # the surface travels −D
            moving, fixed = "surf", "sides"
            window = (*case.window, top + d_max)
        else:
            z_mid = H / 2
            gap = 0.05 * d_min
            pack = lattice_packing(case, 0.0, L, 0.0)
            wall_top = max(pack.top, H) + 3 * d_max
            far = D + margin
            lower = [[-far, 0.0, L + far, 0.0],                 # bottom (normal up)
                     [0.0, z_mid - gap, 0.0, 0.0],              # left side (normal +x)
                     [L, 0.0, L, z_mid - gap],                  # right side (normal −x)
                     [L + far, z_mid - gap, L, z_mid - gap]]    # right flange (normal down... both sides act)
            upper = [[0.0, wall_top, 0.0, z_mid], [L, z_mid, L, wall_top],
                     [0.0, z_mid, -far, z_mid]]                 # left flange
            files["lower.stl"] = stl_text(*segment_triangles(lower, y0, y1))
            files["upper.stl"] = stl_text(*segment_triangles(upper, y0, y1))
            z_lo = -d_max
            x_lo, x_hi = -far - D - d_max, L + far + d_max
            moving, fixed = "lower", "upper"
            window = None                                       # the whole lower half
        platen_z = pack.top + 0.5 * d_max
        inset = 0.02 * d_max
        files["platen.stl"] = stl_text(*segment_triangles([[L - inset, platen_z, inset, platen_z]], y0, y1))
        z_hi = wall_top + 2 * d_max
        box = (x_lo, x_hi, -d_max, d_max, z_lo, z_hi)
        files["grains.data"] = write_liggghts_data(pack, case.density, box)
        skin = 0.2 * d_min
        return dict(files=files, dt=dt, skin=skin, moving=moving, fixed=fixed, n_grains=pack.n, window=window,
                    platen_com=(L / 2, platen_z), platen_force=case.normal_stress * L * t,
                    thickness=t, box=box)

    def parameters(self, case: Case) -> dict:
        """The template's values (all numbers or validated names) and the mesh/data files."""
        g = self.geometry(case)
        dt = g["dt"]
        # type pairs (1 grain, 2 surface/lower box, 3 other walls); wall–wall pairs never meet
        # the box test has no rough surface: its lower half (type 2) is a boundary like the rest
        mu_s = case.friction_ps if case.test == "interface" else case.friction_pw
        mu = [case.friction_pp, mu_s, case.friction_pw,
              mu_s, 0.0, 0.0,
              case.friction_pw, 0.0, 0.0]
        rr = [case.rolling_friction] * 9
        n_shear = steps_for(case.shear_distance / case.shear_velocity, dt)
        vmax, kp = platen_servo(case, dt)
        # LIGGGHTS requires vel_max < skin/(2·dt); with skin = 0.2·d_min that is 0.45·ratio of it
        vmax = min(vmax, 0.5 * g["skin"] / (2 * dt))
        n_snap = max(1, int(round(case.snapshot_every / case.shear_velocity / dt)))
        # history every n_history steps, a divisor of the snapshot interval so that every contact
        # snapshot has a history row at the same step (mesh force vs summed contacts)
        k = max(1, round(n_snap / max(1, n_shear // HISTORY_POINTS)))
        n_history = max(1, n_snap // k)
        n_snap = n_history * k
        params = dict(
            version=__version__, title="interface_shear" if case.test == "interface" else "direct_shear",
            E=youngs_modulus(case.shear_modulus, case.poisson), nu=case.poisson,
            restitution=[case.restitution] * 9, friction=mu, rolling=rr, rolling_model="epsd2",
            dt=dt, skin=g["skin"], moving=g["moving"], fixed=g["fixed"], window=g["window"],
            exits=case.test == "interface",
            platen_com=g["platen_com"], platen_force=g["platen_force"],
            servo_vmax=vmax, servo_kp=kp, shear_velocity=case.shear_velocity,
            # multiples of the snapshot interval: shear then starts on a dump step
            n_consolidate=steps_for(CONSOLIDATION_TIME, dt, n_snap), n_shear=n_shear,
            n_chunk=steps_for(CONSOLIDATION_TIME / 4, dt, n_snap), n_chunks_max=CONSOLIDATION_CHUNKS,
            platen_force_lo=(1 - PLATEN_TOLERANCE) * g["platen_force"],
            platen_force_hi=(1 + PLATEN_TOLERANCE) * g["platen_force"],
            n_snapshot=n_snap,
            n_history=n_history, n_thermo=max(1, n_shear // 20),
        )
        return dict(params=params, geometry=g)

    def template_name(self, case: Case) -> str:
        return "interface_shear.in.j2" if case.test == "interface" else "direct_shear.in.j2"

    def render(self, case: Case) -> dict[str, str | bytes]:
        p = self.parameters(case)
        deck = environment(self.templates).get_template(self.template_name(case)).render(**p["params"])
        files = {"in.deck": deck, **p["geometry"]["files"]}
        meta = {k: v for k, v in p["params"].items()}
        meta.update(thickness=p["geometry"]["thickness"], n_grains=p["geometry"]["n_grains"], shear_sign=1)
        import json
        files["engine.json"] = json.dumps(meta, indent=1, default=float)
        return files

    # ---- run -------------------------------------------------------------------------------
    def timeout_for(self, folder: Path) -> float:
        if self.profile.timeout is not None:
            return self.profile.timeout
        import json
        meta = json.loads((folder / "engine.json").read_text())
        steps = meta["n_consolidate"] + meta["n_chunks_max"] * meta["n_chunk"] + meta["n_shear"]
        return 60.0 + 5.0 * steps * meta["n_grains"] / THROUGHPUT

    def command(self) -> list[str]:
        binary = shutil.which(self.profile.binary) or self.profile.binary
        base = [binary, "-in", "in.deck", "-log", "log.liggghts", "-echo", "none"]
        stdbuf = shutil.which("stdbuf")
        # error->one text is lost when stdout is redirected unless unbuffered (ENGINES.md)
        prefix = [stdbuf, "-o0", "-e0"] if stdbuf else []
        return [*self.profile.launcher, *prefix, *base]

    def execute(self, folder: str | os.PathLike) -> None:
        folder = Path(folder)
        cmd = self.command()
        if shutil.which(self.profile.binary) is None:
            raise EngineError("not_installed", f"LIGGGHTS binary {self.profile.binary!r} not found",
                              command=cmd, folder=folder)
        env = dict(os.environ, OMP_NUM_THREADS=str(self.profile.threads))
        timeout = self.timeout_for(folder)
        log = folder / "engine.log"
        rc = run_logged(cmd, folder, env, timeout, "LIGGGHTS")
        text = log_tail(log, 60)
        leak = check_grain_balance(folder)
        if leak:
            raise EngineError("lost_atoms", leak, command=cmd, returncode=rc, log_tail=log_tail(log), folder=folder)
        unsettled = not_consolidated(text)
        if unsettled:
            # the deck skipped the shear: a platen that never settled on its target would shear
            # the soil under another stress (one well-graded seed: a servo limit cycle, 1.4 × σ)
            raise EngineError("not_consolidated", unsettled, command=cmd, returncode=rc,
                              log_tail=log_tail(log), folder=folder)
        cause = classify(rc, text)
        if cause:
            first = next((ln for ln in text.splitlines() if "ERROR" in ln), f"return code {rc}")
            raise EngineError(cause, first.strip(), command=cmd, returncode=rc, log_tail=log_tail(log), folder=folder)
        for name in ("history.txt", "contacts_pair.dump", "contacts_wall.dump"):
            if not (folder / name).exists():
                raise EngineError("missing_output", f"LIGGGHTS finished without writing {name}", command=cmd,
                                  returncode=rc, log_tail=log_tail(log), folder=folder)

    def read_results(self, folder: str | os.PathLike) -> Results:
        from interphase.io.liggghts import read_folder

        return read_folder(folder)


def check_grain_balance(folder: Path) -> str | None:
    """A message if grains vanished other than through the side openings, else None.

    balance.txt (interface decks, every thermo interval from step 0): grains in the run + grains
    deleted at the openings must stay ≥ grains placed (engine.json n_grains; '>' while a counted
    grain awaits deletion at the next neighbour-list build). LIGGGHTS itself only warns
    (thermo_modify lost warn), because its atom total ignores the deletions."""
    import json

    path = folder / "balance.txt"
    if not path.exists():
        return None
    n0 = json.loads((folder / "engine.json").read_text())["n_grains"]
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
    if returncode is not None and returncode < 0:
        return "killed"
    if returncode in (137, 143):
        return "killed"
    if "ERROR" in text:
        return "engine_error"
    if returncode != 0:
        return "engine_error"
    return None


@functools.lru_cache(maxsize=None)
def _version(binary: str) -> str:
    """'LIGGGHTS-PUBLIC 3.8.0 …' from the binary's help banner (cached per binary)."""
    path = shutil.which(binary)
    if path is None:
        return "not-installed"
    try:
        import tempfile
        with tempfile.TemporaryDirectory() as tmp:   # `liggghts -h` writes log.liggghts into its cwd
            out = subprocess.run([path, "-h"], capture_output=True, text=True, timeout=30, cwd=tmp).stdout
    except (OSError, subprocess.TimeoutExpired):
        return "unknown"
    m = re.search(r"(LIGGGHTS-PUBLIC \d+\.\d+\.\d+)", out)
    return m.group(1).strip() if m else "unknown"
