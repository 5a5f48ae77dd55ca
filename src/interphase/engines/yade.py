"""YADE engine: the case's device (engines/device.py) → params.json + driver.py → `yade -n -x`.

params.json holds the device as plain data (walls as facets, one triangle per segment with an edge
in the grain plane y = 0; a grain at a convex surface vertex touches two facets at the same point,
and the reader merges those into one contact, io/yade.py) and the contact parameters; driver.py
only calls engines/yade_driver.py, which runs the case inside YADE. Contact law: Hertz–Mindlin
(Law2_ScGeom_MindlinPhys_Mindlin) with rolling resistance, mapped from LIGGGHTS' by `contact_parameters`.
The periodic device (params period, bed) runs in YADE's periodic cell (engines/yade_driver.py).
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

from interphase.case import Case
from interphase.engines.base import Engine, Results, log_tail, not_consolidated, register
from interphase.engines.device import Device, device
from interphase.engines.render import environment
from interphase.errors import InputError
from interphase.material import youngs_modulus
from interphase.recipe import FILE as RECIPE_FILE
from interphase.recipe import RECIPE
from interphase.version import __version__

#: Ig2_Facet_Sphere_ScGeom gives the facet refR1 = 2r, so YADE's facet–sphere Hertz radius is
#: R* = 2r/3 where LIGGGHTS' wall has R* = r. Walls get E_w = E/(2/√1.5 − 1) ≈ 1.58·E, which makes
#: YADE's E*·√R* (and G*·√R*, same ν) equal to LIGGGHTS' for every grain–wall contact.
FACET_STIFFENING = 1.0 / (2.0 / math.sqrt(1.5) - 1.0)


def contact_parameters(case: Case, typical_overlap: float = RECIPE.typical_overlap) -> dict:
    """YADE Mindlin parameters that reproduce the LIGGGHTS Hertz model of the same Case (derivation
    and measurements: docs/engine_mapping.md).

    - Stiffness: E = 2G(1+ν); YADE's kn, ks equal LIGGGHTS' Sn, St between grains; facets get
      E_wall = FACET_STIFFENING·E, so grain–wall contacts match too.
    - Damping: betan = betas = √(5/6)·|β(e)|, β = ln e/√(ln²e + π²): LIGGGHTS' dashpot at every overlap.
    - Rolling (both elastic–plastic springs): eta = μr/2 (YADE's cap eta·R_mean·Fn equals epsd2's
      μr·R_eff·Fn for equal grains); krot = ks(δ = typical_overlap·D50)·(D50/4)², epsd2's kt·R_eff²
      for two D50 grains (one constant per functor, a YADE limitation); μr = 0 → krot = 0. Grain–facet
      contacts get epsd2's wall values, krot_wall = ks(R* = r)·r² and cap μr·r·Fn, set per
      interaction by the driver every 10 steps.
    """
    e = case.restitution
    beta = 0.0 if e >= 1 else abs(math.log(e)) / math.sqrt(math.log(e) ** 2 + math.pi ** 2)
    b = math.sqrt(5.0 / 6.0) * beta
    r50 = case.d50 / 2
    g_eff = case.shear_modulus / (2 * (2 - case.poisson))        # YADE/LIGGGHTS G* of two equal materials

    def ks(r_star: float) -> float:        # Mindlin tangential stiffness at the typical overlap [N/m]
        return 8 * g_eff * math.sqrt(r_star * typical_overlap * case.d50)
    E = youngs_modulus(case.shear_modulus, case.poisson)
    rolls = case.rolling_friction > 0
    mu_s = case.friction_ps if case.test == "interface" else case.friction_pw
    return dict(E=E, E_wall=E * FACET_STIFFENING, nu=case.poisson, density=case.density, mu_pp=case.friction_pp,
                mu_ps=mu_s, mu_pw=case.friction_pw, mu_side=case.friction_side, betan=b, betas=b, eta=case.rolling_friction / 2,
                # YADE caps the rolling moment only when eta·R·Fn > 0 (Law2_ScGeom_MindlinPhys_Mindlin:
                # `if (MomentMax > 0)`): eta = 0 with krot > 0 is an UNLIMITED rolling spring, and
                # grains on a flat could not roll at all (μs = 0.5 gave exactly 0.500, measured)
                krot=ks(r50 / 2) * (r50 / 2) ** 2 if rolls else 0.0,
                # the functor's one krot/eta fit grain pairs; the driver sets these on grain–facet contacts
                krot_wall=ks(r50) * r50 ** 2 if rolls else 0.0, mu_r=case.rolling_friction)


def facets(segments, width: float) -> list[list[float]]:
    """Segments (x0, z0, x1, z1) → triangles (9 floats): in-plane edge at y = 0, apex at y = width."""
    return [[x0, 0.0, z0, x1, 0.0, z1, 0.5 * (x0 + x1), width, 0.5 * (z0 + z1)] for x0, z0, x1, z1 in segments]


def driver_input(dev: Device) -> dict:
    """Every value the driver reads (SI units), as plain JSON data."""
    case, r, s = dev.case, dev.recipe, dev.steps
    p = dev.packing
    lo, hi = dev.platen_band
    servo_vmax, servo_band = dev.platen_servo          # LIGGGHTS' law (YADE recipe 3)
    walls = [*zip(dev.wall_names, (dev.moving, dev.fixed)), ("platen", list(dev.platen))]
    return dict(
        version=__version__, test=case.test, dt=dev.dt, gravity=r.gravity,
        material=contact_parameters(case, r.typical_overlap),
        grains=dict(x=p.x.tolist(), z=p.z.tolist(), r=(p.diameter / 2).tolist()),
        walls=[dict(name=name, index=k, triangles=facets(segs, dev.wall_reach))
               for k, (name, segs) in enumerate(walls) if segs],           # periodic: no fixed group
        platen_force=dev.platen_force, platen_z=dev.platen_com[1], wall_reach=dev.wall_reach,
        servo_vmax=servo_vmax, servo_band=servo_band,
        platen_force_lo=lo, platen_force_hi=hi, shear_velocity=case.shear_velocity,
        steps=dict(n_consolidate=s.n_consolidate, n_shear=s.n_shear, n_snapshot=s.n_snapshot, n_history=s.n_history,
                   n_chunk=s.n_chunk, n_chunks_max=s.n_chunks_max),
        bounds=list(dev.bounds), window=dev.window,
        exits=[seg[0] for seg in dev.exits] if dev.exits else None,   # grains past these x are out of the box
        period=dev.record("yade").period, bed=list(dev.bed),           # periodic device (engines/yade_driver.py)
        # YADE runs the system python3: the driver script adds this to its sys.path to import the package
        package_root=str(Path(__file__).resolve().parents[2]),    # src/, above the package
    )


@register
class Yade(Engine):
    name, label = "yade", "YADE"
    outputs = ("history.csv", "contacts.csv", "particles.csv", "bodies.json")
    version_pattern, version_format = r"[Yy]ade(?: version:)?\s+([0-9][\w.\-]*)", "YADE {}"
    template_suffix = ".py.j2"

    def render(self, case: Case) -> dict[str, str | bytes]:
        if case.cell:
            raise InputError(f"the {case.test} cell runs in LIGGGHTS only for now", where="case.test",
                             fix='run it with engine = "liggghts" (docs/soils.md: the laboratory\'s test on the model)')
        if case.three_d:
            raise InputError("the 3D device (periodic3d) runs in LIGGGHTS only for now", where="case.device",
                             fix='run it with engine = "liggghts" (docs/3d.md says what is not done yet)')
        dev = device(case, self.recipe)
        # a prepared specimen (Case.preparation < 1) runs engines/yade_prepare.py's driver; every other
        # case's driver.py and params.json stay as they were (and so do their ids)
        prepared = {"prepared": True} if case.preparation != 1.0 else {}
        params = driver_input(dev) | ({"preparation": case.preparation} if prepared else {})
        return {"driver.py": environment(self.templates).get_template(self.template_name(case)).render(**prepared),
                "params.json": json.dumps(params, indent=None, allow_nan=False),
                RECIPE_FILE: dev.record(self.name).to_json()}

    def template_name(self, case: Case) -> str:
        return "periodic_shear.py.j2" if case.periodic else super().template_name(case)

    def arguments(self, binary: str) -> list[str]:
        threads = ["-j", str(self.profile.threads)] if self.profile.threads > 1 else []
        return [binary, "-n", *threads, "-x", "driver.py", "params.json"]

    def environment(self) -> dict[str, str]:
        return super().environment() | {"PYTHONUNBUFFERED": "1"}

    def diagnose(self, folder: Path, returncode: int) -> tuple[str | None, str]:
        return classify(returncode, log_tail(folder / "engine.log", 80))

    def read_results(self, folder) -> Results:
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
