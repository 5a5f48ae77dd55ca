"""Issue 32 item 7: the Python API (`from interphase import ...`), its help, and docs/api_example.py
run for real (LIGGGHTS, 4 tiny runs)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

import interphase as ip

ROOT = Path(__file__).resolve().parents[1]
API = ("load_campaign", "plan", "run", "status", "summaries", "ensembles", "predict", "predict_dem")


def test_help_shows_the_api():
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"), PAGER="cat", TERM="dumb")
    out = subprocess.run([sys.executable, "-c", "import interphase; help(interphase)"], capture_output=True,
                         text=True, env=env, timeout=60)
    assert out.returncode == 0, out.stderr
    funcs = out.stdout.split("FUNCTIONS", 1)[1]
    for name in API:
        assert f"\n    {name}(" in funcs, name
        assert getattr(ip, name).__doc__, name
    assert "docs/api_example.py" in out.stdout


def test_plan_and_status_from_python(tmp_path):
    c = ip.load_campaign(ROOT / "campaigns" / "quick.toml")
    planned = ip.plan(c)
    assert len(planned) == 34 and planned[0].role == "box"
    assert [p.case_id for p in ip.plan(c, lazy=True)] == [p.case_id for p in planned]
    with pytest.raises(ip.InputError, match="does not exist"):
        ip.status(c, runs=tmp_path / "nothing")
    with pytest.raises(ip.InputError, match="positive diameter"):
        ip.predict(ROOT / "campaigns" / "profiles" / "dektak-1.csv", d50=-1, friction=0.2, fit="study")


@pytest.mark.liggghts
def test_the_api_example_runs(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    out = subprocess.run([sys.executable, str(ROOT / "docs" / "api_example.py"), str(tmp_path)], capture_output=True,
                         text=True, env=env, timeout=600)
    assert out.returncode == 0, out.stdout + out.stderr
    assert f"runs folder {tmp_path / 'runs' / 'tiny'}" in out.stdout
    assert out.stdout.count(" done") == 4 and "θa 3" in out.stdout and "tan δ 0." in out.stdout
    runs = ip.summaries(tmp_path / "tiny.toml")
    assert isinstance(runs, pd.DataFrame) and len(runs) == 4 and (runs["peak_stress_ratio"] > 0).all()
    ens = ip.ensembles(tmp_path / "tiny.toml")
    assert len(ens) == 1 and ens["seeds"].iloc[0] == 2 and 0 < ens["tan_delta"].iloc[0] < 1
    # resumable: a second run from Python runs nothing
    rep = ip.run(tmp_path / "tiny.toml", quiet=True)
    assert rep.exit_code == 0 and rep.ran == 0
