"""Bolton's (1986) stress–dilatancy correlation for sands: the strength and dilatancy a sand of known
relative density should show in drained triaxial compression at a stress, a reference where the
laboratory records stop.

Bolton, M. D. (1986). The strength and dilatancy of sands. Géotechnique 36(1):65–78:
    I_R = Dr (Q − ln p′) − R_B,  Q = 10, R_B = 1, p′ in kPa, Dr as a fraction, I_R kept in [0, 4];
    triaxial compression: φ_max − φ_crit = 3 I_R [°] and (−dεv/dε1)_max = 0.3 I_R;
    I_R ≤ 0: non-dilative (φ_max = φ_crit, no dilation).
p′ is the mean effective stress at failure. In a drained triaxial test at cell pressure σ3′ it is
σ3′ (1 + 2 R)/3 with R = σ1′/σ3′ = (1 + sin φ_max)/(1 − sin φ_max), which depends on φ_max: the pair
is solved as a fixed point. ψ_max is read from the rate with the project's triaxial definition
(analysis.triaxial.psi_from_rate: sin ψ = r/(2 + r)), as the records' and the model's ψ_max are.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from interphase.analysis.triaxial import psi_from_rate

Q = 10.0
R_B = 1.0
IR_MAX = 4.0
#: Bolton's triaxial coefficients: degrees of φ_max − φ_crit, and −dεv/dε1, per unit of I_R
PHI_PER_IR = 3.0
RATE_PER_IR = 0.3


@dataclass(frozen=True)
class BoltonState:
    relative_density: float      # Dr [-]
    cell_pressure: float         # σ3′ [Pa]
    mean_stress: float           # p′ at failure [Pa]
    index: float                 # I_R [-], in [0, IR_MAX]
    phi_peak_deg: float
    psi_max_deg: float
    dilatancy_max: float         # (−dεv/dε1)_max [-]

    def to_dict(self) -> dict:
        return asdict(self)


def dilatancy_index(relative_density, mean_stress) -> np.ndarray:
    """I_R = Dr (Q − ln p′[kPa]) − R_B, kept in [0, IR_MAX]; mean_stress [Pa]."""
    dr = np.asarray(relative_density, float)
    p_kpa = np.asarray(mean_stress, float) / 1e3
    return np.clip(dr * (Q - np.log(p_kpa)) - R_B, 0.0, IR_MAX)


def triaxial(relative_density: float, cell_pressure: float, phi_crit_deg: float, tol: float = 1e-10) -> BoltonState:
    """Bolton's φ_max and ψ_max in drained triaxial compression at cell pressure σ3′ [Pa] for a sand
    of critical-state angle φ_crit [°] at relative density Dr [-]; p′ at failure by fixed point."""
    if not (math.isfinite(cell_pressure) and cell_pressure > 0):
        raise ValueError(f"cell pressure must be a positive stress in Pa, got {cell_pressure!r}")
    p = cell_pressure
    for _ in range(200):        # a contraction: |dp_next/dp| < 1 wherever I_R is in (0, 4)
        ir = float(dilatancy_index(relative_density, p))
        s = math.sin(math.radians(phi_crit_deg + PHI_PER_IR * ir))
        p_next = cell_pressure * (1 + 2 * (1 + s) / (1 - s)) / 3
        if abs(p_next - p) <= tol * p:
            break
        p = p_next
    ir = float(dilatancy_index(relative_density, p_next))
    rate = RATE_PER_IR * ir
    return BoltonState(float(relative_density), float(cell_pressure), float(p_next), ir,
                       phi_crit_deg + PHI_PER_IR * ir, float(psi_from_rate(rate)), rate)
