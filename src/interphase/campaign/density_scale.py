"""A card's density scale fitted on several records of one stress: where each record sits on the
card's preparations, and the straight line from the laboratory's Dr to the model's
(docs/soils.md, "The density scale").

A calibration on one record sets the scale from that record alone (calibrate_cell._lab_scale). With
records at several densities of one stress, each record's preparation is found on a sweep of the
card's preparations at that stress (`anchor_preparation`), read as the model's Dr on the card's
void-ratio map there (`model_dr`), and the line `model Dr = lab_offset + lab_span · Dr` fitted
through them (`fit_scale`); whether the offset is needed is read from its interval
(studies/density_scale/density_scale.py bootstraps the seeds). The records of the other stresses stay held out.
"""

from __future__ import annotations

import numpy as np

from interphase.campaign.calibrate import TOLERANCES as _TOL

TOLERANCES = (_TOL["phi_peak_deg"], _TOL["psi_max_deg"])     # [°] a miss is weighed over these, as a calibration does
GRID = 2001                 # points of the preparation grid the misfit is read on


def misfit(phi, psi, lab_phi: float, lab_psi: float, tolerances=TOLERANCES):
    """Σ (miss / tolerance)² of φ_peak and ψ_max [°] against a record's."""
    return ((np.asarray(phi) - lab_phi) / tolerances[0]) ** 2 + ((np.asarray(psi) - lab_psi) / tolerances[1]) ** 2


def anchor_preparation(prep, phi, psi, lab_phi: float, lab_psi: float, tolerances=TOLERANCES) -> tuple[float, float]:
    """(preparation, misfit there): the preparation in the sweep's range where the straight lines
    through the seed means φ_peak(prep) and ψ_max(prep) [°] come nearest the record's pair (`misfit`).
    A record beyond the sweep's range anchors at its end; its misfit says how far it stayed."""
    prep, phi, psi = (np.asarray(a, float) for a in (prep, phi, psi))
    o = np.argsort(prep)
    grid = np.linspace(prep[o][0], prep[o][-1], GRID)
    m = misfit(np.interp(grid, prep[o], phi[o]), np.interp(grid, prep[o], psi[o]), lab_phi, lab_psi, tolerances)
    i = int(np.argmin(m))
    return float(grid[i]), float(m[i])


def model_dr(prep_map, e_map, preparation: float, limits: tuple[float, float]) -> float:
    """The model's own Dr [-] of a preparation on a void-ratio map (preparations, seed-mean e at the
    test's stress) read on the model's index limits (e_min, e_max; density.read_limits):
    (e_max − e) / (e_max − e_min), e interpolated; points above preparation 1 are not read."""
    p, e = np.asarray(prep_map, float), np.asarray(e_map, float)
    keep = p <= 1.0
    o = np.argsort(p[keep])
    e_min, e_max = limits
    return float((e_max - np.interp(preparation, p[keep][o], e[keep][o])) / (e_max - e_min))


def fit_scale(dr_lab, dr_model) -> tuple[float, float]:
    """(lab_span, lab_offset) of the least-squares line model Dr = lab_offset + lab_span · Dr
    through two or more (laboratory Dr, model Dr) pairs."""
    dr_lab, dr_model = np.asarray(dr_lab, float), np.asarray(dr_model, float)
    if len(dr_lab) < 2 or np.ptp(dr_lab) == 0:
        raise ValueError("a density scale needs records at two or more relative densities")
    span, offset = np.polyfit(dr_lab, dr_model, 1)
    return float(span), float(offset)
