"""Can the cell's preparation make a looser specimen than its loosest (preparation 1)? A probe for
the loose-series miss of the sphere cards (docs/soils.md, "From dense to loose: the state line"):
the loosest packing the protocol makes still dilates ~13° at 200 kPa where the sand at Dr 0.63
dilates 8.7°.

The preparation scales the grains' sliding and rolling friction during the isotropic consolidation
(0: frictionless, densest; 1: the grains' own; above 1 more than their own, up to
case.PREPARATION_MAX); the compression restores the grains' own. This probe runs the state line's
case at preparations (FACTORS) 1 and above, and reads each run by the state line's code
(analysis.rowe `state_row`: φ_peak, ψ_max, e0, Rowe's φ_f, the end).

    PYTHONPATH=src python studies/state_line/loose_preparation.py [--factors 1.5 2.5] [--seeds 1 2] \
        [--runs runs/loose-preparation] [--save docs/soils/loose_preparation]

The state line's grains and protocol (studies/state_line/state_line.toml): friction 0.5317, rolling
friction 0.3143, G 50 MPa, 1000 spheres of the Karlsruhe sieve curve, 200 kPa, 10 /s, here to 20 %
(peaks at 10.7–14.5 % of ε1 over the probe's runs). Its committed preparation-1 runs
(docs/soils/state_line/summaries.csv) are the reference row.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pandas as pd

from interphase.analysis.rowe import state_row

from interphase.campaign.runner import run_single
from interphase.case import Case, case_from_dict

HERE = Path(__file__).resolve().parent
ROOT = Path(__file__).resolve().parents[2]
LINE = HERE / "state_line.toml"


def state_line_case(seed: int, preparation: float) -> Case:
    """The state line's [case] at `preparation` and `seed`, to 20 % of ε1."""
    import tomllib

    fields = tomllib.loads(LINE.read_text())["case"]
    return case_from_dict(fields | dict(preparation=preparation, seed=seed, axial_strain=0.2), where=str(LINE))


def run(factor: float, seed: int, runs: Path) -> dict:
    """One run at preparation `factor` (run_single: a finished folder is read back, not rerun)."""
    folder = runs / f"f{factor:g}-s{seed}"
    out = run_single(state_line_case(seed, factor), "liggghts", folder)
    if out["status"] != "done":
        raise SystemExit(f"{folder}: {out.get('cause')}: {out.get('message')}")
    h = pd.read_parquet(folder / "series.parquet", columns=["eps1", "epsv", "ratio", "e"])
    case = state_line_case(seed, factor)
    return dict(factor=factor, seed=seed, deposition_friction=factor * case.friction_pp,
                deposition_rolling=factor * case.rolling_friction, elapsed_s=float(json.loads((folder / "case.json").read_text())["elapsed"]),
                **state_row(h["eps1"], h["epsv"], h["ratio"], h["e"]))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--factors", type=float, nargs="+", default=[1.5, 2.5])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--runs", type=Path, default=ROOT / "runs" / "loose-preparation")
    ap.add_argument("--save", type=Path)
    a = ap.parse_args(argv)
    rows = pd.DataFrame([run(f, s, a.runs) for f in a.factors for s in a.seeds])
    ref = pd.read_csv(ROOT / "docs" / "soils" / "state_line" / "summaries.csv")
    ref = ref.assign(preparation=ref.preparation.fillna(1.0))
    ref = ref[ref.preparation.isin([0.75, 1.0])]
    cols = ["factor", "seed", "e0", "phi_peak_deg", "psi_max_deg", "eps1_peak", "phi_f_deg", "phi_end_deg", "e_end",
            "elapsed_s"]
    print(rows[cols].round(4).to_string(index=False))
    print("\nseed means:\n", rows.groupby("factor")[cols[2:]].mean().round(3).to_string())
    print("\nthe state line (committed, to 40 %):\n", ref[["preparation", "seed", "e0", "phi_peak_deg", "psi_max_deg"]]
          .round(3).to_string(index=False))
    if a.save:
        a.save.mkdir(parents=True, exist_ok=True)
        rows.to_csv(a.save / "runs.csv", index=False)


if __name__ == "__main__":
    main()
