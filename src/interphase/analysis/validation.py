"""The criterion against laboratory interface tests (seed §6.4.6, Fig. 6.10b–d), with its skill.

For each laboratory row (interphase.lab): the surface rebuilt from its published geometry → θa
(both filters, the row's D50) → θr → E (the criterion's fits, with intervals) → δ = atan(E·tan φ),
where tan φ is the soil's own peak direct-shear strength: the laboratory's (`soil_phi_peak`) when
the row gives it, else the soil card's element test at the nearest stress (said per row).
Beside it, two predictions that need no criterion (docs/methods.md §10):
  δ_soil = φ                    the soil's strength for every surface (full mobilisation);
  δ_rule = min(φμ + θa, φ)      the surface's friction plus its asperity angle, capped at the soil;
  δ_fitted = min(φμ + θa − a, atan(b·tan φ))   the same rule with the two constants fitted on the
                                the criterion's own cases (CriterionModel.rule; NaN when the model
                                has none, e.g. the study's readings): the fair baseline of a fitted
                                criterion (issue 41).
Errors are δ − δ measured in degrees; `within_4` is the study's test (|error| < 4°).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from interphase.errors import InputError

STUDY_FRICTION = (("glass", 0.1), ("ottawa", 0.2), ("sand", 0.2))   # seed §6.4.6 citing Dove et al. 2006
TOLERANCE_DEG = 4.0


def row_friction(row) -> tuple[float, str]:
    """(tan φμ, where it came from) of a lab row."""
    if math.isfinite(row["friction"]):
        return float(row["friction"]), row["friction_source"] or "the laboratory file"
    mat = str(row["soil"]).lower()
    mu = next((v for key, v in STUDY_FRICTION if key in mat), None)
    if mu is None:
        raise InputError(f"no particle–surface friction for {row['soil']!r}", where=f"line {row['row']}: friction",
                         fix="add a friction column (tan φμ) with its friction_source")
    return mu, "seed §6.4.6 (Dove et al. 2006): glass beads 0.1, Ottawa sand 0.2"


def card_phi(card, normal_stress: float) -> tuple[float, str]:
    """(φ_peak [°], where from) of a soil card's element test at the stress nearest `normal_stress` [Pa]."""
    got = []
    for a in card.extra.get("achieved", []):
        if a.get("quantity") == "phi_peak_deg" and math.isfinite(a.get("value", math.nan)):
            got.append((float(card.extra.get("target", {}).get("normal_stress", math.nan)), float(a["value"])))
    for v in card.extra.get("verification", []):
        m = v.get("measured", {})
        if math.isfinite(m.get("phi_peak_deg", math.nan)):
            got.append((float(v["normal_stress"]), float(m["phi_peak_deg"])))
    got = [g for g in got if math.isfinite(g[0])]
    if not got:
        raise InputError(f"the soil card {card.path} has no element-test φ_peak", where=str(card.path),
                         fix="calibrate it with `campaign calibrate`, or give soil_phi_peak_deg in the lab file")
    s, phi = min(got, key=lambda g: abs(math.log(g[0] / normal_stress)))
    return phi, f"card {card.name}: element test at {s / 1e3:g} kPa"


def predict_rows(table, model_for, card=None, default_phi: tuple[float, str] | None = None) -> pd.DataFrame:
    """One row per laboratory test: measured δ, the criterion's δ with its interval, both baselines
    and their errors. `model_for(tan φμ)`: a CriterionModel (its tan φ is replaced per row); `card`:
    SoilCard for rows without the laboratory's own soil φ; `default_phi` = (φ [°], where from) for
    rows with neither (the report: its campaign's simulated soil)."""
    from interphase.analysis.criterion import predict_profile
    from interphase.lab import profile_of

    out = []
    for _, r in table.rows.iterrows():
        mu, mu_from = row_friction(r)
        if math.isfinite(r["soil_phi_peak"]):
            phi, phi_from = float(r["soil_phi_peak"]), "the laboratory's own soil test"
        elif card is not None:
            phi, phi_from = card_phi(card, float(r["normal_stress"]))
        elif default_phi is not None:
            phi, phi_from = default_phi
        else:
            raise InputError("no soil friction angle for this row", where=f"{table.path}:{r['row']}: soil_phi_peak_deg",
                             fix="give the laboratory's soil_phi_peak_deg, or --soil CARD")
        model = model_for(mu)
        model.tan_phi = math.tan(math.radians(phi))
        prof = profile_of(r)
        row = {"row": int(r["row"]), "soil": r["soil"], "surface": r["surface_name"] or prof.name,
               "normal_stress_kpa": r["normal_stress"] / 1e3, "friction": mu, "phi_deg": phi, "phi_from": phi_from,
               "delta_measured_deg": float(r["delta_peak"]),
               "reading_error_deg": float(r["reading_error"]) if math.isfinite(r["reading_error"]) else 0.0,
               "source": r["source"], "table_or_figure": r["table_or_figure"], "note": ""}
        try:
            pp = predict_profile(model, prof, float(r["d50"]), mu)
            p = pp.prediction
            theta_a = pp.theta_a_deg_92 if math.isfinite(pp.theta_a_deg_92) else 0.0
            row |= {"theta_a_deg": theta_a, "theta_r_deg": p.theta_r_deg, "efficiency": p.efficiency,
                    "efficiency_lo": p.efficiency_interval[0], "efficiency_hi": p.efficiency_interval[1],
                    "delta_predicted_deg": p.delta_deg, "delta_lo_deg": p.delta_interval_deg[0],
                    "delta_hi_deg": p.delta_interval_deg[1], "branch": p.branch}
        except InputError as exc:
            from interphase.surface.normals import theta_a as _ta

            t = _ta(prof, float(r["d50"])).theta_a_deg
            theta_a = t if math.isfinite(t) else 0.0
            row |= {"theta_a_deg": theta_a, "theta_r_deg": math.nan, "efficiency": math.nan, "efficiency_lo": math.nan,
                    "efficiency_hi": math.nan, "delta_predicted_deg": math.nan, "delta_lo_deg": math.nan,
                    "delta_hi_deg": math.nan, "branch": "", "note": str(exc)}
        row["efficiency_measured"] = math.tan(math.radians(row["delta_measured_deg"])) / math.tan(math.radians(phi))
        row["delta_soil_deg"] = phi
        row["delta_rule_deg"] = min(math.degrees(math.atan(mu)) + theta_a, phi)
        a, b = model.rule if getattr(model, "rule", None) else (math.nan, math.nan)
        row["delta_fitted_rule_deg"] = min(math.degrees(math.atan(mu)) + theta_a - a,
                                           math.degrees(math.atan(b * math.tan(math.radians(phi)))))
        out.append(row)
    df = pd.DataFrame(out)
    for k in ("predicted", "soil", "rule", "fitted_rule"):
        df[f"error_{k}_deg"] = df[f"delta_{k}_deg"] - df["delta_measured_deg"]
    df["within_4"] = df["error_predicted_deg"].abs() < TOLERANCE_DEG
    return df


def skill(df: pd.DataFrame, mobilised_efficiency: float = 0.95) -> pd.DataFrame:
    """rms and max |error| [°] and the share within 4° of the criterion and both baselines, on every
    row and on the rows the laboratory measured below full mobilisation (tan δ < 0.95 tan φ)."""
    rows = []
    e_meas = np.tan(np.radians(df["delta_measured_deg"])) / np.tan(np.radians(df["phi_deg"]))
    for subset, mask in (("all rows", np.ones(len(df), bool)),
                         ("not fully mobilised (measured E < 0.95)", (e_meas < mobilised_efficiency).to_numpy())):
        for name, col in (("criterion", "error_predicted_deg"), ("δ = φ (soil)", "error_soil_deg"),
                          ("δ = min(φμ + θa, φ)", "error_rule_deg"),
                          ("δ = min(φμ + θa − a, atan(b tan φ)), a, b fitted with the criterion", "error_fitted_rule_deg")):
            if col not in df or df[col].isna().all():
                continue
            e = df.loc[mask, col].dropna().to_numpy(float)
            rows.append({"subset": subset, "prediction": name, "n": int(e.size),
                         "rms_deg": float(np.sqrt(np.mean(e ** 2))) if e.size else math.nan,
                         "max_abs_deg": float(np.abs(e).max()) if e.size else math.nan,
                         "within_4": float(np.mean(np.abs(e) < TOLERANCE_DEG)) if e.size else math.nan})
    return pd.DataFrame(rows)


def largest_miss(df: pd.DataFrame) -> dict | None:
    e = df["error_predicted_deg"]
    if e.notna().sum() == 0:
        return None
    r = df.loc[e.abs().idxmax()]
    return {"row": int(r["row"]), "soil": r["soil"], "surface": r["surface"], "normal_stress_kpa": r["normal_stress_kpa"],
            "error_deg": float(r["error_predicted_deg"]), "source": r["source"], "table_or_figure": r["table_or_figure"]}
