"""`campaign render` and `campaign run-case` from a TOML [case] snippet (real LIGGGHTS)."""

import json

import pandas as pd
import pytest

from interphase.cli import main
from tests.campaign_files import TINY_CASE, toml_text, write_toml

#: the tiny case, a little larger (150 grains in 15 × 10 D50) and sheared 1 mm
CASE = {"test": "interface", **TINY_CASE, "n_grains": 150, "box_length_d50": 15, "box_height_d50": 10,
        "shear_distance": 0.001, "snapshot_every": 0.0005}


@pytest.mark.liggghts
def test_render_then_run_case(tmp_path, capsys):
    toml = write_toml(tmp_path / "c.toml", case=CASE)
    assert main(["render", str(toml), "-o", str(tmp_path / "dry"), "--json"]) == 0
    files = json.loads(capsys.readouterr().out)["files"]
    assert "in.deck" in files and (tmp_path / "dry" / "surface.stl").exists()
    assert main(["run-case", str(toml), "-o", str(tmp_path / "run"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    h = pd.read_parquet(out["history"])
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())["row"]
    # the summary's peak (a tiny walled box: a smoke test, not a strength; docs/strength.md)
    assert len(h) > 50 and out["peak_stress_ratio"] == summary["peak_stress_ratio"] > 0.15


@pytest.mark.parametrize("extra,needle", [("frction_pp = 1", "did you mean 'friction_pp'"),
                                          ("d50 = -1", "case.d50"), ("seed = 1.5", "seed"),
                                          ("profile = {kind = 'zigzag'}", "profile.kind")])
def test_bad_case_toml_exit_2(tmp_path, capsys, extra, needle):
    toml = tmp_path / "bad.toml"
    # a bad profile replaces the good one (TOML refuses a key given twice)
    case = {k: v for k, v in CASE.items() if not (k == "profile" and "profile" in extra)}
    toml.write_text(toml_text(case=case) + extra + "\n")
    assert main(["render", str(toml), "-o", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert str(toml) in err and needle in err
