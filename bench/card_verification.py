"""A calibrated card against laboratory records: the laboratory's test on the model at each record's
σ3′ (the nearest 50 kPa) and relative density Dr0, the verdicts, and the figures (docs/soils.md).

    PYTHONPATH=src python bench/card_verification.py soils/karlsruhe-fine-sand.toml \
        lab/soils/karlsruhe-fine-sand/drained-triaxial/TMD*.dat --runs runs/calibrate/karlsruhe-fine-sand/final \
        --seeds 2 --save docs/soils/karlsruhe-fine-sand

Runs what is not finished (campaign.cell.run_cell, resumable: the calibration's own final runs are
reused when --runs is its final folder), then prints one Markdown row per record: σ3′, Dr0 of the
record and of the model's specimens, φ_peak and ψ_max of both with the model's 95 % interval and the
verdict (within: the interval inside ±1.5° for φ, ±2° for ψ; outside: wholly beyond; else
undecided). --save writes verification.csv, curves.png/.pdf and angles.png/.pdf there.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd

from interphase.analysis.triaxial import shear_state
from interphase.campaign.calibrate import verdict
from interphase.campaign.calibrate_cell import nominal
from interphase.campaign.cell import cell_campaign_file, run_cell
from interphase.campaign.element import CELL_SERIES, run_cases
from interphase.io.lab_triaxial import read_triaxial
from interphase.soil import load_card

TOL = {"phi_peak_deg": 1.5, "psi_max_deg": 2.0}


def verify(card, path: Path, e_lim, seeds, runs: Path) -> tuple[dict, tuple]:
    rec = read_triaxial(path)
    t = rec.table
    lab = shear_state(t.eps1, t.epsv, t.ratio, t.e)
    dr = (e_lim[1] - rec.e0) / (e_lim[1] - e_lim[0])
    sigma, asked = nominal(rec.sigma3_start), min(1.0, max(0.0, dr))
    (r,) = run_cell(card, [sigma], seeds, relative_density=asked, output=runs)
    planned, series, _ = run_cases(cell_campaign_file(runs, card, card.cell["test"], asked), columns=CELL_SERIES)
    model = [(s["eps1"].to_numpy(), s["epsv"].to_numpy(), s["ratio"].to_numpy())
             for p in planned if p.case.normal_stress == sigma and (s := series.get(p.case_id)) is not None]
    row = {"record": path.stem, "confining_stress": sigma, "relative_density": dr,
           "model_relative_density": r.relative_density, "lab_phi": lab.phi_peak_deg, "lab_psi": lab.psi_max_deg,
           "lab_eps1_peak": lab.eps1_peak, **{k: v for k, v in r.to_dict().items() if k.startswith(("phi_", "psi_"))},
           "eps1_at_peak": r.eps1_at_peak, "n_seeds": r.n_seeds, "preparation": r.preparation}
    for q, lq in (("phi_peak_deg", "lab_phi"), ("psi_max_deg", "lab_psi")):
        row[q + "_verdict"] = verdict(row[lq], row[q + "_lo"], row[q + "_hi"], TOL[q])
    title = f"{path.stem}: {sigma / 1e3:g} kPa, Dr {dr:.2f}"
    return row, (title, t, model)


def markdown(df: pd.DataFrame) -> str:
    lines = ["| record | σ3′ [kPa] | Dr0 lab / model | φ_peak lab [°] | φ_peak model [°] | verdict | ψ_max lab [°] | "
             "ψ_max model [°] | verdict | ε1 at peak lab / model [%] |", "|" + "---|" * 10]
    for _, r in df.iterrows():
        lines.append(
            f"| {r['record']} | {r['confining_stress'] / 1e3:g} | {r['relative_density']:.2f} / "
            f"{r['model_relative_density']:.2f} | {r['lab_phi']:.1f} | {r['phi_peak_deg']:.1f} "
            f"({r['phi_peak_deg_lo']:.1f}–{r['phi_peak_deg_hi']:.1f}) | {r['phi_peak_deg_verdict']} | "
            f"{r['lab_psi']:.1f} | {r['psi_max_deg']:.1f} ({r['psi_max_deg_lo']:.1f}–{r['psi_max_deg_hi']:.1f}) | "
            f"{r['psi_max_deg_verdict']} | {100 * r['lab_eps1_peak']:.1f} / {100 * r['eps1_at_peak']:.1f} |")
    return "\n".join(lines)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("card", type=Path)
    ap.add_argument("records", type=Path, nargs="+")
    ap.add_argument("--runs", type=Path, required=True)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--save", type=Path, default=None)
    a = ap.parse_args(argv)
    card = load_card(a.card)
    target = card.extra["target"]
    e_lim = (float(target["e_min"]), float(target["e_max"]))
    rows, pairs = zip(*(verify(card, p, e_lim, list(range(1, a.seeds + 1)), a.runs) for p in a.records))
    df = pd.DataFrame(rows)
    print(markdown(df))
    if a.save:
        from interphase.report.cell_figures import angles_figure, curves_figure

        a.save.mkdir(parents=True, exist_ok=True)
        df.to_csv(a.save / "verification.csv", index=False, float_format="%.5g")
        curves_figure(list(pairs), a.save / "curves")
        angles_figure(rows, a.save / "angles")


if __name__ == "__main__":
    main()
