"""Summary of one cell run (triaxial / biaxial, engines/cell.py) from its history table (io/cell.py).

The strength and dilatancy come from `analysis.triaxial.shear_state`, the code that reads the
laboratory's records, with one step more: the stress ratio is smoothed over SMOOTH_EPS1 of ε1 (a
centred moving average) before its peak is taken, because one run's ratio fluctuates as force chains
rearrange and its largest fluctuation is no peak. 1 % of ε1 is the window whose per-run maximum
reads a known hump's peak through real runs' fluctuation within ±0.06° (studies/peak_estimators/triaxial_peak.py; 0.5 %
reads +0.03 to +0.15° high, 2 % −0.10 to −0.18° low). On the laboratory's 21 records, already smooth,
the same smoothing lowers φ_peak by 0.005–0.17° (tests/test_cell.py). The volumetric strain is not
smoothed: ψ's 1 % straight-line window is its smoothing, as for the laboratory. A physical case's
values are read from its seeds together (analysis/cell_ensemble.py), not from these rows.

Also the checks a reader of the run wants: how well σ3′ was held (largest relative departure of the
lateral stress from the target over the compression), the inertial number I = γ̇ d50 √(ρ/p′) with
γ̇ = ε̇1 − ε̇3 measured from the cell's own strain rates (the largest over the compression; < 1e-3
is quasi-static), the void ratio at the start, at the peak and at the end.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from interphase.analysis.strength import moving_average
from interphase.analysis.triaxial import WINDOW, shear_state

SMOOTH_EPS1 = 0.01      # [-] the moving-average window on ε1 of one run's curves


def lateral_strain(h: pd.DataFrame, three_d: bool) -> np.ndarray:
    """ε3 [-] (compression positive) from εv and ε1: 3D, εv = ε1 + 2ε3 (axisymmetric on average);
    2D, εv = ε1 + ε3. Small-strain sums, as the laboratory's."""
    return (h["epsv"].to_numpy() - h["eps1"].to_numpy()) / (2 if three_d else 1)


def summarise_cell(case, results) -> tuple[dict, pd.DataFrame]:
    """(summary row, series) of a finished triaxial or biaxial run."""
    h = results.history
    three_d = case.test == "triaxial"
    x = h["eps1"].to_numpy()
    ratio = moving_average(x, h["ratio"].to_numpy(), SMOOTH_EPS1)
    epsv = h["epsv"].to_numpy()
    if np.ptp(x) >= WINDOW:
        state = shear_state(x, epsv, ratio, h["e"].to_numpy()).to_dict()
    else:   # a token compression (campaign density): the start's void ratio is what it is for
        state = {"phi_peak_deg": math.nan, "eps1_peak": math.nan, "psi_max_deg": math.nan, "phi_end_deg": math.nan,
                 "ratio_peak": math.nan}
    i_peak = int(np.argmin(np.abs(x - state["eps1_peak"]))) if np.isfinite(state["eps1_peak"]) else 0
    t = h["time"].to_numpy()
    e3 = lateral_strain(h, three_d)
    gamma_dot = np.gradient(x - e3, t) if len(t) > 2 else np.array([math.nan])
    p = h["p"].to_numpy()
    inertial = gamma_dot * case.d50 * np.sqrt(case.density / np.where(p > 0, p, np.nan))
    held = np.abs(h["sigma3"].to_numpy() / case.normal_stress - 1)
    row = {"test": case.test, "case": case.label(), **state,
           "e0": float(h["e"].iloc[0]), "e_peak": float(h["e"].iloc[i_peak]), "void_ratio_start": float(h["e"].iloc[0]),
           "sigma3_departure_max": float(np.nanmax(held)), "sigma3_departure_mean": float(np.nanmean(held)),
           "inertial_number_max": float(np.nanmax(inertial)), "inertial_number_mean": float(np.nanmean(inertial)),
           "coordination_start": float(2 * h["n_contacts"].iloc[0] / case.n_grains),
           "n_grains": int(case.n_grains), "peak_stress_ratio": float(state["ratio_peak"])}
    series = h.assign(ratio_smooth=ratio, eps3=e3)
    return row, series
