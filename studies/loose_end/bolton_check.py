"""The Karlsruhe sand's own records and its 3D card against Bolton's (1986) triaxial correlation.

    python studies/loose_end/bolton_check.py [--check] [--figure]

For each of the sand's 15 drained triaxial records (lab/soils/karlsruhe-fine-sand/drained-triaxial/,
read as `campaign lab-record` reads them): its Dr (the sand's index limits, the card's [target]), its cell
pressure, φ_peak and ψ_max; Bolton's φ_max and ψ_max there (interphase.analysis.bolton.triaxial, φ_crit
the card's 33.1°); and the card's own element test on the record (the card's [[verification]] blocks:
3 seeds each, with their 95 % intervals; TMD17, the fitted record, has none). Writes
results/bolton_records.csv and results/bolton_summary.csv (bias and sd of lab − Bolton and model − Bolton
over the records); --figure draws results/bolton_records.png; --check fails if the committed tables differ
from their re-derivation.
"""

from __future__ import annotations

import argparse
import sys
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd

import interphase as ip
from interphase.analysis.bolton import triaxial
from interphase.campaign.results import settle_tables

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
CARD = ROOT / "soils" / "karlsruhe-fine-sand.toml"
RECORDS = ROOT / "lab" / "soils" / "karlsruhe-fine-sand" / "drained-triaxial"


def records_table() -> pd.DataFrame:
    card = tomllib.loads(CARD.read_text())
    target = card["target"]
    e_min, e_max, phi_c = target["e_min"], target["e_max"], target["phi_cs_deg"]
    model = {v["record"]: v["measured"] for v in card.get("verification", [])}
    rows = []
    for path in sorted(RECORDS.glob("TMD*.dat")):
        lab = ip.lab_record(path)
        dr = (e_max - lab["e0"]) / (e_max - e_min)
        sigma3 = round(lab["sigma3_start"] / 50e3) * 50e3      # the programme's nominal cell pressures (50 kPa steps)
        b = triaxial(dr, sigma3, phi_c)
        m = model.get(path.name, {})
        rows.append({"record": path.name, "cell_pressure": sigma3, "relative_density": round(dr, 4),
                     "index_bolton": round(b.index, 4), "mean_stress_bolton": round(b.mean_stress, 1),
                     "phi_peak_lab": round(lab["phi_peak_deg"], 3), "phi_peak_bolton": round(b.phi_peak_deg, 3),
                     "psi_max_lab": round(lab["psi_max_deg"], 3), "psi_max_bolton": round(b.psi_max_deg, 3),
                     **{f"{q}_model{s}": m.get(f"{q}_deg{s}", np.nan) for q in ("phi_peak", "psi_max")
                        for s in ("", "_lo", "_hi")}})
    return pd.DataFrame(rows)


def summary(t: pd.DataFrame) -> pd.DataFrame:
    out = []
    for q in ("phi_peak", "psi_max"):
        for who in ("lab", "model"):
            d = (t[f"{q}_{who}"] - t[f"{q}_bolton"]).dropna()
            out.append({"quantity": q, "against_bolton": who, "n": len(d), "bias_deg": round(d.mean(), 3),
                        "sd_deg": round(d.std(ddof=1), 3), "max_abs_deg": round(d.abs().max(), 3)})
    return pd.DataFrame(out)


def figure(t: pd.DataFrame, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    phi_c = tomllib.loads(CARD.read_text())["target"]["phi_cs_deg"]
    ir = np.linspace(0, 4, 50)
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.8))
    for ax, q, line, ylab in ((axes[0], "phi_peak", 3 * ir, "φ_peak − φ_c [°]"),
                              (axes[1], "psi_max", np.degrees(np.arcsin(0.3 * ir / (2 + 0.3 * ir))), "ψ_max [°]")):
        shift = phi_c if q == "phi_peak" else 0.0
        ax.plot(ir, line, "k-", label="Bolton (1986), triaxial")
        ax.plot(t["index_bolton"], t[f"{q}_lab"] - shift, "o", label="the sand's records")
        m = t.dropna(subset=[f"{q}_model"])
        ax.errorbar(m["index_bolton"], m[f"{q}_model"] - shift,
                    yerr=[m[f"{q}_model"] - m[f"{q}_model_lo"], m[f"{q}_model_hi"] - m[f"{q}_model"]],
                    fmt="s", ms=4, capsize=2, label="3D card, 3 seeds (95 %)")
        ax.set_xlabel("I_R at the record's Dr and p′ at failure")
        ax.set_ylabel(ylab)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=130)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--figure", action="store_true")
    a = ap.parse_args(argv)
    t = records_table()
    s = summary(t)
    res = HERE / "results"
    if a.figure and not a.check:
        res.mkdir(exist_ok=True)
        figure(t, res / "bolton_records.png")
    print(s.to_string(index=False))
    return settle_tables({res / "bolton_records.csv": t, res / "bolton_summary.csv": s}, a.check, HERE)


if __name__ == "__main__":
    sys.exit(main())
