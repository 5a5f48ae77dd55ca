"""Laboratory data for the comparison (seed §6.4.6, Fig. 6.10b–d).

CSV columns (header row required):
  theta_a_deg   θa of the tested surface, > 92° filter, ψ degrees from vertical; empty or 0 =
                non-dilative
  tan_delta     measured peak interface stress ratio        } at least one of the two
  efficiency    measured peak efficiency E = tan δ / tan φ  }
  material      e.g. "glass beads 0.7 mm", "Ottawa 20/30 sand"
optional:
  friction      particle–surface friction tan φμ; default from the study (§6.4.6): glass beads 0.1,
                Ottawa/sand 0.2 — other materials must give it
  tan_phi       the material's box friction tan φ (else the model's)
  surface       a name for the surface
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.errors import InputError

STUDY_FRICTION = (("glass", 0.1), ("ottawa", 0.2), ("sand", 0.2))   # §6.4.6, Dove et al. 2006


def read_lab(path: str | Path) -> pd.DataFrame:
    p = Path(path)
    try:
        df = pd.read_csv(p)
    except FileNotFoundError:
        raise InputError("file not found", where=str(p), fix="give a CSV with theta_a_deg, tan_delta or efficiency, material") from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise InputError(f"not a readable CSV ({exc})", where=str(p)) from None
    df.columns = [str(c).strip() for c in df.columns]
    for need in ("theta_a_deg", "material"):
        if need not in df.columns:
            raise InputError(f"missing column {need!r} (have: {', '.join(df.columns)})", where=str(p),
                             fix="columns: theta_a_deg, tan_delta or efficiency, material [, friction, tan_phi]")
    if "tan_delta" not in df.columns and "efficiency" not in df.columns:
        raise InputError("needs a tan_delta or an efficiency column", where=str(p))
    for col in ("theta_a_deg", "tan_delta", "efficiency", "friction", "tan_phi"):
        if col in df.columns:
            num = pd.to_numeric(df[col], errors="coerce")
            bad = num.isna() & df[col].notna() & (df[col].astype(str).str.strip() != "")
            if bad.any():
                i = int(np.flatnonzero(bad.to_numpy())[0])
                raise InputError(f"column {col!r}, row {i + 2}: {df[col].iloc[i]!r} is not a number", where=str(p))
            df[col] = num
        else:
            df[col] = np.nan
    if (df["theta_a_deg"].dropna() < 0).any() or (df["theta_a_deg"].dropna() >= 90).any():
        raise InputError("theta_a_deg must be ψ in [0°, 90°) (degrees from vertical)", where=f"{p}: theta_a_deg")
    df["material"] = df["material"].astype(str)
    for i in np.flatnonzero(df["friction"].isna().to_numpy()):
        mat = df["material"].iloc[i].lower()
        mu = next((v for key, v in STUDY_FRICTION if key in mat), None)
        if mu is None:
            raise InputError(f"row {i + 2}: no friction for material {df['material'].iloc[i]!r}", where=f"{p}: friction",
                             fix="add a friction column (particle–surface tan φμ)")
        df.loc[df.index[i], "friction"] = mu
    if "surface" not in df.columns:
        df["surface"] = ""
    return df


def compare(lab: pd.DataFrame, model_for) -> pd.DataFrame:
    """Predicted vs measured interface friction angle per lab row. `model_for(friction)` gives a
    CriterionModel. A row the criterion refuses (θa outside the fit, …) keeps its reason."""
    from interphase.analysis.criterion import predict

    rows = []
    for r in lab.itertuples(index=False):
        model = model_for(float(r.friction))
        tan_phi = r.tan_phi if math.isfinite(r.tan_phi) else model.tan_phi
        measured_td = r.tan_delta if math.isfinite(r.tan_delta) else r.efficiency * tan_phi
        a = r.theta_a_deg if math.isfinite(r.theta_a_deg) and r.theta_a_deg > 0 else math.nan
        row = {"material": r.material, "surface": r.surface, "θa [°]": r.theta_a_deg, "tan φμ [-]": r.friction,
               "tan φ [-]": tan_phi, "δ measured [°]": math.degrees(math.atan(measured_td)) if math.isfinite(measured_td) else math.nan}
        try:
            p = predict(model, float(r.friction), a, a)
            e = p.efficiency
            td = e * tan_phi
            row |= {"θr predicted [°]": p.theta_r_deg, "E predicted [-]": e,
                    "δ predicted [°]": math.degrees(math.atan(td)), "source": p.source, "note": ""}
        except InputError as exc:
            row |= {"θr predicted [°]": math.nan, "E predicted [-]": math.nan, "δ predicted [°]": math.nan,
                    "source": model.source, "note": str(exc)}
        row["δ predicted − measured [°]"] = row["δ predicted [°]"] - row["δ measured [°]"]
        rows.append(row)
    return pd.DataFrame(rows)
