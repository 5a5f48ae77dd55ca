"""Where does E–θr break for each soil? The test of docs/reproduction.md, "Why E saturates earlier".

    python bench/break_by_soil.py campaigns/study.toml campaigns/checks/stronger_soil.toml

For each campaign: Group 1's saw-teeth (Sw/D50 2, no flats) at μs 0.05 with well-graded grains, one
point per RUN (x = its θr at the surface, y = its peak tan δ over the campaign's well-graded tan φ,
the seed-mean soil test), the plateau E = b0 + b1·min(θr, c) fitted with a residual bootstrap
(analysis.correlations.fit_plateau). Runs, not seed means, because the check campaign has 6 physical
cases, fewer than a fit takes. Prints the soil's φ, the break c with its intervals, and c − φ. tan φ
here is the mean of the soil tests' peaks (the report's seed ensemble takes the peak of their mean
curve, a little lower); dividing y by a constant does not move c.
A measurement: exit 0 whatever it finds.
"""

from __future__ import annotations

import math
import sys

import pandas as pd

from interphase.analysis.correlations import fit_plateau
from interphase.campaign.results import open_campaign


def main(campaigns: list[str]) -> None:
    print("| campaign | tan φ (mean of the soil tests' peaks) | φ [°] | runs | E–θr break c [°] (95 %, residual bootstrap) | c − φ [°] |")
    print("|---|---|---|---|---|---|")
    for path in campaigns:
        campaign, store, s = open_campaign(path)
        store.close()
        poly = s["gradation"] == "poly"
        box = s[(s["test"] == "box") & poly]
        tan_phi = float(pd.to_numeric(box["peak_stress_ratio"]).mean())
        r = s[(s["test"] == "interface") & poly & (s["profile_kind"] == "sawtooth")
              & (pd.to_numeric(s["sw"]) == 2) & (pd.to_numeric(s["sr"]) == 0)
              & (pd.to_numeric(s["friction_ps"]) == 0.05)]
        fit = fit_plateau(r["theta_r_surface_deg"].astype(float), r["peak_stress_ratio"].astype(float) / tan_phi,
                          n_boot=999, seed=1)
        phi = math.degrees(math.atan(tan_phi))
        lo, hi = fit.c_interval_bootstrap
        plo, phi_ = fit.c_interval_profile
        print(f"| {campaign.name} | {tan_phi:.3f} ({len(box)} seeds) | {phi:.1f} | {len(r)} | {fit.c:.1f} "
              f"({lo:.1f}–{hi:.1f}; profile {plo:.1f}–{phi_:.1f}) | {fit.c - phi:+.1f} |")


if __name__ == "__main__":
    main(sys.argv[1:] or ["campaigns/study.toml", "campaigns/checks/stronger_soil.toml"])
