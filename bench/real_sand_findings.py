"""Issue 38's findings on the Karlsruhe fine sand, from the committed tables (no runs, no engine).

    PYTHONPATH=src python bench/real_sand_findings.py [--figure PNG]

Reads studies/kfs_group1_2d/results/ (studies/kfs_group1_2d/group1_kfs_2d.toml, the quasi-2D card) and
studies/kfs_group1_3d/results/ (group1_kfs_3d.toml, the 3D card's grains in the 30 × 15 × 10
D50 cell): summaries.csv and curves.parquet, read as the report reads runs (analysis.ensemble_table:
each case's leave-one-out peak over its seeds, E over the paired soil test, 95 % intervals).
Prints Markdown for docs/reproduction.md:
  1. per cell: E (95 %) per Rt/D50 × μs, with θa, the teeth's face angle and θr; the soil's tan φ;
  2. where E saturates, per friction: the highest tooth whose E is decided below 1 (interval under 1)
     and the lowest from which every interval reaches 1, against Dove & Jarrett's laboratory
     thresholds (Rt/D50 > 0.9, face angle ≥ 50°);
  3. E on the teeth at Rt/D50 ≥ 1: range, mean, and how many intervals lie above 1, contain it, lie
     under it (is the interface at full mobilisation stronger than the soil's own test?);
  4. 3D − quasi-2D per physical case (Rt/D50, μs): E's difference with its interval and verdict at
     ± 0.05 (three_d_comparison.e_difference: two soils, two interface ensembles), tan δ's at ± 0.03;
  5. per cell, the soil test read two ways at its peak: τ/σ on the box's horizontal plane (what the
     box reports, what E divides by) and the specimen's own mobilised friction asin(q/p) of its
     average stress (the Mohr circle in x–z; methods.md §6), with the major principal direction
     from the vertical; the quasi-2D one beside the same discs' biaxial φ_peak at TMD17's state
     (docs/soils/karlsruhe-fine-sand-2d/verification_tmd17_6seeds.csv);
  6. the predictions written in group1_kfs_3d.toml's header before its runs, each with what the 3D
     runs read and its verdict (met / not met / within its interval / not yet).
With --figure, draws the two cells per friction against θa: E (upper row) and tan δ (lower row) with
their 95 % intervals, E = 1 and each soil's tan φ as lines (the reading of item 4 at a glance).
The break of E–θr and the criterion's skill are the report's (`bench/refit_reproduction.py --kfs2d
--kfs3d`: correlations.csv, criterion_check.md). A measurement: exit 0 whatever it finds.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).parent))
from three_d_comparison import TOL_E, TOL_TAN, e_difference  # noqa: E402

from interphase.analysis.criterion import rule_delta  # noqa: E402
from interphase.analysis.difference import verdict  # noqa: E402

from interphase.analysis.difference import difference  # noqa: E402
from interphase.analysis.ensemble_table import ensemble_table  # noqa: E402
from interphase.analysis.soil_test import soil_test_readings  # noqa: E402
from interphase.campaign.compare import seed_values  # noqa: E402
from interphase.campaign.results import CommittedCurves  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CELLS = {"quasi-2D": ROOT / "studies" / "kfs_group1_2d" / "results",
         "3D": ROOT / "studies" / "kfs_group1_3d" / "results"}
SATURATED_RT = 1.0        # the teeth whose E item 3 of the issue reads as the plateau
BIAXIAL_2D = ROOT / "docs" / "soils" / "karlsruhe-fine-sand-2d" / "verification_tmd17_6seeds.csv"


def load(folder: Path) -> dict:
    """The cell's ensembles (one row per physical interface case, with rt and μs), per-seed peaks
    (interface by case, soil tests pooled) and the soil's tan φ."""
    summ = pd.read_csv(folder / "summaries.csv", dtype={"case_id": str, "pair_id": str})
    store = CommittedCurves(folder / "curves.parquet")
    table = ensemble_table(summ, store)
    seeds = seed_values(summ, store)
    iface = summ[summ["test"] == "interface"].copy()
    iface["case"] = iface["label"].str.replace(r"-s\d+$", "", regex=True)
    keys = iface.groupby("case")[["rt", "friction_ps", "sw"]].first()
    every = table[table["case"].isin(keys.index)].set_index("case").join(keys)
    cases = every[every["rt"].notna()]      # Group 1's teeth; the flat and measured lines have no Rt
    cases["face_deg"] = np.degrees(np.arctan2(cases["rt"].astype(float), cases["sw"].astype(float) / 2))
    box = seeds[seeds["test"] == "box"]["peak"].to_numpy(float)
    return {"cases": cases.reset_index(), "flat": every[every.index.str.contains("-flat-")].reset_index(),
            "seeds": seeds, "soil": box,
            "tan_phi": table["tan_phi"].dropna().iloc[0] if table["tan_phi"].notna().any() else math.nan,
            "tan_phi_lo": table["tan_phi_lo"].dropna().iloc[0] if table["tan_phi"].notna().any() else math.nan,
            "tan_phi_hi": table["tan_phi_hi"].dropna().iloc[0] if table["tan_phi"].notna().any() else math.nan}


def _e(r) -> str:
    return f"{r.E:.2f} ({r.E_lo:.2f}–{r.E_hi:.2f})" if np.isfinite(r.E) else "—"


def e_table(name: str, d: dict) -> None:
    c = d["cases"]
    phi = math.degrees(math.atan(d["tan_phi"]))
    print(f"\n**{name}**: soil test tan φ {d['tan_phi']:.3f} ({d['tan_phi_lo']:.3f}–{d['tan_phi_hi']:.3f}), "
          f"φ {phi:.1f}°, {d['soil'].size} seeds")
    rts = sorted(c["rt"].astype(float).unique())
    print("\n| Rt/D50 | " + " | ".join(f"{r:g}" for r in rts) + " |")
    print("|---|" + "---|" * len(rts))
    by = c.set_index(["friction_ps", "rt"])
    first = c.groupby("rt").first()
    print("| θa (> 92°), face angle | " + " | ".join(
        f"{first.loc[r, 'theta_a_deg_92']:.1f}°, {first.loc[r, 'face_deg']:.1f}°" for r in rts) + " |")
    for mu in sorted(c["friction_ps"].unique()):
        row = [by.loc[(mu, r)] if (mu, r) in by.index else None for r in rts]
        print(f"| μs {mu:g}: E | " + " | ".join(_e(x) if x is not None else "—" for x in row) + " |")
        print(f"| μs {mu:g}: θr, seeds | " + " | ".join(
            f"{x.theta_r_deg:.1f}°, {int(x.seeds)}" if x is not None else "—" for x in row) + " |")
    half = (c["E_hi"] - c["E_lo"]) / 2
    print(f"\n{len(c)} physical cases; E's 95 % half-width ≤ 0.1 on {int((half <= 0.1).sum())} "
          f"({(half <= 0.1).mean():.0%}); seeds {int(c['seeds'].min())}–{int(c['seeds'].max())}")


def saturation(name: str, d: dict) -> None:
    c = d["cases"]
    print(f"\n{name}, where E saturates (interval reaching 1):")
    for mu, g in c.sort_values("rt").groupby("friction_ps"):
        below = g[g["E_hi"] < 1.0]
        last_below = below["rt"].max() if len(below) else None
        reach = g[g["rt"] > (last_below if last_below is not None else -1)]
        from_rt = reach["rt"].min() if len(reach) else None
        face = reach["face_deg"].min() if len(reach) else math.nan
        lb = f"Rt/D50 {last_below:g} decided below 1 (E {_e(below.iloc[-1])})" if last_below is not None else "none decided below 1"
        print(f"- μs {mu:g}: {lb}; every interval reaches 1 from Rt/D50 {from_rt:g} (face {face:.1f}°)"
              if from_rt is not None else f"- μs {mu:g}: {lb}; not reached")


def plateau(name: str, d: dict) -> None:
    c = d["cases"]
    s = c[c["rt"].astype(float) >= SATURATED_RT]
    if s.empty:
        return
    above, below = int((s["E_lo"] > 1).sum()), int((s["E_hi"] < 1).sum())
    print(f"\n{name}, Rt/D50 ≥ {SATURATED_RT:g} ({len(s)} cases): E {s['E'].min():.2f}–{s['E'].max():.2f}, "
          f"mean {s['E'].mean():.3f}; intervals above 1: {above}, containing 1: {len(s) - above - below}, below 1: {below}")


def paired_cases(d2: dict, d3: dict):
    """(key (Rt/D50, μs), quasi-2D row, 3D row, E 3D − 2D, its 95 % low, high, verdict at ± TOL_E,
    the two per-seed peak arrays) for every 3D case the quasi-2D cell also ran."""
    c2 = d2["cases"].set_index(["rt", "friction_ps"])
    for _, r3 in d3["cases"].sort_values(["friction_ps", "rt"]).iterrows():
        key = (r3["rt"], r3["friction_ps"])
        if key not in c2.index:
            continue
        r2 = c2.loc[key]
        p2 = d2["seeds"].loc[d2["seeds"]["case"] == r2["case"], "peak"].to_numpy(float)
        p3 = d3["seeds"].loc[d3["seeds"]["case"] == r3["case"], "peak"].to_numpy(float)
        yield (key, r2, r3, *e_difference(p2, d2["soil"], p3, d3["soil"]), p2, p3)


def three_vs_two(d2: dict, d3: dict) -> None:
    print("\n| Rt/D50 | μs | E quasi-2D | E 3D | 3D − 2D (95 %) | verdict (± 0.05) | tan δ 3D − 2D (95 %) | verdict (± 0.03) |")
    print("|---|---|---|---|---|---|---|---|")
    for key, r2, r3, de, lo, hi, v, p2, p3 in paired_cases(d2, d3):
        t = difference(p2, p3, TOL_TAN)
        print(f"| {key[0]:g} | {key[1]:g} | {_e(r2)} | {_e(r3)} | {de:+.2f} ({lo:+.2f}, {hi:+.2f}) | {v} "
              f"| {t.change:+.3f} ({t.change_lo:+.3f}, {t.change_hi:+.3f}) | {t.verdict} |")
    print(f"\n(E tolerance ± {TOL_E}; the two cells' soils differ, so E's difference carries both soil tests' scatter)")


def box_reading(name: str, folder: Path) -> None:
    """The soil test's peak read on the box's plane and as the specimen's Mohr circle
    (analysis.soil_test), the quasi-2D one beside the same discs' biaxial φ_peak."""
    r = soil_test_readings(pd.read_csv(folder / "summaries.csv")).iloc[0]

    def f(c: str) -> str:
        return f"{r[c]:.1f}° ({r[c + '_lo']:.1f}–{r[c + '_hi']:.1f}°)"
    print(f"\n{name} soil test at its peak, {int(r['seeds'])} seeds (mean, 95 %): the box's plane {f('phi_plane_deg')}; "
          f"the specimen's Mohr circle asin(q/p) {f('phi_mob_deg')}, major principal stress {f('principal_deg')} "
          f"from the vertical; Mohr's ratio on the horizontal plane there {f('phi_mohr_plane_deg')}; "
          f"atan(sin φ_mob) {f('phi_sin_deg')}")
    if name == "quasi-2D" and BIAXIAL_2D.exists():
        v = pd.read_csv(BIAXIAL_2D).iloc[0]
        print(f"  the same discs' biaxial φ_peak ({v['record']}, {int(v['n_seeds'])} seeds): "
              f"{v['phi_peak_deg']:.1f}° ({v['phi_peak_deg_lo']:.1f}–{v['phi_peak_deg_hi']:.1f}°)")


def _rule_e(mu: float, theta_a: float, tan_phi: float) -> float:
    """The no-fit rule's E: tan δ / tan φ with δ = min(φμ + θa, φ) (criterion.rule_delta)."""
    return math.tan(math.radians(float(rule_delta(mu, theta_a, tan_phi)))) / tan_phi


def _in_range(r, lo: float, hi: float) -> str:
    """A written range against a measured E with its interval: met (the point inside), not met (the
    whole interval outside), else within its interval (the point outside, the interval reaching in)."""
    if lo <= r["E"] <= hi:
        return "met"
    return "not met" if r["E_hi"] < lo or r["E_lo"] > hi else "within its interval"


def predictions_3d(d3: dict, d2: dict | None) -> None:
    """Each prediction written in studies/kfs_group1_3d/group1_kfs_3d.toml's header before its runs,
    against the committed 3D tables: what it said, what the runs read, met / not met / not yet. The
    E–θr break (prediction 3) is the report's fit: `bench/refit_reproduction.py --kfs3d`."""
    c = d3["cases"]
    by = c.set_index(["friction_ps", "rt"])
    tan_phi = d3["tan_phi"]
    print(f"\n3D, the campaign file's predictions (soil tan φ {tan_phi:.3f}, φ {math.degrees(math.atan(tan_phi)):.1f}°):")

    def have(mu, rt):
        return (mu, rt) in by.index

    # 1. saturation: the lowest tooth from which every case reads E >= 0.95 with its interval reaching 1
    said = {0.05: 1.0, 0.2: 0.5, 0.5: 0.5}
    for mu, rt_said in said.items():
        g = c[c["friction_ps"] == mu].sort_values("rt")
        if len(g) < c["rt"].nunique():
            print(f"- 1. μs {mu:g}: saturated from Rt/D50 {rt_said:g} predicted: not yet ({len(g)} of "
                  f"{c['rt'].nunique()} teeth)")
            continue
        sat = (g["E"] >= 0.95) & (g["E_hi"] >= 1.0)
        ok = sat[::-1].cummin()[::-1]           # from this tooth on, every one saturated
        from_rt = g.loc[ok, "rt"].min() if ok.any() else None
        word = ("met" if from_rt == rt_said else "earlier" if from_rt is not None and from_rt < rt_said else
                "later") if from_rt is not None else "not reached"
        print(f"- 1. μs {mu:g}: saturated (E ≥ 0.95, interval reaching 1) from Rt/D50 {rt_said:g} predicted; "
              f"measured from {from_rt if from_rt is None else f'{from_rt:g}'} ({len(g)} teeth): **{word}**")
    # 2. the plateau
    s = c[c["rt"] >= SATURATED_RT]
    words = pd.Series([_in_range(r, 0.98, 1.10) for _, r in s.iterrows()], dtype=object)
    word = "met" if (words == "met").all() else "not met" if (words == "not met").any() else "met within the intervals"
    print(f"- 2. plateau E (Rt/D50 ≥ 1) 0.98–1.10: {len(s)} cases read {s['E'].min():.2f}–{s['E'].max():.2f} "
          f"(mean {s['E'].mean():.3f}); {words.value_counts().to_dict()}: **{word}**")
    # 4. the no-fit rule on the low teeth at μs 0.05, and Rt/D50 0.1 at μs 0.5
    for rt, said_e in ((0.1, 0.22), (0.25, 0.42), (0.5, 0.73)):
        if have(0.05, rt):
            r = by.loc[(0.05, rt)]
            rule = _rule_e(0.05, r["theta_a_deg_92"], tan_phi)
            print(f"- 4. μs 0.05, Rt/D50 {rt:g}: E within 0.1 of the no-fit rule ({said_e} written, {rule:.2f} on "
                  f"this soil test): {_e(r)}, off by {r['E'] - rule:+.2f}: **{'met' if abs(r['E'] - rule) <= 0.1 else 'not met'}**")
    if have(0.5, 0.1):
        r = by.loc[(0.5, 0.1)]
        rule = _rule_e(0.5, r["theta_a_deg_92"], tan_phi)
        print(f"- 4. μs 0.5, Rt/D50 0.1: under the rule ({rule:.2f}): {_e(r)}: "
              f"**{'met' if r['E_hi'] < rule else 'not met'}** (interval {'under' if r['E_hi'] < rule else 'reaching'} it)")
    # 6. the two teeth added later
    said6 = {(0.05, 0.35): (0.3, 0.5), (0.05, 0.7): (0.8, 0.9), (0.2, 0.35): (0.5, 0.7), (0.2, 0.7): (0.8, 1.0),
             (0.5, 0.35): (0.75, 0.95), (0.5, 0.7): (0.85, 1.05)}
    for (mu, rt), (lo, hi) in said6.items():
        if have(mu, rt):
            r = by.loc[(mu, rt)]
            word = _in_range(r, lo, hi)
            print(f"- 6. μs {mu:g}, Rt/D50 {rt:g}: E {lo:g}–{hi:g} (the file's \"~\" read as ± 0.1, its ranges as "
                  f"written): {_e(r)}: **{word}**")
        else:
            print(f"- 6. μs {mu:g}, Rt/D50 {rt:g}: not yet")
    # 5. against the quasi-2D card on the saturated cases, ± 0.1
    if d2 is not None:
        words = [(key, de, verdict(lo, hi, 0.1)) for key, _, r3, de, lo, hi, *_ in paired_cases(d2, d3)
                 if r3["E"] >= 0.95 and r3["E_hi"] >= 1.0]
        tally = pd.Series([w for *_, w in words]).value_counts().to_dict() if words else {}
        bad = [f"Rt/D50 {k[0]:g} μs {k[1]:g} ({de:+.2f})" for k, de, w in words if w == "differ"]
        print(f"- 5. against the quasi-2D card, E within ± 0.1 on the saturated cases and differing on none: "
              f"{len(words)} saturated cases: {tally}; differ: {', '.join(bad) or 'none'}: "
              f"**{'met' if not bad and tally.get('agree', 0) == len(words) else 'not met' if bad else 'partly (some undecided)'}**")
    # 7. the flat
    for _, r in d3["flat"].sort_values("friction_ps").iterrows():
        mu = float(r["friction_ps"])
        if r["seeds"] < 3:
            print(f"- 7. flat, μs {mu:g}: not yet ({int(r['seeds'])} seed)")
            continue
        tan_d = r["tan_delta"]
        phimu = math.degrees(math.atan(mu))
        ok = abs(tan_d - mu) <= 0.01 and abs(r["theta_r_deg"] - phimu) <= 1.0
        print(f"- 7. flat, μs {mu:g}: tan δ = μs within 0.01 and θr within 1° of φμ {phimu:.1f}°: tan δ "
              f"{tan_d:.3f} ({r['tan_delta_lo']:.3f}–{r['tan_delta_hi']:.3f}), θr {r['theta_r_deg']:.1f}°, "
              f"{int(r['seeds'])} seeds: **{'met' if ok else 'not met'}**")
    if d3["flat"].empty:
        print("- 7. the flat at the three frictions: not yet")


def figure(data: dict, path: Path) -> None:
    """E and tan δ against θa per friction, one series per cell, 95 % intervals as bars."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    mus = sorted({mu for d in data.values() for mu in d["cases"]["friction_ps"].unique()})
    fig, axes = plt.subplots(2, len(mus), figsize=(3.6 * len(mus), 6.4), sharex=True, sharey="row",
                             squeeze=False)
    style = {"quasi-2D": ("o", "tab:blue"), "3D": ("s", "tab:red")}
    for j, mu in enumerate(mus):
        for name, d in data.items():
            c = d["cases"][d["cases"]["friction_ps"] == mu].sort_values("theta_a_deg_92")
            if c.empty:
                continue
            marker, colour = style.get(name, ("^", "k"))
            x = c["theta_a_deg_92"].to_numpy(float)
            for i, q in enumerate(("E", "tan_delta")):
                y = c[q].to_numpy(float)
                err = np.vstack([y - c[q + "_lo"].to_numpy(float), c[q + "_hi"].to_numpy(float) - y])
                lo, hi = int(c["seeds"].min()), int(c["seeds"].max())
                axes[i, j].errorbar(x, y, yerr=err, marker=marker, color=colour, capsize=2, lw=1,
                                    label=f"{name} ({lo if lo == hi else f'{lo}–{hi}'} seeds)")
            axes[1, j].axhline(d["tan_phi"], color=colour, ls=":", lw=1)
        axes[0, j].axhline(1.0, color="grey", lw=0.8)
        axes[0, j].set_title(f"μs {mu:g}")
        axes[1, j].set_xlabel("θa (> 92°) [°]")
        axes[0, j].legend(fontsize=7, loc="lower right")
    axes[0, 0].set_ylabel("E = tan δ / tan φ")
    axes[1, 0].set_ylabel("tan δ (dotted: the cell's soil tan φ)")
    fig.suptitle("Karlsruhe fine sand, Group 1: the 3D and quasi-2D cards per case (95 % intervals)", fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=130)
    print(f"\nwrote {path}")


def main() -> None:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--figure", type=Path, help="draw E and tan δ of both cells against θa to this PNG")
    args = ap.parse_args()
    data = {name: load(folder) for name, folder in CELLS.items() if (folder / "summaries.csv").exists()}
    for name, d in data.items():
        e_table(name, d)
        saturation(name, d)
        plateau(name, d)
    for name, folder in CELLS.items():
        if (folder / "summaries.csv").exists():
            box_reading(name, folder)
    if len(data) == 2:
        three_vs_two(data["quasi-2D"], data["3D"])
    if "3D" in data:
        predictions_3d(data["3D"], data.get("quasi-2D"))
    if args.figure:
        figure(data, args.figure)


if __name__ == "__main__":
    main()
