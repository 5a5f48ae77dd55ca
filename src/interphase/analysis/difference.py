"""Is a change real, and does it matter? Two seed ensembles of one quantity compared through the
difference of their means, its 95 % interval and a tolerance (an equivalence decision by interval
inclusion, as in two one-sided tests):

  agree      the interval of the difference lies inside ±tol: any effect is smaller than tol;
  differ     it lies entirely outside ±tol: the effect is larger than tol;
  undecided  it straddles +tol or −tol: more seeds are needed (`seeds_needed` estimates how many
             per side would make the interval's half-width fit between the difference and tol, from
             the scatter seen, Student t at the new count).

Unpaired (different settings on the same packing seeds, which after consolidation and shear are
no longer the same specimen): Welch's interval. Paired (the same specimen read two ways, e.g. two
engines on one packing): a t interval on the per-seed differences; values are matched by seed.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from scipy import stats

VERDICTS = ("agree", "differ", "undecided")
MAX_SEEDS = 1000          # seeds_needed beyond this is reported as None ("not within reach")


@dataclass(frozen=True)
class Difference:
    """value − ref with its 95 % interval and the verdict against ±tol (units of the quantity)."""
    ref: float
    ref_lo: float
    ref_hi: float
    value: float
    value_lo: float
    value_hi: float
    change: float
    change_lo: float
    change_hi: float
    tol: float
    verdict: str
    n_ref: int
    n_value: int
    paired: bool
    seeds_needed: int | None = None     # per side, for an undecided verdict

    def to_dict(self) -> dict:
        return asdict(self)


def _mean_ci(v: np.ndarray) -> tuple[float, float, float]:
    if v.size == 0:
        return math.nan, math.nan, math.nan
    m = float(v.mean())
    if v.size < 2:
        return m, math.nan, math.nan
    h = stats.t.ppf(0.975, v.size - 1) * float(v.std(ddof=1)) / math.sqrt(v.size)
    return m, m - h, m + h


def _welch(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """(standard error, degrees of freedom) of mean(b) − mean(a)."""
    va, vb = a.var(ddof=1) / a.size, b.var(ddof=1) / b.size
    se = math.sqrt(va + vb)
    if se == 0:
        return 0.0, float(a.size + b.size - 2)
    den = va ** 2 / (a.size - 1) + vb ** 2 / (b.size - 1)
    df = (va + vb) ** 2 / den if den > 0 else 0.0     # den underflows for variances near 1e-160
    return se, float(df) if math.isfinite(df) and df > 0 else float(min(a.size, b.size) - 1)


def verdict(lo: float, hi: float, tol: float) -> str:
    """agree | differ | undecided for the interval [lo, hi] of a difference against ±tol."""
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return "undecided"
    if -tol <= lo and hi <= tol:
        return "agree"
    if lo > tol or hi < -tol:
        return "differ"
    return "undecided"


def _seeds_needed(change: float, sd_ref: float, sd_value: float, tol: float, paired: bool) -> int | None:
    """Smallest seeds per side whose 95 % half-width fits between |change| and tol, at the scatter seen."""
    margin = abs(abs(change) - tol)
    if not (math.isfinite(margin) and margin > 0):
        return None
    n = np.arange(2, MAX_SEEDS + 1)
    if paired:
        half = stats.t.ppf(0.975, n - 1) * sd_value / np.sqrt(n)          # sd_value: sd of the differences
    else:
        half = stats.t.ppf(0.975, 2 * n - 2) * np.sqrt((sd_ref ** 2 + sd_value ** 2) / n)
    ok = np.flatnonzero(half < margin)
    return int(n[ok[0]]) if ok.size else None


def difference(ref, value, tol: float, *, paired: bool = False) -> Difference:
    """Compare `value` against `ref` (per-seed values; NaN dropped) at tolerance `tol` > 0.
    paired=True: `ref` and `value` are aligned by seed (same length); pairs with a NaN are dropped."""
    a, b = np.asarray(ref, float), np.asarray(value, float)
    if paired:
        if a.shape != b.shape:
            raise ValueError("paired values need one value per seed on both sides")
        ok = np.isfinite(a) & np.isfinite(b)
        a, b = a[ok], b[ok]
    else:
        a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    r, v = _mean_ci(a), _mean_ci(b)
    change = v[0] - r[0]
    lo = hi = math.nan
    needed = None
    if paired and a.size >= 2:
        d = b - a
        _, lo, hi = _mean_ci(d)
        sd_r, sd_v = 0.0, float(d.std(ddof=1))
    elif not paired and a.size >= 2 and b.size >= 2:
        se, df = _welch(a, b)
        h = stats.t.ppf(0.975, df) * se if se > 0 else 0.0
        lo, hi = change - h, change + h
        sd_r, sd_v = float(a.std(ddof=1)), float(b.std(ddof=1))
    v_ = verdict(lo, hi, tol)
    if v_ == "undecided" and math.isfinite(lo):
        needed = _seeds_needed(change, sd_r, sd_v, tol, paired)
    return Difference(*r, *v, change, lo, hi, tol, v_, int(a.size), int(b.size), paired, needed)


def _log_terms(a: np.ndarray, b: np.ndarray) -> list[tuple[float, int]]:
    """(variance term, seeds) of ln(mean a / mean b) by the delta method, one per side."""
    return [(v.var(ddof=1) / (v.size * v.mean() ** 2), v.size) for v in (a, b)]


def e_difference(a1, b1, a2, b2, tol: float = 0.05, level: float = 0.95) -> tuple[float, float, float, str]:
    """E2 − E1 with its `level` interval and the 95 % interval's verdict at ±tol, E = mean a / mean b
    per side and the four seed groups independent (two interface ensembles over two soil tests, e.g.
    one surface in two cells): each E's delta-method variance on the log, scaled by E², added;
    Student t with Welch–Satterthwaite degrees of freedom, as the report's E interval
    (docs/methods.md)."""
    a1, b1, a2, b2 = (np.asarray(v, float) for v in (a1, b1, a2, b2))
    if min(v.size for v in (a1, b1, a2, b2)) < 2:
        return math.nan, math.nan, math.nan, "undecided"
    e1, e2 = a1.mean() / b1.mean(), a2.mean() / b2.mean()
    terms = [(e1 ** 2 * v, n) for v, n in _log_terms(a1, b1)] + [(e2 ** 2 * v, n) for v, n in _log_terms(a2, b2)]
    var = sum(v for v, _ in terms)
    df = var ** 2 / sum(v ** 2 / (n - 1) for v, n in terms if v > 0) if var > 0 else 1.0
    d = e2 - e1
    h95, h = (stats.t.ppf(0.5 + q / 2, df) * math.sqrt(var) for q in (0.95, level))
    return d, d - h, d + h, verdict(d - h95, d + h95, tol)


def shared_soil_e_difference(a1, a2, b, tol: float = 0.05) -> tuple[float, float, float, str]:
    """E2 − E1 of two interface ensembles over ONE soil ensemble b: (mean a2 − mean a1)/mean b, with
    its 95 % interval and verdict at ±tol. The soil enters once, as a scale: var ≈ var_Welch(a2 −
    a1)/b̄² + d²·s_b²/(n_b·b̄²); Student t with the Welch degrees of freedom of the interface terms
    (counting b in each E and adding the two E's variances, as e_difference does for two soils,
    counts its scatter twice and ignores that it moves both E together)."""
    a1, a2, b = (np.asarray(v, float) for v in (a1, a2, b))
    if min(v.size for v in (a1, a2, b)) < 2:
        return math.nan, math.nan, math.nan, "undecided"
    bm = b.mean()
    d = (a2.mean() - a1.mean()) / bm
    v1, v2 = a1.var(ddof=1) / a1.size, a2.var(ddof=1) / a2.size
    var = (v1 + v2) / bm ** 2 + d ** 2 * b.var(ddof=1) / (b.size * bm ** 2)
    df = (v1 + v2) ** 2 / (v1 ** 2 / (a1.size - 1) + v2 ** 2 / (a2.size - 1)) if v1 + v2 > 0 else 1.0
    h = stats.t.ppf(0.975, df) * math.sqrt(var)
    return d, d - h, d + h, verdict(d - h, d + h, tol)
