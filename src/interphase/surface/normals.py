"""Surface-normal distribution of the centroid trace and its principal direction θa (docs/methods.md §3).

Trace segment i (Δx_i > 0, Δc_i): outward normal angle θ_i = atan2(Δx_i, −Δc_i) in (0, π), weight
w_i = segment length. Keep the resisting side (normals tilted toward −x in the analysis frame: the
soil moves +x relative to the surface): filter 92 → θ > 92° (the study's default for construction
surfaces), filter 90 → θ ≥ 90° (flats included; for regular flat spacing Sr).
S = Σ w·exp(2iθ); θa(ccw) = ½ arg S mod π; θa = ψa = θa(ccw) − 90° (degrees from vertical).
No kept segment (a flat surface) → θa is NaN: "non-dilative".
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from interphase.errors import InputError
from interphase.surface.base import Profile
from interphase.surface.roughness import rn as _rn
from interphase.surface.trace import centroid_trace

FILTERS = (92, 90)
FLAT_TOLERANCE_DEG = 2.0   # segments flatter than this are "flats" for the mean asperity slope


def segment_normals(profile: Profile) -> tuple[np.ndarray, np.ndarray]:
    """(θ [rad, ccw from +x, in (0, π)], weight = segment length [m]) of every segment."""
    dx = np.diff(profile.x)
    dc = np.diff(profile.z)
    return np.arctan2(dx, -dc), np.hypot(dx, dc)


def keep_mask(theta: np.ndarray, filt: int | None) -> np.ndarray:
    """Which normals a filter keeps: 92 → θ > 92°, 90 → θ ≥ 90°, None → all."""
    if filt is None:
        return np.ones(theta.shape, bool)
    if filt == 92:
        return theta > math.radians(92.0)
    if filt == 90:
        # ≥ 90° with a tolerance of a few ulps: a flat trace segment is exactly vertical-normal
        return theta >= math.radians(90.0) - 1e-12
    raise InputError(f"unknown filter {filt!r}", where="--filter", fix="use 92 or 90")


def principal_direction(theta: np.ndarray, weight: np.ndarray) -> float:
    """θa(ccw) [rad] of weighted axial directions: ½·arg Σ w·exp(2iθ) mod π; NaN if empty."""
    if theta.size == 0 or not np.any(weight > 0):
        return math.nan
    s = np.sum(weight * np.exp(2j * theta))
    return float(np.mod(0.5 * np.angle(s), np.pi))


def mean_asperity_slope_deg(profile: Profile) -> float:
    """Arithmetic mean |slope angle| [deg] of the profile's faces, flats (< 2°) excluded, each segment
    weighted by its horizontal length so that resampling does not change it. NaN if no face."""
    dx = np.diff(profile.x)
    ang = np.degrees(np.abs(np.arctan2(np.diff(profile.z), dx)))
    face = ang > FLAT_TOLERANCE_DEG
    if not face.any():
        return math.nan
    return float(np.sum(ang[face] * dx[face]) / np.sum(dx[face]))


@dataclass(frozen=True)
class ThetaA:
    theta_a_deg: float        # ψa, degrees from vertical (positive toward −x); NaN if non-dilative
    theta_a_ccw_deg: float    # θa, degrees counterclockwise from +x
    filter: int
    d50: float                # [m]
    rn: float                 # Rn (Kishida & Uesugi), raw centerline profile, L = D50
    rnc: float                # Rnc(D50), on the centroid trace
    mean_slope_deg: float     # mean asperity slope of the profile, flats excluded
    n_points: int             # trace points used
    kept_fraction: float      # length share of trace segments the filter kept
    max_tilt_deg: float       # largest |ψ| of any trace normal: how far from flat the trace gets
    dilative: bool
    reason: str               # why θa is NaN, else ""

    def to_dict(self) -> dict:
        return asdict(self)


def theta_a(profile: Profile, d50: float, filt: int = 92, dx: float | None = None) -> ThetaA:
    """θa of `profile` [m] for grains of median diameter d50 [m] (docs/methods.md §2–4)."""
    return theta_a_filters(profile, d50, (filt,), dx)[filt]


def theta_a_filters(profile: Profile, d50: float, filters=FILTERS, dx: float | None = None) -> dict[int, ThetaA]:
    """{filter: ThetaA} from one centroid trace (the trace is the expensive part)."""
    for filt in filters:
        if filt not in FILTERS:
            raise InputError(f"unknown filter {filt!r}", where="--filter", fix="use 92 or 90")
    trace = centroid_trace(profile, d50, dx)
    theta, w = segment_normals(trace)
    tilt = float(np.max(np.abs(np.degrees(theta) - 90.0))) if theta.size else 0.0
    shared = dict(d50=d50, rn=_rn(profile, d50), rnc=_rn(trace, d50), mean_slope_deg=mean_asperity_slope_deg(profile),
                  n_points=int(trace.x.size), max_tilt_deg=tilt)
    out = {}
    for filt in filters:
        keep = keep_mask(theta, filt)
        ccw = principal_direction(theta[keep], w[keep])
        reason = ""
        if math.isnan(ccw) or (filt == 90 and not np.any(theta[keep] > math.radians(90.0) + 1e-12)):
            reason = (f"non-dilative: no centroid-trace normal beyond the {filt}° filter at D50 = {d50 * 1e3:g} mm "
                      f"(largest normal tilt {tilt:.3g}°)")
            ccw = math.nan
        out[filt] = ThetaA(
            theta_a_deg=math.degrees(ccw) - 90.0 if not math.isnan(ccw) else math.nan,
            theta_a_ccw_deg=math.degrees(ccw) if not math.isnan(ccw) else math.nan,
            filter=filt,
            kept_fraction=float(w[keep].sum() / w.sum()) if w.sum() > 0 else 0.0,
            dilative=not math.isnan(ccw),
            reason=reason,
            **shared,
        )
    return out
