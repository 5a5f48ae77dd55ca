"""The stages of a case summary: the run brought into the analysis frame once, then strength, peak
snapshot, surface, region, shear band and profile, each returning its values and the reason for
every NaN among them (analysis.summary puts them together; docs/methods.md §6 has the formulas).

Every stage takes what the earlier ones found (the peak, the peak snapshot, the sampling rectangle)
as arguments; none re-checks columns or re-applies the shear sign: `AnalysisFrame.of` does both.
Units SI; angles ψ in degrees (from vertical, positive toward −x) unless a name says ccw.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from interphase.analysis import anisotropy as an_
from interphase.analysis import strength as st
from interphase.analysis.stress import average_stress, sampling_rectangle, trace_top
from interphase.tables import CONTACT_COLUMNS, HISTORY_COLUMNS, PARTICLE_COLUMNS, require_columns

#: the surface quantities read at the peak snapshot: row key → column of anisotropy.surface_anisotropy
SURFACE_KEYS = {"theta_r_surface_deg": "theta_r_deg", "theta_n_surface_deg": "theta_n_deg", "a_r_surface": "ar",
                "a_n_surface": "an", "surface_force_angle_deg": "force_angle_deg", "lee_share_surface": "lee_share",
                "stress_ratio_surface_contacts": "stress_ratio"}
#: the 3D device's out-of-plane surface readings (docs/3d.md): row key → column of surface_anisotropy
SURFACE_3D_KEYS = {"r_yy_surface": "r_yy", "fy_share_surface": "fy_share",
                   "principal_tilt_y_surface_deg": "principal_tilt_y_deg", "fabric_yy_surface": "fabric_yy",
                   "nf_yy_surface": "nf_yy"}
#: the region's stress readings: row key → column of stress.average_stress
STRESS_KEYS = {"stress_ratio_region": "stress_ratio", "qp_region": "qp", "principal_stress_deg_region": "principal_deg"}
#: the region's anisotropy: row key → column of anisotropy.region_anisotropy
REGION_KEYS = {"theta_r_region_deg": "theta_r_deg", "theta_n_region_deg": "theta_n_deg",
               "theta_t_region_deg": "theta_t_deg", "theta_fabric_region_deg": "theta_fabric_deg", "a_region": "a",
               "an_region": "an", "at_region": "at", "f0_region": "f0", "qp_sff": "qp_sff"}
BAND_KEYS = ("shear_band_d50", "shear_rate", "inertial_number")
PROFILE_KEYS = ("theta_a_deg_92", "theta_a_deg_90", "rn", "rnc", "mean_slope_deg")


@dataclass
class Stage:
    """A stage's row values and {key: why it is NaN, or a note}."""
    values: dict = field(default_factory=dict)
    reasons: dict = field(default_factory=dict)


@dataclass(frozen=True)
class AnalysisFrame:
    """A run's tables in the analysis frame (soil moving +x relative to the surface), columns checked:
    contacts (ContactTable), history (sorted by shear displacement, index 0..n−1), particles or None."""
    contacts: pd.DataFrame
    history: pd.DataFrame
    particles: pd.DataFrame | None

    @classmethod
    def of(cls, results, shear_sign: int = 1) -> "AnalysisFrame":
        """Check the tables of `results` (.contacts, .history, optional .particles) against their
        contracts and mirror x when `shear_sign` = −1 (tables written with the surface moving +x)."""
        particles = getattr(results, "particles", None)
        require_columns(results.contacts, CONTACT_COLUMNS)
        require_columns(results.history, HISTORY_COLUMNS, "History")
        if particles is not None:
            require_columns(particles, PARTICLE_COLUMNS, "Particles")
            particles = an_.apply_shear_sign(particles, shear_sign)
        history = an_.apply_shear_sign(results.history, shear_sign)
        return cls(contacts=an_.apply_shear_sign(results.contacts, shear_sign),
                   history=history.sort_values("shear_disp", kind="stable").reset_index(drop=True),
                   particles=particles)


def _at(df: pd.DataFrame | None, key, col: str):
    """df[col] at row `key`; NaN when there is no table or no such row."""
    if key is None or df is None or key not in df.index:
        return math.nan
    return df.at[key, col]


def _nan_reasons(values: dict, keys, why: str) -> dict:
    return {k: why for k in keys if not math.isfinite(values[k])}


# ---- strength ------------------------------------------------------------------------------------

@dataclass
class Strength(Stage):
    ratio: pd.Series = None         # stress ratio per History row (μs, or τ/σ of a box)
    balanced: np.ndarray = None     # History rows whose surface carries its share of the platen's load
    used: pd.Series = None          # ratio on the balanced rows, NaN elsewhere: what the peak is read from
    peak: st.Peak = None


def strength(case, hist: pd.DataFrame, window: float, max_load_mismatch: float | None) -> Strength:
    """Peak (smoothed over `window` m), raw maximum, residual, dilation and peak_at_end from History."""
    interface = case.test == "interface"
    ratio = st.surface_stress_ratio(hist) if interface else st.box_stress_ratio(hist)
    balanced = st.load_balanced(hist, max_load_mismatch)
    used = ratio.where(balanced)
    out = Strength(ratio=ratio, balanced=balanced, used=used)
    skipped = int((~balanced).sum())
    if skipped:
        out.reasons["history_rows_skipped"] = (f"{skipped} of {len(hist)} History rows left out of the peak: "
                                               f"surface normal force ≠ platen force by > {max_load_mismatch:.0%}")
    peak = out.peak = st.find_peak(hist["shear_disp"], used, window)
    out.values.update(peak_stress_ratio=peak.value, peak_stress_ratio_raw=peak.raw_max, peak_window=window,
                      shear_disp_at_peak=peak.shear_disp, history_rows_skipped=skipped,
                      residual_stress_ratio=st.residual_ratio(hist["shear_disp"], used),
                      dilation_at_peak=st.dilation(hist, peak.shear_disp) if len(hist) else math.nan)
    if peak.reason:
        for k in ("peak_stress_ratio", "shear_disp_at_peak", "residual_stress_ratio", "dilation_at_peak"):
            out.reasons[k] = f"History: {peak.reason}"
    # a maximum within one smoothing window of the last row may be a ratio still rising: a lower
    # bound of the peak, not a peak (a note, the value stands)
    end = float(hist["shear_disp"].max()) if len(hist) else math.nan
    at_end = bool(math.isfinite(peak.shear_disp) and peak.shear_disp >= end - window)
    out.values["peak_at_end"] = at_end
    if at_end:
        out.reasons["peak_at_end"] = (f"the peak lies within one smoothing window ({window * 1e3:.3g} mm) of the end "
                                      f"of the shear ({end * 1e3:.3g} mm): the ratio may still be rising; shear further")
    return out


# ---- the peak snapshot ---------------------------------------------------------------------------

@dataclass
class PeakSnapshot(Stage):
    snaps: pd.Series = None         # shear displacement [m] of every contact snapshot, by snapshot
    key: object = None              # the snapshot standing for the peak state, None without one

    @property
    def why_none(self) -> str:
        return self.reasons.get("peak_snapshot", "")


def peak_snapshot(contacts: pd.DataFrame, hist: pd.DataFrame, s: Strength) -> PeakSnapshot:
    """The contact snapshot that stands for the peak state (strength.peak_snapshot)."""
    snaps = (contacts.groupby("snapshot")["shear_disp"].first().sort_index() if len(contacts)
             else pd.Series(dtype=float))
    k = st.peak_snapshot(snaps.to_numpy(), hist["shear_disp"], s.used, s.peak)
    key = snaps.index[k] if k is not None else None
    out = PeakSnapshot(snaps=snaps, key=key)
    if key is None:
        out.reasons["peak_snapshot"] = "no peak in the History" if len(snaps) else "no contact snapshot"
    out.values["peak_snapshot"] = int(key) if key is not None else math.nan
    out.values["peak_snapshot_shear_disp"] = float(snaps[key]) if key is not None else math.nan
    return out


# ---- surface -------------------------------------------------------------------------------------

@dataclass
class Surface(Stage):
    table: pd.DataFrame | None = None   # surface_anisotropy per snapshot (None for a box test)


def in_window(contacts: pd.DataFrame, x0: float, x1: float) -> pd.DataFrame:
    """The contacts less the 'ps' ones of grains centred outside [x0, x1] (x2 = grain centre)."""
    ps = contacts["kind"].eq("ps").to_numpy()
    x = contacts["x2"].to_numpy(float)
    return contacts[~ps | ((x >= x0) & (x <= x1))]


def surface(case, contacts: pd.DataFrame, ps: PeakSnapshot) -> Surface:
    """θr, θn, a_r, a_n, the summed-force angle, the lee share, the sliding share and the contacts'
    stress ratio of the surface contacts of the measuring window at the peak snapshot."""
    if case.test != "interface":
        values = {k: math.nan for k in SURFACE_KEYS} | {"n_contacts_surface": 0, "slide_share_surface": math.nan}
        return Surface(values=values, reasons={k: "box test: no rough surface" for k in (*SURFACE_KEYS, "slide_share_surface")})
    table = an_.surface_anisotropy(in_window(contacts, *case.window), snapshots=ps.snaps.index.to_numpy())
    key = ps.key
    values = {k: _at(table, key, col) for k, col in SURFACE_KEYS.items()}
    values["n_contacts_surface"] = int(_at(table, key, "n_contacts")) if key is not None else 0
    slide = an_.sliding_share(in_window(contacts, *case.window), case.friction_ps, snapshots=[key] if key is not None else [])
    values["slide_share_surface"] = float(slide.iloc[0]) if key is not None and len(slide) else math.nan
    if getattr(case, "three_d", False):     # the out-of-plane part of the 3D tensors (docs/3d.md)
        values |= {k: _at(table, key, col) for k, col in SURFACE_3D_KEYS.items()}
    why = _at(table, key, "reason") if key is not None else ps.why_none
    reasons = _nan_reasons(values, (*SURFACE_KEYS, "slide_share_surface"), why or "undefined at the peak snapshot")
    return Surface(values=values, reasons=reasons,
                   table=table)


# ---- sampling region -----------------------------------------------------------------------------

@dataclass
class Region(Stage):
    rect: tuple = None                  # (x0, x1, z0, z1) [m]
    soil_top: float = math.nan          # [m]
    stress: pd.DataFrame | None = None  # average_stress per snapshot
    anisotropy: pd.DataFrame | None = None


def soil_top(contacts: pd.DataFrame, particles, d50: float) -> float:
    """Half a grain below the highest grain centre, the lowest over all snapshots [m]; NaN if none."""
    if particles is not None and len(particles):
        tops = particles.groupby("snapshot")["z"].max()
    elif len(contacts):
        tops = contacts.groupby("snapshot")["z2"].max()
    else:
        return math.nan
    tops = tops[np.isfinite(tops)]
    return float(tops.min()) - 0.5 * d50 if len(tops) else math.nan


def _centre_heights(contacts: pd.DataFrame, particles) -> np.ndarray:
    if particles is not None and len(particles):
        return particles["z"].to_numpy(float)
    pp = contacts[contacts["kind"].eq("pp").to_numpy()]
    return np.concatenate([pp["z1"].to_numpy(float), pp["z2"].to_numpy(float), contacts["z2"].to_numpy(float)])


def sampling_region(case, frame: AnalysisFrame) -> tuple[tuple, float, dict]:
    """(rect (x0, x1, z0, z1) [m], soil top [m], notes). Interface: the measuring window above the
    trace top, which the surface contact points overrule when they disagree with it by more than a
    grain; box: the whole specimen between its lowest grain centre and the soil top."""
    contacts, d50 = frame.contacts, case.d50
    top = soil_top(contacts, frame.particles, d50)
    notes = {}
    if case.test != "interface":
        centres_z = _centre_heights(contacts, frame.particles)
        lo = float(np.nanmin(centres_z)) if centres_z.size else 0.0
        return (0.0, case.box_length, lo, top if math.isfinite(top) else lo), top, notes
    z0 = trace_top(case)
    ps = contacts[contacts["kind"].eq("ps").to_numpy()]
    if len(ps):
        top_pts = float(np.nanmax(ps["cz"].to_numpy(float)))
        profile_top = z0 - 0.5 * d50
        if top_pts > profile_top + d50 or top_pts < profile_top - d50:
            notes["region_z0"] = (f"profile top {profile_top:.6g} m disagrees with the highest surface contact "
                                  f"point {top_pts:.6g} m: region starts at that point + D50/2")
            z0 = top_pts + 0.5 * d50
    x0, x1 = case.window
    return (x0, x1, *sampling_rectangle(case, z0, top)[2:]), top, notes


def region(case, frame: AnalysisFrame, ps: PeakSnapshot) -> Region:
    """Average stress and contact anisotropy in the sampling region at the peak snapshot."""
    rect, top, notes = sampling_region(case, frame)
    keys = ps.snaps.index.to_numpy()
    contacts = frame.contacts
    stress = (average_stress(contacts, rect, snapshots=keys, max_branch=1.5 * case.gradation.d_max)
              if len(keys) else None)
    aniso = an_.region_anisotropy(contacts, rect, snapshots=keys) if len(keys) else None
    values = dict(region_x0=rect[0], region_x1=rect[1], region_z0=rect[2], region_z1=rect[3])
    values |= {k: _at(stress, ps.key, col) for k, col in STRESS_KEYS.items()}
    values |= {k: _at(aniso, ps.key, col) for k, col in REGION_KEYS.items()}
    values["n_contacts_region"] = _at(aniso, ps.key, "n_contacts")
    reasons = dict(notes)
    for keys_, table in ((STRESS_KEYS, stress), (REGION_KEYS, aniso)):
        why = _at(table, ps.key, "reason") if table is not None else ""
        why = why if isinstance(why, str) and why else ps.reasons.get("peak_snapshot", "undefined")
        reasons |= _nan_reasons(values, keys_, why)
    return Region(values=values, reasons=reasons, rect=rect, soil_top=top, stress=stress, anisotropy=aniso)


# ---- shear band and inertial number --------------------------------------------------------------

def shear_band(case, particles, ps: PeakSnapshot, reg: Region) -> Stage:
    """Shear-band thickness [D50], shear rate [1/s] and inertial number between the particle
    snapshots either side of the peak snapshot (the incremental displacement shows the active band,
    not the pre-peak creep); quasi_static = I < 1e−3 (None when I is undefined)."""
    out = Stage(values={k: math.nan for k in BAND_KEYS})
    if particles is None or particles.empty:
        out.reasons = dict.fromkeys(BAND_KEYS, "no Particles table")
    elif ps.key is None:
        out.reasons = dict.fromkeys(BAND_KEYS, ps.reasons.get("peak_snapshot", "no peak snapshot"))
    else:
        psnaps = np.unique(particles["snapshot"].to_numpy())
        i = int(np.searchsorted(psnaps, ps.key))
        s0, s1 = psnaps[max(i - 1, 0)], psnaps[min(i + 1, psnaps.size - 1)]
        if s0 == s1:
            out.reasons = dict.fromkeys(BAND_KEYS, "fewer than two particle snapshots")
        else:
            d50, z_ref = case.d50, reg.rect[2]
            prof = st.displacement_profile(particles, s0, s1, z_ref,
                                           period=case.box_length if case.periodic else None)
            band, why = st.shear_band(prof["z"], prof["U"], z_ref, d50)
            out.values["shear_band_d50"] = band
            if why:
                out.reasons["shear_band_d50"] = why
            rate = st.shear_rate_from_profile(particles[particles["snapshot"].between(s0, s1)],
                                              z_min=z_ref - 0.5 * d50,
                                              z_max=reg.soil_top if math.isfinite(reg.soil_top) else None)
            out.values["shear_rate"] = rate
            out.values["inertial_number"] = st.inertial_number(rate, d50, case.normal_stress, case.density)
            if not math.isfinite(out.values["inertial_number"]):
                out.reasons["shear_rate"] = out.reasons["inertial_number"] = \
                    "fewer than two grain layers in the velocity profile"
    i_num = out.values["inertial_number"]
    out.values["quasi_static"] = bool(i_num < st.QUASI_STATIC_I) if math.isfinite(i_num) else None
    return out


# ---- specimen ------------------------------------------------------------------------------------

SPECIMEN_KEYS = ("solid_fraction", "solid_fraction_end", "max_overlap_d50")


def solid_fraction(case, particles: pd.DataFrame, snapshot) -> float:
    """Area of the grains' sections over the area they sit in [-] (2D: Σπr² of the grains whose
    centres lie in the rectangle, over its area), in the engine frame at one snapshot. Rectangle:
    3 D50 clear of each side wall; from 1 D50 above the surface's peaks (box: 2 D50 above the floor)
    to 3 D50 below the soil's top (highest grain top), so that no boundary's looser layer counts."""
    d = case.d50
    p = particles[particles["snapshot"].to_numpy() == snapshot]
    if p.empty:
        return math.nan
    r = p["radius"].to_numpy(float)
    x, z = p["x"].to_numpy(float), p["z"].to_numpy(float)
    x0, x1 = 3 * d, case.box_length - 3 * d
    z0 = (float(np.max(case.surface().z)) + d) if case.test == "interface" else 2 * d
    z1 = float(np.max(z + r)) - 3 * d
    if not (x1 > x0 and z1 > z0):
        return math.nan
    inside = (x > x0) & (x < x1) & (z > z0) & (z < z1)
    if getattr(case, "three_d", False):     # 3D: volume of the grains over the slab's, the cell's depth
        return float(4 / 3 * np.pi * np.sum(r[inside] ** 3) / ((x1 - x0) * (z1 - z0) * case.box_depth))
    return float(np.pi * np.sum(r[inside] ** 2) / ((x1 - x0) * (z1 - z0)))


def specimen(case, particles, contacts: pd.DataFrame) -> Stage:
    """The specimen's solid fraction at the start and at the end of the shear (engine frame:
    the particle table as the engine wrote it), and the largest overlap of any contact [D50]: a
    grain jammed against a wall's edge shows as 0.1–0.2 D50 where free shearing stays below 0.07
    (G = 50 MPa, 1044 grains; docs/strength.md)."""
    out = Stage(values=dict.fromkeys(SPECIMEN_KEYS, math.nan))
    if len(contacts):
        out.values["max_overlap_d50"] = float(contacts["overlap"].max()) / case.d50
    else:
        out.reasons["max_overlap_d50"] = "no contacts"
    if particles is None or particles.empty:
        out.reasons |= {k: "no particle snapshots" for k in SPECIMEN_KEYS[:2]}
        return out
    snaps = np.sort(particles["snapshot"].unique())
    out.values.update(solid_fraction=solid_fraction(case, particles, snaps[0]),
                      solid_fraction_end=solid_fraction(case, particles, snaps[-1]))
    for k in SPECIMEN_KEYS[:2]:
        if not math.isfinite(out.values[k]):
            out.reasons[k] = "the soil is shallower than its boundary layers (3 D50 + 1 D50)"
    return out


# ---- profile -------------------------------------------------------------------------------------

def profile_features(case) -> Stage:
    """θa (both filters), Rn, Rnc and the mean asperity slope of an interface case's profile; of an
    areal scan's closed patch (Case.surface_patch), the same of the normals pooled over the patch's
    grid lines along the shear, each read as periodic (surface.patch.theta_a_patch)."""
    out = Stage(values=dict.fromkeys(PROFILE_KEYS, math.nan))
    if case.test != "interface" or case.profile is None:
        out.reasons = dict.fromkeys(PROFILE_KEYS, "box test: no surface profile")
        return out
    from interphase.surface.normals import theta_a_filters
    from interphase.surface.builder import from_spec

    patch = case.surface_patch() if hasattr(case, "surface_patch") else None
    if patch is not None:       # an areal scan's closed patch: the pooled θa of its lines along the shear
        from interphase.surface.patch import theta_a_patch

        t = theta_a_patch(patch, case.d50, (92, 90))["+x"]
    else:
        # the surface the engine sheared (Case.sheared_surface); a saw-tooth is periodic: the trace of
        # n periods is n copies of one period's, so one period gives the same θa, Rn, Rnc and slope at
        # 1/n of the cost
        periodic = case.profile.kind in ("sawtooth", "asymmetric")
        prof = from_spec(case.profile, case.d50, case.d50) if periodic else case.sheared_surface()
        t = theta_a_filters(prof, case.d50, (92, 90))
    t92, t90 = t[92], t[90]
    out.values.update(theta_a_deg_92=t92.theta_a_deg, theta_a_deg_90=t90.theta_a_deg, rn=t92.rn, rnc=t92.rnc,
                      mean_slope_deg=t92.mean_slope_deg)
    if t92.reason:
        out.reasons["theta_a_deg_92"] = t92.reason
    if t90.reason:
        out.reasons["theta_a_deg_90"] = t90.reason
    if not math.isfinite(t92.mean_slope_deg):
        out.reasons["mean_slope_deg"] = "no asperity face steeper than 2° (flat surface)"
    return out


# ---- series --------------------------------------------------------------------------------------

def series(hist: pd.DataFrame, s: Strength, window: float, ps: PeakSnapshot, surf: Surface,
           reg: Region) -> pd.DataFrame:
    """History rows (shear_disp, stress_ratio, its moving average over the balanced rows,
    load_balanced, platen_z, normal_force) with the snapshot quantities set on the History row
    nearest each snapshot (NaN elsewhere)."""
    out = _series(hist, s.ratio, window, surf.table, reg.stress, reg.anisotropy, ps.snaps)
    if len(hist):
        out["load_balanced"] = s.balanced
        out["stress_ratio_smooth"] = st.moving_average(out["shear_disp"].to_numpy(float),
                                                       s.used.to_numpy(float), window)
    return out


def mean_over_loaded(series_: pd.DataFrame, key: str) -> Stage:
    """Mean of a snapshot quantity over the snapshots whose History row is load-balanced (the
    surface carries its share of the platen's load): steadier than the one peak snapshot, which a
    stick–slip event sets (docs/liggghts.md: θr over the shear vs δ)."""
    name = key.replace("_deg", "_mean_deg")
    if key not in series_ or "load_balanced" not in series_:
        return Stage({name: math.nan}, {name: "no snapshot series (box test or no contacts)"})
    v = series_.loc[series_["load_balanced"].astype(bool) & series_[key].notna(), key]
    if v.empty:
        return Stage({name: math.nan}, {name: "no snapshot where the surface carries its share of the platen's load"})
    return Stage({name: float(v.mean())})


def _series(hist, ratio, window, surf, stress, region_, snaps) -> pd.DataFrame:
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
        if "r_yy" in surf.columns:      # 3D: the resultant tensor's out-of-plane share
            snap["r_yy_surface"] = surf["r_yy"]
    if stress is not None:
        snap["stress_ratio_region"] = stress["stress_ratio"]
        snap["qp_region"] = stress["qp"]
        snap["principal_stress_deg_region"] = stress["principal_deg"]
    if region_ is not None:
        snap["theta_r_region_deg"] = region_["theta_r_deg"]
        snap["theta_n_region_deg"] = region_["theta_n_deg"]
        snap["qp_sff"] = region_["qp_sff"]
    if base.empty:
        return snap.reset_index().rename(columns={"snapshot_shear_disp": "shear_disp"})
    cols = list(snap.columns)
    for c in cols:
        base[c] = np.nan
    base["snapshot"] = pd.array([pd.NA] * len(base), dtype="Int64")
    if len(snap):
        s = base["shear_disp"].to_numpy()
        at = snap["snapshot_shear_disp"].to_numpy()
        pos = np.searchsorted(s, at)
        lo = np.clip(pos - 1, 0, len(s) - 1)
        hi = np.clip(pos, 0, len(s) - 1)
        near = np.where(np.abs(s[lo] - at) <= np.abs(s[hi] - at), lo, hi)
        for c in cols:
            vals = base[c].to_numpy(float).copy()
            vals[near] = snap[c].to_numpy(float)
            base[c] = vals
        sn = base["snapshot"].copy()
        sn.iloc[near] = snap.index.to_numpy()
        base["snapshot"] = sn
    return base
