"""What moved between two fits of the same campaign (issue 39 item 1: "say which moved and by how much").

    PYTHONPATH=src python studies/reproduction/findings_moved.py OLD NEW [--tol-e 0.05] [--tol-deg 1]

OLD and NEW are report folders of `studies/reproduction/refit_reproduction.py` (DIR/<set>/, e.g. the study's 3-seed
runs and its sequential rerun: `--study --out /tmp/old`, `--precision --out /tmp/new`). Reads each one's
correlations.json (every bilinear fit, numeric, with its intervals), tables/ensembles.csv (one row per
physical case: E, tan δ, θr with 95 % intervals) and tables/criterion_check.csv (δ predicted against
measured, in sample and held out). Prints Markdown:
  1. the fits: per correlation and slice, n, the break c with its profile interval, b0, b1 and R²,
     old → new; "moved" where the new c lies outside the old interval or the old outside the new;
  2. the cases: how many have E's half-width ≤ 0.1 and ≤ 0.05, each side; the cases whose E moved by
     more than --tol-e (largest first); the cases whose reading against E = 1 changed (interval under
     1, containing it, above it);
  3. the criterion: per fold, cases, mean error, rms, share within 4°, old → new.
A measurement: exit 0 whatever it finds.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd


def _fits(folder: Path) -> pd.DataFrame:
    rows = json.loads((folder / "correlations.json").read_text())
    df = pd.DataFrame(rows)
    return df.set_index(["correlation", "slice"])


def _num(x) -> float:
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def _iv(v, lo, hi, digits: int = 1) -> str:
    v, lo, hi = _num(v), _num(lo), _num(hi)
    if not np.isfinite(v):
        return "—"
    if np.isfinite(lo) and np.isfinite(hi):
        return f"{v:.{digits}f} ({lo:.{digits}f}–{hi:.{digits}f})"
    return f"{v:.{digits}f}"


def fits(old: pd.DataFrame, new: pd.DataFrame) -> None:
    print("\n| correlation | slice | n | c [°] | moved | b0 | b1 | R² |")
    print("|---|---|---|---|---|---|---|---|")
    for key in old.index.union(new.index):
        o = old.loc[key] if key in old.index else None
        n = new.loc[key] if key in new.index else None

        def g(r, col):
            return r[col] if r is not None and col in r.index else math.nan

        co, cn = _num(g(o, "c")), _num(g(n, "c"))
        olo, ohi = _num(g(o, "c_lo_profile")), _num(g(o, "c_hi_profile"))
        nlo, nhi = _num(g(n, "c_lo_profile")), _num(g(n, "c_hi_profile"))
        moved = ""
        if np.isfinite(co) and np.isfinite(cn):
            out_old = np.isfinite(olo) and not (olo <= cn <= ohi)
            out_new = np.isfinite(nlo) and not (nlo <= co <= nhi)
            moved = f"**{cn - co:+.1f}°**" if out_old or out_new else f"{cn - co:+.1f}°"
        print(f"| {key[0]} | {key[1]} | {_num(g(o, 'n')):.0f} → {_num(g(n, 'n')):.0f} "
              f"| {_iv(co, olo, ohi)} → {_iv(cn, nlo, nhi)} | {moved} "
              f"| {_num(g(o, 'b0')):.3g} → {_num(g(n, 'b0')):.3g} | {_num(g(o, 'b1')):.3g} → {_num(g(n, 'b1')):.3g} "
              f"| {_num(g(o, 'r2')):.3f} → {_num(g(n, 'r2')):.3f} |")
    print("\n(moved in bold: the new break lies outside the old one's profile interval, or the old outside the new's)")


def _side(lo: pd.Series, hi: pd.Series) -> pd.Series:
    return pd.Series(np.where(hi < 1, "under 1", np.where(lo > 1, "above 1", "contains 1")), index=lo.index)


def cases(old: pd.DataFrame, new: pd.DataFrame, tol: float) -> None:
    for name, d in (("old", old), ("new", new)):
        soils = d.groupby(d["case"].str.rsplit("-", n=1).str[-1])[["tan_phi", "tan_phi_lo", "tan_phi_hi", "box_seeds"]].first()
        print(f"- {name}, the soil tests: " + "; ".join(
            f"{g} tan φ {_iv(r.tan_phi, r.tan_phi_lo, r.tan_phi_hi, 3)} on {r.box_seeds:.0f} seeds"
            for g, r in soils.iterrows()))
        half = (d["E_hi"] - d["E_lo"]) / 2
        print(f"- {name}: {len(d)} physical cases, seeds {d['seeds'].min():.0f}–{d['seeds'].max():.0f} "
              f"(mean {d['seeds'].mean():.1f}); E's half-width ≤ 0.1 on {int((half <= 0.1).sum())} "
              f"({(half <= 0.1).mean():.0%}), ≤ 0.05 on {int((half <= 0.05).sum())} ({(half <= 0.05).mean():.0%})")
    cols = ["case", "E", "E_lo", "E_hi", "seeds"]
    j = old[cols].merge(new[cols], on="case", suffixes=("_old", "_new")).set_index("case")
    j["dE"] = j["E_new"] - j["E_old"]
    big = j[j["dE"].abs() > tol].sort_values("dE", key=np.abs, ascending=False)
    print(f"\n{len(j)} cases in both; E moved by more than {tol:g} on {len(big)}; |ΔE| median "
          f"{j['dE'].abs().median():.3f}, largest {j['dE'].abs().max():.3f}")
    if len(big):
        print("\n| case | seeds | E old | E new | ΔE |")
        print("|---|---|---|---|---|")
        for cid, r in big.iterrows():
            print(f"| {cid} | {r['seeds_old']:.0f} → {r['seeds_new']:.0f} | {_iv(r['E_old'], r['E_lo_old'], r['E_hi_old'], 2)} "
                  f"| {_iv(r['E_new'], r['E_lo_new'], r['E_hi_new'], 2)} | {r['dE']:+.3f} |")
    so, sn = _side(j["E_lo_old"], j["E_hi_old"]), _side(j["E_lo_new"], j["E_hi_new"])
    flips = j[so != sn]
    print(f"\nreading against E = 1 changed on {len(flips)} case(s)"
          + ("".join(f"\n- {cid}: {so[cid]} → {sn[cid]} (E {r['E_old']:.2f} → {r['E_new']:.2f})"
                     for cid, r in flips.iterrows())))


def criterion(old: pd.DataFrame, new: pd.DataFrame) -> None:
    print("\n| fold | cases | mean error [°] | rms [°] | within 4° |")
    print("|---|---|---|---|---|")
    for fold in pd.unique(pd.concat([old["fold"], new["fold"]])):
        cells = []
        for d in (old, new):
            e = pd.to_numeric(d.loc[d["fold"] == fold, "error [°]"], errors="coerce").dropna()
            cells.append((len(e), e.mean(), math.sqrt((e ** 2).mean()) if len(e) else math.nan,
                          (e.abs() <= 4).mean() if len(e) else math.nan))
        (no, mo, ro, wo), (nn, mn, rn, wn) = cells
        print(f"| {fold} | {no} → {nn} | {mo:+.2f} → {mn:+.2f} | {ro:.2f} → {rn:.2f} | {wo:.0%} → {wn:.0%} |")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old", type=Path)
    ap.add_argument("new", type=Path)
    ap.add_argument("--tol-e", type=float, default=0.05, help="list the cases whose E moved by more (default 0.05)")
    args = ap.parse_args(argv)
    print(f"# What moved: {args.old} → {args.new}")
    print("\n## The fits")
    fits(_fits(args.old), _fits(args.new))
    print("\n## The cases")
    ens = [pd.read_csv(f / "tables" / "ensembles.csv") for f in (args.old, args.new)]
    cases(*(e[e["E"].notna()] for e in ens), args.tol_e)
    print("\n## The criterion against every case")
    criterion(*(pd.read_csv(f / "tables" / "criterion_check.csv") for f in (args.old, args.new)))


if __name__ == "__main__":
    main()
