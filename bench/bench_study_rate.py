"""Cases per hour of a campaign as it actually ran: read from its index (every finished case's start,
end and engine time), not from a timed run of its own — the study campaign is hours of engine time.

    .venv/bin/python bench/bench_study_rate.py [campaigns/study.toml] [--output DIR]

Prints, per stretch of continuous running (a gap of more than 15 minutes between one case's end and
the next case's start splits them): cases finished, wall time, cases per hour, and the engine time
per case (median, 10–90 %) per kind of case (interface / box, gradation). The load of the machine
while it ran is not in the index: say it beside the numbers (BENCHMARKS.md).
"""

from __future__ import annotations

import argparse
import datetime as dt
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]

from interphase.campaign.run import campaign_status
from interphase.campaign.store import CampaignStore

GAP = 15 * 60.0     # [s] a pause longer than this starts a new stretch


def stretches(done: pd.DataFrame) -> pd.DataFrame:
    """One row per stretch of continuous running: start, end, cases, cases per hour."""
    d = done.sort_values("started")
    end_so_far = d["finished"].cummax().shift()
    new = (d["started"] - end_so_far > GAP) | end_so_far.isna()
    d = d.assign(stretch=new.cumsum())
    g = d.groupby("stretch")
    out = pd.DataFrame({"start": g["started"].min(), "end": g["finished"].max(), "cases": g.size(),
                        "engine_h": g["elapsed"].sum() / 3600})
    out["wall_h"] = (out["end"] - out["start"]) / 3600
    out["cases_per_h"] = out["cases"] / out["wall_h"]
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("campaign", nargs="?", default=str(ROOT / "campaigns" / "study.toml"))
    ap.add_argument("--output", default=None)
    args = ap.parse_args(argv)
    campaign, planned, status = campaign_status(args.campaign, output=args.output)
    with CampaignStore(campaign.output) as store:
        summ = store.summaries()
    ids = set(status.loc[status["status"] == "done", "case_id"])
    done = summ[summ["case_id"].isin(ids)].copy()
    for c in ("started", "finished", "elapsed"):
        done[c] = pd.to_numeric(done[c], errors="coerce")
    done = done.dropna(subset=["started", "finished"])
    if done.empty:
        print("no finished case")
        return 1
    when = lambda t: dt.datetime.fromtimestamp(t, dt.timezone.utc).strftime("%Y-%m-%d %H:%M")
    print(f"{campaign.name}: {len(done)} of {len(planned)} cases finished")
    print("stretch (UTC)                         cases   wall [h]   cases/h   engine h / wall h")
    for r in stretches(done).itertuples():
        print(f"{when(r.start)} – {when(r.end)[11:]}            {r.cases:5d}   {r.wall_h:8.2f}   {r.cases_per_h:7.1f}"
              f"   {r.engine_h / r.wall_h:6.2f}")
    print("engine time per case [s]        n   median   10 %   90 %")
    for (test, grad), g in done.groupby(["test", "gradation"]):
        q = np.quantile(g["elapsed"], [0.5, 0.1, 0.9])
        print(f"  {test:<9} {grad:<12} {len(g):8d}   {q[0]:6.0f}  {q[1]:5.0f}  {q[2]:5.0f}")
    left = len(planned) - len(done)
    rate = stretches(done)["cases_per_h"].iloc[-1]
    print(f"left: {left} cases ≈ {left / rate:.1f} h at the last stretch's rate")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
