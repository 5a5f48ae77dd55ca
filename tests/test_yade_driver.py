"""The YADE driver module's pure parts, without YADE; and its import by YADE's own python."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from interphase.case import Case
from interphase.engines import yade_driver as drv
from interphase.engines.base import EngineProfile
from interphase.engines.yade import Yade
from interphase.surface.spec import ProfileSpec

CASE = Case(profile=ProfileSpec.make("flat"), shear_modulus=50e6, n_grains=60, box_length_d50=16, box_height_d50=8,
            shear_distance=0.5e-3, snapshot_every=0.25e-3)


def test_the_module_imports_without_yade():
    """YADE is imported inside main() only: with every `import yade` made to fail, the module still
    imports (a top-level import would fail here, whether or not YADE's python is installed)."""
    code = ("import sys; sys.modules['yade'] = None\n"
            "import interphase.engines.yade_driver as d\n"
            "print(d.main.__name__, d.servo_velocity(10.0, 9.5, 0.1, 0.1))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["main", "-0.05"]


def test_servo_velocity_is_proportional_then_capped():
    # force below target: the platen moves down, at speed·error/band, capped at the speed
    assert drv.servo_velocity(10.0, 9.5, 0.1, 0.1) == pytest.approx(-0.05)
    assert drv.servo_velocity(10.0, 0.0, 0.1, 0.1) == -0.1
    assert drv.servo_velocity(10.0, 30.0, 0.1, 0.1) == 0.1          # pushed too hard: up, capped
    assert drv.servo_velocity(10.0, 10.0, 0.1, 0.1) == 0.0


def test_consolidation_checks_fall_on_the_first_stretch_and_chunk_ends():
    steps = {"n_consolidate": 100, "n_chunk": 25}
    assert [drv.chunks_done(it, steps) for it in (0, 99, 100, 101, 125, 150, 174)] == [None, None, 0, None, 1, 2, None]


def test_window_and_bounds_are_open_intervals():
    assert drv.in_window(0.5, 0.1, (0.0, 1.0, 0.2)) and not drv.in_window(1.0, 0.1, (0.0, 1.0, 0.2))
    assert not drv.in_window(0.5, 0.2, (0.0, 1.0, 0.2))
    assert drv.in_bounds(0.0, 0.0, (-1, 1, -1, 1)) and not drv.in_bounds(0.0, 1.0, (-1, 1, -1, 1))


def test_periodic_x_is_wrapped_into_the_period():
    assert drv.wrap(-0.25, 1.0) == 0.75 and drv.wrap(1.0, 1.0) == 0.0 and drv.wrap(0.5, 1.0) == 0.5
    assert drv.wrap(-0.25, None) == -0.25                  # walled device: positions as they are


def test_long_facets_are_split_for_the_periodic_cell():
    """No body may span half of YADE's periodic cell: a flat [0, L] facet becomes 4 of L/4, each an
    in-plane triangle with its apex over its own midpoint; short facets are kept."""
    flat = [[0.0, 0.0, 0.1, 1.0, 0.0, 0.1, 0.5, 0.2, 0.1]]
    out = drv.split_facets(flat, 0.25)
    assert len(out) == 4 and out[0] == [0.0, 0.0, 0.1, 0.25, 0.0, 0.1, 0.125, 0.2, 0.1]
    assert [t[3] for t in out] == [0.25, 0.5, 0.75, 1.0]
    tooth = [[0.0, 0.0, 0.0, 0.1, 0.0, 0.1, 0.05, 0.2, 0.05]]
    assert drv.split_facets(tooth, 0.25) == tooth


def test_rows_match_their_headers():
    v = (1.0, 0.0, 2.0)
    rows = {drv.CONTACT_HEADER: drv.contact_row(7, 1, 2, v, v, v, 1e-6, v, v),
            drv.PARTICLE_HEADER: drv.particle_row(7, 3, v, v, 5e-4),
            drv.HISTORY_HEADER: drv.history_row(7, (0.1, -1.0), 1.0, 0.01, 12, (0.05, -0.5), 60, 0)}
    for header, row in rows.items():
        assert row.endswith("\n") and len(row.split(",")) == len(header.split(","))
        assert row.startswith("7,")
    assert drv.contact_row(7, 1, 2, (1.5, 9.0, 2.5), v, v, 0.0, v, v).split(",")[3:5] == ["1.5", "2.5"]   # x, z


def test_the_script_only_calls_the_module():
    files = Yade(profile=EngineProfile("yade")).render(CASE)
    script = files["driver.py"]
    assert "from interphase.engines.yade_driver import main" in script and "main(PARAMS)" in script
    root = json.loads(files["params.json"])["package_root"]
    assert (Path(root) / "interphase" / "engines" / "yade_driver.py").is_file()


@pytest.mark.yade
def test_yade_python_imports_the_driver_from_package_root(tmp_path):
    """YADE runs the system python3 (its launcher's shebang), not this venv's: the package must be
    importable there from params.json's package_root alone."""
    from tests.conftest import need_binary

    launcher = need_binary("yade")
    python = open(launcher).readline()[2:].strip().split()[0]
    if shutil.which(python) is None:
        pytest.fail(f"YADE's python {python} not found")
    Yade(profile=EngineProfile("yade")).write_input(CASE, tmp_path)
    probe = ("import json, sys; sys.path.append(json.load(open('params.json'))['package_root']); "
             "import interphase.engines.yade_driver as d; print(d.__file__)")
    out = subprocess.run([python, "-c", probe], cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == drv.__file__
