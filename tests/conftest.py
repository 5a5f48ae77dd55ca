"""Shared fixtures: tests/data, engine binaries, a real quick campaign."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"


@pytest.fixture(scope="session")
def dektak_csv() -> Path:
    """The real stylus-profilometer export (tests/data/README.md)."""
    return DATA / "dektak-1.csv"


def need_binary(name: str) -> str:
    """Path of a required engine binary; a missing one FAILS (make test installs it)."""
    path = shutil.which(name)
    if path is None:
        pytest.fail(f"{name} is not installed: run `make test`, which installs it with apt-get")
    return path


@pytest.fixture(scope="session")
def quick_campaign(tmp_path_factory) -> Path:
    """campaigns/quick.toml run for real (LIGGGHTS, 5 tiny cases) into a temporary output folder;
    returns the path of the campaign file that points there. Run once per test session."""
    from interphase.cli import main

    need_binary("liggghts")
    tmp = tmp_path_factory.mktemp("quick")
    text = (ROOT / "campaigns" / "quick.toml").read_text()
    toml = tmp / "quick.toml"
    toml.write_text(text.replace('name = "quick"', f'name = "quick"\noutput = "{tmp / "runs"}"', 1))
    assert main(["run", str(toml)]) == 0
    return toml
