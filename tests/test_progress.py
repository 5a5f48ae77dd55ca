"""Progress of a running engine, read from its own files (engines.progress), and shown by `campaign
run` within seconds of a case's start: on a real LIGGGHTS case."""

from __future__ import annotations

import re
import subprocess
import sys
import time

import pytest

from interphase.engines.progress import Stage, liggghts_stage
from tests.campaign_files import TINY_CASE, write_toml
from tests.conftest import need_binary

pytestmark = pytest.mark.liggghts


def test_a_real_run_reads_prepare_then_shear_rising_to_the_end(tmp_path):
    """Sampled while a tiny interface case runs: the stages come in the deck's order, the shear's
    share never falls, and the finished folder reads the shear at its end (within one history
    interval)."""
    need_binary("liggghts")
    toml = write_toml(tmp_path / "c.toml", campaign={"name": "p", "engines": ["liggghts"], "output": "out"},
                      execution={"jobs": 1}, case={**TINY_CASE, "shear_velocity": 0.01}, pairs={"box": False})
    proc = subprocess.Popen([sys.executable, "-m", "interphase.cli", "run", str(toml), "--plain"], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    seen: list[Stage] = []
    while proc.poll() is None:
        for folder in (tmp_path / "out").glob("*/in.deck"):
            s = liggghts_stage(folder.parent)
            if s is not None and (not seen or s != seen[-1]):
                seen.append(s)
        time.sleep(0.05)
    out = proc.stdout.read()
    assert proc.returncode == 0, out
    order = ["prepare", "consolidate", "shear", "finishing"]
    names = [s.name for s in seen]
    assert "shear" in names and names == sorted(names, key=order.index), names
    shear = [s.share for s in seen if s.name == "shear"]
    assert shear == sorted(shear) and 0 <= shear[0] < 0.5 and shear[-1] > 0.5, shear
    (folder,) = [p.parent for p in (tmp_path / "out").glob("*/DONE")]
    end = liggghts_stage(folder)                  # the shear's last history row, one print interval from its end
    assert end.name == "finishing" or (end.name == "shear" and end.share > 0.9), end
    # the campaign said where it was, the first time within 10 s of the start
    at = [ln for ln in out.splitlines() if ln.startswith("  at ")]
    assert at, out
    first = re.search(r"\((\d+)s\)$", at[0])
    assert first and int(first.group(1)) <= 10, at[0]
    assert "estimated time:" in out


def test_a_folder_without_a_deck_has_no_stage(tmp_path):
    assert liggghts_stage(tmp_path) is None
