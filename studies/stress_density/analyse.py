"""The stress-and-density study's tables from its committed runs (no engine): the soil-test strength
tables the Karlsruhe cards' answers read ([criterion] strength), and E against stress and density.

    python studies/stress_density/analyse.py [--check]

Reads each set's committed summaries.csv and curves.parquet (results/<set>/, written by `campaign
pack` of the study's runs folders) beside the criterion campaigns' own (studies/kfs_group1_3d/, kfs_group1_2d/),
and writes results/strength_3d.csv, results/strength_2d.csv (the states on at least TABLE_SEEDS seeds),
results/soil_tests_3d.csv (every 3D state, whatever its seeds) and results/e_2d.csv. --check re-derives
them and fails if a committed one differs.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

from interphase.analysis.ensemble_table import box_ensembles, ensemble_table
from interphase.campaign.results import read_committed

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
CARD_RUNS = {"3d": ROOT / "studies/kfs_group1_3d/results", "2d": ROOT / "studies/kfs_group1_2d/results"}
STUDY_RUNS = {"3d": HERE / "results" / "soil_3d", "2d": HERE / "results" / "e_2d"}


def _sets(dim: str):
    for folder in (CARD_RUNS[dim], STUDY_RUNS[dim]):
        if (folder / "summaries.csv").exists():
            yield read_committed(folder)


#: seeds a soil-test state needs before the card's strength table (which the answer reads) holds it: a
#: state on fewer has no interval worth the name, and the answer is refused there rather than read off one run
TABLE_SEEDS = 3


def soil_tests(dim: str) -> pd.DataFrame:
    """One row per (stress, preparation) soil test, whatever its seeds; a state measured in both sets is
    read from the one with more seeds (the study restores the criterion campaign's runs of the same id)."""
    rows = pd.concat([box_ensembles(s, c) for s, c in _sets(dim)], ignore_index=True)
    rows = rows.sort_values("seeds").drop_duplicates(["normal_stress", "preparation"], keep="last")
    cols = ["normal_stress", "preparation", "tan_phi", "tan_phi_lo", "tan_phi_hi", "seeds", "tan_phi_cs",
            "tan_phi_cs_lo", "tan_phi_cs_hi"]
    return rows.sort_values(["preparation", "normal_stress"])[cols].round(6).reset_index(drop=True)


def strength(dim: str) -> pd.DataFrame:
    """The card's strength table: the states with at least TABLE_SEEDS seeds."""
    rows = soil_tests(dim)
    return rows[rows["seeds"] >= TABLE_SEEDS].reset_index(drop=True)


def e_table() -> pd.DataFrame:
    """E, tan δ and tan φ with their intervals per physical case of the quasi-2D E study."""
    folder = STUDY_RUNS["2d"]
    if not (folder / "summaries.csv").exists():
        return pd.DataFrame()
    summ, curves = read_committed(folder)
    ens = ensemble_table(summ, curves)
    state = summ.drop_duplicates("physical_id").set_index("physical_id")[["normal_stress", "preparation", "rt"]]
    cols = ["rt", "normal_stress", "preparation", "seeds", "box_seeds", "tan_delta", "tan_delta_lo", "tan_delta_hi",
            "tan_phi", "tan_phi_lo", "tan_phi_hi", "E", "E_lo", "E_hi", "theta_r_deg"]
    return ens.join(state, on="physical_id")[cols].sort_values(["rt", "preparation", "normal_stress"]).round(6)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="fail if a committed table differs from its re-derivation")
    args = ap.parse_args(argv)
    tables = {"strength_3d.csv": strength("3d"), "soil_tests_3d.csv": soil_tests("3d"), "strength_2d.csv": strength("2d"),
              "e_2d.csv": e_table()}
    bad = []
    for name, df in tables.items():
        path = HERE / "results" / name
        text = df.to_csv(index=False)
        if args.check:
            if df.empty and not path.exists():          # a set not packed yet: nothing to hold
                continue
            if not path.exists() or path.read_text() != text:
                bad.append(name)
        elif len(df):
            path.write_text(text)
        print(f"{name}:\n{df.to_string(index=False)}\n")
    if bad:
        print(f"differs from the committed table: {', '.join(bad)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
