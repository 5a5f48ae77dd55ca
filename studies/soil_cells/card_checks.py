"""A calibrated card's checks against its laboratory records, as the Markdown table docs/soils.md
prints for each card: the fitted record ([[achieved]]) and every held-out one ([[verification]]).

    PYTHONPATH=src python studies/soil_cells/card_checks.py soils/karlsruhe-fine-sand.toml

Per record: σ3′, Dr0 of the record / of the model's specimens, φ_peak and ψ_max of the record / the
model's seed mean (95 % interval) with the verdict at the card's tolerance, the model's ε1 at peak and
its angle at the end of the cell (φ_cs). Angles in degrees, strains in %.
"""

from __future__ import annotations

import argparse
import tomllib
from pathlib import Path

from interphase.report.cell_tables import card_markdown


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("card", type=Path)
    a = ap.parse_args(argv)
    print(card_markdown(tomllib.loads(a.card.read_text())))


if __name__ == "__main__":
    main()
