"""What `campaign validate` writes: the table of predicted against measured δ per laboratory row,
the skill table (criterion and both baselines), and Fig. 6.10(b–d) style figures: one panel per
soil, δ predicted (criterion interval as the vertical bar; the DEM's seed interval when simulated)
against δ measured (its reading error as the horizontal bar), the 1:1 line and the ±4° band."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from interphase.report.figures import plt, save


def validation_figure(df: pd.DataFrame, folder: Path, stem: str = "validation") -> list[Path]:
    soils = list(dict.fromkeys(df["soil"]))
    fig, axes = plt.subplots(1, len(soils), figsize=(4.8 * len(soils), 4.6), squeeze=False)
    cols = [c for c in ("delta_measured_deg", "delta_predicted_deg", "delta_dem_deg") if c in df]
    vals = pd.concat([df[c] for c in cols]).dropna()
    lo, hi = (float(vals.min()) - 3, float(vals.max()) + 3) if len(vals) else (0.0, 45.0)
    for ax, soil in zip(axes[0], soils):
        g = df[df["soil"] == soil]
        ax.fill_between([lo, hi], [lo - 4, hi - 4], [lo + 4, hi + 4], color="0.9", label="±4° (the study's test)")
        ax.plot([lo, hi], [lo, hi], color="0.4", lw=1, label="1:1")
        x = g["delta_measured_deg"].to_numpy(float)
        xerr = g["reading_error_deg"].to_numpy(float)
        y = g["delta_predicted_deg"].to_numpy(float)
        yerr = np.vstack([y - g["delta_lo_deg"].to_numpy(float), g["delta_hi_deg"].to_numpy(float) - y])
        ok = np.isfinite(y)
        ax.errorbar(x[ok], y[ok], xerr=xerr[ok], yerr=np.where(np.isfinite(yerr[:, ok]), yerr[:, ok], 0), fmt="o",
                    ms=5, color="C0", mec="k", mew=0.4, elinewidth=0.8, capsize=2, label="criterion (fit interval)")
        if "delta_dem_deg" in g and g["delta_dem_deg"].notna().any():
            d = g["delta_dem_deg"].to_numpy(float)
            derr = np.vstack([d - g["delta_dem_lo_deg"].to_numpy(float), g["delta_dem_hi_deg"].to_numpy(float) - d])
            okd = np.isfinite(d)
            ax.errorbar(x[okd], d[okd], xerr=xerr[okd], yerr=np.where(np.isfinite(derr[:, okd]), derr[:, okd], 0),
                        fmt="s", ms=5, color="C3", mec="k", mew=0.4, elinewidth=0.8, capsize=2,
                        label="DEM, calibrated soil (seed interval)")
        n = int(ok.sum())
        ax.set(xlim=(lo, hi), ylim=(lo, hi), xlabel="δ measured [°]", ylabel="δ predicted [°]",
               title=f"{soil} ({n} of {len(g)} tests)")
        ax.set_aspect("equal")
        ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    return save(fig, folder, stem)


def markdown(df: pd.DataFrame, cols: dict[str, str]) -> str:
    """A Markdown table of `df`'s columns `cols` (column → heading), numbers to 2 decimals."""
    head = "| " + " | ".join(cols.values()) + " |\n|" + "---|" * len(cols) + "\n"

    def cell(v):
        if isinstance(v, (float, np.floating)):
            return "" if not np.isfinite(v) else f"{v:.2f}"
        return str(v).replace("|", "/")

    return head + "".join("| " + " | ".join(cell(r[c]) for c in cols) + " |\n" for _, r in df.iterrows())
