"""Campaign TOML → validated `Campaign` (a list of Cases with their groups and pairs), before anything runs.

File layout (SI units; [case] keys are the field names of `interphase.case.Case`):

    [campaign]
    name = "group1"                    # letters, digits, - and _ (folder name)
    description = "..."
    engines = ["liggghts"]             # or engine = "liggghts"; `campaign run --engine` overrides
    output = "../runs/group1"          # the runs folder, relative to the campaign file; default: runs/<name>
                                       # beside the campaign file; `--runs DIR` on any command overrides it
    specimen_from = "liggghts"         # optional, with two engines: the other engine shears the specimen
                                       # this one consolidated for the same case (its grains and platen
                                       # at the start of the shear); its runs come first

    [execution]
    executor = "local"                 # local | slurm
    jobs = 0                           # local pool size; 0 = number of cores
    partition = "debug"                # slurm partition (default: the cluster's default)
    time_limit = "auto"                # minutes per case, or "auto" (from the case size)
    time_factor = 3.0                  # "auto": limit = factor × estimated run time (+ 2 min)
    max_concurrent = 16                # slurm array parallelism (cases running at once)

    [case]                             # constants of every case
    soil = "soils/ottawa-20-30.toml"   # optional: a soil card's grain fields (interphase.soil); a field
                                       # set here as well, or swept, is an error naming both places
    profile = {kind = "sawtooth", rt = 1, sw = 2, sr = 0}   # D50 units; files: {kind="file", path=...}
    friction_ps = 0.2

    [sweep]                            # cartesian product of lists (TOML order)
    friction_ps = [0.05, 0.2, 0.5]
    gradation = ["mono", "poly"]
    profile.rt = [0.1, 0.2, 0.5]       # a profile parameter (dotted key)
    profile = [{kind = "file", path = "profiles/a.csv", units = "um"}, ...]   # or whole profiles

    [zip]                              # lists of one length, taken together (one factor of the product)
    name = ["A", "B"]
    profile.au = [1, 2]

    [[group]]                          # optional: several groups in one file, each with its own
    name = "1"                         # [group.case] overrides, [group.sweep] and [group.zip];
    [group.sweep]                      # without [[group]] the file is one group named after [campaign]
    profile.rt = [0.1, 0.2]

    [pairs]                            # paired direct shear box tests, for E = tan δ / tan φ
    box = true                         # default: true when the campaign has interface cases
    case = {shear_distance = 0.004}    # overrides for the box tests
    seeds = [1, 2, 3, 4, 5, 6]         # each soil's box test also on these packing seeds: tan φ, shared
                                       # by every interface case on that soil, rests on more seeds

    [seeds]                            # sequential seeds (campaign.sequential), instead of a seed sweep:
    start = 3                          # every physical case runs seeds 1..start first
    max = 12                           # the cap: never more seeds than this per physical case
    step = 1                           # seeds added per round to a case still wider than the target
    target = {quantity = "E", halfwidth = 0.05}   # E | tan_delta | E_cs | tan_delta_cs; halfwidth [-],
                                       # absolute, half the width of the quantity's 95 % interval

Every message names the file, the line of the key, the key, the allowed values and the fix.
"""

from __future__ import annotations

import copy
import difflib
import itertools
import math
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from interphase.case import PLANNED_FIELDS, Case, canonical_json, case_from_dict
from interphase.errors import InputError

ENGINES = ("liggghts", "yade")
EXECUTORS = ("local", "slurm")
TOP_KEYS = ("campaign", "execution", "case", "sweep", "zip", "group", "pairs", "seeds",
            "crosscheck")   # [crosscheck] tolerances: read by campaign.crosscheck, ignored here
CAMPAIGN_KEYS = ("name", "description", "engines", "engine", "output", "specimen_from")
EXECUTION_KEYS = ("executor", "jobs", "partition", "time_limit", "time_factor", "max_concurrent")
GROUP_KEYS = ("name", "description", "case", "sweep", "zip")
PAIR_KEYS = ("box", "case", "seeds")
SEEDS_KEYS = ("start", "max", "step", "target")
TARGET_KEYS = ("quantity", "halfwidth")
#: quantities a [seeds] target may name: columns of the report's ensembles table (analysis.ensemble_table)
SEED_QUANTITIES = ("E", "tan_delta", "E_cs", "tan_delta_cs")
CASE_FIELDS = tuple(f for f in Case.__dataclass_fields__ if f not in PLANNED_FIELDS)
NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")


@dataclass(frozen=True)
class Execution:
    """How cases run. Times in minutes."""

    executor: str = "local"
    jobs: int = 0                       # 0: one per core
    partition: str | None = None
    time_limit: float | None = None     # minutes per case; None: from the case size
    time_factor: float = 3.0
    max_concurrent: int = 16


@dataclass(frozen=True)
class SeedRule:
    """[seeds]: sequential seeds (campaign.sequential). Every physical case runs seeds 1..start; after
    each round a case whose 95 % interval of `quantity` is wider than ± `halfwidth` [-] (absolute,
    half of hi − lo) gets `step` more seeds, up to `max` seeds."""

    start: int
    max: int
    step: int
    quantity: str
    halfwidth: float
    pair_seeds: tuple[int, ...] = ()    # [pairs] seeds: the soils' further seeds, always run


@dataclass(frozen=True)
class Group:
    name: str
    variables: tuple[str, ...]          # swept keys, e.g. ("profile.rt", "friction_ps", "gradation")
    description: str = ""


@dataclass(frozen=True)
class CampaignCase:
    """One case of the campaign: the Case, its group, role and the swept values that made it."""

    case: Case
    group: str
    role: str                           # "interface" | "box"
    values: tuple[tuple[str, object], ...] = ()
    pair: int | None = None             # index (in Campaign.cases) of the paired box case


@dataclass(frozen=True)
class Campaign:
    name: str
    path: Path
    engines: tuple[str, ...]
    groups: tuple[Group, ...]
    cases: tuple[CampaignCase, ...]
    output: Path
    execution: Execution = field(default_factory=Execution)
    description: str = ""
    specimen_from: str | None = None    # the engine whose consolidated specimens the others shear
    seeds: SeedRule | None = None       # [seeds]: sequential seeds (campaign.sequential); None: as swept
    stated: tuple[str, ...] = ()        # Case fields the file states ([case], groups, sweeps, zips)
    output_from: str = ""               # where `output` came from, said with it (the runs folder)
    size: int = 0                       # cases of the sweeps' products (before box tests), counted
    lazy: bool = False                  # more than EAGER_MAX: `cases` is empty, see iter_cases()
    _spec: object = field(default=None, compare=False, repr=False)

    def warnings(self) -> list[str]:
        """Implausible values and unstated converged settings (interphase.campaign.checks), one line
        each: what `campaign run`, its dry run and `campaign status` print before anything else."""
        from interphase.campaign.checks import default_notes, input_warnings

        cases = list(self._spec.checked) if self._spec is not None else [c.case for c in self.cases]
        notes = list(getattr(self._spec.ctx, "notes", [])) if self._spec is not None else []
        shear = any(not c.cell for c in cases)
        return notes + input_warnings(cases) + (default_notes(self.stated) if shear else [])

    @property
    def pairs(self) -> list[tuple[int, int]]:
        """(interface case index, box case index) for every interface case with a paired box test."""
        return [(i, c.pair) for i, c in enumerate(self.cases) if c.pair is not None]


# ---- locating keys in the TOML text ---------------------------------------------------------
_HEADER = re.compile(r"^\s*(\[\[?)\s*([^\]]+?)\s*\]\]?\s*(#.*)?$")
_KEYLINE = re.compile(r"^\s*((?:[A-Za-z0-9_-]+|\"[^\"]*\"|'[^']*')(?:\s*\.\s*(?:[A-Za-z0-9_-]+|\"[^\"]*\"|'[^']*'))*)\s*=")


def _split_key(text: str) -> tuple[str, ...]:
    parts = re.findall(r"\"[^\"]*\"|'[^']*'|[A-Za-z0-9_-]+", text)
    return tuple(p.strip("\"'") for p in parts)


class Locator:
    """Line numbers of TOML keys by path, e.g. ("group", 0, "sweep", "profile", "rt") (array index as int).

    tomllib keeps no positions, so this scans the text: table headers, array-of-table counters and
    `key =` lines. Inline tables resolve to the line of their key (the best a person can use)."""

    def __init__(self, text: str):
        self.lines: dict[tuple, int] = {}
        table: tuple = ()
        counts: dict[tuple, int] = {}
        for no, line in enumerate(text.splitlines(), start=1):
            m = _HEADER.match(line)
            if m and not _KEYLINE.match(line):
                parts = _split_key(m.group(2))
                if m.group(1) == "[[":
                    counts[parts] = counts.get(parts, -1) + 1
                table = self._with_indices(parts, counts, array=m.group(1) == "[[")
                self.lines.setdefault(table, no)
                continue
            k = _KEYLINE.match(line)
            if k:
                self.lines.setdefault(table + _split_key(k.group(1)), no)

    @staticmethod
    def _with_indices(parts: tuple, counts: dict, array: bool) -> tuple:
        out: list = []
        for i in range(len(parts)):
            out.append(parts[i])
            prefix = parts[: i + 1]
            if prefix in counts:
                out.append(counts[prefix])
        return tuple(out)

    def line(self, path: tuple) -> int | None:
        """Line of `path`, or of its longest located prefix (the inline table or table holding it)."""
        for n in range(len(path), 0, -1):
            if path[:n] in self.lines:
                return self.lines[path[:n]]
        return None


def _dotted(path: tuple) -> str:
    return ".".join(str(p) if not isinstance(p, int) else f"[{p}]" for p in path).replace(".[", "[")


class _Ctx:
    """Builds located InputErrors for one file."""

    def __init__(self, path: Path, text: str):
        self.path = path
        self.loc = Locator(text)
        self.notes: list[str] = []          # said with the warnings (a --quick soil card)

    def error(self, path: tuple, message: str, fix: str | None = None) -> InputError:
        line = self.loc.line(path)
        where = f"{self.path}:{line}" if line else str(self.path)
        if path:
            where += f": {_dotted(path)}"
        return InputError(message, where=where, fix=fix)


def _did_you_mean(key: str, allowed) -> str:
    close = difflib.get_close_matches(key, list(allowed), n=1)
    hint = f"did you mean {close[0]!r}? " if close else ""
    return f"{hint}allowed keys: {', '.join(sorted(allowed))}"


def _check_keys(ctx: _Ctx, table: dict, allowed, path: tuple) -> None:
    for key in table:
        if key not in allowed:
            raise ctx.error(path + (key,), f"unknown key {key!r}", _did_you_mean(key, allowed))


def _type_name(v) -> str:
    return {str: "a string", bool: "a boolean", int: "an integer", float: "a number", list: "a list",
            dict: "a table"}.get(type(v), type(v).__name__)


# ---- loading --------------------------------------------------------------------------------
def load_campaign(path: str | os.PathLike, *, output: str | os.PathLike | None = None) -> Campaign:
    """Read and validate a campaign file; every case is built (and validated) here, nothing runs.

    `output` overrides the runs folder (else [campaign].output relative to the file, else runs/<name>
    beside the file; never the current directory). `Campaign.output_from` says which."""
    path = Path(path)
    ctx, data = _read_toml(path)
    meta = data.get("campaign", {})
    name, description = _name_and_description(ctx, meta, path)
    engines = _engines(ctx, meta)
    specimen_from = _specimen_from(ctx, meta, engines)
    base_dir = path.parent.resolve()
    out, output_from = _resolve_output(ctx, meta, name, path, output)
    execution = _execution(ctx, data.get("execution", {}))

    groups_raw = data.get("group")
    top_case = data.get("case", {})
    groups_spec = _group_specs(ctx, data, name, description)
    _check_case_keys(ctx, top_case, ("case",))
    seed_rule, groups_spec = _with_seed_rule(ctx, data, groups_raw, groups_spec)
    groups, gens = _groups_and_factors(ctx, top_case, groups_spec, base_dir)
    size = sum(math.prod(len(f) for f in factors) for _, _, factors, _ in gens)
    pairs = data.get("pairs", {})
    stated = set(top_case) | {k for g in groups_spec for k in g[2]} | {v.split(".")[0] for g in groups for v in g.variables}
    stated |= _card_fields(base_dir, [top_case, *(g[2] for g in groups_spec)])
    lazy = size > EAGER_MAX
    cases, checked = _load_cases(ctx, gens, base_dir, pairs, lazy)
    return Campaign(stated=tuple(sorted(stated)), name=name, path=path.resolve(), engines=engines,
                    groups=tuple(groups), cases=cases, size=size, lazy=lazy,
                    output=Path(os.path.abspath(out)), output_from=output_from, execution=execution,
                    description=description, specimen_from=specimen_from, seeds=seed_rule,
                    _spec=_Spec(ctx, tuple(gens), base_dir, pairs, tuple(c.case for c in checked)))


def _read_toml(path: Path) -> tuple[_Ctx, dict]:
    """(located context, parsed tables) of a campaign file; the top-level keys and their table
    types checked. An unreadable file or a TOML syntax error is an InputError naming the line."""
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise InputError(f"cannot read the campaign file ({exc.strerror})", where=str(path),
                         fix="give the path of an existing .toml file") from None
    text = raw.decode("utf-8", errors="replace")
    ctx = _Ctx(path, text)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"line (\d+)", str(exc))
        where = f"{path}:{m.group(1)}" if m else str(path)
        raise InputError(f"TOML syntax error: {exc}", where=where,
                         fix="see https://toml.io (strings need quotes, tables [name], lists [a, b])") from None
    _check_keys(ctx, data, TOP_KEYS, ())
    for key in ("campaign", "execution", "case", "sweep", "zip", "pairs", "seeds"):
        # [zip] may be one table or an array of them; every other key is one table
        if key in data and not isinstance(data[key], (dict, list) if key == "zip" else dict):
            raise ctx.error((key,), f"must be a table [{key}], got {_type_name(data[key])}")
    return ctx, data


def _name_and_description(ctx: _Ctx, meta: dict, path: Path) -> tuple[str, str]:
    """[campaign] name (folder-safe; default: the file's stem) and description, keys checked."""
    _check_keys(ctx, meta, CAMPAIGN_KEYS, ("campaign",))
    name = meta.get("name", path.stem)
    if not isinstance(name, str) or not NAME_RE.match(name):
        raise ctx.error(("campaign", "name"), f"campaign name must be a folder-safe string, got {name!r}",
                        "use letters, digits, '-', '_' and '.'")
    description = meta.get("description", "")
    if not isinstance(description, str):
        raise ctx.error(("campaign", "description"), f"must be a string, got {_type_name(description)}")
    return name, description


def _group_specs(ctx: _Ctx, data: dict, name: str, description: str) -> list[tuple]:
    """(name, description, case overrides, sweep, zips, TOML path) per group. Without [[group]] the
    file is one group named after the campaign; with it, top-level [sweep]/[zip] apply to every group."""
    groups_raw = data.get("group")
    if groups_raw is None:
        return [(name, description, {}, data.get("sweep", {}), _as_list(data.get("zip", [])), ())]
    if not isinstance(groups_raw, list) or not all(isinstance(g, dict) for g in groups_raw):
        raise ctx.error(("group",), "must be an array of tables [[group]]")
    if not groups_raw:
        raise ctx.error(("group",), "is empty", "add [[group]] tables or remove the key")
    groups_spec = []
    for gi, g in enumerate(groups_raw):
        gp = ("group", gi)
        _check_keys(ctx, g, GROUP_KEYS, gp)
        gname = g.get("name", str(gi + 1))
        if not isinstance(gname, str) or not NAME_RE.match(gname):
            raise ctx.error(gp + ("name",), f"group name must be a short string, got {gname!r}")
        gcase = g.get("case", {})
        if not isinstance(gcase, dict):
            raise ctx.error(gp + ("case",), "must be a table of Case fields")
        # a top-level [sweep]/[zip] applies to every group, before the group's own
        sweep = {**data.get("sweep", {}), **g.get("sweep", {})}
        zips = _as_list(data.get("zip", [])) + _as_list(g.get("zip", []))
        groups_spec.append((gname, g.get("description", ""), gcase, sweep, zips, gp))
    names = [g[0] for g in groups_spec]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise ctx.error(("group",), f"group name {sorted(dup)[0]!r} is used twice", "give every group its own name")
    return groups_spec


def _groups_and_factors(ctx: _Ctx, top_case: dict, groups_spec: list, base_dir: Path) -> tuple[list, list]:
    """(Groups, generators): per group its merged base case (with its soil card's fields) and the
    factors of its product, (group name, base case dict, factors, TOML path)."""
    groups: list[Group] = []
    gens: list[tuple] = []
    for gname, gdesc, gcase, sweep, zips, gpath in groups_spec:
        _check_case_keys(ctx, gcase, gpath + ("case",))
        base = _merge(top_case, gcase)
        factors, variables = _factors(ctx, sweep, zips, gpath)
        if "soil" in base:
            where = gpath + ("case", "soil") if "soil" in gcase else ("case", "soil")
            base = _with_soil(ctx, base, base_dir, where, variables)
        groups.append(Group(gname, tuple(variables), gdesc if isinstance(gdesc, str) else ""))
        gens.append((gname, base, factors, gpath))
    return groups, gens


def _load_cases(ctx: _Ctx, gens: list, base_dir: Path, pairs: dict, lazy: bool) -> tuple[tuple, list]:
    """(the campaign's cases with their box tests, the cases built to check them). A lazy campaign
    keeps no cases: it checks one case per swept value instead."""
    if lazy:
        # every swept value is built once, with the other factors at their first value: a bad value
        # is refused now, at load, without building the product (combinations are built as planned)
        checked = [c for c in _value_cases(ctx, gens, base_dir)]
        _pair_options(ctx, pairs, any(c.role == "interface" for c in checked))
        return (), checked
    seen: dict[str, tuple] = {}
    cases = tuple(_add_pairs(ctx, pairs, list(_iter_group_cases(ctx, gens, base_dir, seen)), seen))
    return cases, [c for c in cases]


def _seed_rule(ctx: _Ctx, table: dict, pairs: dict) -> SeedRule:
    """[seeds] → SeedRule, every key checked (file, line and field in every message)."""
    p = ("seeds",)
    _check_keys(ctx, table, SEEDS_KEYS, p)
    for key in ("start", "max", "target"):
        if key not in table:
            raise ctx.error(p, f"[seeds] needs {key}", "e.g. start = 3, max = 12, step = 1, "
                            'target = {quantity = "E", halfwidth = 0.05}')
    n = {}
    from interphase.analysis.ensemble import MIN_SEEDS

    for key, low in (("start", MIN_SEEDS), ("max", MIN_SEEDS), ("step", 1)):
        v = table.get(key, 1)
        if isinstance(v, bool) or not isinstance(v, int) or v < low:
            raise ctx.error(p + (key,), f"must be an integer ≥ {low}, got {v!r}",
                            f"no interval is computed below {MIN_SEEDS} seeds (docs/methods.md)" if low > 1 else None)
        n[key] = v
    if n["start"] > n["max"]:
        raise ctx.error(p + ("start",), f"start = {n['start']} is more than max = {n['max']}",
                        "start is the seeds every case runs first, max the cap: start ≤ max")
    target = table["target"]
    if not isinstance(target, dict):
        raise ctx.error(p + ("target",), f"must be a table, got {_type_name(target)}",
                        'e.g. target = {quantity = "E", halfwidth = 0.05}')
    _check_keys(ctx, target, TARGET_KEYS, p + ("target",))
    q = target.get("quantity")
    if q not in SEED_QUANTITIES:
        raise ctx.error(p + ("target", "quantity"), f"unknown quantity {q!r}",
                        _did_you_mean(str(q), SEED_QUANTITIES).replace("allowed keys", "allowed"))
    h = target.get("halfwidth")
    if isinstance(h, bool) or not isinstance(h, (int, float)) or not math.isfinite(h) or h <= 0:
        raise ctx.error(p + ("target", "halfwidth"), f"must be a number > 0 (half the 95 % interval's width, "
                        f"in the quantity's own units), got {h!r}", "e.g. halfwidth = 0.05")
    if q.startswith("E") and isinstance(pairs, dict) and pairs.get("box", True) is False:
        raise ctx.error(p + ("target", "quantity"), f"{q} needs the paired box tests, and [pairs] box = false",
                        'target tan_delta instead, or remove box = false')
    extra = pairs.get("seeds", []) if isinstance(pairs, dict) else []
    extra = tuple(x for x in extra if isinstance(x, int)) if isinstance(extra, list) else ()
    return SeedRule(n["start"], n["max"], n["step"], q, float(h), extra)


def _with_seed_rule(ctx: _Ctx, data: dict, groups_raw, groups_spec: list) -> tuple:
    """(SeedRule or None, the groups with `seed = [1..max]` swept last when the file has [seeds])."""
    if "seeds" not in data:
        return None, groups_spec
    rule = _seed_rule(ctx, data["seeds"], data.get("pairs", {}))
    _no_seed_sweep(ctx, data, groups_raw)
    values = list(range(1, rule.max + 1))
    return rule, [(n, d, c, {**sw, "seed": values}, z, gp) for n, d, c, sw, z, gp in groups_spec]


def _no_seed_sweep(ctx: _Ctx, data: dict, groups_raw) -> None:
    """[seeds] replaces the seed sweep: a seed set anywhere else is an error naming both."""
    places = [("case",), ("sweep",)] + [("zip",)] * isinstance(data.get("zip"), dict)
    tables = [(pl, data.get(pl[0], {})) for pl in places]
    if isinstance(data.get("zip"), list):
        tables += [(("zip", i), z) for i, z in enumerate(data["zip"])]
    for gi, g in enumerate(groups_raw if isinstance(groups_raw, list) else []):
        for key in ("case", "sweep", "zip"):
            if isinstance(g.get(key), dict):
                tables.append((("group", gi, key), g[key]))
    for path, table in tables:
        if isinstance(table, dict) and "seed" in table:
            line = ctx.loc.line(("seeds",))
            raise ctx.error(path + ("seed",), f"the seed is set here and by [seeds] (line {line}): [seeds] "
                            "runs seeds 1, 2, … itself", "remove one: the seed sweep, or the [seeds] table")


#: above this many cases (the product of the sweeps, before box tests) a campaign is planned lazily:
#: `Campaign.cases` stays empty and `iter_cases()` / `campaign.plan.iter_plan` build cases one at a
#: time (10⁶ cases: BENCHMARKS.md)
EAGER_MAX = 20_000


@dataclass(frozen=True)
class _Spec:
    """What a lazy campaign builds its cases from (the located file, its groups' factors)."""

    ctx: object
    gens: tuple
    base_dir: Path
    pairs: dict
    checked: tuple          # the Cases built at load (all of them, or one per swept value when lazy)


def _iter_group_cases(ctx: _Ctx, gens, base_dir: Path, seen: dict | set):
    """Every case of the groups' products, in file order; refuses a duplicate (`seen`: canonical
    JSON → (group, values) when a dict; a set of digests when lazy, to bound memory)."""
    import hashlib

    for gname, base, factors, gpath in gens:
        for combo in itertools.product(*factors) if factors else [()]:
            values: list[tuple[str, object, tuple]] = [kv for part in combo for kv in part]
            data_case = copy.deepcopy(base)
            for key, value, _ in values:
                _assign(ctx, data_case, key, value, gpath)
            case = _build_case(ctx, data_case, base_dir, values, gpath)
            key = canonical_json(case.canonical())
            mark = key if isinstance(seen, dict) else hashlib.blake2b(key.encode(), digest_size=16).digest()
            if mark in seen:
                prev_g, prev_vals = seen[mark] if isinstance(seen, dict) else ("?", "an earlier case")
                first = values[0][2] if values else gpath + ("case",)
                shown = ", ".join(f"{k} = {v!r}" for k, v, _ in values) or "(no sweep)"
                raise ctx.error(first, f"duplicate case: {shown} gives the same case as group {prev_g!r} "
                                f"with {prev_vals or '(no sweep)'}",
                                "remove repeated values from the sweep (case identity ignores 'name')")
            if isinstance(seen, dict):
                seen[mark] = (gname, ", ".join(f"{k} = {v!r}" for k, v, _ in values))
            else:
                seen.add(mark)
            role = "interface" if case.test == "interface" else "box"
            yield CampaignCase(case, gname, role, tuple((k, _freeze(v)) for k, v, _ in values))


def _value_cases(ctx: _Ctx, gens, base_dir: Path):
    """One case per swept value (the other factors at their first value): load-time checks of a
    lazy campaign."""
    for gname, base, factors, gpath in gens:
        for i, factor in enumerate(factors):
            for choice in factor:
                combo = [f[0] for f in factors[:i]] + [choice] + [f[0] for f in factors[i + 1:]]
                values = [kv for part in combo for kv in part]
                data_case = copy.deepcopy(base)
                for key, value, _ in values:
                    _assign(ctx, data_case, key, value, gpath)
                case = _build_case(ctx, data_case, base_dir, values, gpath)
                yield CampaignCase(case, gname, "interface" if case.test == "interface" else "box")


def iter_cases(campaign: "Campaign"):
    """(CampaignCase, its paired box CampaignCase or None, the box tests first seen here) one
    interface case at a time, in file order: a lazy campaign's cases without holding them all.
    Box tests come before the first interface case that needs them, each soil's once (with its
    [pairs] seeds after it)."""
    spec = campaign._spec
    want, overrides, seeds = _pair_options(spec.ctx, spec.pairs, True)
    boxes: dict[str, CampaignCase] = {}
    for c in _iter_group_cases(spec.ctx, spec.gens, spec.base_dir, set()):
        if c.role == "box":
            key = canonical_json(c.case.canonical())
            new = [] if key in boxes else [c]
            boxes.setdefault(key, c)
            yield None, None, new
            continue
        if not want:
            yield c, None, []
            continue
        box = _box_of(spec.ctx, c, overrides)
        key = canonical_json(box.case.canonical())
        new = []
        if key not in boxes:
            boxes[key] = box
            new.append(box)
            for seed in seeds:
                extra = box.case.replace(seed=seed)
                k2 = canonical_json(extra.canonical())
                if k2 not in boxes:
                    boxes[k2] = CampaignCase(extra, "box", "box", box.values)
                    new.append(boxes[k2])
        yield c, boxes[key], new


def _resolve_output(ctx: _Ctx, meta: dict, name: str, path: Path, output) -> tuple[Path, str]:
    """(runs folder, where it came from): `output` (--runs), else [campaign] output relative to the
    campaign file, else runs/<name> beside the file. Never the current directory."""
    base_dir = path.parent.resolve()
    if output is not None:
        out = Path(output)
        output_from = "given on the command line (--runs)"
    elif "output" in meta:
        if not isinstance(meta["output"], str) or not meta["output"]:
            raise ctx.error(("campaign", "output"), "must be a folder path (string)")
        out = Path(meta["output"])
        out = out if out.is_absolute() else base_dir / out
        line = ctx.loc.line(("campaign", "output"))
        output_from = f"[campaign] output of {path}" + (f":{line}" if line else "")
    else:
        # beside the campaign file, wherever the command is run from (it used to be the current
        # folder's ./runs/<name>: `status` from elsewhere found nothing and said "pending")
        out = base_dir / "runs" / name
        output_from = f"the default runs/{name} beside {path.name} ([campaign] output or --runs to change)"
    return Path(os.path.abspath(out)), output_from


def campaign_output(path, output=None) -> tuple[Path, str]:
    """(runs folder, where it came from) of a campaign file, from its [campaign] table alone (no
    case is built): what a command that reads runs says it read."""
    path = Path(path)
    try:
        text = path.read_text()
        meta = tomllib.loads(text).get("campaign", {})
    except (OSError, tomllib.TOMLDecodeError):
        raise InputError("cannot read the campaign file", where=str(path)) from None
    name = meta.get("name", path.stem) if isinstance(meta, dict) else path.stem
    return _resolve_output(_Ctx(path, text), meta if isinstance(meta, dict) else {}, str(name), path, output)


def _as_list(z) -> list:
    return z if isinstance(z, list) else [z]


def _freeze(v):
    if isinstance(v, dict):
        return tuple(sorted((k, _freeze(x)) for k, x in v.items()))
    if isinstance(v, list):
        return tuple(_freeze(x) for x in v)
    return v


def _merge(a: dict, b: dict) -> dict:
    out = copy.deepcopy(a)
    for k, v in b.items():
        if k == "profile" and isinstance(v, dict) and isinstance(out.get(k), dict) and "kind" not in v:
            out[k] = {**out[k], **v}        # group overrides some profile parameters only
        else:
            out[k] = copy.deepcopy(v)
    return out


def _engines(ctx: _Ctx, meta: dict) -> tuple[str, ...]:
    if "engine" in meta and "engines" in meta:
        raise ctx.error(("campaign", "engine"), "give either engine or engines, not both")
    key = "engines" if "engines" in meta else "engine"
    value = meta.get(key, ["liggghts"])
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, list) or not value or not all(isinstance(v, str) for v in value):
        raise ctx.error(("campaign", key), f"must be an engine name or a non-empty list of them, got {value!r}",
                        f"allowed: {', '.join(ENGINES)}")
    for v in value:
        if v not in ENGINES:
            close = difflib.get_close_matches(v, ENGINES, n=1)
            raise ctx.error(("campaign", key), f"unknown engine {v!r}",
                            (f"did you mean {close[0]!r}? " if close else "") + f"allowed: {', '.join(ENGINES)}")
    if len(set(value)) != len(value):
        raise ctx.error(("campaign", key), "an engine is listed twice")
    return tuple(value)


def _specimen_from(ctx: _Ctx, meta: dict, engines: tuple[str, ...]) -> str | None:
    value = meta.get("specimen_from")
    if value is None:
        return None
    if value not in engines:
        raise ctx.error(("campaign", "specimen_from"), f"must be one of the campaign's engines "
                        f"({', '.join(engines)}), got {value!r}", f'e.g. specimen_from = "{engines[0]}"')
    if len(engines) < 2:
        raise ctx.error(("campaign", "specimen_from"), "needs a second engine to shear the specimens",
                        'engines = ["liggghts", "yade"], or remove specimen_from')
    return value


def _execution(ctx: _Ctx, ex: dict) -> Execution:
    p = ("execution",)
    _check_keys(ctx, ex, EXECUTION_KEYS, p)
    executor = ex.get("executor", "local")
    if executor not in EXECUTORS:
        raise ctx.error(p + ("executor",), f"unknown executor {executor!r}", f"allowed: {', '.join(EXECUTORS)}")
    jobs = ex.get("jobs", 0)
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 0:
        raise ctx.error(p + ("jobs",), f"must be an integer ≥ 0 (0 = one per core), got {jobs!r}")
    part = ex.get("partition")
    if part is not None and (not isinstance(part, str) or not NAME_RE.match(part)):
        raise ctx.error(p + ("partition",), f"must be a SLURM partition name, got {part!r}")
    tl = ex.get("time_limit", "auto")
    if tl == "auto":
        tl = None
    elif isinstance(tl, bool) or not isinstance(tl, (int, float)) or not math.isfinite(tl) or tl <= 0:
        raise ctx.error(p + ("time_limit",), f"must be minutes > 0 or \"auto\", got {tl!r}")
    tf = ex.get("time_factor", 3.0)
    if isinstance(tf, bool) or not isinstance(tf, (int, float)) or not math.isfinite(tf) or tf < 1:
        raise ctx.error(p + ("time_factor",), f"must be a number ≥ 1, got {tf!r}")
    mc = ex.get("max_concurrent", 16)
    if isinstance(mc, bool) or not isinstance(mc, int) or mc < 1:
        raise ctx.error(p + ("max_concurrent",), f"must be an integer ≥ 1, got {mc!r}")
    return Execution(executor, jobs, part, None if tl is None else float(tl), float(tf), mc)


def _with_soil(ctx: _Ctx, base: dict, base_dir: Path, where: tuple, variables) -> dict:
    """[case] soil = "soils/NAME.toml": the card's soil fields fill the case (interphase.soil); a
    field set in the campaign as well, as a constant or swept, is an error naming both places."""
    from interphase.soil import load_card, merge_soil

    base = dict(base)
    ref = base.pop("soil")
    if not isinstance(ref, str) or not ref:
        raise ctx.error(where, f"soil must be the path of a soil card, got {ref!r}", 'e.g. soil = "soils/ottawa-20-30.toml"')
    path = Path(ref) if Path(ref).is_absolute() else base_dir / ref
    try:
        card = load_card(path)
    except InputError as exc:
        raise ctx.error(where, f"the soil card: {exc}", None) from None
    if card.quick and not any(str(card.path) in n for n in ctx.notes):
        ctx.notes.append(f"the soil card {card.path} is a --quick calibration: a first look, not a calibrated soil")
    for v in variables:
        if v.split(".")[0] in card.soil:
            raise ctx.error(where, f"{v!r} is swept here and set in the soil card {card.path}",
                            "remove it from the sweep (the card's soil is calibrated as a whole), or drop `soil`")
    try:
        return merge_soil(base, card, where="")
    except InputError as exc:
        raise ctx.error(where, exc.message, exc.fix) from None


def _card_fields(base_dir: Path, tables) -> set[str]:
    """The Case fields that the soil cards named in `tables` ([case] tables) state: a card states
    them as surely as the file would (already checked by _with_soil, so a card that fails is skipped)."""
    from interphase.soil import load_card

    out = set()
    for table in tables:
        ref = table.get("soil") if isinstance(table, dict) else None
        if isinstance(ref, str) and ref:
            try:
                out |= set(load_card(Path(ref) if Path(ref).is_absolute() else base_dir / ref).soil)
            except InputError:
                pass
    return out


def _check_case_keys(ctx: _Ctx, table: dict, path: tuple) -> None:
    for key in table:
        if key == "soil":
            continue
        if key in PLANNED_FIELDS:
            raise ctx.error(path + (key,), f"{key!r} is not set in a case table", PLANNED_FIELDS[key])
        if key not in CASE_FIELDS:
            raise ctx.error(path + (key,), f"unknown case field {key!r}", _did_you_mean(key, CASE_FIELDS))


def _flatten_sweep(table: dict, prefix: tuple = ()) -> list[tuple[tuple, object]]:
    """[sweep] entries as (key path, list); `profile.rt = [...]` arrives as {"profile": {"rt": [...]}}."""
    out = []
    for k, v in table.items():
        if isinstance(v, dict):
            out.extend(_flatten_sweep(v, prefix + (k,)))
        else:
            out.append((prefix + (k,), v))
    return out


def _check_var(ctx: _Ctx, key: tuple, where: tuple) -> str:
    name = ".".join(key)
    if key[0] not in CASE_FIELDS:
        raise ctx.error(where, f"unknown case field {key[0]!r}", _did_you_mean(key[0], CASE_FIELDS))
    if len(key) > 1 and key[0] != "profile" or len(key) > 2:
        raise ctx.error(where, f"{name!r} cannot be swept by parts", "only profile parameters take dotted keys "
                        "(profile.rt, profile.sw, profile.sr, profile.au, profile.ar, profile.rtmax, profile.seed, "
                        "profile.path)")
    return name


def _factors(ctx: _Ctx, sweep: dict, zips: list, gpath: tuple):
    """The product's factors: each a list of choices, a choice = [(key, value, toml path), ...]."""
    factors, variables = [], []
    sp = gpath + ("sweep",) if gpath else ("sweep",)
    if not isinstance(sweep, dict):
        raise ctx.error(sp, "must be a table of lists")
    for key, values in _flatten_sweep(sweep):
        where = sp + key
        name = _check_var(ctx, key, where)
        if not isinstance(values, list):
            raise ctx.error(where, f"a sweep needs a list of values, got {_type_name(values)}",
                            f"write {name} = [{values!r}] or move it to [case]")
        if not values:
            raise ctx.error(where, "empty sweep: no value to run", "give at least one value, or remove the key")
        factors.append([[(name, v, where)] for v in values])
        variables.append(name)
    for z in zips:
        zp = (gpath + ("zip",) if gpath else ("zip",))
        if not isinstance(z, dict):
            raise ctx.error(zp, "must be a table of equal-length lists")
        entries = _flatten_sweep(z)
        if not entries:
            continue
        lengths = {}
        for key, values in entries:
            where = zp + key
            name = _check_var(ctx, key, where)
            if not isinstance(values, list) or not values:
                raise ctx.error(where, "a zip needs a non-empty list of values", f"write {name} = [v1, v2, ...]")
            lengths[name] = (len(values), where)
        ns = {n for n, _ in lengths.values()}
        if len(ns) > 1:
            (k1, (n1, _)), (k2, (n2, w2)) = sorted(lengths.items(), key=lambda kv: kv[1][0])[:1] + \
                sorted(lengths.items(), key=lambda kv: -kv[1][0])[:1]
            raise ctx.error(w2, f"zipped lists differ in length: {k2} has {n2} values, {k1} has {n1}",
                            "lists in one [zip] are taken together and need one length")
        n = ns.pop()
        factors.append([[(".".join(k), v[i], zp + k) for k, v in entries] for i in range(n)])
        variables.extend(".".join(k) for k, _ in entries)
    return factors, variables


def _assign(ctx: _Ctx, data: dict, key: str, value, gpath: tuple) -> None:
    if "." in key:
        field_, param = key.split(".", 1)
        prof = data.get(field_)
        if not isinstance(prof, dict):
            raise ctx.error((gpath + ("case",) if gpath else ("case",)) + ("profile",),
                            f"sweeping {key!r} needs a profile table in [case]",
                            "e.g. profile = {kind = \"sawtooth\", rt = 1, sw = 2, sr = 0}")
        data[field_] = {**prof, param: value}
    else:
        data[key] = value


_FIELD_IN_MSG = re.compile(r"\bcase\.([a-z_0-9]+)(?:\.([a-z_0-9]+))?")
_UNKNOWN_IN_MSG = re.compile(r"unknown (?:key|parameter) '([^']+)'")


def _build_case(ctx: _Ctx, data: dict, base_dir: Path, values, gpath: tuple) -> Case:
    """case_from_dict, with its message re-anchored at the TOML line that supplied the bad field."""
    from interphase.campaign.checks import input_errors

    try:
        case = case_from_dict(data, where="case", base_dir=base_dir)
        input_errors([case], where="case")
        return case
    except InputError as exc:
        msg = str(exc)
        m = _FIELD_IN_MSG.search(msg)
        field_ = m.group(1) if m else None
        sub = m.group(2) if m else None
        u = _UNKNOWN_IN_MSG.search(msg)
        if field_ == "profile" and u and not sub:
            sub = u.group(1)
        # the swept value that set this field, else the constant tables
        path = None
        for key, _, where in values:
            if field_ and (key == field_ or key == f"{field_}.{sub}" or key.startswith(f"{field_}.")):
                path = where
                break
        if path is None and field_:
            for tbl in ((gpath + ("case",)) if gpath else None, ("case",)):
                if tbl and ctx.loc.line(tbl + (field_,)) and (tbl + (field_,)) in ctx.loc.lines:
                    path = tbl + (field_,) + ((sub,) if sub else ())
                    break
        if path is None:
            path = ("case",) + ((field_,) if field_ else ())
        shown = ", ".join(f"{k} = {v!r}" for k, v, _ in values)
        detail = msg.split(": ", 1)[1] if msg.startswith("case") and ": " in msg else msg
        text = detail + (f" (in the case with {shown})" if shown else "")
        raise ctx.error(path, text, None) from None


def _add_pairs(ctx: _Ctx, pairs: dict, cases: list[CampaignCase], seen: dict) -> list[CampaignCase]:
    """One direct shear box case per distinct soil (every Case field but the surface), for E.

    The box case keeps the soil, stiffness, stress, speed and seed of the interface case; its walls
    (both halves) take the particle–boundary friction friction_pw, so friction_ps := friction_pw
    (the study's box has no rough surface). [pairs].case overrides box-only settings."""
    want, overrides, seeds = _pair_options(ctx, pairs, any(c.role == "interface" for c in cases))
    if not want:
        return cases
    out = list(cases)
    index: dict[str, int] = {}
    for i, c in enumerate(cases):
        if c.role == "box":
            index.setdefault(canonical_json(c.case.canonical()), i)
    for i, c in enumerate(cases):
        if c.role != "interface":
            continue
        box = _box_of(ctx, c, overrides).case
        key = canonical_json(box.canonical())
        if key not in index:
            index[key] = len(out)
            out.append(CampaignCase(box, "box", "box", (("pair_of", c.group),)))
        out[i] = CampaignCase(c.case, c.group, c.role, c.values, index[key])
    for j in range(len(out)):               # the soils' further seeds, after every paired test
        b = out[j]
        if b.role != "box" or j < len(cases):
            continue
        for seed in seeds:
            extra = b.case.replace(seed=seed)
            key = canonical_json(extra.canonical())
            if key not in index:
                index[key] = len(out)
                out.append(CampaignCase(extra, "box", "box", b.values))
    return out


def _pair_options(ctx: _Ctx, pairs: dict, has_interface: bool) -> tuple[bool, dict, list]:
    """([pairs] box, case overrides, seeds), checked."""
    _check_keys(ctx, pairs, PAIR_KEYS, ("pairs",))
    want = pairs.get("box", has_interface)
    if not isinstance(want, bool):
        raise ctx.error(("pairs", "box"), f"must be true or false, got {want!r}")
    overrides = pairs.get("case", {})
    if not isinstance(overrides, dict):
        raise ctx.error(("pairs", "case"), "must be a table of Case fields")
    _check_case_keys(ctx, overrides, ("pairs", "case"))
    for bad in ("test", "profile", "profile_y", "friction_ps"):
        if bad in overrides:
            raise ctx.error(("pairs", "case", bad), f"{bad} of a paired box test is set by the campaign",
                            "remove it (box tests have no surface)")
    seeds = pairs.get("seeds", [])
    if (not isinstance(seeds, list) or not all(isinstance(x, int) and not isinstance(x, bool) and x >= 1
                                                for x in seeds) or len(set(seeds)) != len(seeds)):
        raise ctx.error(("pairs", "seeds"), f"must be a list of distinct packing seeds (integers ≥ 1), got {seeds!r}",
                        "e.g. seeds = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10]")
    return want, overrides, seeds


def _box_of(ctx: _Ctx, c: CampaignCase, overrides: dict) -> CampaignCase:
    """The paired box test of interface case `c`: its soil (every field but the surface), walls at
    friction_pw, [pairs].case overrides."""
    data = {k: v for k, v in c.case.canonical().items() if k not in ("profile", "profile_y", "test", "friction_ps")}
    data.update(test="box", friction_ps=c.case.friction_pw, **overrides)
    data = {k: v for k, v in data.items() if v is not None}
    try:
        box = case_from_dict(data, where="pairs.case")
    except InputError as exc:
        raise ctx.error(("pairs", "case"), str(exc).split(": ", 1)[-1]) from None
    return CampaignCase(box, "box", "box", (("pair_of", c.group),))
