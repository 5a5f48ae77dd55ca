"""Instrument files as they come: line and areal scans read through SurfaceTopography.

`read_scan(path)` returns a `Scan` in metres: heights on the file's grid with NaN where the
instrument has no point (SurfaceTopography's masked/undefined data), positions from the file's own
sizes and units. SurfaceTopography (MIT, github.com/ContactEngineering/SurfaceTopography) reads the
instrument formats, the Dektak CSV export included (tried: the same 9600 points and heights as the
project's former parser). The project's own two-column text reader stays for plain x z text, which
SurfaceTopography reads without units; there the project's reader gives line-numbered messages and
takes the units as an option (default mm).

A line is chosen from an areal scan by axis (x: the file's first axis, lines of fixed y; y: lines
of fixed x), index and direction ("+": as measured, "-": mirrored, the same surface sheared the
other way). `line_profile` returns that line levelled by its least-squares line; a line with missing
points gives its longest valid run.
"""

from __future__ import annotations

import contextlib
import io
import math
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from interphase.errors import InputError
from interphase.surface.spec import UNITS

#: metres per unit: the project's option names (surface.spec.UNITS) and the other names
#: SurfaceTopography reports
UNIT_FACTORS = {**UNITS, "µm": 1e-6, "μm": 1e-6, "nm": 1e-9, "Å": 1e-10, "pm": 1e-12}
UNITS_FIX = "give the units of the file's x and z (--units um | mm | m, or units = \"...\" in the campaign)"
_NUM = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*$")
_SPLIT = re.compile(r"[,;\t ]+")


@dataclass(frozen=True, eq=False)
class Scan:
    """A measured surface in metres. Line: heights (n,), x (n,). Areal: heights (nx, ny) indexed
    [i along x, j along y], x (nx,), y (ny,). NaN heights are points the instrument did not measure."""
    heights: np.ndarray
    x: np.ndarray
    y: np.ndarray | None
    name: str
    units: str          # the units the file declares (or the caller's override)
    reader: str         # which reader read it

    @property
    def areal(self) -> bool:
        return self.heights.ndim == 2

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(self.heights.shape)

    @property
    def n_missing(self) -> int:
        return int(np.count_nonzero(~np.isfinite(self.heights)))

    def lines(self, axis: str = "x") -> tuple[np.ndarray, np.ndarray]:
        """(positions along `axis` [m], heights (n_lines, n_points) [m]): every grid line along the axis."""
        axis = check_axis(axis, self.name)
        if not self.areal:
            if axis != "x":
                raise InputError("a line scan has only the x axis", where=self.name, fix="use axis x")
            return self.x, self.heights[None, :]
        if axis == "x":
            return self.x, self.heights.T
        return self.y, self.heights


def check_axis(axis: str, where: str = "--axis") -> str:
    if axis not in ("x", "y"):
        raise InputError(f"unknown axis {axis!r}", where=where, fix="use x (the file's first axis) or y")
    return axis


def _is_text(raw: bytes) -> bool:
    head = raw[:4096]
    return b"\0" not in head and all(32 <= b or b in (9, 10, 13) for b in head)


def _starts_with_numbers(raw: bytes) -> bool:
    """Plain numeric text from its first line on ('#' comments and blank lines aside): such a file
    declares no units, so SurfaceTopography has nothing to add to the project's reader."""
    if not _is_text(raw):
        return False
    for line in re.split(r"\r*\n|\r", raw[:65536].decode("latin-1")):
        body = line.split("#", 1)[0].strip().strip(",;")
        if not body:
            continue
        parts = [p for p in _SPLIT.split(body) if p]
        return all(_NUM.match(p) or p.lower() in ("nan", "inf", "-inf") for p in parts[:2])
    return False


def _st_error(exc: Exception) -> str:
    text = "".join(c if c.isprintable() else " " for c in str(exc))
    text = " ".join(text.split())
    return text[:160] + ("…" if len(text) > 160 else "")


def read_scan(path: str | Path, units: str | None = None) -> Scan:
    """Read a line or areal scan into metres. `units` ('um' | 'mm' | 'm') overrides the file's own;
    a file that declares no units needs it (plain two-column text defaults to mm, as before)."""
    path = Path(path)
    where = str(path)
    if units is not None and units not in ("m", "mm", "um"):
        raise InputError(f"unknown units {units!r}", where="--units", fix="use one of m, mm, um")
    if not path.is_file():
        raise InputError("file not found", where=where, fix="give the path of a profile file")
    raw = path.read_bytes()
    if not raw.strip():
        raise InputError("the file is empty", where=where, fix="give a file with two columns x, z")
    if not _starts_with_numbers(raw):
        try:
            return _read_surfacetopography(path, units)
        except InputError as exc:
            # text SurfaceTopography cannot read, or reads without units: the project's reader says
            # what is wrong line by line, and takes the units as an option (default mm)
            if not (_is_text(raw) and getattr(exc, "text_fallback", False)):
                raise
    from interphase.surface.readers import read_text_profile

    prof = read_text_profile(path, units=units)
    return Scan(prof.z, prof.x, None, where, units or "mm", "interphase two-column text")


def _read_surfacetopography(path: Path, units: str | None) -> Scan:
    where = str(path)
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()), \
            contextlib.redirect_stderr(io.StringIO()):
        warnings.simplefilter("ignore")
        from SurfaceTopography import open_topography

        try:
            reader = open_topography(str(path))
            topo = reader.topography()
        except Exception as exc:      # SurfaceTopography raises many kinds; all mean "cannot read it"
            err = InputError(f"SurfaceTopography cannot read this file ({type(exc).__name__}: {_st_error(exc)})",
                             where=where, fix="export it in a format SurfaceTopography reads (FRT, SUR, MNT, OPDx, "
                             "HFM, Mitutoyo XLSX, Dektak CSV, X3P, …) or as two columns x z text")
            err.text_fallback = True
            raise err from None
        file_units = topo.unit
        if units is None:
            if file_units is None or file_units not in UNIT_FACTORS:
                err = InputError(f"the file's units are unknown ({file_units!r})", where=where, fix=UNITS_FIX)
                err.text_fallback = file_units is None
                raise err
            factor, units_name = UNIT_FACTORS[file_units], str(file_units)
        else:
            factor, units_name = UNIT_FACTORS[units], units
        fmt = getattr(reader, "format", None)
        name = reader.name() if callable(getattr(reader, "name", None)) else type(reader).__name__
        label = f"SurfaceTopography {name}" + (f" ({fmt()})" if callable(fmt) else "")
        h = topo.heights()
        z = np.ma.filled(np.ma.asarray(h, dtype=float), np.nan) * factor
        if topo.dim == 1:
            if topo.is_uniform:
                x = np.arange(topo.nb_grid_pts[0]) * (topo.physical_sizes[0] / topo.nb_grid_pts[0])
            else:
                x, _ = topo.positions_and_heights()
            x = np.asarray(x, float) * factor
            step = np.diff(x)
            if np.any(step < 0):
                raise InputError("x decreases along the line", where=where, fix="x must not decrease; sort the rows")
            if np.any(step == 0):
                # instruments that round the lateral position can write one x twice: one point, mean height
                ux, group = np.unique(x, return_inverse=True)
                ok = np.isfinite(z)
                zs = np.bincount(group[ok], weights=z[ok], minlength=ux.size)
                cnt = np.bincount(group[ok], minlength=ux.size)
                with np.errstate(invalid="ignore", divide="ignore"):
                    z = np.where(cnt > 0, zs / np.maximum(cnt, 1), np.nan)
                x = ux
            return Scan(z, x, None, where, units_name, label)
        nx, ny = topo.nb_grid_pts
        sx, sy = topo.physical_sizes
        x = np.arange(nx) * (sx / nx) * factor
        y = np.arange(ny) * (sy / ny) * factor
        return Scan(z, x, y, where, units_name, label)


def valid_runs(valid: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(line, start, stop) of every maximal run of True along axis 1 of a 2-D bool array (stop exclusive),
    in line order then position order."""
    valid = np.atleast_2d(valid)
    padded = np.zeros((valid.shape[0], valid.shape[1] + 2), np.int8)
    padded[:, 1:-1] = valid
    d = np.diff(padded, axis=1)
    line, start = np.nonzero(d == 1)
    _, stop = np.nonzero(d == -1)
    return line, start, stop


def spread_index(n_lines: int, k: int, n: int) -> int:
    """Index of the k-th (1-based) of n lines spread evenly over n_lines: the middle of the k-th of n
    equal bands."""
    return min(n_lines - 1, int(math.floor((k - 0.5) * n_lines / n)))


def parse_line(line, n_lines: int, where: str) -> int:
    """A line choice → index: an integer index (0-based, negative counts from the end) or "k/n", the
    k-th of n lines spread evenly over the scan."""
    if isinstance(line, str):
        m = re.fullmatch(r"\s*(\d+)\s*/\s*(\d+)\s*", line)
        if not m or not 1 <= int(m.group(1)) <= int(m.group(2)):
            raise InputError(f"line {line!r} is neither an index nor 'k/n' with 1 ≤ k ≤ n", where=where,
                             fix="e.g. line = 250 or line = \"2/3\" (the 2nd of 3 lines spread over the scan)")
        return spread_index(n_lines, int(m.group(1)), int(m.group(2)))
    if isinstance(line, bool) or not isinstance(line, (int, np.integer)) and not (
            isinstance(line, float) and line.is_integer()):
        raise InputError(f"line must be an integer index or 'k/n', got {line!r}", where=where)
    i = int(line)
    if not -n_lines <= i < n_lines:
        raise InputError(f"line {i} is outside the scan's {n_lines} lines", where=where,
                         fix=f"use 0 … {n_lines - 1}")
    return i % n_lines


def line_profile(scan: Scan, axis: str = "x", line=None, direction: str = "+", d50: float | None = None):
    """The Profile of one grid line [m], levelled by its least-squares line, starting at x = 0:
    `line` an index or "k/n" (default: the middle line; a line scan has one), direction "+" as
    measured, "-" mirrored. Missing points: the longest valid run of the line."""
    from interphase.surface.profiles import Profile

    if direction not in ("+", "-"):
        raise InputError(f"unknown direction {direction!r}", where=scan.name, fix="use '+' or '-'")
    s, Z = scan.lines(axis)
    i = Z.shape[0] // 2 if line is None else parse_line(line, Z.shape[0], scan.name)
    z = Z[i]
    li, start, stop = valid_runs(np.isfinite(z)[None, :])
    if start.size == 0:
        raise InputError(f"line {i} along {axis} has no measured point", where=scan.name,
                         fix="choose another line")
    j = int(np.argmax(stop - start))
    a, b = int(start[j]), int(stop[j])
    if b - a < 3:
        raise InputError(f"line {i} along {axis}: its longest run of measured points has {b - a} points",
                         where=scan.name, fix="choose another line")
    x, zz = s[a:b] - s[a], z[a:b]
    if d50 is not None and x[-1] <= d50:
        raise InputError(f"line {i} along {axis}: its longest valid run is {x[-1] * 1e3:.4g} mm, shorter than one "
                         f"grain diameter (D50 = {d50 * 1e3:g} mm)", where=scan.name,
                         fix="choose another line or a smaller D50")
    slope, icpt = np.polyfit(x, zz, 1)
    zz = zz - (icpt + slope * x)
    prof = Profile(x, zz, periodic=False, name=scan.name)
    if direction == "-":
        m = prof.mirrored()
        prof = Profile(m.x - m.x[0], m.z, False, scan.name)
    return prof
