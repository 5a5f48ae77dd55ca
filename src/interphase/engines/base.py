"""The engine contract (ASE genericfileio style): a template that writes input, executes and reads
results, plus a profile that knows how this machine launches the binary.

    files = engine.write_input(case, folder)   # {relative path: text or bytes}; also written
    engine.execute(folder)                     # subprocess, cwd=folder, logs to files; EngineError
    results = engine.read_results(folder)      # Results(contacts, history) in the analysis frame

`render(case)` returns the same file map without touching the disk (dry runs, golden tests). An
engine serialises the case's device (engines/device.py) in its own formats and writes recipe.json
(interphase.recipe) beside them; everything else it keeps is what is truly its own: its command
line, the output files it must leave, its log classifier and the pattern of its version banner.
"""

from __future__ import annotations

import abc
import dataclasses
import functools
import hashlib
import json
import os
import re
import shlex
import shutil
import signal
import subprocess
import tempfile
import threading
from dataclasses import dataclass, field
from pathlib import Path

from interphase.case import Case
from interphase.errors import InputError
from interphase.recipe import RECIPE, RECIPE_VERSIONS, Recipe, read_record
from interphase.tables import Results

#: classified causes of an engine failure
CAUSES = ("lost_atoms", "not_consolidated", "bad_mesh", "timeout", "killed", "crashed", "engine_error",
          "missing_output", "not_installed")
#: signals an engine dies of by itself (a crash), not sent from outside
CRASH_SIGNALS = tuple(getattr(signal, n) for n in ("SIGSEGV", "SIGBUS", "SIGFPE", "SIGILL", "SIGABRT")
                      if hasattr(signal, n))


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


@dataclass(frozen=True)
class EngineProfile:
    """How this machine launches an engine binary. Read from env, never from templates.

    `launcher` is a prefix such as ("mpirun", "-np", "2"); `threads` sets OMP_NUM_THREADS (and
    YADE's -j); `env` adds environment variables; `version`, when given, is used instead of asking
    the binary (a machine where the binary cannot be probed, e.g. behind a launcher)."""

    binary: str
    launcher: tuple[str, ...] = ()
    threads: int = 1
    timeout: float | None = None   # seconds; None: the estimate from the case's recipe.json
    env: tuple[tuple[str, str], ...] = field(default=())
    version: str | None = None

    @classmethod
    def from_env(cls, engine: str) -> "EngineProfile":
        """INTERPHASE_<ENGINE>_BINARY (default: the engine's name), _LAUNCHER (split as a shell
        would), _THREADS (an integer, default 1) and _TIMEOUT (seconds, default: estimated)."""
        prefix = f"INTERPHASE_{engine.upper()}_"
        threads = os.environ.get(prefix + "THREADS", "1")
        try:
            n = int(threads)
        except ValueError:
            raise InputError(f"{prefix}THREADS={threads!r} is not an integer", where="environment",
                             fix=f"set {prefix}THREADS to a thread count such as 1 or 2") from None
        timeout = os.environ.get(prefix + "TIMEOUT")
        return cls(binary=os.environ.get(prefix + "BINARY", engine),
                   launcher=tuple(shlex.split(os.environ.get(prefix + "LAUNCHER", ""))), threads=n,
                   timeout=float(timeout) if timeout is not None else None)


class Engine(abc.ABC):
    name: str = ""
    label: str = ""                      # the engine's name in messages ("LIGGGHTS")
    outputs: tuple[str, ...] = ()        # files a finished run must leave in its folder
    version_args: tuple[str, ...] = ("--version",)
    version_pattern: str = ""            # regex whose group 1 is the version in the binary's output
    version_format: str = "{}"
    template_suffix: str = ""            # of the templates interface_shear<suffix>, direct_shear<suffix>

    def __init__(self, profile: EngineProfile | None = None, templates: str | os.PathLike | None = None,
                 recipe: Recipe = RECIPE, recipe_version: int | None = None):
        self.profile = profile or self.default_profile()
        self.templates = Path(templates) if templates else template_root() / self.name
        self.recipe = recipe
        #: this engine's number in interphase.recipe.RECIPE_VERSIONS unless given (recipe_id)
        self.recipe_version = recipe_version

    # -- machine side
    @classmethod
    def default_profile(cls) -> EngineProfile:
        return EngineProfile.from_env(cls.name)

    def version(self) -> str:
        """Engine version string (provenance in case.json): the profile's, else from the binary's
        banner ('not-installed', 'unknown' when it cannot be read)."""
        if self.profile.version:
            return self.profile.version
        path = shutil.which(self.profile.binary)
        if path is None:
            return "not-installed"
        out = _banner(path, self.version_args)
        m = re.search(self.version_pattern, out) if out is not None else None
        return self.version_format.format(m.group(1).strip()) if m else "unknown"

    def recipe_id(self) -> str:
        """Short SHA-256 of what decides this engine's case folders besides the Case: the engine's
        name, its recipe version (its number in interphase.recipe.RECIPE_VERSIONS unless the engine
        was built with another) and the Recipe's values. Code and templates are not hashed (a refactor
        that writes the same inputs keeps every finished case); a change that alters what an engine is
        given must bump its number, which tests/test_recipe_version.py enforces. The engine binary's
        version is provenance (case.json), not identity."""
        version = RECIPE_VERSIONS[self.name] if self.recipe_version is None else self.recipe_version
        payload = {"engine": self.name, "version": version, "recipe": self.recipe.to_dict()}
        return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:16]

    # -- the contract
    def template_name(self, case: Case) -> str:
        return ("interface_shear" if case.test == "interface" else "direct_shear") + self.template_suffix

    @abc.abstractmethod
    def render(self, case: Case) -> dict[str, str | bytes]:
        """Every input file of the case as data: {relative path: content}, recipe.json included."""

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
    def arguments(self, binary: str) -> list[str]:
        """The command line after the profile's launcher, `binary` resolved on PATH."""

    def command(self) -> list[str]:
        binary = shutil.which(self.profile.binary) or self.profile.binary
        return [*self.profile.launcher, *self.arguments(binary)]

    def environment(self) -> dict[str, str]:
        """The run's environment: this process's, the profile's additions, OMP_NUM_THREADS."""
        return dict(os.environ, **dict(self.profile.env), OMP_NUM_THREADS=str(self.profile.threads))

    @abc.abstractmethod
    def diagnose(self, folder: Path, returncode: int) -> tuple[str | None, str]:
        """(cause, message) of a run that ended with `returncode`, from its log and files; cause
        None if it succeeded."""

    def timeout_for(self, folder: str | os.PathLike) -> float:
        """The profile's time limit, else recipe.json's estimate: timeout_base + timeout_factor ×
        the most steps the run can take × grains / the engine's assumed throughput [s]."""
        if self.profile.timeout is not None:
            return self.profile.timeout
        rec = read_record(folder)
        r = rec.recipe
        return r.timeout_base + r.timeout_factor * rec.steps.most * rec.n_grains / r.throughput(self.name)

    def execute(self, folder: str | os.PathLike) -> None:
        """Run the engine with cwd = folder; raise EngineError on failure (not_installed, timeout,
        the causes `diagnose` finds, missing_output)."""
        folder = Path(folder)
        cmd = self.command()
        if shutil.which(self.profile.binary) is None:
            raise EngineError("not_installed", f"{self.label} binary {self.profile.binary!r} not found",
                              command=cmd, folder=folder)
        rc = run_logged(cmd, folder, self.environment(), self.timeout_for(folder), self.label)
        log = folder / "engine.log"
        cause, message = self.diagnose(folder, rc)
        if rc is not None and rc < 0 and cause in ("killed", "engine_error"):
            cause, message = died_of_signal(self.label, -rc)
        if cause:
            raise EngineError(cause, message, command=cmd, returncode=rc, log_tail=log_tail(log), folder=folder)
        for name in self.required_outputs(folder):
            if not (folder / name).exists():
                raise EngineError("missing_output", f"{self.label} finished without writing {name}", command=cmd,
                                  returncode=rc, log_tail=log_tail(log), folder=folder)

    def required_outputs(self, folder: Path) -> tuple[str, ...]:
        """The files the run in `folder` must leave (an engine whose tests leave different files
        overrides it)."""
        return self.outputs

    @abc.abstractmethod
    def read_results(self, folder: str | os.PathLike) -> Results:
        """ContactTable + History of a finished run, in the analysis frame."""


def died_of_signal(label: str, sig: int) -> tuple[str, str]:
    """(cause, message) of an engine ended by signal `sig`: 'crashed' for a signal a process raises
    itself (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT), else 'killed' (sent from outside)."""
    try:
        name = signal.Signals(sig).name
    except ValueError:
        name = f"signal {sig}"
    what = f"{name}, {signal.strsignal(sig) or 'unknown signal'}"
    if sig in CRASH_SIGNALS:
        return "crashed", f"{label} crashed ({what}): its output is not used"
    return "killed", (f"{label} was killed by {what} from outside (the out-of-memory killer, an administrator, "
                      "a batch system)")


@functools.lru_cache(maxsize=None)
def _banner(path: str, args: tuple[str, ...]) -> str | None:
    """stdout of `path *args`, run in a scratch folder (LIGGGHTS writes log.liggghts into its cwd);
    None if it could not run. Cached per binary."""
    try:
        with tempfile.TemporaryDirectory() as tmp:
            return subprocess.run([path, *args], capture_output=True, text=True, timeout=60, cwd=tmp,
                                  stdin=subprocess.DEVNULL).stdout
    except (OSError, subprocess.TimeoutExpired):
        return None


def template_root() -> Path:
    """Templates shipped in the wheel (interphase/templates) or, in a source checkout, ./templates."""
    packaged = Path(__file__).resolve().parents[1] / "templates"
    if packaged.is_dir():
        return packaged
    return Path(__file__).resolve().parents[3] / "templates"


def not_consolidated(text: str) -> str | None:
    """The 'NOT CONSOLIDATED: …' line both engines' drivers print when the consolidation loop ran
    out with the platen force outside its band (engines.device; the shear was skipped), else None."""
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


def engine_class(name: str) -> type[Engine]:
    """The Engine class of a name ('liggghts' | 'yade'); InputError for another."""
    import importlib

    if name not in _REGISTRY:
        try:
            importlib.import_module(f"interphase.engines.{name}")
        except ModuleNotFoundError:
            pass
    if name not in _REGISTRY:
        raise InputError(f"unknown engine {name!r}", where="engine", fix="use liggghts or yade")
    return _REGISTRY[name]


def get_engine(name: str, **kwargs) -> Engine:
    """Engine by name ('liggghts' | 'yade')."""
    return engine_class(name)(**kwargs)


@dataclass(frozen=True)
class EngineSpec:
    """An engine as a value: its class, this machine's profile, the Recipe and the recipe version
    (with `options`, further keyword arguments of the class). Frozen and picklable (the class by
    reference), so that it travels from the plan to the executors' workers (a pool's spawned
    processes, SLURM jobs), which build the very engine the plan's ids were hashed with
    (`build()`) instead of looking a name up again. `engine_spec(name)` makes the one a name
    stands for; a test passes another (a bumped recipe version, a test-only engine class)."""

    cls: type[Engine]
    profile: EngineProfile
    recipe: Recipe = RECIPE
    recipe_version: int = 0
    options: tuple[tuple[str, object], ...] = ()

    @property
    def name(self) -> str:
        return self.cls.name

    def build(self) -> Engine:
        return self.cls(profile=self.profile, recipe=self.recipe, recipe_version=self.recipe_version,
                        **dict(self.options))

    def recipe_id(self) -> str:
        """The recipe id of the engine it builds (Engine.recipe_id); runs no binary."""
        return self.build().recipe_id()


def engine_spec(engine: "str | EngineSpec", **changes) -> EngineSpec:
    """The EngineSpec a name stands for on this machine: its registered class, its profile from the
    environment (EngineProfile.from_env), the Recipe and its RECIPE_VERSIONS number; `changes`
    replace fields. An EngineSpec is returned as it is (with `changes` applied)."""
    if isinstance(engine, EngineSpec):
        return dataclasses.replace(engine, **changes) if changes else engine
    cls = engine_class(engine)
    spec = EngineSpec(cls, cls.default_profile(), RECIPE, RECIPE_VERSIONS[cls.name])
    return dataclasses.replace(spec, **changes) if changes else spec


def _hold_signals(held: list[int]) -> dict:
    """Replace the SIGINT and SIGTERM handlers by one that appends the signal to `held`; returns the
    handlers to restore. Around Popen: a signal handled while Popen waits for the child's exec raises
    out of Popen after the fork, and the engine runs on in its own session with no one holding its
    pid (seen as an engine left running after `campaign stop`). Handlers exist in the main thread
    only; elsewhere none run, and nothing is held."""
    if threading.current_thread() is not threading.main_thread():
        return {}
    return {s: signal.signal(s, lambda signum, frame: held.append(signum))
            for s in (signal.SIGINT, signal.SIGTERM)}


def _release(handlers: dict, held: list[int]) -> None:
    """Restore the handlers `_hold_signals` replaced, then raise the signals it held through them."""
    for s, handler in handlers.items():
        signal.signal(s, handler)
    for signum in held:
        signal.raise_signal(signum)


def _kill_group(proc: subprocess.Popen) -> None:
    """SIGKILL the engine's session and reap it. An engine gone before its setsid has no group: a
    Ctrl-C to the campaign's group reaches a child forked a moment before it left that group, and it
    dies there, before exec (seen: ProcessLookupError recorded as a failed case)."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait()


def run_logged(cmd: list[str], folder: Path, env: dict, timeout: float, name: str) -> int:
    """Run an engine: cwd = folder (never chdir), stdout + stderr to folder/engine.log, in its own
    session so that a timeout or an interruption kills the whole process group. Returns the return
    code; a timeout raises EngineError('timeout') with the log tail."""
    log = Path(folder) / "engine.log"
    with open(log, "wb") as out:
        held: list[int] = []
        handlers = _hold_signals(held)
        try:
            proc = subprocess.Popen(cmd, cwd=folder, stdout=out, stderr=subprocess.STDOUT, env=env,
                                    stdin=subprocess.DEVNULL, start_new_session=True)
        except BaseException:
            _release(handlers, held)        # an interruption outranks the failed start
            raise
        try:
            _release(handlers, held)    # inside the try: a signal from here on kills the engine
            return proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            _kill_group(proc)
            raise EngineError("timeout", f"{name} ran longer than {timeout:.0f} s", command=cmd,
                              log_tail=log_tail(log), folder=folder) from None
        except BaseException:
            _kill_group(proc)
            raise
