"""A soil's box test read two ways at its peak: on the box's plane, and as the specimen's Mohr circle.

The box reports τ/σ on its horizontal plane (what E divides by). The specimen's average stress at
the peak snapshot (the whole box, `analysis.stress`) has its own mobilised friction
φ_mob = asin(q/p) and its major principal direction α, degrees from the vertical. On the horizontal
plane Mohr's circle gives

    τ/σ = sin φ_mob · sin 2α / (1 + sin φ_mob · cos 2α),

which is tan φ_mob only when α = 45° + φ_mob/2 (the plane is the plane of maximum obliquity) and
sin φ_mob when α = 45° (the plane of zero extension at zero dilatancy, Davis 1968; Rowe 1969,
Géotechnique 19(1) 75–86). A triaxial or biaxial test reads φ_mob itself, so this is how a card's
laboratory angle and its box angle are put side by side (docs/soils.md, "Direct shear and the
laboratory's test on one card"). Angles in degrees.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from interphase.analysis.ensemble import physical_ids, values_interval

#: (column, what it holds) of `soil_test_readings`, each with `_lo`/`_hi` (95 % over the seeds)
READINGS = {
    "phi_plane_deg": "atan of the box's peak τ/σ on its plane (History forces)",
    "phi_mob_deg": "of the specimen's average stress at the peak snapshot (its x–z part in 3D)",
    "principal_deg": "major principal stress direction at the peak snapshot, from the vertical",
    "phi_mohr_plane_deg": "atan of Mohr's τ/σ on the horizontal plane at that direction",
    "phi_sin_deg": "the plane's reading at σ1 45° from the vertical",
}


def plane_ratio(sin_phi, alpha_deg):
    """τ/σ on the horizontal plane of a Mohr circle with sin φ = q/p whose major principal stress lies
    `alpha_deg` from the vertical (elementwise)."""
    s, a = np.asarray(sin_phi, float), np.radians(np.asarray(alpha_deg, float))
    return s * np.sin(2 * a) / (1 + s * np.cos(2 * a))


def soil_test_readings(summaries: pd.DataFrame) -> pd.DataFrame:
    """One row per physical box case and engine of a summaries table: `case` (its name, with the
    engine when the table has several), `seeds`, and each of
    READINGS with its 95 % interval over the seeds (angles' t interval in [0°, 90°]). Runs without
    the region's tensor at their peak (`qp_region`, `principal_stress_deg_region`) are left out.
    Empty (with the columns) when the table has no box test."""
    cols = ["case", "physical_id", "seeds"] + [c + s for c in READINGS for s in ("", "_lo", "_hi")]
    if summaries.empty or "test" not in summaries:
        return pd.DataFrame(columns=cols)
    box = summaries[summaries["test"] == "box"]
    need = ["peak_stress_ratio", "qp_region", "principal_stress_deg_region"]
    if box.empty or any(c not in box for c in need):
        return pd.DataFrame(columns=cols)
    box = box.dropna(subset=need)
    sphi = box["qp_region"].to_numpy(float)
    alpha = box["principal_stress_deg_region"].to_numpy(float)
    engine = box["engine"].astype(str).to_numpy() if "engine" in box else ""
    per_run = pd.DataFrame({
        "physical_id": physical_ids(box).to_numpy(), "engine": engine,
        "case": box["label"].str.replace(r"-s\d+$", "", regex=True).to_numpy() if "label" in box else "",
        "phi_plane_deg": np.degrees(np.arctan(box["peak_stress_ratio"].to_numpy(float))),
        "phi_mob_deg": np.degrees(np.arcsin(np.clip(sphi, -1, 1))),
        "principal_deg": alpha,
        "phi_mohr_plane_deg": np.degrees(np.arctan(plane_ratio(sphi, alpha))),
        "phi_sin_deg": np.degrees(np.arctan(sphi)),
    })
    rows = []
    for (pid, eng), g in per_run.groupby(["physical_id", "engine"], sort=False):   # engines never pooled
        row = {"case": g["case"].iloc[0] + (f" ({eng})" if eng and per_run["engine"].nunique() > 1 else ""),
               "physical_id": pid, "seeds": len(g)}
        for c in READINGS:
            v = g[c].to_numpy(float)
            row[c] = float(np.mean(v))
            row[c + "_lo"], row[c + "_hi"] = values_interval(v, "friction_angle_deg")
        rows.append(row)
    return pd.DataFrame(rows, columns=cols)
