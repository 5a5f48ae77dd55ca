"""Where in a calibration's free ranges the targets can be met: a linear response surface over its
samples (each angle against friction, rolling friction and preparation, least squares), and the
point of least misfit (each angle's miss over its tolerance, squared and summed, as the fit weighs
them) in the target's ranges and in wider ones.

    PYTHONPATH=src python studies/soil_cells/response_surface.py docs/soils/karlsruhe-fine-sand/calibration_samples.csv \
        --target soils/targets/karlsruhe-fine-sand.toml [--offset 1.7]

`--offset DEG`: what the samples' packing seeds read under other seeds in φ_peak (seeds 1–2 read
1.7° under seeds 1–6 for two grain sets: docs/soils.md, "Why each sample has seeds of its own");
the surface is shifted by it before the targets are met. A linear surface fitted on samples inside
the ranges says where the best point lies and which bounds hold it; beyond the samples it is an
extrapolation, and its numbers there are a direction, not a value.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.optimize import minimize

from interphase.campaign.calibrate import TOLERANCES
from interphase.campaign.calibrate_cell import load_cell_target

FREE = ["friction_pp", "rolling_friction", "preparation"]
ANGLES = ["phi_peak_deg", "psi_max_deg", "phi_cs_deg"]


def surface(samples: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """(coefficients [angle, 1 + free], rms residual per angle [°])."""
    x = np.c_[np.ones(len(samples)), samples[FREE].to_numpy(float)]
    coef = np.array([np.linalg.lstsq(x, samples[a].to_numpy(float), rcond=None)[0] for a in ANGLES])
    res = samples[ANGLES].to_numpy(float) - x @ coef.T
    return coef, np.sqrt((res ** 2).mean(axis=0))


def best(coef: np.ndarray, target: np.ndarray, bounds: list[tuple[float, float]]):
    """(free values, predicted angles, misfit) of the least-misfit point within `bounds`."""
    tol = np.array([TOLERANCES[a] for a in ANGLES])
    start = [0.5 * (lo + hi) for lo, hi in bounds]
    m = minimize(lambda v: float(((((coef[:, 0] + coef[:, 1:] @ v) - target) / tol) ** 2).sum()), start,
                 bounds=bounds)
    return m.x, coef[:, 0] + coef[:, 1:] @ m.x, float(m.fun)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("samples", type=Path, help="a calibration's samples table (calibration_samples.csv)")
    ap.add_argument("--target", type=Path, required=True, help="the calibration target it was drawn for")
    ap.add_argument("--offset", type=float, default=0.0, help="φ_peak the samples' seeds read low by [°]")
    a = ap.parse_args()
    t = load_cell_target(a.target)
    target = np.array([t.values[a_] for a_ in ANGLES])
    coef, rms = surface(pd.read_csv(a.samples))
    print(f"targets φ_peak {target[0]:.2f}, ψ_max {target[1]:.2f}, φ_cs {target[2]:.2f}; "
          f"samples' φ_peak offset {a.offset:+.1f}°")
    print("| angle | constant | per friction | per rolling friction | per preparation | rms residual [°] |")
    print("|---|---|---|---|---|---|")
    for name, c, r in zip(ANGLES, coef, rms):
        print(f"| {name} | {c[0]:.1f} | {c[1]:+.1f} | {c[2]:+.1f} | {c[3]:+.1f} | {r:.2f} |")
    shifted = coef.copy()
    shifted[0, 0] += a.offset
    ranges = [tuple(t.free[f]) for f in FREE]
    print("\n| ranges | friction | rolling friction | preparation | φ_peak | ψ_max | φ_cs | misfit |")
    print("|---|---|---|---|---|---|---|---|")
    for label, bounds in (("the target's", ranges),
                          ("friction from 0.25, preparation from 0.1", [(0.25, ranges[0][1]), ranges[1], (0.1, ranges[2][1])]),
                          ("friction from 0.2, preparation from 0", [(0.2, ranges[0][1]), ranges[1], (0.0, ranges[2][1])])):
        v, pred, mis = best(shifted, target, bounds)
        print(f"| {label} | {v[0]:.3f} | {v[1]:.3f} | {v[2]:.3f} | {pred[0]:.1f} ({pred[0] - target[0]:+.1f}) | "
              f"{pred[1]:.1f} ({pred[1] - target[1]:+.1f}) | {pred[2]:.1f} ({pred[2] - target[2]:+.1f}) | {mis:.2f} |")


if __name__ == "__main__":
    main()
