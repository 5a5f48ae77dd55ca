"""Everything `campaign report` fits, written again from the committed summaries and curves (no runs
folder, no engine): the seed ensembles, the correlations with their seed bootstrap, criterion.json,
the criterion's check against every case, and the findings tables.

    PYTHONPATH=src python studies/reproduction/refit_reproduction.py [--study] [--sandlike] [--kfs2d] [--kfs3d]
        [--precision] [--out DIR] [--boot N] [--figures] [--commit]

--study: docs/reproduction/ (campaigns/study.toml); --sandlike: docs/reproduction/group1_sandlike/;
--kfs2d, --kfs3d: Group 1 on the Karlsruhe fine sand, studies/kfs_group1_2d/results/ and studies/kfs_group1_3d/results/;
--precision: the study's sequential rerun to E ± 0.1, docs/reproduction/precision/study/
(studies/reproduction/study_sequential.toml; studies/reproduction/findings_moved.py reads it against --study).
The report is written to DIR/<name>/ (default /tmp/refit). --commit copies its results where the
repository keeps them: the sequential study's (--precision) criterion.json to
src/interphase/data/criterion_reproduction.json and, with --figures, its figures to
docs/reproduction/figures/; every set but --study (whose ensembles.csv studies/reproduction/ensembles_tables.py
writes) its correlations.csv,
criterion.json, criterion_check.md, ensembles.csv (and, with --figures, the figures its folder
already holds, or SET_FIGURES where it holds none) to its folder: every committed number then comes from the committed curves (float32;
a report on the runs themselves differs from them in the fourth digit).
Bootstrap refits per correlation: 99 (the shipped criterion's count) unless --boot.
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

import pandas as pd

from interphase.campaign.results import CommittedCurves
from interphase.campaign.schema import load_campaign
from interphase.report.build import analyse, write

ROOT = Path(__file__).resolve().parents[2]
REPRO = ROOT / "docs" / "reproduction"
STUDIES = ROOT / "studies"
SETS = {"study": (REPRO, ROOT / "campaigns" / "study.toml"),
        "sandlike": (REPRO / "group1_sandlike", ROOT / "campaigns" / "soils" / "group1_sandlike.toml"),
        "kfs2d": (STUDIES / "kfs_group1_2d" / "results", STUDIES / "kfs_group1_2d" / "group1_kfs_2d.toml"),
        "kfs3d": (STUDIES / "kfs_group1_3d" / "results", STUDIES / "kfs_group1_3d" / "group1_kfs_3d.toml"),
        "precision": (REPRO / "precision" / "study", ROOT / "studies" / "reproduction" / "study_sequential.toml")}


#: the figures a set's folder keeps when it holds none yet (the real-sand sets' Figs. 6.8, 6.10a and the check)
SET_FIGURES = ("fig6_8.png", "fig6_10a.png", "criterion_check.png")


def refit(name: str, out: Path, n_boot: int, figures: bool):
    folder, campaign_file = SETS[name]
    summ = pd.read_csv(folder / "summaries.csv", dtype={"case_id": str})
    store = CommittedCurves(folder / "curves.parquet")
    try:
        campaign = load_campaign(campaign_file)
    except Exception as exc:                 # the input tables are decoration: fit without them
        print(f"{campaign_file}: {exc}; no input tables", file=sys.stderr)
        campaign = None
    model = analyse(summ, campaign=campaign, store=store, n_boot=n_boot)
    if not figures:
        import interphase.report.build as B
        B._figures = lambda m, fdir, store, res: ([], [])
    res = write(model, out / name, store=store)
    print(f"{name}: wrote {len(res.files)} files to {out / name}")
    return out / name


#: the set whose fits the package ships and whose figures docs/reproduction/figures/ holds: the
#: sequential study (every case to E ± 0.1), which holds the 3-seed study's runs too
SHIPPED = "precision"


def commit(name: str, report: Path, figures: bool) -> None:
    if name == SHIPPED:
        shutil.copy(report / "criterion.json", ROOT / "src" / "interphase" / "data" / "criterion_reproduction.json")
        if figures:
            for png in (REPRO / "figures").glob("*.png"):
                shutil.copy(report / "figures" / png.name, png)
    if name == "study":                      # its ensembles.csv is studies/reproduction/ensembles_tables.py's
        return
    dest = SETS[name][0]
    shutil.copy(report / "criterion.json", dest / "criterion.json")
    for table in ("correlations.csv", "criterion_check.md", "ensembles.csv"):
        shutil.copy(report / "tables" / table, dest / table)
    if figures:
        for name in {p.name for p in dest.glob("*.png")} or SET_FIGURES:
            shutil.copy(report / "figures" / name, dest / name)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", action="store_true")
    ap.add_argument("--sandlike", action="store_true")
    ap.add_argument("--kfs2d", action="store_true")
    ap.add_argument("--kfs3d", action="store_true")
    ap.add_argument("--precision", action="store_true")
    ap.add_argument("--out", default="/tmp/refit")
    ap.add_argument("--boot", type=int, default=99)
    ap.add_argument("--figures", action="store_true")
    ap.add_argument("--commit", action="store_true")
    args = ap.parse_args(argv)
    for name in [n for n in SETS if getattr(args, n)]:
        report = refit(name, Path(args.out), args.boot, args.figures)
        if args.commit:
            commit(name, report, args.figures)


if __name__ == "__main__":
    main()
