"""One Summary per case: the peak state of an interface (or box) test as a flat row plus series.

`summarise(case, results)` reads Results (contacts, history, particles; analysis frame, docs/methods.md §0)
and returns Summary(row, series). Others read these row keys (values JSON-able; NaN written as null):

  test, peak_stress_ratio (tan δ interface / tan φ box), peak_stress_ratio_raw, shear_disp_at_peak [m],
  peak_at_end (the maximum lies within one smoothing window of the end of the shear: a lower bound),
  residual_stress_ratio, dilation_at_peak [m], peak_snapshot, peak_snapshot_shear_disp [m],
  theta_r_surface_deg, theta_n_surface_deg (ψ, deg from vertical, + toward −x), theta_r_surface_mean_deg
  (θr averaged over the snapshots where the surface carries its load), a_r_surface,
  a_n_surface, surface_force_angle_deg, lee_share_surface (share of the surface contact force on
  faces leaning with the shear, which pulls δ below θr), stress_ratio_surface_contacts, n_contacts_surface,
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

from interphase.analysis import anisotropy as an_
from interphase.analysis import strength as st
from interphase.analysis.stress import average_stress, sampling_rectangle, trace_top
from interphase.tables import CONTACT_COLUMNS, HISTORY_COLUMNS, PARTICLE_COLUMNS, require_columns

ROW_KEYS = (
    "test", "peak_stress_ratio", "shear_disp_at_peak", "peak_at_end", "residual_stress_ratio", "dilation_at_peak",
    "peak_snapshot", "theta_r_surface_deg", "theta_r_surface_mean_deg", "theta_n_surface_deg", "a_r_surface",
    "a_n_surface",
    "surface_force_angle_deg", "lee_share_surface", "theta_r_region_deg", "theta_n_region_deg", "a_region", "an_region",
    "at_region", "stress_ratio_region", "qp_region", "qp_sff", "principal_stress_deg_region",
    "shear_band_d50", "inertial_number", "theta_a_deg_92", "theta_a_deg_90", "rn", "rnc",
    "mean_slope_deg", "n_contacts_surface", "reasons",
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


def _first(df: pd.DataFrame, key, col: str):
    if key is None or df is None or key not in df.index:
        return math.nan
    return df.at[key, col]


def summarise(case, results, *, shear_sign: int = 1, window: float | None = None,
              max_load_mismatch: float | None = st.MAX_LOAD_MISMATCH) -> Summary:
    """Summary of one finished case (see the module doc). `results` has .contacts, .history and
    optionally .particles (interphase.engines.base.Results or any object with those attributes);
    `shear_sign` = −1 mirrors tables written with the surface moving +x; `window` [m] overrides
    the peak-smoothing window (default PEAK_WINDOW_D50 · D50); History rows whose surface normal
    force differs from the platen force by more than `max_load_mismatch` (None: keep all) are left
    out of the peak and residual (strength.load_balanced)."""
    contacts = results.contacts
    history = results.history
    particles = getattr(results, "particles", None)
    require_columns(contacts, CONTACT_COLUMNS)
    require_columns(history, HISTORY_COLUMNS, "History")
    if particles is not None:
        require_columns(particles, PARTICLE_COLUMNS, "Particles")
    contacts = an_.apply_shear_sign(contacts, shear_sign)
    history = an_.apply_shear_sign(history, shear_sign)
    particles = an_.apply_shear_sign(particles, shear_sign) if particles is not None else None

    d50 = case.d50
    window = PEAK_WINDOW(d50) if window is None else window
    interface = case.test == "interface"
    reasons: dict[str, str] = {}
    row: dict = {"test": case.test, "case": case.label()}

    # -- strength from History
    hist = history.sort_values("shear_disp", kind="stable").reset_index(drop=True)
    ratio = st.surface_stress_ratio(hist) if interface else st.box_stress_ratio(hist)
    x0, x1 = case.window                      # the tables are in the analysis frame from here on
    balanced = st.load_balanced(hist, max_load_mismatch, share=(x1 - x0) / case.box_length)
    used = ratio.where(balanced)
    if (~balanced).any():
        reasons["history_rows_skipped"] = (f"{int((~balanced).sum())} of {len(hist)} History rows left out of the peak: "
                                           f"surface normal force ≠ platen force by > {max_load_mismatch:.0%}")
    peak = st.find_peak(hist["shear_disp"], used, window)
    row.update(peak_stress_ratio=peak.value, peak_stress_ratio_raw=peak.raw_max, peak_window=window,
               shear_disp_at_peak=peak.shear_disp, history_rows_skipped=int((~balanced).sum()),
               residual_stress_ratio=st.residual_ratio(hist["shear_disp"], used),
               dilation_at_peak=st.dilation(hist, peak.shear_disp) if len(hist) else math.nan)
    if peak.reason:
        for k in ("peak_stress_ratio", "shear_disp_at_peak", "residual_stress_ratio", "dilation_at_peak"):
            reasons[k] = f"History: {peak.reason}"
    # a maximum within one smoothing window of the last row may be a ratio still rising: a lower
    # bound of the peak, not a peak (a note, the value stands)
    end = float(hist["shear_disp"].max()) if len(hist) else math.nan
    row["peak_at_end"] = bool(math.isfinite(peak.shear_disp) and peak.shear_disp >= end - window)
    if row["peak_at_end"]:
        reasons["peak_at_end"] = (f"the peak lies within one smoothing window ({window * 1e3:.3g} mm) of the end of "
                                  f"the shear ({end * 1e3:.3g} mm): the ratio may still be rising; shear further")

    # -- the peak snapshot
    snaps = contacts.groupby("snapshot")["shear_disp"].first().sort_index() if len(contacts) else pd.Series(dtype=float)
    k = st.peak_snapshot(snaps.to_numpy(), hist["shear_disp"], used, peak)
    peak_snap = snaps.index[k] if k is not None else None
    if peak_snap is None:
        reasons["peak_snapshot"] = "no peak in the History" if len(snaps) else "no contact snapshot"
    row["peak_snapshot"] = int(peak_snap) if peak_snap is not None else math.nan
    row["peak_snapshot_shear_disp"] = float(snaps[peak_snap]) if peak_snap is not None else math.nan
    keys = snaps.index.to_numpy()

    # -- surface anisotropy
    surf = None
    if interface:
        surf = an_.surface_anisotropy(_in_window(contacts, x0, x1), snapshots=keys)
        row.update(theta_r_surface_deg=_first(surf, peak_snap, "theta_r_deg"),
                   theta_n_surface_deg=_first(surf, peak_snap, "theta_n_deg"),
                   a_r_surface=_first(surf, peak_snap, "ar"), a_n_surface=_first(surf, peak_snap, "an"),
                   surface_force_angle_deg=_first(surf, peak_snap, "force_angle_deg"),
                   lee_share_surface=_first(surf, peak_snap, "lee_share"),
                   stress_ratio_surface_contacts=_first(surf, peak_snap, "stress_ratio"),
                   n_contacts_surface=int(_first(surf, peak_snap, "n_contacts")) if peak_snap is not None else 0)
        why = _first(surf, peak_snap, "reason") if peak_snap is not None else reasons.get("peak_snapshot", "")
        for k in ("theta_r_surface_deg", "theta_n_surface_deg", "a_r_surface", "a_n_surface",
                  "surface_force_angle_deg", "lee_share_surface", "stress_ratio_surface_contacts"):
            if not math.isfinite(row[k]):
                reasons[k] = why or "undefined at the peak snapshot"
    else:
        for k in ("theta_r_surface_deg", "theta_n_surface_deg", "a_r_surface", "a_n_surface",
                  "surface_force_angle_deg", "lee_share_surface", "stress_ratio_surface_contacts"):
            row[k] = math.nan
            reasons[k] = "box test: no rough surface"
        row["n_contacts_surface"] = 0

    # -- sampling region: stress and anisotropy
    centres_z = _centre_heights(contacts, particles)
    soil_top = _soil_top(contacts, particles, d50)
    if interface:
        z0 = trace_top(case)
        ps = contacts[contacts["kind"].eq("ps").to_numpy()]
        if len(ps):
            top_pts = float(np.nanmax(ps["cz"].to_numpy(float)))
            if top_pts > z0 - 0.5 * d50 + d50 or top_pts < z0 - 0.5 * d50 - d50:
                reasons["region_z0"] = (f"profile top {z0 - 0.5 * d50:.6g} m disagrees with the highest surface contact "
                                        f"point {top_pts:.6g} m: region starts at that point + D50/2")
                z0 = top_pts + 0.5 * d50
        rect = (x0, x1, *sampling_rectangle(case, z0, soil_top)[2:])
    else:
        lo = float(np.nanmin(centres_z)) if centres_z.size else 0.0
        rect = (0.0, case.box_length, lo, soil_top if math.isfinite(soil_top) else lo)
    row.update(region_x0=rect[0], region_x1=rect[1], region_z0=rect[2], region_z1=rect[3])
    max_branch = 1.5 * case.gradation.d_max
    stress = average_stress(contacts, rect, snapshots=keys, max_branch=max_branch) if len(keys) else None
    region = an_.region_anisotropy(contacts, rect, snapshots=keys) if len(keys) else None
    row.update(stress_ratio_region=_first(stress, peak_snap, "stress_ratio"),
               qp_region=_first(stress, peak_snap, "qp"),
               principal_stress_deg_region=_first(stress, peak_snap, "principal_deg"),
               theta_r_region_deg=_first(region, peak_snap, "theta_r_deg"),
               theta_n_region_deg=_first(region, peak_snap, "theta_n_deg"),
               theta_t_region_deg=_first(region, peak_snap, "theta_t_deg"),
               theta_fabric_region_deg=_first(region, peak_snap, "theta_fabric_deg"),
               a_region=_first(region, peak_snap, "a"), an_region=_first(region, peak_snap, "an"),
               at_region=_first(region, peak_snap, "at"), f0_region=_first(region, peak_snap, "f0"),
               qp_sff=_first(region, peak_snap, "qp_sff"),
               n_contacts_region=_first(region, peak_snap, "n_contacts"))
    why_s = _first(stress, peak_snap, "reason") if stress is not None else ""
    why_r = _first(region, peak_snap, "reason") if region is not None else ""
    for k in ("stress_ratio_region", "qp_region", "principal_stress_deg_region"):
        if not math.isfinite(row[k]):
            reasons[k] = why_s if isinstance(why_s, str) and why_s else reasons.get("peak_snapshot", "undefined")
    for k in ("theta_r_region_deg", "theta_n_region_deg", "theta_t_region_deg", "theta_fabric_region_deg",
              "a_region", "an_region", "at_region", "f0_region", "qp_sff"):
        if not math.isfinite(row[k]):
            reasons[k] = why_r if isinstance(why_r, str) and why_r else reasons.get("peak_snapshot", "undefined")

    # -- shear band and inertial number around the peak
    row.update(shear_band_d50=math.nan, shear_rate=math.nan, inertial_number=math.nan)
    if particles is None or particles.empty:
        for k in ("shear_band_d50", "shear_rate", "inertial_number"):
            reasons[k] = "no Particles table"
    elif peak_snap is None:
        for k in ("shear_band_d50", "shear_rate", "inertial_number"):
            reasons[k] = reasons.get("peak_snapshot", "no peak snapshot")
    else:
        psnaps = np.unique(particles["snapshot"].to_numpy())
        i = int(np.searchsorted(psnaps, peak_snap))
        s0, s1 = psnaps[max(i - 1, 0)], psnaps[min(i + 1, psnaps.size - 1)]
        if s0 == s1:
            for k in ("shear_band_d50", "shear_rate", "inertial_number"):
                reasons[k] = "fewer than two particle snapshots"
        else:
            prof = st.displacement_profile(particles, s0, s1, rect[2])
            band, why = st.shear_band(prof["z"], prof["U"], rect[2], d50)
            row["shear_band_d50"] = band
            if why:
                reasons["shear_band_d50"] = why
            sel = particles["snapshot"].between(s0, s1)
            rate = st.shear_rate_from_profile(particles[sel], z_min=rect[2] - 0.5 * d50,
                                              z_max=soil_top if math.isfinite(soil_top) else None)
            row["shear_rate"] = rate
            row["inertial_number"] = st.inertial_number(rate, d50, case.normal_stress, case.density)
            if not math.isfinite(row["inertial_number"]):
                reasons["shear_rate"] = reasons["inertial_number"] = "fewer than two grain layers in the velocity profile"
    row["quasi_static"] = bool(row["inertial_number"] < st.QUASI_STATIC_I) if math.isfinite(row["inertial_number"]) else None

    # -- profile quantities
    _profile_features(case, row, reasons)

    # -- quasi-static checks of the run (overlaps, platen-force error, grains that left); I is above
    from interphase.analysis.quasistatic import checks

    for k, v in checks(case, results).items():
        row.setdefault(k, v)

    series = _series(hist, ratio, window, surf, stress, region, snaps)
    if len(hist):
        series["load_balanced"] = balanced
        series["stress_ratio_smooth"] = st.moving_average(series["shear_disp"].to_numpy(float),
                                                          used.to_numpy(float), window)
    row["theta_r_surface_mean_deg"] = _mean_over_loaded(series, "theta_r_surface_deg", reasons)

    # anything NaN without a reason gets one, so that no NaN goes unexplained
    for k, v in list(row.items()):
        if isinstance(v, float) and not math.isfinite(v) and k not in reasons:
            reasons[k] = "undefined (see the other reasons)"
    row = {k: _scalar(v) for k, v in row.items()}
    row["reasons"] = reasons
    return Summary(row=row, series=series)


def _mean_over_loaded(series: pd.DataFrame, key: str, reasons: dict) -> float:
    """Mean of a snapshot quantity over the snapshots whose History row is load-balanced (the
    surface carries its share of the platen's load): steadier than the one peak snapshot, which a
    stick–slip event sets (docs/liggghts.md: θr over the shear vs δ)."""
    name = key.replace("_deg", "_mean_deg")
    if key not in series or "load_balanced" not in series:
        reasons[name] = "no snapshot series (box test or no contacts)"
        return math.nan
    v = series.loc[series["load_balanced"].astype(bool) & series[key].notna(), key]
    if v.empty:
        reasons[name] = "no snapshot where the surface carries its share of the platen's load"
        return math.nan
    return float(v.mean())


def _in_window(contacts: pd.DataFrame, x0: float, x1: float) -> pd.DataFrame:
    """The contacts less the 'ps' ones of grains centred outside [x0, x1] (x2 = grain centre)."""
    ps = contacts["kind"].eq("ps").to_numpy()
    x = contacts["x2"].to_numpy(float)
    return contacts[~ps | ((x >= x0) & (x <= x1))]


def PEAK_WINDOW(d50: float) -> float:
    """Default peak-smoothing window [m]: PEAK_WINDOW_D50 · D50."""
    return st.PEAK_WINDOW_D50 * d50


def _centre_heights(contacts: pd.DataFrame, particles) -> np.ndarray:
    if particles is not None and len(particles):
        return particles["z"].to_numpy(float)
    pp = contacts[contacts["kind"].eq("pp").to_numpy()]
    return np.concatenate([pp["z1"].to_numpy(float), pp["z2"].to_numpy(float), contacts["z2"].to_numpy(float)])


def _soil_top(contacts: pd.DataFrame, particles, d50: float) -> float:
    """Half a grain below the highest grain centre, the lowest over all snapshots [m]; NaN if none."""
    if particles is not None and len(particles):
        tops = particles.groupby("snapshot")["z"].max()
    elif len(contacts):
        tops = contacts.groupby("snapshot")["z2"].max()
    else:
        return math.nan
    tops = tops[np.isfinite(tops)]
    return float(tops.min()) - 0.5 * d50 if len(tops) else math.nan


def _profile_features(case, row: dict, reasons: dict) -> None:
    keys = ("theta_a_deg_92", "theta_a_deg_90", "rn", "rnc", "mean_slope_deg")
    for k in keys:
        row[k] = math.nan
    if case.test != "interface" or case.profile is None:
        for k in keys:
            reasons[k] = "box test: no surface profile"
        return
    from interphase.surface.normals import theta_a_filters
    from interphase.surface.profiles import from_spec

    # a saw-tooth is periodic: the trace of n periods is n copies of one period's, so θa, Rn, Rnc
    # and the slope of one period are those of the box's profile, at 1/n of the cost
    length = case.d50 if case.profile.kind == "sawtooth" else case.box_length
    t = theta_a_filters(from_spec(case.profile, case.d50, length), case.d50, (92, 90))
    t92, t90 = t[92], t[90]
    row.update(theta_a_deg_92=t92.theta_a_deg, theta_a_deg_90=t90.theta_a_deg, rn=t92.rn, rnc=t92.rnc,
               mean_slope_deg=t92.mean_slope_deg)
    if t92.reason:
        reasons["theta_a_deg_92"] = t92.reason
    if t90.reason:
        reasons["theta_a_deg_90"] = t90.reason
    if not math.isfinite(t92.mean_slope_deg):
        reasons["mean_slope_deg"] = "no asperity face steeper than 2° (flat surface)"


def _series(hist, ratio, window, surf, stress, region, snaps) -> pd.DataFrame:
    """History rows (shear_disp, stress_ratio, its moving average, platen_z, normal_force) with the
    snapshot quantities set on the History row nearest each snapshot (NaN elsewhere)."""
    base = pd.DataFrame({
        "shear_disp": hist["shear_disp"].to_numpy(float),
        "stress_ratio": ratio.to_numpy(float),
        "stress_ratio_smooth": st.moving_average(hist["shear_disp"].to_numpy(float), ratio.to_numpy(float), window),
        "platen_z": hist["platen_z"].to_numpy(float),
        "normal_force": hist["normal_force"].to_numpy(float),
    })
    snap = pd.DataFrame(index=snaps.index)
    snap["snapshot_shear_disp"] = snaps.to_numpy(float)
    if surf is not None:
        snap["theta_r_surface_deg"] = surf["theta_r_deg"]
        snap["theta_n_surface_deg"] = surf["theta_n_deg"]
        snap["a_r_surface"] = surf["ar"]
        snap["surface_force_angle_deg"] = surf["force_angle_deg"]
        snap["lee_share_surface"] = surf["lee_share"]
        snap["stress_ratio_surface_contacts"] = surf["stress_ratio"]
    if stress is not None:
        snap["stress_ratio_region"] = stress["stress_ratio"]
        snap["qp_region"] = stress["qp"]
        snap["principal_stress_deg_region"] = stress["principal_deg"]
    if region is not None:
        snap["theta_r_region_deg"] = region["theta_r_deg"]
        snap["theta_n_region_deg"] = region["theta_n_deg"]
        snap["qp_sff"] = region["qp_sff"]
    if base.empty:
        out = snap.reset_index().rename(columns={"snapshot_shear_disp": "shear_disp"})
        return out
    cols = [c for c in snap.columns]
    for c in cols:
        base[c] = np.nan
    base["snapshot"] = pd.array([pd.NA] * len(base), dtype="Int64")
    if len(snap):
        s = base["shear_disp"].to_numpy()
        pos = np.searchsorted(s, snap["snapshot_shear_disp"].to_numpy())
        lo = np.clip(pos - 1, 0, len(s) - 1)
        hi = np.clip(pos, 0, len(s) - 1)
        near = np.where(np.abs(s[lo] - snap["snapshot_shear_disp"].to_numpy())
                        <= np.abs(s[hi] - snap["snapshot_shear_disp"].to_numpy()), lo, hi)
        for c in cols:
            vals = base[c].to_numpy(float).copy()
            vals[near] = snap[c].to_numpy(float)
            base[c] = vals
        sn = base["snapshot"].copy()
        sn.iloc[near] = snap.index.to_numpy()
        base["snapshot"] = sn
    return base
