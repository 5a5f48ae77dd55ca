"""Model against laboratory for the triaxial/biaxial cell (docs/soils.md): per record, σ1′/σ3′ and εv
against ε1, the laboratory's curve against the model's seed-mean curve and the band its seeds span;
and φ_peak, ψ_max against confining stress, one marker per density, laboratory against model with
its 95 % interval. Files: PNG (200 dpi) and PDF."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def curves_figure(pairs, path: Path) -> list[Path]:
    """`pairs` = [(title, record table (eps1, epsv, ratio) or None, [model runs (eps1, epsv, ratio)]),
    ...]: one column per pair, σ1′/σ3′ on top, εv below (compression positive, so dilation goes down)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from interphase.analysis.cell_ensemble import mean_curves

    n = len(pairs)
    cols = min(5, n)
    groups = -(-n // cols)
    fig, ax = plt.subplots(2 * groups, cols, figsize=(2.6 * cols + 0.6, 4.4 * groups), squeeze=False)
    for j, (title, lab, runs) in enumerate(pairs):
        top, bottom = ax[2 * (j // cols), j % cols], ax[2 * (j // cols) + 1, j % cols]
        if lab is not None:
            top.plot(100 * lab["eps1"], lab["ratio"], color="k", lw=1.2, label="laboratory")
            bottom.plot(100 * lab["eps1"], 100 * lab["epsv"], color="k", lw=1.2)
        if runs:
            grid, R, V = mean_curves(runs)
            for a, y in ((top, R), (bottom, 100 * V)):
                a.fill_between(100 * grid, y.min(axis=0), y.max(axis=0), color="C0", alpha=0.25, lw=0)
                a.plot(100 * grid, y.mean(axis=0), color="C0", lw=1.2, label=f"model ({len(runs)} seeds)")
        top.set_title(title, fontsize=8)
        bottom.set_xlabel("ε1 [%]")
        if j % cols == 0:
            top.set_ylabel("σ1′/σ3′")
            bottom.set_ylabel("εv [%]")
        if j == 0:
            top.legend(fontsize=7, frameon=False)
    for k in range(n, groups * cols):
        ax[2 * (k // cols), k % cols].axis("off")
        ax[2 * (k // cols) + 1, k % cols].axis("off")
    fig.tight_layout()
    return _save(fig, path)


def angles_figure(rows, path: Path) -> list[Path]:
    """`rows` = dicts with confining_stress [Pa], relative_density (the laboratory's), lab_phi, lab_psi
    and the model's phi_peak_deg, psi_max_deg with _lo/_hi: φ_peak and ψ_max against σ3′."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dens = sorted({round(r["relative_density"], 1) for r in rows})
    lines = -(-2 * len(dens) // 4)                # the legend's rows, four entries a row
    fig, ax = plt.subplots(1, 2, figsize=(8, 3.4 + 0.15 * lines))
    for k, (q, lab) in enumerate((("phi_peak_deg", "lab_phi"), ("psi_max_deg", "lab_psi"))):
        for i, d in enumerate(dens):
            sel = [r for r in rows if round(r["relative_density"], 1) == d]
            s = np.array([r["confining_stress"] / 1e3 for r in sel])
            ax[k].plot(s, [r[lab] for r in sel], "o", mfc="none", color=f"C{i}", label=f"laboratory, Dr ≈ {d:.1f}")
            m = np.array([r.get(q, np.nan) for r in sel], float)
            lo = np.array([r.get(q + "_lo", np.nan) for r in sel], float)
            hi = np.array([r.get(q + "_hi", np.nan) for r in sel], float)
            ax[k].errorbar(s * 1.03, m, yerr=[m - lo, hi - m], fmt="s", color=f"C{i}", ms=4, capsize=2,
                           label=f"model, Dr ≈ {d:.1f}")
        ax[k].set_xscale("log")
        ticks = sorted({round(r["confining_stress"] / 1e3) for r in rows})
        ax[k].set_xticks(ticks, [f"{t:g}" for t in ticks])
        ax[k].minorticks_off()
        ax[k].set_xlabel("σ3′ [kPa]")
        ax[k].set_ylabel("φ_peak [°]" if k == 0 else "ψ_max [°]")
    # below the panels: on a card's full programme (four densities, five stresses) no corner is free
    handles, labels = ax[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(4, len(dens)), fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0.02 + 0.05 * lines, 1, 1))
    return _save(fig, path)


def _save(fig, path: Path) -> list[Path]:
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    out = [path.with_suffix(".png"), path.with_suffix(".pdf")]
    fig.savefig(out[0], dpi=200)
    fig.savefig(out[1])
    plt.close(fig)
    return out
