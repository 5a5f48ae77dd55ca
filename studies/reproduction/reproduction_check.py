"""Does a campaign run here reproduce a committed summaries table? (issue 15's done-when)

    python studies/reproduction/reproduction_check.py campaigns/study.toml docs/reproduction/summaries.csv

For every run finished here (not restored) whose case id is a row of the table: the largest
relative difference of each numeric summary column, and the runs that differ beyond the table's own
rounding (6 significant digits). Prints a Markdown table; exit 0 whatever it finds (a measurement).
"""

from __future__ import annotations

import json
import sys

import numpy as np
import pandas as pd

from interphase.campaign.restore import is_restored
from interphase.campaign.results import open_campaign

ROUNDING = 1e-5      # the table's float_format %.6g: relative error up to 5e-6


def main(campaign: str, table: str) -> None:
    _, store, here = open_campaign(campaign)
    try:
        ran = [cid for cid in here["case_id"].astype(str)
               if not is_restored(json.loads((store.case_folder(cid) / "case.json").read_text()))]
    finally:
        store.close()
    old = pd.read_csv(table, dtype={"case_id": str}).set_index("case_id")
    new = here.set_index(here["case_id"].astype(str))
    ids = sorted(set(ran) & set(old.index))
    cols = [c for c in old.columns if c in new.columns and c not in ("elapsed", "efficiency")
            and pd.api.types.is_numeric_dtype(old[c])]
    a = old.loc[ids, cols].astype(float)
    b = new.loc[ids, cols].apply(pd.to_numeric, errors="coerce").astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = ((b - a).abs() / a.abs().where(a.abs() > 0, 1.0)).where(~(a.isna() & b.isna()), 0.0)
    worst = rel.max().sort_values(ascending=False)
    differ = (rel > ROUNDING).any(axis=1)
    print(f"{len(ids)} runs finished here that the table has ({len(ran)} finished here, {len(old)} rows); "
          f"{int(differ.sum())} differ beyond the table's rounding in some column")
    print("\n| column | largest relative difference |\n|---|---|")
    for c, v in worst.head(8).items():
        print(f"| {c} | {v:.2e} |")
    if differ.any():
        print("\nruns that differ:", ", ".join(f"{i} ({old.loc[i, 'label']})" for i in rel.index[differ]))


if __name__ == "__main__":
    main(*sys.argv[1:3])
