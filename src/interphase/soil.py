"""Soil cards: a calibrated granular soil as data (`soils/NAME.toml`), and the element test's cases.

A card holds the Case fields of the grains (`[soil]`), the element test's protocol (`[element]`),
and what the calibration knew and found (`[target]`, `[posterior]`, `[[achieved]]`,
`[[verification]]`, written by `campaign calibrate`). A campaign uses it with
`[case] soil = "soils/NAME.toml"`: the card's `[soil]` fields fill the Case; a field set in the
campaign as well is an error naming both places (a soil is calibrated as a whole).

The element test is the soil's own shear test in the wall-free device (Case test = "box", device =
"periodic": the soil sheared against a frozen bed of its own grains under a servo platen, x
periodic; docs/strength.md, docs/soils.md), at the card's `[element]` cell and speed.
Units: SI (m, Pa, m/s, kg/m³).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from interphase.errors import InputError

#: Case fields a card may set: the grains and how the specimen is made, nothing of a surface or a test
SOIL_FIELDS = ("d50", "gradation", "density", "shear_modulus", "poisson", "restitution", "friction_pp",
               "rolling_friction", "preparation")
#: Case fields of the element test's protocol, and their defaults (docs/soils.md: the cell that agrees
#: with the interface campaigns' 40 × 25 D50 soil test at 0.02 m/s within its scatter, and whose φ_peak
#: scatters a fifth as much as the 20 × 15 cell's over 5 seeds, at twice its cost; the speed of the
#: campaigns, quasi-static: estimated I 6.5e-4 at 100 kPa, < 1e-3 down to ~45 kPa, where 0.05 m/s gave
#: 1.6e-3 — φ within the scatter of 0.02 in the 20 × 15 cell; `campaign element --shear-velocity`)
ELEMENT_DEFAULTS = {"box_length_d50": 30.0, "box_height_d50": 20.0, "shear_velocity": 0.02,
                    "shear_distance": 0.006, "snapshot_every": 0.0005, "friction_pw": 0.9}
#: the laboratory's element test on the periodic cell (`[cell]`, engines/cell.py): its test and protocol
#: (docs/soils.md: the specimen size converged for φ_peak and ψ_max, the rate quasi-static)
CELL_DEFAULTS = {"test": "triaxial", "n_grains": 1000, "strain_rate": 10.0, "axial_strain": 0.2}
DR_LIMITS = ("index", "test")       # [density] dr_limits: what a relative density is read on (SoilCard.dr_limits)
CARD_KEYS = ("soil", "element", "cell", "density", "target", "posterior", "achieved", "verification", "calibration",
             "criterion")


@dataclass(frozen=True)
class SoilCard:
    name: str
    path: Path
    soil: dict                        # Case fields (SOIL_FIELDS)
    element: dict                     # element-test protocol (ELEMENT_DEFAULTS keys)
    description: str = ""
    extra: dict = field(default_factory=dict)     # target, posterior, achieved, verification, calibration

    @property
    def cell(self) -> dict:
        """The card's [cell] protocol over CELL_DEFAULTS (2D cards: `test = "biaxial"`)."""
        return {**CELL_DEFAULTS, **{k: v for k, v in self.extra.get("cell", {}).items() if k != "relative_density"}}

    @property
    def relative_density(self) -> float | None:
        """The relative density [-] the card's cell tests are run at when none is asked ([cell]
        relative_density: the laboratory series the card stands for); None: at its preparation."""
        v = self.extra.get("cell", {}).get("relative_density")
        return None if v is None else float(v)

    def cell_case(self, confining_stress: float, seed: int = 1, *, test: str | None = None, **changes) -> dict:
        """The laboratory's element test (triaxial / biaxial) as a [case] table (plain data)."""
        cell = dict(self.cell)
        test = test or cell.pop("test")
        cell.pop("test", None)
        device = "periodic3d" if test == "triaxial" else "periodic"
        return {"test": test, "device": device, **self.soil, **cell, "normal_stress": float(confining_stress),
                "seed": int(seed), **changes}

    @property
    def void_ratio_limits(self) -> tuple[float, float]:
        """(e_min, e_max) the card's grains reach by its own protocol ([density], `campaign density`);
        NaNs without them."""
        d = self.extra.get("density", {})
        return float(d.get("e_min", "nan")), float(d.get("e_max", "nan"))

    @property
    def lab_span(self) -> float:
        """The slope of the density scale, model Dr = lab_offset + lab_span · laboratory Dr, on the model's
        span of void ratios (frictionless preparation to the grains' own friction, on the limits
        `dr_limits` names): [density] lab_span, set by a calibration against records
        (calibrate_cell._lab_scale). On index limits the sand's e_max − e_min over the model's, so a step
        in the laboratory's e0 is the same step in the model's; on the test's limits the model's Dr at
        the fitted state over the record's. 1 when the card has none: the model's own limits are the
        laboratory's (docs/soils.md, "The density scale")."""
        return float(self.extra.get("density", {}).get("lab_span", 1.0))

    @property
    def lab_offset(self) -> float:
        """The model's Dr [-] that a laboratory Dr of 0 maps onto ([density] lab_offset: set with lab_span
        by a calibration on index limits so that the fitted record's Dr lands on the fitted state, or
        fitted through several records of one stress by studies/density_scale/density_scale.py): the model's Dr =
        lab_offset + lab_span · Dr. 0 when the card has none (the one-parameter scale: the model's
        loosest packing is the laboratory's e_max). Negative when the laboratory's loose end lies
        beyond what the protocol packs; a Dr mapped there is made at the loosest packing (preparation 1)
        and reported at the Dr it reached."""
        return float(self.extra.get("density", {}).get("lab_offset", 0.0))

    @property
    def dr_limits(self) -> str:
        """The void ratios a relative density is read on ([density] dr_limits): "index" (the default),
        the model's index limits at the reference stress, so a Dr is one void ratio after
        consolidation at every stress, as the laboratory's Dr0 is; "test", the limits the preparation
        makes at the test's stress, for grains that compress far more than the sand (their overlap
        is not a denser fabric). Which one a card's grains need: docs/soils.md, "Density by relative
        density"."""
        return str(self.extra.get("density", {}).get("dr_limits", "index"))

    @property
    def quick(self) -> bool:
        """Written by `campaign calibrate --quick`: a first look, not a calibrated soil."""
        return bool(self.extra.get("calibration", {}).get("quick", False))

    def element_case(self, normal_stress: float, seed: int = 1, **changes) -> dict:
        """The element test's Case fields as a [case] table (plain data)."""
        return {"test": "box", "device": "periodic", **self.soil, **self.element, "normal_stress": float(normal_stress),
                "seed": int(seed), **changes}


def _line_of(text: str, table: str, key: str) -> int | None:
    """The line of `key = ` inside `[table]` (1-based), for messages."""
    inside = False
    for n, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if s.startswith("["):
            inside = s.strip("[] ") == table
        elif inside and s.split("=", 1)[0].strip() == key:
            return n
    return None


def read_toml(path, what: str, fix: str):
    """(path, text, data, bad) of a TOML file the soil commands read: a missing file or a syntax
    error is an InputError naming the file; `bad(table, key, message, fix)` builds one naming the
    file, the line and the field."""
    p = Path(path)
    try:
        text = p.read_text()
        data = tomllib.loads(text)
    except FileNotFoundError:
        raise InputError(f"{what} not found", where=str(p), fix=fix) from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"TOML syntax error: {exc}", where=str(p)) from None

    def bad(table, key, msg, fix=None):
        line = _line_of(text, table, key)
        return InputError(msg, where=f"{p}:{line}: [{table}] {key}" if line else f"{p}: [{table}] {key}", fix=fix)

    return p, text, data, bad


def soil_fields(table: dict, bad, fix: str) -> dict:
    """A [soil] table's Case fields, each checked to be one of SOIL_FIELDS."""
    for key in table:
        if key not in SOIL_FIELDS:
            raise bad("soil", key, f"{key!r} is not a soil field", fix)
    return dict(table)


def element_fields(table: dict, bad) -> dict:
    """The element protocol: ELEMENT_DEFAULTS with an [element] table's values."""
    element = dict(ELEMENT_DEFAULTS)
    for key, value in table.items():
        if key not in ELEMENT_DEFAULTS:
            raise bad("element", key, f"{key!r} is not an element-test field", f"use {', '.join(ELEMENT_DEFAULTS)}")
        element[key] = value
    return element


def load_card(path) -> SoilCard:
    """Read and check a soil card. Every problem is an InputError naming the file, line and field."""
    if Path(path).suffix.lower() in (".dat", ".csv", ".txt", ".xlsx", ".xls"):
        raise InputError("a laboratory record, not a soil card", where=str(path),
                         fix="read it with `campaign lab-record`, calibrate a card on it (`campaign calibrate "
                             "TARGET.toml`; docs/answer.md, from a record to an answer), or give soils/NAME.toml")
    p, text, data, bad = read_toml(path, "soil card", "give the path of a soils/NAME.toml card "
                                   "(`campaign calibrate TARGET.toml` writes one)")
    for key in data:
        if key not in CARD_KEYS:
            raise InputError(f"unknown table [{key}]", where=str(p), fix=f"a soil card has {', '.join(CARD_KEYS)}")
    soil = dict(data.get("soil", {}))
    if not soil:
        raise InputError("no [soil] table", where=str(p), fix=f"give the grains' Case fields: {', '.join(SOIL_FIELDS)}")
    name = soil.pop("name", p.stem)
    description = soil.pop("description", "")
    soil = soil_fields(soil, bad, f"a card sets only {', '.join(SOIL_FIELDS)}; surface and test fields belong in "
                       "the campaign")
    element = element_fields(data.get("element", {}), bad)
    card = SoilCard(name=str(name), path=p.resolve(), soil=soil, element=element, description=str(description),
                    extra={k: data[k] for k in CARD_KEYS[2:] if k in data})
    check_fields(card.element_case(100e3), card, bad)
    _check_cell(card, bad)
    return card


def check_fields(case: dict, card: SoilCard, bad) -> None:
    """Every field checked now, as the Case would; an error names the card's line and table."""
    import re

    from interphase.case import case_from_dict

    try:
        case_from_dict(case, where="case")
    except InputError as exc:
        m = re.match(r"case\.(\w+)[^:]*: (.*)", str(exc), re.S)
        if m is None:
            raise InputError(str(exc).removeprefix("case: "), where=str(card.path)) from None
        key, msg = m.groups()
        table = "soil" if key in card.soil else "element" if key in ELEMENT_DEFAULTS else None
        if table is None:
            raise InputError(msg, where=f"{card.path}: {key}") from None
        raise bad(table, key, msg) from None


def _check_cell(card: SoilCard, bad) -> None:
    """The [cell] table's keys, and its case as the Case would check it."""
    from interphase.case import case_from_dict

    for key in card.extra.get("cell", {}):
        if key not in (*CELL_DEFAULTS, "relative_density"):
            raise bad("cell", key, f"{key!r} is not a cell field", f"use {', '.join(CELL_DEFAULTS)}, relative_density")
    dr = card.extra.get("cell", {}).get("relative_density")
    if dr is not None and not (isinstance(dr, (int, float)) and 0 <= dr <= 1):
        raise bad("cell", "relative_density", f"must be a fraction in [0, 1], got {dr!r}", "e.g. relative_density = 0.81")
    span = card.extra.get("density", {}).get("lab_span")
    if span is not None and not (isinstance(span, (int, float)) and span > 0):
        raise bad("density", "lab_span", f"must be a positive share, got {span!r}",
                  "the model's Dr at the fitted state over the record's (campaign calibrate writes it)")
    offset = card.extra.get("density", {}).get("lab_offset")
    if offset is not None and not (isinstance(offset, (int, float)) and not isinstance(offset, bool)
                                   and math.isfinite(offset)):
        raise bad("density", "lab_offset", f"must be a number, got {offset!r}",
                  "the model's Dr a laboratory Dr of 0 maps onto (studies/density_scale/density_scale.py fits it), e.g. -1.2")
    limits = card.extra.get("density", {}).get("dr_limits")
    if limits is not None and limits not in DR_LIMITS:
        raise bad("density", "dr_limits", f"unknown limits {limits!r}",
                  'use "index" (the model\'s index void ratios, the default) or "test" (the limits at the test\'s stress)')
    if card.cell["test"] not in ("triaxial", "biaxial"):
        raise bad("cell", "test", f"unknown cell test {card.cell['test']!r}", 'use "triaxial" (3D) or "biaxial" (2D)')
    try:
        case_from_dict(card.cell_case(100e3), where="[cell]")
    except InputError as exc:
        raise InputError(str(exc), where=f"{card.path}") from None


def merge_soil(table: dict, card: SoilCard, where: str) -> dict:
    """A campaign's [case] table with the card's soil fields filled in; a field in both is an error
    naming both places, and so is a card calibrated in 3D (triaxial cell) in a quasi-2D device, or a
    quasi-2D card (biaxial cell, discs) in the 3D one: its grains are another material there."""
    device = table.get("device", "walled")
    calibrated_in = card.extra.get("cell", {}).get("test")      # a card calibrated by the box test has none
    if calibrated_in is not None and (calibrated_in == "triaxial") != (device == "periodic3d"):
        dim, other = ("3D", "quasi-2D") if card.cell["test"] == "triaxial" else ("quasi-2D", "3D")
        raise InputError(f"the soil card {card.path} is calibrated in {dim} (its [cell] test is {card.cell['test']}), "
                         f"the device {device!r} is {other}", where=f"{where}.device",
                         fix='use device = "periodic3d" for a 3D card and "periodic" for a quasi-2D one, or the '
                             f"sand's {other} card")
    both = sorted(set(table) & set(card.soil))
    if both:
        raise InputError(f"{both[0]!r} is set here and in the soil card {card.path}", where=where,
                         fix=f"remove {both[0]!r} from the campaign (the card's soil is calibrated as a whole), "
                             "or drop `soil` and give every soil field yourself")
    return {**card.soil, **table}


def criterion_fit(card: SoilCard) -> Path:
    """The criterion.json the card names in `[criterion] fit` (relative to the card): the criterion
    fitted on its own interface runs (`campaign predict --soil`). InputError, naming the card's
    field and the fix, when it names none or the file is missing."""
    ref = card.extra.get("criterion", {}).get("fit")
    where = f"{card.path}: [criterion] fit"
    if not isinstance(ref, str) or not ref:
        raise InputError("the card names no criterion fitted on its soil", where=where,
                         fix="run the soil's interface campaign (e.g. studies/kfs_group1_3d/group1_kfs_3d.toml), "
                             "`campaign report` it, and set [criterion] fit = \"…/criterion.json\" in the card; "
                             "or predict with --fit")
    path = Path(ref) if Path(ref).is_absolute() else (card.path.parent / ref).resolve()
    if not path.exists():
        raise InputError(f"the card's criterion file {path} does not exist", where=where,
                         fix="the path is relative to the card; `campaign report` writes criterion.json")
    return path


def card_d50_mm(card: SoilCard, given_mm, why: str, where: str = "--d50") -> float:
    """The card's D50 [mm]; a given one more than 1 % off it is refused (`why`: what depends on it;
    `where`: the option or argument that gave it)."""
    d50_mm = round(float(card.soil["d50"]) * 1e3, 9)
    if given_mm is not None and abs(given_mm - d50_mm) > 0.01 * d50_mm:
        raise InputError(f"{where} {given_mm:g} mm is not the card's D50 ({d50_mm:g} mm): {why}", where=where,
                         fix=f"drop {where} (the card's is used), or give no soil card for another soil")
    return d50_mm
