"""Quasi-static checks of a finished run (engine-free: Case + Results → a dict for the summary).

- inertial number I = γ̇·D50 / sqrt(σn/ρ) (docs/methods.md §6, `strength.inertial_number`), γ̇ the largest
  layer-to-layer shear rate of the measured velocity profile (`strength.shear_rate_from_profile`,
  1-D50 layers, snapshots after the first). Quasi-static means I < 1e−3.
- overlaps: max and mean contact overlap / D50.
- platen-force error: mean and max |F − F_target| / F_target over the shear, F_target = σ·L·t.
- grains that left: grains missing from the last snapshot (`grains_left`: they passed under a side
  wall with the surface and the engine removed them, engines.device), and grains outside the soil
  box [0, L] in it (`grains_outside_box`: walled interface tests only; the box test's lower half
  carries its grains past x = L by design, and in the periodic device x wraps, so 0 there).
Units SI; velocities in the analysis frame (the surface moves −v, so grain velocity relative to the
surface is vx + v).
"""

from __future__ import annotations

import math

import numpy as np

from interphase.analysis.strength import inertial_number, shear_rate_from_profile
from interphase.case import Case

QUASI_STATIC_I = 1e-3


def checks(case: Case, results) -> dict:
    """The quasi-static checks of docs/methods.md/issue 3 as a flat dict (NaN where not computable)."""
    out: dict = {}
    parts = results.particles
    if parts is not None and not parts.empty:
        # the gradient of vx does not depend on the frame's velocity offset
        gd = shear_rate_from_profile(parts, snapshots=np.unique(parts.snapshot)[1:], bin_height=case.d50)
        out["shear_rate_max"] = gd
        out["inertial_number"] = inertial_number(gd, case.d50, case.normal_stress, case.density) \
            if math.isfinite(gd) else math.nan
        counts = parts.groupby("snapshot").size()
        out["grains_left"] = int(counts.iloc[0] - counts.iloc[-1])
        last = parts[parts.snapshot == parts.snapshot.max()]
        walled_interface = case.test == "interface" and not case.periodic
        out["grains_outside_box"] = int(((last.x < 0) | (last.x > case.box_length)).sum()) if walled_interface else 0
    else:
        out.update(shear_rate_max=math.nan, inertial_number=math.nan, grains_left=-1, grains_outside_box=-1)
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
