"""Group 1 on the 3D Karlsruhe card: its tables from its committed runs (no engine), and the card
against the quasi-2D one case by case.

    python studies/kfs_group1_3d/analyse.py [--check] [--figure]

Reads results/summaries.csv and results/curves.parquet (the committed runs of group1_kfs_3d.toml)
and, for the comparison, studies/kfs_group1_2d/results/; writes, beside this study's runs:
  ensembles.csv    the seed ensembles, one row per physical interface case (`campaign report`'s)
  cases.csv        the same per case with its tooth (Rt/D50, Sw/D50, face angle) and friction
  saturation.csv   per friction: the first tooth whose E interval reaches 1, the one under it
  plateau.csv      E on the teeth at Rt/D50 >= 1 against 1
  soil_test.csv    the paired soil test read on the box's plane and as the specimen's Mohr circle
  vs_2d.csv        per tooth and friction: 3D − quasi-2D in E (both soils' scatter carried; verdicts
                   at ± 0.05 and at the campaign file's ± 0.1) and in tan δ (± 0.03)
  predictions.csv  each prediction written in group1_kfs_3d.toml's header before its runs, what the
                   runs read and the verdict
--figure draws results/3d_vs_2d.png (E and tan δ against θa, both cards). --check writes nothing and
fails if a committed table differs from its re-derivation. The fits (criterion.json,
correlations.csv, criterion_check.md, Figs. 6.8, 6.10a) are the report's:
`studies/reproduction/refit_reproduction.py --kfs3d`.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.analysis.difference import difference, e_difference, verdict
from interphase.analysis.ensemble_table import ensemble_table
from interphase.analysis.group1 import SATURATED_RT, plateau, rule_efficiency, saturation, tooth_cases
from interphase.analysis.soil_test import soil_test_readings
from interphase.campaign.compare import seed_values
from interphase.campaign.results import read_committed, settle_tables

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
QUASI_2D = HERE.parent / "kfs_group1_2d" / "results"
TOL_E, TOL_TAN = 0.05, 0.03
#: the campaign file's own tolerance for "E agrees with the quasi-2D card" (its prediction 5)
TOL_E_FILE = 0.1


def _card(folder: Path) -> dict:
    summ, store = read_committed(folder)
    seeds = seed_values(summ, store)
    return {"summ": summ, "store": store, "cases": tooth_cases(summ, store), "seeds": seeds,
            "soil": seeds.loc[seeds["test"].eq("box"), "peak"].to_numpy(float)}


def _peaks(card: dict, case: str) -> np.ndarray:
    s = card["seeds"]
    return s.loc[s["case"].eq(case), "peak"].to_numpy(float)


def vs_2d(d3: dict, d2: dict) -> pd.DataFrame:
    """3D − quasi-2D per tooth and friction both cards ran."""
    c2 = d2["cases"].dropna(subset=["rt"]).set_index(["rt", "friction_ps"])
    rows = []
    for r3 in d3["cases"].dropna(subset=["rt"]).itertuples():
        if (r3.rt, r3.friction_ps) not in c2.index:
            continue
        r2 = c2.loc[(r3.rt, r3.friction_ps)]
        p2, p3 = _peaks(d2, r2["case"]), _peaks(d3, r3.case)
        de, lo, hi, v = e_difference(p2, d2["soil"], p3, d3["soil"], TOL_E)
        t = difference(p2, p3, TOL_TAN)
        rows.append({"rt": r3.rt, "friction_ps": r3.friction_ps, "E_2d": r2["E"], "E_2d_lo": r2["E_lo"],
                     "E_2d_hi": r2["E_hi"], "E_3d": r3.E, "E_3d_lo": r3.E_lo, "E_3d_hi": r3.E_hi,
                     "saturated_3d": bool(r3.E >= 0.95 and r3.E_hi >= 1.0),
                     "dE": de, "dE_lo": lo, "dE_hi": hi, "verdict_E": v, "verdict_E_file": verdict(lo, hi, TOL_E_FILE),
                     "dtan_delta": t.change, "dtan_delta_lo": t.change_lo, "dtan_delta_hi": t.change_hi,
                     "verdict_tan_delta": t.verdict})
    return pd.DataFrame(rows)


def _e(r) -> str:
    return f"{r['E']:.2f} ({r['E_lo']:.2f}–{r['E_hi']:.2f})"


def _in_range(r, lo: float, hi: float) -> str:
    """A written range against a measured E with its interval: met (the point inside), not met (the
    whole interval outside), else within its interval (the point outside, the interval reaching in)."""
    if lo <= r["E"] <= hi:
        return "met"
    return "not met" if r["E_hi"] < lo or r["E_lo"] > hi else "within its interval"


def predictions(d3: dict, cmp: pd.DataFrame) -> pd.DataFrame:
    """Each prediction of the campaign file's header, numbered as there, against the runs. The
    E–θr break (its 3) is the report's fit (correlations.csv)."""
    c = d3["cases"]
    teeth = c.dropna(subset=["rt"])
    by = teeth.set_index(["friction_ps", "rt"])
    tan_phi = float(c["tan_phi"].dropna().iloc[0])
    rows = []

    def add(item, said, read, word):
        rows.append({"item": item, "prediction": said, "measured": read, "verdict": word})

    for mu, rt_said in {0.05: 1.0, 0.2: 0.5, 0.5: 0.5}.items():
        g = teeth[teeth["friction_ps"] == mu].sort_values("rt")
        sat = ((g["E"] >= 0.95) & (g["E_hi"] >= 1.0))[::-1].cummin()[::-1]     # from this tooth on, every one
        got = g.loc[sat, "rt"].min() if sat.any() else math.nan
        word = ("not reached" if not math.isfinite(got) else "met" if got == rt_said
                else "earlier" if got < rt_said else "later")
        add(1, f"μs {mu:g}: E saturated (≥ 0.95, interval reaching 1) from Rt/D50 {rt_said:g}",
            f"from Rt/D50 {got:g}", word)
    s = teeth[teeth["rt"] >= SATURATED_RT]
    words = pd.Series([_in_range(r, 0.98, 1.10) for _, r in s.iterrows()], dtype=object)
    add(2, "plateau E (Rt/D50 ≥ 1) 0.98–1.10",
        f"{len(s)} cases {s['E'].min():.2f}–{s['E'].max():.2f}, mean {s['E'].mean():.3f}; "
        + ", ".join(f"{k} {v}" for k, v in words.value_counts().items()),
        "met" if (words == "met").all() else "not met" if (words == "not met").any() else "met within the intervals")
    for rt, said in ((0.1, 0.22), (0.25, 0.42), (0.5, 0.73)):
        r = by.loc[(0.05, rt)]
        rule = rule_efficiency(0.05, r["theta_a_deg_92"], tan_phi)
        add(4, f"μs 0.05, Rt/D50 {rt:g}: E within 0.1 of the no-fit rule ({said} written)",
            f"{_e(r)}; the rule {rule:.2f} on this soil test, off by {r['E'] - rule:+.2f}",
            "met" if abs(r["E"] - rule) <= 0.1 else "not met")
    r = by.loc[(0.5, 0.1)]
    rule = rule_efficiency(0.5, r["theta_a_deg_92"], tan_phi)
    add(4, f"μs 0.5, Rt/D50 0.1: E under the no-fit rule ({rule:.2f})", _e(r),
        "met" if r["E_hi"] < rule else "not met")
    sat = cmp[cmp["saturated_3d"]]
    tally = sat["verdict_E_file"].value_counts()
    differ = sat[sat["verdict_E_file"].eq("differ")]
    add(5, "against the quasi-2D card: E within ± 0.1 on the saturated cases, differing on none",
        f"{len(sat)} saturated cases: " + ", ".join(f"{k} {v}" for k, v in tally.items())
        + (f"; differ: {len(differ)}" if len(differ) else ""),
        "met" if tally.get("agree", 0) == len(sat) else "not met" if len(differ) else "met where decided")
    written = {(0.05, 0.35): (0.3, 0.5), (0.05, 0.7): (0.8, 0.9), (0.2, 0.35): (0.5, 0.7), (0.2, 0.7): (0.8, 1.0),
               (0.5, 0.35): (0.75, 0.95), (0.5, 0.7): (0.85, 1.05)}        # the file's "~" read as ± 0.1
    for (mu, rt), (lo, hi) in written.items():
        r = by.loc[(mu, rt)]
        add(6, f"μs {mu:g}, Rt/D50 {rt:g}: E {lo:g}–{hi:g}", _e(r), _in_range(r, lo, hi))
    for r in c[c["profile_kind"].eq("flat")].itertuples():
        phimu = math.degrees(math.atan(r.friction_ps))
        ok = abs(r.tan_delta - r.friction_ps) <= 0.01 and abs(r.theta_r_deg - phimu) <= 1.0
        add(7, f"flat, μs {r.friction_ps:g}: tan δ = μs within 0.01, θr within 1° of φμ {phimu:.1f}°",
            f"tan δ {r.tan_delta:.3f} ({r.tan_delta_lo:.3f}–{r.tan_delta_hi:.3f}), θr {r.theta_r_deg:.1f}°",
            "met" if ok else "not met")
    return pd.DataFrame(rows)


def figure(cards: dict, path: Path) -> None:
    """E and tan δ against θa per friction, one series per card, 95 % intervals as bars."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    mus = sorted({mu for d in cards.values() for mu in d["cases"]["friction_ps"].unique()})
    fig, axes = plt.subplots(2, len(mus), figsize=(3.6 * len(mus), 6.4), sharex=True, sharey="row", squeeze=False)
    style = {"quasi-2D": ("o", "tab:blue"), "3D": ("s", "tab:red")}
    for j, mu in enumerate(mus):
        for name, d in cards.items():
            c = d["cases"].dropna(subset=["rt"])
            c = c[c["friction_ps"] == mu].sort_values("theta_a_deg_92")
            marker, colour = style[name]
            x = c["theta_a_deg_92"].to_numpy(float)
            for i, q in enumerate(("E", "tan_delta")):
                y = c[q].to_numpy(float)
                err = np.vstack([y - c[q + "_lo"].to_numpy(float), c[q + "_hi"].to_numpy(float) - y])
                lo, hi = int(c["seeds"].min()), int(c["seeds"].max())
                axes[i, j].errorbar(x, y, yerr=err, marker=marker, color=colour, capsize=2, lw=1,
                                    label=f"{name} ({lo if lo == hi else f'{lo}–{hi}'} seeds)")
            axes[1, j].axhline(float(c["tan_phi"].iloc[0]), color=colour, ls=":", lw=1)
        axes[0, j].axhline(1.0, color="grey", lw=0.8)
        axes[0, j].set_title(f"μs {mu:g}")
        axes[1, j].set_xlabel("θa (> 92°) [°]")
        axes[0, j].legend(fontsize=7, loc="lower right")
    axes[0, 0].set_ylabel("E = tan δ / tan φ")
    axes[1, 0].set_ylabel("tan δ (dotted: the cell's soil tan φ)")
    fig.suptitle("Karlsruhe fine sand, Group 1: the 3D and quasi-2D cards per case (95 % intervals)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    print(f"wrote {path.relative_to(HERE)}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="fail if a committed table differs from its re-derivation")
    ap.add_argument("--figure", action="store_true", help="draw results/3d_vs_2d.png")
    args = ap.parse_args(argv)
    d3, d2 = _card(RESULTS), _card(QUASI_2D)
    cmp = vs_2d(d3, d2)
    out = {RESULTS / "ensembles.csv": ensemble_table(d3["summ"], d3["store"]),
           RESULTS / "cases.csv": d3["cases"].round(6),
           RESULTS / "saturation.csv": saturation(d3["cases"]).round(6),
           RESULTS / "plateau.csv": plateau(d3["cases"]).round(6),
           RESULTS / "soil_test.csv": soil_test_readings(d3["summ"]).round(6),
           RESULTS / "vs_2d.csv": cmp.round(6),
           RESULTS / "predictions.csv": predictions(d3, cmp)}
    with pd.option_context("display.width", 250, "display.max_columns", 30, "display.max_colwidth", 120):
        for path, df in out.items():
            if path.name not in ("ensembles.csv", "cases.csv"):
                print(f"{path.name}:\n{df.to_string(index=False)}\n")
    if args.figure and not args.check:
        figure({"quasi-2D": d2, "3D": d3}, RESULTS / "3d_vs_2d.png")
    return settle_tables(out, args.check, HERE)


if __name__ == "__main__":
    sys.exit(main())
