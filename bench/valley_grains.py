"""Which grains carry the surface's load on narrow teeth? A measurement for Group 3's misses
(docs/reproduction.md, "Group 3"): do fine grains fill valleys narrower than D50?

    python bench/valley_grains.py campaigns/study.toml campaigns/checks/narrow_valleys.toml

For every finished interface run on saw-teeth of Rt/D50 1 without flats (Group 3 and Group 1's
Sw/D50 2), from its own dumps over the shear (snapshots after the first), with the surface's
particle contacts (kind 'ps') joined to their grains by snapshot and id:
  d_load      median diameter of the grains touching the surface, weighted by contact normal force [D50]
  deep        share of the surface's normal force carried below half the teeth's height
  grains      grains touching the surface per snapshot
Prints one Markdown row per physical case and gradation: seed means with their sd. Runs restored from
a summaries table have no dumps and are skipped. A measurement: exit 0 whatever it finds.
"""

from __future__ import annotations

import sys

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from interphase.report.build import open_campaign


def run_row(folder, d50: float, rt: float) -> dict | None:
    cp, pp = folder / "contacts.parquet", folder / "particles.parquet"
    if not (cp.exists() and pp.exists()):
        return None
    c = pq.read_table(cp, columns=["snapshot", "kind", "id2", "cz", "fn"]).to_pandas()
    c = c[(c["kind"] == "ps") & (c["snapshot"] > 0)]
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
            "grains": float(c.groupby("snapshot")["id2"].nunique().mean())}


def main(campaigns: list[str]) -> None:
    rows = []
    for path in campaigns:
        _, store, summ = open_campaign(path)
        try:
            s = summ[(summ["test"] == "interface") & (summ.get("profile_kind") == "sawtooth")]
            s = s[(pd.to_numeric(s["rt"]) == 1) & (pd.to_numeric(s["sr"]) == 0)]
            for r in s.itertuples():
                got = run_row(store.case_folder(str(r.case_id)), float(r.d50), float(r.rt))
                if got:
                    rows.append({"sw": float(r.sw), "friction_ps": float(r.friction_ps), "gradation": r.gradation,
                                 "seed": int(r.seed), "theta_r": float(r.theta_r_surface_deg),
                                 "tan_delta": float(r.peak_stress_ratio), **got})
        finally:
            store.close()
    df = pd.DataFrame(rows)
    if df.empty:
        print("no run with dumps")
        return
    g = df.groupby(["gradation", "friction_ps", "sw"])
    out = g[["d_load", "deep", "grains", "theta_r", "tan_delta"]].agg(["mean", "std"])
    print("| gradation | μs | Sw/D50 | seeds | d_load [D50] | deep share | grains on the surface | θr [°] | tan δ |")
    print("|---|---|---|---|---|---|---|---|---|")
    for (grad, mu, sw), r in out.iterrows():
        cell = lambda k, f: f"{r[(k, 'mean')]:{f}} ± {r[(k, 'std')]:{f}}"
        print(f"| {grad} | {mu:g} | {sw:g} | {g.size()[(grad, mu, sw)]} | {cell('d_load', '.3f')} | {cell('deep', '.2f')} | "
              f"{cell('grains', '.0f')} | {cell('theta_r', '.1f')} | {cell('tan_delta', '.3f')} |")


if __name__ == "__main__":
    main(sys.argv[1:] or ["campaigns/study.toml"])
