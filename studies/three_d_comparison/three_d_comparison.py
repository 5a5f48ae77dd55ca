"""The 2D–3D comparison and the areal surface's two directions (issue 31), from the 3D campaign.

    PYTHONPATH=src python studies/three_d_comparison/three_d_comparison.py [studies/three_d_comparison/compare_2d3d.toml] [--save DIR]

Reads the campaign's finished runs (or, without runs, the committed copy in DIR: summaries.csv and
curves.parquet) and prints three Markdown tables for docs/3d.md:
  1. per Rt/D50: tan δ (peak) and E with their 95 % seed intervals in the quasi-2D and the 3D cell,
     the study's 2D cell (40 × 25 D50, the sequential study: docs/reproduction/precision/study/ensembles.csv) beside them, and 3D − 2D with
     its interval and verdict (analysis.difference: Welch on the seeds' peak states, tolerance 0.03;
     E through the delta method on the log of each side's ratio of means, tolerance 0.05; E's
     difference also at 90 %);
  2. the 3D out-of-plane share: R_yy and Σ|fy|/Σ|f| at the surface, θr in both devices;
  3. the areal surface z = p(x) + q(y) sheared along each set of teeth, against two predictions of
     the profile criterion for the trace along the shear: (a) the measured 3D extruded profile of
     the same teeth (same soil, cell, stress), the difference over that one soil counted once
     (shared_soil_e_difference); (b) the chain θa → θr → E of the
     reproduction's fits (shipped with the package; fitted on the quasi-2D soil) at the 3D soil's
     tan φ, θa read on the areal surface's own traces in that direction (surface.areal).
Seed states and E are the report's (analysis.ensemble_table, docs/methods.md).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from interphase.analysis.difference import difference, e_difference, shared_soil_e_difference
from interphase.analysis.ensemble_table import ensemble_table
from interphase.campaign.results import CommittedCurves as _Curves
from interphase.campaign.compare import seed_values

HERE = Path(__file__).resolve().parent
ROOT = Path(__file__).resolve().parents[2]
CAMPAIGN = HERE / "compare_2d3d.toml"
SAVED = ROOT / "docs" / "reproduction" / "three_d"
STUDY = ROOT / "docs" / "reproduction" / "precision" / "study" / "ensembles.csv"
TOL_TAN, TOL_E = 0.03, 0.05


def load(campaign: Path, save: Path | None):
    """(summaries, store-like with .curve) from the runs, saved to `save`; else from SAVED."""
    try:
        from interphase.campaign.results import open_campaign

        _, store, summ = open_campaign(campaign)
    except Exception as exc:      # noqa: BLE001 — no runs here: the committed copy
        print(f"(no runs of {campaign.name}: {str(exc).splitlines()[0]}; reading {SAVED})")
        return pd.read_csv(SAVED / "summaries.csv", dtype={"case_id": str, "pair_id": str}), _Curves(SAVED / "curves.parquet")
    if save:
        save.mkdir(parents=True, exist_ok=True)
        summ.to_csv(save / "summaries.csv", index=False)
        rows = []
        for cid in summ["case_id"]:
            c = store.curve(cid)
            if c is not None:
                rows.append(pd.DataFrame({"case_id": cid, "shear_disp": c[0], "stress_ratio": c[1]}))
        pd.concat(rows).to_parquet(save / "curves.parquet", index=False)
    return summ, store


def _fmt(v, lo, hi, nd=3) -> str:
    return f"{v:.{nd}f} ({lo:.{nd}f}–{hi:.{nd}f})"


def main(campaign: Path, save: Path | None) -> None:
    summ, store = load(campaign, save)
    table = ensemble_table(summ, store).set_index("case")
    seeds = seed_values(summ, store)
    iface = summ[summ["test"] == "interface"].copy()
    iface["_case"] = iface["label"].str.replace(r"-s\d+$", "", regex=True)
    iface["profile_y"] = iface["profile_y"] if "profile_y" in iface else None
    boxes = seeds[seeds["test"] == "box"]
    soil = {dev: boxes[boxes["case"].str.contains(f"box-{dev}-")]["peak"].to_numpy(float)
            for dev in ("periodic", "periodic3d")}
    study = pd.read_csv(STUDY).set_index("case")

    def peaks(case):
        return seeds[seeds["case"] == case]["peak"].to_numpy(float)

    def case_of(device, rt, across=None):
        m = (iface["device"] == device) & np.isclose(iface["rt"].astype(float), rt)
        m &= iface["profile_y"].isna() if across is None else iface["profile_y"].astype(str).str.contains(f"rt{across:g}-")
        names = iface.loc[m, "_case"].unique()
        return names[0] if len(names) else None

    print("\n| Rt/D50 | tan δ 2D (20 × 15) | tan δ 3D (20 × 10 × 15) | 3D − 2D | verdict (± 0.03) | E 2D | E 3D | 3D − 2D (95 %; 90 %) | verdict (± 0.05) | E, study's 2D cell (40 × 25) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for rt in (0.2, 1.0, 3.0):
        c2, c3 = case_of("periodic", rt), case_of("periodic3d", rt)
        if c2 is None or c3 is None or c2 not in table.index or c3 not in table.index:
            print(f"| {rt:g} | (not finished) |")
            continue
        t2, t3 = table.loc[c2], table.loc[c3]
        d = difference(peaks(c2), peaks(c3), TOL_TAN)
        de, lo, hi, v = e_difference(peaks(c2), soil["periodic"], peaks(c3), soil["periodic3d"], TOL_E)
        _, lo90, hi90, _ = e_difference(peaks(c2), soil["periodic"], peaks(c3), soil["periodic3d"], TOL_E, level=0.90)
        s = study.loc[c2] if c2 in study.index else None
        big = _fmt(s["E"], s["E_lo"], s["E_hi"], 2) if s is not None else "—"
        print(f"| {rt:g} | {_fmt(t2.tan_delta, t2.tan_delta_lo, t2.tan_delta_hi)} | {_fmt(t3.tan_delta, t3.tan_delta_lo, t3.tan_delta_hi)} "
              f"| {d.change:+.3f} ({d.change_lo:+.3f}, {d.change_hi:+.3f}) | {d.verdict} "
              f"| {_fmt(t2.E, t2.E_lo, t2.E_hi, 2)} | {_fmt(t3.E, t3.E_lo, t3.E_hi, 2)} | {de:+.2f} ({lo:+.2f}, {hi:+.2f}; {lo90:+.2f}, {hi90:+.2f}) | {v} | {big} |")
    b2, b3 = soil["periodic"], soil["periodic3d"]
    tphi = {k: (v.mean(), *stats.t.interval(0.95, v.size - 1, v.mean(), v.std(ddof=1) / math.sqrt(v.size)))
            for k, v in soil.items() if v.size >= 2}
    for k, (m, lo, hi) in tphi.items():
        print(f"soil test {k}: tan φ {_fmt(m, lo, hi)} = φ {math.degrees(math.atan(m)):.1f}° ({len(soil[k])} seeds)")
    if b2.size >= 2 and b3.size >= 2:
        d = difference(b2, b3, TOL_TAN)
        print(f"soil 3D − 2D: {d.change:+.3f} ({d.change_lo:+.3f}, {d.change_hi:+.3f}) {d.verdict}")

    print("\n| case | device | θr at the surface [°] | R_yy | Σ|fy|/Σ|f| | peak at [mm] |")
    print("|---|---|---|---|---|---|")
    for case, g in iface.groupby("_case", sort=False):
        num = lambda col: pd.to_numeric(g[col], errors="coerce") if col in g else pd.Series(np.nan)
        th = table.loc[case] if case in table.index else None
        tr = _fmt(th.theta_r_deg, th.theta_r_lo, th.theta_r_hi, 1) if th is not None else "—"
        print(f"| {case} | {g['device'].iloc[0]} | {tr} | {num('r_yy_surface').mean():.3f} | "
              f"{num('fy_share_surface').mean():.3f} | {num('shear_disp_at_peak').mean() * 1e3:.1f} |")

    areal = iface[iface["profile_y"].notna()]
    if areal.empty:
        return
    print("\n| sheared along | across | E measured | E of the 3D extruded teeth along | difference (one soil) | verdict (± 0.05) | θa along [°] | E predicted by the fits (θr) |")
    print("|---|---|---|---|---|---|---|---|")
    for rt_along, rt_across in ((1.0, 0.2), (0.2, 1.0)):
        ca, ce = case_of("periodic3d", rt_along, rt_across), case_of("periodic3d", rt_along)
        if ca is None or ca not in table.index:
            continue
        ta = table.loc[ca]
        row = areal[areal["_case"] == ca].iloc[0]
        th_a, pred = _predicted(row, tphi.get("periodic3d", (math.nan,))[0])
        if ce is not None and ce in table.index:
            te = table.loc[ce]
            de, lo, hi, v = shared_soil_e_difference(peaks(ce), peaks(ca), soil["periodic3d"], TOL_E)
            ext, diff = _fmt(te.E, te.E_lo, te.E_hi, 2), f"{de:+.2f} ({lo:+.2f}, {hi:+.2f})"
        else:
            ext, diff, v = "(not finished)", "—", "—"
        print(f"| Rt/D50 {rt_along:g} teeth | Rt/D50 {rt_across:g} teeth | {_fmt(ta.E, ta.E_lo, ta.E_hi, 2)} | {ext} | {diff} | {v} "
              f"| {th_a:.1f} | {pred} |")


def _predicted(row, tan_phi: float) -> tuple[float, str]:
    """θa of the areal surface's traces along the shear, and the shipped fits' E (θr) at tan φ."""
    from interphase.analysis.criterion import predict
    from interphase.criterion_fits import criterion_model
    from interphase.surface.areal import theta_a_lines

    from interphase.campaign.schema import load_campaign

    case = next(c.case for c in load_campaign(CAMPAIGN).cases if c.case.label() == row["label"])
    p, q = case.surface(), case.surface_across()
    reps = 3                                     # whole periods in each direction, so no edge matters
    dx = case.d50 / 100
    x = np.arange(0, reps * p.length, dx)
    y = np.arange(0, reps * q.length, case.d50 / 4)
    Z = np.interp(x % p.length, p.x, p.z)[None, :] + np.interp(y % q.length, q.x, q.z)[:, None]
    res = theta_a_lines(x, Z, case.d50, filters=(92,), dx=dx)["+"][92]
    model = criterion_model(case.friction_ps, None, tan_phi)
    pr = predict(model, case.friction_ps, res.theta_a_deg, math.nan)
    return res.theta_a_deg, f"{pr.efficiency:.2f} ({pr.efficiency_interval[0]:.2f}–{pr.efficiency_interval[1]:.2f}) at θr {pr.theta_r_deg:.1f}°"


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("campaign", nargs="?", type=Path, default=CAMPAIGN)
    ap.add_argument("--save", type=Path, help=f"copy the runs' summaries and curves here (e.g. {SAVED.relative_to(ROOT)})")
    a = ap.parse_args()
    main(a.campaign, a.save)
