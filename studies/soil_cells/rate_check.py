"""Does the triaxial cell's result depend on its strain rate? Paired by seed against the slowest rate
(each seed is the same specimen at every rate: the packing and consolidation do not depend on it).

    PYTHONPATH=src python studies/soil_cells/rate_check.py studies/soil_cells/kfs_rate.toml --save docs/soils/kfs_rate

Reads the campaign's finished runs (or, without them, the committed summaries.csv in --save) and
prints per rate: the inertial number at most (seed range), each run's own φ_peak, ψ_max and angle at
the end as seed means, and their differences from the slowest rate, seed by seed, as a mean with its
95 % t interval and a verdict against the calibration's tolerances (1.5° for φ, 2° for ψ: within when
the whole interval lies inside, outside when wholly beyond, else undecided), with the wall time per run.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

from interphase.analysis.ensemble import t_interval
from interphase.campaign.calibrate import TOLERANCES, verdict

from interphase.report.cell_tables import cell_runs as from_runs

KEEP = ["case_id", "seed", "strain_rate", "phi_peak_deg", "eps1_peak", "psi_max_deg", "phi_end_deg",
        "inertial_number_max", "sigma3_departure_max", "elapsed"]
ANGLES = {"phi_peak_deg": ("φ_peak", TOLERANCES["phi_peak_deg"]), "psi_max_deg": ("ψ_max", TOLERANCES["psi_max_deg"]),
          "phi_end_deg": ("φ at the end", TOLERANCES["phi_cs_deg"])}


def table(summ: pd.DataFrame) -> str:
    slow = summ["strain_rate"].min()
    base = summ[summ["strain_rate"] == slow].set_index("seed")
    head = "| rate [1/s] | seeds | I at most | " + " | ".join(
        f"{n} [°] | Δ{n} [°] | verdict" for n, _ in ANGLES.values()) + " | wall per run [s] |"
    lines = [head, "|" + "---|" * (4 + 3 * len(ANGLES))]
    for rate, g in summ.groupby("strain_rate"):
        g = g.set_index("seed")
        cells = []
        for col, (_, tol) in ANGLES.items():
            cells.append(f"{g[col].mean():.2f}")
            if rate == slow:
                cells += ["–", "–"]
                continue
            d = (g[col] - base[col]).dropna()
            lo, hi = t_interval(d.to_numpy())
            cells += [f"{d.mean():+.2f} ({lo:+.2f}, {hi:+.2f})", verdict(0.0, lo, hi, tol)]
        i = g["inertial_number_max"]
        lines.append(f"| {rate:g} | {len(g)} | {i.min():.1e}–{i.max():.1e} | " + " | ".join(cells)
                     + f" | {g['elapsed'].mean():.0f} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("campaign", type=Path)
    ap.add_argument("--save", type=Path, default=None, help="folder of the committed summaries.csv")
    a = ap.parse_args()
    got = from_runs(a.campaign)
    if got is not None:
        summ = got[0][KEEP].sort_values(["strain_rate", "seed"])
        if a.save:
            a.save.mkdir(parents=True, exist_ok=True)
            summ.to_csv(a.save / "summaries.csv", index=False)
    elif a.save and (a.save / "summaries.csv").exists():
        summ = pd.read_csv(a.save / "summaries.csv", dtype={"case_id": str})
    else:
        sys.exit(f"{a.campaign}: no finished runs here and no --save copy")
    print(table(summ))


if __name__ == "__main__":
    main()
