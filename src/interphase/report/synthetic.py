"""A synthetic summaries table shaped like CampaignStore.summaries(), for tests and the report
benchmark. NOT simulation results: the trends are the study's default correlations plus noise
(criterion.default_theta_r, E plateau at θr = 30°), so fits have a known truth.

Truth used: θr = φμ + (35 − φμ)·θa/40 (θa ≤ 40), 35 + 0.5·(θa − 40) beyond; E = 0.2 + 0.8·min(θr, 30)/30;
tan φ = 0.55 (box tests, one per gradation); flat-spaced (Group 2) surfaces: θa(≥ 90°) = 25–40°,
θr/θa = 0.6 + 0.01·(θa,ccw − 115) on [0.45, 0.9].
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

TAN_PHI = 0.55
FRICTIONS = (0.05, 0.2, 0.5)


def true_theta_r(theta_a, mu):
    phi_mu = np.degrees(np.arctan(mu))
    a = np.asarray(theta_a, float)
    return np.where(a <= 40.0, phi_mu + (35.0 - phi_mu) * a / 40.0, 35.0 + 0.5 * (a - 40.0))


def true_efficiency(theta_r):
    return 0.2 + 0.8 * np.minimum(np.asarray(theta_r, float), 30.0) / 30.0


def synthetic_summaries(n: int = 200, seed: int = 0, noise_deg: float = 1.0, noise_e: float = 0.02) -> pd.DataFrame:
    """`n` interface cases over groups 1–5 (≈ 20 % Group 2; half of Group 1 with uniform grains) and
    three frictions, plus 2 box tests."""
    rng = np.random.default_rng(seed)
    u = rng.random(n)
    box_ids = {"mono": "box000000mono", "poly": "box000000poly"}
    group = rng.choice(["group1", "group2", "group3", "group4", "group5"], size=n, p=[0.25, 0.2, 0.2, 0.2, 0.15])
    grad = np.where((group == "group1") & (u < 0.5), "mono", "poly")    # as the study: uniform grains on Group 1
    mu = rng.choice(FRICTIONS, size=n)
    fs = group == "group2"
    ta92 = rng.uniform(0.0, 50.0, n)
    ta92[rng.random(n) < 0.05] = np.nan                 # some non-dilative surfaces
    ta90 = np.where(np.isnan(ta92), 0.0, ta92 * 0.97)
    ta90[fs] = rng.uniform(25.0, 40.0, fs.sum())
    ta92[fs] = 42.0 + rng.normal(0, 0.5, fs.sum())      # the study: Group 2 sits at θa(>92°) ≈ 42°
    tr = true_theta_r(np.nan_to_num(ta92), mu) + rng.normal(0, noise_deg, n)
    ratio = np.clip(0.6 + 0.01 * (ta90[fs] + 90.0 - 115.0), 0.45, 0.9)
    tr[fs] = ratio * ta90[fs] + rng.normal(0, noise_deg * 0.3, fs.sum())
    e = true_efficiency(tr) + rng.normal(0, noise_e, n)
    peak = e * TAN_PHI
    kind = np.where(np.isnan(ta92), "flat", np.where(group == "group4", "random",
                                                      np.where(group == "group5", "file", "sawtooth")))
    ids = [f"c{i:011d}" for i in range(n)]
    df = pd.DataFrame({
        "case_id": ids, "engine": "liggghts", "group": group,
        "label": [f"{g}-{k}-mu{m:g}-{gr}-{i}" for i, (g, k, m, gr) in enumerate(zip(group, kind, mu, grad))],
        "role": "interface", "pair_id": [box_ids[g] for g in grad], "status": "done", "test": "interface",
        "profile_kind": kind, "rt": np.where(kind == "sawtooth", 1.0, np.nan),
        "sw": np.where(kind == "sawtooth", 2.0, np.nan),
        "sr": np.where(fs, rng.choice([0.2, 0.5, 1, 2, 3, 5, 8, 10], n), np.where(kind == "sawtooth", 0.0, np.nan)),
        "au": np.where(kind == "random", 2.0, np.nan), "ar": np.where(kind == "random", 1.0, np.nan),
        "rtmax": np.where(kind == "random", 2.0, np.nan), "profile_path": None, "friction_ps": mu,
        "gradation": grad, "seed": 1, "d50": 0.7e-3,
        "peak_stress_ratio": peak, "shear_disp_at_peak": rng.uniform(1e-3, 3e-3, n),
        "residual_stress_ratio": peak * 0.85, "dilation_at_peak": rng.uniform(0, 1e-4, n),
        "theta_r_surface_deg": tr, "theta_n_surface_deg": tr * 0.9 + rng.normal(0, 1, n),
        "a_r_surface": rng.uniform(0.2, 1, n), "a_n_surface": rng.uniform(0.2, 1, n),
        "surface_force_angle_deg": np.degrees(np.arctan(peak)),
        "theta_r_region_deg": tr * 0.8 + rng.normal(0, 1, n), "theta_n_region_deg": tr * 0.75 + rng.normal(0, 1, n),
        "stress_ratio_region": peak * 0.9, "qp_region": peak * 0.5, "qp_sff": peak * 0.5,
        "shear_band_d50": rng.uniform(3, 12, n), "inertial_number": rng.uniform(1e-5, 1e-3, n),
        "theta_a_deg_92": ta92, "theta_a_deg_90": ta90,
        "rn": np.nan_to_num(ta92) / 60, "rnc": np.nan_to_num(ta92) / 80, "mean_slope_deg": np.nan_to_num(ta92) * 1.1,
        "n_contacts_surface": rng.integers(20, 200, n), "peak_snapshot": 4,
    })
    box = pd.DataFrame({"case_id": list(box_ids.values()), "engine": "liggghts", "group": "box",
                        "label": [f"box-{g}" for g in box_ids], "role": "box", "pair_id": None, "status": "done",
                        "test": "box", "gradation": list(box_ids), "d50": 0.7e-3, "friction_ps": math.nan,
                        "peak_stress_ratio": TAN_PHI, "seed": 1})
    return pd.concat([df, box], ignore_index=True)
