"""Symmetric 2×2 tensor helpers and the two angle readings of docs/methods.md §0.

A tensor is given by its components (x11, x22, x12), arrays allowed (broadcast).
θ: radians counterclockwise from +x in [0, π). ψ: θ − π/2, tilt from vertical (positive toward −x).
"""

from __future__ import annotations

import numpy as np


def aniso(x11, x22, x12):
    """Anisotropy magnitude 2·sqrt((X11−X22)² + 4·X12²)."""
    return 2.0 * np.sqrt((np.asarray(x11) - x22) ** 2 + 4.0 * np.asarray(x12) ** 2)


def direction(x11, x22, x12):
    """Major principal direction ½·atan2(2·X12, X11−X22) mod π, radians ccw from +x."""
    return np.mod(0.5 * np.arctan2(2.0 * np.asarray(x12), np.asarray(x11) - x22), np.pi)


def psi_deg(theta_rad):
    """ψ in degrees (tilt from vertical, positive toward −x) from θ radians ccw from +x."""
    return np.degrees(theta_rad) - 90.0


def ccw_deg(theta_rad):
    """θ in degrees ccw from +x, in [0, 180)."""
    return np.mod(np.degrees(theta_rad), 180.0)
