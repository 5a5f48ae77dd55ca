"""The low branch on the quasi-2D Karlsruhe card: its tables and the verdict on the prediction written
in low_relief_2d.toml, from the committed runs (no engine).

    python studies/low_branch/analyse.py [--check]

Reads results/low_relief_2d/ (summaries.csv, curves.parquet) and writes, beside them:
  ensembles.csv  the seed ensembles (what `campaign report` writes as tables/ensembles.csv)
  cases.csv      per physical interface case: the surface, μs, θa (filter 92, the cell's surface at
                 D50), seeds, the simulated tan δ and δ with their 95 % seed intervals, and δ as
                 predicted before the runs by the card's criterion (soils/karlsruhe-fine-sand-2d.toml's
                 [criterion] fit, its tan φ), by the no-fit rule min(φμ + θa, φ) and by the
                 two-constant rule fitted on the card's Group 1; each one's bias (predicted − simulated);
                 the surface contacts' sliding share, lee share and θr, seed means
  verdict.csv    the four written predictions: what each said, what was measured, met / not met /
                 undecided (a case whose δ interval is wider than the claim decides nothing)
--check writes nothing and fails if a committed table differs from its re-derivation.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.analysis.criterion import predict, rule_delta
from interphase.analysis.ensemble import values_interval
from interphase.analysis.ensemble_table import ensemble_table
from interphase.campaign.results import read_committed, settle_tables
from interphase.criterion_fits import load_criterion

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results" / "low_relief_2d"
#: the fit the prediction was written with (the card's [criterion] fit)
FIT = HERE.parents[1] / "studies" / "kfs_group1_2d" / "results" / "criterion.json"
#: the low branch, as the issue and the prediction name it [° ψ]
LOW_THETA_A = 15.0


def _deg(t):
    return np.degrees(np.arctan(np.asarray(t, float)))


def _surface(label: str) -> str:
    """A short name of the surface from the profile label (asymmetric teeth say which flank is loaded:
    the soil moves +x relative to the surface, so it climbs the rising flank)."""
    if label.startswith("asymmetric"):
        p = {k: float(v) for k, v in re.findall(r"-([a-z]+)([0-9.]+)", label)}
        return f"asymmetric rt {p['rt']:g}, {'steep' if p['rise'] < p['fall'] else 'gentle'}-loaded"
    return label


def cases(summ: pd.DataFrame, ens: pd.DataFrame) -> pd.DataFrame:
    """One row per physical interface case (see the module doc)."""
    model = load_criterion(FIT)
    rule = json.loads(FIT.read_text()).get("rule") or {}
    done = summ[summ["test"].eq("interface") & summ["status"].eq("done")]
    first = done.groupby("physical_id").first()
    means = done.groupby("physical_id")[[c for c in ("slide_share_surface", "lee_share_surface",
                                                      "theta_r_surface_deg") if c in done]].mean()
    slide_n = (done.groupby("physical_id")["slide_share_surface"].count() if "slide_share_surface" in done
               else pd.Series(0, index=first.index))
    e = ens[ens["physical_id"].isin(first.index)].set_index("physical_id")
    out = pd.DataFrame(index=e.index)
    out["surface"] = [_surface(str(first.at[p, "profile_label"])) for p in out.index]
    out["friction_ps"] = first.loc[out.index, "friction_ps"].astype(float)
    out["theta_a_deg_92"] = first.loc[out.index, "theta_a_deg_92"].astype(float)
    out["theta_a_deg_90"] = first.loc[out.index, "theta_a_deg_90"].astype(float)
    out["seeds"] = e["seeds"].astype(int)
    for k in ("tan_delta", "tan_delta_lo", "tan_delta_hi"):
        out[k] = e[k].astype(float)
    out["delta_deg"], out["delta_lo"], out["delta_hi"] = (_deg(out[k]) for k in ("tan_delta", "tan_delta_lo", "tan_delta_hi"))
    tan_phi = model.tan_phi
    out["delta_criterion"] = [predict(model, mu, a92 if a92 > 0 else math.nan, a90).delta_deg
                              for mu, a92, a90 in zip(out["friction_ps"], out["theta_a_deg_92"], out["theta_a_deg_90"])]
    out["delta_rule"] = rule_delta(out["friction_ps"], out["theta_a_deg_92"].fillna(0.0), tan_phi)
    out["delta_rule2"] = (rule_delta(out["friction_ps"], out["theta_a_deg_92"].fillna(0.0), tan_phi,
                                     rule["a_deg"], rule["b"]) if rule else math.nan)
    for k in ("criterion", "rule", "rule2"):
        out[f"bias_{k}"] = out[f"delta_{k}"] - out["delta_deg"]
    for k in means.columns:
        out[k] = means.loc[out.index, k]
    out["slide_seeds"] = slide_n.reindex(out.index).fillna(0).astype(int)
    out["decided_001"] = (out["tan_delta_hi"] - out["tan_delta_lo"]) <= 0.02 + 1e-9
    return (out.reset_index().sort_values(["surface", "friction_ps"], kind="stable").reset_index(drop=True)
            .round(6))


def _fmt(v, f=".1f"):
    return "–" if not math.isfinite(v) else format(v, f)


def verdict(c: pd.DataFrame) -> pd.DataFrame:
    """The four predictions of low_relief_2d.toml against the cases."""
    rows = []
    add = lambda n, said, found, state: rows.append({"prediction": n, "said": said, "found": found, "verdict": state})
    low = c[(c["theta_a_deg_92"] < LOW_THETA_A) & c["friction_ps"].isin([0.05, 0.2])]
    # 1: over-prediction on ≥ 2/3 of the low cases at μs 0.05/0.2, mean bias +1..+3°; μs 0.5 within ±1.5°
    if len(low):
        below = (low["delta_hi"] < low["delta_criterion"]).sum()
        above = (low["delta_lo"] > low["delta_criterion"]).sum()
        mean, lo, hi = _mean_ci(low["bias_criterion"])
        share_ok = below >= math.ceil(2 * len(low) / 3)
        state = ("met" if share_ok and 1.0 <= lo and hi <= 3.0 else
                 "not met" if (len(low) - above) < math.ceil(2 * len(low) / 3) or hi < 1.0 or lo > 3.0 else "undecided")
        add(1, "criterion over-predicts: simulated δ below it on ≥ 2/3 of θa < 15° cases at μs 0.05/0.2, "
               "mean bias +1° to +3°",
            f"{below} of {len(low)} below (decided), {above} above; mean bias {mean:+.2f}° ({_fmt(lo, '+.2f')} to {_fmt(hi, '+.2f')})",
            state)
    hi_mu = c[(c["theta_a_deg_92"] < LOW_THETA_A) & c["friction_ps"].eq(0.5)]
    if len(hi_mu):
        mean, lo, hi = _mean_ci(hi_mu["bias_criterion"])
        state = "met" if -1.5 <= lo and hi <= 1.5 else "not met" if hi < -1.5 or lo > 1.5 else "undecided"
        add(1, "at μs 0.5 the bias within ± 1.5°", f"{len(hi_mu)} cases, mean bias {mean:+.2f}° ({_fmt(lo, '+.2f')} to {_fmt(hi, '+.2f')})", state)
    # 2: steep-loaded above gentle-loaded by at least half the criterion's gap
    for rt in (0.1, 0.25):
        for mu in (0.05, 0.2):
            pick = lambda side: c[c["surface"].eq(f"asymmetric rt {rt:g}, {side}-loaded") & c["friction_ps"].eq(mu)]
            s, g = pick("steep"), pick("gentle")
            if s.empty or g.empty:
                continue
            s, g = s.iloc[0], g.iloc[0]
            gap_pred = s["delta_criterion"] - g["delta_criterion"]
            gap = s["delta_deg"] - g["delta_deg"]
            need = 0.5 * gap_pred
            state = ("met" if s["delta_lo"] - g["delta_hi"] >= need else
                     "not met" if s["delta_hi"] - g["delta_lo"] < need else "undecided")
            add(2, f"rt {rt:g}, μs {mu:g}: steep-loaded above gentle-loaded by ≥ {need:.1f}° (half the criterion's {gap_pred:.1f}°)",
                f"{s['delta_deg']:.1f}° vs {g['delta_deg']:.1f}°: {gap:+.1f}° (intervals {s['delta_lo']:.1f}–{s['delta_hi']:.1f}, "
                f"{g['delta_lo']:.1f}–{g['delta_hi']:.1f})", state)
    # 3: sliding share > 1/2 on every θa < 10° case at μs 0.05, falling with θa
    m = c[(c["theta_a_deg_92"] < 10.0) & c["friction_ps"].eq(0.05) & c["slide_seeds"].gt(0)]
    if len(m):
        n_over = int((m["slide_share_surface"] > 0.5).sum())
        every = c[c["friction_ps"].eq(0.05) & c["slide_seeds"].gt(0)]
        rho = every[["theta_a_deg_92", "slide_share_surface"]].corr(method="spearman").iloc[0, 1] if len(every) > 2 else math.nan
        state = "met" if n_over == len(m) and rho < 0 else "not met"
        add(3, "sliding share > 1/2 on every θa < 10° case at μs 0.05, falling with θa",
            f"{n_over} of {len(m)} above 1/2 (range {m['slide_share_surface'].min():.2f}–{m['slide_share_surface'].max():.2f}); "
            f"Spearman ρ(θa, share) over the {len(every)} μs 0.05 cases {_fmt(rho, '+.2f')}", state)
    # 4: the no-fit rule over-predicts more than the criterion below θa 15°
    low_all = c[c["theta_a_deg_92"] < LOW_THETA_A]
    if len(low_all):
        more = int((low_all["bias_rule"] > low_all["bias_criterion"]).sum())
        d, lo, hi = _mean_ci(low_all["bias_rule"] - low_all["bias_criterion"])
        state = "met" if more == len(low_all) else "not met"
        add(4, "the no-fit rule over-predicts more than the criterion on every θa < 15° case",
            f"{more} of {len(low_all)}; rule − criterion bias {d:+.2f}° ({_fmt(lo, '+.2f')} to {_fmt(hi, '+.2f')})", state)
    return pd.DataFrame(rows)


def _mean_ci(v) -> tuple[float, float, float]:
    """Mean of case values and its 95 % t interval over the cases (analysis.ensemble.values_interval:
    NaN below 3)."""
    v = np.asarray(v, float)
    v = v[np.isfinite(v)]
    return (float(v.mean()) if v.size else math.nan), *values_interval(v)


def tables(folder: Path = RESULTS) -> dict[Path, pd.DataFrame]:
    summ, store = read_committed(folder)
    ens = ensemble_table(summ, store)
    c = cases(summ, ens)
    return {folder / "ensembles.csv": ens, folder / "cases.csv": c, folder / "verdict.csv": verdict(c)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="fail if a committed table differs from its re-derivation")
    args = ap.parse_args(argv)
    out = tables()
    show = ["surface", "friction_ps", "theta_a_deg_92", "seeds", "tan_delta", "tan_delta_lo", "tan_delta_hi",
            "delta_deg", "delta_criterion", "delta_rule", "delta_rule2", "slide_share_surface", "theta_r_surface_deg"]
    with pd.option_context("display.width", 250, "display.max_columns", 30, "display.max_colwidth", 120):
        c = out[RESULTS / "cases.csv"]
        print(c[[k for k in show if k in c]].to_string(index=False), "\n")
        print(out[RESULTS / "verdict.csv"].to_string(index=False), "\n")
    return settle_tables(out, args.check, HERE)


if __name__ == "__main__":
    sys.exit(main())
