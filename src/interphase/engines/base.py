"""The engine contract (ASE genericfileio style): a template that writes input, executes and reads
results, plus a profile that knows how this machine launches the binary.

    files = engine.write_input(case, folder)   # {relative path: text or bytes}; also written
    engine.execute(folder)                     # subprocess, cwd=folder, logs to files; EngineError
    results = engine.read_results(folder)      # Results(contacts, history) in the analysis frame

`render(case)` returns the same file map without touching the disk (dry runs, golden tests).
"""

from __future__ import annotations

import abc
import ast
import functools
import hashlib
import inspect
import os
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from interphase.case import Case

#: classified causes of an engine failure
CAUSES = ("lost_atoms", "not_consolidated", "bad_mesh", "timeout", "killed", "engine_error", "missing_output",
          "not_installed")


class EngineError(RuntimeError):
    """An engine run failed. Carries the command, return code, a classified cause and the log tail."""

    def __init__(self, cause: str, message: str, *, command=None, returncode=None, log_tail: str = "",
                 folder: str | os.PathLike | None = None):
        self.cause = cause
        self.command = command
        self.returncode = returncode
        self.log_tail = log_tail
        self.folder = str(folder) if folder is not None else None
        text = f"[{cause}] {message}"
        if returncode is not None:
            text += f" (return code {returncode})"
        if log_tail:
            text += "\n--- log tail ---\n" + log_tail
        super().__init__(text)

    def to_dict(self) -> dict:
        return {"cause": self.cause, "message": str(self).split("\n", 1)[0], "returncode": self.returncode,
                "command": self.command if self.command is None else [str(c) for c in self.command],
                "log_tail": self.log_tail}


@dataclass
class Results:
    contacts: pd.DataFrame   # interphase.tables.CONTACT_COLUMNS
    history: pd.DataFrame    # interphase.tables.HISTORY_COLUMNS
    particles: pd.DataFrame | None = None  # interphase.tables.PARTICLE_COLUMNS


@dataclass(frozen=True)
class EngineProfile:
    """How this machine launches an engine binary. Read from env, never from templates.

    `launcher` is a prefix such as ("mpirun", "-np", "2"); `threads` sets OMP_NUM_THREADS."""

    binary: str
    launcher: tuple[str, ...] = ()
    threads: int = 1
    timeout: float | None = None   # seconds; None: the engine's estimate from the case
    env: tuple[tuple[str, str], ...] = field(default=())


class Engine(abc.ABC):
    name: str = ""

    def __init__(self, profile: EngineProfile | None = None, templates: str | os.PathLike | None = None):
        self.profile = profile or self.default_profile()
        self.templates = Path(templates) if templates else template_root() / self.name

    # -- machine side
    @classmethod
    @abc.abstractmethod
    def default_profile(cls) -> EngineProfile: ...

    @abc.abstractmethod
    def version(self) -> str:
        """Engine version string (part of every case id)."""

    def template_hash(self) -> str:
        """SHA-256 (short) of the recipe: every template file of this engine (names included) and the
        code of the Python modules that compute the templates' values (the engine's module and
        engines/device.py, render.py), so that a change of physics made in Python (a rolling
        model, a wall height) changes every case id as a template edit does. Code is hashed as its
        syntax tree without docstrings: comments, layout and docstrings do not count."""
        h = hashlib.sha256()
        for p in sorted(self.templates.rglob("*")):
            if p.is_file():
                h.update(p.relative_to(self.templates).as_posix().encode())
                h.update(p.read_bytes())
        here = Path(__file__).parent
        for src in (Path(inspect.getsourcefile(type(self))), here / "device.py", here / "render.py"):
            h.update(src.name.encode())
            h.update(code_digest(src).encode())
        return h.hexdigest()[:16]

    # -- the contract
    @abc.abstractmethod
    def render(self, case: Case) -> dict[str, str | bytes]:
        """Every input file of the case as data: {relative path: content}."""

    def write_input(self, case: Case, folder: str | os.PathLike) -> dict[str, str | bytes]:
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        files = self.render(case)
        for rel, content in files.items():
            target = folder / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            if isinstance(content, bytes):
                target.write_bytes(content)
            else:
                target.write_text(content)
        return files

    @abc.abstractmethod
    def execute(self, folder: str | os.PathLike) -> None:
        """Run the engine with cwd = folder; raise EngineError on failure."""

    @abc.abstractmethod
    def read_results(self, folder: str | os.PathLike) -> Results:
        """ContactTable + History of a finished run, in the analysis frame."""


def template_root() -> Path:
    """Templates shipped in the wheel (interphase/templates) or, in a source checkout, ./templates."""
    packaged = Path(__file__).resolve().parents[1] / "templates"
    if packaged.is_dir():
        return packaged
    return Path(__file__).resolve().parents[3] / "templates"


def not_consolidated(text: str) -> str | None:
    """The 'NOT CONSOLIDATED: …' line both engines' drivers print when the consolidation loop ran
    out with the platen force outside its band (engines.device; the shear was skipped), else None."""
    import re

    m = re.search(r"^NOT CONSOLIDATED: [^\n]*", text, re.MULTILINE)
    return m.group(0) if m else None


def log_tail(path: str | os.PathLike, lines: int = 30) -> str:
    try:
        with open(path, "rb") as fh:
            fh.seek(0, os.SEEK_END)
            size = fh.tell()
            fh.seek(max(0, size - 64 * 1024))
            text = fh.read().decode(errors="replace")
    except OSError:
        return ""
    return "\n".join(text.splitlines()[-lines:])


_REGISTRY: dict[str, type[Engine]] = {}


def register(cls: type[Engine]) -> type[Engine]:
    _REGISTRY[cls.name] = cls
    return cls


def get_engine(name: str, **kwargs) -> Engine:
    """Engine by name ('liggghts' | 'yade')."""
    import importlib

    if name not in _REGISTRY:
        try:
            importlib.import_module(f"interphase.engines.{name}")
        except ModuleNotFoundError:
            pass
    if name not in _REGISTRY:
        from interphase.errors import InputError
        raise InputError(f"unknown engine {name!r}", where="engine", fix="use liggghts or yade")
    return _REGISTRY[name](**kwargs)


def run_logged(cmd: list[str], folder: Path, env: dict, timeout: float, name: str) -> int:
    """Run an engine: cwd = folder (never chdir), stdout + stderr to folder/engine.log, in its own
    session so that a timeout or an interruption kills the whole process group. Returns the return
    code; a timeout raises EngineError('timeout') with the log tail."""
    import signal
    import subprocess

    log = Path(folder) / "engine.log"
    with open(log, "wb") as out:
        proc = subprocess.Popen(cmd, cwd=folder, stdout=out, stderr=subprocess.STDOUT, env=env,
                                stdin=subprocess.DEVNULL, start_new_session=True)
        try:
            return proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            raise EngineError("timeout", f"{name} ran longer than {timeout:.0f} s", command=cmd,
                              log_tail=log_tail(log), folder=folder) from None
        except BaseException:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            raise


def steps_for(duration: float, dt: float, multiple: int = 1) -> int:
    """Time steps covering `duration` [s] at step `dt` [s], rounded up to a multiple of `multiple`
    (decks align stage boundaries with the snapshot interval so dumps fall on them)."""
    import math

    n = max(1, int(math.ceil(duration / dt)))
    return -(-n // multiple) * multiple


@functools.lru_cache(maxsize=None)
def _code_digest(text: str) -> str:
    tree = ast.parse(text)
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if (isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and body
                and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant)
                and isinstance(body[0].value.value, str)):
            node.body = body[1:] or [ast.Pass()]
    return hashlib.sha256(ast.dump(tree).encode()).hexdigest()


def code_digest(path: str | os.PathLike) -> str:
    """SHA-256 of a Python file's syntax tree without docstrings (comments and layout never reach
    the tree): what the code does, not how it is written or explained."""
    return _code_digest(Path(path).read_text())
