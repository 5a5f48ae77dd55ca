"""The answer a user asks for: δ of a sand (a soil card) on a surface, at a stress and a density,
with two 95 % prediction intervals that own their errors (docs/answer.md).

    δ = atan(E · tan φ)
      E      the criterion θa → θr → E fitted on the card's own interface runs ([criterion] fit)
      tan φ  the card's own paired soil test (the box test E is divided by) at the asked normal
             stress and density ([criterion] strength: a table over stress × preparation)

The model's interval (`model_delta_deg_lo`/`_hi`) is what a simulation of this surface on this card
would read; its parts, each a 95 % half-width in degrees of δ, add in quadrature:
  fit       the seed-bootstrap interval of the fitted chain at this surface
  residual  the chain's error on surfaces its fits did not see (criterion.json `held_out`: the
            reproduction's held-out fold), t(n−1) · rms · √(1 + 1/n)
  tan φ     the soil test's own seed interval at this stress and density
The sand's interval (`delta_deg_lo`/`_hi`) adds the card's misfit against the laboratory records it
was not calibrated on ([[verification]] φ_peak, model − record), t(n−1) · rms · √(1 + 1/n) carried
into δ by ∂δ/∂φ. No data here bound the interface contact itself against a laboratory interface
test of this sand: the answer says so.

Density: a relative density is the preparation that makes it in the card's own cell test, read off
the card's verification records by least squares, preparation = a + b·Dr + c·ln(σ/100 kPa).
Units: stresses in Pa, angles in degrees, friction as a coefficient.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.card_state import LEVEL, ErrorScale, card_dimension, card_misfit, soil_state
from interphase.errors import InputError

#: tan φ above this is an angle given in degrees, not a tangent (tan 55° = 1.43: steeper than a dense
#: gravel at low stress; the next integer a user could mean in degrees, 1°, is no soil either)
MAX_TAN_PHI = 1.43


def held_out_units(held_out: dict) -> list[str]:
    """The units a held-out fold left out one at a time: groups ("group held out") or surfaces
    (θa > 92°, "surface held out")."""
    return [_unit(c, held_out["fold"]) for c in held_out["cases"]]


def _unit(case: dict, fold: str) -> str:
    return case["group"] if fold == "group held out" else f"θa {case['theta_a_deg_92']:.3f}"


#: E predicted at and above this is the plateau (the fit's E saturates near 1): the chain's error there
#: is a fraction of the rising branch's, so each branch's cases set its own scale (docs/answer.md)
PLATEAU_E = 0.95


def branch_of(e) -> str:
    """"plateau" for E predicted ≥ PLATEAU_E, else "rising" (None: rising)."""
    return "plateau" if e is not None and e >= PLATEAU_E else "rising"


def residual(held_out: dict | None, *, without: str | None = None, branch: str | None = None) -> ErrorScale:
    """The chain's held-out error scale (criterion.json `held_out`), on one branch ("rising": E
    predicted < PLATEAU_E, "plateau"; None: all), optionally without one unit (a group or a surface:
    `held_out_units`)."""
    if not held_out:
        return ErrorScale(0, math.nan, math.nan, "no held-out errors in the fit")
    cases = [c for c in held_out["cases"] if (without is None or _unit(c, held_out["fold"]) != without)
             and (branch is None or branch_of(c.get("E_predicted")) == branch)]
    return ErrorScale.of([c["error_deg"] for c in cases],
                         f"{held_out['fold']}, {len(cases)} cases" + (f" on the {branch} branch" if branch else ""))


def interval_coverage(held_out: dict, by_branch: bool = True) -> dict:
    """How often the residual part of the model's interval covers a case it did not see, nested: each
    unit's cases against the half-width from every other unit's errors (of the case's branch, with
    `by_branch`). Returns the share inside and the mean half-width [°], on all cases, the rising
    branch (E predicted < PLATEAU_E) and the plateau. The fit's and tan φ's parts only widen the
    interval, so the share is a lower bound of the whole interval's."""
    units = held_out_units(held_out)
    rows = []
    for case, unit in zip(held_out["cases"], units):
        b = branch_of(case.get("E_predicted"))
        h = residual(held_out, without=unit, branch=b if by_branch else None).half_width
        rows.append({"inside": abs(case["error_deg"]) <= h, "half_width": h, "branch": b})
    df = pd.DataFrame(rows)
    out = {"fold": held_out["fold"], "units": len(set(units)), "by_branch": by_branch}
    for name, part in (("all", df), ("rising", df[df["branch"] == "rising"]), ("plateau", df[df["branch"] == "plateau"])):
        out[name] = {"n": int(len(part)), "covered": float(part["inside"].mean()) if len(part) else math.nan,
                     "mean_half_width_deg": float(part["half_width"].mean()) if len(part) else math.nan}
    return out


# ---- the answer ------------------------------------------------------------------------------------
@dataclass
class Answer:
    """δ with its two intervals and every number it stands on (`to_dict` is `predict --json`)."""
    profile: str
    friction: float
    delta_deg: float
    model_delta_deg_lo: float
    model_delta_deg_hi: float
    delta_deg_lo: float
    delta_deg_hi: float
    parts_deg: dict              # 95 % half-widths in degrees of δ: fit, residual, tan_phi, card
    theta_a_deg: float
    theta_r_deg: float
    efficiency: float
    efficiency_lo: float
    efficiency_hi: float
    tan_phi: float
    phi_deg: float
    tan_delta: float
    branch: str
    d50_mm: float
    normal_stress: float | None
    relative_density: float | None
    preparation: float | None
    soil: str | None
    dimension: str | None
    fit: str
    fit_source: str
    runs: str
    domain: str
    theta_r_lo: float = math.nan
    theta_r_hi: float = math.nan
    theta_a_filter: int = 92          # 92: Fig. 6.8's branch, 90: flat-spaced (Fig. 6.9)
    flat_spaced: bool = False
    flat_spacing_reason: str = ""
    theta_a_deg_92: float = math.nan  # θa of both filters (NaN: non-dilative)
    theta_a_deg_90: float = math.nan
    mean_slope_deg: float = math.nan
    trace_share: float = math.nan     # an areal scan's line length under the pooled trace (NaN: a line)
    notes: list = field(default_factory=list)

    def to_dict(self) -> dict:
        return asdict(self)

    def paragraph(self) -> str:
        """The answer in one paragraph, to paste."""
        p = self.parts_deg
        parts = ", ".join(f"{k} ±{v:.2f}°" for k, v in p.items() if v is not None and math.isfinite(v))
        where = (f"{self.soil} ({self.dimension} card)" if self.soil else "no soil card")
        state = (f"at {self.normal_stress / 1e3:g} kPa" if self.normal_stress else "")
        if self.relative_density is not None:
            state += f", Dr {self.relative_density:.2f} (preparation {self.preparation:.3f})"
        sand = (f"; for the sand itself {self.delta_deg_lo:.1f}–{self.delta_deg_hi:.1f}°"
                if math.isfinite(self.delta_deg_lo) and (self.delta_deg_lo, self.delta_deg_hi) !=
                (self.model_delta_deg_lo, self.model_delta_deg_hi) else "")
        text = (f"δ = {self.delta_deg:.1f}° (95 % prediction interval of the model "
                f"{self.model_delta_deg_lo:.1f}–{self.model_delta_deg_hi:.1f}°{sand}) for {self.profile} "
                f"with {where} {state}, μ = tan φμ = {self.friction:g}: θa {self.theta_a_deg:.1f}° → θr "
                f"{self.theta_r_deg:.1f}° → E {self.efficiency:.3f} ({self.branch}), tan φ {self.tan_phi:.3f} "
                f"(φ {self.phi_deg:.1f}°). Interval parts (95 % half-widths, added in quadrature): {parts}. "
                f"Fit: {self.fit_source.split(' (')[0]}, {self.runs}. Holds in: {self.domain}.")
        return "\n".join([text, *(f"note: {n}" for n in self.notes)])


def _deg(t: float) -> float:
    return math.degrees(math.atan(t)) if math.isfinite(t) else math.nan


def _quad(*h) -> float:
    vals = [x for x in h if x is not None and math.isfinite(x)]
    return math.sqrt(sum(x * x for x in vals)) if vals else math.nan


def check_tan_phi(tan_phi, where: str = "--tan-phi") -> None:
    if tan_phi is None:
        return
    if not (isinstance(tan_phi, (int, float)) and math.isfinite(tan_phi) and tan_phi > 0):
        raise InputError(f"must be a tangent > 0, got {tan_phi!r}", where=where, fix="e.g. 0.70 for φ 35°")
    if tan_phi > MAX_TAN_PHI:
        raise InputError(f"{tan_phi:g} is a tangent of {_deg(tan_phi):.1f}°: steeper than any sand; an angle in degrees?",
                         where=where, fix=f"give the tangent: tan {tan_phi:g}° = {math.tan(math.radians(tan_phi)):.3f}"
                         if tan_phi < 90 else "give tan φ, e.g. 0.70 for φ 35°")


def friction_from(friction, smooth_delta_deg) -> float:
    """μ = tan φμ from `friction` or from δ on a smooth plate of the surface's material [°] (a
    laboratory's interface test on a polished plate: no asperity to climb, so tan δ = μ)."""
    if (friction is None) == (smooth_delta_deg is None):
        raise InputError("give the particle–surface friction once", where="--friction",
                         fix="--friction MU (tan φμ), or --smooth-delta DEG (δ of the sand on a smooth plate of the "
                             "same material)")
    if smooth_delta_deg is not None:
        if not (isinstance(smooth_delta_deg, (int, float)) and 0 <= smooth_delta_deg < 60):
            raise InputError(f"must be an angle in degrees in [0, 60), got {smooth_delta_deg!r}", where="--smooth-delta",
                             fix="e.g. 12 for δ 12° on a smooth steel plate")
        return math.tan(math.radians(smooth_delta_deg))
    if not (isinstance(friction, (int, float)) and math.isfinite(friction) and friction >= 0):
        raise InputError(f"must be a friction coefficient ≥ 0, got {friction!r}", where="--friction")
    if friction > 1.5:
        raise InputError(f"friction {friction:g} is tan of {_deg(friction):.1f}°: an angle in degrees?", where="--friction",
                         fix=f"give the coefficient: tan {friction:g}° = {math.tan(math.radians(friction)):.3f}, "
                             "or --smooth-delta DEG" if friction < 90 else "give μ = tan φμ, e.g. 0.3")
    return float(friction)


#: a profile sampled coarser than this share of D50 has valleys a grain feels between its samples
MAX_STEP_D50 = 0.5


def _read_surface(profile, units, d50: float, notes: list):
    """The scan as read, refusing one sampled too coarsely for the grains; its length and relief in notes
    (so a µm file read as mm shows)."""
    from interphase.surface.readers import TEXT_READER, read_scan

    scan = read_scan(str(profile), units)
    x, z = (np.asarray(a, float) for a in scan.lines("x"))
    step = float(np.median(np.diff(x))) if x.size > 1 else math.nan
    relief = float(np.nanmax(z) - np.nanmin(z)) if np.isfinite(z).any() else math.nan
    notes.append(f"surface read ({'units ' + units if units else 'the file’s own units'}): {1e3 * (x.max() - x.min()):.3g} mm "
                 f"long, relief {1e3 * relief:.3g} mm, sampled every {1e6 * step:.3g} µm ({step / d50:.2f} D50)"
                 + (" per line" if scan.areal else ""))
    coarse = math.isfinite(step) and step > MAX_STEP_D50 * d50
    if coarse and scan.reader == TEXT_READER:       # two columns: a polyline's vertices, exact between them
        notes.append(f"points {step / d50:.2f} D50 apart: read as a polyline's vertices (straight between them); "
                     "if they are measured samples, the valleys between them are unseen")
    elif coarse:
        raise InputError(f"sampled every {1e3 * step:.3g} mm, {step / d50:.2f} D50: a valley narrower than a grain lies "
                         f"unseen between samples (the centroid trace needs steps ≤ {MAX_STEP_D50:g} D50)",
                         where=str(profile), fix="measure or export the profile finer, or check --units "
                         f"(read as {units or 'the file’s own'})")
    return scan


def predict(profile, *, friction: float | None = None, smooth_delta_deg: float | None = None, soil=None,
            fit: str | None = None, d50: float | None = None, tan_phi: float | None = None,
            normal_stress: float | None = None, relative_density: float | None = None, units: str | None = None,
            axis: str | None = None, filt: int | None = None) -> Answer:
    """δ for a surface (line profile or areal scan) on a soil card at a stress [Pa] and relative
    density, or with `fit` ('study', 'study-figures', a criterion.json or a campaign file) on a
    simulated soil of grain size `d50` [m]. Every refusal is an InputError naming the option."""
    from interphase.analysis.criterion import OutOfFitRange, predict_measured
    from interphase.criterion_fits import criterion_model

    mu = friction_from(friction, smooth_delta_deg)
    check_tan_phi(tan_phi)
    notes: list[str] = []
    if soil is None and fit is None:
        raise InputError("no soil named: whose grains answer?", where="--soil",
                         fix="give --soil CARD (your sand's card, e.g. soils/karlsruhe-fine-sand.toml), or --fit study "
                             "(the study's simulated discs) with --d50")
    if soil is not None and fit is not None:
        raise InputError("a soil card names its own fit", where="--fit", fix="give --soil CARD or --fit, not both")
    if soil is not None:
        card = load_soil(soil)
        if tan_phi is not None:
            raise InputError("the card's own soil test gives tan φ", where="--tan-phi",
                             fix="drop --tan-phi (the card is your sand), or use --fit without --soil")
        from interphase.soil import card_d50_mm, criterion_fit

        fit_path = str(criterion_fit(card))
        d50 = card_d50_mm(card, None if d50 is None else d50 * 1e3, "its fit is of that soil") * 1e-3
        model = criterion_model(mu, fit_path)
        state = soil_state(card, model, normal_stress, relative_density)
    else:
        card, fit_path = None, fit
        if normal_stress is not None or relative_density is not None:
            raise InputError("a fit alone has no soil tests at other stresses or densities: the option would be ignored",
                             where="--normal-stress" if normal_stress is not None else "--relative-density",
                             fix="give --soil CARD, whose soil tests measured them, or drop the option")
        if d50 is None:             # a given one is checked by the API (interphase.api.checks.d50)
            raise InputError("no grain size given", where="--d50",
                             fix="give --d50 MM (the grains' median diameter), or --soil CARD")
        model = criterion_model(mu, fit_path, tan_phi)
        state = {"tan_phi": model.tan_phi, "half": math.nan, "stress": None, "preparation": None, "dr": None,
                 "source": "given (--tan-phi)" if tan_phi is not None else f"the fit's simulated soil ({model.source})",
                 "domain": "the fit's soil test only"}
    scan = _read_surface(profile, units, d50, notes)
    try:
        res = predict_measured(model, scan, d50, mu, axis, filt, where="--axis")
    except OutOfFitRange as exc:
        if card is None or scan.areal:          # --simulate takes a card and one line, not a scan
            raise
        raise InputError(exc.message, where=exc.where, fix=f"{exc.fix}, or add --simulate to run the DEM on this "
                         "profile with the card's grains") from exc
    if scan.areal:
        _check_trace_share(res.trace_share, profile, axis or "x")
        notes.append(f"θa rests on {100 * res.trace_share:.0f} % of the scan's line length along {axis or 'x'}")
    return _answer(profile, mu, card, fit_path, model, state, res, d50, notes)


#: below this share of a scan's line length under the centroid trace, θa speaks for a small part of the scan
MIN_TRACE_SHARE = 0.5


def _check_trace_share(share: float, profile, axis: str) -> None:
    """Refuse an areal θa resting on less than MIN_TRACE_SHARE of the scan's lines: missing points, runs
    shorter than MIN_RUN_D50 D50 (dropped) and the grain's half-width at each run's ends leave the rest unseen."""
    from interphase.surface.areal import MIN_RUN_D50

    if math.isfinite(share) and share < MIN_TRACE_SHARE:
        raise InputError(f"θa would rest on {100 * share:.0f} % of the scan's line length along {axis} (at least "
                         f"{100 * MIN_TRACE_SHARE:.0f} % needed): the rest is missing points, runs shorter than "
                         f"{MIN_RUN_D50:g} D50, or run ends", where=str(profile),
                         fix="crop the scan to its measured area or fill its missing points, or give --axis "
                             f"{'y' if axis == 'x' else 'x'} if its lines hold more")


def load_soil(soil):
    """A soil card by path, or by name from the shipped soils/ (the 3D card by the sand's plain name)."""
    from interphase.soil import load_card

    p = Path(soil)
    if not p.exists() and not p.suffix:
        shipped = Path(__file__).resolve().parents[2] / "soils" / f"{soil}.toml"
        p = shipped if shipped.exists() else p
    return load_card(p)


def _answer(profile, mu, card, fit_path, model, state, res, d50, notes) -> Answer:
    """δ at the state's tan φ with its interval parts (module docstring)."""
    p = res.prediction
    tp = state["tan_phi"]
    flat = p.branch == "non-dilative"
    bound = min(mu, tp)
    td = bound if flat else max(p.efficiency * tp, bound)
    e = td / tp
    e_lo, e_hi = p.efficiency_interval
    deg_at = lambda E: _deg(max(E * tp, bound)) if math.isfinite(E) else math.nan
    delta = _deg(td)
    fit_half = (deg_at(e_hi) - deg_at(e_lo)) / 2 if math.isfinite(e_lo) and math.isfinite(e_hi) else math.nan
    scale = residual(model.held_out, branch=branch_of(e))
    slope = e / (1 + (e * tp) ** 2) * (1 + tp * tp)        # ∂δ/∂φ of δ = atan(E tan φ)
    tan_half = math.degrees(slope * state["half"] / (1 + tp * tp)) if math.isfinite(state["half"]) else math.nan
    misfit = card_misfit(card) if card is not None else None
    card_half = slope * misfit.half_width if misfit is not None and misfit.n >= 2 else math.nan
    parts = {"fit": fit_half, "residual": scale.half_width, "tan_phi": tan_half}
    h_model = _quad(*parts.values())
    h_sand = _quad(h_model, card_half) if card is not None else h_model    # no card: the soil is the fit's
    parts["card"] = card_half
    if not math.isfinite(scale.half_width):
        notes.append("the fit holds no held-out errors: the model's interval is the fit's bootstrap alone")
    if card is not None:
        notes.append(f"the sand's interval adds the card's misfit against its held-out records ({misfit.what}: bias "
                     f"{misfit.bias:+.2f}°, rms {misfit.rms:.2f}°); the grain–surface contact itself has never been "
                     "checked against a laboratory interface test of this sand, and no interval here bounds that")
        if card_dimension(card) == "quasi-2D":
            notes.append("a quasi-2D card: one layer of discs; where the sand has a 3D card, that one answers")
    if card is None:
        notes.append("no soil card: the soil is the fit's simulated one, so no laboratory misfit widens the interval")
    notes.append(f"tan φ from {state['source']}; E as fitted on the card's runs at their one stress and density "
                 "(whether E moves with them: studies/stress_density/README.md)" if card is not None
                 else f"tan φ from {state['source']}")
    notes += p.notes
    from interphase.analysis.criterion import coverage as fit_coverage

    dom = f"μ and θa as the fit covers ({fit_coverage(model)}); {state['domain']}"
    clip = lambda v: max(v, 0.0) if math.isfinite(v) else v
    return Answer(profile=str(profile), friction=mu, delta_deg=delta,
                  model_delta_deg_lo=clip(delta - h_model), model_delta_deg_hi=delta + h_model,
                  delta_deg_lo=clip(delta - h_sand), delta_deg_hi=delta + h_sand, parts_deg=parts,
                  theta_a_deg=p.theta_a_deg, theta_r_deg=p.theta_r_deg, efficiency=e,
                  efficiency_lo=e_lo, efficiency_hi=e_hi, tan_phi=tp, phi_deg=_deg(tp), tan_delta=td,
                  branch=p.branch, d50_mm=d50 * 1e3, normal_stress=state["stress"],
                  relative_density=state["dr"], preparation=state["preparation"],
                  soil=str(card.path) if card is not None else None,
                  dimension=card_dimension(card) if card is not None else None,
                  fit=str(fit_path), fit_source=model.source, runs=_runs_of(model), domain=dom,
                  theta_r_lo=p.theta_r_interval[0], theta_r_hi=p.theta_r_interval[1], theta_a_filter=p.filter,
                  flat_spaced=res.flat_spaced, flat_spacing_reason=res.flat_spacing_reason,
                  theta_a_deg_92=res.theta_a_deg_92, theta_a_deg_90=res.theta_a_deg_90,
                  mean_slope_deg=res.mean_slope_deg, trace_share=res.trace_share, notes=notes)


def _runs_of(model) -> str:
    """What the fit stands on, in words (criterion.json `about`)."""
    a = model.about or {}
    if not a:
        return "the study's figures" if model.is_default else "unknown"
    return (f"{a.get('interface_runs', '?')} interface runs over {a.get('physical_cases', '?')} physical cases "
            f"(groups {', '.join(a.get('groups', []))}), μs {', '.join(f'{m:g}' for m in a.get('frictions', []))}")
