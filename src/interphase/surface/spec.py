"""ProfileSpec: the engine-free reference to a surface profile that a Case carries.

A spec is data (hashable, canonical), not the profile itself: `interphase.surface.profiles.from_spec`
builds the Profile. Sizes in `params` are in D50 units (docs/methods.md §1); a file spec carries the
file's SHA-256 so that a case's identity follows the file's content, not its path.

kinds and their params:
  flat      —
  sawtooth  rt, sw, sr           (Groups 1–3: height, width, flat spacing; D50 units)
  random    au, ar, rtmax, seed  (Group 4; D50 units, integer seed)
  file      path, units, sha256 (+ optional cutoff: Gaussian filter cut-off in m)
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field
from pathlib import Path

from interphase.errors import InputError

KIND_PARAMS = {
    "flat": (),
    "sawtooth": ("rt", "sw", "sr"),
    "random": ("au", "ar", "rtmax", "seed"),
    "file": (),
}
UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6}


def file_sha256(path: str | Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


@dataclass(frozen=True)
class ProfileSpec:
    kind: str
    params: tuple[tuple[str, float], ...] = ()
    path: str | None = None
    units: str = "m"
    sha256: str | None = None
    cutoff: float | None = None  # Gaussian filter cut-off wavelength [m], file profiles only
    where: str = field(default="profile", compare=False, repr=False)

    def __post_init__(self):
        if self.kind not in KIND_PARAMS:
            raise InputError(f"unknown profile kind {self.kind!r}", where=f"{self.where}.kind",
                             fix=f"use one of {', '.join(KIND_PARAMS)}")
        names = dict(self.params)
        need = KIND_PARAMS[self.kind]
        for key in need:
            if key not in names:
                raise InputError(f"missing {key!r} for a {self.kind} profile", where=f"{self.where}.{key}",
                                 fix=f"a {self.kind} profile needs {', '.join(need)} (D50 units)")
        for key, value in self.params:
            if key not in need:
                raise InputError(f"unknown parameter {key!r} for a {self.kind} profile",
                                 where=f"{self.where}.{key}", fix=f"allowed: {', '.join(need) or 'none'}")
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise InputError(f"{key} must be a finite number, got {value!r}", where=f"{self.where}.{key}")
        if self.kind == "sawtooth":
            if names["rt"] <= 0 or names["sw"] <= 0 or names["sr"] < 0:
                raise InputError("need rt > 0, sw > 0, sr ≥ 0 (D50 units)", where=self.where)
        if self.kind == "random":
            if names["au"] <= 0 or names["ar"] <= 0 or names["rtmax"] <= 0:
                raise InputError("need au > 0, ar > 0, rtmax > 0 (D50 units)", where=self.where)
            if int(names["seed"]) != names["seed"]:
                raise InputError("seed must be an integer", where=f"{self.where}.seed")
        if self.kind == "file":
            if not self.path:
                raise InputError("a file profile needs a path", where=f"{self.where}.path")
            if self.units not in UNITS:
                raise InputError(f"unknown units {self.units!r}", where=f"{self.where}.units",
                                 fix=f"use one of {', '.join(UNITS)}")
            if self.cutoff is not None and not (math.isfinite(self.cutoff) and self.cutoff > 0):
                raise InputError("cutoff must be a positive length in m", where=f"{self.where}.cutoff")

    @classmethod
    def make(cls, kind: str, where: str = "profile", **params) -> "ProfileSpec":
        """Generated profile from keyword params, e.g. ProfileSpec.make('sawtooth', rt=1, sw=2, sr=0)."""
        return cls(kind=kind, params=tuple(sorted(params.items())), where=where)

    @classmethod
    def from_file(cls, path: str | Path, units: str = "m", cutoff: float | None = None,
                  where: str = "profile") -> "ProfileSpec":
        p = Path(path)
        if not p.is_file():
            raise InputError(f"profile file {str(p)!r} does not exist", where=f"{where}.path",
                             fix="give the path of an existing profile file (relative to the campaign file)")
        return cls(kind="file", path=str(p), units=units, sha256=file_sha256(p), cutoff=cutoff, where=where)

    def param(self, name: str) -> float:
        return dict(self.params)[name]

    def canonical(self) -> dict:
        """Identity of the profile: content hash, not path, for files."""
        out: dict = {"kind": self.kind}
        if self.params:
            out["params"] = {k: float(v) for k, v in self.params}
        if self.kind == "file":
            out.update(sha256=self.sha256, units=self.units, cutoff=self.cutoff)
        return out

    def label(self) -> str:
        if self.kind == "file":
            return Path(self.path).stem
        if not self.params:
            return self.kind
        return self.kind + "-" + "-".join(f"{k}{v:g}" for k, v in self.params)
