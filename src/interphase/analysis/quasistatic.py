"""Quasi-static checks of a finished run (engine-free: Case + Results → a dict for the summary).

- inertial number I = γ̇·D50 / sqrt(σn/ρ) (METHODS.md §6), γ̇ the largest shear rate of the measured
  velocity profile: grains binned by height (1 D50 bins) above the surface, mean velocity relative to
  the surface per bin and snapshot, |Δu/Δz| between neighbouring bins, averaged over the snapshots
  after the first. Quasi-static means I < 1e−3.
- overlaps: max and mean contact overlap / D50.
- platen-force error: mean and max |F − F_target| / F_target over the shear, F_target = σ·L·t.
- lost grains: grains missing from the last snapshot, and grains outside the soil box [0, L].
Units SI; velocities in the analysis frame (the surface moves −v, so grain velocity relative to the
surface is vx + v).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from interphase.case import Case

QUASI_STATIC_I = 1e-3


def inertial_number(gamma_dot: float, d50: float, sigma_n: float, density: float) -> float:
    """I = γ̇·D50 / sqrt(σn/ρ) [-]; γ̇ [1/s], D50 [m], σn [Pa], ρ [kg/m³]."""
    return gamma_dot * d50 / math.sqrt(sigma_n / density)


def shear_rate_profile(particles: pd.DataFrame, d50: float, surface_velocity: float,
                       z_ref: float = 0.0) -> pd.DataFrame:
    """Mean velocity relative to the surface per 1-D50 height bin, averaged over snapshots ≥ 1.

    Returns bins (z_mid [m], u [m/s], count). `surface_velocity` is the surface's x velocity [m/s]
    (−v in these decks)."""
    p = particles[particles.snapshot >= 1]
    if p.empty:
        return pd.DataFrame(columns=["z_mid", "u", "count"])
    b = np.floor((p.z.to_numpy() - z_ref) / d50).astype(int)
    u = p.vx.to_numpy() - surface_velocity
    g = pd.DataFrame({"bin": b, "u": u}).groupby("bin")["u"].agg(["mean", "size"])
    g = g[g["size"] >= 3]
    return pd.DataFrame({"z_mid": z_ref + (g.index.to_numpy() + 0.5) * d50, "u": g["mean"].to_numpy(),
                         "count": g["size"].to_numpy()})


def max_shear_rate(profile: pd.DataFrame) -> float:
    """Largest |Δu/Δz| between neighbouring bins [1/s]; NaN with fewer than two bins."""
    if len(profile) < 2:
        return math.nan
    return float(np.max(np.abs(np.diff(profile.u.to_numpy()) / np.diff(profile.z_mid.to_numpy()))))


def checks(case: Case, results) -> dict:
    """The quasi-static checks of METHODS.md/issue 3 as a flat dict (NaN where not computable)."""
    out: dict = {}
    parts = results.particles
    surface_v = -case.shear_velocity
    if parts is not None and not parts.empty:
        prof = shear_rate_profile(parts, case.d50, surface_v if case.test == "interface" else 0.0,
                                  z_ref=float(parts.z.min()) - case.d50 / 2)
        gd = max_shear_rate(prof)
        out["shear_rate_max"] = gd
        out["inertial_number"] = inertial_number(gd, case.d50, case.normal_stress, case.density) \
            if math.isfinite(gd) else math.nan
        counts = parts.groupby("snapshot").size()
        out["lost_grains"] = int(counts.iloc[0] - counts.iloc[-1])
        last = parts[parts.snapshot == parts.snapshot.max()]
        out["grains_outside_box"] = int(((last.x < 0) | (last.x > case.box_length)).sum())
    else:
        out.update(shear_rate_max=math.nan, inertial_number=math.nan, lost_grains=-1, grains_outside_box=-1)
    out["quasi_static"] = bool(out["inertial_number"] < QUASI_STATIC_I) if math.isfinite(out["inertial_number"]) else False
    c = results.contacts
    ov = c.overlap.to_numpy() / case.d50 if len(c) else np.array([np.nan])
    out["overlap_max_d50"] = float(np.nanmax(ov)) if len(c) else math.nan
    out["overlap_mean_d50"] = float(np.nanmean(ov)) if len(c) else math.nan
    h = results.history
    target = case.normal_stress * case.box_length * case.thickness
    if len(h):
        err = np.abs(h.normal_force.to_numpy() - target) / target
        out["platen_force_error_mean"] = float(err.mean())
        out["platen_force_error_max"] = float(err.max())
    else:
        out["platen_force_error_mean"] = out["platen_force_error_max"] = math.nan
    return out
