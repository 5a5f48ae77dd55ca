"""The failure criterion (seed §6.4.3–6.4.5, docs/methods.md §7): profile → θa → θr → E → tan δ.

Chain, as the study prescribes (§6.4.4):
  * most surfaces: θa with the > 92° filter, θr from the θa–θr correlation (Fig. 6.8, the fit of the
    case's particle–surface friction if the campaign has it, else the pooled fit);
  * surfaces with regular flat spacing between asperities (Group 2 kind): θa with the ≥ 90° filter,
    θr = (θr/θa)·θa from the Fig. 6.9 correlation (x axis: θa counterclockwise from +x);
  * non-dilative surface (θa undefined): θa = 0, i.e. the correlation's vertical-axis intercept
    (≈ φμ, §6.4.3);
  * E from the E–θr correlation (Fig. 6.10a); tan δ = E·tan φ, tan φ of the granular material alone.
All angles are ψ, degrees from vertical, unless a name says ccw.

STUDY DEFAULTS (used when no campaign has been fitted) are approximate readings of the published
figures, not fits — the output says "study defaults" wherever they are used:
  θr(θa) = φμ + (35° − φμ)·θa/40°  for θa ≤ 40°;  35° + 0.5·(θa − 40°) beyond   (Fig. 6.8: intercept
           ≈ φμ, slope falling with friction up to the ~40° breakpoint, one common line above it)
  θr/θa  = 0.5 + 0.5·min(θa,ccw − 95°, 35°)/35° for flat-spaced surfaces (Fig. 6.9; coarse reading)
  E(θr)  = tan(min(θr, 30°)) / tan φ (Fig. 6.10a: full mobilisation beyond θr ≈ 30°; at θr = φμ this
           is tan φμ / tan φ, the non-dilative answer)
  tan φ  = tan 30° unless given (an assumption: the study does not print its box friction angle)
  fitted θa range 0–60°.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from interphase.analysis.correlations import SPECS, FitError, fit_bilinear, of_gradation, subset
from interphase.errors import InputError

DEFAULT_PHI_DEG = 30.0
FULL_MOBILISATION_DEG = 30.0
STUDY_DEFAULT_RANGE = (0.0, 60.0)
FLAT_TILT_DEG = 2.0          # a raw-profile segment flatter than this is "flat" (the 92° filter's 2°)
MIN_FLAT_SHARE = 0.10        # flats must cover ≥ 10 % of the length …
MAX_FLAT_CV = 0.25           # … in runs of nearly equal length (coefficient of variation)


CRITERION_SCHEMA = "interphase-dem criterion 1"


def _finite(d: dict) -> dict:
    """NaN → None (strict JSON)."""
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in d.items()}


class _Curve:
    """A default correlation: predict(x) plus no interval."""

    def __init__(self, fn, name: str):
        self._fn = fn
        self.name = name
        self.x_range = STUDY_DEFAULT_RANGE

    def predict(self, x):
        return self._fn(np.asarray(x, dtype=float))

    def predict_interval(self, x):
        return (math.nan, math.nan)


def default_theta_r(friction: float) -> _Curve:
    phi_mu = math.degrees(math.atan(friction))

    def fn(a):
        return np.where(a <= 40.0, phi_mu + (35.0 - phi_mu) * a / 40.0, 35.0 + 0.5 * (a - 40.0))
    return _Curve(fn, f"study default θr(θa), φμ = {phi_mu:.2f}°")


def default_ratio() -> _Curve:
    c = _Curve(lambda a: 0.5 + 0.5 * np.clip(a - 95.0, 0.0, 35.0) / 35.0, "study default θr/θa(θa ccw)")
    c.x_range = (STUDY_DEFAULT_RANGE[0] + 90.0, STUDY_DEFAULT_RANGE[1] + 90.0)   # its x is θa ccw
    return c


def default_efficiency(tan_phi: float) -> _Curve:
    return _Curve(lambda r: np.tan(np.radians(np.clip(r, 0.0, FULL_MOBILISATION_DEG))) / tan_phi,
                  "study default E(θr) = tan min(θr, 30°) / tan φ")


@dataclass
class CriterionModel:
    """The three correlations of the chain plus tan φ. Fits are BilinearFit (campaign) or defaults."""
    source: str                                   # "study defaults" | "campaign NAME"
    tan_phi: float
    theta_r: dict = field(default_factory=dict)   # friction (float) or "all" → fit of θr vs θa (> 92°)
    ratio: object | None = None                   # θr/θa vs θa ccw (≥ 90°), flat-spaced
    efficiency: object | None = None              # E vs θr
    reasons: dict = field(default_factory=dict)   # why a correlation is missing
    is_default: bool = False
    rule: tuple | None = None    # (a [°], b) of δ = min(φμ + θa − a, atan(b tan φ)) fitted on the same cases (fit_rule)
    held_out: dict | None = None  # the chain's error on cases its fits did not see (held_out_errors)
    about: dict = field(default_factory=dict)    # what the fits stand on (criterion.json about)

    @classmethod
    def study_defaults(cls, friction: float, tan_phi: float | None = None) -> "CriterionModel":
        tp = math.tan(math.radians(DEFAULT_PHI_DEG)) if tan_phi is None else tan_phi
        return cls(source="study defaults", tan_phi=tp, theta_r={friction: default_theta_r(friction)},
                   ratio=default_ratio(), efficiency=default_efficiency(tp), is_default=True)

    def to_dict(self, about: dict | None = None) -> dict:
        """JSON data of a FITTED model (every fit with its bootstrap refits, so intervals survive):
        what `campaign report` writes as criterion.json and `campaign predict` reads back."""
        if self.is_default:
            raise ValueError("the study defaults are readings, not fits: nothing to write")

        def fit(f):
            if f is None:
                return None
            boots = np.asarray(f.extra.get("boot_params", np.empty((0, 0))), float)
            return _finite(f.to_dict()) | {"boot_params": np.round(boots, 6).tolist()}

        return {"schema": CRITERION_SCHEMA, "source": self.source, "about": about or {},
                "tan_phi": self.tan_phi if math.isfinite(self.tan_phi) else None,
                "theta_r": {str(k): fit(f) for k, f in self.theta_r.items()},
                "ratio": fit(self.ratio), "efficiency": fit(self.efficiency), "reasons": dict(self.reasons),
                "rule": _finite({"a_deg": self.rule[0], "b": self.rule[1]}) if self.rule else None,
                "held_out": self.held_out}

    @classmethod
    def from_dict(cls, d: dict, where: str = "criterion.json") -> "CriterionModel":
        from interphase.analysis.correlations import BilinearFit

        if d.get("schema") != CRITERION_SCHEMA:
            raise InputError(f"not a criterion file of this version (schema {d.get('schema')!r}, expected "
                             f"{CRITERION_SCHEMA!r})", where=where, fix="write it again with `campaign report`")

        def fit(x):
            if x is None:
                return None
            f = BilinearFit.from_dict({k: (math.nan if v is None else v) for k, v in x.items() if k != "boot_params"})
            f.extra["boot_params"] = np.asarray(x.get("boot_params") or [], float)
            return f

        return cls(source=d["source"], tan_phi=math.nan if d.get("tan_phi") is None else float(d["tan_phi"]),
                   theta_r={("all" if k == "all" else float(k)): fit(v) for k, v in d["theta_r"].items()},
                   ratio=fit(d.get("ratio")), efficiency=fit(d.get("efficiency")), reasons=d.get("reasons", {}),
                   rule=_rule_of(d.get("rule")), held_out=d.get("held_out"), about=d.get("about") or {})

    @classmethod
    def from_points(cls, points: pd.DataFrame, source: str, *, n_boot: int = 199, seed: int = 0) -> "CriterionModel":
        """Fit the chain's correlations on a points table (correlations.prepare_points)."""
        reasons: dict = {}

        def fit(spec_key, df):
            spec = SPECS[spec_key]
            try:
                return fit_bilinear(pd.to_numeric(df[spec.x], errors="coerce"), pd.to_numeric(df[spec.y], errors="coerce"),
                                    spec.model, n_boot=n_boot, seed=seed)
            except FitError as exc:
                reasons[spec_key] = str(exc)
                return None

        tr: dict = {}
        pts8 = subset(points, SPECS["fig6_8"])
        tr["all"] = fit("fig6_8", pts8)
        for mu, g in pts8.groupby("friction_ps"):
            f = fit("fig6_8", g)
            if f is not None:
                tr[float(mu)] = f
        reasons.pop("fig6_8", None) if tr["all"] is not None else None
        return cls(source=source, tan_phi=fitted_soil_tan_phi(points),
                   theta_r={k: v for k, v in tr.items() if v is not None},
                   ratio=fit("fig6_9", subset(points, SPECS["fig6_9"])),
                   efficiency=fit("fig6_10a", points), reasons=reasons)


def fitted_soil_tan_phi(points: pd.DataFrame) -> float:
    """tan φ [-] of the soil the θa–θr fit (Fig. 6.8) was made on: the median over the points of its
    gradation (the well-graded one when both ran); NaN without a finished soil test."""
    soil = of_gradation(points, SPECS["fig6_8"].gradation)
    tp = pd.to_numeric(soil.get("tan_phi", pd.Series(dtype=float)), errors="coerce").dropna()
    return float(tp.median()) if len(tp) else math.nan


def regular_flat_spacing(x, z, d50: float) -> tuple[bool, str]:
    """Does a raw profile (x, z in m) have regular flat spacing between asperities (Group-2 kind)?
    Rule (the project's; the study only says "regular horizontal spacing"): segments tilted < 2° are
    flat; flats joined into runs, runs shorter than 0.1·D50 ignored; regular when the runs cover
    ≥ 10 % of the length, there are ≥ 2 interior runs (the end runs are cut by the profile) and their
    lengths vary by ≤ 25 % (coefficient of variation)."""
    x = np.asarray(x, float)
    z = np.asarray(z, float)
    dx, dz = np.diff(x), np.diff(z)
    flat = np.abs(np.degrees(np.arctan2(dz, dx))) < FLAT_TILT_DEG
    if not flat.any():
        return False, "no flat segments"
    edges = np.diff(np.concatenate([[0], flat.astype(int), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    csum = np.concatenate([[0.0], np.cumsum(dx)])
    runs = csum[ends] - csum[starts]
    interior = (starts > 0) & (ends < flat.size)
    runs_i = runs[interior & (runs >= 0.1 * d50)]
    share = runs[runs >= 0.1 * d50].sum() / max(csum[-1], 1e-300)
    if share < MIN_FLAT_SHARE:
        return False, f"flats cover {share:.0%} of the length (< {MIN_FLAT_SHARE:.0%})"
    if runs_i.size < 2:
        return False, "fewer than two interior flat runs"
    cv = float(runs_i.std() / runs_i.mean())
    if cv > MAX_FLAT_CV:
        return False, f"flat runs irregular (length CV {cv:.2f} > {MAX_FLAT_CV})"
    return True, f"{runs_i.size} flat runs of {runs_i.mean() / d50:.2g}·D50 (CV {cv:.2f}), {share:.0%} of the length"


@dataclass
class Prediction:
    source: str
    branch: str                   # "dilative (Fig. 6.8)" | "flat-spaced (Fig. 6.9)" | "non-dilative"
    filter: int
    theta_a_deg: float            # ψ used in the chain (0 for non-dilative)
    theta_a_ccw_deg: float
    theta_r_deg: float
    theta_r_interval: tuple
    efficiency: float
    efficiency_interval: tuple
    tan_phi: float
    tan_delta: float
    tan_delta_interval: tuple
    delta_deg: float
    delta_interval_deg: tuple
    friction: float
    notes: list

    def to_dict(self) -> dict:
        d = self.__dict__.copy()
        for k in ("theta_r_interval", "efficiency_interval", "tan_delta_interval", "delta_interval_deg"):
            d[k] = list(d[k])
        return d


class _Blend:
    """θr(θa) between the fits of two bracketing frictions, linear in φμ = atan(μ) — the intercept
    ≈ φμ and the slope falls steadily with friction (Fig. 6.8), so interpolating both is the least
    assumption."""

    def __init__(self, f_lo, f_hi, w: float):
        self.f_lo, self.f_hi, self.w = f_lo, f_hi, w
        self.x_range = (max(f_lo.x_range[0], f_hi.x_range[0]), min(f_lo.x_range[1], f_hi.x_range[1]))

    def predict(self, x):
        return (1 - self.w) * self.f_lo.predict(x) + self.w * self.f_hi.predict(x)

    def predict_interval(self, x):
        a, b = self.f_lo.predict_interval(x), self.f_hi.predict_interval(x)
        return ((1 - self.w) * a[0] + self.w * b[0], (1 - self.w) * a[1] + self.w * b[1])


def fitted_frictions(model: CriterionModel) -> list[float]:
    """The particle–surface frictions the model's θa–θr fits were made at (empty: the study's
    readings, or only a pooled fit)."""
    return sorted(float(k) for k in model.theta_r if k != "all") if not model.is_default else []


def coverage(model: CriterionModel) -> str:
    """What a model's fits cover, in words: the frictions and the θa ranges of each branch."""
    parts = []
    mus = fitted_frictions(model)
    if mus:
        parts.append(f"frictions {mus[0]:g}–{mus[-1]:g} (fitted at {', '.join(f'{m:g}' for m in mus)})")
    fits = [f for f in model.theta_r.values() if f is not None]
    if fits:
        lo, hi = max(f.x_range[0] for f in fits), min(f.x_range[1] for f in fits)
        parts.append(f"θa {lo:.1f}–{hi:.1f}° (> 92° filter)")
    if model.ratio is not None:
        lo, hi = model.ratio.x_range
        parts.append(f"θa {lo - 90:.1f}–{hi - 90:.1f}° on flat-spaced surfaces (≥ 90° filter)")
    return ", ".join(parts) or "nothing"


def _check_friction(model: CriterionModel, friction: float) -> None:
    """Refuse a friction outside the fitted ones: the intercept ≈ φμ and the slope of θr(θa) move
    with friction (Fig. 6.8), and nothing in the data says how they go on beyond the last fit."""
    mus = fitted_frictions(model)
    if mus and not (mus[0] - 1e-9 <= friction <= mus[-1] + 1e-9):
        raise InputError(f"friction {friction:g} is outside what the fits of {model.source} cover: {coverage(model)}",
                         where="--friction", fix=f"give a friction within {mus[0]:g}–{mus[-1]:g}, fit a campaign that "
                         "covers it (--fit), or `--fit study-figures` (the study's readings, any friction)")


def _pick_theta_r(model: CriterionModel, friction: float, notes: list):
    per = {float(k): f for k, f in model.theta_r.items() if k != "all"}
    for k, f in per.items():
        if abs(k - friction) <= 1e-9:
            return f
    below = [k for k in per if k < friction]
    above = [k for k in per if k > friction]
    if below and above:
        lo, hi = max(below), min(above)
        w = (math.atan(friction) - math.atan(lo)) / (math.atan(hi) - math.atan(lo))
        notes.append(f"no θa–θr fit for friction {friction:g}: interpolated between the fits for {lo:g} and {hi:g} "
                     "(linear in φμ)")
        return _Blend(per[lo], per[hi], w)
    if "all" in model.theta_r and not per:
        notes.append(f"no θa–θr fit per friction: the pooled fit (all frictions) is used for {friction:g}")
        return model.theta_r["all"]
    raise InputError(f"no θa–θr correlation in {model.source}: " + model.reasons.get("fig6_8", "no data"),
                     where="--fit", fix="run more cases, or `--fit study-figures` for the study's readings")


class OutOfFitRange(InputError):
    """A surface whose θa lies outside the fitted range (the correlation would be extrapolated)."""


def _check_range(fit, value: float, what: str, model: CriterionModel) -> None:
    lo, hi = fit.x_range
    tol = 1e-9 * max(1.0, abs(hi - lo))
    if not (lo - tol <= value <= hi + tol):
        raise OutOfFitRange(f"{what} = {value:.2f}° is outside the fitted range {lo:.2f}–{hi:.2f}° of {model.source} "
                         f"(the fits cover {coverage(model)})", where="PROFILE",
                         fix="the correlation would be extrapolated; fit a campaign that covers it")


def _theta_r(model: CriterionModel, friction: float, theta_a_92: float, theta_a_90: float, use90: bool,
             notes: list) -> tuple:
    """(θr, its interval, branch, θa used, filter) of the chain's first two steps."""
    if use90 and math.isfinite(theta_a_90) and theta_a_90 > 0:
        if model.ratio is None:
            raise InputError("no flat-spaced (Fig. 6.9) correlation in " + model.source + ": "
                             + model.reasons.get("fig6_9", "no data"), where="--fit",
                             fix="use --filter 92, or fit a campaign with Group 2 surfaces")
        a_ccw = theta_a_90 + 90.0
        _check_range(model.ratio, a_ccw, "θa (≥ 90°, ccw)", model)
        ratio = float(model.ratio.predict(a_ccw))
        r_lo, r_hi = model.ratio.predict_interval(a_ccw)
        return ratio * theta_a_90, (r_lo * theta_a_90, r_hi * theta_a_90), "flat-spaced (Fig. 6.9)", theta_a_90, 90
    a, branch = theta_a_92, "dilative (Fig. 6.8)"
    if not math.isfinite(a):
        a, branch = 0.0, "non-dilative"
        notes.append("θa undefined (non-dilative): θa = 0, the θa–θr intercept ≈ φμ")
    fit = _pick_theta_r(model, friction, notes)
    _check_range(fit, a, "θa (> 92°)", model)
    return float(fit.predict(a)), tuple(fit.predict_interval(a)), branch, a, 92


def _efficiency(model: CriterionModel, theta_r: float, tr_iv) -> tuple[float, tuple]:
    """(E, its interval) from the E–θr fit at θr and at the ends of θr's interval."""
    if model.efficiency is None:
        raise InputError("no E–θr correlation in " + model.source + ": " + model.reasons.get("fig6_10a", "no data"),
                         where="--fit", fix="the campaign needs box tests paired with its interface cases")
    e = float(model.efficiency.predict(theta_r))
    cands = [model.efficiency.predict_interval(t) for t in (theta_r, *tr_iv) if math.isfinite(t)]
    lo = [c[0] for c in cands if math.isfinite(c[0])]
    hi = [c[1] for c in cands if math.isfinite(c[1])]
    return e, ((min(lo), max(hi)) if lo and hi else (math.nan, math.nan))


def _bounded(tan_delta: float, iv: tuple, friction: float, tan_phi: float, flat: bool, notes: list) -> tuple:
    """tan δ and its interval held to what the physics allows. The flat-surface value is
    tan δ_flat = min(μ, tan φ): on a flat every contact has |ft| ≤ μ fn, so ΣFt ≤ μ ΣFn (Coulomb),
    and the study's non-dilative systems slide at φμ where μ < tan φ (where μ ≥ tan φ the soil
    fails first, at φ). On a flat the prediction IS that value (its interval: the fit's lower end
    below, the bound above); on any other surface it is never below it, so that δ is monotone in μ
    wherever the fits are and rough never predicts less than smooth."""
    bound = min(friction, tan_phi)
    deg = lambda t: math.degrees(math.atan(t))
    if flat:
        if abs(tan_delta - bound) > 1e-12:
            notes.append(f"flat (non-dilative): δ = min(φμ, φ) = {deg(bound):.2f}° (Coulomb: ΣFt ≤ μ ΣFn; the "
                         f"study's non-dilative systems slide at φμ); the fitted E–θr gave {deg(tan_delta):.2f}°")
        lo = min(iv[0], bound) if math.isfinite(iv[0]) else math.nan
        return bound, (lo, bound if math.isfinite(iv[1]) else math.nan)
    if tan_delta < bound:
        notes.append(f"the chain gave δ {deg(tan_delta):.2f}°, below the flat-surface value min(φμ, φ) = "
                     f"{deg(bound):.2f}°: the flat-surface value is given (a rough surface grips no less)")
    clip = lambda t: max(t, bound) if math.isfinite(t) else t
    return max(tan_delta, bound), (clip(iv[0]), clip(iv[1]))


def predict(model: CriterionModel, friction: float, theta_a_92: float, theta_a_90: float,
            flat_spaced: bool = False, filt: int | None = None) -> Prediction:
    """Run the chain. θa in ψ degrees (NaN: non-dilative). `filt` forces the branch (92: Fig. 6.8,
    90: Fig. 6.9); None chooses it from `flat_spaced` as the study does. A friction or θa outside
    what the fits cover is refused (InputError naming the covered range); tan δ is held to the
    flat-surface value (`_bounded`)."""
    if not (math.isfinite(friction) and friction >= 0):
        raise InputError(f"must be a friction coefficient ≥ 0, got {friction!r}", where="--friction")
    notes: list = []
    use90 = (filt == 90) if filt is not None else flat_spaced
    if model.is_default:
        notes.append("STUDY DEFAULTS: approximate readings of the study's published figures, not fits")
    _check_friction(model, friction)
    theta_r, tr_iv, branch, a_used, f_used = _theta_r(model, friction, theta_a_92, theta_a_90, use90, notes)
    e, e_iv = _efficiency(model, theta_r, tr_iv)
    tp = model.tan_phi
    td, td_iv = _bounded(e * tp, (e_iv[0] * tp, e_iv[1] * tp), friction, tp, branch == "non-dilative", notes)
    e, e_iv = td / tp, (td_iv[0] / tp, td_iv[1] / tp)
    deg = lambda t: math.degrees(math.atan(t)) if math.isfinite(t) else math.nan
    return Prediction(source=model.source, branch=branch, filter=f_used, theta_a_deg=a_used,
                      theta_a_ccw_deg=a_used + 90.0, theta_r_deg=theta_r, theta_r_interval=tuple(tr_iv),
                      efficiency=e, efficiency_interval=e_iv, tan_phi=tp, tan_delta=td, tan_delta_interval=td_iv,
                      delta_deg=deg(td), delta_interval_deg=(deg(td_iv[0]), deg(td_iv[1])), friction=friction,
                      notes=notes)


@dataclass
class ProfilePrediction:
    """The chain run on a profile: the Prediction with the profile quantities that chose its branch."""
    prediction: Prediction
    theta_a_deg_92: float         # ψ, NaN when non-dilative
    theta_a_deg_90: float
    mean_slope_deg: float
    flat_spaced: bool
    flat_spacing_reason: str
    trace_share: float = math.nan  # an areal scan's line length under the pooled trace (NaN for a line)

    def to_dict(self) -> dict:
        """JSON data of `campaign predict` (and `ip.predict`): the prediction, δ's interval [°] also
        as delta_deg_lo/_hi, and the profile quantities."""
        lo, hi = self.prediction.delta_interval_deg
        return self.prediction.to_dict() | {
            "delta_deg_lo": lo, "delta_deg_hi": hi,
            "flat_spaced": self.flat_spaced, "flat_spacing_reason": self.flat_spacing_reason,
            "theta_a_deg_92": self.theta_a_deg_92, "theta_a_deg_90": self.theta_a_deg_90,
            "mean_slope_deg": self.mean_slope_deg, "trace_share": self.trace_share}


def predict_profile(model: CriterionModel, profile, d50: float, friction: float,
                    filt: int | None = None) -> ProfilePrediction:
    """Profile [m] → θa (both filters) → flat spacing → `predict`, for grains of median diameter
    d50 [m] on a surface of particle–surface friction `friction` (tan φμ)."""
    from interphase.surface.normals import theta_a_filters

    t = theta_a_filters(profile, d50, (92, 90))
    flat_spaced, why = regular_flat_spacing(profile.x, profile.z, d50)
    p = predict(model, friction, t[92].theta_a_deg, t[90].theta_a_deg, flat_spaced, filt)
    return ProfilePrediction(p, t[92].theta_a_deg, t[90].theta_a_deg, t[92].mean_slope_deg, flat_spaced, why)


def predict_scan(model: CriterionModel, scan, d50: float, friction: float, axis: str = "x",
                 filt: int | None = None) -> ProfilePrediction:
    """An areal scan [m] sheared along +`axis` → `predict`: θa (both filters) of the normals pooled
    over every grid line along the axis (surface.areal.theta_a_scan, as `campaign theta-a` reads a
    scan), and flat spacing judged line by line (regular_flat_spacing on each line with its
    least-squares line removed; regular when more than half of the lines are)."""
    from interphase.surface.areal import theta_a_scan

    t = theta_a_scan(scan, d50, (92, 90), axes=(axis,))[f"+{axis}"]
    s, Z = scan.lines(axis)
    votes = []
    for z in Z:                 # grid lines of a scan (hundreds), each judged whole
        ok = np.isfinite(z)
        if ok.sum() < 3:
            continue
        x, h = s[ok], z[ok]
        votes.append(regular_flat_spacing(x, h - np.polyval(np.polyfit(x, h, 1), x), d50)[0])
    flat = bool(votes) and float(np.mean(votes)) > 0.5
    why = f"{sum(votes)} of {len(votes)} lines along {axis} with regular flat spacing"
    p = predict(model, friction, t[92].theta_a_deg, t[90].theta_a_deg, flat, filt)
    return ProfilePrediction(p, t[92].theta_a_deg, t[90].theta_a_deg, t[92].mean_slope_deg, flat, why,
                             t[92].trace_share)


def predict_measured(model: CriterionModel, scan, d50: float, friction: float, axis: str | None = None,
                     filt: int | None = None, where: str = "axis") -> ProfilePrediction:
    """A measured surface as read (surface.readers.read_scan, metres) → the chain: a line profile
    centerline-corrected (predict_profile; it has only the x axis, `where` names the option that
    gave another), an areal scan along +`axis` (predict_scan, default x). A θa outside the fits is
    refused naming the file (`scan.name`)."""
    if axis not in (None, "x") and not scan.areal:
        raise InputError("a line profile has only the x axis", where=where, fix=f"omit {where} for a line")
    from interphase.surface.filters import prepare_measured
    from interphase.surface.lines import scan_profile

    try:
        if scan.areal:
            return predict_scan(model, scan, d50, friction, axis or "x", filt)
        return predict_profile(model, prepare_measured(scan_profile(scan)), d50, friction, filt)
    except OutOfFitRange as exc:
        raise OutOfFitRange(exc.message, where=scan.name, fix=exc.fix) from exc


def _rule_of(d) -> tuple | None:
    """(a, b) of a criterion file's "rule" entry, None when absent or not finite (older files)."""
    if not d or d.get("a_deg") is None or d.get("b") is None:
        return None
    return float(d["a_deg"]), float(d["b"])


def rule_delta(friction, theta_a_deg, tan_phi, a_deg: float = 0.0, b: float = 1.0) -> np.ndarray:
    """δ [°] of the rule δ = min(φμ + θa − a, atan(b·tan φ)): with a = 0, b = 1 the rule with no
    fitted constant; `fit_rule` gives the best two constants."""
    phimu = np.degrees(np.arctan(np.asarray(friction, float)))
    cap = np.degrees(np.arctan(b * np.asarray(tan_phi, float)))
    return np.minimum(phimu + np.asarray(theta_a_deg, float) - a_deg, cap)


def fit_rule(points: pd.DataFrame) -> tuple[float, float]:
    """The two constants (a [°], b) of δ = min(φμ + θa − a, atan(b·tan φ)) that fit the measured δ of
    `points` (columns friction_ps, theta_a_deg_92, tan_phi, peak_stress_ratio = tan δ) best by least
    squares in δ [°]: the fair baseline of a criterion fitted on the same cases (issue 41). NaN
    without three usable cases."""
    from scipy import optimize

    num = lambda k: pd.to_numeric(points.get(k, pd.Series(dtype=float)), errors="coerce").to_numpy(float)
    mu, ta, tp, td = (num(k) for k in ("friction_ps", "theta_a_deg_92", "tan_phi", "peak_stress_ratio"))
    ok = np.isfinite(mu) & np.isfinite(ta) & np.isfinite(tp) & np.isfinite(td)
    if ok.sum() < 3:
        return math.nan, math.nan
    delta = np.degrees(np.arctan(td[ok]))
    sse = lambda p: float(np.sum((rule_delta(mu[ok], ta[ok], tp[ok], p[0], p[1]) - delta) ** 2))
    best = min((optimize.minimize(sse, x0, method="Nelder-Mead", options={"xatol": 1e-4, "fatol": 1e-8})
                for x0 in ((0.0, 1.0), (3.0, 1.05), (-3.0, 0.95))), key=lambda r: r.fun)
    return float(best.x[0]), float(best.x[1])


def check_cases(model: CriterionModel, points: pd.DataFrame, rule: tuple[float, float] | None = None) -> pd.DataFrame:
    """The chain run on every physical case of a points table (correlations.prepare_points /
    seed_ensemble) against what the simulation measured: one row per case with the predicted and
    measured θr [°], E and tan δ, δ [°], and `error_deg` = δ predicted − δ measured (the study's
    measure of its criterion: < 4° against the lab). The prediction uses the case's own θa (both
    filters), flat spacing, friction and its box ensemble's tan φ; a case the chain cannot take
    (θa outside a fit's range, a missing correlation) keeps NaN and the reason in `note`. Beside it,
    the baselines' errors (PREDICTORS); `rule` = (a, b) of the two-constant rule (`fit_rule`, fitted
    by the caller on the same cases as the criterion; NaN columns without it)."""
    rows = []
    col = lambda r, k: float(r[k]) if k in r and pd.notna(r[k]) else math.nan
    for _, r in points.iterrows():
        out = {"group": r.get("group"), "physical_case": r.get("physical_case"), "friction_ps": col(r, "friction_ps"),
               "theta_a_deg_92": col(r, "theta_a_deg_92"), "flat_spaced": bool(r.get("flat_spaced", False)),
               "theta_r_measured": col(r, "theta_r_surface_deg"), "E_measured": col(r, "efficiency"),
               "tan_delta_measured": col(r, "peak_stress_ratio"), "tan_phi": col(r, "tan_phi"), "note": ""}
        try:
            p = predict(model, out["friction_ps"], out["theta_a_deg_92"], col(r, "theta_a_deg_90"), out["flat_spaced"])
            out.update(theta_r_predicted=p.theta_r_deg, E_predicted=p.efficiency, branch=p.branch)
        except InputError as exc:
            out.update(theta_r_predicted=math.nan, E_predicted=math.nan, branch="", note=str(exc))
        out["tan_delta_predicted"] = out["E_predicted"] * out["tan_phi"]
        rows.append(out)
    df = pd.DataFrame(rows)
    if df.empty:
        return df
    deg = lambda t: np.degrees(np.arctan(pd.to_numeric(t, errors="coerce")))
    df["delta_predicted_deg"], df["delta_measured_deg"] = deg(df["tan_delta_predicted"]), deg(df["tan_delta_measured"])
    df["error_deg"] = df["delta_predicted_deg"] - df["delta_measured_deg"]
    # the two baselines a criterion must beat (docs/reproduction.md): the soil's own strength on every
    # surface, and a rule with no fit at all, δ = min(φμ + θa, φ)
    soil = deg(df["tan_phi"])
    df["error_soil_deg"] = soil - df["delta_measured_deg"]
    df["error_rule_deg"] = rule_delta(df["friction_ps"], df["theta_a_deg_92"], df["tan_phi"]) - df["delta_measured_deg"]
    a, b = rule if rule is not None else (math.nan, math.nan)
    df["rule_a_deg"], df["rule_b"] = a, b
    df["error_fitted_rule_deg"] = rule_delta(df["friction_ps"], df["theta_a_deg_92"], df["tan_phi"], a, b) \
        - df["delta_measured_deg"]
    df["mobilised"] = pd.to_numeric(df["E_measured"], errors="coerce") >= FULLY_MOBILISED_E
    return df


#: a case counts as fully mobilised when its measured E (seed means) reaches this
FULLY_MOBILISED_E = 0.95
PREDICTORS = {"error_deg": "criterion", "error_soil_deg": "δ = φ (the soil's own)",
              "error_rule_deg": "δ = min(φμ + θa, φ) (no fit)",
              "error_fitted_rule_deg": "δ = min(φμ + θa − a, atan(b tan φ)) (2 fitted)"}


def skill(df: pd.DataFrame, n_boot: int = 4000) -> pd.DataFrame:
    """The criterion beside its baselines (PREDICTORS; the fitted rule where check_cases had it), on all cases, on the fully mobilised ones
    (E measured ≥ FULLY_MOBILISED_E) and on the rest: per predictor and subset, n, rms and mean error [°
    of δ] and the share within 4°. Only cases all three predict are counted, so that each row
    compares the same cases. `rms_gap_deg` is a baseline's rms minus the criterion's, with its 95 %
    interval over a paired bootstrap of the cases (`rms_gap_lo`/`_hi`; fixed seed): above 0 the
    criterion misses less than that baseline by more than these cases' scatter, an interval
    containing 0 cannot tell them apart. The fits are held fixed, so the interval is what the case set
    can read, not the fit's own uncertainty."""
    rows = []
    cols = [c for c in PREDICTORS if c in df and df[c].notna().any()]
    ok = df.dropna(subset=cols)
    full = ok["mobilised"].astype(bool)
    rng = np.random.default_rng(0)
    rms = lambda e: float(np.sqrt(np.mean(e ** 2))) if e.size else math.nan
    for subset, part in (("all", ok), ("fully mobilised", ok[full]), ("not fully mobilised", ok[~full])):
        err = {c: pd.to_numeric(part[c], errors="coerce").to_numpy(float) for c in cols}
        draws = rng.integers(0, len(part), (n_boot, len(part))) if len(part) else None
        for c in cols:
            e = err[c]
            row = {"subset": subset, "predictor": PREDICTORS[c], "n": int(e.size), "rms_deg": rms(e),
                   "mean_deg": float(e.mean()) if e.size else math.nan,
                   "within_4deg": float((np.abs(e) < 4.0).mean()) if e.size else math.nan,
                   "rms_gap_deg": math.nan, "rms_gap_lo": math.nan, "rms_gap_hi": math.nan}
            if c != "error_deg" and "error_deg" in err and draws is not None:
                base = err["error_deg"]
                gap = np.sqrt(np.mean(e[draws] ** 2, axis=1)) - np.sqrt(np.mean(base[draws] ** 2, axis=1))
                row.update(rms_gap_deg=rms(e) - rms(base), rms_gap_lo=float(np.percentile(gap, 2.5)),
                           rms_gap_hi=float(np.percentile(gap, 97.5)))
            rows.append(row)
    return pd.DataFrame(rows)


def held_out_errors(checks: pd.DataFrame | None) -> dict | None:
    """The chain's error on cases its fits did not see, as criterion.json keeps it: the held-out fold
    of `report.build.criterion_checks` ("group held out", else "surface held out"), one entry per
    case the chain could take: its group, μs, θa (> 92°) [°], E predicted and error [° of δ] =
    δ predicted − δ measured (seed means; the case's own tan φ). None without a held-out fold. What
    `interphase.answer` builds the model's prediction interval from."""
    if checks is None or "fold" not in checks:
        return None
    fold = next((f for f in ("group held out", "surface held out") if (checks["fold"] == f).any()), None)
    if fold is None:
        return None
    g = checks[checks["fold"] == fold].dropna(subset=["error_deg"])
    num = lambda v: None if not math.isfinite(float(v)) else round(float(v), 6)
    cases = [{"group": str(r.group), "case": str(r.physical_case), "friction_ps": num(r.friction_ps),
              "theta_a_deg_92": num(r.theta_a_deg_92), "E_predicted": num(r.E_predicted),
              "error_deg": num(r.error_deg)} for r in g.itertuples()]
    return {"fold": fold, "n": len(cases), "n_without": int((checks["fold"] == fold).sum() - len(cases)),
            "cases": cases}


def check_summary(df: pd.DataFrame) -> dict:
    """n, mean, sd, 5–95 % range and the largest |error| [° of δ] (with its case) of check_cases."""
    e = pd.to_numeric(df.get("error_deg", pd.Series(dtype=float)), errors="coerce")
    ok = e.dropna()
    if ok.empty:
        return {"n": 0, "n_without": int(len(e))}
    worst = ok.abs().idxmax()
    return {"n": int(len(ok)), "n_without": int(len(e) - len(ok)), "mean": float(ok.mean()),
            "sd": float(ok.std(ddof=1)) if len(ok) > 1 else math.nan,
            "p5": float(ok.quantile(0.05)), "p95": float(ok.quantile(0.95)), "max_abs": float(ok.abs().max()),
            "worst_case": str(df.loc[worst, "physical_case"]), "worst_group": str(df.loc[worst, "group"]),
            "within_4deg": float((ok.abs() < 4.0).mean())}
