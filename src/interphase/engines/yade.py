"""YADE engine: Case → params.json + driver script → `yade -n -x` subprocess → Results.

The geometry is the LIGGGHTS deck's (engines/liggghts.py), built from the same packing
(engines/packing.lattice_packing) and the same surface profile:
  interface: soil box [0, L] between fixed side walls whose bottoms sit above the surface's
    highest point (`engines.device.side_walls`, as LIGGGHTS); the rough surface slides −x beneath
    it at the shear velocity; a platen servo holds σ·L·t on top (t = D50, the quasi-2D thickness).
    History also carries window_fx/fz, the force on the surface from the grains in Case.window;
    grains whose centres pass under a side wall are erased (LIGGGHTS' side openings).
  box: a direct shear box of height H split at H/2, lower half (bottom, sides, right flange) slides −x.
Walls are facets, one triangle per segment with an edge in the grain plane y = 0
(surface.mesh.inplane_triangles); a grain at a convex surface vertex touches two facets at the same
point, and the reader merges those into one contact (io/yade.py).

Time step: dt = 0.2 × Rayleigh time of the smallest grain, as LIGGGHTS. Contact law:
Hertz–Mindlin (Law2_ScGeom_MindlinPhys_Mindlin) with rolling resistance; the parameter mapping to
LIGGGHTS (restitution → betan/betas, epsd2 rolling coefficient → eta, krot) is in docs/engine_mapping.md
and `contact_parameters` below.
"""

from __future__ import annotations

import functools
import json
import math
import os
import re
import shutil
import subprocess
from pathlib import Path


from interphase import __version__
from interphase.case import Case
from interphase.engines.base import (Engine, EngineError, EngineProfile, Results, log_tail, not_consolidated, register,
                                     run_logged, steps_for)
from interphase.engines.device import CONSOLIDATION_CHUNKS, CONSOLIDATION_TIME, PLATEN_TOLERANCE, side_walls
from interphase.engines.packing import lattice_packing
from interphase.engines.render import environment
from interphase.material import youngs_modulus
from interphase.surface.mesh import inplane_triangles
from interphase.surface.profiles import from_spec

THROUGHPUT = 0.5e6          # particle-steps/s assumed for the timeout (measured ~1e6 with export)
HISTORY_POINTS = 400
SERVO_BAND = 0.1            # relative force error at which the platen reaches servo_vmax
TYPICAL_OVERLAP = 0.003     # δ/D50 used to size the rolling stiffness krot (ENGINES.md: 0.25–0.4 %)


def time_step(case: Case) -> float:
    """dt = 0.2 × Rayleigh time of the smallest grain [s] (the LIGGGHTS rule, same value)."""
    from interphase.engines.liggghts import time_step as lig_dt

    return lig_dt(case)


#: Ig2_Facet_Sphere_ScGeom gives the facet refR1 = 2r, so YADE's facet–sphere Hertz radius is
#: R* = 2r/3 where LIGGGHTS' wall has R* = r. Walls get E_w = E/(2/√1.5 − 1) ≈ 1.58·E, which makes
#: YADE's E*·√R* (and G*·√R*, same ν) equal to LIGGGHTS' for every grain–wall contact.
FACET_STIFFENING = 1.0 / (2.0 / math.sqrt(1.5) - 1.0)


def contact_parameters(case: Case) -> dict:
    """YADE Mindlin parameters that reproduce the LIGGGHTS Hertz model of the same Case.

    - E = 2G(1+ν) per material; YADE's kn = 1.5·kno·√δ = 2E*√(R*δ) and ks = 8G*√(R*δ) are the
      LIGGGHTS tangent stiffnesses Sn, St exactly between grains; walls (facets, R* = 2r/3 in YADE)
      get E_wall = FACET_STIFFENING·E so that grain–wall contacts match LIGGGHTS' (R* = r) too.
    - Damping: LIGGGHTS γ = 2√(5/6)·|β|·√(S·m*) with β = ln e/√(ln²e + π²); YADE c = 2·betan·√(kn·m̄).
      So betan = betas = √(5/6)·|β(e)| gives the same dashpot (YADE's `en` would use Thornton's fit,
      a different law). YADE drops the shear dashpot at sliding contacts; LIGGGHTS applies none there
      either (it only dumps it).
    - Rolling: both engines use an elastic–plastic rolling spring. LIGGGHTS epsd2: kr = kt·R_eff²,
      cap μr·R_eff·Fn (R_eff = r1r2/(r1+r2) between grains); YADE's moment is capped at
      eta·R_mean·Fn (R_mean = (r1+r2)/2). eta = μr/2 matches the grain–grain cap for equal grains.
      krot [N·m/rad] (one constant per functor, YADE's limitation) =
      ks(δ = 0.3 % D50)·(D50/4)²: epsd2's kt·R_eff² for two D50 grains (R_eff = D50/4) at a typical
      overlap ((D50/2)², four times stiffer, left YADE 10–25 % stronger than LIGGGHTS on the box and
      the spaced saw-tooth; docs/crosscheck.md). μr = 0 → krot = 0 (YADE applies no cap when eta = 0).
      Grain–facet contacts (where the functor's eta·R_mean would be 0.75·μr·r, R_mean = 1.5r with
      the facet's refR1 = 2r) get epsd2's wall values instead, set per interaction by the driver every
      10 steps: krot_wall = ks(R* = r)·r², cap μr·r·Fn. Measured effect in docs/crosscheck.md.
    """
    e = case.restitution
    beta = 0.0 if e >= 1 else abs(math.log(e)) / math.sqrt(math.log(e) ** 2 + math.pi ** 2)
    b = math.sqrt(5.0 / 6.0) * beta
    r50 = case.d50 / 2
    g_eff = case.shear_modulus / (2 * (2 - case.poisson))        # YADE/LIGGGHTS G* of two equal materials

    def ks(r_star: float) -> float:        # Mindlin tangential stiffness at the typical overlap [N/m]
        return 8 * g_eff * math.sqrt(r_star * TYPICAL_OVERLAP * case.d50)
    E = youngs_modulus(case.shear_modulus, case.poisson)
    return dict(E=E, E_wall=E * FACET_STIFFENING, nu=case.poisson, density=case.density,
                mu_pp=case.friction_pp, mu_ps=case.friction_ps if case.test == "interface" else case.friction_pw,
                mu_pw=case.friction_pw, betan=b, betas=b, eta=case.rolling_friction / 2,
                # YADE caps the rolling moment only when eta·R·Fn > 0 (Law2_ScGeom_MindlinPhys_Mindlin:
                # `if (MomentMax > 0)`): eta = 0 with krot > 0 is an UNLIMITED rolling spring, and
                # grains on a flat could not roll at all (μs = 0.5 gave exactly 0.500, measured)
                krot=ks(r50 / 2) * (r50 / 2) ** 2 if case.rolling_friction > 0 else 0.0,
                # grain–facet contacts, set per interaction by the driver: epsd2's kr = kt·r² with
                # R* = r, and its cap μr·r·Fn (the functor's one krot/eta fit grain pairs)
                krot_wall=ks(r50) * r50 ** 2 if case.rolling_friction > 0 else 0.0,
                mu_r=case.rolling_friction)


def _inplane(segments, width: float) -> list[list[float]]:
    """Segments (x0, z0, x1, z1) → triangles (9 floats): in-plane edge at y = 0, apex at y = width."""
    out = []
    for x0, z0, x1, z1 in segments:
        out.append([x0, 0.0, z0, x1, 0.0, z1, 0.5 * (x0 + x1), width, 0.5 * (z0 + z1)])
    return out


@register
class Yade(Engine):
    name = "yade"

    @classmethod
    def default_profile(cls) -> EngineProfile:
        threads = os.environ.get("INTERPHASE_YADE_THREADS", "1")
        try:
            n = int(threads)
        except ValueError:
            from interphase.errors import InputError
            raise InputError(f"INTERPHASE_YADE_THREADS={threads!r} is not an integer", where="environment",
                             fix="set INTERPHASE_YADE_THREADS to a thread count such as 1 or 2") from None
        return EngineProfile(
            binary=os.environ.get("INTERPHASE_YADE_BINARY", "yade"), threads=n,
            timeout=float(os.environ["INTERPHASE_YADE_TIMEOUT"]) if "INTERPHASE_YADE_TIMEOUT" in os.environ else None)

    def version(self) -> str:
        return _version(self.profile.binary)

    # ---- input -----------------------------------------------------------------------------
    def parameters(self, case: Case) -> dict:
        """Every value the driver reads (SI units), as plain JSON data."""
        d_min, d_max, d50 = case.gradation.d_min, case.gradation.d_max, case.d50
        L, H, D = case.box_length, case.box_height, case.shear_distance
        width = 0.45 * d_max * 2                 # facets reach y = 0.9·d_max, beyond any grain
        margin = 2 * d_max
        gap = 0.05 * d_min
        dt = time_step(case)
        if case.test == "interface":
            prof = from_spec(case.profile, d50, L + D + 2 * margin)
            x, z = prof.x - margin, prof.z
            top = float(z.max())
            pack = lattice_packing(case, 0.0, L, top + 0.02 * d_max)
            wall_top = pack.top + 3 * d_max
            pts, tri = inplane_triangles(type(prof)(x, z, prof.periodic, prof.name), width)
            moving = pts[tri].reshape(-1, 9).tolist()
            fixed = _inplane(side_walls(prof, L, d_min, d_max, case.d50, wall_top), width)   # LIGGGHTS' walls
            window = [*case.window, top + d_max]
            z_lo = float(z.min()) - d_max
            x_lo, x_hi = float(x.min()) - D - d_max, float(x.max()) + d_max
        else:
            z_mid = H / 2
            pack = lattice_packing(case, 0.0, L, 0.0)
            wall_top = max(pack.top, H) + 3 * d_max
            far = D + margin
            window = None
            moving = _inplane([[-far, 0.0, L + far, 0.0], [0.0, z_mid - gap, 0.0, 0.0],
                               [L, 0.0, L, z_mid - gap], [L + far, z_mid - gap, L, z_mid - gap]], width)
            fixed = _inplane([[0.0, wall_top, 0.0, z_mid], [L, z_mid, L, wall_top], [0.0, z_mid, -far, z_mid]], width)
            z_lo = -d_max
            x_lo, x_hi = -far - D - d_max, L + far + d_max
        platen_z = pack.top + 0.5 * d_max
        inset = 0.02 * d_max
        platen = _inplane([[L - inset, platen_z, inset, platen_z]], width)
        z_hi = wall_top + 2 * d_max
        n_shear = steps_for(D / case.shear_velocity, dt)
        n_snap = max(1, int(round(case.snapshot_every / case.shear_velocity / dt)))
        k = max(1, round(n_snap / max(1, n_shear // HISTORY_POINTS)))
        n_hist = max(1, n_snap // k)
        n_snap = n_hist * k                      # every snapshot step also has a history row
        n_cons = steps_for(CONSOLIDATION_TIME, dt, n_snap)
        platen_force = case.normal_stress * L * case.thickness
        skin = 0.2 * d_min
        return dict(
            version=__version__, test=case.test, dt=dt, gravity=9.81,
            material=contact_parameters(case),
            grains=dict(x=pack.x.tolist(), z=pack.z.tolist(), r=(pack.diameter / 2).tolist()),
            walls=[dict(name="surface" if case.test == "interface" else "lower", index=0, triangles=moving),
                   dict(name="sides" if case.test == "interface" else "upper", index=1, triangles=fixed),
                   dict(name="platen", index=2, triangles=platen)],
            platen_force=platen_force, servo_vmax=min(0.1, 0.5 * skin / (2 * dt)), servo_band=SERVO_BAND,
            platen_force_lo=(1 - PLATEN_TOLERANCE) * platen_force,
            platen_force_hi=(1 + PLATEN_TOLERANCE) * platen_force,
            shear_velocity=case.shear_velocity,
            steps=dict(n_consolidate=n_cons, n_shear=n_shear, n_snapshot=n_snap, n_history=n_hist,
                       n_chunk=steps_for(CONSOLIDATION_TIME / 4, dt, n_snap), n_chunks_max=CONSOLIDATION_CHUNKS),
            bounds=[x_lo, x_hi, z_lo, z_hi], window=window,
            exits=[0.0, L] if case.test == "interface" else None,   # grains past these x are out of the box
            thickness=case.thickness, n_grains=pack.n, shear_sign=1,
        )

    def template_name(self, case: Case) -> str:
        return "interface_shear.py.j2" if case.test == "interface" else "direct_shear.py.j2"

    def render(self, case: Case) -> dict[str, str | bytes]:
        params = self.parameters(case)
        script = environment(self.templates).get_template(self.template_name(case)).render()
        return {"driver.py": script, "params.json": json.dumps(params, indent=None, allow_nan=False)}

    # ---- run -------------------------------------------------------------------------------
    def timeout_for(self, folder: Path) -> float:
        if self.profile.timeout is not None:
            return self.profile.timeout
        p = json.loads((folder / "params.json").read_text())
        s = p["steps"]
        steps = s["n_consolidate"] + s["n_chunks_max"] * s["n_chunk"] + s["n_shear"]
        return 60.0 + 5.0 * steps * p["n_grains"] / THROUGHPUT

    def command(self) -> list[str]:
        binary = shutil.which(self.profile.binary) or self.profile.binary
        threads = ["-j", str(self.profile.threads)] if self.profile.threads > 1 else []
        return [binary, "-n", *threads, "-x", "driver.py", "params.json"]

    def execute(self, folder: str | os.PathLike) -> None:
        folder = Path(folder)
        cmd = self.command()
        if shutil.which(self.profile.binary) is None:
            raise EngineError("not_installed", f"YADE binary {self.profile.binary!r} not found",
                              command=cmd, folder=folder)
        env = dict(os.environ, OMP_NUM_THREADS=str(self.profile.threads), PYTHONUNBUFFERED="1")
        timeout = self.timeout_for(folder)
        log = folder / "engine.log"
        rc = run_logged(cmd, folder, env, timeout, "YADE")
        text = log_tail(log, 80)
        cause, message = classify(rc, text)
        if cause:
            raise EngineError(cause, message, command=cmd, returncode=rc, log_tail=log_tail(log), folder=folder)
        for name in ("history.csv", "contacts.csv", "particles.csv", "bodies.json"):
            if not (folder / name).exists():
                raise EngineError("missing_output", f"YADE finished without writing {name}", command=cmd,
                                  returncode=rc, log_tail=log_tail(log), folder=folder)

    def read_results(self, folder: str | os.PathLike) -> Results:
        from interphase.io.yade import read_folder

        return read_folder(folder)


def classify(returncode: int, text: str) -> tuple[str | None, str]:
    """(cause, message) of a finished YADE run; cause None if it succeeded.

    A Python traceback in the log is an engine_error whose message is the traceback's last line
    (the exception); the driver prints 'ERROR: Lost atoms' when grains leave the domain and
    'NOT CONSOLIDATED: …' when the platen never settled on its target (the shear is skipped)."""
    unsettled = not_consolidated(text)
    if unsettled:
        return "not_consolidated", unsettled
    lost = re.search(r"ERROR: Lost atoms[^\n]*", text)
    if lost:
        return "lost_atoms", lost.group(0)
    if "Traceback (most recent call last)" in text:
        tail = text.split("Traceback (most recent call last)")[-1]
        lines = [ln.strip() for ln in tail.splitlines() if ln.strip() and not ln.startswith((" ", "\t"))]
        exc = next((ln for ln in reversed(lines) if re.match(r"^[A-Za-z_.]+(Error|Exception|Exit)\b", ln)),
                   lines[-1] if lines else "Python traceback")
        cause = "bad_mesh" if re.search(r"facet|vertices|triangle", exc, re.I) else "engine_error"
        return cause, exc
    if returncode is not None and (returncode < 0 or returncode in (137, 143)):
        return "killed", f"YADE was killed (return code {returncode})"
    if returncode != 0:
        return "engine_error", f"YADE exited with return code {returncode}"
    if "interphase: finished" not in text:
        return "engine_error", "YADE exited without finishing the run"
    return None, ""


@functools.lru_cache(maxsize=None)
def _version(binary: str) -> str:
    """'YADE 2023.02a' from `yade --version` (cached per binary)."""
    path = shutil.which(binary)
    if path is None:
        return "not-installed"
    try:
        out = subprocess.run([path, "--version"], capture_output=True, text=True, timeout=60,
                             stdin=subprocess.DEVNULL).stdout
    except (OSError, subprocess.TimeoutExpired):
        return "unknown"
    m = re.search(r"[Yy]ade(?: version:)?\s+([0-9][\w.\-]*)", out)
    return f"YADE {m.group(1)}" if m else "unknown"
