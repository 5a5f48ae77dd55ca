"""Pure filters of a Profile: the centerline correction, uniform resampling and the Gaussian
profile filter (ISO 16610-21 style), and the study's recipe for a measured line. No file is read."""

from __future__ import annotations

import math

import numpy as np

from interphase.errors import InputError
from interphase.surface.base import Profile


def centerline(profile: Profile) -> Profile:
    """Remove the least-squares line z = a + b·x (the centerline correction)."""
    b, a = np.polyfit(profile.x, profile.z, 1)
    return Profile(profile.x, profile.z - (a + b * profile.x), profile.periodic, profile.name)


def resample(profile: Profile, dx: float) -> Profile:
    """Linear interpolation on a uniform step close to `dx` [m] spanning the same x range."""
    n = max(2, int(math.ceil(profile.length / dx)) + 1)
    x = np.linspace(profile.x[0], profile.x[-1], n)
    return Profile(x, np.interp(x, profile.x, profile.z), profile.periodic, profile.name)


def gaussian_filter(profile: Profile, cutoff: float, keep: str = "roughness") -> Profile:
    """ISO 16610-21 style Gaussian profile filter with cut-off wavelength `cutoff` [m].

    The weighting function s(x) = exp(−π (x/(α λc))²)/(α λc), α = sqrt(ln 2/π), is a Gaussian of
    standard deviation α λc / sqrt(2π); it passes 50 % amplitude at λc. The filtered line is the
    waviness; keep='roughness' (default) returns z − waviness, keep='waviness' the line itself.
    The profile is resampled uniformly first (median step). Ends: mirror extension (scipy 'reflect').
    """
    if not (math.isfinite(cutoff) and cutoff > 0):
        raise InputError(f"cut-off must be a positive length, got {cutoff!r}", where="cutoff")
    if keep not in ("roughness", "waviness"):
        raise InputError(f"keep must be roughness or waviness, got {keep!r}", where="keep")
    dx = float(np.median(np.diff(profile.x)))
    uni = resample(profile, dx)
    alpha = math.sqrt(math.log(2) / math.pi)
    sigma = alpha * cutoff / math.sqrt(2 * math.pi) / (uni.x[1] - uni.x[0])
    from scipy.ndimage import gaussian_filter1d   # here, not at the top: every engine worker imports this module

    wav = gaussian_filter1d(uni.z, sigma, mode="wrap" if profile.periodic else "reflect")
    z = uni.z - wav if keep == "roughness" else wav
    return Profile(uni.x, z, profile.periodic, profile.name)


def prepare_measured(profile: Profile, cutoff: float | None = None) -> Profile:
    """The study's recipe for a measured profile: centerline-corrected, optionally Gaussian-filtered."""
    out = centerline(profile)
    if cutoff is not None:
        out = gaussian_filter(out, cutoff)
    return out
