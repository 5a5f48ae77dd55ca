"""A runs folder as tables (`campaign pack RUNS -o DIR`): what a calibration or generated campaign
needs to go on on another machine without its dumps (`campaign calibrate --restore DIR`,
campaign.restore.restoring)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from interphase.campaign import store as st
from interphase.campaign.element import CELL_SERIES, SHEAR_SERIES
from interphase.campaign.restore import CURVES
from interphase.errors import InputError

#: the series columns kept: what the element and cell tests read back (campaign.element.run_cases)
SERIES = (*SHEAR_SERIES, *CELL_SERIES)


def pack_runs(runs: str | Path, out: str | Path) -> list[tuple[Path, int]]:
    """Every campaign store under `runs` as tables under `out`, at the store's own relative path:
    summaries.csv (`CampaignStore.summaries`, its finished runs) and curves.parquet (case_id and the
    series columns the element and cell tests read, every recorded row as recorded: a calibration
    resumed from its pack must read the same numbers, or its next iteration's samples, and with them
    the case ids, would move). What a calibration or generated campaign needs to go on on another
    machine without its dumps. Returns [(table, rows)]."""
    runs, out = Path(runs), Path(out)
    if not runs.is_dir():
        raise InputError(f"no runs folder {str(runs)!r}", where="campaign pack", fix="give the runs folder a "
                         "campaign or calibration wrote (its [campaign] output or --runs)")
    written = []
    for index in sorted(runs.rglob(st.INDEX)):
        with st.CampaignStore(index.parent) as store:
            summ = store.summaries()
            frames = []
            for cid in summ["case_id"].astype(str) if len(summ) else []:
                path = store.case_folder(cid) / "series.parquet"
                try:
                    series = pd.read_parquet(path)
                except (OSError, ValueError):
                    continue            # no readable series: left out of the curves, so a restore runs it again
                frames.append(series[[c for c in SERIES if c in series.columns]].assign(case_id=cid))
        if not len(summ):
            continue
        dest = out / index.parent.relative_to(runs)
        dest.mkdir(parents=True, exist_ok=True)
        summ.to_csv(dest / "summaries.csv", index=False)
        if frames:
            curves = pd.concat(frames, ignore_index=True)
            curves["case_id"] = curves["case_id"].astype("category")
            curves.to_parquet(dest / CURVES, index=False, compression="zstd")
        written.append((dest / "summaries.csv", len(summ)))
    if not written:
        raise InputError(f"{runs}: no finished run in any campaign folder under it", where="campaign pack",
                         fix="give the runs folder a campaign or calibration wrote")
    return written
