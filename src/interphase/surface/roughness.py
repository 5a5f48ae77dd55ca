"""Normalised roughness Rn (Kishida & Uesugi 1987) and Rnc(D50) (docs/methods.md §4).

Rn = Rt,ave(L = D50)/D50: the mean over every window start of (max − min) within a window of length
D50 of the centerline-corrected profile; O(N) with running max/min filters (scipy.ndimage).
Rnc(D50) is the same on the centroid trace (pass the trace).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.ndimage import maximum_filter1d, minimum_filter1d

from interphase.surface.base import Profile
from interphase.surface.filters import centerline, resample
from interphase.surface.trace import uniform_grid


def rt_ave(profile: Profile, window: float, dx: float | None = None) -> float:
    """Mean peak-to-valley height [m] over sliding windows of `window` m (every start on a uniform
    grid of step ≤ dx, default window/500). Periodic profiles wrap; open ones use full windows only.
    The least-squares line is removed first."""
    dx = dx or window / 500
    if profile.periodic:
        _, z, step = uniform_grid(profile, dx)
    else:
        prof = centerline(profile)
        uni = resample(prof, dx)
        z, step = uni.z, uni.x[1] - uni.x[0]
    w = int(round(window / step)) + 1           # samples in a closed window of length L
    if profile.periodic:
        # a periodic profile is its own centerline over whole periods, up to a constant
        zz = np.concatenate([z, z[:w]])
        mx = maximum_filter1d(zz, w, origin=-(w // 2))[: z.size]
        mn = minimum_filter1d(zz, w, origin=-(w // 2))[: z.size]
    else:
        if z.size < w:
            return math.nan
        mx = maximum_filter1d(z, w, origin=-(w // 2))[: z.size - w + 1]
        mn = minimum_filter1d(z, w, origin=-(w // 2))[: z.size - w + 1]
    return float(np.mean(mx - mn))


def rn(profile: Profile, d50: float) -> float:
    """Rn = Rt,ave(L = D50)/D50 (on a trace: Rnc(D50))."""
    return rt_ave(profile, d50) / d50
