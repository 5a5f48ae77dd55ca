"""Would the cross-check decide at a few seeds if both engines sheared the same specimen?

    python bench/crosscheck_same_start.py CAMPAIGN.toml --output runs/xc-platen [LABEL_PART] [--out DIR]

For every finished LIGGGHTS interface run of the cross-check output whose label contains LABEL_PART
(default: the 45° saw-tooth), YADE is run from LIGGGHTS' consolidated specimen: the grains of its
first contact snapshot (the start of the shear) and its platen height there replace the YADE input's
lattice and platen (params.json is data: engines/yade.py), then YADE consolidates for its usual first
stretch at the same servo and shears as usual. Printed: per seed, θr mean over the loaded snapshots,
critical-state ratio and mean overlap in both engines, and the paired difference with its t interval
and the correlation of the pairs. A measurement, not a feature: the cross-check itself still starts
each engine from its own consolidation.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from interphase.campaign.plan import plan
from interphase.campaign.schema import load_campaign
from interphase.campaign.store import CampaignStore
from interphase.campaign.runner import summarise
from interphase.engines.yade import Yade

METRICS = ("theta_r_surface_mean_deg", "residual_stress_ratio", "overlap_mean_d50", "peak_stress_ratio")


def start_state(folder: Path) -> tuple[pd.DataFrame, float]:
    """(grains x, z, radius at the first snapshot, platen height at the start of shear) of a run."""
    p = pd.read_parquet(folder / "particles.parquet", columns=["snapshot", "id", "x", "z", "radius"])
    first = p[p["snapshot"] == p["snapshot"].min()].sort_values("id")
    h = pd.read_parquet(folder / "history.parquet", columns=["shear_disp", "platen_z"])
    return first, float(h["platen_z"].iloc[0])


def yade_from(case: Case, grains: pd.DataFrame, platen_z: float, folder: Path) -> dict:
    eng = Yade()
    folder.mkdir(parents=True, exist_ok=True)
    eng.write_input(case, folder)
    params = json.loads((folder / "params.json").read_text())
    params["grains"] = {"x": grains["x"].tolist(), "z": grains["z"].tolist(), "r": grains["radius"].tolist()}
    dz = platen_z - params["platen_z"]
    for wall in params["walls"]:
        if wall["name"] == "platen":
            for tri in wall["triangles"]:
                for k in (2, 5, 8):
                    tri[k] += dz
    params["platen_z"] = platen_z
    (folder / "params.json").write_text(json.dumps(params))
    eng.execute(folder)
    row, _ = summarise(case, eng.read_results(folder))
    return row


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("campaign")
    ap.add_argument("--output", required=True, help="the cross-check's output folder")
    ap.add_argument("label", nargs="?", default="sawtooth-rt1")
    ap.add_argument("--out", default="bench/out/same_start")
    a = ap.parse_args()
    cases = {p.case_id: p.case for p in plan(load_campaign(a.campaign, output=a.output))}
    with CampaignStore(a.output) as st:
        s = st.summaries()
    lig = s[(s["engine"] == "liggghts") & s["label"].str.contains(a.label) & (s["test"] == "interface")]
    rows = []
    for r in lig.sort_values("seed").itertuples():
        folder = Path(a.output) / r.case_id
        case = cases[r.case_id]
        grains, pz = start_state(folder)
        y = yade_from(case, grains, pz, Path(a.out) / r.case_id)
        rows.append({"seed": r.seed, **{f"L_{m}": getattr(r, m) for m in METRICS}, **{f"Y_{m}": y.get(m) for m in METRICS}})
        print(f"seed {r.seed}: " + ", ".join(f"{m} L {getattr(r, m):.4g} Y {y.get(m):.4g}" for m in METRICS), flush=True)
    df = pd.DataFrame(rows)
    print(f"\n{len(df)} seeds of {a.label}, YADE from LIGGGHTS' consolidated specimen")
    for m in METRICS:
        d = (df[f"Y_{m}"] - df[f"L_{m}"]).astype(float)
        lo, hi = stats.t.interval(0.95, len(d) - 1, d.mean(), d.std(ddof=1) / np.sqrt(len(d)))
        corr = np.corrcoef(df[f"L_{m}"].astype(float), df[f"Y_{m}"].astype(float))[0, 1]
        print(f"| {m} | {d.mean():+.4g} [{lo:+.4g}, {hi:+.4g}] | paired sd {d.std(ddof=1):.3g} | corr {corr:+.2f} |")


if __name__ == "__main__":
    sys.exit(main())
