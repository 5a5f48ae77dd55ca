"""Every surface file format, read into metres: the one module that opens profile and scan files.

`read_scan(path)` returns a `Scan`: heights on the file's grid with NaN where the instrument has no
point (SurfaceTopography's masked/undefined data), positions from the file's own sizes and units.
SurfaceTopography (MIT, github.com/ContactEngineering/SurfaceTopography) reads the instrument
formats, the Dektak CSV export included (tried: the same 9600 points and heights as the project's
former parser). The project's own reader takes
  - Plain two-column text/CSV: comma, semicolon, tab or spaces; leading header lines that are not
    numbers are skipped; '#' starts a comment. Units as given (the caller's option, default mm),
    which SurfaceTopography would read without units; the project's reader gives line-numbered
    messages.
x must not decrease; rows with the same x (lateral positions rounded by the instrument) are merged
into one point at the mean of their z.
`read_profile` is a line file as a Profile, `load_profile` the same prepared for the centroid trace.
Every failure is an InputError naming the file and, where it applies, the line.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import re
import warnings
from collections import OrderedDict
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.errors import InputError
from interphase.surface.base import Profile, Scan
from interphase.surface.filters import prepare_measured
from interphase.surface.lines import scan_profile
from interphase.surface.units import UNIT_FACTORS, UNITS_FIX, units_factor

_NUM = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*$")
_SPLIT = re.compile(r"[,;\t ]+")
#: one line break is \n, \r\n, a lone \r, or the \r\r\n some instrument exports write
_LINE_BREAK = re.compile(r"\r*\n|\r")
_NON_FINITE = ("nan", "inf", "-inf")
TEXT_READER = "interphase two-column text"
TEXT_DEFAULT_UNITS = "mm"


#: the last scans read, by (path, units, SHA-256 of the bytes): a campaign names one instrument file in
#: many cases, and SurfaceTopography's parse costs ~0.1 s a read (group5.toml: 108 reads of one file)
_SCANS: OrderedDict[tuple[str, str | None, bytes], Scan] = OrderedDict()
_SCANS_KEPT = 8


def read_scan(path: str | Path, units: str | None = None) -> Scan:
    """Read a line or areal scan into metres. `units` ('um' | 'mm' | 'm') overrides the file's own;
    a file that declares no units needs it (plain two-column text defaults to mm). The same bytes
    read again return the same Scan, whose arrays are read-only (a caller copies before it changes one)."""
    path = Path(path)
    if units is not None:
        units_factor(units)
    raw = _read_bytes(path)
    key = (str(path), units, hashlib.sha256(raw).digest())
    scan = _SCANS.get(key)
    if scan is None:
        scan = _frozen(_read_scan(path, raw, units))
        _SCANS[key] = scan
        while len(_SCANS) > _SCANS_KEPT:
            _SCANS.popitem(last=False)
    else:
        _SCANS.move_to_end(key)
    return scan


def _frozen(scan: Scan) -> Scan:
    for a in (scan.heights, scan.x, scan.y):
        if a is not None:
            a.setflags(write=False)
    return scan


def _read_scan(path: Path, raw: bytes, units: str | None) -> Scan:
    if not _starts_with_numbers(raw):
        try:
            return _read_surfacetopography(path, units)
        except InputError as exc:
            # text SurfaceTopography cannot read, or reads without units: the project's reader says
            # what is wrong line by line, and takes the units as an option (default mm)
            if not (_is_text(raw) and getattr(exc, "text_fallback", False)):
                raise
    prof = _parse_text(raw, str(path), units)
    return Scan(prof.z, prof.x, None, str(path), units or TEXT_DEFAULT_UNITS, TEXT_READER)


def read_profile(path: str | Path, units: str | None = None) -> Profile:
    """Read a measured line profile into metres (any format `read_scan` reads). `units`
    ('um' | 'mm' | 'm') overrides the file's own. Missing points: the longest valid run. An areal scan
    is refused here (choose a line: lines.line_profile, or `campaign theta-a` on the whole scan)."""
    return scan_profile(read_scan(path, units))


def load_profile(path: str | Path, units: str | None = None, cutoff: float | None = None) -> Profile:
    """A measured profile file ready for the centroid trace: read (`units` m | mm | um, default the
    file's own for a Dektak export, else mm), centerline-corrected and, with `cutoff` [m],
    Gaussian-filtered. Unknown units are refused before the file is read."""
    return prepare_measured(read_profile(path, units=units), cutoff)


def read_text_profile(path: str | Path, units: str | None = None) -> Profile:
    """The project's reader of plain two-column text x z (see the module doc); `units` default mm."""
    path = Path(path)
    if units is not None:
        units_factor(units)
    return _parse_text(_read_bytes(path), str(path), units)


def _read_bytes(path: Path) -> bytes:
    if not path.is_file():
        raise InputError("file not found", where=str(path), fix="give the path of a profile file")
    raw = path.read_bytes()
    if not raw.strip():
        raise InputError("the file is empty", where=str(path), fix="give a file with two columns x, z")
    return raw


def _is_text(raw: bytes) -> bool:
    head = raw[:4096]
    return b"\0" not in head and all(32 <= b or b in (9, 10, 13) for b in head)


def _numeric_row(line: str) -> bool | None:
    """Whether a text line is a data row (its first two fields numbers); None for a blank or comment line."""
    body = line.split("#", 1)[0].strip().strip(",;")
    if not body:
        return None
    parts = [p for p in _SPLIT.split(body) if p]
    return all(_NUM.match(p) or p.lower() in _NON_FINITE for p in parts[:2])


def _starts_with_numbers(raw: bytes) -> bool:
    """Plain numeric text from its first line on ('#' comments and blank lines aside): such a file
    declares no units, so SurfaceTopography has nothing to add to the project's reader."""
    if not _is_text(raw):
        return False
    for line in _LINE_BREAK.split(raw[:65536].decode("latin-1")):
        row = _numeric_row(line)
        if row is not None:
            return row
    return False


def _find_table(lines: list[str]) -> int:
    """Index of the first data line (the first numeric row within the first 52 lines; else 0)."""
    for i, line in enumerate(lines):
        if _numeric_row(line):
            return i
        if i > 50:
            break
    return 0


def _parse_text(raw: bytes, where: str, units: str | None) -> Profile:
    """Two-column text x z (the module doc) → Profile [m]; every message names the line."""
    phys = _LINE_BREAK.split(raw.decode("latin-1"))
    start = _find_table(phys)
    factor = units_factor(units or TEXT_DEFAULT_UNITS)
    rows = phys[start:]
    first = start + 1   # 1-based number of the first table line
    # keep non-empty, non-comment lines with their line numbers
    numbers = np.arange(first, first + len(rows))
    body = pd.Series(rows, dtype=object).str.split("#", n=1).str[0].str.strip().str.strip(",;")
    keep = body.str.len() > 0
    body, numbers = body[keep], numbers[keep.to_numpy()]
    if body.empty:
        raise InputError("no data rows", where=where, fix="the file needs rows of two numbers x, z")
    cols = body.str.split(_SPLIT, regex=True)
    ncol = cols.str.len().to_numpy()
    if np.any(ncol < 2):
        i = int(np.argmax(ncol < 2))
        raise InputError(f"line {numbers[i]} has one column ({body.iloc[i]!r})", where=where,
                         fix="each row needs two numbers: x and z")
    xs = cols.str[0]
    zs = cols.str[1]
    x = pd.to_numeric(xs, errors="coerce").to_numpy(float)
    z = pd.to_numeric(zs, errors="coerce").to_numpy(float)
    for arr, src, name in ((x, xs, "x"), (z, zs, "z")):
        bad = np.isnan(arr)
        if bad.any():
            i = int(np.argmax(bad))
            token = src.iloc[i]
            what = "NaN" if token.strip().lower() in ("nan", "na", "n/a") else f"text {token!r}"
            raise InputError(f"line {numbers[i]}: {what} where a number ({name}) was expected", where=where,
                             fix="remove or repair that row")
        if np.isinf(arr).any():
            i = int(np.argmax(np.isinf(arr)))
            raise InputError(f"line {numbers[i]}: infinite {name}", where=where, fix="remove or repair that row")
    step = np.diff(x)
    if np.any(step < 0):
        i = int(np.argmax(step < 0)) + 1
        raise InputError(f"line {numbers[i]}: x = {x[i]:g} decreases (previous {x[i-1]:g})",
                         where=where, fix="x must not decrease down the file; sort the rows")
    if np.any(step == 0):
        # instruments that round the lateral position (Dektak: to 0.1 µm) can write one x twice; the
        # stylus read that position twice, so its height is the mean of the readings
        x, group = np.unique(x, return_inverse=True)
        z = np.bincount(group, weights=z) / np.bincount(group)
    if x.size < 3:
        raise InputError(f"only {x.size} data rows", where=where, fix="a profile needs at least 3 points")
    return Profile(x * factor, z * factor, periodic=False, name=where)   # messages name the file


def _st_error(exc: Exception) -> str:
    text = "".join(c if c.isprintable() else " " for c in str(exc))
    text = " ".join(text.split())
    return text[:160] + ("…" if len(text) > 160 else "")


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
            factor, units_name = units_factor(units), units
        fmt = getattr(reader, "format", None)
        name = reader.name() if callable(getattr(reader, "name", None)) else type(reader).__name__
        label = f"SurfaceTopography {name}" + (f" ({fmt()})" if callable(fmt) else "")
        z = np.ma.filled(np.ma.asarray(topo.heights(), dtype=float), np.nan) * factor
        if topo.dim == 1:
            return _line_scan(topo, z, factor, where, units_name, label)
        nx, ny = topo.nb_grid_pts
        sx, sy = topo.physical_sizes
        x = np.arange(nx) * (sx / nx) * factor
        y = np.arange(ny) * (sy / ny) * factor
        return Scan(z, x, y, where, units_name, label)


def _line_scan(topo, z: np.ndarray, factor: float, where: str, units_name: str, label: str) -> Scan:
    """A SurfaceTopography line → Scan; rows with the same x become one point at their mean height."""
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
