"""Plan: the campaign's cases × engines → `PlannedCase`s with stable ids, folders and flat parameters.

A campaign with `specimen_from` (the cross-check) gives every other engine's case a `Start` on the
source engine's run of the same case (interphase.case.Start): its id hashes that run's id, so it
is known before anything runs, and the source engine's cases come first in the plan.

A case id is `interphase.case.case_id(case, engine, recipe id)`: the same inputs run by the same
engine and recipe (the engine's number in interphase.recipe.RECIPE_VERSIONS and the Recipe's values) get the same id on
every machine, with or without the engine installed; a new recipe version gives that engine new ids (and so new
folders: old results are never overwritten). The engine build that ran a case is provenance in its
case.json.

Engines are values here: a name given to `plan` is made once into an EngineSpec
(interphase.engines.base.engine_spec: class, profile, Recipe, recipe version), and every
PlannedCase carries its engine's (`engine_spec`), which the executors hand to the runner as it is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from interphase.case import Case, Start, case_id, physical_id
from interphase.campaign.schema import Campaign
from interphase.engines.base import EngineSpec, engine_spec
from interphase.errors import InputError


@dataclass(frozen=True)
class PlannedCase:
    """One engine run of the campaign."""

    case_id: str
    engine: str
    case: Case
    group: str
    role: str                                   # "interface" | "box"
    label: str
    values: tuple = ()                          # the swept values that made it
    pair_id: str | None = None                  # case id of the paired box test (interface cases)
    index: int = 0                              # position in the plan (stable order)
    recipe_id: str = ""
    physical_id: str = ""                       # interphase.case.physical_id: the same for every seed of the case
    params: dict = field(default_factory=dict, compare=False, hash=False)
    #: the engine as a value (class, profile, Recipe, recipe version): what runs the case; its
    #: identity is `recipe_id`
    engine_spec: EngineSpec | None = field(default=None, compare=False, hash=False, repr=False)

    def meta(self, campaign: str = "") -> dict:
        """What the runner records in case.json besides the inputs (JSON data)."""
        return {"case_id": self.case_id, "engine": self.engine, "group": self.group, "role": self.role,
                "label": self.label, "pair_id": self.pair_id, "campaign": campaign,
                "values": {k: _jsonable(v) for k, v in self.values}, "params": self.params,
                "recipe_id": self.recipe_id, "physical_id": self.physical_id}


def _jsonable(v):
    if isinstance(v, tuple):
        if all(isinstance(x, tuple) and len(x) == 2 and isinstance(x[0], str) for x in v):
            return {k: _jsonable(x) for k, x in v}
        return [_jsonable(x) for x in v]
    return v


def flat_params(case: Case) -> dict:
    """The Case's canonical parameters as one flat row of JSON scalars (report columns)."""
    out: dict = {}
    for key, value in case.canonical().items():
        if key == "profile":
            continue
        if key == "start":
            out["start"] = case.start.label()
            continue
        if key == "profile_y":          # 3D relief across the shear: its label (a scalar column)
            out["profile_y"] = case.profile_y.label()
            continue
        if key == "gradation":
            out["gradation"] = value if isinstance(value, str) else "user"
            continue
        out[key] = value
    prof = case.profile
    out["profile_kind"] = prof.kind if prof else None
    for p in ("rt", "sw", "sr", "au", "ar", "rtmax", "seed"):
        out[f"profile_{p}" if p == "seed" else p] = None
    if prof is not None:
        for k, v in prof.params:
            out[f"profile_{k}" if k == "seed" else k] = float(v)
    out["profile_path"] = prof.path if prof is not None and prof.kind == "file" else None
    out["profile_sha256"] = prof.sha256 if prof is not None and prof.kind == "file" else None
    out["profile_label"] = prof.label() if prof is not None else None
    return out


def plan(campaign: Campaign, engines=None, identity=None) -> list[PlannedCase]:
    """Every (case, engine) of the campaign, box tests first (E needs them), in a stable order.

    `engines` (names or EngineSpecs) overrides the campaign's engine list (`campaign run --engine`);
    a name becomes its EngineSpec here, once. The recipe id is the EngineSpec's; `identity(name)`,
    when given, replaces it (benchmarks and tests may pass a constant one)."""
    if campaign.lazy:
        return list(iter_plan(campaign, engines, identity))
    specs = engine_specs(campaign, engines)
    rids = {s.name: identity(s.name) if identity else s.recipe_id() for s in specs.values()}
    out: list[PlannedCase] = []
    order = sorted(range(len(campaign.cases)), key=lambda i: (campaign.cases[i].role != "box", i))
    src = campaign.specimen_from
    names = tuple(specs)
    starts = {}
    if src:
        names = tuple(sorted(names, key=lambda n: n != src))     # the specimens are made first
        src_id = rids[src] if src in rids else (identity(src) if identity else engine_spec(src).recipe_id())
        for i, c in enumerate(campaign.cases):
            sid = case_id(c.case, src, src_id)
            starts[i] = Start(src, sid, str(campaign.output / sid))
    for name in names:
        rid = rids[name]
        cases = [c.case if name == src or i not in starts else c.case.replace(start=starts[i])
                 for i, c in enumerate(campaign.cases)]
        ids = {i: case_id(case, name, rid) for i, case in enumerate(cases)}
        for i in order:
            c = campaign.cases[i]
            params = flat_params(cases[i])
            out.append(PlannedCase(
                case_id=ids[i], engine=name, case=cases[i], group=c.group, role=c.role, label=case_label(c.case),
                values=c.values, pair_id=ids[c.pair] if c.pair is not None else None, index=len(out),
                recipe_id=rid, physical_id=physical_id(cases[i]), params=params, engine_spec=specs[name]))
    return out


def engine_specs(campaign: Campaign, engines=None) -> dict[str, EngineSpec]:
    """{name: EngineSpec} of `engines` (names or EngineSpecs; None: the campaign's engine names), in
    their order; a name is made into this machine's EngineSpec (engines.base.engine_spec)."""
    from interphase.campaign.schema import ENGINES

    out = {}
    for e in tuple(engines) if engines else campaign.engines:
        if not isinstance(e, EngineSpec) and e not in ENGINES:
            raise InputError(f"unknown engine {e!r}", where="--engine", fix=f"use one of {', '.join(ENGINES)}")
        spec = engine_spec(e)
        out[spec.name] = spec
    return out


def iter_plan(campaign: Campaign, engines=None, identity=None):
    """The planned cases one at a time, never all in memory: what `campaign run --dry-run` counts
    and samples. A campaign of at most schema.EAGER_MAX cases gives plan()'s list in plan()'s
    order; a larger (lazy) one is built as it is read, each box test just before the first
    interface case that needs it (the same ids as plan() would give; 10⁶ cases: BENCHMARKS.md)."""
    if not campaign.lazy:
        yield from plan(campaign, engines, identity)
        return
    from interphase.campaign.schema import iter_cases

    specs = engine_specs(campaign, engines)
    if campaign.specimen_from:
        raise InputError(f"a campaign of {campaign.size} cases with specimen_from is not planned lazily",
                         where=f"{campaign.path}: campaign.specimen_from",
                         fix="split the sweep into files of at most 20000 cases")
    rids = {n: identity(n) if identity else s.recipe_id() for n, s in specs.items()}
    index = 0
    for c, box, new in iter_cases(campaign):
        for name in specs:
            rid = rids[name]
            for b in new + ([c] if c is not None else []):
                pair = case_id(box.case, name, rid) if b is c and box is not None else None
                yield PlannedCase(case_id=case_id(b.case, name, rid), engine=name, case=b.case, group=b.group,
                                  role=b.role, label=case_label(b.case), values=b.values, pair_id=pair, index=index,
                                  recipe_id=rid, physical_id=physical_id(b.case), params=flat_params(b.case),
                                  engine_spec=specs[name])
                index += 1


def case_label(case: Case) -> str:
    """A case's label in a campaign (PlannedCase.label, the runs' `label` column): Case.label(), made
    unique within a campaign when the case carries a name (Group 4's A–G)."""
    if not case.name:
        return case.label()
    grading = "user" if case.gradation.sizes else case.gradation.name
    return f"{case.name}-mu{case.friction_ps:g}-{grading}-s{case.seed}"


def estimate_grains(case: Case) -> int:
    """Grains the engines will place (interphase.engines.packing.grain_count)."""
    from interphase.engines.packing import grain_count

    return grain_count(case)


def estimate_seconds(case: Case, throughput: float = 1.5e6) -> float:
    """Rough engine run time [s]: particle-steps / throughput (docs/engines.md: 1.5–4e6 steps/s on one core),
    with the LIGGGHTS deck's own time step and consolidation time. Used for SLURM time limits; the
    engine's own timeout is separate."""
    if case.cell:
        return _cell_seconds(case, throughput)
    from interphase.engines.device import CONSOLIDATION_TIME
    from interphase.engines.liggghts import time_step

    steps = (CONSOLIDATION_TIME + case.shear_distance / case.shear_velocity) / time_step(case)
    return steps * estimate_grains(case) / throughput


#: consolidation chunks an element cell typically needs past its first stretch (2–3 on the 3D Karlsruhe
#: card's 1000-grain cells at 50–100 kPa, read off their LIGGGHTS logs)
CELL_CHUNKS = 2


def _cell_seconds(case: Case, throughput: float) -> float:
    """An element cell's run time [s]: its own steps (engines.cell.cell_steps at the cell's time step:
    the first consolidation, CELL_CHUNKS chunks, the settle, the axial compression) over its grains."""
    from interphase.engines.cell import cell

    c = cell(case)
    s = c.steps
    steps = s.n_consolidate + CELL_CHUNKS * s.n_chunk + c.n_settle + s.n_shear
    return steps * c.packing.n / throughput


#: SLURM time limits are rounded up to one of these (minutes), so that a campaign makes few arrays
TIME_BUCKETS = (1, 2, 5, 10, 15, 30, 60, 120, 240, 480, 720, 1440, 2880)


def time_limit_minutes(case: Case, factor: float = 3.0, fixed: float | None = None) -> int:
    """Time limit of a case on SLURM [min]: `fixed`, else factor × estimate + 2 min, bucketed."""
    if fixed is not None:
        return max(1, int(math.ceil(fixed)))
    need = factor * estimate_seconds(case) / 60.0 + 2.0
    for b in TIME_BUCKETS:
        if need <= b:
            return b
    return int(math.ceil(need))


def case_folder(root: Path, planned: PlannedCase) -> Path:
    return Path(root) / planned.case_id
