"""How a calibration's two-seed φ_peak reads against its seeds' own maxima (docs/soils.md, Karlsruhe
fine sand, "What the fit's φ_peak reads").

    PYTHONPATH=src python bench/calibration_peak_bias.py docs/soils/karlsruhe-fine-sand

From a card's committed calibration tables (no runs folder, no engine): `calibration_samples.csv`
(each sample's φ_peak as the calibration read it: the seed ensemble's leave-one-out peak,
analysis.cell_ensemble) and `calibration_runs.csv` (each run's own maximum of its smoothed curve and
the ε1 where it lies). Per sample: the ensemble value, the mean of the seeds' maxima, their
difference, and the gap between the seeds' peak strains; then the mean, sd and extremes of the
difference and its correlation with the gap. A measurement: exit 0 whatever it finds.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.report.validation import markdown

KEYS = ("friction_pp", "rolling_friction", "preparation")


def table(folder: Path) -> pd.DataFrame:
    samples = pd.read_csv(folder / "calibration_samples.csv")
    runs = pd.read_csv(folder / "calibration_runs.csv")
    for t in (samples, runs):                 # the runs' inputs are written to 6 digits
        for k in KEYS:
            t[k] = t[k].round(4)
    per = runs.groupby(list(KEYS)).agg(runs=("seed", "size"), maxima=("phi_peak_deg", "mean"),
                                       gap_pct=("eps1_peak", lambda e: 100 * (e.max() - e.min()))).reset_index()
    out = samples.drop_duplicates(list(KEYS)).merge(per, on=list(KEYS))
    out["difference"] = out["phi_peak_deg"] - out["maxima"]
    return out[[*KEYS, "runs", "phi_peak_deg", "maxima", "difference", "gap_pct"]]


def main(folder: str) -> None:
    t = table(Path(folder))
    shown = t.assign(**{k: t[k].map("{:.4g}".format) for k in KEYS})      # the grains' values to 4 digits
    print(markdown(shown, {c: c for c in t.columns}))
    d = t["difference"]
    print(f"\n{len(t)} samples: ensemble − mean of maxima {d.mean():+.2f}° (sd {d.std():.2f}°, "
          f"{d.min():+.2f}° to {d.max():+.2f}°); correlation with the peak-strain gap "
          f"{np.corrcoef(d, t['gap_pct'])[0, 1]:+.2f}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "docs/soils/karlsruhe-fine-sand")
