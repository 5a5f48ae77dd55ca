"""The house rules of the design, held by parsing every module (imports inside functions count too):
surface/, analysis/ and io/ import nothing from engines/, campaign/, report/ or cli; engines/ imports
nothing from campaign/, report/ or cli. The checker is shown to flag each kind of import it must see."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "interphase"
PACKAGE = "interphase"

#: layer → the layers it must not import
FORBIDDEN = {
    "surface": ("engines", "campaign", "report", "cli"),
    "analysis": ("engines", "campaign", "report", "cli"),
    "io": ("engines", "campaign", "report", "cli"),
    "engines": ("campaign", "report", "cli"),
}


def _module_name(path: Path) -> str:
    parts = path.relative_to(SRC.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported_modules(source: str, module: str, is_package: bool = False) -> list[tuple[int, str]]:
    """(line, absolute dotted name) of everything `source` imports, relative imports resolved
    against `module`; `from a import b` yields a.b as well as a (b may be a submodule)."""
    out = []
    package = module if is_package else module.rpartition(".")[0]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            out.append((node.lineno, target))
            out += [(node.lineno, f"{target}.{alias.name}") for alias in node.names if alias.name != "*"]
    return out


def violations(source: str, module: str, is_package: bool = False) -> list[str]:
    """The imports of `source` (module `module`, e.g. interphase.io.yade) that break FORBIDDEN."""
    layer = module.split(".")[1] if module.count(".") >= 1 else ""
    banned = FORBIDDEN.get(layer, ())
    bad = []
    for line, name in imported_modules(source, module, is_package):
        parts = name.split(".")
        if parts[0] == PACKAGE and len(parts) > 1 and parts[1] in banned:
            bad.append(f"{module}:{line} imports {name}")
    return sorted(set(bad))


def _modules():
    return sorted(p for p in SRC.rglob("*.py") if "__pycache__" not in p.parts)


def test_every_module_keeps_the_house_rules():
    bad = []
    for path in _modules():
        bad += violations(path.read_text(), _module_name(path), path.name == "__init__.py")
    assert not bad, "imports breaking the layer rules:\n" + "\n".join(bad)


def test_the_rules_cover_every_layer_present():
    layers = {p.relative_to(SRC).parts[0] for p in _modules() if len(p.relative_to(SRC).parts) > 1}
    assert set(FORBIDDEN) <= layers


@pytest.mark.parametrize("module, source", [
    ("interphase.io.liggghts", "from interphase.engines.base import Results\n"),
    ("interphase.io.liggghts", "import interphase.campaign.store as st\n"),
    ("interphase.analysis.summary", "from interphase import report\n"),
    ("interphase.analysis.summary", "def f():\n    from interphase.cli import main\n"),
    ("interphase.surface.trace", "from ..engines import base\n"),
    ("interphase.surface.trace", "from ..engines.base import Results\n"),
    ("interphase.engines.yade", "from interphase.campaign.runner import run_case\n"),
    ("interphase.engines.yade", "from interphase.report.build import build_report\n"),
    ("interphase.engines.yade", "from .. import cli\n"),
])
def test_the_checker_flags_a_forbidden_import(module, source):
    assert violations(source, module), f"{source!r} in {module} was not flagged"


@pytest.mark.parametrize("module, source", [
    ("interphase.io.liggghts", "from interphase.tables import CONTACT_COLUMNS\n"),
    ("interphase.analysis.quasistatic", "from interphase.case import Case\n"),
    ("interphase.analysis.stress", "from interphase.surface.builder import from_spec\n"),
    ("interphase.engines.liggghts", "from interphase.io.liggghts import read_folder\n"),
    ("interphase.campaign.runner", "from interphase.engines.base import get_engine\n"),
    ("interphase.cli", "from interphase.campaign.runner import run_single\n"),
    ("interphase.surface.trace", "from .profiles import Profile\n"),
    ("interphase.io.yade", "import json\nfrom pathlib import Path\n"),
])
def test_the_checker_lets_allowed_imports_pass(module, source):
    assert violations(source, module) == []
