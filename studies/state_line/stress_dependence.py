"""Why the Karlsruhe card does not lose strength with stress: the sand's and the spheres' φ_peak,
ψ_max and void ratio at large strain against σ3′ at a fixed initial void ratio (docs/soils.md,
"Karlsruhe fine sand", the paragraph "Why the card did not weaken with stress").

    PYTHONPATH=src python studies/state_line/stress_dependence.py [--runs DIR ...] [--save CSV] [--table CSV]

Specimens: the sand's 15 drained records (lab/soils/karlsruhe-fine-sand/drained-triaxial) and the
card's triaxial runs to 40 % of ε1: every run folder under each `--runs DIR` (case.json, series.parquet)
and the committed 6 + 6 seeds at 100 kPa of docs/soils/kfs_best_sample. `--save` writes the model's
specimen rows (the committed table is docs/soils/karlsruhe-fine-sand/stress_dependence.csv);
`--table` reads them back instead of run folders (no engine output needed).

Per specimen: e0, φ_peak, ψ_max (analysis.triaxial.shear_state, the laboratory's definitions) and
e, p′ and the dilatancy rate r = −dεv/dε1 at ε1 = 20 % (every record reaches it; a line through the
samples within ±1 %). Per source, least squares with 95 % intervals:
    y = a + b·e0 + c·log2(σ3′)     for y = φ_peak, ψ_max, e at 20 %
c is the change per doubling of σ3′ at a fixed e0. If the peak is set by the distance of e0 from
the void ratio the specimen heads for (a state parameter), the stress coefficient follows from the
other two: c_φ ≈ −b_φ · c_e, with c_e the slope of the large-strain void ratio per doubling; the
script prints both sides for the sand and for the spheres.
A measurement: exit 0 whatever it finds.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from interphase.analysis.triaxial import shear_state
from interphase.io.lab_triaxial import read_triaxial

ROOT = Path(__file__).resolve().parents[2]
RECORDS = ROOT / "lab/soils/karlsruhe-fine-sand/drained-triaxial"
BEST = ROOT / "docs/soils/kfs_best_sample"
AT = 0.20          # ε1 at which the large-strain state is read (every record reaches it)
HALF = 0.01        # ± this in ε1 for the line through e and εv there


def specimen(eps1, epsv, ratio, e, sigma3: float) -> dict:
    x, v, r, ev = (np.asarray(a, float) for a in (eps1, epsv, ratio, e))
    s = shear_state(x, v, r, ev)
    sel = np.abs(x - AT) <= HALF
    e_at = float(np.polyval(np.polyfit(x[sel], ev[sel], 1), AT))
    rate = -float(np.polyfit(x[sel], v[sel], 1)[0])
    ratio_at = float(np.mean(r[sel]))
    return dict(sigma3_kPa=sigma3 / 1e3, e0=float(ev[0]), phi_peak_deg=s.phi_peak_deg, psi_max_deg=s.psi_max_deg,
                eps1_peak=s.eps1_peak, e20=e_at, p20_kPa=sigma3 * (ratio_at + 2) / 3 / 1e3, rate20=rate)


def sand_rows() -> pd.DataFrame:
    rows = []
    for p in sorted(RECORDS.glob("*.dat")):
        rec = read_triaxial(p)
        t = rec.table
        rows.append({"source": "sand", "name": p.stem, **specimen(t["eps1"], t["epsv"], t["ratio"], t["e"],
                                                                  rec.sigma3_start)})
    return pd.DataFrame(rows)


def run_rows(folders: list[Path]) -> pd.DataFrame:
    rows = []
    for top in folders:
        for case in sorted(top.glob("*/case.json")):
            c = json.loads(case.read_text())
            i = c["inputs"]
            series = case.parent / "series.parquet"
            if i.get("test") != "triaxial" or not (case.parent / "DONE").exists() or not series.exists():
                continue
            s = pd.read_parquet(series)
            if s["eps1"].max() < AT + HALF:
                continue
            rows.append({"source": "spheres", "name": c["case_id"], "preparation": i.get("preparation", 1.0),
                         "seed": i["seed"], "friction_pp": i["friction_pp"],
                         **specimen(s["eps1"], s["epsv"], s["ratio"], s["e"], i["normal_stress"])})
    summ = pd.read_csv(BEST / "summaries.csv")
    curves = pd.read_parquet(BEST / "cell_curves.parquet")
    for _, r in summ.iterrows():
        c = curves[curves["case_id"] == r["case_id"]]
        rows.append({"source": "spheres", "name": r["case_id"], "preparation": math.nan, "seed": int(r["seed"]),
                     "friction_pp": r["friction_pp"],
                     **specimen(c["eps1"], c["epsv"], c["ratio"], c["e"], r["normal_stress"])})
    return pd.DataFrame(rows)


def fit(d: pd.DataFrame, y: str) -> dict:
    """y = a + b e0 + c log2 σ3′ by least squares; coefficients with 95 % half-widths."""
    X = np.column_stack([np.ones(len(d)), d["e0"], np.log2(d["sigma3_kPa"])])
    v = d[y].to_numpy(float)
    beta, *_ = np.linalg.lstsq(X, v, rcond=None)
    res = v - X @ beta
    dof = len(v) - 3
    cov = res @ res / dof * np.linalg.inv(X.T @ X)
    h = stats.t.ppf(0.975, dof) * np.sqrt(np.diag(cov))
    return dict(y=y, n=len(v), a=beta[0], b=beta[1], b_h=h[1], c=beta[2], c_h=h[2], sd=float(np.sqrt(res @ res / dof)))


def report(d: pd.DataFrame, name: str) -> None:
    print(f"\n{name}: {len(d)} specimens, σ3′ {d['sigma3_kPa'].min():.0f}–{d['sigma3_kPa'].max():.0f} kPa, "
          f"e0 {d['e0'].min():.3f}–{d['e0'].max():.3f}")
    f = {y: fit(d, y) for y in ("phi_peak_deg", "psi_max_deg", "e20")}
    for y, r in f.items():
        print(f"  {y:13s} per +0.1 of e0: {r['b'] / 10:+.3f} ± {r['b_h'] / 10:.3f}   per doubling of σ3′: "
              f"{r['c']:+.3f} ± {r['c_h']:.3f}   (residual sd {r['sd']:.3f})")
    ce = f["e20"]["c"]
    for y in ("phi_peak_deg", "psi_max_deg"):
        print(f"  {y}: the state-parameter reading −b·c_e = {-f[y]['b'] * ce:+.2f}° per doubling "
              f"(measured {f[y]['c']:+.2f} ± {f[y]['c_h']:.2f})")
    print(f"  dilatancy rate at 20 %: {d['rate20'].mean():.3f} (sd {d['rate20'].std(ddof=1):.3f})")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=Path, action="append", default=[], help="a runs folder of triaxial runs to 40 %%")
    ap.add_argument("--save", type=Path, help="write the spheres' specimen rows here")
    ap.add_argument("--table", type=Path, help="read the spheres' specimen rows from here instead of run folders")
    args = ap.parse_args(argv)
    sand = sand_rows()
    spheres = pd.read_csv(args.table) if args.table else run_rows(args.runs)
    if args.save:
        spheres.to_csv(args.save, index=False, float_format="%.6g")
    report(sand, "sand (15 records)")
    report(spheres, "spheres (the card's grains, G 500 MPa, 1000 grains, to 40 %)")
    by = spheres.groupby("sigma3_kPa")[["e0", "phi_peak_deg", "psi_max_deg", "e20", "p20_kPa", "rate20"]].mean()
    by["n"] = spheres.groupby("sigma3_kPa").size()
    print("\nspheres by σ3′ (means):")
    print(by.round(3).to_string())
    return 0


if __name__ == "__main__":
    sys.exit(main())
