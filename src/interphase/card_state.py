"""A soil card's state at a user's stress and density: tan φ of its paired soil test over stress ×
preparation (the table `[criterion] strength` names), the map from a relative density to the
preparation that makes it, and the card's misfit against its held-out laboratory records.
Units: stresses in Pa, angles in degrees."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.errors import InputError

REFERENCE_STRESS = 100e3        # [Pa] the stress of the density map's ln term and of a card without a table
LEVEL = 0.95                    # every interval here is a 95 % one


def _t(n: int, level: float = LEVEL) -> float:
    from scipy import stats

    return float(stats.t.ppf(0.5 + level / 2, max(n - 1, 1)))


@dataclass(frozen=True)
class ErrorScale:
    """A prediction error's scale from n held-out errors [°]: bias (mean), rms, and the 95 % half-width
    of a new error, t(n−1) · rms · √(1 + 1/n) (rms, not sd: a bias widens the interval, it is not
    corrected, since it was measured on other cases)."""
    n: int
    bias: float
    rms: float
    what: str

    @classmethod
    def of(cls, errors, what: str) -> "ErrorScale":
        e = np.asarray([x for x in errors if x is not None and math.isfinite(x)], float)
        if e.size < 2:
            return cls(int(e.size), math.nan, math.nan, what)
        return cls(int(e.size), float(e.mean()), float(np.sqrt(np.mean(e ** 2))), what)

    @property
    def half_width(self) -> float:
        return _t(self.n) * self.rms * math.sqrt(1 + 1 / self.n) if self.n >= 2 else math.nan


@dataclass(frozen=True)
class StrengthTable:
    """tan φ of the card's paired soil test over normal stress [Pa] × preparation, with its 95 % seed
    interval: the table `[criterion] strength` names (csv: normal_stress, preparation, tan_phi,
    tan_phi_lo, tan_phi_hi, seeds). Read between rows linearly in ln σ and in preparation; a point
    outside the rows' span is refused (nothing here says how strength goes on beyond it)."""
    rows: pd.DataFrame
    path: Path

    @classmethod
    def read(cls, path: Path, where: str) -> "StrengthTable":
        try:
            df = pd.read_csv(path)
        except (OSError, ValueError) as exc:
            raise InputError(f"cannot read the strength table {path}: {exc}", where=where,
                             fix="the path is relative to the card; studies/stress_density/README.md makes one") from None
        need = ("normal_stress", "preparation", "tan_phi", "tan_phi_lo", "tan_phi_hi", "seeds")
        missing = [c for c in need if c not in df]
        if missing:
            raise InputError(f"the strength table {path} has no column {missing[0]!r}", where=where,
                             fix=f"its columns are {', '.join(need)}")
        return cls(df.sort_values(["preparation", "normal_stress"]).reset_index(drop=True), Path(path))

    @property
    def stresses(self) -> tuple[float, float]:
        return float(self.rows["normal_stress"].min()), float(self.rows["normal_stress"].max())

    @property
    def preparations(self) -> list[float]:
        return sorted(self.rows["preparation"].unique().tolist())

    def at(self, stress: float, preparation: float) -> tuple[float, float, float]:
        """(tan φ, lo, hi) at `stress` [Pa] and `preparation`; InputError outside the table."""
        per = []
        for prep in self.preparations:
            g = self.rows[self.rows["preparation"] == prep]
            s = np.log(g["normal_stress"].to_numpy(float))
            if not (s.min() - 1e-9 <= math.log(stress) <= s.max() + 1e-9):
                per.append(None)
                continue
            per.append((prep, *(float(np.interp(math.log(stress), s, g[c].to_numpy(float)))
                                for c in ("tan_phi", "tan_phi_lo", "tan_phi_hi"))))
        ok = [p for p in per if p is not None]
        if not ok:
            lo, hi = self.stresses
            raise InputError(f"normal stress {stress / 1e3:g} kPa is outside what the card's soil tests measured "
                             f"({lo / 1e3:g}–{hi / 1e3:g} kPa, {self.path})", where="--normal-stress",
                             fix=f"give a stress within {lo / 1e3:g}–{hi / 1e3:g} kPa, or run the card's soil test "
                                 "there (studies/stress_density/README.md)")
        preps = np.array([p[0] for p in ok])
        if not (preps.min() - 1e-9 <= preparation <= preps.max() + 1e-9):
            raise InputError(f"preparation {preparation:.3f} is outside the preparations the card's soil tests measured "
                             f"at {stress / 1e3:g} kPa ({', '.join(f'{p:g}' for p in preps)}; {self.path})",
                             where="--relative-density",
                             fix="give a relative density within the domain the answer prints, or run the card's soil "
                                 "test at that preparation (studies/stress_density/README.md)")
        return tuple(float(np.interp(preparation, preps, [p[i] for p in ok])) for i in (1, 2, 3))


@dataclass(frozen=True)
class DensityMap:
    """preparation = a + b·Dr + c·ln(σ/100 kPa), least squares over the card's verification records
    (the preparation each record's Dr0 was made at in the card's cell, at its stress), with the fitted
    state (the card's own preparation at its calibration record's Dr) among them; sd = the residual
    scatter [preparation]."""
    a: float
    b: float
    c: float
    sd: float
    n: int

    def preparation(self, relative_density: float, stress: float) -> float:
        return self.a + self.b * relative_density + self.c * math.log(stress / REFERENCE_STRESS)

    def relative_density(self, preparation: float, stress: float) -> float:
        return (preparation - self.a - self.c * math.log(stress / REFERENCE_STRESS)) / self.b


def density_map(card) -> DensityMap | None:
    """The card's DensityMap, None with fewer than 4 records."""
    pts = [(v["relative_density"], v["preparation"], v["confining_stress"]) for v in card.extra.get("verification", [])
           if all(k in v for k in ("relative_density", "preparation", "confining_stress"))]
    target = card.extra.get("target", {})
    fitted = next((a for a in card.extra.get("achieved", []) if a.get("quantity") == "relative_density"), None)
    if fitted is not None and "preparation" in card.soil:
        pts.append((fitted["laboratory"], card.soil["preparation"], float(target.get("confining_stress", REFERENCE_STRESS))))
    if len(pts) < 4:
        return None
    dr, prep, s = (np.array(x, float) for x in zip(*pts))
    A = np.c_[np.ones_like(dr), dr, np.log(s / REFERENCE_STRESS)]
    coef, *_ = np.linalg.lstsq(A, prep, rcond=None)
    sd = float(np.std(prep - A @ coef, ddof=3)) if len(pts) > 3 else math.nan
    return DensityMap(*map(float, coef), sd, len(pts))


def card_misfit(card) -> ErrorScale:
    """The card's φ_peak against the laboratory records it was not calibrated on ([[verification]]
    checks: model − record [°])."""
    diffs = [ch["difference"] for v in card.extra.get("verification", []) for ch in v.get("checks", [])
             if ch.get("quantity") == "phi_peak_deg"]
    return ErrorScale.of(diffs, f"φ_peak, model − record, {len(diffs)} held-out records")


def card_dimension(card) -> str:
    """'3D' or 'quasi-2D': what the card's grains are calibrated in (its cell test)."""
    return "3D" if card.cell.get("test") == "triaxial" else "quasi-2D"


def strength_of(card, where: str) -> StrengthTable | None:
    ref = card.extra.get("criterion", {}).get("strength")
    if not ref:
        return None
    path = Path(ref) if Path(ref).is_absolute() else (card.path.parent / ref).resolve()
    return StrengthTable.read(path, where)


def soil_state(card, model, normal_stress, relative_density) -> dict:
    """tan φ (with its 95 % half-width in tan) at the asked stress and density, the preparation, the
    Dr and the domain in words. Without a strength table only the fit's own state is answered."""
    where = f"{card.path}: [criterion] strength"
    table = strength_of(card, where)
    dmap = density_map(card)
    fitted_prep = float(card.soil.get("preparation", 1.0))
    stress = REFERENCE_STRESS if normal_stress is None else float(normal_stress)
    if not (math.isfinite(stress) and stress > 0):
        raise InputError(f"must be > 0 Pa, got {normal_stress!r}", where="--normal-stress", fix="e.g. 100e3")
    if relative_density is not None and not (0 <= relative_density <= 1):
        raise InputError(f"must be a fraction in [0, 1], got {relative_density!r}", where="--relative-density",
                         fix="e.g. 0.8 for 80 %")
    if relative_density is not None and dmap is None:
        raise InputError("the card has too few verification records to map a relative density", where="--relative-density",
                         fix="drop --relative-density (the card's own preparation is used)")
    prep = fitted_prep if relative_density is None else dmap.preparation(relative_density, stress)
    dr = dmap.relative_density(prep, stress) if dmap is not None else None
    if table is None:
        if abs(stress - REFERENCE_STRESS) > 1 or abs(prep - fitted_prep) > 1e-3:
            raise InputError(f"the card has no strength table: it answers at {REFERENCE_STRESS / 1e3:g} kPa and its own "
                             f"preparation {fitted_prep:g} only", where="--normal-stress" if normal_stress is not None
                             else "--relative-density", fix="drop the option, or give the card a [criterion] strength "
                             "table (studies/stress_density/README.md)")
        return {"tan_phi": model.tan_phi, "half": math.nan, "stress": stress, "preparation": prep, "dr": dr,
                "source": f"the fit's own soil test ({model.source})",
                "domain": f"{REFERENCE_STRESS / 1e3:g} kPa, preparation {fitted_prep:g}"}
    tp, lo, hi = table.at(stress, prep)
    s_lo, s_hi = table.stresses
    span = lambda a, b, f: f"{a:{f}}" if f"{a:{f}}" == f"{b:{f}}" else f"{a:{f}}–{b:{f}}"
    dom = f"{span(s_lo / 1e3, s_hi / 1e3, 'g')} kPa, preparation {span(min(table.preparations), max(table.preparations), 'g')}"
    if dmap is not None:
        drs = [dmap.relative_density(p, s) for p in table.preparations for s in (s_lo, s_hi)]
        dom += f" (Dr {span(min(drs), max(drs), '.2f')} by the card's cell map)"
    return {"tan_phi": tp, "half": (hi - lo) / 2, "stress": stress, "preparation": prep, "dr": dr,
            "source": f"the card's soil test at {stress / 1e3:g} kPa ({table.path.name})", "domain": dom}



