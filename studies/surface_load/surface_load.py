"""Where does the surface's load sit on saw-teeth? Measurements for two of the reproduction's
departures from the study (docs/reproduction.md): Group 3's narrow teeth, and θr running above θa
on steep teeth (Fig. 6.8's upper branch).

    python studies/surface_load/surface_load.py campaigns/study.toml campaigns/checks/narrow_valleys.toml

For every finished interface run on saw-teeth without flats (Groups 1 and 3), from its own dumps, with
the surface's particle contacts (kind 'ps') joined to their grains by snapshot and id:
  d_load      median diameter of the grains touching the surface, weighted by contact normal force
              [D50], over the shear (snapshots after the first)
  deep        share of the surface's normal force carried below half the teeth's height, same snapshots
  grains      grains touching the surface per snapshot
  θr, θr stoss   at the run's peak snapshot: θr of every surface contact (the summary's, without its
              measuring window) and of the contacts on the faces the soil moves against alone
              (normals not leaning toward +x by more than 2°: the lee-share rule of docs/methods.md §5)
Prints one Markdown row per physical case and gradation: seed means with their sd. Runs restored from
a summaries table have no dumps and are skipped. A measurement: exit 0 whatever it finds.
"""

from __future__ import annotations

import sys

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from interphase.analysis.anisotropy import LEE_TILT, resultant_direction
from interphase.campaign.results import open_campaign


def run_row(folder, d50: float, rt: float, peak: int) -> dict | None:
    cp, pp = folder / "contacts.parquet", folder / "particles.parquet"
    if not (cp.exists() and pp.exists()):
        return None
    c = pq.read_table(cp, columns=["snapshot", "kind", "id2", "cz", "fn", "fx", "fz", "nx", "nz"]).to_pandas()
    c = c[(c["kind"] == "ps") & (c["snapshot"] > 0)]
    at = c[c["snapshot"] == peak]
    stoss = at[at["nx"] <= np.sin(LEE_TILT) * np.hypot(at["nx"], at["nz"])]
    theta_r = [float(resultant_direction(t["fx"], t["fz"])["theta_r_deg"].iloc[0]) if len(t) > 1 else np.nan
               for t in (at, stoss)]
    p = pq.read_table(pp, columns=["snapshot", "id", "radius"]).to_pandas()
    c = c.merge(p, left_on=["snapshot", "id2"], right_on=["snapshot", "id"], how="inner")
    if c.empty:
        return None
    d = 2 * c["radius"].to_numpy() / d50
    w = c["fn"].to_numpy()
    order = np.argsort(d)
    cum = np.cumsum(w[order]) / w.sum()
    # the surface's tips are its highest contacts' level: the profile runs from 0 to Rt·D50
    deep = c["cz"].to_numpy() < 0.5 * rt * d50
    return {"d_load": float(d[order][np.searchsorted(cum, 0.5)]), "deep": float(w[deep].sum() / w.sum()),
            "grains": float(c.groupby("snapshot")["id2"].nunique().mean()), "theta_r_all": theta_r[0],
            "theta_r_stoss": theta_r[1]}


def main(campaigns: list[str]) -> None:
    rows = []
    for path in campaigns:
        _, store, summ = open_campaign(path)
        try:
            s = summ[(summ["test"] == "interface") & (summ.get("profile_kind") == "sawtooth")]
            s = s[pd.to_numeric(s["sr"]) == 0]
            for r in s.itertuples():
                got = run_row(store.case_folder(str(r.case_id)), float(r.d50), float(r.rt), int(r.peak_snapshot))
                if got:
                    rows.append({"rt": float(r.rt), "sw": float(r.sw), "friction_ps": float(r.friction_ps),
                                 "gradation": r.gradation, "seed": int(r.seed), "theta_a": float(r.theta_a_deg_92),
                                 "theta_r": float(r.theta_r_surface_deg), "lee": float(r.lee_share_surface),
                                 "tan_delta": float(r.peak_stress_ratio), **got})
        finally:
            store.close()
    df = pd.DataFrame(rows)
    if df.empty:
        print("no run with dumps")
        return
    keys = ["gradation", "friction_ps", "rt", "sw"]
    g = df.groupby(keys)
    out = g[["theta_a", "d_load", "deep", "grains", "lee", "theta_r", "theta_r_all", "theta_r_stoss", "tan_delta"]
            ].agg(["mean", "std"])
    print("| gradation | μs | Rt/D50 | Sw/D50 | seeds | θa [°] | d_load [D50] | deep share | grains on the surface | "
          "lee share | θr (summary) [°] | θr all [°] | θr stoss [°] | tan δ |")
    print("|" + "---|" * 14)
    for key, r in out.iterrows():
        cell = lambda k, f: f"{r[(k, 'mean')]:{f}} ± {r[(k, 'std')]:{f}}"
        grad, mu, rt, sw = key
        print(f"| {grad} | {mu:g} | {rt:g} | {sw:g} | {g.size()[key]} | {r[('theta_a', 'mean')]:.1f} | "
              f"{cell('d_load', '.3f')} | {cell('deep', '.2f')} | {cell('grains', '.0f')} | {cell('lee', '.2f')} | "
              f"{cell('theta_r', '.1f')} | {cell('theta_r_all', '.1f')} | {cell('theta_r_stoss', '.1f')} | "
              f"{cell('tan_delta', '.3f')} |")


if __name__ == "__main__":
    main(sys.argv[1:] or ["campaigns/study.toml"])
