"""Every study's committed tables re-derive from its committed runs (studies/NAME/*.py --check):
the scripts that need no engine are run here, and a table that no longer follows from its runs fails."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted(p for p in (ROOT / "studies").glob("*/*.py") if "--check" in p.read_text())


def test_every_study_has_a_re_derivation():
    assert SCRIPTS, "no study script with --check"


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_the_committed_tables_follow_from_the_committed_runs(script):
    res = subprocess.run([sys.executable, str(script), "--check"], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout[-2000:] + res.stderr[-2000:]
