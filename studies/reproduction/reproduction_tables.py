"""The tables and case counts docs/reproduction.md quotes for the study's groups, printed from a set's
committed seed ensembles (no engine, no runs folder).

    PYTHONPATH=src python studies/reproduction/reproduction_tables.py [SET_FOLDER [REPORT]]

SET_FOLDER holds ensembles.csv and summaries.csv (default docs/reproduction/precision/study/, the
sequential study). Prints Markdown: the soil tests (tan φ at the peak and at the critical state, the
ensemble φ); one grid per group in the doc's layout (E with its 95 % interval, θr at the surface, θa
with the > 92° filter; Group 2 adds θa with every normal, from the summaries); the plateau of Group 1
per gradation at Rt/D50 ≥ 0.5 (E at the peak and at the critical state: range, mean, how many
intervals lie under 1, contain it, lie above it); uniform minus well-graded on the 27 Group 1 cases;
θr − δ per friction where θr ≤ 30° (well-graded Groups 1, 3, 4, 5); the summed-force angle against
δ and θn on the steep teeth (well-graded, seed means of the runs); and, given REPORT (a folder
`studies/reproduction/refit_reproduction.py` wrote for the set, e.g. /tmp/refit/precision), the criterion's error
per fold and group from its tables/criterion_check.csv. Every E and tan δ is the
set's seed-ensemble value (the bagged leave-one-out peak, docs/methods.md).
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[2]
DEFAULT = ROOT / "docs" / "reproduction" / "precision" / "study"
PATTERN = re.compile(r"rt(?P<rt>[\d.]+)-sr(?P<sr>[\d.]+)-sw(?P<sw>[\d.]+)-mu(?P<mu>[\d.]+)-(?P<grad>\w+)$")
FRICTIONS = (0.05, 0.2, 0.5)


def load(folder: Path) -> pd.DataFrame:
    """The set's ensembles with the case's geometry and friction parsed from its label."""
    e = pd.read_csv(folder / "ensembles.csv")
    geo = e["case"].str.extract(PATTERN).astype({"rt": float, "sr": float, "sw": float, "mu": float})
    e = pd.concat([e, geo], axis=1)
    other = e["rt"].isna()                          # random profiles and measured lines: "A-mu0.05-poly"
    e.loc[other, "mu"] = e.loc[other, "case"].str.extract(r"mu([\d.]+)")[0].astype(float)
    e.loc[other, "grad"] = e.loc[other, "case"].str.rsplit("-", n=1).str[1]
    e["profile"] = e["case"].str.replace(r"-mu[\d.]+-\w+$", "", regex=True)
    return e


def _num(x: float, nd: int = 2) -> str:
    return "–" if not np.isfinite(x) else f"{x:.{nd}f}"


def _iv(row, col: str, nd: int = 2) -> str:
    return f"{_num(row[col], nd)} ({_num(row[col + '_lo'], nd)}–{_num(row[col + '_hi'], nd)})"


#: each quantity's row name; E and tan δ print with their 95 % intervals, θr with one where asked
NAMES = {"E": "E", "E_cs": "E, critical state", "tan_delta": "tan δ", "theta_r": "θr [°]"}


def _cell(row, what: str, theta_r_iv: bool) -> str:
    if what == "theta_r":
        return (f"{row['theta_r_deg']:.1f} ({row['theta_r_lo']:.1f}–{row['theta_r_hi']:.1f})" if theta_r_iv
                else f"{row['theta_r_deg']:.1f}")
    return _iv(row, what, 3 if what == "tan_delta" else 2)


def grid(e: pd.DataFrame, key: str, label: str, rows: list[tuple[str, float]], theta_r_iv: bool) -> str:
    """One group's table: a column per `key` value, a row per (quantity, friction) of `rows`."""
    cols = sorted(e[key].unique(), key=lambda v: (isinstance(v, str), v))
    out = [f"| {label} | " + " | ".join(f"{c:g}" if isinstance(c, float) else str(c) for c in cols) + " |",
           "|---|" + "---|" * len(cols)]
    first = e.drop_duplicates(key).set_index(key)
    out.append("| θa (> 92°) [°] | " + " | ".join(_num(first.loc[c, "theta_a_deg_92"], 1) for c in cols) + " |")
    for what, mu in rows:
        sub = e[e["mu"] == mu].set_index(key)
        cells = [_cell(sub.loc[c], what, theta_r_iv) if c in sub.index else "–" for c in cols]
        out.append(f"| {NAMES[what]}, μs {mu} | " + " | ".join(cells) + " |")
    return "\n".join(out)


def reading(lo: pd.Series, hi: pd.Series) -> str:
    return f"{int((hi < 1).sum())} under 1, {int(((lo <= 1) & (hi >= 1)).sum())} contain 1, {int((lo > 1).sum())} above 1"


def plateau(e: pd.DataFrame) -> str:
    out = []
    g1 = e[e["group"].isin(["group1", "group1-mono"]) & (e["rt"] >= 0.5)]
    for grad, sub in g1.groupby("grad"):
        for col in ("E", "E_cs"):
            out.append(f"- Group 1 {grad}, Rt/D50 ≥ 0.5, {col}: {len(sub)} cases, {sub[col].min():.2f}–"
                       f"{sub[col].max():.2f}, mean {sub[col].mean():.3f}; "
                       f"{reading(sub[col + '_lo'], sub[col + '_hi'])}")
    g = e[e["group"].isin(["group1", "group1-mono"])].pivot_table(index=["rt", "mu"], columns="grad",
                                                                   values=["E", "theta_r_deg"])
    for col in ("E", "theta_r_deg"):
        d = g[(col, "mono")] - g[(col, "poly")]
        out.append(f"- uniform − well-graded {col} over {d.notna().sum()} cases: {d.mean():+.3f} ± {d.std():.3f}"
                   f" (mean ± sd); at Rt/D50 ≥ 0.5: {d[d.index.get_level_values('rt') >= 0.5].mean():+.3f}")
    return "\n".join(out)


def theta_r_minus_delta(e: pd.DataFrame) -> str:
    wg = e[e["group"].isin(["group1", "group3", "group4", "group5"]) & (e["grad"] == "poly")]
    delta = np.degrees(np.arctan(wg["tan_delta"]))
    out = []
    for mu in FRICTIONS:
        m = (wg["mu"] == mu) & (wg["theta_r_deg"] <= 30)
        d = wg.loc[m, "theta_r_deg"] - delta[m]
        out.append(f"- μs {mu}: θr − δ = {d.mean():+.1f}° ± {d.std():.1f}° ({int(m.sum())} cases with θr ≤ 30°)")
    hi = wg["theta_r_deg"] > 30
    out.append(f"- above θr 30°: δ {delta[hi].min():.1f}–{delta[hi].max():.1f}°, θr up to {wg.loc[hi, 'theta_r_deg'].max():.1f}°")
    return "\n".join(out)


def statics(folder: Path, e: pd.DataFrame) -> str:
    """The summed-force angle on the surface and θn, per physical case (seed means of the runs)."""
    s = pd.read_csv(folder / "summaries.csv")
    runs = s[s["test"] == "interface"].groupby("physical_id")[
        ["surface_force_angle_deg", "theta_n_surface_deg", "peak_stress_ratio"]].mean()
    wg = e[e["grad"] == "poly"].join(runs, on="physical_id")
    d = wg["surface_force_angle_deg"] - np.degrees(np.arctan(wg["tan_delta"]))
    own = wg["surface_force_angle_deg"] - np.degrees(np.arctan(wg["peak_stress_ratio"]))
    r = np.corrcoef(wg["surface_force_angle_deg"], np.degrees(np.arctan(wg["tan_delta"])))[0, 1]
    out = [f"- summed-force angle − δ (ensemble peak): {d.mean():+.2f}° ± {d.std():.2f}° over {d.notna().sum()}"
           f" well-graded cases, r {r:.3f}; − the runs' own maxima's δ (seed mean): {own.mean():+.2f}° ± {own.std():.2f}°"]
    g1 = wg[wg["group"] == "group1"].set_index(["rt", "mu"])["theta_n_surface_deg"]
    for rt in (0.1, 1.2, 1.5):
        out.append(f"- θn at Rt/D50 {rt:g}: " + ", ".join(f"{g1.loc[(rt, mu)]:.1f}°" for mu in FRICTIONS)
                   + " at μs " + ", ".join(f"{mu:g}" for mu in FRICTIONS))
    return "\n".join(out)


def criterion_by_group(report: Path) -> str:
    """Per fold and group: the criterion's error in δ (mean ± sd, largest miss) and the cases beyond 4°."""
    c = pd.read_csv(report / "tables" / "criterion_check.csv").dropna(subset=["error [°]"])
    out = []
    for (fold, group), sub in c.groupby(["fold", "group"]):
        err = sub["error [°]"]
        worst = sub.loc[err.abs().idxmax()]
        out.append(f"- {fold}, {group}: {err.mean():+.2f}° ± {err.std():.2f}°, {len(sub)} cases; largest miss "
                   f"{worst['error [°]']:+.2f}° ({worst['case']})")
    far = c[c["error [°]"].abs() > 3.5]
    out += [f"- beyond 3.5°: {r['fold']}, {r['case']}: {r['error [°]']:+.2f}° (E measured {r['E measured']:.2f},"
            f" predicted {r['E predicted']:.2f})" for _, r in far.iterrows()]
    return "\n".join(out)


def soil(folder: Path, e: pd.DataFrame) -> str:
    s = pd.read_csv(folder / "summaries.csv")
    out = []
    for grad, sub in e[e["grad"].notna()].groupby("grad"):
        r = sub.iloc[0]
        phi = np.degrees(np.arctan(r["tan_phi"]))
        n_box = int(((s["test"] == "box") & (s["gradation"] == grad)).sum())
        out.append(f"- {grad}: tan φ {_iv(r, 'tan_phi', 3)} on {n_box} soil-test seeds (ensemble φ {phi:.1f}°); "
                   f"critical state {_iv(r, 'tan_phi_cs', 3)}")
    return "\n".join(out)


def main(argv=None) -> None:
    args = argv if argv is not None else sys.argv[1:]
    folder = Path(args[0]) if args else DEFAULT
    e = load(folder)
    s = pd.read_csv(folder / "summaries.csv", dtype={"case_id": str})
    iface = s[s["test"] == "interface"].groupby("group")["seed"].agg(["size"])
    print(f"# {folder}\n\n## Soil tests\n{soil(folder, e)}\n")
    print("## Runs per group\n" + "\n".join(f"- {g}: {int(n)} runs" for g, n in iface["size"].items()))
    seeds = e.groupby("group")["seeds"].agg(["min", "max", "mean"])
    print("\n".join(f"- {g}: {int(r['min'])}–{int(r['max'])} seeds a case (mean {r['mean']:.1f})" for g, r in seeds.iterrows()))
    hw = (e["E_hi"] - e["E_lo"]) / 2
    print(f"- E's half-width: median {hw.median():.3f}; ≤ 0.1 on {int((hw <= 0.1).sum())} of {len(e)}\n")
    both = [(w, m) for w in ("E", "E_cs") for m in FRICTIONS] + [("theta_r", m) for m in FRICTIONS]
    for group, key, label, rows, iv in (
            ("group1", "rt", "Rt/D50", both, False),
            ("group1-mono", "rt", "Rt/D50", both, False),
            ("group4", "profile", "profile", [(w, m) for m in FRICTIONS for w in ("theta_r", "E")], True),
            ("group2", "sr", "Sr/D50", both, True),
            ("group3", "sw", "Sw/D50", [(w, m) for m in FRICTIONS for w in ("theta_r", "E")], True),
            ("group5", "profile", "line", [(w, m) for m in FRICTIONS for w in ("tan_delta", "E", "theta_r")], False)):
        print(f"## {group}\n" + grid(e[e["group"] == group], key, label, rows, iv) + "\n")
    print("## The plateau and the gradations\n" + plateau(e) + "\n")
    print("## θr − δ (well-graded Groups 1, 3, 4, 5)\n" + theta_r_minus_delta(e) + "\n")
    print("## Statics and θn (well-graded)\n" + statics(folder, e) + "\n")
    if len(args) > 1:
        print("## The criterion per group\n" + criterion_by_group(Path(args[1])))


if __name__ == "__main__":
    main()
