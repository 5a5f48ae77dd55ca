"""Shared fixtures. Paths to ../shared (the steering repo's data) and tests/data."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("INTERPHASE_SHARED", ROOT.parent / "shared"))
DATA = ROOT / "tests" / "data"


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    return SHARED


@pytest.fixture(scope="session")
def dektak_csv() -> Path:
    """The real stylus-profilometer export; shipped copy in tests/data if ../shared is absent."""
    for p in (DATA / "dektak-1.csv", SHARED / "data" / "profiles" / "dektak-1.csv"):
        if p.exists():
            return p
    pytest.fail("dektak-1.csv not found in tests/data or ../shared/data/profiles")


def need_binary(name: str) -> str:
    """Path of a required engine binary; a missing one FAILS (make test installs it)."""
    path = shutil.which(name)
    if path is None:
        pytest.fail(f"{name} is not installed: run `make test`, which installs it with apt-get")
    return path
