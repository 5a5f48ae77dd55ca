"""One Summary per case: the peak state of an interface (or box) test as a flat row plus series.

`summarise(case, results)` reads Results (contacts, history, particles) and returns Summary(row,
series). A pipeline (analysis.summary_stages): the tables are checked against their contracts and
brought into the analysis frame (docs/methods.md §0) once, then the strength, peak-snapshot,
surface, region, shear-band and profile stages each return their values and the reason for every
NaN among them. Others read these row keys (values JSON-able; NaN written as null):

  test, peak_stress_ratio (tan δ interface / tan φ box), peak_stress_ratio_raw, shear_disp_at_peak [m],
  peak_at_end (the maximum lies within one smoothing window of the end of the shear: a lower bound),
  residual_stress_ratio, dilation_at_peak [m], peak_snapshot, peak_snapshot_shear_disp [m],
  theta_r_surface_deg, theta_n_surface_deg (ψ, deg from vertical, + toward −x), theta_r_surface_mean_deg
  (θr averaged over the snapshots where the surface carries its load), a_r_surface,
  a_n_surface, surface_force_angle_deg, lee_share_surface (share of the surface contact force on
  faces leaning with the shear, which pulls δ below θr), slide_share_surface (share of the loaded surface
  contacts whose tangential force reaches 0.99 μs·fn: sliding, not sticking), stress_ratio_surface_contacts,
  n_contacts_surface,
  theta_r_region_deg, theta_n_region_deg, theta_t_region_deg, theta_fabric_region_deg, a_region,
  an_region, at_region, f0_region [N], stress_ratio_region (−σxz/σzz), qp_region, qp_sff,
  principal_stress_deg_region, n_contacts_region, region_x0/x1/z0/z1 [m], shear_band_d50,
  shear_rate [1/s], inertial_number, quasi_static, theta_a_deg_92, theta_a_deg_90, rn, rnc,
  mean_slope_deg, reasons {key: why it is NaN, or a note}.

Choices (where docs/methods.md is silent):
- Peak: the maximum of a centred moving average of the History stress ratio over PEAK_WINDOW_D50 ·
  D50 of shear displacement (strength.py); the state quantities come from the contact snapshot
  nearest the peak among those whose smoothed ratio is within 5 % of the peak (`peak_snapshot`,
  strength.peak_snapshot): on a sliding plateau the plain nearest one can be the start of shear.
- Measuring window (Case.window): interface tests measure over the grains whose centres lie 3 D50 or
  more from either side wall — History's window_fx/fz for μs, the 'ps' contacts of those grains for
  the surface anisotropy, and the sampling region's x range. A departure from docs/methods.md (which
  takes the whole surface [0, L]): grains wedged under the leading wall's edge load the surface
  through the wall, not through the soil (docs/liggghts.md has the measurements).
- Interface tests: the surface = 'ps' contacts; μs from History (the mesh force: dumped tangential
  forces at sliding contacts include damping, docs/engines.md, which biases sums of contact forces and
  thus θr slightly toward the shear direction on sliding flats; at sticking contacts they agree).
- Box tests: no 'ps' contacts; peak_stress_ratio = peak of surface_fx/|normal_force| (the lower
  half's horizontal force over the platen force, i.e. τ/σ on the shear plane); the surface
  quantities and the profile quantities are NaN with a reason; the sampling region is the whole
  specimen between its lowest and highest grain centres.
- Sampling region (interface): [x0, x1] of the window × [trace top, trace top + 20·D50], lowered to half a grain
  below the highest grain centre when the soil is thinner (stress.py). The trace top comes from the
  case's profile (the engines place the profile at its own z); if the 'ps' contact points disagree
  with it by more than a grain, the data win (max contact-point height + D50/2) and a note says so.
- Shear band and inertial number: from the Particles table between the snapshots either side of
  the peak snapshot (the incremental displacement shows the active band, not the pre-peak creep);
  γ̇ = the largest layer-to-layer velocity gradient (strength.shear_rate_from_profile, "max").
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from interphase.analysis import strength as st
from interphase.analysis import summary_stages as stage

ROW_KEYS = (
    "test", "peak_stress_ratio", "shear_disp_at_peak", "peak_at_end", "residual_stress_ratio", "dilation_at_peak",
    "peak_snapshot", "theta_r_surface_deg", "theta_r_surface_mean_deg", "theta_n_surface_deg", "a_r_surface",
    "a_n_surface",
    "surface_force_angle_deg", "lee_share_surface", "slide_share_surface", "theta_r_region_deg", "theta_n_region_deg", "a_region", "an_region",
    "at_region", "stress_ratio_region", "qp_region", "qp_sff", "principal_stress_deg_region",
    "shear_band_d50", "inertial_number", "theta_a_deg_92", "theta_a_deg_90", "rn", "rnc",
    "mean_slope_deg", "n_contacts_surface", "solid_fraction", "reasons",
)


def _scalar(v):
    """A JSON-able Python scalar (numpy → float/int/bool; None stays)."""
    if v is None or isinstance(v, (str, bool)):
        return v
    if isinstance(v, (np.bool_,)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    try:
        return float(v)
    except (TypeError, ValueError):
        return str(v)


def _nan_to_none(v):
    return None if isinstance(v, float) and not math.isfinite(v) else v


@dataclass
class Summary:
    row: dict
    series: pd.DataFrame = field(default_factory=pd.DataFrame)

    @property
    def reasons(self) -> dict:
        return self.row.get("reasons", {})

    def to_json(self) -> str:
        """Strict JSON (NaN/inf → null): {"row": {...}, "series": {column: [values]}}."""
        row = {k: (v if k == "reasons" else _nan_to_none(_scalar(v))) for k, v in self.row.items()}
        series = {c: [_nan_to_none(_scalar(v)) for v in self.series[c].tolist()] for c in self.series.columns}
        return json.dumps({"row": row, "series": series}, allow_nan=False, indent=1)

    @classmethod
    def from_json(cls, text: str) -> "Summary":
        data = json.loads(text)
        row = {k: (math.nan if v is None else v) for k, v in data["row"].items()}
        series = pd.DataFrame({c: pd.Series([math.nan if v is None else v for v in vals], dtype=object)
                               for c, vals in data.get("series", {}).items()})
        for c in series.columns:
            series[c] = _numeric(series[c])
        return cls(row=row, series=series)


def _numeric(s: pd.Series) -> pd.Series:
    try:
        return pd.to_numeric(s)
    except (TypeError, ValueError):
        return s


def summarise(case, results, *, shear_sign: int = 1, window: float | None = None,
              max_load_mismatch: float | None = st.MAX_LOAD_MISMATCH) -> Summary:
    """Summary of one finished case (see the module doc). `results` has .contacts, .history and
    optionally .particles (interphase.tables.Results or any object with those attributes);
    `shear_sign` = −1 mirrors tables written with the surface moving +x; `window` [m] overrides
    the peak-smoothing window (default PEAK_WINDOW_D50 · D50); History rows whose surface normal
    force differs from the platen force by more than `max_load_mismatch` (None: keep all) are left
    out of the peak and residual (strength.load_balanced)."""
    frame = stage.AnalysisFrame.of(results, shear_sign)
    window = PEAK_WINDOW(case.d50) if window is None else window
    hist = frame.history

    strength = stage.strength(case, hist, window, max_load_mismatch)
    peak = stage.peak_snapshot(frame.contacts, hist, strength)
    surface = stage.surface(case, frame.contacts, peak)
    region = stage.region(case, frame, peak)
    band = stage.shear_band(case, frame.particles, peak, region)
    profile = stage.profile_features(case)

    row: dict = {"test": case.test, "case": case.label()}
    reasons: dict[str, str] = {}
    for part in (strength, peak, surface, region, band, profile):
        row.update(part.values)
        reasons.update(part.reasons)
    # the quasi-static checks read the engine's own frame (grains outside [0, L]; |dvx/dz|), so they
    # get the tables as written; the stages' values win where both give one
    from interphase.analysis.quasistatic import checks

    for k, v in checks(case, results).items():
        row.setdefault(k, v)
    spec = stage.specimen(case, getattr(results, "particles", None), frame.contacts)
    row.update(spec.values)
    reasons.update(spec.reasons)

    series = stage.series(hist, strength, window, peak, surface, region)
    mean = stage.mean_over_loaded(series, "theta_r_surface_deg")
    row.update(mean.values)
    reasons.update(mean.reasons)

    # anything NaN without a reason gets one, so that no NaN goes unexplained
    for k, v in row.items():
        if isinstance(v, float) and not math.isfinite(v) and k not in reasons:
            reasons[k] = "undefined (see the other reasons)"
    row = {k: _scalar(v) for k, v in row.items()}
    row["reasons"] = reasons
    return Summary(row=row, series=series)


def PEAK_WINDOW(d50: float) -> float:
    """Default peak-smoothing window [m]: PEAK_WINDOW_D50 · D50."""
    return st.PEAK_WINDOW_D50 * d50
