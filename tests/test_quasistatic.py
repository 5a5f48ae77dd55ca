"""Quasi-static checks on real LIGGGHTS output (the formulas are tested in test_strength.py)."""

import json
from pathlib import Path

import pandas as pd

from interphase.analysis.quasistatic import checks
from interphase.case import case_from_dict
from interphase.tables import Results

DATA = Path(__file__).parent / "data" / "liggghts_sawtooth45"


def test_checks_on_real_liggghts_output():
    meta = json.loads((DATA / "case.json").read_text())
    c = meta["case"]
    case = case_from_dict({k: v for k, v in c.items() if k not in ("profile", "gradation")} |
                          {"profile": {"kind": "sawtooth", **c["profile"]["params"]}, "gradation": c["gradation"]})
    res = Results(pd.read_parquet(DATA / "contacts.parquet"), pd.read_parquet(DATA / "history.parquet"),
                  pd.read_parquet(DATA / "particles.parquet"))
    out = checks(case, res)
    # grains leave the box under the left wall with the surface and are removed (engines.device)
    assert 0 <= out["grains_left"] <= 10 and out["grains_outside_box"] == 0
    # the max flags a grain caught under the left wall's edge on top of a valley grain (0.42 D50
    # here, soft G; docs/liggghts.md, left-wall gap)
    assert 0 < out["overlap_mean_d50"] < 0.05 < out["overlap_max_d50"] < 0.5
    assert 0 <= out["platen_force_error_mean"] < 0.5 and out["quasi_static"] == (out["inertial_number"] < 1e-3)
    assert out["inertial_number"] > 0 and out["shear_rate_max"] > 0
