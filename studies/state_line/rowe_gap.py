"""The flow-rule miss in Rowe's terms: how much of its critical-state friction a specimen mobilises at
its peak, the Karlsruhe fine sand's records against spheres of its grading at G 500 MPa
(docs/soils.md, "Karlsruhe fine sand", the paragraph "In Rowe's terms").

    PYTHONPATH=src python studies/state_line/rowe_gap.py [--cells docs/soils/kfs_best_sample]

From committed data only (no engine). Rowe (1962) in triaxial compression: σ1′/σ3′ = K (1 + r),
r = −dεv/dε1, K = tan²(45° + φ_f/2). Per specimen:
- at the peak (analysis.rowe.state_row: r over ε1 within ±0.5 % of the peak): φ_f, and the lag
  ε1 at ψ_max − ε1 at the peak; for the sand's 15 records and for the 82 runs to 15 % of ε1 in
  docs/soils/karlsruhe-fine-sand/triaxial_curves.parquet (500 MPa spheres: the present fit's first
  iteration, shared with the fit before, and that fit's second iteration and checks; friction
  0.35–0.51, rolling friction 0.32–0.55, 50–400 kPa);
- φ_f read with ψ_max (peak and fastest dilation taken together, as Bolton reads them) minus the
  angle at the end (the sand: its published φ_c 33.1°; the samples of the present fit,
  calibration_samples.csv: their angle at 40 % of ε1, a critical state), and that gap's linear
  dependence on the free parameters over the 20 samples (least squares, 95 % intervals).
--cells FOLDER adds, per grain set (friction, rolling friction, preparation) of a cell campaign's
committed copy (studies/soil_cells/cell_study.py --save: summaries.csv, cell_curves.parquet to 40 % of ε1), the
same readings per specimen with 95 % intervals over its seeds, the end angle its own at 40 %.
A measurement: exit 0 whatever it finds.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from interphase.analysis.rowe import record_rows, state_row

from interphase.analysis.ensemble import t_interval
from interphase.analysis.triaxial import friction_angle

ROOT = Path(__file__).resolve().parents[2]
RECORDS = ROOT / "lab" / "soils" / "karlsruhe-fine-sand" / "drained-triaxial"
CARD = ROOT / "docs" / "soils" / "karlsruhe-fine-sand"
PHI_C = 33.1          # the published φ_c (Wichtmann & Triantafyllidis 2016)


def phi_f_at_psi_max(phi_peak_deg, psi_max_deg):
    """Rowe's φ_f [°] from φ_peak and ψ_max (sin ψ = r/(2 + r), so r = 2 sin ψ/(1 − sin ψ))."""
    s = np.sin(np.radians(np.asarray(phi_peak_deg, float)))
    sp = np.sin(np.radians(np.asarray(psi_max_deg, float)))
    return friction_angle((1 + s) / (1 - s) / (1 + 2 * sp / (1 - sp)))


def mean_ci(v) -> str:
    v = np.asarray(v, float)
    lo, hi = t_interval(v)
    return f"{v.mean():.2f} ({lo:.2f} to {hi:.2f}), sd {v.std(ddof=1):.2f}, n {v.size}"


def grain_sets(folder: Path) -> None:
    summ = pd.read_csv(folder / "summaries.csv", dtype={"case_id": str})
    curves = pd.read_parquet(folder / "cell_curves.parquet")
    keys = [k for k in ("friction_pp", "rolling_friction", "preparation") if k in summ]
    grains = summ.set_index("case_id")[keys]
    rows = []
    for cid, c in curves.groupby("case_id", sort=False):
        c = c.sort_values("eps1")
        rows.append({**grains.loc[cid].to_dict(), **state_row(c["eps1"].to_numpy(), c["epsv"].to_numpy(),
                                                               c["ratio"].to_numpy(), c["e"].to_numpy())})
    runs = pd.DataFrame(rows)
    runs["gap"] = phi_f_at_psi_max(runs["phi_peak_deg"], runs["psi_max_deg"]) - runs["phi_end_deg"]
    runs["lag"] = 100 * (runs["eps1_psi"] - runs["eps1_peak"])
    for key, g in runs.groupby(keys):
        print(f"\n{dict(zip(keys, key))}")
        for col, name in (("phi_f_deg", "φ_f at the peak [°]"), ("lag", "ε1 at ψ_max − at the peak [%]"),
                          ("gap", "φ_f (with ψ_max) − φ at the end [°]")):
            print(f"  {name}: {mean_ci(g[col])}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=Path, default=None, help="a cell campaign's committed copy (studies/soil_cells/cell_study.py --save)")
    args = ap.parse_args(argv)
    sand = record_rows(RECORDS)
    curves = pd.read_parquet(CARD / "triaxial_curves.parquet")
    runs = []
    for cid, g in curves.groupby("case_id", sort=True):
        g = g.sort_values("eps1")
        e = np.full(len(g), np.nan)           # the curves table holds no void ratio: e0 is not read here
        runs.append({"sigma3_kPa": g["normal_stress"].iloc[0] / 1e3,
                     **state_row(g["eps1"].to_numpy(), g["epsv"].to_numpy(), g["ratio"].to_numpy(), e)})
    model = pd.DataFrame(runs)
    print("Rowe's φ_f at the peak [°]")
    print(f"  sand records        {mean_ci(sand['phi_f_deg'])}")
    print(f"  spheres, 500 MPa    {mean_ci(model['phi_f_deg'])}")
    for s3, g in model.groupby("sigma3_kPa"):
        print(f"    {s3:g} kPa: {g['phi_f_deg'].mean():.2f} (n {len(g)})")
    print("ε1 at ψ_max − ε1 at the peak [% of ε1]")
    print(f"  sand records        {mean_ci(100 * (sand['eps1_psi'] - sand['eps1_peak']))}")
    print(f"  spheres, 500 MPa    {mean_ci(100 * (model['eps1_psi'] - model['eps1_peak']))}")
    print(f"ψ at the peak − ψ_max: sand {mean_ci(sand['psi_peak_deg'] - sand['psi_max_deg'])}; "
          f"spheres {mean_ci(model['psi_peak_deg'] - model['psi_max_deg'])}")

    print("\nφ_f (read with ψ_max) − the angle at the end [°]")
    print(f"  sand records (− φ_c {PHI_C})   {mean_ci(phi_f_at_psi_max(sand['phi_peak_deg'], sand['psi_max_deg']) - PHI_C)}")
    s = pd.read_csv(CARD / "calibration_samples.csv")
    gap = phi_f_at_psi_max(s["phi_peak_deg"], s["psi_max_deg"]) - s["phi_cs_deg"]
    print(f"  the fit's samples (− φ at 40 %) {mean_ci(gap)}")
    names = ["friction_pp", "rolling_friction", "preparation"]
    X = np.column_stack([np.ones(len(s)), s[names].to_numpy(float)])
    b, *_ = np.linalg.lstsq(X, gap, rcond=None)
    r = gap - X @ b
    dof = len(gap) - X.shape[1]
    se = np.sqrt(np.diag(r @ r / dof * np.linalg.inv(X.T @ X)))
    t = stats.t.ppf(0.975, dof)
    for n, bi, si in zip(names, b[1:], se[1:]):
        print(f"    d gap / d {n}: {bi / 10:+.2f} ± {t * si / 10:.2f} per 0.1")
    near = s.assign(phi_f_gap=gap).sort_values("phi_f_gap").head(3)
    print("  the samples nearest the sand's gap:")
    print(near[names + ["phi_peak_deg", "psi_max_deg", "phi_cs_deg", "phi_f_gap", "seeds"]].round(3).to_string(index=False))
    if args.cells:
        grain_sets(args.cells)
    return 0


if __name__ == "__main__":
    sys.exit(main())
