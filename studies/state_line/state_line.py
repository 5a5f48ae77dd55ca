"""Strength against dilatancy: the card's spheres from dense to loose beside the sand's 15 records
(docs/soils.md, "From dense to loose: the state line"), as Markdown, a CSV and a figure.

    PYTHONPATH=src python studies/state_line/state_line.py studies/state_line/state_line.toml \
        --records lab/soils/karlsruhe-fine-sand/drained-triaxial --save docs/soils/state_line

Per run (the campaign's finished runs, or the committed copy in --save) and per record, by the same
code (analysis.triaxial.shear_state): φ_peak, ψ_max, e0, the end state, and Rowe's friction part at
the peak, φ_f = asin((K − 1)/(K + 1)) with K = R_peak / (1 + r_peak) (triaxial compression,
σ1′/σ3′ = K (1 − dεv/dε1)), r_peak the dilatancy rate −dεv/dε1 of a straight line over ε1 within
±0.5 % of the peak (analysis.rowe), and ψ at the peak from r_peak (the ψ_max formula); ε1 at ψ_max is the centre of
its window. The comparison in the (ψ_max, φ_peak) plane: a least-squares line through the
model's runs, and each record's φ_peak minus that line at the record's ψ_max (mean over the records,
Student-t 95 % interval). Rowe's relation is read as stress-independent, so records at 50–400 kPa are
set beside model runs at 200 kPa; the table says each record's stress.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from interphase.analysis.rowe import record_rows, state_row
from interphase.analysis.triaxial import friction_angle
from interphase.io.lab_triaxial import read_triaxial
from interphase.report.cell_tables import cell_runs as from_runs

def model_rows(summ: pd.DataFrame, curves: pd.DataFrame) -> pd.DataFrame:
    rows = []
    summ = summ.assign(preparation=summ["preparation"].fillna(1.0))    # 1 (the grains' own friction) is stored as unset
    for _, r in summ.iterrows():
        c = curves[curves["case_id"] == r["case_id"]]
        rows.append({"source": "model", "name": f"prep {r['preparation']:g} s{int(r['seed'])}",
                     "preparation": r["preparation"], "seed": int(r["seed"]), "sigma3_kPa": r["normal_stress"] / 1e3,
                     **state_row(c["eps1"], c["epsv"], c["ratio"], c["e"])})
    return pd.DataFrame(rows)


def offset(model: pd.DataFrame, sand: pd.DataFrame, x: str = "psi_max_deg") -> dict:
    """The sand's φ_peak minus the model's line φ_peak(x) at the sand's own x (ψ_max, or ψ at the
    peak): mean and 95 % interval."""
    fit = stats.linregress(model[x], model["phi_peak_deg"])
    d = sand["phi_peak_deg"] - (fit.intercept + fit.slope * sand[x])
    n = len(d)
    h = stats.t.ppf(0.975, n - 1) * d.std(ddof=1) / math.sqrt(n)
    return dict(slope=fit.slope, intercept=fit.intercept, r2=fit.rvalue ** 2, n_model=len(model), n_sand=n,
                offset=float(d.mean()), lo=float(d.mean() - h), hi=float(d.mean() + h),
                x=x, x_model=(float(model[x].min()), float(model[x].max())))


def by_preparation(model: pd.DataFrame) -> pd.DataFrame:
    cols = ["e0", "phi_peak_deg", "eps1_peak", "psi_max_deg", "eps1_psi", "rate_peak", "psi_peak_deg", "rate_max",
            "phi_f_deg", "phi_end_deg", "e_end", "dilatancy_end"]
    g = model.groupby("preparation")
    out = g[cols].mean()
    out["n"] = g.size()
    for c in ("phi_peak_deg", "psi_max_deg", "phi_end_deg"):
        out[c + "_min"], out[c + "_max"] = g[c].min(), g[c].max()
    return out.reset_index()


def figure(model: pd.DataFrame, sand: pd.DataFrame, curves: pd.DataFrame, summ: pd.DataFrame, records: Path,
           path: Path) -> None:
    """φ_peak against ψ_max and against ψ at the peak (model runs coloured by preparation, records by
    stress, each with the model's line), and the curves of the model's preparation 0.2 beside TMD18."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 3, figsize=(15, 4.3))
    for a, x, name in ((ax[0], "psi_max_deg", "ψ_max"), (ax[1], "psi_peak_deg", "ψ at the peak")):
        sc = a.scatter(model[x], model["phi_peak_deg"], c=model["preparation"], cmap="viridis", vmin=0, vmax=1,
                       label="spheres, 200 kPa")
        for s3, m in zip((50, 100, 200, 300, 400), "v<s>^"):
            sel = (sand["sigma3_kPa"] - s3).abs() < 25
            a.scatter(sand.loc[sel, x], sand.loc[sel, "phi_peak_deg"], marker=m, color="k", facecolors="none",
                      label=f"sand {s3} kPa")
        o = offset(model, sand, x)
        xs = np.linspace(0, 25, 20)
        a.plot(xs, o["intercept"] + o["slope"] * xs, color="C0", lw=1)
        a.set(xlabel=f"{name} [°]", ylabel="φ_peak [°]",
              title=f"sand − spheres' line: {o['offset']:+.1f}° ({o['lo']:+.1f} to {o['hi']:+.1f})")
    ax[0].legend(fontsize=7)
    fig.colorbar(sc, ax=ax[1], label="preparation")
    b = ax[2]
    b2 = b.twinx()
    ids = summ.loc[summ["preparation"].fillna(1.0) == 0.2, "case_id"]
    for cid in ids:
        c = curves[curves["case_id"] == cid]
        b.plot(c["eps1"] * 100, friction_angle(c["ratio"]), color="C0", lw=1)
        b2.plot(c["eps1"] * 100, c["epsv"] * 100, color="C0", lw=1, ls="--")
    t = read_triaxial(records / "TMD18.dat").table
    b.plot(t["eps1"] * 100, friction_angle(t["ratio"]), color="k", lw=1.5)
    b2.plot(t["eps1"] * 100, t["epsv"] * 100, color="k", lw=1.5, ls="--")
    b.axhline(33.1, color="grey", lw=0.8, ls=":")
    b.set(xlabel="ε1 [%]", ylabel="mobilised φ [°] (solid)", title="spheres, prep 0.2 (blue) and TMD18 (black)")
    b2.set_ylabel("εv [%] (dashed; compression +)")
    fig.tight_layout()
    fig.savefig(path, dpi=130)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("campaign", type=Path)
    ap.add_argument("--records", type=Path, required=True)
    ap.add_argument("--save", type=Path, default=None, help="folder of the committed copy and the outputs")
    a = ap.parse_args(argv)
    got = from_runs(a.campaign)
    if got is not None and a.save:
        a.save.mkdir(parents=True, exist_ok=True)
        keep = ["case_id", "label", "test", "seed", "preparation", "normal_stress", "phi_peak_deg", "psi_max_deg",
                "e0", "elapsed"]
        got[0][[c for c in keep if c in got[0]]].to_csv(a.save / "summaries.csv", index=False, float_format="%.6g")
        got[1].astype({k: np.float32 for k in ("eps1", "epsv", "ratio", "e")}).to_parquet(
            a.save / "cell_curves.parquet", index=False, compression="zstd")
    if got is None:
        got = (pd.read_csv(a.save / "summaries.csv"), pd.read_parquet(a.save / "cell_curves.parquet"))
    model, sand = model_rows(*got), record_rows(a.records)
    off = offset(model, sand)
    prep = by_preparation(model)
    pd.set_option("display.width", 200)
    print(prep.round(3).to_string(index=False))
    print(sand[["name", "sigma3_kPa", "e0", "phi_peak_deg", "eps1_peak", "psi_max_deg", "eps1_psi", "rate_peak",
                "psi_peak_deg", "phi_f_deg", "phi_end_deg", "e_end", "dilatancy_end"]].round(3).to_string(index=False))
    for o in (off, offset(model, sand, "psi_peak_deg")):
        print({k: (round(float(v), 3) if isinstance(v, (float, np.floating)) else v) for k, v in o.items()})
    if a.save:
        pd.concat([model, sand], ignore_index=True).to_csv(a.save / "state_line.csv", index=False, float_format="%.5g")
        figure(model, sand, got[1], got[0], a.records, a.save / "state_line.png")


if __name__ == "__main__":
    main()
