"""surface/ as layers, held by parsing its modules (imports inside functions count too): the plain
types and the units table at the bottom import no other surface module; a spec is data, so spec.py
imports only those; files are opened by readers.py (and hashed by the builder). That no module is
in an import cycle is tests/test_import_rules.py's test (find_cycle); surface_graph is shown to give
it a cycle that only an import inside a function closes."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.test_import_rules import find_cycle, imported_modules

SURFACE = Path(__file__).resolve().parents[1] / "src" / "interphase" / "surface"
PREFIX = "interphase.surface."

#: module → the surface modules it may import at most (the bottom layers and the spec)
ONLY = {
    "units": set(),
    "base": set(),
    "spec": {"base", "units"},
}
#: the modules that read files (open them, or hand a path to SurfaceTopography)
READERS = {"readers", "builder"}


def surface_graph(sources: dict[str, str]) -> dict[str, set[str]]:
    """module (short name) → the surface modules it imports, anywhere in its body."""
    graph = {}
    for name, source in sources.items():
        deps = set()
        for _, target in imported_modules(source, PREFIX + name):
            if not target.startswith(PREFIX):
                continue
            short = target[len(PREFIX):].split(".")[0]     # profiles.Profile → profiles
            if short in sources and short != name:
                deps.add(short)
        graph[name] = deps
    return graph


def _sources() -> dict[str, str]:
    return {p.stem: p.read_text() for p in sorted(SURFACE.glob("*.py")) if p.stem != "__init__"}


def test_the_bottom_layers_and_the_spec_import_only_what_is_below_them():
    graph = surface_graph(_sources())
    for module, allowed in ONLY.items():
        assert graph[module] <= allowed, f"surface/{module}.py imports {sorted(graph[module] - allowed)}"


def test_only_the_reader_and_the_builder_open_files():
    openers = {name for name, source in _sources().items()
               if "SurfaceTopography import open_topography" in source or "read_bytes(" in source
               or "open(path" in source or "open(p" in source}
    assert openers <= READERS, f"files opened outside readers.py/builder.py: {sorted(openers - READERS)}"


@pytest.mark.parametrize("sources", [
    {"a": "from interphase.surface.b import f\n", "b": "def g():\n    from interphase.surface.a import h\n"},
    {"a": "from .b import f\n", "b": "from .c import g\n", "c": "def k():\n    from . import a\n"},
    {"a": "import interphase.surface.b\n", "b": "def k():\n    import interphase.surface.a as x\n"},
])
def test_the_checker_finds_a_cycle_closed_inside_a_function(sources):
    assert find_cycle(surface_graph(sources)) is not None


def test_the_checker_passes_a_chain():
    sources = {"a": "from interphase.surface.b import f\n", "b": "def g():\n    from .c import h\n", "c": "import numpy\n"}
    assert surface_graph(sources) == {"a": {"b"}, "b": {"c"}, "c": set()}
    assert find_cycle(surface_graph(sources)) is None
