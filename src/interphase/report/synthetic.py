"""A synthetic summaries table shaped like CampaignStore.summaries(), for tests and the report
benchmark. NOT simulation results: the trends are the study's default correlations plus noise
(criterion.default_theta_r, E plateau at θr = 30°), so fits have a known truth.

Truth used: θr = φμ + (35 − φμ)·θa/40 (θa ≤ 40), 35 + 0.5·(θa − 40) beyond; E = 0.2 + 0.8·min(θr, 30)/30,
never below min(μ, tan φ)/tan φ (a flat's, as the criterion holds);
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
    # no surface grips less than a flat of its friction: tan δ ≥ min(μ, tan φ) (Coulomb on the flat; the
    # criterion's floor), within the noise
    e = np.maximum(e, np.minimum(mu, TAN_PHI) / TAN_PHI * (1 + rng.normal(0, noise_e, n)))
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


def _synthetic_curve(peak: float, distance: float, rng, points: int = 200) -> tuple[np.ndarray, np.ndarray]:
    """A stress-ratio curve [-] over shear displacement [m]: a rise to `peak` at 0.3 of `distance`, a
    15 % softening after it, and ±2 % noise."""
    s = np.linspace(0.0, distance, points)
    sp = 0.3 * distance
    r = peak * np.tanh(2.5 * s / sp) * (1.0 - 0.15 * np.clip((s - sp) / (distance - sp), 0.0, 1.0))
    return s, r * (1.0 + rng.normal(0.0, 0.02, points))


def synthetic_restore(campaign_path, folder, seed: int = 0, scatter_deg: float = 2.0,
                      scatter_e: float = 0.03) -> tuple:
    """summaries.csv and curves.parquet in `folder` for every case the campaign file plans (its ids,
    labels and recipe), as `campaign report` writes them: `campaign run FILE --restore
    folder/summaries.csv` then brings the campaign back without an engine (for the report's tests
    and screenshots). NOT simulation results: θa is the surface's own (surface.normals.theta_a),
    θr and E follow the truth above with a per-seed scatter (`scatter_deg` [°], `scatter_e` [-]),
    tan φ = TAN_PHI ± 3 % per box seed. Returns the two paths."""
    from pathlib import Path

    from interphase.campaign.plan import plan
    from interphase.campaign.schema import load_campaign
    from interphase.errors import InputError
    from interphase.surface.normals import theta_a
    from interphase.surface.builder import from_spec

    campaign = load_campaign(campaign_path)
    rng = np.random.default_rng(seed)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    rows, curves, surfaces = [], [], {}
    for p in plan(campaign):
        c = p.case
        row = {"case_id": p.case_id, "label": p.label, "group": p.group, "test": p.params["test"],
               "pair_id": p.pair_id, "friction_ps": c.friction_ps, "gradation": p.params["gradation"],
               "seed": c.seed, "recipe_id": p.recipe_id, "d50": c.d50, "engine_version": "synthetic"}
        if p.params["test"] == "box":
            peak = TAN_PHI * (1.0 + rng.normal(0.0, 0.03))
        else:
            key = (c.profile.kind, c.profile.params, c.profile.path)
            if key not in surfaces:
                try:
                    prof = from_spec(c.profile, c.d50, min(c.box_length_d50, 40.0) * c.d50)
                    res92, res90 = theta_a(prof, c.d50, 92), theta_a(prof, c.d50, 90)
                    surfaces[key] = (res92.theta_a_deg if res92.dilative else 0.0,
                                     res90.theta_a_deg if res90.dilative else 0.0)
                except InputError:
                    surfaces[key] = (0.0, 0.0)
            ta92, ta90 = surfaces[key]
            tr = float(true_theta_r(ta92, c.friction_ps)) + rng.normal(0.0, scatter_deg)
            peak = (float(true_efficiency(tr)) + rng.normal(0.0, scatter_e)) * TAN_PHI
            row |= {"theta_a_deg_92": ta92, "theta_a_deg_90": ta90, "rnc": ta92 / 80.0, "rn": ta92 / 60.0,
                    "theta_r_surface_deg": tr, "theta_n_surface_deg": 0.9 * tr + rng.normal(0.0, 1.0),
                    "theta_r_region_deg": 0.8 * tr + rng.normal(0.0, 1.0), "stress_ratio_region": 0.9 * peak,
                    "lee_share_surface": float(np.clip(0.3 + rng.normal(0.0, 0.05), 0.0, 1.0))}
        x, r = _synthetic_curve(peak, c.shear_distance, rng)
        row |= {"peak_stress_ratio": float(r.max()), "shear_disp_at_peak": float(x[int(np.argmax(r))]),
                "residual_stress_ratio": float(r[-40:].mean())}
        rows.append(row)
        curves.append(pd.DataFrame({"case_id": p.case_id, "shear_disp": x.astype(np.float32),
                                    "stress_ratio": r.astype(np.float32)}))
    summaries, curve_path = folder / "summaries.csv", folder / "curves.parquet"
    pd.DataFrame(rows).to_csv(summaries, index=False, float_format="%.6g")
    pd.concat(curves, ignore_index=True).to_parquet(curve_path, index=False)
    return summaries, curve_path
