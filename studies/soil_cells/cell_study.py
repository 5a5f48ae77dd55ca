"""Seed ensembles of a campaign of triaxial/biaxial cells (the cell-size study, the pilot of the free
parameters), as Markdown for docs/soils.md and BENCHMARKS.md.

    PYTHONPATH=src python studies/soil_cells/cell_study.py campaigns/soils/cell_size.toml --by n_grains --save docs/soils/cell_size

Reads the campaign's finished runs (or, without them, the committed copy in --save: summaries.csv and
cell_curves.parquet, each run's ε1, εv, R, e every 0.2 % of ε1) and prints, per physical case (the
fields named by --by), the CellResult of its seeds (report.cell_tables, analysis.cell_ensemble: φ_peak, ψ_max, φ at the
end and e0 with 95 % intervals) and the mean wall time per run.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.report.cell_tables import cell_ensembles, cell_markdown, cell_runs


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("campaign", type=Path)
    ap.add_argument("--by", action="append", required=True, help="the field(s) that tell physical cases apart")
    ap.add_argument("--save", type=Path, default=None, help="folder of the committed copy")
    a = ap.parse_args(argv)
    got = cell_runs(a.campaign)
    if got is not None and a.save:
        a.save.mkdir(parents=True, exist_ok=True)
        keep = ["case_id", "label", "physical_id", "test", "seed", *a.by, "normal_stress", "phi_peak_deg", "eps1_peak",
                "psi_max_deg", "phi_end_deg", "e0", "sigma3_departure_max", "inertial_number_max", "coordination_start",
                "elapsed"]
        got[0][[c for c in dict.fromkeys(keep) if c in got[0]]].to_csv(a.save / "summaries.csv", index=False,
                                                                     float_format="%.6g")
        got[1].astype({k: np.float32 for k in ("eps1", "epsv", "ratio", "e")}).to_parquet(
            a.save / "cell_curves.parquet", index=False, compression="zstd")
    if got is None:
        got = (pd.read_csv(a.save / "summaries.csv"), pd.read_parquet(a.save / "cell_curves.parquet"))
    print(cell_markdown(cell_ensembles(*got, a.by), a.by))


if __name__ == "__main__":
    main()
