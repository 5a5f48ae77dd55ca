"""Quasi-static checks: the METHODS.md inertial-number example and real LIGGGHTS output."""

import json
from pathlib import Path

import pandas as pd
import pytest

from interphase.analysis.quasistatic import checks, inertial_number, max_shear_rate, shear_rate_profile
from interphase.case import case_from_dict
from interphase.engines.base import Results

DATA = Path(__file__).parent / "data" / "liggghts_sawtooth45"


def test_inertial_number_example():
    # v = 1 mm/s over a 10 mm band, D50 1 mm, 100 kPa, 2650 kg/m³ → 1.63e−5
    assert inertial_number(1e-3 / 10e-3, 1e-3, 100e3, 2650) == pytest.approx(1.63e-5, rel=2e-3)


def test_linear_profile_gives_its_slope():
    z = [i * 1e-3 for i in range(10) for _ in range(5)]
    parts = pd.DataFrame({"snapshot": 1, "z": z, "vx": [0.01 * (1 - zz / 9e-3) for zz in z]})
    prof = shear_rate_profile(parts, 1e-3, 0.0, z_ref=-0.5e-3)
    assert max_shear_rate(prof) == pytest.approx(0.01 / 9e-3, rel=1e-9)


def test_checks_on_real_liggghts_output():
    meta = json.loads((DATA / "case.json").read_text())
    c = meta["case"]
    case = case_from_dict({k: v for k, v in c.items() if k not in ("profile", "gradation")} |
                          {"profile": {"kind": "sawtooth", **c["profile"]["params"]}, "gradation": c["gradation"]})
    res = Results(pd.read_parquet(DATA / "contacts.parquet"), pd.read_parquet(DATA / "history.parquet"),
                  pd.read_parquet(DATA / "particles.parquet"))
    out = checks(case, res)
    assert out["lost_grains"] == 0
    # the max flags the grain jammed under the left wall in this soft toy case (docs/liggghts.md)
    assert 0 < out["overlap_mean_d50"] < 0.05 < out["overlap_max_d50"] < 0.5
    assert 0 <= out["platen_force_error_mean"] < 0.5 and out["quasi_static"] == (out["inertial_number"] < 1e-3)
    assert out["inertial_number"] > 0 and out["shear_rate_max"] > 0
