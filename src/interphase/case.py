"""The engine-free Case: every physical input of one simulation, SI units, frozen and hashable.

A Case knows nothing of LIGGGHTS or YADE. Its identity (`case_id`) is the short hash of its
canonical JSON plus the engine's name and recipe id (Engine.recipe_id): floats canonicalised by
repr of the round-tripped value, keys sorted (signac style).

Geometry: the soil box is `box_length_d50` × `box_height_d50` (D50 units) in the x–z plane, quasi-2D
(one grain layer in y), except in the 3D device (`device = "periodic3d"`, docs/3d.md): periodic in x
and y, `box_depth_d50` deep in y, grains filling the depth, the profile extruded over it (or, with
`profile_y`, z = p(x) + q(y); or, with an areal scan as the profile, the scan's closed patch:
`surface_patch`). For `test = "interface"` the rough surface (profile) slides in x beneath
the soil held in the box; for `test = "box"` a direct shear box of two halves is sheared on the
mid-height plane (no profile).
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import math
from dataclasses import dataclass, field

from interphase.errors import InputError
from interphase.material import Gradation
from interphase.surface.spec import ProfileSpec

TESTS = ("interface", "box", "triaxial", "biaxial")
#: the laboratory's element tests on a periodic cell (engines/cell.py) → the device each runs in
CELL_TESTS = {"triaxial": "periodic3d", "biaxial": "periodic"}
#: the named preparation states → Case.preparation (docs/soils.md gives the solid fraction each reaches)
PREPARATIONS = {"dense": 0.0, "medium": 0.3, "loose": 1.0}
#: the largest Case.preparation: above 1 the consolidation is more frictional than the grains (looser
#: on 50 MPa grains, denser on 500 MPa ones: docs/soils.md, "Looser than the loosest")
PREPARATION_MAX = 3.0
DEVICES = ("walled", "periodic", "periodic3d")
WALL_ZONE_D50 = 3.0      # [D50] left out of the measuring window next to each side wall (Case.window)


@dataclass(frozen=True)
class Start:
    """A case that starts from the specimen another engine's run of the same case consolidated (the
    cross-check's same-specimen protocol, docs/crosscheck.md): that run's grains at the start of its
    shear and its platen height there replace the lattice and the platen (engines/device.py); the
    engine then consolidates for its first stretch and shears as usual. Its identity is the source
    run's engine and case id; `folder` is only where that run lies."""

    engine: str
    case_id: str
    folder: str = field(default="", compare=False)

    def canonical(self) -> dict:
        return {"engine": self.engine, "case_id": self.case_id}

    def label(self) -> str:
        return f"{self.engine}:{self.case_id}"


@dataclass(frozen=True)
class Case:
    test: str = "interface"                 # "interface" | "box"
    profile: ProfileSpec | None = None      # required for interface tests, None for box tests
    d50: float = 0.7e-3                     # median diameter [m]
    gradation: Gradation = field(default_factory=Gradation)
    friction_pp: float = 0.5                # particle–particle sliding friction [-]
    friction_ps: float = 0.2                # particle–surface [-] (tan φμ)
    friction_pw: float = 0.9                # particle–boundary: platen, the box's lower half [-]
    friction_side: float = 0.0              # particle–side wall: the fixed walls (interface box sides,
                                            # the box's upper half) [-]; study 0.9, see docs/strength.md
    rolling_friction: float = 0.1           # rolling-friction coefficient, all contacts [-]
    density: float = 2650.0                 # [kg/m³]
    shear_modulus: float = 29e9             # [Pa] (study: 29 GPa; campaigns may soften it, see docs)
    poisson: float = 0.3                    # [-]
    restitution: float = 0.5                # normal coefficient of restitution [-] (damping ratio 0.215; see docs/liggghts.md)
    normal_stress: float = 100e3            # [Pa], compression positive
    shear_velocity: float = 0.05            # [m/s]
    shear_distance: float = 3e-3            # [m]
    snapshot_every: float = 0.25e-3         # shear displacement between contact dumps [m]
    box_length_d50: float = 40.0            # soil box length [D50]
    box_height_d50: float = 20.0            # soil height above the surface [D50]
    n_grains: int | None = None             # None: fill the box to box_height_d50
    seed: int = 1                           # packing seed
    preparation: float = 1.0                # the share of the grain–grain sliding and rolling friction
                                            # active while the specimen is deposited and consolidated
                                            # (restored for the shear): 0 the densest, 1 the grains'
                                            # own, above 1 more than their own (up to
                                            # PREPARATION_MAX); names in PREPARATIONS
    device: str = "walled"                  # "walled": soil box between side walls (the study's);
                                            # "periodic": x periodic over the box length, no side walls;
                                            # "periodic3d": the same, also periodic in y over
                                            # box_depth_d50, grains filling the depth (docs/3d.md)
    box_depth_d50: float = 10.0             # the 3D cell's depth in y [D50] (periodic3d only; not in
                                            # the identity of other devices)
    profile_y: ProfileSpec | None = None    # periodic3d interface only: the relief across the shear;
                                            # the surface is z(x, y) = profile(x) + profile_y(y) and
                                            # the depth is profile_y's periodic cell nearest
                                            # box_depth_d50 (docs/3d.md). None: the profile extruded
    name: str = field(default="", compare=False)  # a label for people; not part of the identity
    strain_rate: float = 10.0               # triaxial/biaxial only: axial strain rate [1/s] (engineering)
    axial_strain: float = 0.2               # triaxial/biaxial only: axial strain at the end [-]
    start: Start | None = None              # None: the engine's own lattice and consolidation; else
                                            # another run's consolidated specimen (set by the plan,
                                            # [campaign] specimen_from; never in a [case] table)

    def __post_init__(self):
        def bad(fld, msg, fix=None):
            raise InputError(msg, where=f"case.{fld}", fix=fix)

        if self.test not in TESTS:
            bad("test", f"unknown test {self.test!r}", f"use one of {', '.join(TESTS)}")
        if self.device not in DEVICES:
            bad("device", f"unknown device {self.device!r}", f"use one of {', '.join(DEVICES)}")
        if self.test == "interface" and self.profile is None:
            bad("profile", "an interface test needs a surface profile", "give profile = {kind = 'flat'} or another")
        if self.test in CELL_TESTS:
            self._check_cell(bad)
        if self.test == "box" and self.profile is not None:
            bad("profile", "a direct shear box test takes no surface profile", "remove the profile")
        if self.test == "box" and self.friction_ps != self.friction_pw:
            # the box has no rough surface: both halves are boundaries (friction_pw), so one box
            # test has one identity, label and deck however it was declared
            object.__setattr__(self, "friction_ps", self.friction_pw)
        if not isinstance(self.gradation, Gradation):
            bad("gradation", "gradation must be a Gradation")
        if self.device != "periodic3d" and self.box_depth_d50 != 10.0 and not self.cell:
            bad("box_depth_d50", f"only the 3D device has a depth (device is {self.device!r})",
                'use device = "periodic3d", or remove box_depth_d50')
        if self.profile_y is not None and not (self.three_d and self.test == "interface"):
            bad("profile_y", "only an interface test in the 3D device has relief across the shear",
                'use device = "periodic3d" and test = "interface", or remove profile_y')
        if self.profile is not None and self.profile.areal:
            if not (self.three_d and self.test == "interface"):
                bad("profile", "an areal scan's patch is the surface of the 3D cell's interface test only",
                    'use device = "periodic3d" and test = "interface", or shear a line of the scan (remove areal)')
            if self.profile_y is not None:
                bad("profile_y", "an areal scan's patch has its own relief across the shear", "remove profile_y")
        if self.profile_y is not None and not isinstance(self.profile_y, ProfileSpec):
            bad("profile_y", f"must be a profile table, got {self.profile_y!r}",
                'e.g. profile_y = {kind = "sawtooth", rt = 0.2, sw = 2, sr = 0}')
        if self.three_d and self.start is not None:
            bad("start", "a 3D case cannot start from another engine's specimen (LIGGGHTS only, docs/3d.md)",
                "remove specimen_from for 3D cases")
        if self.start is not None and not isinstance(self.start, Start):
            bad("start", f"must be a Start or None, got {self.start!r}", "set it with [campaign] specimen_from")
        positive = ("d50", "density", "shear_modulus", "normal_stress", "shear_velocity", "shear_distance",
                    "snapshot_every", "box_length_d50", "box_height_d50", "box_depth_d50", "strain_rate",
                    "axial_strain")
        nonneg = ("friction_pp", "friction_ps", "friction_pw", "friction_side", "rolling_friction")
        for f in positive + nonneg + ("poisson", "restitution", "preparation"):
            v = getattr(self, f)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                bad(f, f"must be a finite number, got {v!r}")
        for f in positive:
            if getattr(self, f) <= 0:
                bad(f, f"must be > 0, got {getattr(self, f)!r}")
        for f in nonneg:
            if getattr(self, f) < 0:
                bad(f, f"must be ≥ 0, got {getattr(self, f)!r}")
        if not 0 <= self.poisson < 0.5:
            bad("poisson", f"must be in [0, 0.5), got {self.poisson!r}")
        if not 0 <= self.preparation <= PREPARATION_MAX:
            bad("preparation", f"must be in [0, {PREPARATION_MAX:g}] or one of {', '.join(PREPARATIONS)}, got "
                f"{self.preparation!r}", "0 consolidates frictionless grains (densest), 1 at their own friction, "
                f"{PREPARATION_MAX:g} at {PREPARATION_MAX:g} times it (loosest)")
        if not 0 < self.restitution <= 1:
            bad("restitution", f"must be in (0, 1], got {self.restitution!r}")
        if self.d50 > 0.1:
            bad("d50", f"{self.d50!r} m is more than 10 cm", "d50 is in metres (0.7 mm = 0.0007)")
        if self.n_grains is not None and (isinstance(self.n_grains, bool) or not isinstance(self.n_grains, int)
                                          or self.n_grains < 2):
            bad("n_grains", f"must be an integer ≥ 2 or omitted, got {self.n_grains!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or not 0 <= self.seed < 2**63:
            # the packing's numpy generator takes non-negative integers only
            bad("seed", f"must be an integer ≥ 0 (the packing's random seed), got {self.seed!r}",
                "use 1, 2, 3, …")
        if self.test == "interface" and not self.periodic and self.box_length_d50 < 4 * WALL_ZONE_D50:
            bad("box_length_d50", f"{self.box_length_d50!r} leaves less than half the box to measure in "
                f"({WALL_ZONE_D50:g} D50 next to each side wall are left out)", f"use ≥ {4 * WALL_ZONE_D50:g}")
        if self.snapshot_every > self.shear_distance:
            bad("snapshot_every", "is longer than shear_distance: no contact snapshot would be written",
                "make snapshot_every ≤ shear_distance")
        if self.d50 < self.gradation.d_min or self.d50 > self.gradation.d_max:
            bad("d50", f"{self.d50!r} m lies outside the gradation {self.gradation.d_min}–{self.gradation.d_max} m")

    def _check_cell(self, bad) -> None:
        """The element tests' own rules (the shared ones follow in __post_init__)."""
        want = CELL_TESTS[self.test]
        if self.device != want:
            bad("device", f"a {self.test} test runs in the {want!r} cell, not {self.device!r}", f'use device = "{want}"')
        if self.profile is not None or self.profile_y is not None:
            bad("profile", f"a {self.test} test shears no surface", "remove the profile")
        if self.n_grains is None:
            bad("n_grains", f"a {self.test} test needs its number of grains", "give n_grains (e.g. 1000 in 3D, 400 in 2D)")
        if isinstance(self.axial_strain, (int, float)) and not 0 < self.axial_strain < 0.6:
            bad("axial_strain", f"{self.axial_strain!r} is not an axial strain in (0, 0.6)", "e.g. 0.2 for 20 %")
        if self.start is not None:
            bad("start", f"a {self.test} test starts from its own lattice", "remove specimen_from")

    @property
    def cell(self) -> bool:
        """A laboratory element test on a periodic cell (triaxial or biaxial)."""
        return self.test in CELL_TESTS

    # ---- derived ---------------------------------------------------------------------------
    @property
    def periodic(self) -> bool:
        """x periodic over the box length (no side walls): the periodic and the 3D device."""
        return self.device in ("periodic", "periodic3d")

    @property
    def three_d(self) -> bool:
        """The 3D device: also periodic in y over `box_depth`, grains filling the depth."""
        return self.device == "periodic3d"

    @property
    def box_depth(self) -> float:
        """The 3D cell's depth in y [m] (box_depth_d50·D50); NaN for the quasi-2D devices."""
        if not self.three_d:
            return math.nan
        if self.test == "interface" and self.profile.areal:
            return self._patch.width
        return self._cell_y.length if self.profile_y is not None else self.box_depth_d50 * self.d50

    @property
    def box_length(self) -> float:
        """Soil box length [m]: box_length_d50·D50, except for an interface test in the periodic
        device, where it is the length of the periodic cell (`surface()`): where the surface
        closes on itself nearest box_length_d50·D50."""
        if self.periodic and self.test == "interface":
            return self._cell.length
        return self.box_length_d50 * self.d50

    @functools.cached_property
    def _cell(self):
        """The periodic device's surface (computed once per Case; a random or measured profile is
        generated and cut, see surface.builder.periodic_cell)."""
        from interphase.surface.builder import periodic_cell

        if self.profile.areal:      # the patch's x–z silhouette: its length and highest point
            return self._patch.silhouette()
        return periodic_cell(self.profile, self.d50, self.box_length_d50 * self.d50, self._extruded_over)

    @functools.cached_property
    def _patch(self):
        from interphase.surface.builder import areal_patch

        return areal_patch(self.profile, self.d50, self.box_length_d50 * self.d50, self.box_depth_d50 * self.d50)

    def surface_patch(self):
        """An areal scan's closed patch (surface.patch.Patch: heights over [0, L] × [0, W], x from the
        cell's start, y from its side −W/2), the surface the 3D cell shears; None for every other case.
        `surface()` is then its x–z silhouette (the highest point across y at each x)."""
        if self.test == "interface" and self.profile is not None and self.profile.areal:
            return self._patch
        return None

    @functools.cached_property
    def _cell_y(self):
        """The 3D device's relief across the shear: profile_y's periodic cell nearest the requested
        depth, its abscissa the y coordinate from the cell's side (−W/2)."""
        from interphase.surface.builder import periodic_cell

        return periodic_cell(self.profile_y, self.d50, self.box_depth_d50 * self.d50)

    def surface_across(self):
        """The relief across the shear (a Profile whose x is y + W/2 [m]), or None: extruded."""
        return self._cell_y if self.profile_y is not None else None

    @property
    def wall_width(self) -> float:
        """The extent of the walls and the surface across the shear (y) [m]: quasi-2D, 0.9·d_max on
        each side of the grains' plane (beyond any grain); the 3D device, its depth."""
        return self.box_depth if self.three_d else 1.8 * self.gradation.d_max

    @property
    def _extruded_over(self) -> float | None:
        """The width the surface's profile is extruded over [m] (its triangles span it; what a
        measured line's sampling must allow, surface.builder.mesh_step), None with a relief across."""
        areal = self.profile is not None and self.profile.areal
        return None if self.profile_y is not None or areal else self.wall_width

    @property
    def thickness(self) -> float:
        """Out-of-plane thickness t [m] that converts stress to force (F = σ·L·t): quasi-2D, one grain
        layer, t = D50; the 3D device, its depth. Both engines and the analysis use it."""
        return self.box_depth if self.three_d else self.d50

    @property
    def surface_margin(self) -> float:
        """How far the surface reaches beyond the box at each end before the shear [m]: 2·d_max."""
        return 2 * self.gradation.d_max

    def surface(self):
        """The whole rough surface of an interface test in the engine frame at the start of the
        shear [m]: walled device, from x = −surface_margin to beyond L + shear_distance +
        surface_margin (it slides −x by shear_distance beneath the box [0, L]); periodic device,
        exactly the cell [0, L] (`box_length`; the engine wraps it). The one profile object of the
        case: the engines build their meshes from it, the analysis measures it (`sheared_surface`)."""
        from interphase.surface.base import Profile
        from interphase.surface.builder import from_spec

        if self.periodic:       # exactly [0, L]: the engine wraps it as it slides
            return self._cell
        m = self.surface_margin
        prof = from_spec(self.profile, self.d50, self.box_length + self.shear_distance + 2 * m, self._extruded_over)
        return Profile(prof.x - m, prof.z, prof.periodic, prof.name)

    def sheared_surface(self):
        """The part of `surface()` that passes beneath the box during the shear, x ∈ [0, L + shear
        distance] [m]: what θa, Rn, Rnc describe for this case. A periodic profile is returned whole
        (its every period is the same)."""
        from interphase.surface.profiles import crop

        s = self.surface()
        return s if s.periodic else crop(s, 0.0, self.box_length + self.shear_distance)

    @property
    def window(self) -> tuple[float, float]:
        """Measuring window (x0, x1) [m] of an interface test: the soil box [0, L] less
        WALL_ZONE_D50·D50 at each side wall. Surface forces, surface anisotropy and the stress
        sampling region are taken over grains (contacts) inside it. Why: a grain carried by the
        surface into the bottom edge of the leading side wall wedges there, and that force loop
        (surface → grain → wall) never passes through the soil; on a 45° saw-tooth it made the
        whole-surface ratio peak at 1.27 where the window's peaked at 0.72 (1000 grains,
        docs/liggghts.md). A departure from docs/methods.md, which takes [0, L]. Box tests: [0, L]."""
        if self.test != "interface" or self.periodic:
            return (0.0, self.box_length)
        return (WALL_ZONE_D50 * self.d50, self.box_length - WALL_ZONE_D50 * self.d50)

    @property
    def box_height(self) -> float:
        """Soil height [m]."""
        return self.box_height_d50 * self.d50

    # ---- identity --------------------------------------------------------------------------
    def canonical(self) -> dict:
        """Physical inputs as plain JSON data (no label), floats as round-trip values."""
        out = {}
        for f in dataclasses.fields(self):
            if not f.compare:
                continue
            v = getattr(self, f.name)
            if (f.name in ("start", "profile_y") and v is None) or (f.name == "preparation" and v == 1.0) \
                    or (f.name == "box_depth_d50" and not self.three_d) \
                    or (f.name in CELL_ONLY and not self.cell) or (f.name in CELL_IGNORES and self.cell):
                continue            # the usual start and preparation, a 2D device's depth: no key, so every case id without them stays as it was
            if isinstance(v, (ProfileSpec, Gradation, Start)):
                v = v.canonical()
            elif isinstance(v, float):
                v = float(repr(v))
            out[f.name] = v
        if self.cell:               # the cell protocol's constants (interphase.recipe.CELL_RECIPE) are part of it
            from interphase.recipe import CELL_RECIPE

            out["cell_recipe"] = CELL_RECIPE.identity()
        return out

    def label(self) -> str:
        if self.name:
            return self.name
        if self.cell:
            grading = "user" if self.gradation.sizes else self.gradation.name
            prep = "" if self.preparation == 1.0 else f"-prep{self.preparation:g}"
            return f"{self.test}-{self.normal_stress / 1e3:g}kPa-n{self.n_grains}-{grading}{prep}-s{self.seed}"
        surface = self.profile.label() if self.profile else "box"
        if self.profile_y is not None:
            surface += f"-y-{self.profile_y.label()}"
        grading = "user" if self.gradation.sizes else self.gradation.name
        test = f"{self.test}-{self.device}" if self.periodic else self.test
        prep = "" if self.preparation == 1.0 else f"-prep{self.preparation:g}"
        return f"{test}-{surface}-mu{self.friction_ps:g}-{grading}{prep}-s{self.seed}"

    def replace(self, **changes) -> "Case":
        return dataclasses.replace(self, **changes)


def canonical_json(obj) -> str:
    """Sorted keys, no whitespace, floats by repr: the same bytes on every machine."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False)


def case_id(case: Case, engine: str, recipe_id: str, length: int = 12) -> str:
    """Short hash of the case's canonical inputs, the engine that runs it and the engine's recipe
    (Engine.recipe_id: its name, its RECIPE_VERSIONS number and the Recipe's values). Probed nowhere: the same
    on a machine without any engine."""
    payload = canonical_json({"case": case.canonical(), "engine": engine, "recipe": recipe_id})
    return hashlib.sha256(payload.encode()).hexdigest()[:length]



def physical_id(case: Case, length: int = 12) -> str:
    """Short hash of the PHYSICAL case: the canonical inputs without the packing seed, the start
    reduced to the engine whose specimen it takes (the source run's id carries its seed). Every seed
    of one physical case has it, whatever engine or recipe runs it: what seed ensembles pool by."""
    inputs = case.canonical()
    inputs.pop("seed", None)
    if "start" in inputs:
        inputs["start"] = {"engine": inputs["start"]["engine"]}
    return hashlib.sha256(canonical_json({"physical_case": inputs}).encode()).hexdigest()[:length]

#: in the identity of a cell test only (every other case id stays as it was)
CELL_ONLY = ("strain_rate", "axial_strain")
#: what a cell test does not use: left out of its identity
CELL_IGNORES = ("profile", "profile_y", "friction_ps", "friction_pw", "friction_side", "shear_velocity",
                "shear_distance", "snapshot_every", "box_length_d50", "box_height_d50", "box_depth_d50")

#: Case fields the plan sets, never a campaign's [case] table → what to write instead
PLANNED_FIELDS = {"start": 'a case starts from another engine\'s specimen by [campaign] specimen_from = "liggghts"'}


def _did_you_mean(key: str, allowed) -> str:
    import difflib

    close = difflib.get_close_matches(key, list(allowed), n=1)
    return f"did you mean {close[0]!r}?" if close else f"allowed keys: {', '.join(sorted(allowed))}"


def case_from_dict(data: dict, where: str = "case", base_dir=None) -> Case:
    try:
        return _case_from_dict(data, where, base_dir)
    except InputError as exc:
        if str(exc).startswith(where):
            raise
        # anchor the message at the caller's location (file/table), keeping field and fix
        raise InputError(str(exc), where=where) from None


def _case_from_dict(data: dict, where: str, base_dir) -> Case:
    """Build a Case from plain data (a TOML table), SI units, field names as in Case.

    `profile` is a table: {kind = "sawtooth", rt = 1, sw = 2, sr = 0} (D50 units), or
    {kind = "file", path = "x.csv", units = "um", cutoff = 0.0008}, or an areal scan as the 3D cell's
    surface {kind = "file", path = "s.frt", areal = true, direction = "+y"}; a relative path is taken from
    `base_dir` (the campaign file's folder). `gradation` is "mono" | "poly" or
    {sizes = [m...], fractions = [...]}. Unknown keys are refused with a did-you-mean.
    `where` prefixes every message (e.g. "group1.toml: [case]"). `profile_y` (the 3D device's
    relief across the shear) takes the same tables as `profile`.
    """
    fields = {f.name: f for f in dataclasses.fields(Case) if f.name not in PLANNED_FIELDS}
    kwargs = {}
    for key, value in data.items():
        if key in PLANNED_FIELDS:
            raise InputError(f"{key!r} is not set in a case table", where=where, fix=PLANNED_FIELDS[key])
        if key not in fields:
            raise InputError(f"unknown key {key!r}", where=where, fix=_did_you_mean(key, fields))
        kwargs[key] = value
    for key in ("profile", "profile_y"):
        if kwargs.get(key) is not None:
            kwargs[key] = _profile_spec(kwargs[key], f"{where}.{key}", base_dir)
    grad = kwargs.get("gradation")
    if grad is not None:
        if isinstance(grad, str):
            kwargs["gradation"] = Gradation(name=grad)
        elif isinstance(grad, dict):
            extra = set(grad) - {"sizes", "fractions"}
            if extra:
                raise InputError(f"unknown key {sorted(extra)[0]!r} in gradation", where=f"{where}.gradation",
                                 fix="a user gradation has sizes = [m, ...] and fractions = [...]")
            kwargs["gradation"] = Gradation(name="user", sizes=tuple(float(s) for s in grad.get("sizes", ())),
                                            fractions=tuple(float(f) for f in grad.get("fractions", ())))
        else:
            raise InputError(f"gradation must be 'mono', 'poly' or a table, got {grad!r}", where=f"{where}.gradation")
    prep = kwargs.get("preparation")
    if isinstance(prep, str):
        if prep not in PREPARATIONS:
            raise InputError(f"unknown preparation {prep!r}", where=f"{where}.preparation",
                             fix=f"use one of {', '.join(PREPARATIONS)} or a number in [0, {PREPARATION_MAX:g}]")
        kwargs["preparation"] = PREPARATIONS[prep]
    # ints given where floats are expected are fine; floats where ints are expected are not
    for key in ("n_grains", "seed"):
        if isinstance(kwargs.get(key), float) and float(kwargs[key]).is_integer():
            kwargs[key] = int(kwargs[key])
    for key, value in kwargs.items():
        if isinstance(value, int) and not isinstance(value, bool) and fields[key].type in ("float", float):
            kwargs[key] = float(value)
    return Case(**kwargs)


def _profile_spec(prof, where: str, base_dir) -> ProfileSpec:
    """A profile table (or a file path) of a case table as a ProfileSpec; `where` names the key."""
    from pathlib import Path

    from interphase.surface.builder import file_spec

    if isinstance(prof, ProfileSpec):
        return prof
    if isinstance(prof, str):
        prof = {"kind": "file", "path": prof} if prof not in ("flat",) else {"kind": "flat"}
    if not isinstance(prof, dict) or "kind" not in prof:
        raise InputError(f"{where.rsplit('.', 1)[-1]} must be a table with a 'kind'", where=where,
                         fix="e.g. {kind = \"sawtooth\", rt = 1, sw = 2, sr = 0}")
    prof = dict(prof)
    kind = prof.pop("kind")
    if kind != "file":
        return ProfileSpec.make(kind, where=where, **prof)
    allowed = {"path", "units", "cutoff", "axis", "line", "direction", "areal", "window"}
    for k in prof:
        if k not in allowed:
            raise InputError(f"unknown key {k!r} in a file profile", where=where, fix=_did_you_mean(k, allowed))
    if "path" not in prof:
        raise InputError("a file profile needs a path", where=f"{where}.path")
    path = Path(prof["path"])
    if base_dir is not None and not path.is_absolute():
        path = Path(base_dir) / path
    return file_spec(path, units=prof.get("units"), cutoff=prof.get("cutoff"), where=where, axis=prof.get("axis"),
                     line=prof.get("line"), direction=prof.get("direction", "+"), areal=prof.get("areal", False),
                     window=prof.get("window"))
