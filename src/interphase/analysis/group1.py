"""A Group 1 campaign read tooth by tooth: the study's saw-teeth (Table 6.1: Sw/D50 2, Sr 0, Rt/D50
swept) at several particle-surface frictions, from its seed ensembles (analysis.ensemble_table, the
report's E and intervals). Where E saturates, and what it reads at full mobilisation.

    tooth_cases(summaries, store)   one row per physical interface case, with its tooth and friction
    saturation(cases)               per friction: the first tooth whose E interval reaches 1, the one
                                    under it, and any taller tooth decided below 1 again
    plateau(cases)                  E over the teeth at Rt/D50 ≥ 1: range, mean, intervals against 1
    rule_efficiency(mu, θa, tan φ)  the no-fit rule's E, tan(min(φμ + θa, φ)) / tan φ

The flat and measured surfaces a Group 1 campaign may hold beside its teeth are in `tooth_cases`
with rt NaN; `saturation` and `plateau` read the teeth alone.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from interphase.analysis.criterion import rule_delta
from interphase.analysis.ensemble import physical_case
from interphase.analysis.ensemble_table import ensemble_table

#: the teeth read as the plateau: the study's Fig. 6.10 saturates by Rt/D50 1 on every soil so far
SATURATED_RT = 1.0

CASE_COLUMNS = ["group", "case", "profile_kind", "rt", "sw", "friction_ps", "theta_a_deg_92", "face_deg", "seeds",
                "box_seeds", "tan_delta", "tan_delta_lo", "tan_delta_hi", "tan_phi", "tan_phi_lo", "tan_phi_hi",
                "E", "E_lo", "E_hi", "theta_r_deg", "theta_r_lo", "theta_r_hi"]


def tooth_cases(summaries: pd.DataFrame, store) -> pd.DataFrame:
    """The ensembles table of the campaign's interface cases, each with its profile kind, tooth
    (rt, sw: NaN for a flat or measured surface), friction and the teeth's face angle
    atan(2 Rt/Sw) [deg], sorted by friction and tooth."""
    table = ensemble_table(summaries, store)
    iface = summaries[summaries["test"].eq("interface")]
    keys = (iface.assign(case=iface["label"].map(physical_case))
            .groupby("case")[["profile_kind", "rt", "sw", "friction_ps"]].first())
    out = table.join(keys, on="case")
    for c in ("rt", "sw", "friction_ps"):
        out[c] = pd.to_numeric(out[c], errors="coerce")
    saw = out["profile_kind"].eq("sawtooth")
    out.loc[~saw, ["rt", "sw"]] = np.nan
    out["face_deg"] = np.degrees(np.arctan2(out["rt"], out["sw"] / 2))
    return out.sort_values(["friction_ps", "rt", "case"], na_position="first")[CASE_COLUMNS].reset_index(drop=True)


def saturation(cases: pd.DataFrame) -> pd.DataFrame:
    """Per friction, on the teeth: `from_rt` the lowest tooth whose E interval reaches 1 (E_hi ≥ 1),
    with its face angle and θa; `below_rt` the tooth under it (decided below 1 by construction) with
    its E and interval; `dips` the taller teeth decided below 1 again ("Rt/D50 5 (0.93)"), empty
    when none."""
    rows = []
    teeth = cases[cases["rt"].notna()]
    for mu, g in teeth.sort_values("rt").groupby("friction_ps", sort=True):
        reach = g[g["E_hi"] >= 1.0]
        row = {"friction_ps": mu, "teeth": len(g)}
        if reach.empty:
            rows.append(row)
            continue
        first = reach.iloc[0]
        under = g[g["rt"] < first["rt"]]
        above = g[(g["rt"] > first["rt"]) & (g["E_hi"] < 1.0)]
        row.update(from_rt=first["rt"], from_face_deg=first["face_deg"], from_theta_a_deg=first["theta_a_deg_92"])
        if len(under):
            u = under.iloc[-1]
            row.update(below_rt=u["rt"], below_E=u["E"], below_E_lo=u["E_lo"], below_E_hi=u["E_hi"])
        row["dips"] = "; ".join(f"Rt/D50 {r.rt:g} ({r.E:.2f}, {r.E_lo:.2f}–{r.E_hi:.2f})" for r in above.itertuples())
        rows.append(row)
    cols = ["friction_ps", "teeth", "from_rt", "from_face_deg", "from_theta_a_deg", "below_rt", "below_E", "below_E_lo",
            "below_E_hi", "dips"]
    return pd.DataFrame(rows).reindex(columns=cols)


def plateau(cases: pd.DataFrame, rt_min: float = SATURATED_RT) -> pd.DataFrame:
    """One row: the teeth at Rt/D50 ≥ rt_min, their E's range and mean, and how many intervals lie
    above 1, contain it, lie under it (is the interface at full mobilisation stronger than the
    soil's own test?)."""
    s = cases[cases["rt"] >= rt_min]
    above, below = int((s["E_lo"] > 1).sum()), int((s["E_hi"] < 1).sum())
    return pd.DataFrame([{"rt_min": rt_min, "cases": len(s), "E_min": s["E"].min(), "E_max": s["E"].max(),
                          "E_mean": s["E"].mean(), "above_1": above, "containing_1": len(s) - above - below,
                          "below_1": below}])


def rule_efficiency(mu: float, theta_a_deg: float, tan_phi: float) -> float:
    """The no-fit rule's E: tan δ / tan φ with δ = min(φμ + θa, φ) (analysis.criterion.rule_delta)."""
    return math.tan(math.radians(float(rule_delta(mu, theta_a_deg, tan_phi)))) / tan_phi
