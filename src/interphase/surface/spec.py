"""ProfileSpec: the engine-free reference to a surface profile that a Case carries.

A spec is plain data (hashable, canonical; it reads no file), not the profile itself:
`interphase.surface.builder.from_spec` builds the Profile, and `builder.file_spec` builds a file spec
from a user's input (it reads and hashes the file). Sizes in `params` are in D50 units
(docs/methods.md §1); a file spec carries the file's SHA-256 so that a case's identity follows the
file's content, not its path.

kinds and their params:
  flat      —
  sawtooth  rt, sw, sr           (Groups 1–3: height, width, flat spacing; D50 units)
  random    au, ar, rtmax, seed  (Group 4; D50 units, integer seed)
  selfaffine hurst, rms_slope, long_cutoff, short_cutoff, length, seed
                                 (Fourier synthesis through SurfaceTopography: Hurst exponent 0 < H < 1,
                                 rms slope, roll-off and short cut-off wavelengths and the period, D50 units)
  file      path, units, sha256 (+ optional cutoff: Gaussian filter cut-off in m; units None = the
            file's own). A line of a scan (line or areal, any format readers.read_scan reads):
            optional axis "x" | "y" (grid lines along that axis; default x), line (an index, or "k/n":
            the k-th of n lines spread over the scan; default the middle line), direction "+" | "-"
            ("-": the line mirrored, sheared the other way). Specs without them keep their identity.
            An areal scan as the 3D cell's surface (areal = true; surface/patch.py cuts and closes
            its patch): direction "+x" | "-x" | "+y" | "-y" (the soil's motion over the scan; "+" and
            "-" mean "+x" and "-x"; in the identity when not "+x"), optional window (x0, y0) [m]: the
            patch's corner in the file's frame (None: the window whose opposite edges match best;
            in the identity when given), and the patch rule (base.AREAL_PATCH_RULE), always in it.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import PurePath

from interphase.errors import InputError
from interphase.surface.base import AREAL_DIRECTIONS, AREAL_PATCH_RULE, CONTACT_STEP_D50, DIRECTIONS, check_axis
from interphase.surface.units import units_factor

KIND_PARAMS = {
    "flat": (),
    "sawtooth": ("rt", "sw", "sr"),
    "asymmetric": ("rt", "rise", "fall", "sr"),
    "random": ("au", "ar", "rtmax", "seed"),
    "selfaffine": ("hurst", "rms_slope", "long_cutoff", "short_cutoff", "length", "seed"),
    "file": (),
}
_SHA256 = re.compile(r"[0-9a-f]{64}")


@dataclass(frozen=True)
class ProfileSpec:
    kind: str
    params: tuple[tuple[str, float], ...] = ()
    path: str | None = None
    units: str | None = "m"      # None: the file's own units (file profiles)
    sha256: str | None = None
    cutoff: float | None = None  # Gaussian filter cut-off wavelength [m], file profiles only
    axis: str | None = None      # file profiles: grid lines along x | y (None: x, the file's first axis)
    line: int | str | None = None   # file profiles: line index or "k/n" (None: the middle line)
    direction: str = "+"         # file profiles: "+" as measured, "-" mirrored; areal: AREAL_DIRECTIONS
    areal: bool = False          # file profiles: the areal scan as the 3D cell's surface (surface/patch.py)
    window: tuple[float, float] | None = None   # areal: the patch's corner (x0, y0) [m] in the file's frame
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
        if self.kind == "asymmetric":
            if names["rt"] <= 0 or names["rise"] <= 0 or names["fall"] <= 0 or names["sr"] < 0:
                raise InputError("need rt, rise, fall > 0 and sr ≥ 0 (D50 units)", where=self.where)
        if self.kind == "random":
            if names["au"] <= 0 or names["ar"] <= 0 or names["rtmax"] <= 0:
                raise InputError("need au > 0, ar > 0, rtmax > 0 (D50 units)", where=self.where)
            if int(names["seed"]) != names["seed"] or names["seed"] < 0:
                raise InputError(f"seed must be an integer ≥ 0, got {names['seed']!r}", where=f"{self.where}.seed",
                                 fix="use 1, 2, 3, …")
        if self.kind == "selfaffine":
            if not 0 < names["hurst"] < 1:
                raise InputError("need 0 < hurst < 1", where=f"{self.where}.hurst")
            if names["rms_slope"] <= 0 or names["short_cutoff"] <= 0:
                raise InputError("need rms_slope > 0 and short_cutoff > 0 (D50 units)", where=self.where)
            if not names["short_cutoff"] < names["long_cutoff"] <= names["length"]:
                raise InputError("need short_cutoff < long_cutoff ≤ length (D50 units)", where=self.where,
                                 fix="e.g. short_cutoff = 0.8, long_cutoff = 10, length = 60")
            if names["short_cutoff"] / 8 < CONTACT_STEP_D50 - 1e-12:
                # the line is synthesised on a grid of short_cutoff/8 and meshed as it is: finer facets
                # than the grains' contact scale read a flat 0.020 too strong in tan δ (base.CONTACT_STEP_D50)
                raise InputError(f"short_cutoff {names['short_cutoff']:g} D50 puts the line's grid at "
                                 f"{names['short_cutoff'] / 8:g} D50, finer than the {CONTACT_STEP_D50:g} D50 facets "
                                 "below which LIGGGHTS resolves one grain contact as several",
                                 where=f"{self.where}.short_cutoff",
                                 fix=f"short_cutoff ≥ {8 * CONTACT_STEP_D50:g} (D50 units)")
            if names["length"] / names["short_cutoff"] > 1e5:
                raise InputError("length/short_cutoff above 1e5 grid points", where=self.where)
            if int(names["seed"]) != names["seed"] or names["seed"] < 0:
                raise InputError(f"seed must be an integer ≥ 0, got {names['seed']!r}", where=f"{self.where}.seed",
                                 fix="use 1, 2, 3, …")
        if self.kind != "file" and (self.axis, self.line, self.direction, self.areal, self.window) != (
                None, None, "+", False, None):
            raise InputError("axis, line, direction, areal and window are for file profiles", where=self.where)
        if self.kind == "file":
            self._check_file()

    def _check_file(self) -> None:
        """A file spec's own rules: its path and hash, units and cutoff, then a line's or a patch's choices."""
        if not self.path:
            raise InputError("a file profile needs a path", where=f"{self.where}.path")
        if not isinstance(self.sha256, str) or not _SHA256.fullmatch(self.sha256):
            raise InputError(f"a file profile needs the file's SHA-256, got {self.sha256!r}",
                             where=f"{self.where}.sha256",
                             fix="build it with interphase.surface.builder.file_spec, which hashes the file")
        if self.units is not None:
            units_factor(self.units, f"{self.where}.units")
        if self.cutoff is not None and not (math.isfinite(self.cutoff) and self.cutoff > 0):
            raise InputError("cutoff must be a positive length in m", where=f"{self.where}.cutoff")
        if self.areal:
            self._check_areal()
            return
        if self.axis is not None:
            check_axis(self.axis, f"{self.where}.axis")
        if self.direction not in DIRECTIONS:
            raise InputError(f"unknown direction {self.direction!r}", where=f"{self.where}.direction",
                             fix="use \"+\" (as measured) or \"-\" (mirrored: sheared the other way); an areal "
                             "scan's patch (areal = true) takes +x, -x, +y, -y")
        if self.window is not None:
            raise InputError("window is for an areal scan's patch", where=f"{self.where}.window",
                             fix="add areal = true, or remove window")
        if self.line is not None and (isinstance(self.line, bool) or not isinstance(self.line, (int, str))):
            raise InputError(f"line must be an integer index or \"k/n\", got {self.line!r}",
                             where=f"{self.where}.line")

    def _check_areal(self) -> None:
        """An areal patch: a direction of AREAL_DIRECTIONS ("+"/"-" read as "+x"/"-x"), a window of two
        lengths ≥ 0 [m] or none; no line choice and no line filter."""
        if self.areal is not True:
            raise InputError(f"areal must be true or false, got {self.areal!r}", where=f"{self.where}.areal")
        if self.axis is not None or self.line is not None:
            raise InputError("an areal scan's patch takes no axis or line", where=self.where,
                             fix="give the direction of shear over the scan (+x, -x, +y, -y) instead")
        if self.cutoff is not None:
            raise InputError("an areal scan's patch is not filtered (cutoff is for a line)", where=f"{self.where}.cutoff",
                             fix="remove cutoff")
        direction = {"+": "+x", "-": "-x"}.get(self.direction, self.direction)
        if direction not in AREAL_DIRECTIONS:
            raise InputError(f"unknown direction {self.direction!r} for an areal scan", where=f"{self.where}.direction",
                             fix=f"use one of {', '.join(AREAL_DIRECTIONS)} (the soil's motion over the scan)")
        object.__setattr__(self, "direction", direction)
        if self.window is not None:
            w = self.window
            if (not isinstance(w, (tuple, list)) or len(w) != 2
                    or any(isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0
                           for v in w)):
                raise InputError(f"window must be two lengths [x0, y0] ≥ 0 in m, got {w!r}",
                                 where=f"{self.where}.window", fix="e.g. window = [0.002, 0.004]")
            object.__setattr__(self, "window", (float(w[0]), float(w[1])))

    @classmethod
    def make(cls, kind: str, where: str = "profile", **params) -> "ProfileSpec":
        """Generated profile from keyword params, e.g. ProfileSpec.make('sawtooth', rt=1, sw=2, sr=0)."""
        return cls(kind=kind, params=tuple(sorted(params.items())), where=where)

    def param(self, name: str) -> float:
        return dict(self.params)[name]

    def canonical(self) -> dict:
        """Identity of the profile: content hash, not path, for files."""
        out: dict = {"kind": self.kind}
        if self.params:
            out["params"] = {k: float(v) for k, v in self.params}
        if self.kind == "file":
            out.update(sha256=self.sha256, units=self.units, cutoff=self.cutoff)
            if self.areal:          # a new kind of identity: no older spec has these keys
                out.update(areal=True, patch=AREAL_PATCH_RULE)
                if self.direction != "+x":
                    out["direction"] = self.direction
                if self.window is not None:
                    out["window"] = [float(v) for v in self.window]
                return out
            # the line choice joins the identity only when made (older specs keep their ids)
            if self.axis is not None:
                out["axis"] = self.axis
            if self.line is not None:
                out["line"] = self.line
            if self.direction != "+":
                out["direction"] = self.direction
        return out

    def label(self) -> str:
        if self.kind == "file" and self.areal:
            out = PurePath(self.path).stem + "-areal"
            if self.direction != "+x":
                out += "-" + self.direction.replace("+", "p").replace("-", "m")
            if self.window is not None:
                out += f"-at{self.window[0] * 1e3:g}-{self.window[1] * 1e3:g}mm"
            return out
        if self.kind == "file":
            out = PurePath(self.path).stem
            if self.axis is not None or self.line is not None:
                out += f"-{self.axis or 'x'}{str(self.line).replace('/', 'of') if self.line is not None else ''}"
            return out + ("-rev" if self.direction == "-" else "")
        if not self.params:
            return self.kind
        return self.kind + "-" + "-".join(f"{k}{v:g}" for k, v in self.params)
