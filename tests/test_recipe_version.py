"""RECIPE_VERSIONS keeps case ids honest: what each engine is given for reference cases is pinned.

A case id hashes the Case, the engine and its recipe id (the engine's number in RECIPE_VERSIONS and
the Recipe's values), not the code, so that a refactor keeps every finished case. The price: a change
that alters what an engine is given (a template, the device, the packing, the rendering, the YADE
driver's behaviour) must bump that engine's number in interphase.recipe.RECIPE_VERSIONS. This test
renders reference cases of both engines and compares every file's hash (and the YADE driver's code,
which runs inside YADE) with tests/data/recipe_renders.json, written for the current numbers. When it
fails: if the change is meant, bump the engine's number and run `python tests/test_recipe_version.py`
to write the file again.
"""

from __future__ import annotations

import ast
import hashlib
import json
import sys
from pathlib import Path

from interphase.case import Case
from interphase.engines.base import EngineProfile
from interphase.engines.liggghts import Liggghts
from interphase.engines.yade import Yade
from interphase.material import Gradation
from interphase.recipe import RECIPE_VERSIONS
from interphase.surface.spec import ProfileSpec

GOLDEN = Path(__file__).parent / "data" / "recipe_renders.json"
DRIVER = Path(__file__).resolve().parents[1] / "src" / "interphase" / "engines" / "yade_driver.py"
TINY = dict(shear_modulus=50e6, n_grains=120, box_length_d50=16, box_height_d50=8, shear_distance=1e-3,
            snapshot_every=5e-4, friction_ps=0.5)
SAW = ProfileSpec.make("sawtooth", rt=1, sw=2, sr=0)
CASES = {
    "walled-sawtooth-poly": Case(profile=SAW, gradation=Gradation("poly"), **TINY),
    "walled-random-mono": Case(profile=ProfileSpec.make("random", au=2, ar=1, rtmax=2, seed=1), gradation=Gradation("mono"),
                               **TINY),
    "walled-box": Case(test="box", **TINY),
    "periodic-sawtooth-spaced": Case(profile=ProfileSpec.make("sawtooth", rt=1, sw=2, sr=2), device="periodic", **TINY),
    "periodic-random": Case(profile=ProfileSpec.make("random", au=2, ar=1, rtmax=2, seed=1), device="periodic", **TINY),
    "periodic-box": Case(test="box", device="periodic", **TINY),
}
MACHINE_KEYS = ("package_root",)      # params.json values that say where this machine keeps things


def _digest(name: str, content) -> str:
    data = content if isinstance(content, bytes) else content.encode()
    if name.endswith("params.json"):
        d = json.loads(data)
        for k in MACHINE_KEYS:
            d.pop(k, None)
        data = json.dumps(d, sort_keys=True).encode()
    return hashlib.sha256(data).hexdigest()[:16]


def _code(path: Path) -> str:
    """SHA-256 of a Python file's syntax tree without docstrings: what the code does."""
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if (isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and body
                and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant)
                and isinstance(body[0].value.value, str)):
            node.body = body[1:] or [ast.Pass()]
    return hashlib.sha256(ast.dump(tree).encode()).hexdigest()[:16]


def renders() -> dict:
    out = {"recipe_versions": dict(RECIPE_VERSIONS), "yade_driver": _code(DRIVER), "files": {}}
    for engine in (Liggghts(profile=EngineProfile("liggghts")), Yade(profile=EngineProfile("yade"))):
        for name, case in CASES.items():
            for rel, content in sorted(engine.render(case).items()):
                out["files"][f"{engine.name}/{name}/{rel}"] = _digest(rel, content)
    return out


def test_rendered_inputs_change_only_with_the_recipe_version():
    pinned = json.loads(GOLDEN.read_text())
    now = renders()
    problems = []
    for engine, version in RECIPE_VERSIONS.items():
        changed = sorted(k for k in set(pinned["files"]) | set(now["files"])
                         if k.startswith(f"{engine}/") and pinned["files"].get(k) != now["files"].get(k))
        if engine == "yade" and pinned["yade_driver"] != now["yade_driver"]:
            changed.append("src/interphase/engines/yade_driver.py (code)")
        fix = (f"bump RECIPE_VERSIONS[{engine!r}] in interphase/recipe.py (every {engine} case id changes: its "
               "finished cases become stale) and run `python tests/test_recipe_version.py`")
        if pinned["recipe_versions"].get(engine) != version:
            problems.append(f"RECIPE_VERSIONS[{engine!r}] is {version}, the pinned renders are for "
                            f"{pinned['recipe_versions'].get(engine)}: run `python tests/test_recipe_version.py`")
        elif changed:
            problems.append(f"what {engine} is given changed at its recipe version {version}: {changed}; {fix}")
    assert not problems, "\n".join(problems)


def test_renders_do_not_depend_on_the_machine(tmp_path, monkeypatch):
    # ids must travel: the same renders from another working directory
    monkeypatch.chdir(tmp_path)
    assert renders() == json.loads(GOLDEN.read_text())


if __name__ == "__main__":
    GOLDEN.write_text(json.dumps(renders(), indent=1, sort_keys=True) + "\n")
    print(f"wrote {GOLDEN} for recipe versions {RECIPE_VERSIONS}", file=sys.stderr)
