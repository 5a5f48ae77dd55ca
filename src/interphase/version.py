"""The package's version (pyproject.toml says the same), in a module of its own so that any module
can read it without importing the package's API (interphase/__init__.py imports interphase.api)."""

__version__ = "0.1.0"
