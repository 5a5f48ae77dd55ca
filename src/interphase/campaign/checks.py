"""Plausibility of a case's inputs: the one check that `render`, `run-case` and `run` (and its dry
run) share, so that a value is an error or a warning in all of them alike.

Hard limits (a value no engine can run: a negative seed, a non-finite number, a friction < 0) are
enforced by `interphase.case.Case` itself when a case is built, i.e. when the file is loaded. This
module adds what is legal but physically implausible for a quasi-2D shear test of sand-like grains:

- `input_errors(cases)`: a shear so fast that the soil is no longer sheared but thrown (estimated
  inertial number I ≥ `INERTIAL_ERROR`, the dense-inertial regime; quasi-static is I < 1e-3).
  Raises one InputError naming the field, the value and a speed that would do.
- `input_warnings(cases)`: I ≥ 1e-3 (not quasi-static), and every numeric field outside the
  range of `PLAUSIBLE` (units SI, as in Case).
- `default_notes(stated)`: the settings the convergence study chose (docs/convergence.md) that a
  file leaves unstated, whose Case defaults are the source study's instead (the default device is
  the walled one). The defaults are kept on purpose: a case id hashes every input, so changing a
  default would give every finished case that relied on it a new id; the note says so and how to
  state the chosen value.
"""

from __future__ import annotations

from interphase.analysis.quasistatic import inertial_estimate, quasi_static_speed, rate_warnings
from interphase.case import case_from_dict
from interphase.errors import InputError

#: field → (low, high, unit, why): outside [low, high] a value is legal but implausible (a warning)
PLAUSIBLE = {
    "d50": (1e-5, 0.02, "m", "sand and gravel grains are 0.01–20 mm"),
    "density": (1000.0, 8000.0, "kg/m³", "mineral and metal grains"),
    "shear_modulus": (1e7, 1e11, "Pa", "below 10 MPa grains overlap by several % of D50; above 100 GPa "
                      "the time step is tiny (docs/campaigns.md, softened stiffness)"),
    "normal_stress": (1e3, 1e7, "Pa", "1 kPa–10 MPa: the range of interface tests"),
    "shear_distance": (1e-4, 0.1, "m", "0.1 mm–10 cm of shear"),
    "friction_pp": (0.0, 1.5, "-", "a sliding friction above 1.5 (56°) is not of grains"),
    "friction_ps": (0.0, 1.5, "-", "a sliding friction above 1.5 (56°) is not of a surface"),
    "friction_pw": (0.0, 1.5, "-", "a sliding friction above 1.5 (56°)"),
    "friction_side": (0.0, 1.5, "-", "a sliding friction above 1.5 (56°)"),
    "rolling_friction": (0.0, 1.0, "-", "rolling resistance above 1 locks grains"),
    "box_length_d50": (4.0, 2000.0, "D50", "a box of more than 2000 D50 is millions of grains"),
    "box_height_d50": (2.0, 500.0, "D50", "a soil column of more than 500 D50"),
    "n_grains": (2, 1_000_000, "grains", "more than 10⁶ grains on one core takes days"),
}

#: above this estimated inertial number the case is refused (docs/strength.md: quasi-static < 1e-3;
#: 0.1 is well into the dense inertial regime, where a "peak" says nothing about the soil)
INERTIAL_ERROR = 0.1

#: the settings the convergence study chose (README, docs/convergence.md) that differ from the Case
#: defaults (the source study's); rolling friction 0.1 is both, so it is not listed
CONVERGED = {
    "device": ("periodic", "walled", "its side walls lift E by ~0.1–0.2 (docs/strength.md)"),
    "shear_velocity": (0.02, 0.05, "quasi-static in the periodic device"),
    "shear_modulus": (50e6, 29e9, "softened; 29 GPa costs ~50× the time"),
    "shear_distance": (6e-3, 3e-3, "past the peak into the critical state"),
    "box_length_d50": (60.0, 40.0, "with 35 D50 of height: every critical state within 0.01 of an 80 × 50 cell's"),
    "box_height_d50": (35.0, 20.0, "the study's 40 × 25 reads tan φ and tan δ ~0.03 low"),
}


def cell_inertial_estimate(case) -> float:
    """The inertial number a triaxial/biaxial case starts its compression at [-]: I = γ̇ d50 √(ρ/σ3′)
    with γ̇ = 1.5 ε̇1 (ε̇3 ≈ −ε̇1/2 at constant volume); the run measures its own (analysis/cell_run.py)."""
    import math

    return 1.5 * case.strain_rate * case.d50 * math.sqrt(case.density / case.normal_stress)


def _cell_rate(cases) -> list[str]:
    slow = [c for c in cases if c.cell and cell_inertial_estimate(c) >= 1e-3]
    if not slow:
        return []
    c = max(slow, key=cell_inertial_estimate)
    return [f"{len(slow)} triaxial/biaxial case(s) at a strain rate whose estimated inertial number reaches "
            f"{cell_inertial_estimate(c):.2g} (strain_rate {c.strain_rate:g} /s at σ3′ {c.normal_stress:g} Pa): not "
            "quasi-static (I < 1e-3); lower strain_rate"]


def input_errors(cases, where: str = "case") -> None:
    """Raise an InputError for the first case whose shear is far from quasi-static (I ≥ INERTIAL_ERROR)."""
    for c in cases:
        if c.cell:
            if cell_inertial_estimate(c) >= INERTIAL_ERROR:
                raise InputError(f"strain_rate = {c.strain_rate:g} /s gives an estimated inertial number "
                                 f"{cell_inertial_estimate(c):.2g}: the grains are thrown, not sheared",
                                 where=f"{where}.strain_rate", fix="use a strain rate of about 10 /s or less")
            continue
        i = inertial_estimate(c)
        if i >= INERTIAL_ERROR:
            raise InputError(f"shear_velocity = {c.shear_velocity:g} m/s gives an estimated inertial number "
                             f"I ≈ {i:.2g} at σ = {c.normal_stress:g} Pa: the grains are thrown, not sheared "
                             f"(quasi-static is I < 1e-3)", where=f"{where}.shear_velocity",
                             fix=f"use shear_velocity ≤ {quasi_static_speed(c):.3g} m/s")


def input_warnings(cases) -> list[str]:
    """One line per implausible (field, value) over `cases` (with how many cases it concerns), then
    the inertial-number warnings of `analysis.quasistatic.rate_warnings`. Empty when everything is plausible."""
    seen: dict[tuple[str, object], int] = {}
    cells = [c for c in cases if c.cell]
    cases = [c for c in cases if not c.cell]
    for c in cases + cells:
        for name, (lo, hi, _, _) in PLAUSIBLE.items():
            if c.cell and name in ("shear_distance", "box_length_d50", "box_height_d50"):
                continue
            v = getattr(c, name)
            if v is not None and not lo <= v <= hi:
                seen[(name, v)] = seen.get((name, v), 0) + 1
    out = []
    for (name, v), n in seen.items():
        lo, hi, unit, why = PLAUSIBLE[name]
        out.append(f"{n} case(s) with {name} = {v:g} {unit}: outside the plausible {lo:g}–{hi:g} {unit} ({why})")
    return out + (rate_warnings(cases) if cases else []) + _cell_rate(cells)


def default_notes(stated) -> list[str]:
    """Notes on the convergence study's settings that the input leaves to the Case defaults.
    `stated`: the Case field names the file (or call) gave."""
    missing = [k for k in CONVERGED if k not in set(stated)]
    if not missing:
        return []
    shown = ", ".join(f"{k} = {CONVERGED[k][1]!r} (chosen: {CONVERGED[k][0]!r}: {CONVERGED[k][2]})"
                      for k in missing)
    return [f"unstated settings take the source study's defaults, not the convergence study's choices "
            f"(docs/convergence.md): {shown}. The defaults stay so that finished cases keep their ids; "
            "state the chosen values in [case] to use them"]


def case_file_warnings(path, case) -> list[str]:
    """input_warnings and default_notes of a case file (`campaign render`, `campaign run-case`)."""
    import tomllib
    from pathlib import Path

    stated = tomllib.loads(Path(path).read_text()).get("case", {})
    return input_warnings([case]) + default_notes(stated)


def load_case_file(path):
    """The Case of a TOML file's [case] table (Case fields, SI units; a profile file's path is
    relative to the TOML file), refused when its shear is far from quasi-static (input_errors). Every
    problem is an InputError naming the file."""
    import tomllib
    from pathlib import Path

    p = Path(path)
    try:
        data = tomllib.loads(p.read_text())
    except FileNotFoundError:
        raise InputError("file not found", where=str(path), fix="give a TOML file with a [case] table") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"TOML syntax error: {exc}", where=str(path)) from None
    if "case" not in data or not isinstance(data["case"], dict):
        raise InputError("no [case] table", where=str(path), fix="put the Case fields under [case]")
    case = case_from_dict(data["case"], where=f"{path}: [case]", base_dir=p.parent)
    input_errors([case], where=f"{path}: [case]: case")
    return case
