"""`campaign calibrate TARGET.toml`: grain parameters from a laboratory soil's element-test values,
by GrainLearning's iterative Bayesian filter (sequential Monte Carlo over parameter samples, new
samples drawn from a Gaussian mixture fitted to the posterior, iteration after iteration).

Each iteration's samples run as one generated campaign of element tests (campaign.element): local
or SLURM, resumable, a finished run never repeated (identity is the hash of the inputs). Every step
of GrainLearning is deterministic here (unscrambled Halton samples first, a fixed random state for
the mixture), so a calibration stopped at any point and started again draws the same samples and
reuses every finished run.

The target (TOML):

    [target]
    name = "ottawa-20-30"               # the card's name (soils/<name>.toml)
    description = "..."
    normal_stress = 100e3               # [Pa] the stress the fit uses
    phi_peak_deg = 37.0                 # the laboratory's direct-shear values at that stress ...
    phi_cs_deg = 31.0
    psi_max_deg = 9.0                   # (optional)
    source = "Author (year), Table n"   # required: where every number comes from
    [soil]                              # the grains' fixed Case fields (interphase.soil.SOIL_FIELDS)
    d50 = 0.00072
    gradation = "poly"
    [free]                              # the calibrated fields, each [min, max]
    friction_pp = [0.3, 1.0]
    rolling_friction = [0.1, 1.0]
    preparation = [0.0, 1.0]
    [element]                           # optional: the element test's cell (interphase.soil.ELEMENT_DEFAULTS)
    [budget]                            # optional: samples per iteration, iterations, seeds per sample,
    samples = 24                        # seeds of the final element test; quick = {...} for --quick
    [[verification]]                    # laboratory values at stresses the fit does not use
    normal_stress = 200e3
    phi_peak_deg = 35.0
    source = "..."

Observations: φ_peak, φ_cs (and ψ_max when given), each sample's from its seed ensemble; the
likelihood's spread for each is proportional to TOLERANCES (1.5°, 1.5°, 2°: what the card must reach),
its scale set by GrainLearning to keep the effective sample size at ess_target.
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import tomli_w

from interphase.case import PREPARATION_MAX
from interphase.campaign.element import element_of, run_cases, run_element, write_campaign
from interphase.campaign.restore import restoring
from interphase.errors import InputError
from interphase.soil import SOIL_FIELDS, SoilCard, element_fields, load_card, read_toml, soil_fields

QUANTITIES = ("phi_peak_deg", "phi_cs_deg", "psi_max_deg")
TOLERANCES = {"phi_peak_deg": 1.5, "phi_cs_deg": 1.5, "psi_max_deg": 2.0}     # [°]
FREE_FIELDS = ("friction_pp", "rolling_friction", "preparation")
BUDGET = {"samples": 24, "iterations": 3, "seeds": 2, "final_seeds": 5, "ess_target": 0.3, "components": 3}
QUICK = {"samples": 4, "iterations": 1, "seeds": 1, "final_seeds": 2}
TARGET_KEYS = ("name", "description", "normal_stress", *QUANTITIES, "source", "density_state", "note", "card", "runs")


@dataclass(frozen=True)
class Target:
    path: Path
    name: str
    normal_stress: float
    values: dict                    # quantity → laboratory value [°]
    source: str
    soil: dict
    free: dict                      # field → (min, max)
    element: dict
    budget: dict
    verification: tuple = ()
    raw: dict = field(default_factory=dict)


def load_target(path) -> Target:
    p, text, data, bad = read_toml(path, "target file", "give a calibration target TOML")
    for key in data:
        if key not in ("target", "soil", "free", "element", "budget", "verification"):
            raise InputError(f"unknown table [{key}]", where=str(p),
                             fix="a target has [target], [soil], [free], [element], [budget], [[verification]]")
    t = data.get("target")
    if not isinstance(t, dict):
        raise InputError("no [target] table", where=str(p), fix="give the laboratory values under [target]")
    for key in t:
        if key not in TARGET_KEYS:
            raise bad("target", key, f"unknown key {key!r}", f"allowed: {', '.join(TARGET_KEYS)}")
    if not str(t.get("source", "")).strip():
        raise bad("target", "source", "the laboratory values carry no source",
                  "give source = \"Author (year), title, table or figure\": a number without its source is not used")
    name = t.get("name", p.stem)
    sigma = t.get("normal_stress")
    if not isinstance(sigma, (int, float)) or not sigma > 0:
        raise bad("target", "normal_stress", f"must be a stress > 0 in Pa, got {sigma!r}", "e.g. normal_stress = 100e3")
    values = target_angles(t, lambda q, msg, fix=None: bad("target", q, msg, fix))
    soil = soil_fields(data.get("soil", {}), bad, f"use {', '.join(SOIL_FIELDS)}")
    free = {}
    for key, rng in data.get("free", {}).items():
        if key not in FREE_FIELDS:
            raise bad("free", key, f"{key!r} cannot be calibrated", f"free parameters: {', '.join(FREE_FIELDS)}")
        if key in soil:
            raise bad("free", key, f"{key!r} is both fixed in [soil] and free", "keep it in one of the two")
        if (not isinstance(rng, list) or len(rng) != 2
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in rng)):
            raise bad("free", key, f"must be a range [min, max], got {rng!r}", f"e.g. {key} = [0.1, 1.0]")
        if rng[0] >= rng[1]:
            raise bad("free", key, f"the range's min {rng[0]} is not below its max {rng[1]}", "write [min, max]")
        if rng[0] < 0 or (key == "preparation" and rng[1] > PREPARATION_MAX):
            raise bad("free", key, f"the range {rng} leaves the field's domain",
                      f"frictions ≥ 0; preparation within [0, {PREPARATION_MAX:g}]")
        free[key] = (float(rng[0]), float(rng[1]))
    if not free:
        raise InputError("no [free] parameter", where=str(p), fix=f"free some of {', '.join(FREE_FIELDS)} with ranges")
    element = element_fields(data.get("element", {}), bad)
    budget = dict(BUDGET)
    raw_budget = data.get("budget", {})
    quick = dict(QUICK) | raw_budget.get("quick", {})
    for key, v in raw_budget.items():
        if key == "quick":
            continue
        if key not in BUDGET:
            raise bad("budget", key, f"unknown key {key!r}", f"allowed: {', '.join(BUDGET)}, quick")
        budget[key] = v
    budget["quick"] = quick
    verification = []
    for i, v in enumerate(data.get("verification", [])):
        if not str(v.get("source", "")).strip():
            raise InputError("a verification row carries no source", where=f"{p}: [[verification]] #{i + 1}",
                             fix="give source = \"Author (year), table or figure\"")
        if not isinstance(v.get("normal_stress"), (int, float)) or not v["normal_stress"] > 0:
            raise InputError("needs normal_stress > 0 [Pa]", where=f"{p}: [[verification]] #{i + 1}")
        target_angles(v, lambda q, msg, fix=None, i=i: InputError(msg, where=f"{p}: [[verification]] #{i + 1}: {q}",
                                                                   fix=fix), required=())
        verification.append(dict(v))
    # the grains must make a valid Case with every free field at its bounds
    probe = SoilCard(name=str(name), path=p, soil={**soil, **{k: r[0] for k, r in free.items()}}, element=element)
    from interphase.case import case_from_dict

    case_from_dict(probe.element_case(float(sigma)), where=f"{p}: [soil]")
    return Target(p, str(name), float(sigma), values, str(t["source"]), soil, free, element, budget,
                  tuple(verification), raw=data)


#: plausible laboratory friction angles of a soil [°] (sands, gravels, glass beads: 20–50°, with room)
PLAUSIBLE_PHI_DEG = (15.0, 60.0)


def target_angles(t: dict, bad, required=QUANTITIES[:2]) -> dict:
    """The laboratory angles of a [target] table (or a verification row), checked at load: numbers
    in degrees, φ within PLAUSIBLE_PHI_DEG (a value below 1.6 reads as radians and is said so),
    φ_cs ≤ φ_peak and ψ_max below φ_peak. `bad(key, message, fix)` builds the InputError."""
    values = {}
    for q in QUANTITIES:
        if q not in t:
            continue
        v = t[q]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise bad(q, f"must be an angle in degrees, got {v!r}")
        lo, hi = PLAUSIBLE_PHI_DEG
        if q != "psi_max_deg" and 0 < v < 1.6:
            raise bad(q, f"{v!r} looks like radians ({math.degrees(v):.1f}°)", f"give degrees: {q} = "
                      f"{math.degrees(v):.1f}")
        if q != "psi_max_deg" and not lo <= v <= hi:
            raise bad(q, f"{v!r}° is outside the plausible {lo:g}–{hi:g}° of a soil's friction angle",
                      "check the value against its source (degrees, direct-shear φ)")
        if q == "psi_max_deg" and not -hi < v < hi:
            raise bad(q, f"{v!r}° is not a plausible dilatancy angle", "check the value against its source (degrees)")
        values[q] = float(v)
    for q in required:
        if q not in values:
            raise bad(q, f"{q} is missing", "the calibration needs φ_peak and φ_cs at the target stress")
    peak = values.get("phi_peak_deg")
    if peak is not None and values.get("phi_cs_deg", -math.inf) > peak:
        raise bad("phi_cs_deg", f"φ_cs {values['phi_cs_deg']}° exceeds φ_peak {peak}°",
                  "φ_cs ≤ φ_peak: check the two values against their source")
    if peak is not None and values.get("psi_max_deg", -math.inf) >= peak:
        raise bad("psi_max_deg", f"ψ_max {values['psi_max_deg']}° is not below φ_peak {peak}°",
                  "a soil dilates at less than its friction angle: check the value against its source")
    return values


def _weighted_quantile(x: np.ndarray, w: np.ndarray, q: float) -> float:
    order = np.argsort(x)
    cw = np.cumsum(w[order])
    return float(np.interp(q * cw[-1], cw, x[order]))


def sample_rows(zip_: dict, iteration: int, n_seeds: int) -> dict:
    """The [zip] of an iteration's samples with each sample's own packing seeds: every sample k of
    iteration `iteration` runs on seeds 1 + n·(k + K·iteration) … n·(k + 1 + K·iteration) (K the
    samples, n `n_seeds`), no two samples of a calibration on the same specimens. The seed sets a
    specimen's fabric, and its peak follows the fabric whatever the grains (two grain sets on seeds
    1–6 of the Karlsruhe cell: r = 0.67 between their φ_peak by seed, seeds 1–2 1.7° under the six's
    mean; docs/soils.md): samples that shared seeds would share that seed's offset, which the
    posterior then fits, where independent seeds let it average out over the samples."""
    names = list(zip_)
    k_all = len(zip_[names[0]])
    rows = {n: [] for n in names} | {"seed": []}
    for k in range(k_all):
        first = 1 + n_seeds * (k + k_all * iteration)
        for seed in range(first, first + n_seeds):
            for n in names:
                rows[n].append(zip_[n][k])
            rows["seed"].append(seed)
    return rows


def _posterior(calib, names: list[str], target) -> tuple[dict, dict, float]:
    """(chosen parameters, posterior per parameter {mean, lo, hi}, effective sample size) of the last
    iteration's weighted samples."""
    post = np.asarray(calib.inference.posterior if getattr(calib.inference, "posterior", None) is not None
                      else calib.inference.Bayes_filter.get_posterior_at_time(), float).ravel()
    params = np.asarray(calib.system.param_data, float)
    # the card takes the posterior mean: the most probable single sample is the one whose few seeds
    # happened to land nearest the target (measured: docs/soils.md, the recovery test)
    chosen = {n: round(float(post @ params[:, j]), 4) for j, n in enumerate(names)}
    # 95 % credible intervals: weighted quantiles of the last iteration's samples (clipped to the
    # range: GrainLearning's normalisation leaves its bounds off by an ulp)
    posterior = {n: {"mean": float(post @ params[:, j]),
                     **{k: float(np.clip(_weighted_quantile(params[:, j], post, q), *target.free[n]))
                        for k, q in (("lo", 0.025), ("hi", 0.975))}} for j, n in enumerate(names)}
    ess = float(1.0 / np.sum(post ** 2)) if post.sum() > 0 else math.nan
    return chosen, posterior, ess


def _final_checks(card: SoilCard, target, n_seeds: int, runs: Path, executor, jobs, stream, rerun_failed=False):
    """The chosen grains' element test at the target stress and every held-out one (in `runs`,
    the calibration's own runs folder: --runs governs every run): (final ElementResult, achieved
    checks, verification entries, runs)."""
    seeds = range(1, n_seeds + 1)
    print(f"calibrate {target.name}: the chosen grains' element test at {target.normal_stress / 1e3:g} kPa, "
          f"{len(seeds)} seeds → {runs}", file=stream, flush=True)
    final, *held_out = run_element(card, [target.normal_stress, *(v["normal_stress"] for v in target.verification)],
                                   seeds, output=runs, executor=executor, jobs=jobs, stream=stream,
                                   rerun_failed=rerun_failed)
    achieved = [{"quantity": c["quantity"], "target": c["laboratory"], "value": c["measured"], "lo": c["lo"],
                 "hi": c["hi"], "difference": c["difference"], "verdict": c["verdict"]}
                for c in check_angles(target.values, final)]
    verification = [{**v, "measured": {k: val for k, val in r.to_dict().items()
                                       if k.startswith(("phi_", "psi_", "solid_")) or k in ("n_seeds", "has_peak")},
                     "checks": check_angles(v, r)} for v, r in zip(target.verification, held_out)]
    return final, achieved, verification, len(seeds) * (1 + len(target.verification))


@dataclass
class Plan:
    """What one calibration does and where: the target, its budget (quick or full), the card's name
    and path and the runs folder, each with where it came from (campaign.folders)."""
    target: Target
    quick: bool
    budget: dict
    name: str
    card: Path
    card_from: str
    runs: Path
    runs_from: str

    @property
    def tag(self) -> str:
        return "-quick" if self.quick else ""

    def identity(self) -> dict:
        """What makes two calibrations the same one: the card records all of it."""
        t = self.target
        return {"target": _located_out(t.raw["target"]) | {"free": {k: list(v) for k, v in t.free.items()}},
                "element": dict(t.element), "soil": dict(t.soil), "budget": dict(self.budget), "quick": self.quick}


def _located_out(t: dict) -> dict:
    """A [target] table without where its outputs go (card, runs): not part of what is calibrated."""
    return {k: v for k, v in t.items() if k not in ("card", "runs")}


def plan_calibration(target_path, *, quick: bool = False, card_path=None, output=None) -> Plan:
    """The target read and checked, its budget, and where the card and the runs go."""
    from interphase.campaign.folders import calibrate_folders

    target = load_target(target_path)
    budget = {**target.budget, **(target.budget["quick"] if quick else {})}
    budget.pop("quick", None)
    (card, card_from), (runs, runs_from) = calibrate_folders(target, quick, card_path, output)
    return Plan(target, quick, budget, target.name + ("-quick" if quick else ""), card, card_from, runs, runs_from)


def existing_card(plan: Plan) -> dict | None:
    """None when the card's path is free. A card there from this same calibration (same target,
    element, soil, budget, quick or not) is read back: its result, nothing rerun. Any other file is
    refused (InputError): nothing finished is replaced, a new name is suggested."""
    from interphase.campaign.folders import next_free

    path = plan.card
    if not path.exists():
        return None
    try:
        card = load_card(path)
    except InputError:
        card = None
    cal = card.extra.get("calibration", {}) if card else {}
    if card is not None:
        ext = card.extra
        held = {"target": _located_out(ext.get("target") or {}), "element": card.element, "soil": {k: card.soil.get(k) for k in
                                                                              plan.target.soil},
                "budget": cal.get("budget"), "quick": cal.get("quick", False)}
        if held == plan.identity():
            names = list(plan.target.free)
            achieved = [a | {"verdict": verdict(a["target"], a.get("lo"), a.get("hi"), TOLERANCES[a["quantity"]])}
                        for a in ext.get("achieved", [])]      # judged by today's rule, whenever written
            return {"card": str(path), "target": plan.target.name, "chosen": {n: card.soil[n] for n in names},
                    "posterior": ext.get("posterior", {}), "achieved": achieved,
                    "verification": ext.get("verification", []), "calibration": cal, "reused": True}
    what = ("a soil card of another calibration" + (f" ({cal.get('runs', '?')} runs"
                                                    + (", --quick" if cal.get("quick") else "") + ")" if cal else "")
            if card is not None else "a file that is no soil card")
    raise InputError(f"{path} holds {what}; a calibration never replaces it", where=f"card {path} ({plan.card_from})",
                     fix=f"write the new card elsewhere: -o {next_free(path)}")


def calibrate(target_path, *, quick: bool = False, card_path=None, output=None, executor=None, jobs=None,
              stream=None, rerun_failed: bool = False, restore=None) -> dict:
    """Calibrate, write the soil card, return what it holds (JSON data). A card already at the
    card's path is read back when it is this calibration's, else refused (`existing_card`).
    `restore`: a pack of this calibration's runs folder (`campaign pack`) whose finished runs are
    brought back before each generated campaign runs."""
    stream = stream or sys.stdout
    plan = plan_calibration(target_path, quick=quick, card_path=card_path, output=output)
    print(f"calibrate {plan.name}: card {plan.card} ({plan.card_from}); runs folder {plan.runs} ({plan.runs_from})",
          file=stream, flush=True)
    done = existing_card(plan)
    if done is not None:
        print(f"calibrate {plan.name}: {plan.card} already holds this calibration, finished: read back, nothing "
              "rerun", file=stream, flush=True)
        return done
    t0 = time.time()
    with restoring(plan.runs, restore):
        calib, history, n_runs = _sample(plan, executor, jobs, stream, rerun_failed)
        chosen, posterior, ess = _posterior(calib, list(plan.target.free), plan.target)
        card = SoilCard(name=plan.name, path=plan.card, soil={**plan.target.soil, **chosen}, element=plan.target.element)
        final, achieved, verification, n_final = _final_checks(card, plan.target, int(plan.budget["final_seeds"]),
                                                               plan.runs / "element", executor, jobs, stream,
                                                               rerun_failed)
    result = {
        "card": str(plan.card), "target": plan.target.name, "chosen": chosen, "posterior": posterior,
        "achieved": achieved, "verification": verification,
        "calibration": {"runs": n_runs[0] + n_final, "wall_time_s": round(time.time() - t0, 1), "iterations": len(
            {h["iteration"] for h in history}), "samples": len(history), "effective_sample_size": ess,
            "budget": plan.budget, "quick": plan.quick, "element_solid_fraction": final.solid_fraction,
            "element_has_peak": final.has_peak, "engine": "liggghts"},
    }
    import pandas as pd

    pd.DataFrame(history).to_csv(plan.runs / f"samples{plan.tag}.csv", index=False)
    write_card(plan.card, plan.target, result, name=plan.name)
    return result


def grainlearning():
    """(BayesianCalibration, DynamicSystem) of GrainLearning; a missing install is an error that says
    how to install it (its numpy < 2 pin keeps `pip install grainlearning` from resolving beside this
    project's numpy 2 stack; it runs on numpy 2 with the same posterior: docs/soils.md)."""
    try:
        from grainlearning import BayesianCalibration
        from grainlearning.dynamic_systems import DynamicSystem
    except ImportError:
        raise InputError("GrainLearning is not installed: calibration needs it", where="campaign calibrate",
                         fix="`make venv` installs it, or `pip install --no-deps grainlearning==2.0.5` "
                             "(its other needs come with this project)") from None
    return BayesianCalibration, DynamicSystem


def _sample(plan: Plan, executor, jobs, stream, rerun_failed: bool):
    """GrainLearning's iterations, each sample's element tests run as a generated campaign:
    (the calibration object, every sample's row, [runs made])."""
    BayesianCalibration, DynamicSystem = grainlearning()

    target, budget = plan.target, plan.budget
    names = list(target.free)
    obs = [q for q in QUANTITIES if q in target.values]
    history: list[dict] = []          # every sample: params, achieved values, iteration
    n_runs = [0]

    def run_samples(calib):
        it = calib.curr_iter
        params = np.asarray(calib.system.param_data, float)
        zip_ = {k: [round(float(v), 6) for v in params[:, j]] for j, k in enumerate(names)}
        zip_["name"] = [f"{target.name}-i{it}-k{k}" for k in range(len(params))]
        path = write_campaign(plan.runs / f"iteration-{it}{plan.tag}.toml", name=f"calibrate-{target.name}-i{it}",
                              case={"test": "box", "device": "periodic", **target.soil, **target.element,
                                    "normal_stress": target.normal_stress},
                              zip_=sample_rows(zip_, it, int(budget["seeds"])),
                              executor=executor or "local", jobs=jobs or 0,
                              description=f"calibration of {target.name}, iteration {it}")
        print(f"calibrate {target.name}: iteration {it}, {len(params)} samples × {budget['seeds']} seed(s) → {path}",
              file=stream, flush=True)
        planned, series, summ = run_cases(path, executor=executor, jobs=jobs, stream=stream, rerun_failed=rerun_failed)
        n_runs[0] += len(planned)
        sim = np.zeros((len(params), len(obs), 1))
        for k in range(len(params)):
            cases = [p for p in planned if p.case.name == zip_["name"][k]]
            r = element_of(cases, series, summ, cases[0].case.d50, target.normal_stress).to_dict()
            sim[k, :, 0] = [r[q] if r[q] is not None else 0.0 for q in obs]    # a failed sample: far from any target
            history.append({"iteration": it, **{n: float(params[k, j]) for j, n in enumerate(names)},
                            **{q: r[q] for q in QUANTITIES}, "solid_fraction": r["solid_fraction"],
                            "has_peak": r["has_peak"], "seeds": r["n_seeds"]})
        calib.system.set_sim_data(sim)

    calib = BayesianCalibration.from_dict({
        "num_iter": int(budget["iterations"]), "callback": run_samples, "save_fig": -1,
        "system": {"system_type": DynamicSystem, "param_names": names,
                   "param_min": [target.free[n][0] for n in names], "param_max": [target.free[n][1] for n in names],
                   "num_samples": int(budget["samples"]), "obs_data": np.array([[target.values[q]] for q in obs]),
                   "obs_names": obs, "ctrl_data": [target.normal_stress], "sim_name": target.name,
                   "inv_obs_weight": [(TOLERANCES[q] / target.values[q]) ** 2 for q in obs]},
        "inference": {"Bayes_filter": {"ess_target": float(budget["ess_target"])},
                      "sampling": {"max_num_components": int(budget["components"]), "random_state": 0,
                                   "slice_sampling": False}},
    })
    _quiet(lambda: _iterate(calib, int(budget["iterations"])))
    return calib, history, n_runs


def check_angles(lab: dict, measured) -> list[dict]:
    """Each laboratory angle of `lab` against the element test `measured` (an ElementResult):
    difference [°] (measured − laboratory), and the verdict against TOLERANCES: "within" when the
    whole 95 % interval lies within the tolerance of the laboratory value (so it is narrower than
    twice the tolerance; one seed has no interval and decides nothing), "outside" when the whole
    interval lies beyond it, else "undecided" (more seeds would tell)."""
    out = []
    for q in QUANTITIES:
        if q not in lab:
            continue
        v, lo, hi = (getattr(measured, q + k) for k in ("", "_lo", "_hi"))
        d, tol = v - float(lab[q]), TOLERANCES[q]
        out.append({"quantity": q, "laboratory": float(lab[q]), "measured": v, "lo": lo, "hi": hi,
                    "difference": d, "tolerance": tol, "verdict": verdict(float(lab[q]), lo, hi, tol)})
    return out


def verdict(lab: float, lo, hi, tol: float) -> str:
    """"within" when the interval [lo, hi] lies inside lab ± tol, "outside" when it lies wholly
    beyond, else "undecided" (no interval: one seed decides nothing)."""
    lo = math.nan if lo is None else float(lo)
    hi = math.nan if hi is None else float(hi)
    if math.isfinite(lo) and math.isfinite(hi) and lab - tol <= lo and hi <= lab + tol:
        return "within"
    if (math.isfinite(lo) and lo - lab > tol) or (math.isfinite(hi) and lab - hi > tol):
        return "outside"
    return "undecided"


def _iterate(calib, iterations: int) -> None:
    """GrainLearning's iteration (BayesianCalibration.run_one_iteration), except that the last one
    fits no new proposal: nothing would run from it, and with few samples the mixture fit fails on a
    posterior that sits on one sample."""
    inference, system = calib.inference, calib.system
    for it in range(iterations):
        calib.curr_iter = system.curr_iter = it
        if it == 0:
            inference.initialize(system)
        system.param_data = inference.param_data_list[-1]
        system.num_samples = system.param_data.shape[0]
        system.sim_data = None
        calib.callback(calib)
        inference.run_inference(system)
        inference.sigma_list.append(system.sigma_max)
        if it < iterations - 1:
            inference.run_sampling(system)


def _quiet(fn):
    """GrainLearning prints its progress on stdout: send it to stderr so that --json stays clean."""
    import contextlib

    with contextlib.redirect_stdout(sys.stderr):
        return fn()


def _clean(obj):
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()
                if v is not None and not (isinstance(v, list) and not v)
                and not (isinstance(v, (float, np.floating)) and math.isnan(v))}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, (np.floating, np.integer)):
        return obj.item()
    return obj


def write_card(path: Path, target: Target, result: dict, name: str | None = None) -> None:
    """The soil card: [soil] (chosen), [element], [target] (as given), [posterior], [[achieved]],
    [[verification]], [calibration]. A quick calibration's card says so in its name (NAME-quick)
    and header. Written only where no file is (a finished card is never replaced)."""
    t = target.raw["target"]
    name = name or target.name
    cal = result["calibration"]
    data = {
        "soil": {"name": name, "description": str(t.get("description", "")), **target.soil,
                 **result["chosen"]},
        "element": target.element,
        "target": {**t, "free": {k: list(v) for k, v in target.free.items()}},
        "posterior": result["posterior"],
        "achieved": result["achieved"],
        "verification": result["verification"],
        "calibration": cal,
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    head = (f"# Soil card {name}: written by `campaign calibrate {target.path.name}`. [soil] is what a campaign\n"
            f"# uses ([case] soil = \"{path.as_posix()}\"); the rest records how it was found (docs/soils.md).\n")
    if cal.get("quick"):
        head = (f"# QUICK CALIBRATION (--quick: {cal.get('runs', '?')} runs, {cal['budget'].get('samples')} samples, "
                f"{cal['budget'].get('seeds')} seed(s) each): a first look, NOT a calibrated soil;\n"
                "# run `campaign calibrate` without --quick for a card to use.\n") + head
    try:
        with open(path, "x") as f:
            f.write(head + tomli_w.dumps(_clean(data)))
    except FileExistsError:
        raise InputError(f"{path} appeared while the calibration ran; it is kept, the new card is not written",
                         where=str(path), fix="run again with -o NEW.toml: every run is reused") from None
    load_card(path)          # the card we wrote reads back
