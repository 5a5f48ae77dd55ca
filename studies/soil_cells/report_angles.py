"""φ_peak and ψ_max against σ3′, model against laboratory, for the records of several `campaign element
… --record … --report DIR` reports together (their verification.csv; a record in two: the later
one), drawn as one report draws its own (report.cell_figures.angles_figure).

    PYTHONPATH=src python studies/soil_cells/report_angles.py OUT.png DIR [DIR …] [--skip RECORD …]

docs/soils/karlsruhe-fine-sand/angles_held_out.png: the 3D card's 14 held-out records,
`studies/soil_cells/report_angles.py … void_ratio_scale void_ratio_scale_rest void_ratio_scale_rest_b --skip TMD17`.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from interphase.report.cell_figures import angles_figure
from interphase.report.cell_tables import read_verification


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("reports", nargs="+", type=Path)
    ap.add_argument("--skip", action="append", default=[], help="a record to leave out (its name, e.g. TMD17)")
    a = ap.parse_args(argv)
    rows = read_verification(a.reports)
    rows = rows[~rows["record"].isin(a.skip)]
    for p in angles_figure(rows.to_dict("records"), a.out):
        print(p)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
