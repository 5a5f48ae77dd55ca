"""`campaign calibrate TARGET.toml` for a target that names laboratory triaxial records (`[target]
test = "triaxial"` or "biaxial"): grain parameters from the laboratory's own test, run on the model
in the cell (engines/cell.py), by the same GrainLearning filter as the direct-shear targets
(campaign/calibrate.py). The target (TOML; paths relative to the file):

    [target]
    name = "karlsruhe-fine-sand"
    test = "triaxial"                       # the cell test the card runs (biaxial: quasi-2D)
    record = "../../lab/soils/karlsruhe-fine-sand/drained-triaxial/TMD17.dat"   # the fitted test
    e_min = 0.677                           # the sand's index void ratios: the records' Dr = (e_max − e0)/(e_max − e_min)
    e_max = 1.054
    phi_cs_deg = 33.1                       # optional: the published critical-state angle, against the model's φ at the end
    source = "Wichtmann & Triantafyllidis (2016) ..., records and index properties"
    [soil]                                  # fixed grain fields
    [free]                                  # friction_pp, rolling_friction, preparation: [min, max]
    [cell]                                  # the card's cell (interphase.soil.CELL_DEFAULTS)
    [budget]                                # samples, iterations, seeds, final_seeds, ess_target, components
    [[verification]]                        # every other record of the soil: held out
    record = "../../lab/soils/karlsruhe-fine-sand/drained-triaxial/TMD18.dat"

Observations of a sample (its seeds together, analysis.cell_ensemble): φ_peak and ψ_max against the
record's own (analysis.triaxial on the record: the same code), and φ at the end against phi_cs_deg
when given (judged only where the model's volume has stopped changing: `_checks`). The record's Dr0
is not matched (CellTarget.values); each sample's Dr is recorded beside its angles, on its own
e_min (the frictionless preparation: the same for every sample, measured once) and e_max (the
loosest packing at the sample's own friction: one token consolidation per sample), both at the
record's stress. Likelihood spreads ∝ TOLERANCES.

After sampling: the card ([soil] = posterior mean, [cell], [density] measured for the chosen grains,
with the density scale lab_span, lab_offset that maps the record's Dr onto the fitted state,
`_lab_scale`), then the laboratory's test on it at the fitted record and at every held-out one, each
at that record's σ3′ and Dr0 (`campaign.cell.run_cell`), with verdicts (within / outside /
undecided, as calibrate.py).
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import tomli_w

from interphase.analysis.cell_ensemble import at_critical_state
from interphase.campaign import store as st
from interphase.campaign.calibrate import TOLERANCES as ANGLE_TOLERANCES
from interphase.campaign.calibrate import _clean, _iterate, _posterior, _quiet, check_angles, grainlearning, sample_rows
from interphase.campaign.element import CELL_SERIES, run_cases, write_campaign
from interphase.campaign.restore import restoring
from interphase.errors import InputError
from interphase.soil import CELL_DEFAULTS, SoilCard, load_card, read_toml, soil_fields

QUANTITIES = ("phi_peak_deg", "psi_max_deg", "phi_cs_deg", "relative_density")
NOT_CRITICAL = "not a critical state"
TOLERANCES = {**ANGLE_TOLERANCES, "relative_density": 0.05}     # [°], and Dr [-]
FREE_FIELDS = ("friction_pp", "rolling_friction", "preparation")
BUDGET = {"samples": 12, "iterations": 3, "seeds": 2, "final_seeds": 3, "ess_target": 0.3, "components": 2}
QUICK = {"samples": 3, "iterations": 1, "seeds": 1, "final_seeds": 1}


@dataclass(frozen=True)
class Record:
    """One laboratory record as the calibration uses it: its stress, density and angles."""
    path: Path
    confining_stress: float          # [Pa] σ3′ at the start of shearing
    e0: float
    relative_density: float
    values: dict                     # phi_peak_deg, psi_max_deg (and phi_cs_deg when the target gives it)


@dataclass(frozen=True)
class CellTarget:
    path: Path
    name: str
    test: str
    record: Record
    source: str
    soil: dict
    free: dict
    cell: dict
    budget: dict
    verification: tuple = ()
    raw: dict = field(default_factory=dict)

    @property
    def values(self) -> dict:
        """What the fit matches: the record's angles. Its Dr is not matched: the spheres dilate more
        than the sand at the same Dr on their own limits (docs/soils.md, "The density scale"),
        so the model's Dr is measured at the fitted state and fixes the card's density scale."""
        return dict(self.record.values)

    @property
    def index_limits(self) -> tuple[float, float]:
        """The sand's (e_min, e_max) from its index tests ([target] e_min, e_max)."""
        t = self.raw["target"]
        return float(t["e_min"]), float(t["e_max"])


def is_cell_target(path) -> bool:
    _, _, data, _ = read_toml(path, "target file", "give a calibration target TOML")
    return data.get("target", {}).get("test") in ("triaxial", "biaxial")


def read_record(path: Path, e_lim: tuple[float, float], phi_cs: float | None) -> Record:
    from interphase.analysis.triaxial import shear_state
    from interphase.io.lab_triaxial import read_triaxial

    rec = read_triaxial(path)
    t = rec.table
    s = shear_state(t.eps1, t.epsv, t.ratio, t.e)
    values = {"phi_peak_deg": s.phi_peak_deg, "psi_max_deg": s.psi_max_deg}
    if phi_cs is not None:
        values["phi_cs_deg"] = float(phi_cs)
    e_min, e_max = e_lim
    return Record(Path(path), float(rec.sigma3_start), float(rec.e0), (e_max - rec.e0) / (e_max - e_min), values)


def load_cell_target(path) -> CellTarget:
    p, text, data, bad = read_toml(path, "target file", "give a calibration target TOML")
    t = data.get("target", {})
    for key in ("record", "e_min", "e_max", "source"):
        if key not in t:
            raise bad("target", key, f"a {t.get('test')} target needs {key}", "see campaign/calibrate_cell.py")
    e_lim = (float(t["e_min"]), float(t["e_max"]))
    if not 0 < e_lim[0] < e_lim[1]:
        raise bad("target", "e_min", f"e_min {e_lim[0]} must be below e_max {e_lim[1]}", "the sand's index void ratios")
    phi_cs = t.get("phi_cs_deg")
    here = p.resolve().parent
    record = read_record(here / t["record"], e_lim, phi_cs)
    ver = tuple(read_record(here / v["record"], e_lim, None) for v in data.get("verification", []))
    soil = soil_fields(data.get("soil", {}), bad, "the grains' fixed fields")
    free = {}
    for key, rng in data.get("free", {}).items():
        if key not in FREE_FIELDS or key in soil:
            raise bad("free", key, f"{key!r} cannot be free here", f"free parameters: {', '.join(FREE_FIELDS)}, not in [soil]")
        if not (isinstance(rng, list) and len(rng) == 2 and rng[0] < rng[1] and rng[0] >= 0):
            raise bad("free", key, f"must be a range [min, max], got {rng!r}", f"e.g. {key} = [0.1, 1.0]")
        free[key] = (float(rng[0]), float(rng[1]))
    cell = {**CELL_DEFAULTS, **data.get("cell", {}), "test": t["test"]}
    budget = {**BUDGET, **{k: v for k, v in data.get("budget", {}).items() if k != "quick"}}
    budget["quick"] = {**QUICK, **data.get("budget", {}).get("quick", {})}
    return CellTarget(p, str(t.get("name", p.stem)), t["test"], record, str(t["source"]), soil, free, cell, budget, ver,
                      raw=data)


def _card(target: CellTarget, soil: dict, name: str, path: Path) -> SoilCard:
    return SoilCard(name=name, path=path, soil=soil, element={}, extra={"cell": {**target.cell}})


def e_min_once(target, runs: Path, executor, jobs, stream, rerun_failed) -> float:
    """The frictionless preparation's void ratio at the fitted record's stress (the same for every
    sample: preparation 0 scales both frictions to 0), seeds 1–2."""
    from interphase.campaign.density import TOKEN_STRAIN

    probe = _card(target, {**target.soil, **{k: r[0] for k, r in target.free.items()}}, target.name, target.path)
    base = probe.cell_case(nominal(target.record.confining_stress), axial_strain=TOKEN_STRAIN, preparation=0.0)
    base.pop("seed")
    path = write_campaign(runs / "e_min.toml", name=f"calibrate-{target.name}-e-min", case=base,
                          sweep={"seed": [1, 2]}, description="the grains' frictionless packing")
    planned, series, _ = run_cases(path, executor=executor, jobs=jobs, stream=stream, rerun_failed=rerun_failed,
                                   columns=CELL_SERIES)
    vals = [float(series[p.case_id]["e"].iloc[0]) for p in planned if p.case_id in series]
    if not vals:
        raise InputError("the frictionless packing did not finish", where=str(path), fix="see `campaign status`")
    return float(np.mean(vals))


def _sample(target: CellTarget, budget: dict, runs: Path, tag: str, e_min: float, executor, jobs, stream,
            rerun_failed):
    """GrainLearning's iterations; each sample's cell tests (and its e_max token) run as generated
    campaigns. Returns (calibration object, every sample's row, runs made)."""
    BayesianCalibration, DynamicSystem = grainlearning()

    from interphase.campaign.cell import cell_of
    from interphase.campaign.density import TOKEN_STRAIN

    names, rec = list(target.free), target.record
    obs = [q for q in QUANTITIES if q in target.values]
    history, n_runs = [], [0]
    probe = _card(target, dict(target.soil), target.name, target.path)

    def run_samples(calib):
        it = calib.curr_iter
        params = np.asarray(calib.system.param_data, float)
        zip_ = {k: [round(float(v), 6) for v in params[:, j]] for j, k in enumerate(names)}
        zip_["name"] = [f"{target.name}-i{it}-k{k}" for k in range(len(params))]
        base = {k: v for k, v in probe.cell_case(nominal(rec.confining_stress)).items() if k not in names and k != "seed"}
        path = write_campaign(runs / f"iteration-{it}{tag}.toml", name=f"calibrate-{target.name}-i{it}", case=base,
                              zip_=sample_rows(zip_, it, int(budget["seeds"])),
                              description=f"calibration of {target.name}, iteration {it}")
        loose = {k: v for k, v in zip_.items() if k != "preparation"}
        tok = {k: v for k, v in probe.cell_case(nominal(rec.confining_stress), axial_strain=TOKEN_STRAIN).items()
               if k not in names and k != "seed"} | {"preparation": 1.0}
        tpath = write_campaign(runs / f"iteration-{it}{tag}-e-max.toml", name=f"calibrate-{target.name}-i{it}-e-max",
                               case=tok, zip_=loose, description="each sample's loosest packing")
        print(f"calibrate {target.name}: iteration {it}, {len(params)} samples × {budget['seeds']} seed(s) → {path}",
              file=stream, flush=True)
        planned, series, summ = run_cases(path, executor=executor, jobs=jobs, stream=stream,
                                               rerun_failed=rerun_failed, columns=CELL_SERIES)
        tplanned, tseries, _ = run_cases(tpath, executor=executor, jobs=jobs, stream=stream,
                                              rerun_failed=rerun_failed, columns=CELL_SERIES)
        n_runs[0] += len(planned) + len(tplanned)
        sim = np.zeros((len(params), len(obs), 1))
        for k, nm in enumerate(zip_["name"]):
            r = cell_of([p for p in planned if p.case.name == nm], series, summ).to_dict()
            e_max = next((float(tseries[p.case_id]["e"].iloc[0]) for p in tplanned
                          if p.case.name == nm and p.case_id in tseries), math.nan)
            r["relative_density"] = (e_max - r["void_ratio"]) / (e_max - e_min) if r["void_ratio"] is not None else None
            sim[k, :, 0] = [r[q] if r[q] is not None and math.isfinite(r[q]) else 0.0 for q in obs]
            history.append({"iteration": it, **{n: float(params[k, j]) for j, n in enumerate(names)},
                            **{q: r[q] for q in QUANTITIES}, "void_ratio": r["void_ratio"], "e_max": e_max,
                            "seeds": r["n_seeds"]})
        calib.system.set_sim_data(sim)

    values = target.values
    calib = BayesianCalibration.from_dict({
        "num_iter": int(budget["iterations"]), "callback": run_samples, "save_fig": -1,
        "system": {"system_type": DynamicSystem, "param_names": names,
                   "param_min": [target.free[n][0] for n in names], "param_max": [target.free[n][1] for n in names],
                   "num_samples": int(budget["samples"]), "obs_data": np.array([[values[q]] for q in obs]),
                   "obs_names": obs, "ctrl_data": [rec.confining_stress], "sim_name": target.name,
                   "inv_obs_weight": [(TOLERANCES[q] / values[q]) ** 2 for q in obs]},
        "inference": {"Bayes_filter": {"ess_target": float(budget["ess_target"])},
                      "sampling": {"max_num_components": int(budget["components"]), "random_state": 0,
                                   "slice_sampling": False}},
    })
    _quiet(lambda: _iterate(calib, int(budget["iterations"])))
    return calib, history, n_runs[0]


def _checks(lab: dict, r, dr_lab: float) -> list[dict]:
    """calibrate.check_angles' verdicts on the angles, and the specimens' relative density beside them.
    φ_cs is judged only where the model has reached a critical state (|−dεv/dε1| at the end within
    cell_ensemble.CRITICAL_RATE); else its verdict says so and the note says how to get there."""
    checks = check_angles(lab, r)
    for c in checks:
        if c["quantity"] == "phi_cs_deg" and not at_critical_state(r.dilatancy_end):
            c["verdict"] = NOT_CRITICAL
            c["note"] = (f"the model's volume still changes at ε1 = {r.eps1_end:.0%} (−dεv/dε1 = {r.dilatancy_end:.2f}): "
                         "its end angle is no critical state; run the cell further ([cell] axial_strain: the "
                         "Karlsruhe card's spheres need 0.35–0.4, docs/soils.md)")
    return checks + [{"quantity": "relative_density", "laboratory": dr_lab, "measured": r.relative_density,
                      "difference": r.relative_density - dr_lab, "tolerance": TOLERANCES["relative_density"]}]


def _lab_scale(card: SoilCard, target: CellTarget, seeds, output: Path, executor, jobs, stream, rerun_failed):
    """(lab_span, lab_offset, the model's own Dr of the fitted state at the record's stress, on the limits
    the card reads a Dr on: density.read_limits): the scale model Dr = lab_offset + lab_span · Dr that maps
    the record's Dr back onto the fitted state (SoilCard.lab_span, lab_offset).

    On index limits a laboratory step in Dr keeps its step in void ratio: lab_span = the sand's
    e_max − e_min over the model's, the offset puts the record on the fitted state (the void-ratio
    scale, docs/soils.md: per unit of e0 the spheres gain φ_peak and ψ_max as the sand does). On the
    test's own limits the scale is the ratio model Dr / record Dr (offset 0)."""
    from interphase.campaign.density import own_relative_density

    rec = target.record
    model_dr = own_relative_density(card, nominal(rec.confining_stress), seeds, card.soil["preparation"],
                                    output=output, executor=executor, jobs=jobs, stream=stream,
                                    rerun_failed=rerun_failed)
    if card.dr_limits == "index":
        e_min, e_max = card.void_ratio_limits
        lab_min, lab_max = target.index_limits
        span = (lab_max - lab_min) / (e_max - e_min)
        return round(span, 6), round(model_dr - span * rec.relative_density, 6), round(model_dr, 4)
    return round(model_dr / rec.relative_density, 4), 0.0, round(model_dr, 4)


def nominal(stress: float) -> float:
    """The model's confining stress for a record's [Pa]: the nearest multiple of 50 kPa (the records'
    programme: 48.9–50.9 kPa are its 50 kPa tests, 392.1–401.5 its 400 kPa ones), so that one density
    map per stress serves every record there."""
    return max(50e3, round(stress / 50e3) * 50e3)


def _final(card: SoilCard, target: CellTarget, seeds, runs: Path, executor, jobs, stream, rerun_failed):
    """The laboratory's test on the chosen grains at every record's σ3′ and Dr0 (the fitted one
    first): ([achieved checks], the fitted record's preparation, [verification entries], finished
    runs in `runs`)."""
    from interphase.campaign.cell import run_cell

    out = []
    for rec in (target.record, *target.verification):
        (r,) = run_cell(card, [nominal(rec.confining_stress)], seeds, relative_density=min(1.0, max(0.0, rec.relative_density)),
                        output=runs, executor=executor, jobs=jobs, stream=stream, rerun_failed=rerun_failed)
        out.append({"record": rec.path.name, "confining_stress": rec.confining_stress, "e0": rec.e0,
                    "relative_density": rec.relative_density, "preparation": r.preparation,
                    "measured": {k: v for k, v in r.to_dict().items() if k.startswith(("phi_", "psi_", "void_", "eps1_"))
                                 or k in ("n_seeds", "relative_density", "dilatancy_end")},
                    "checks": _checks(rec.values, r, rec.relative_density)})
    # the tests and the density maps' token runs (5 a stress and the refinement's) that finished
    return out[0]["checks"], out[0]["preparation"], out[1:], sum(1 for _ in Path(runs).rglob(st.DONE)) if Path(runs).is_dir() else 0


def calibrate_cell(target_path, *, quick: bool = False, card_path=None, output=None, executor=None, jobs=None,
                   stream=None, rerun_failed: bool = False, restore=None) -> dict:
    """calibrate.calibrate for a record target: the laboratory's test on the cell; `restore` as there."""
    from interphase.campaign.folders import calibrate_folders, next_free

    stream = stream or sys.stdout
    target = load_cell_target(target_path)
    budget = {**target.budget, **(target.budget["quick"] if quick else {})}
    budget.pop("quick", None)
    (card_at, card_from), (runs, runs_from) = calibrate_folders(target, quick, card_path, output)
    name = target.name + ("-quick" if quick else "")
    print(f"calibrate {name}: card {card_at} ({card_from}); runs folder {runs} ({runs_from})", file=stream, flush=True)
    if card_at.exists():
        raise InputError(f"{card_at} exists; a calibration never replaces it", where=f"card {card_at} ({card_from})",
                         fix=f"write the new card elsewhere: -o {next_free(card_at)}")
    with restoring(runs, restore):
        result = _calibrate(target, budget, runs, card_at, name, quick, executor, jobs, stream, rerun_failed)
    _write(card_at, target, result, name)
    return result


def _calibrate(target, budget, runs, card_at, name, quick, executor, jobs, stream, rerun_failed) -> dict:
    from interphase.campaign.density import REFERENCE_STRESS, limits_of, void_ratio_map

    t0 = time.time()
    tag = "-quick" if quick else ""
    e_min = e_min_once(target, runs, executor, jobs, stream, rerun_failed)
    calib, history, n_runs = _sample(target, budget, runs, tag, e_min, executor, jobs, stream, rerun_failed)
    chosen, posterior, ess = _posterior(calib, list(target.free), target)
    card = _card(target, {**target.soil, **chosen}, name, card_at)
    seeds = list(range(1, min(2, int(budget["final_seeds"])) + 1))      # the density limits: 2 seeds (1 when quick)
    prep, e = void_ratio_map(card, REFERENCE_STRESS, seeds, output=runs / f"density{tag}", executor=executor,
                             jobs=jobs, stream=stream, rerun_failed=rerun_failed)
    e_min, e_max = limits_of(prep, e)
    density = {"reference_stress": REFERENCE_STRESS, "seeds": len(seeds), "n_grains": int(target.cell["n_grains"]),
               "preparations": list(prep), "void_ratios": [round(float(v), 5) for v in e],
               "e_min": round(e_min, 5), "e_max": round(e_max, 5)}
    card.extra["density"] = density         # the index limits _lab_scale reads the fitted state on
    density["lab_span"], density["lab_offset"], density["model_relative_density"] = _lab_scale(
        card, target, seeds, runs / f"final{tag}" / "density", executor, jobs, stream, rerun_failed)
    achieved, achieved_prep, verification, n_final = _final(card, target, list(range(1, int(budget["final_seeds"]) + 1)),
                                             runs / f"final{tag}", executor, jobs, stream, rerun_failed)
    import pandas as pd

    runs.mkdir(parents=True, exist_ok=True)
    pd.DataFrame(history).to_csv(runs / f"samples{tag}.csv", index=False)
    result = {"card": str(card_at), "target": name, "chosen": chosen, "posterior": posterior, "achieved": achieved,
              "achieved_preparation": achieved_prep, "verification": verification, "density": density,
              "calibration": {"runs": n_runs + 2 + 2 * len(prep) + n_final, "wall_time_s": round(time.time() - t0, 1),
                              "iterations": int(budget["iterations"]), "samples": len(history),
                              "effective_sample_size": ess, "e_min_frictionless": e_min, "budget": budget,
                              "quick": quick, "engine": "liggghts"}}
    return result


def _write(path: Path, target: CellTarget, result: dict, name: str) -> None:
    t = target.raw["target"]
    data = {"soil": {"name": name, "description": str(t.get("description", "")), **target.soil, **result["chosen"]},
            "cell": dict(target.cell), "density": result["density"],
            "target": {**t, "free": {k: list(v) for k, v in target.free.items()}},
            "posterior": result["posterior"], "achieved": result["achieved"], "verification": result["verification"],
            "calibration": result["calibration"]}
    head = (f"# Soil card {name}: written by `campaign calibrate {target.path.name}` against laboratory records\n"
            "# (the laboratory's own test on the model, docs/soils.md). [soil] and [cell] are what a campaign uses.\n")
    if result["calibration"]["quick"]:
        head = "# QUICK CALIBRATION (--quick): a first look, NOT a calibrated soil.\n" + head
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "x") as f:
        f.write(head + tomli_w.dumps(_clean(data)))
    load_card(path)
