"""One compression curve read in Rowe's terms, as the state-line study reads the card's runs and the
laboratory's records (studies/state_line/).

Conventions: strains are fractions, compression positive (εv > 0 contracts); the dilatancy rate is
r = −dεv/dε1 (> 0 dilates); ratio is σ1′/σ3′; angles in degrees. Rowe (1962) in triaxial compression:
σ1′/σ3′ = K (1 + r), K = tan²(45° + φ_f/2), so the friction part at the peak is
φ_f = asin((K − 1)/(K + 1)) with K = R_peak / (1 + r_peak).

- `rate_at(eps1, epsv, at)`: r of a straight line over ε1 within ±ROWE_HALF (0.5 %) of `at`.
- `state_row(eps1, epsv, ratio, e)`: analysis.triaxial.shear_state's φ_peak, ψ_max, end state, plus
  r and ψ at the peak, Rowe's φ_f, e0 and ε1 at ψ_max (the centre of its window).
- `record_rows(folder)`: `state_row` of every laboratory record (*.dat) in a folder, with σ3′ [kPa].
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.analysis.triaxial import friction_angle, psi_from_rate, shear_state
from interphase.io.lab_triaxial import read_triaxial

ROWE_HALF = 0.005      # the rate at the peak: ε1 within ±0.5 % of it [-]


def rate_at(eps1, epsv, at: float) -> float:
    """−dεv/dε1 of a straight line over ε1 within ±ROWE_HALF of `at`; NaN with < 3 samples there."""
    x, v = np.asarray(eps1, float), np.asarray(epsv, float)
    sel = np.abs(x - at) <= ROWE_HALF
    return -float(np.polyfit(x[sel], v[sel], 1)[0]) if sel.sum() >= 3 else math.nan


def rowe_friction_deg(ratio_peak: float, rate_peak: float) -> float:
    """Rowe's friction part at the peak [°]: the Mohr–Coulomb angle of K = ratio_peak / (1 + rate_peak)."""
    return float(friction_angle(ratio_peak / (1 + rate_peak)))


def state_row(eps1, epsv, ratio, e) -> dict:
    """The curve's peak, dilatancy and end state with Rowe's reading at the peak (module docstring)."""
    s = shear_state(eps1, epsv, ratio, e)
    r_peak = rate_at(eps1, epsv, s.eps1_peak)
    return dict(phi_peak_deg=s.phi_peak_deg, eps1_peak=s.eps1_peak, psi_max_deg=s.psi_max_deg,
                eps1_psi=s.eps1_psi + s.window / 2, rate_max=s.dilatancy_max, rate_peak=r_peak,
                psi_peak_deg=float(psi_from_rate(r_peak)),
                phi_end_deg=s.phi_end_deg, e0=float(np.asarray(e, float)[0]), e_end=s.e_end,
                dilatancy_end=s.dilatancy_end, eps1_last=s.eps1_last,
                phi_f_deg=rowe_friction_deg(s.ratio_peak, r_peak))


def record_rows(folder: str | Path) -> pd.DataFrame:
    """One row per laboratory record (*.dat, io.lab_triaxial) in `folder`: source "sand", its name,
    σ3′ at the start [kPa] and its `state_row`."""
    rows = []
    for p in sorted(Path(folder).glob("*.dat")):
        rec = read_triaxial(p)
        t = rec.table
        rows.append({"source": "sand", "name": p.stem, "sigma3_kPa": rec.sigma3_start / 1e3,
                     **state_row(t["eps1"], t["epsv"], t["ratio"], t["e"])})
    return pd.DataFrame(rows)
