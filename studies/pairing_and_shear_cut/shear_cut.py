"""Which part of the shear changes nothing (issue 30 item 3), measured on the committed study.

Every run of the study (docs/reproduction: 398 runs, 6 mm of shear at 0.02 m/s) is read again as if
it had stopped earlier: its stress-ratio curve cut at the stop, the seed ensembles of
docs/methods.md (peak of the seed-mean curve, critical state over the last 40 % of each seed's
shear, E against the soil tests) computed from the cut curves exactly as the report computes them
from whole ones. A run stopped at u is the first u of the 6 mm run (the engine is deterministic and
nothing in the deck depends on the shear's length before its end), so full and cut readings are the
same specimens: each physical case's change is judged PAIRED on its seeds (analysis.difference,
t interval on the per-seed differences) against campaign compare's tolerances (tan 0.03, E 0.05);
the ensemble E (interface seeds' mean over all soil tests' mean) through both paired changes.

Two kinds of stop:
  fixed  the shear_distance of every case cut to c mm;
  rule   each run stops at the first check u (every CHECK_MM from MIN_MM) where its critical state
         is established by a stated test: the peak of its curve (smoothed over 0.5 D50) lies before
         the critical window [0.6u, u], and the least-squares drift of the ratio across that window
         is within ±DRIFT (the slope times the window's length). A box test (the soil) takes the
         same rule.
The saving is in shear steps (a case is ~95 % shear: 11 s of consolidation, 194 s of shear for a
1 056-grain case, BENCHMARKS.md). Not measured here: θr at the critical state (from contact dumps,
not in the committed curves); the peak θr is unchanged whenever the peak lies before the stop.

Usage:  python studies/pairing_and_shear_cut/shear_cut.py [--out docs/reproduction/shear_cut.csv]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.analysis.difference import difference, verdict
from interphase.campaign.compare import TOLERANCES, seed_values

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "docs" / "reproduction"
FULL_MM = 6.0
MIN_MM, CHECK_MM = 2.5, 0.5
DRIFT = 0.02              # tan units across the critical window
SMOOTH_D50 = 0.5


class Curves:
    """A store stand-in: each run's committed curve, cut at its stop [m]."""

    def __init__(self, curves: pd.DataFrame, stop: dict[str, float]):
        self.by_id = {cid: g[["shear_disp", "stress_ratio"]].reset_index(drop=True) for cid, g in curves.groupby("case_id")}
        self.stop = stop

    def curve(self, cid: str) -> tuple[np.ndarray, np.ndarray]:
        c = self.by_id[cid]
        c = c[c["shear_disp"] <= self.stop[cid] + 1e-12]
        return c["shear_disp"].to_numpy(float), c["stress_ratio"].to_numpy(float)


def rule_stop(curve: pd.DataFrame, d50: float) -> float:
    """The stated test's stop [m] for one run (FULL_MM if never established)."""
    u_all, r_all = curve["shear_disp"].to_numpy(), curve["stress_ratio"].to_numpy()
    k = max(1, int(round(SMOOTH_D50 * d50 / np.median(np.diff(u_all)))))
    smooth = pd.Series(r_all).rolling(k, center=True, min_periods=1).mean().to_numpy()
    for u_mm in np.arange(MIN_MM, FULL_MM + 1e-9, CHECK_MM):
        u = u_mm * 1e-3
        upto = u_all <= u + 1e-12
        lo = 0.6 * u
        w = upto & (u_all >= lo)
        if w.sum() < 5:
            continue
        peak_at = u_all[upto][np.argmax(smooth[upto])]
        slope = np.polyfit(u_all[w], r_all[w], 1)[0]
        if peak_at < lo and abs(slope * (u - lo)) <= DRIFT:
            return u
    return FULL_MM * 1e-3


def _rel_change(a: np.ndarray, b: np.ndarray) -> tuple[float, float, int]:
    """(relative change of the mean, its standard error, seeds) of paired values a → b."""
    ok = np.isfinite(a) & np.isfinite(b)
    a, b = a[ok], b[ok]
    d = (b - a) / a.mean()
    return float(d.mean()), float(d.std(ddof=1) / np.sqrt(d.size)), int(d.size)


def efficiency_change(a, a_cut, s, s_cut) -> tuple[float, float, float, float]:
    """(E, ΔE, ΔE_lo, ΔE_hi) of the ensemble E = mean(interface)/mean(soil) when both are re-read:
    ln E moves by ln(1 + r_a) − ln(1 + r_s), r the paired relative changes of the two means; their
    standard errors add in quadrature (different runs), Student t at the smaller count less one
    (conservative), as the report's delta-method interval of E (docs/methods.md)."""
    from scipy import stats

    e = np.nanmean(a) / np.nanmean(s)
    ra, sa, na = _rel_change(a, a_cut)
    rs, ss, ns = _rel_change(s, s_cut)
    dl = np.log1p(ra) - np.log1p(rs)
    se = np.hypot(sa / (1 + ra), ss / (1 + rs))
    t = stats.t.ppf(0.975, max(1, min(na, ns) - 1))
    return e, e * np.expm1(dl), e * np.expm1(dl - t * se), e * np.expm1(dl + t * se)


def judge(full: pd.DataFrame, cut: pd.DataFrame) -> pd.DataFrame:
    """Per physical case and metric, cut − full: tan δ, tan φ paired on seeds; E through both."""
    rows = []
    cut = cut.set_index("case_id")
    soil_of = full[full["test"].eq("box")].set_index("case_id")["case"]
    for case, a in full.groupby("case"):
        b = cut.reindex(a["case_id"])
        test = str(a["test"].iloc[0])
        for state in ("peak", "critical"):
            metric = ("tan_phi" if test == "box" else "tan_delta") + ("_cs" if state == "critical" else "")
            d = difference(a[state].to_numpy(float), b[state].to_numpy(float), TOLERANCES[metric], paired=True)
            rows.append(dict(case=case, test=test, metric=metric, ref=d.ref, change=d.change, change_lo=d.change_lo,
                             change_hi=d.change_hi, verdict=d.verdict))
            if test == "box":
                continue
            soil = full[full["case"].eq(soil_of[a["pair_id"].iloc[0]])]
            e, de, lo, hi = efficiency_change(a[state].to_numpy(float), b[state].to_numpy(float),
                                              soil[state].to_numpy(float),
                                              cut.reindex(soil["case_id"])[state].to_numpy(float))
            metric = "E" + ("_cs" if state == "critical" else "")
            rows.append(dict(case=case, test=test, metric=metric, ref=e, change=de, change_lo=lo, change_hi=hi,
                             verdict=verdict(lo, hi, TOLERANCES[metric])))
    return pd.DataFrame(rows)


def main(out: Path | None) -> None:
    summ = pd.read_csv(DATA / "summaries.csv", dtype={"case_id": str, "pair_id": str})
    curves = pd.read_parquet(DATA / "curves.parquet")
    curves["case_id"] = curves["case_id"].astype(str)
    ids = summ["case_id"].tolist()
    full = seed_values(summ, Curves(curves, {c: 1.0 for c in ids}))
    d50 = dict(zip(summ["case_id"], summ["d50"]))
    stops = {"rule": {cid: rule_stop(g, d50[cid]) for cid, g in curves.groupby("case_id")}}
    for c in (3.0, 4.0, 5.0):
        stops[f"fixed {c:g} mm"] = {cid: c * 1e-3 for cid in ids}
    rows, tables = [], []
    for name, stop in stops.items():
        t = judge(full, seed_values(summ, Curves(curves, stop))).assign(stop=name)
        tables.append(t)
        saved = 1 - np.mean([stop[c] for c in ids]) / (FULL_MM * 1e-3)
        row = {"stop": name, "shear saved": f"{saved:.0%}"}
        for metric in ("tan_delta", "tan_delta_cs", "E", "E_cs", "tan_phi", "tan_phi_cs"):
            m = t[t["metric"].eq(metric)]
            counts = m["verdict"].value_counts()
            row[metric] = (f"{counts.get('agree', 0)}/{counts.get('undecided', 0)}/{counts.get('differ', 0)}"
                           f" (max |Δ| {m['change'].abs().max():.3f})")
        rows.append(row)
    table = pd.DataFrame(rows)
    print(f"{len(ids)} runs, {full['case'].nunique()} physical cases; verdicts agree/undecided/differ, "
          f"paired, tolerances tan {TOLERANCES['tan_delta']}, E {TOLERANCES['E']}")
    print(table.to_string(index=False))
    for test, g in summ.groupby("test"):
        q = (g["shear_disp_at_peak"] * 1e3).quantile([0.1, 0.25, 0.5, 0.75, 0.9]).round(1).tolist()
        print(f"{test}: each run's peak at [mm], 10/25/50/75/90 %: {q}; peak within a window of the end "
              f"{g['peak_at_end'].mean():.0%} ({len(g)} runs)")
    r = pd.Series(stops["rule"]) * 1e3
    print(f"rule stops [mm]: median {r.median():.1f}, 6 mm (never established) {int((r >= FULL_MM).sum())} of {len(r)}")
    if out:
        pd.concat(tables).to_csv(out, index=False, float_format="%.5g")
        print(f"per-case table → {out}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path)
    main(ap.parse_args().out)
    sys.exit(0)
