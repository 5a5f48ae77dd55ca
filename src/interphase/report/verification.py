"""The model-against-laboratory report of element tests (`campaign element … --record … --report DIR`,
campaign/cell_records.py makes the rows): verification.csv (one row per test), verification.md (the
same as the Markdown table docs/soils.md shows), curves.png/.pdf (σ1′/σ3′ and εv against ε1: the
record against the model's seed band and seed-mean curve) and, with records, angles.png/.pdf
(φ_peak and ψ_max against σ3′ by density, laboratory against model with its interval)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd


def markdown(df: pd.DataFrame) -> str:
    """The verification table as docs/soils.md shows it."""
    def iv(r, q):
        lo, hi = r[q + "_lo"], r[q + "_hi"]
        return f"{r[q]:.1f}" + (f" ({lo:.1f}–{hi:.1f})" if pd.notna(lo) and pd.notna(hi) else "")

    lines = ["| record | σ3′ [kPa] | Dr0 lab / model | φ_peak lab [°] | φ_peak model [°] | verdict | ψ_max lab [°] | "
             "ψ_max model [°] | verdict | ε1 at peak lab / model [%] |", "|" + "---|" * 10]
    for _, r in df.iterrows():
        lines.append(
            f"| {r['record']} | {r['confining_stress'] / 1e3:g} | {r['relative_density']:.2f} / "
            f"{r['model_relative_density']:.2f} | {r['lab_phi']:.1f} | {iv(r, 'phi_peak_deg')} | "
            f"{r['phi_peak_deg_verdict']} | {r['lab_psi']:.1f} | {iv(r, 'psi_max_deg')} | {r['psi_max_deg_verdict']} | "
            f"{100 * r['lab_eps1_peak']:.1f} / {100 * r['eps1_at_peak']:.1f} |")
    return "\n".join(lines)


def write_report(folder: Path, rows, pairs) -> list[Path]:
    """verification.csv/.md, curves and (with records) angles in `folder`; the paths written.
    `pairs` = [(title, record table or None, model runs), …]."""
    from interphase.report.cell_figures import angles_figure, curves_figure

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    if rows:
        df = pd.DataFrame(rows)
        df.to_csv(folder / "verification.csv", index=False, float_format="%.5g")
        (folder / "verification.md").write_text(markdown(df) + "\n")
        out += [folder / "verification.csv", folder / "verification.md"]
        if any(r.get("lab_phi") is not None for r in rows):
            out += angles_figure(rows, folder / "angles")
    out += curves_figure(list(pairs), folder / "curves")
    return out
