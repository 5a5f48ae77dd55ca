"""The void ratios a soil card's grains reach by the cell's preparation (`campaign density CARD`):
the model's own e_min and e_max, so that a relative density means for the model what it means for
the laboratory (docs/soils.md, "Density by relative density").

Protocol: the card's cell test (engines/cell.py: isotropic consolidation of a loose lattice with the
grain–grain sliding and rolling friction scaled by the preparation), at REFERENCE_STRESS, for each of
PREPARATIONS, on the seeds given; e is each run's void ratio at the start of its (token) axial
compression, averaged over the seeds. e_min = e at preparation 0 (frictionless grains: the densest
packing the protocol makes), e_max = e at preparation 1 (the grains' own friction). A
preparation above 1 is outside these limits: it packed looser on 50 MPa grains and denser on the
3D Karlsruhe card's 500 MPa ones (docs/soils.md, "Looser than the loosest").
These are the model's index void ratios: the laboratory's are measured at next to no stress and its Dr0
is read on them after consolidation, so a relative density is one void ratio at every stress. The
map e(preparation) measured at the stress a test is consolidated to is what `preparation_at` inverts
at that void ratio.

The result is appended to the card as its [density] table; a card that has one keeps it (nothing
measured is overwritten: delete the table to measure again).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import tomli_w

from interphase.campaign.element import CELL_SERIES, run_cases, write_campaign
from interphase.soil import SoilCard

PREPARATIONS = (0.0, 0.25, 0.5, 0.75, 1.0)
REFERENCE_STRESS = 10e3        # [Pa]
TOKEN_STRAIN = 0.002           # [-] the axial compression these runs need only to record their start
MAP_SEEDS = 2                  # seeds of a void-ratio map at a test's stress (the first of the test's own)
REFINE = 2                     # points a map at a test's stress may gain where it is read
E_TOL = 0.003                  # [-] a map point this close to the target e ends the refinement (Dr ~0.01 on
                               # the Karlsruhe card's span at 200 kPa)


def density_runs(card: SoilCard, runs=None):
    """(folder, where the rule came from): --runs, else runs/density/NAME beside the card."""
    from interphase.campaign.folders import beside, given

    return given(runs, "--runs") if runs is not None else beside(card.path, f"runs/density/{card.name}", "--runs")


def measure_density(card: SoilCard, seeds, *, output: Path | None = None, executor=None, jobs=None,
                    stream=None, rerun_failed: bool = False) -> dict:
    seeds = [int(s) for s in seeds]
    output = density_runs(card, output)[0]
    prep, e = void_ratio_map(card, REFERENCE_STRESS, seeds, output=output, executor=executor, jobs=jobs,
                             stream=stream, rerun_failed=rerun_failed)
    e_min, e_max = limits_of(prep, e)
    e = [float(v) for v in e]
    table = {"reference_stress": REFERENCE_STRESS, "seeds": len(seeds), "n_grains": int(card.cell["n_grains"]),
             "preparations": prep, "void_ratios": [round(v, 5) for v in e],
             "e_min": round(e_min, 5), "e_max": round(e_max, 5),
             "method": "campaign density: isotropic consolidation of the card's cell at the reference stress, grain "
                       "friction scaled by the preparation; e at the start of the axial compression, seed mean"}
    written = _append(card, table)
    return {"card": str(card.path), "written": written, **table}


def preparation_at(card: SoilCard, relative_density: float | None, stress: float, seeds, *, test: str | None = None,
                   output: Path, executor=None, jobs=None, stream=None,
                   rerun_failed: bool = False) -> tuple[float | None, tuple[float, float]]:
    """(preparation, (e_min, e_max)) at `stress` [Pa]. The limits are the model's index void ratios
    (`read_limits`: the protocol's densest and loosest packings at REFERENCE_STRESS) read on the
    card's density scale (`lab_limits`); the preparation is the one whose specimen, consolidated to
    `stress`, has e = e_max − Dr (e_max − e_min): the map e(preparation) measured at `stress` (token
    compressions at PREPARATIONS on the first MAP_SEEDS of `seeds`; resumable) inverted there; None
    without a relative density. So a Dr is one void ratio after consolidation at every stress, as the
    laboratory's Dr0 is (its index tests at next to no stress, e0 after consolidation). Limits read at
    the test's stress instead drift denser with it (the 3D Karlsruhe card's grains: both limits fall
    ~0.04 in e from 50 to 400 kPa), and that drift offset the spheres' own loss of strength with stress
    (docs/soils.md, "Why the card did not weaken with stress"). A card whose grains compress far more
    than the sand (overlap that is not a denser fabric) reads them at the test's stress instead
    ([density] dr_limits = "test", SoilCard.dr_limits).

    The map is refined where it is read: e(preparation) is steep and curved near 0, where every Dr
    above ~0.55 lies (Karlsruhe card at 200 kPa: e 0.417 at 0, 0.454 at 0.061, 0.474 at 0.117, 0.521
    at 0.25), so a straight segment between the coarse points picks preparations that pack looser
    than asked (Dr 0.03-0.05 less, measured). Up to REFINE times, the preparation read off the map is
    measured itself (the same token runs) and the map read again, until that point's e is within
    E_TOL of the target. Points an earlier call measured in `output` stay on the map
    (`void_ratio_map`), and the preparation picked for a Dr (on the card's scale) is recorded
    beside the map (`_Picks`) and returned as it is by every later call on that map: on a noisy map
    each refinement moves the inverse a little (150 grains at 100 kPa: 0.1102, 0.1163, 0.1115, 0.1105,
    0.1104 in turn), and a Dr read again must not make new specimens and rerun the seeds already
    sheared on the first. A target looser than the map's loosest point at `stress` is made at
    preparation 1 and reported at the Dr it reached."""
    from interphase.errors import InputError

    if relative_density is not None and not 0 <= relative_density <= 1:
        raise InputError(f"relative density {relative_density!r} is not a fraction in [0, 1]",
                         where="--relative-density", fix="e.g. 0.81 for 81 %")
    kw = dict(test=test, output=output, executor=executor, jobs=jobs, stream=stream, rerun_failed=rerun_failed)
    seeds = list(seeds)[:MAP_SEEDS]
    # the map at the test's stress: the inversion needs it, and so do limits read there
    needed = relative_density is not None or card.dr_limits == "test"
    here = void_ratio_map(card, stress, seeds, **kw) if needed else None
    limits = lab_limits(*read_limits(card, seeds, here, **kw), card.lab_span, card.lab_offset)
    if relative_density is None:
        return None, limits
    prep, e = here
    picks = _Picks(*_map_file(card, stress, test, output, seeds), seeds)
    if (picked := picks.get(relative_density, limits)) is not None:
        return picked, limits
    target = limits[1] - relative_density * (limits[1] - limits[0])
    known = len(prep)
    for _ in range(REFINE + 1):
        _finished(e, stress, output)
        guess = invert_map(prep, e, target)
        if guess in prep or len(prep) >= known + REFINE or np.min(np.abs(e - target)) <= E_TOL:
            break
        prep, e = void_ratio_map(card, stress, seeds, also=[guess], **kw)
    picks.put(relative_density, limits, guess)
    return guess, limits


def read_limits(card: SoilCard, seeds, here=None, *, test=None, output: Path, executor=None, jobs=None,
                stream=None, rerun_failed: bool = False) -> tuple[float, float]:
    """The model's own (e_min, e_max) a relative density is read on (SoilCard.dr_limits): "index",
    the card's [density] table (`campaign density`, measured at REFERENCE_STRESS), else the same map
    measured in `output` on `seeds` (resumable); "test", the ends of `here`, the map (preparations,
    e) at the test's stress that the caller measured."""
    if card.dr_limits == "test":
        return limits_of(*here)
    table = card.extra.get("density", {})
    if "e_min" in table and "e_max" in table:
        return float(table["e_min"]), float(table["e_max"])
    prep, e = void_ratio_map(card, REFERENCE_STRESS, seeds, test=test, output=output, executor=executor, jobs=jobs,
                             stream=stream, rerun_failed=rerun_failed)
    _finished(e, REFERENCE_STRESS, output)
    return limits_of(prep, e)


def own_relative_density(card: SoilCard, stress: float, seeds, preparation: float, *, output: Path, executor=None,
                         jobs=None, stream=None, rerun_failed: bool = False) -> float:
    """The model's own Dr [-] (on the limits its card reads a Dr on, `read_limits`; no lab_span) of the
    specimen `preparation` makes when consolidated to `stress` [Pa]: the void-ratio map there with
    that point added (the same token runs `preparation_at` reads in `output`, so nothing runs twice)."""
    p = round(float(preparation), 4)
    seeds = list(seeds)[:MAP_SEEDS]
    kw = dict(output=output, executor=executor, jobs=jobs, stream=stream, rerun_failed=rerun_failed)
    prep, e = void_ratio_map(card, stress, seeds, also=[p], **kw)
    _finished(e, stress, output)
    e_min, e_max = read_limits(card, seeds, (prep, e), **kw)
    return float((e_max - e[prep.index(p)]) / (e_max - e_min))


def limits_of(prep, e) -> tuple[float, float]:
    """(e_min, e_max) of a void-ratio map: e at preparation 0 and at 1, the protocol's densest and its
    loosest at the grains' own friction, whatever else the map holds (a point at a preparation
    above 1 is read on these limits, never made one)."""
    prep = [float(p) for p in prep]
    return float(e[prep.index(0.0)]), float(e[prep.index(1.0)])


def _finished(e, stress: float, output: Path) -> None:
    """Refuse a void-ratio map with a run that did not finish, saying where to look."""
    from interphase.errors import InputError

    if not np.isfinite(e).all():
        raise InputError(f"the void-ratio map at {stress / 1e3:g} kPa has runs that did not finish",
                         where=str(output),
                         fix="see `campaign status` of the density campaign there; --rerun-failed runs them again")


def lab_limits(e_min: float, e_max: float, span: float, offset: float = 0.0) -> tuple[float, float]:
    """(e_min, e_max) that a laboratory Dr is read on, from the model's own (its densest and loosest
    packings): a laboratory Dr stands for the model's Dr = offset + span · Dr (SoilCard.lab_span and
    lab_offset: the spheres dilate more than the sand at the same Dr on their own limits, docs/soils.md
    "The density scale"), so Dr 1 is e_max − (offset + span)(e_max − e_min) and Dr 0 is
    e_max − offset (e_max − e_min). With offset 0 the model's loosest packing is the laboratory's."""
    d = e_max - e_min
    return e_max - (offset + span) * d, e_max - offset * d


def invert_map(prep, e, target: float) -> float:
    """The preparation in [0, 1] whose e is `target` on the map (prep ascending, e its seed means),
    rounded to 4 decimals (so that a case id is stable); a target outside the map's e gives its end
    (0, or 1: looser than the protocol packs). Seed noise can put two close points out of order (at
    200 kPa, e 0.5215 at preparation 0.2269 and 0.5209 at 0.25); a straight line is drawn through the
    running maximum of e instead, so that the target is always bracketed by neighbours in preparation.
    Points above 1 are not read: they lie outside the limits and do not continue the map (denser than
    1 on the 3D Karlsruhe card's grains)."""
    prep, e = np.asarray(prep, float), np.asarray(e, float)
    keep = prep <= 1.0
    prep, e = prep[keep], e[keep]
    o = np.argsort(prep, kind="stable")
    return round(float(np.interp(target, np.maximum.accumulate(e[o]), prep[o])), 4)


def void_ratio_map(card: SoilCard, stress: float, seeds, *, test=None, output: Path, executor=None, jobs=None,
                   stream=None, rerun_failed: bool = False, also=()) -> tuple[list, np.ndarray]:
    """(preparations ascending, seed-mean e at the start of a token compression at `stress` for each):
    PREPARATIONS (0 and 1 among them: the limits, `limits_of`), the preparations in `also`,
    and every point the map in `output` already holds for the same grains and seeds (a map only grows:
    a point measured once is never dropped); a preparation's runs have the same id in every map that
    holds it, so a finer map reruns nothing."""
    seeds = [int(s) for s in seeds]
    path, base = _map_file(card, stress, test, output, seeds)
    name = path.stem
    preparations = sorted({*PREPARATIONS, *(float(p) for p in also), *_mapped(path, base, seeds)})
    path = write_campaign(path, name=name, case=base, sweep={"preparation": preparations, "seed": seeds},
                          description=f"void ratio against preparation of the soil card {card.path}")
    planned, series, _ = run_cases(path, executor=executor, jobs=jobs, stream=stream, rerun_failed=rerun_failed,
                                   columns=CELL_SERIES)
    e = []
    for prep in preparations:
        vals = [float(series[p.case_id]["e"].iloc[0]) for p in planned
                if p.case.preparation == prep and p.case_id in series]
        e.append(float(np.mean(vals)) if vals else float("nan"))
    return preparations, np.asarray(e)


def _map_file(card: SoilCard, stress: float, test, output: Path, seeds) -> tuple[Path, dict]:
    """(the map's campaign file in `output`, the [case] its token runs share but for preparation and seed).

    The file is named by the grains and seeds as well as the card's name: a refit of a target writes a
    card of the same name into the same runs folder, and on one file per name each card's map (its
    refined points, its picks) would replace the other's, so a Dr read again on the first card would
    pick another preparation than its checks were run at. A map file named by the card alone is taken
    over when its grains and seeds are these."""
    import hashlib

    base = card.cell_case(stress, test=test, axial_strain=TOKEN_STRAIN)
    base.pop("preparation", None), base.pop("seed")
    seeds = [int(s) for s in seeds]
    canon = json.dumps({"case": _canonical(base), "seeds": seeds}, sort_keys=True)
    stem = f"density-{card.name}-{stress / 1e3:g}kPa"
    path = Path(output) / f"{stem}-{hashlib.sha256(canon.encode()).hexdigest()[:8]}.toml"
    legacy = Path(output) / f"{stem}.toml"
    if not path.exists() and _mapped(legacy, base, seeds):
        path.write_text(legacy.read_text())
        if (picks := legacy.with_suffix(".picks.json")).exists():
            path.with_suffix(".picks.json").write_text(picks.read_text())
    return path, base


def _canonical(case: dict) -> dict:
    """`case` as its TOML file gives it back (what `_mapped` compares)."""
    import tomllib

    return tomllib.loads(tomli_w.dumps({"case": case}))["case"]


class _Picks:
    """The preparation picked for each relative density on one map, in a JSON file beside the map's
    campaign file, keyed by the Dr and the limits it was read on (the index limits on the card's
    scale: together they fix the target e on the map); kept only while it belongs to the same grains
    and seeds (as `_mapped` keeps points)."""

    def __init__(self, map_path: Path, case: dict, seeds):
        self.path = map_path.with_suffix(".picks.json")
        self.key = {"case": json.loads(json.dumps(case)), "seeds": [int(s) for s in seeds]}
        data = json.loads(self.path.read_text()) if self.path.exists() else {}
        self.picks = data.get("picks", {}) if {k: data.get(k) for k in self.key} == self.key else {}

    @staticmethod
    def _key(relative_density: float, limits: tuple[float, float]) -> str:
        return f"Dr {relative_density:.6f} on e {limits[0]:.6f} to {limits[1]:.6f}"

    def get(self, relative_density: float, limits: tuple[float, float]) -> float | None:
        return self.picks.get(self._key(relative_density, limits))

    def put(self, relative_density: float, limits: tuple[float, float], preparation: float) -> None:
        self.picks[self._key(relative_density, limits)] = preparation
        self.path.write_text(json.dumps({**self.key, "picks": self.picks}, indent=1) + "\n")


def _mapped(path: Path, case: dict, seeds: list[int]) -> list[float]:
    """The preparations the map file at `path` already lists, if it is a map of the same case and
    seeds (another card, or other seeds, start a map of their own)."""
    import tomllib

    if not path.exists():
        return []
    data = tomllib.loads(path.read_text())
    sweep = data.get("sweep", {})
    if data.get("case") != _canonical(case) or sweep.get("seed") != seeds:
        return []
    return [float(p) for p in sweep.get("preparation", [])]


def _append(card: SoilCard, table: dict) -> bool:
    """Append [density] to the card unless it has one (or a value is missing); True if written."""
    if "density" in card.extra or not np.isfinite(table["void_ratios"]).all():
        return False
    text = card.path.read_text()
    block = tomli_w.dumps({"density": table})
    card.path.write_text(text.rstrip("\n") + "\n\n# the grains' own void-ratio limits (campaign density; docs/soils.md)\n"
                         + block)
    return True
