"""Does the model's prediction interval of `campaign predict --soil` hold? Its residual part on the
cases each shipped fit held out, nested (each group or surface against the scale of the others).

    python studies/answer_intervals/coverage.py [--check]

Reads the `held_out` block of each fit (criterion.json, written by `campaign report` from the
committed runs) and writes results/coverage.csv: per fit and rule, the share of held-out cases whose
simulated δ falls inside, and the mean half-width [°], on all cases and per branch. Rules: the
t-interval on the rms of each branch's errors (the answer's), the same pooled over both branches,
and the split-conformal quantile pooled (distribution-free). --check fails if the committed table
differs from its re-derivation.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.answer import LEVEL, branch_of, held_out_units, interval_coverage

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
FITS = {"study (reproduction, 930 runs)": ROOT / "src/interphase/data/criterion_reproduction.json",
        "Karlsruhe 3D card": ROOT / "studies/kfs_group1_3d/results/criterion.json",
        "Karlsruhe quasi-2D card": ROOT / "studies/kfs_group1_2d/results/criterion.json"}


def conformal(held_out: dict) -> dict:
    """Split-conformal, nested: each unit's cases against the ⌈(n+1)·LEVEL⌉-th smallest |error| of
    the others (pooled over branches)."""
    units, cases = held_out_units(held_out), held_out["cases"]
    rows = []
    for c, u in zip(cases, units):
        other = np.sort([abs(d["error_deg"]) for d, v in zip(cases, units) if v != u])
        q = other[min(math.ceil((other.size + 1) * LEVEL), other.size) - 1]
        rows.append({"inside": abs(c["error_deg"]) <= q, "half_width": q, "branch": branch_of(c["E_predicted"])})
    df = pd.DataFrame(rows)
    return {name: {"n": len(p), "covered": p["inside"].mean(), "mean_half_width_deg": p["half_width"].mean()}
            for name, p in (("all", df), ("rising", df[df.branch == "rising"]), ("plateau", df[df.branch == "plateau"]))}


def table() -> pd.DataFrame:
    rows = []
    for name, path in FITS.items():
        h = json.loads(path.read_text())["held_out"]
        rules = {"t on rms, per branch (the answer's)": interval_coverage(h, by_branch=True),
                 "t on rms, pooled": interval_coverage(h, by_branch=False), "conformal, pooled": conformal(h)}
        for rule, c in rules.items():
            for part in ("all", "rising", "plateau"):
                rows.append({"fit": name, "fold": h["fold"], "rule": rule, "cases": part, "n": c[part]["n"],
                             "covered": round(float(c[part]["covered"]), 3),
                             "mean_half_width_deg": round(float(c[part]["mean_half_width_deg"]), 2)})
    return pd.DataFrame(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args(argv)
    df, path = table(), HERE / "results" / "coverage.csv"
    print(df.to_string(index=False))
    if args.check:
        if not path.exists() or path.read_text() != df.to_csv(index=False):
            print(f"{path} differs from its re-derivation", file=sys.stderr)
            return 1
        return 0
    path.write_text(df.to_csv(index=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
