"""What pairing buys (issue 30 item 2), measured on the committed study.

Two pairings a campaign could exploit: (a) an interface run and the soil (box) test of the same
packing seed; (b) the runs of one surface at the three particle–surface frictions on the same seed.
For each, the within-case correlation of the seeds' peak stress ratios (each case's mean removed),
and for (a) the 95 % half-width of E both ways over the 126 physical cases:
  paired:   E_run = tan δ_s / tan φ_s per seed s (3 seeds), Student t on the mean of E_run;
  unpaired: the seed-ensemble E (the report's: interface seeds against all 10 soil seeds, delta
            method; docs/methods.md), computed here from the same peak values.
Every peak here, both sides, is each run's own maximum (summaries.csv `peak_stress_ratio`), not the
seed ensemble's leave-one-out peak the report reads: a comparison of the two pairings on one
reading, not the report's E or φ. Only positive correlations make a paired interval narrower. Usage:
    python studies/pairing_and_shear_cut/pairing_value.py [docs/reproduction/summaries.csv]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from interphase.analysis.ensemble import ratio_interval

ROOT = Path(__file__).resolve().parents[2]


def main(path: Path) -> None:
    s = pd.read_csv(path, dtype={"case_id": str, "pair_id": str})
    box = s[s["test"] == "box"]
    tan_phi = box.set_index("case_id")["peak_stress_ratio"]
    i = s[s["test"] == "interface"].copy()
    i["tan_phi"] = i["pair_id"].map(tan_phi)
    i["case"] = i["label"].str.replace(r"-s\d+$", "", regex=True)
    centred = lambda col: i[col] - i.groupby("case")[col].transform("mean")
    r_box = np.corrcoef(centred("peak_stress_ratio"), centred("tan_phi"))[0, 1]
    print(f"(a) interface run vs its paired soil test: within-case r = {r_box:+.2f} ({len(i)} runs, "
          f"{i['case'].nunique()} physical cases)")
    i["surface"] = i["case"].str.replace(r"-mu[0-9.]+", "", regex=True)
    for grad, g in i.groupby("gradation"):
        piv = g.pivot_table(index=["surface", "seed"], columns="friction_ps", values="peak_stress_ratio")
        piv = piv - piv.groupby(level=0).transform("mean")
        c = piv.corr().to_numpy()
        pairs = c[np.triu_indices_from(c, 1)]
        print(f"(b) {grad}: r between frictions on one surface and seed: " + ", ".join(f"{x:+.2f}" for x in pairs))

    soil_of = {gr: box[box["gradation"] == gr]["peak_stress_ratio"].to_numpy(float) for gr in box["gradation"].unique()}
    rows = []
    for case, g in i.groupby("case"):
        e_run = (g["peak_stress_ratio"] / g["tan_phi"]).to_numpy(float)
        n = e_run.size
        hw_paired = stats.t.ppf(0.975, n - 1) * e_run.std(ddof=1) / np.sqrt(n)
        a = g["peak_stress_ratio"].to_numpy(float)
        b = soil_of[g["gradation"].iloc[0]]
        lo, hi = ratio_interval(a.mean(), a.std(ddof=1), n, b.mean(), b.std(ddof=1), b.size)
        rows.append({"case": case, "paired": hw_paired, "unpaired": (hi - lo) / 2})
    df = pd.DataFrame(rows)
    print(f"E half-width, median over {len(df)} cases: paired (3 seeds) {df['paired'].median():.3f}, "
          f"unpaired seed ensemble (3 + 10 soil seeds) {df['unpaired'].median():.3f}; paired narrower in "
          f"{(df['paired'] < df['unpaired']).mean():.0%} of cases")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "docs" / "reproduction" / "summaries.csv")
