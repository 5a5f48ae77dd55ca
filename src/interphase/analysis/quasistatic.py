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

from interphase.analysis.strength import QUASI_STATIC_I, inertial_number, shear_rate_from_profile
from interphase.case import Case



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


# ---- before the run: the estimate from a case's inputs (campaign.checks, campaign.plan) --------------
#: Shear-band thickness [D50] the inertial-number estimate assumes, per device, from the summaries' own
#: I (the grains' velocity profiles; band = v/(I·√(σ/ρ))), 100 kPa, ~1040 grains, G = 50 MPa:
#:  walled: 2.9–5.8e-3 on 45° and 72° saw-teeth at 0.05 m/s (band 2–5 D50; docs/strength.md): 3 D50
#:    reproduces the interface values, the ones the warning must not miss;
#:  periodic: at 0.02 m/s 2.5–6.3e-4 over 15 runs (band 5.1–13 D50, median 8.5), at 0.05 m/s median
#:    1.15e-3 (band 7 D50) with single slip events down to 1 D50 (docs/convergence.md): 5 D50, the
#:    thinnest band of the quasi-static runs.
#:  periodic3d: not measured yet; taken as the periodic device's (docs/3d.md).
BAND_ESTIMATE_D50 = {"walled": 3.0, "periodic": 5.0, "periodic3d": 5.0}


def inertial_estimate(case: Case, band_d50: float | None = None) -> float:
    """I ≈ γ̇·D50/√(σ/ρ) with γ̇ = v/(band_d50·D50) (default: the case's device's band), before the run [-]."""
    band = band_d50 or BAND_ESTIMATE_D50[case.device]
    return case.shear_velocity / (band * math.sqrt(case.normal_stress / case.density))


def quasi_static_speed(case: Case, band_d50: float | None = None, limit: float = QUASI_STATIC_I) -> float:
    """The shear speed [m/s] at which the estimate reaches `limit`."""
    band = band_d50 or BAND_ESTIMATE_D50[case.device]
    return limit * band * math.sqrt(case.normal_stress / case.density)


def rate_warnings(cases) -> list[str]:
    """One line per distinct (speed, stress, density) whose estimated I ≥ 1e-3, naming the speed
    that would make it quasi-static and how many cases it concerns."""
    groups: dict[tuple, list] = {}
    for c in cases:
        groups.setdefault((c.shear_velocity, c.normal_stress, c.density, c.device), []).append(c)
    out = []
    for (v, sigma, rho, dev), cs in sorted(groups.items()):
        i = inertial_estimate(cs[0])
        if i >= QUASI_STATIC_I:
            fix = quasi_static_speed(cs[0])
            out.append(f"{len(cs)} case(s) at shear_velocity = {v:g} m/s, σ = {sigma:g} Pa: estimated inertial "
                       f"number I ≈ {i:.1e} ≥ {QUASI_STATIC_I:g} (not quasi-static; band "
                       f"{BAND_ESTIMATE_D50[dev]:g} D50 assumed in the {dev} device); shear_velocity ≤ {fix:.3g} m/s "
                       "would make it quasi-static")
    return out
