"""Two density scales of one card against the laboratory, record by record: the misses in φ_peak and
ψ_max of each `campaign element … --record … --report DIR` (its verification.csv), and their summed
misfit Σ (miss_φ / 1.5°)² + (miss_ψ / 2°)², the verdicts' tolerances (campaign.calibrate.TOLERANCES;
docs/soils.md, "A scale that keeps the sand's void-ratio differences").

    PYTHONPATH=src python studies/soil_cells/scale_misfit.py NAME=DIR[,DIR…] NAME=DIR[,DIR…]

Each NAME is one scale; its folders are read together (a record in two folders: the later one). Only
records every scale has are compared. A measurement: exit 0 whatever it finds.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

from interphase.campaign.calibrate import TOLERANCES
from interphase.report.cell_tables import read_verification

TOL = {"phi": TOLERANCES["phi_peak_deg"], "psi": TOLERANCES["psi_max_deg"]}     # [°]


def misses(folders: list[Path]) -> pd.DataFrame:
    v = read_verification(folders)
    return pd.DataFrame({"record": v.record, "stress_kPa": v.confining_stress / 1e3, "dr_lab": v.relative_density,
                         "e0": v.void_ratio, "phi": v.phi_peak_deg - v.lab_phi, "psi": v.psi_max_deg - v.lab_psi,
                         "n": v.n_seeds}).set_index("record")


def main(argv=None) -> int:
    scales = {}
    for arg in argv if argv is not None else sys.argv[1:]:
        name, _, dirs = arg.partition("=")
        scales[name] = misses([Path(d) for d in dirs.split(",")])
    common = sorted(set.intersection(*(set(m.index) for m in scales.values())))
    table = pd.concat({k: m.loc[common, ["e0", "phi", "psi"]] for k, m in scales.items()}, axis=1)
    first = next(iter(scales.values())).loc[common, ["stress_kPa", "dr_lab"]]
    print(pd.concat([first, table], axis=1).sort_values(["dr_lab"]).round(3).to_string())
    print()
    for k, m in scales.items():
        m = m.loc[common]
        cost = ((m.phi / TOL["phi"]) ** 2 + (m.psi / TOL["psi"]) ** 2).sum()
        print(f"{k}: {len(m)} records; φ_peak miss mean {m.phi.mean():+.2f}° sd {m.phi.std():.2f}°, "
              f"ψ_max miss mean {m.psi.mean():+.2f}° sd {m.psi.std():.2f}°; summed misfit {cost:.2f}; "
              f"within tolerance by the point: φ {int((m.phi.abs() <= TOL['phi']).sum())}, "
              f"ψ {int((m.psi.abs() <= TOL['psi']).sum())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
