"""Normalised roughness Rn (Kishida & Uesugi 1987) and Rnc(D50) (docs/methods.md §4).

Rn = Rt,ave(L = D50)/D50: the mean over every window start of (max − min) within a window of length
D50 of the centerline-corrected profile; running max/min over numpy's window view (`running`).
Rnc(D50) is the same on the centroid trace (pass the trace).
"""

from __future__ import annotations

import math

import numpy as np

from interphase.surface.base import Profile
from interphase.surface.filters import centerline, resample
from interphase.surface.trace import uniform_grid


def running(z: np.ndarray, w: int, op=np.max) -> np.ndarray:
    """op (np.max or np.min) over every window z[i:i+w], i = 0 … z.size − w. Not scipy.ndimage's
    maximum_filter1d (the same numbers): importing scipy.ndimage costs ~0.3 CPU-s, paid once per
    engine-run process by every interface summary (Rn, Rnc); numpy's window view costs O(N·w), a few
    ms at the 500 samples a window rt_ave uses."""
    return op(np.lib.stride_tricks.sliding_window_view(z, w), axis=1)


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
        zz = np.concatenate([z, np.resize(z, w - 1)])     # wrapped: z.size windows, whatever the period
        mx = running(zz, w, np.max)
        mn = running(zz, w, np.min)
    else:
        if z.size < w:
            return math.nan
        mx = running(z, w, np.max)
        mn = running(z, w, np.min)
    return float(np.mean(mx - mn))


def rn(profile: Profile, d50: float) -> float:
    """Rn = Rt,ave(L = D50)/D50 (on a trace: Rnc(D50))."""
    return rt_ave(profile, d50) / d50
