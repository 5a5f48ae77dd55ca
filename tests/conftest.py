"""Shared fixtures: tests/data, engine binaries, a real quick campaign."""

from __future__ import annotations

import inspect
import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"


@pytest.fixture(scope="session")
def dektak_csv() -> Path:
    """The real stylus-profilometer export (tests/data/README.md)."""
    return DATA / "dektak-1.csv"


_NEEDS = re.compile(r"need_binary\(\s*[\"'](\w+)[\"']")


def _engines_needed(func, cache: dict) -> set[str]:
    """The engines whose binary `func`'s body asks for (need_binary("…"))."""
    if func not in cache:
        try:
            cache[func] = set(_NEEDS.findall(inspect.getsource(func)))
        except (OSError, TypeError):
            cache[func] = set()
    return cache[func]


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """Every test that needs an engine carries its marker, so that the engine-free selection
    (-m "not liggghts and not yade and not slurm") runs none: a test whose body or any of its
    fixtures (directly or through others) calls need_binary(name) must be marked `name`."""
    cache: dict = {}
    unmarked = []
    for item in items:
        funcs = [getattr(item, "function", None)]
        info = getattr(item, "_fixtureinfo", None)
        for defs in (info.name2fixturedefs.values() if info is not None else ()):
            funcs += [d.func for d in defs]
        needed = set().union(*(_engines_needed(f, cache) for f in funcs if f is not None))
        missing = needed - {m.name for m in item.iter_markers()}
        if missing:
            unmarked.append(f"{item.nodeid}: needs {', '.join(sorted(missing))}")
    if unmarked:
        raise pytest.UsageError("tests that run an engine without its marker (add @pytest.mark.<engine>):\n  "
                                + "\n  ".join(unmarked))
    for item in items:
        group = xdist_group(item)
        if group is not None:
            item.add_marker(pytest.mark.xdist_group(group))


def pytest_collection_finish(session):
    """Under --dist loadgroup, xdist groups a test by a "@group" suffix of its node id; on pytest
    9.2 that suffix no longer takes (pytest-dev/pytest-xdist#1386) and grouped fixtures would be
    built on every worker: refuse rather than run slowly in silence."""
    if getattr(session.config.option, "loadgroup", False) and any(
            it.get_closest_marker("xdist_group") and "@" not in it.nodeid for it in session.items):
        raise pytest.UsageError("pytest-xdist did not group the tests (--dist loadgroup): pytest "
                                f"{pytest.__version__} is too new for it; `make test` installs pytest < 9.2")


def xdist_group(item) -> str | None:
    """The worker group of a test under `pytest -n N --dist loadgroup` (make test): tests that share
    an expensive fixture wider than one test run on one worker, so that it is built once, not once per
    worker. The SLURM tests are one group (each module brings up its own daemons: one cluster at a
    time, no two racing for free ports); a test using a module- or session-scoped fixture of tests/
    runs with its module. Every other test goes to whichever worker is free: quick_campaign, shared by
    nine files, is built once for all workers behind a lock instead (its fixture)."""
    if item.get_closest_marker("slurm") is not None:
        return "slurm"
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return None
    for defs in info.name2fixturedefs.values():
        d = defs[-1]
        if d.scope != "function" and getattr(d.func, "__module__", "").startswith("tests"):
            return item.nodeid.split("::")[0]
    return None


def need_binary(name: str) -> str:
    """Path of a required engine binary; a missing one FAILS (make test installs it)."""
    path = shutil.which(name)
    if path is None:
        pytest.fail(f"{name} is not installed: run `make test`, which installs it with apt-get")
    return path


@pytest.fixture(scope="session")
def quick_campaign(tmp_path_factory, request) -> Path:
    """campaigns/quick.toml with a smaller sweep (Rt/D50 0.5 and 1 at μs 0.2, seeds 1 and 2: 4
    interface cases and their 2 box tests) and 1 mm of shear, not its 3 mm (the shear is most of a
    case's engine time), run for real with LIGGGHTS into a temporary output folder; returns the path
    of the campaign file that points there. Run once per test session; test_stale, test_restore and
    test_store_verify rerun its cases as they are.
    Over 1 mm the runs are a pipeline's input, not a soil's strength: the box tests have not peaked
    (one seed's peak is at the end, tan φ 0.22) and E reads 1.5-1.8. No test reads the physics; what
    they read holds with margin: 5 contact snapshots a run (animation test: more than 3), 209 grains
    and 19 surface contacts in the network figure's peak snapshot (more than 50, at least 1), the
    restored campaign's ensembles within 0.17 % of the original's (test_restore: 1 %).
    Under pytest-xdist the first worker to ask runs it in the session's shared temporary folder and
    the others wait on its lock and read the same runs (every reader only reads or copies them, as
    `campaign status` reads a running campaign), so its reading tests spread over the workers."""
    from filelock import FileLock

    need_binary("liggghts")
    base = tmp_path_factory.getbasetemp()
    under_xdist = hasattr(request.config, "workerinput")       # each worker's basetemp is one folder down
    tmp = (base.parent if under_xdist else base) / "quick-campaign"
    toml = tmp / "quick.toml"
    built = tmp / "BUILT"                   # written last: a worker that died mid-run leaves none
    with FileLock(str(tmp) + ".lock"):
        if not built.exists():
            shutil.rmtree(tmp, ignore_errors=True)
            tmp.mkdir()
            _run_quick_campaign(tmp, toml)
            built.touch()
    return toml


def _run_quick_campaign(tmp: Path, toml: Path) -> None:
    """The reduced quick campaign written to `toml`, its runs to `tmp`/runs, run for real."""
    from interphase.cli import main

    text = (ROOT / "campaigns" / "quick.toml").read_text()
    text = text.split("[sweep]")[0] + "[sweep]\nprofile.rt = [0.5, 1]\nfriction_ps = [0.2]\nseed = [1, 2]\n"
    assert "\nshear_distance = 0.003\n" in text
    text = text.replace("\nshear_distance = 0.003\n", "\nshear_distance = 0.001\n", 1)
    text = "\n".join(line for line in text.splitlines() if not line.startswith("output ="))
    toml.write_text(text.replace('name = "quick"', f'name = "quick"\noutput = "{tmp / "runs"}"', 1))
    assert main(["run", str(toml)]) == 0
