"""The house rules of the design, held by parsing every module (imports inside functions count too):
surface/, analysis/ and io/ import nothing from engines/, campaign/, report/ or cli; engines/ imports
nothing from campaign/, report/ or cli; campaign/ imports nothing from report/, cli, cli_soils or api
(the result format is the campaign's: campaign/results.py); the CLI (cli, cli_soils, cli_text)
imports of the package only the API (interphase.api*), interphase.errors, interphase.version and its
own modules, so every command runs through the API; and no two modules of src/interphase import each
other, directly or round a circle; no function (or method) of src/interphase is longer
than MAX_FUNCTION_LINES. The checkers are shown to flag each kind of import and function they must
see."""

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
    "campaign": ("report", "cli", "cli_soils", "api"),
}

#: the CLI's modules, and all they may import of the package (the package itself is the API too)
CLI_MODULES = ("cli", "cli_soils", "cli_text")
CLI_ALLOWED = ("api", "errors", "version", *CLI_MODULES)


def _module_name(path: Path) -> str:
    parts = path.relative_to(SRC.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _from_target(node: ast.ImportFrom, package: str) -> str:
    """The absolute module a `from ... import` names, relative levels resolved against `package`."""
    if not node.level:
        return node.module
    base = package.split(".")
    base = base[:len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def imported_modules(source: str, module: str, is_package: bool = False) -> list[tuple[int, str]]:
    """(line, absolute dotted name) of everything `source` imports, relative imports resolved
    against `module`; `from a import b` yields a.b as well as a (b may be a submodule)."""
    out = []
    package = module if is_package else module.rpartition(".")[0]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            target = _from_target(node, package)
            out.append((node.lineno, target))
            out += [(node.lineno, f"{target}.{alias.name}") for alias in node.names if alias.name != "*"]
    return out


def violations(source: str, module: str, is_package: bool = False) -> list[str]:
    """The imports of `source` (module `module`, e.g. interphase.io.yade) that break FORBIDDEN, or,
    in a CLI module, reach past CLI_ALLOWED."""
    layer = module.split(".")[1] if module.count(".") >= 1 else ""
    banned = FORBIDDEN.get(layer, ())
    bad = []
    for line, name in imported_modules(source, module, is_package):
        parts = name.split(".")
        if parts[0] != PACKAGE or len(parts) == 1:
            continue
        if parts[1] in banned or (layer in CLI_MODULES and parts[1] not in CLI_ALLOWED):
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
    ("interphase.campaign.restore", "from interphase.report.build import RUN_COLUMNS\n"),
    ("interphase.campaign.validate", "def f():\n    from interphase.api import ensembles\n"),
    ("interphase.campaign.validate", "def f():\n    from interphase import api\n"),
    ("interphase.campaign.run", "from ..cli_soils import main\n"),
    ("interphase.io.liggghts", "from interphase.engines.base import Results\n"),
    ("interphase.io.liggghts", "import interphase.campaign.store as st\n"),
    ("interphase.analysis.summary", "from interphase import report\n"),
    ("interphase.analysis.summary", "def f():\n    from interphase.cli import main\n"),
    ("interphase.surface.trace", "from ..engines import base\n"),
    ("interphase.surface.trace", "from ..engines.base import Results\n"),
    ("interphase.engines.yade", "from interphase.campaign.runner import run_case\n"),
    ("interphase.engines.yade", "from interphase.report.build import build_report\n"),
    ("interphase.engines.yade", "from .. import cli\n"),
    # the CLI reaches the package only through the API
    ("interphase.cli", "from interphase.campaign.runner import run_single\n"),
    ("interphase.cli", "from interphase import answer\n"),
    ("interphase.cli", "from .surface.readers import read_scan\n"),
    ("interphase.cli_soils", "def f():\n    from interphase.soil import load_card\n"),
    ("interphase.cli_text", "import interphase.report.verification as v\n"),
])
def test_the_checker_flags_a_forbidden_import(module, source):
    assert violations(source, module), f"{source!r} in {module} was not flagged"


@pytest.mark.parametrize("module, source", [
    ("interphase.io.liggghts", "from interphase.tables import CONTACT_COLUMNS\n"),
    ("interphase.analysis.quasistatic", "from interphase.case import Case\n"),
    ("interphase.analysis.stress", "from interphase.surface.builder import from_spec\n"),
    ("interphase.engines.liggghts", "from interphase.io.liggghts import read_folder\n"),
    ("interphase.campaign.runner", "from interphase.engines.base import get_engine\n"),
    ("interphase.cli", "from interphase import api\nfrom interphase.errors import InputError\n"),
    ("interphase.cli", "from interphase.version import __version__\nfrom interphase.cli_soils import add_soils\n"),
    ("interphase.cli_soils", "def f():\n    from interphase.api.soils import records\n    import pandas\n"),
    ("interphase.cli", "import argparse\nfrom . import cli_text\n"),
    ("interphase.report.build", "from interphase.campaign.results import open_campaign\n"),
    ("interphase.campaign.sequential", "from interphase.analysis.ensemble_table import ensemble_tables\n"),
    ("interphase.surface.trace", "from .profiles import Profile\n"),
    ("interphase.io.yade", "import json\nfrom pathlib import Path\n"),
])
def test_the_checker_lets_allowed_imports_pass(module, source):
    assert violations(source, module) == []


# ---- no import cycle -------------------------------------------------------------------------
def module_graph(sources: dict[str, tuple[str, bool]]) -> dict[str, set[str]]:
    """module → the modules (keys of `sources`: dotted name → (source, is it a package's
    __init__)) it imports anywhere in its body. `from p import x` is an import of p.x when that is a
    module, else of p (x being a name defined there); `import p.q` of p.q."""
    graph = {}
    for module, (source, is_package) in sources.items():
        package = module if is_package else module.rpartition(".")[0]
        deps = set()
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, ast.Import):
                deps |= {a.name for a in node.names if a.name in sources}
            elif isinstance(node, ast.ImportFrom):
                target = _from_target(node, package)
                for a in node.names:
                    if f"{target}.{a.name}" in sources:
                        deps.add(f"{target}.{a.name}")
                    elif target in sources:
                        deps.add(target)
        graph[module] = deps - {module}
    return graph


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import cycle as [a, b, …, a], or None (depth-first search, white/grey/black)."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for dep in sorted(graph.get(node, ())):
            if state.get(dep) == 1:
                return stack[stack.index(dep):] + [dep]
            if dep not in state:
                found = visit(dep)
                if found:
                    return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state:
            found = visit(node)
            if found:
                return found
    return None


def test_no_import_cycle_between_modules():
    graph = module_graph({_module_name(p): (p.read_text(), p.name == "__init__.py") for p in _modules()})
    assert len(graph) > 50
    cycle = find_cycle(graph)
    assert cycle is None, "import cycle (imports inside functions counted): " + " → ".join(cycle)


@pytest.mark.parametrize("sources", [
    {"interphase.a": "from interphase.b import f\n", "interphase.b": "def g():\n    from interphase.a import h\n"},
    {"interphase.p.a": "from .b import f\n", "interphase.p.b": "from .c import g\n",
     "interphase.p.c": "def k():\n    from . import a\n"},
    {"interphase.a": "import interphase.b\n", "interphase.b": "def k():\n    import interphase.a as x\n"},
    # through a package's __init__: `from interphase import __version__` imports interphase/__init__.py
    {"interphase": ("from interphase.api import run\n", True), "interphase.api": "def f():\n    from interphase.r import g\n",
     "interphase.r": "from interphase import __version__\n"},
])
def test_the_cycle_checker_finds_a_cycle_closed_inside_a_function(sources):
    sources = {k: v if isinstance(v, tuple) else (v, False) for k, v in sources.items()}
    assert find_cycle(module_graph(sources)) is not None


def test_the_cycle_checker_passes_a_chain():
    sources = {"interphase": ("from interphase.version import __version__\n", True),
               "interphase.a": ("from interphase.b import f\nfrom interphase import __version__\n", False),
               "interphase.b": ("def g():\n    from .c import h\n", False),
               "interphase.c": ("import numpy\nfrom interphase.version import __version__\n", False),
               "interphase.version": ("__version__ = '0'\n", False)}
    assert module_graph(sources) == {"interphase": {"interphase.version"}, "interphase.a": {"interphase.b", "interphase"},
                                     "interphase.b": {"interphase.c"}, "interphase.c": {"interphase.version"},
                                     "interphase.version": set()}
    assert find_cycle(module_graph(sources)) is None


# ---- no long function ------------------------------------------------------------------------
#: the longest function (def line to last line, decorators not counted) a newcomer is asked to read
MAX_FUNCTION_LINES = 80


def long_functions(source: str, where: str, limit: int = MAX_FUNCTION_LINES) -> list[str]:
    """`where:line name (n lines)` of every function or method of `source` longer than `limit`
    lines, nested ones included."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            n = node.end_lineno - node.lineno + 1
            if n > limit:
                out.append(f"{where}:{node.lineno} {node.name} ({n} lines)")
    return out


def test_no_function_is_longer_than_the_limit():
    bad = []
    for path in _modules():
        bad += long_functions(path.read_text(), str(path.relative_to(SRC.parent)))
    assert not bad, f"functions over {MAX_FUNCTION_LINES} lines (split them):\n" + "\n".join(bad)


def test_the_length_checker_names_a_long_function_and_method():
    def body(n: int, indent: str) -> str:
        return "".join(f"{indent}x{i} = {i}\n" for i in range(n))

    # `edge` is exactly at the limit (its def and 79 lines), `long` one over it (its def and 80)
    source = ("def short():\n    pass\n\n\nclass K:\n    async def long(self):\n" + body(80, " " * 8)
              + "\n\ndef edge():\n" + body(79, " " * 4))
    assert long_functions(source, "m.py") == ["m.py:6 long (81 lines)"]
