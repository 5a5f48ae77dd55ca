"""Readers of measured profiles and their preparation (centerline, resampling, Gaussian filter).

Formats: instrument files (the Dektak CSV export among them) through SurfaceTopography, see
surface/instruments.py; and the project's own reader of
  - Plain two-column text/CSV: comma, semicolon, tab or spaces; leading header lines that are not
    numbers are skipped; '#' starts a comment. Units as given (the caller's option).
x must not decrease; rows with the same x (lateral positions rounded by the instrument) are merged
into one point at the mean of their z.
Every failure is an InputError naming the file and, where it applies, the line.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.ndimage import gaussian_filter1d

from interphase.errors import InputError
from interphase.surface.profiles import Profile, units_factor

_NUM = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*$")
_SPLIT = re.compile(r"[,;\t ]+")


def read_profile(path: str | Path, units: str | None = None) -> Profile:
    """Read a measured line profile into metres (any format `instruments.read_scan` reads). `units`
    ('um' | 'mm' | 'm') overrides the file's own. Missing points: the longest valid run. An areal scan
    is refused here (choose a line: instruments.line_profile, or `campaign theta-a` on the whole scan)."""
    from interphase.surface.instruments import read_scan, valid_runs

    scan = read_scan(path, units)
    if scan.areal:
        nx, ny = scan.shape
        raise InputError(f"an areal scan ({nx} × {ny} points), not a line", where=str(path),
                         fix="choose a line (profile axis/line in the campaign) or give the scan to `campaign theta-a`")
    x, z = scan.x, scan.heights
    if not np.all(np.isfinite(z)):
        _, start, stop = valid_runs(np.isfinite(z)[None, :])
        if start.size == 0:
            raise InputError("the line has no measured point", where=str(path), fix="give a measured profile")
        j = int(np.argmax(stop - start))
        x, z = x[start[j]:stop[j]], z[start[j]:stop[j]]
    if x.size < 3:
        raise InputError(f"only {x.size} data points", where=str(path), fix="a profile needs at least 3 points")
    return Profile(x, z, periodic=False, name=str(path))


def read_text_profile(path: str | Path, units: str | None = None) -> Profile:
    """The project's reader of plain two-column text x z (see the module doc); `units` default mm."""
    path = Path(path)
    where = str(path)
    if not path.is_file():
        raise InputError("file not found", where=where, fix="give the path of a profile file")
    raw = path.read_bytes()
    if not raw.strip():
        raise InputError("the file is empty", where=where, fix="give a file with two columns x, z")
    # one line break is \n, \r\n, a lone \r, or the \r\r\n some instrument exports write
    phys = re.split(r"\r*\n|\r", raw.decode("latin-1"))
    start, file_units = _find_table(phys)
    if units is None:
        units = file_units or "mm"
    factor = units_factor(units)
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
    return Profile(x * factor, z * factor, periodic=False, name=str(path))   # messages name the file


def _find_table(lines: list[str]) -> tuple[int, str | None]:
    """Index of the first data line (the first numeric row), and None: plain text declares no units."""
    for i, line in enumerate(lines):
        parts = [p for p in _SPLIT.split(line.split("#", 1)[0].strip().strip(",;")) if p]
        if len(parts) >= 1 and all(_NUM.match(p) or p.lower() in ("nan", "inf", "-inf") for p in parts[:2]):
            return i, None
        if i > 50:
            break
    return 0, None


def centerline(profile: Profile) -> Profile:
    """Remove the least-squares line z = a + b·x (the centerline correction)."""
    b, a = np.polyfit(profile.x, profile.z, 1)
    return Profile(profile.x, profile.z - (a + b * profile.x), profile.periodic, profile.name)


def resample(profile: Profile, dx: float) -> Profile:
    """Linear interpolation on a uniform step close to `dx` [m] spanning the same x range."""
    n = max(2, int(math.ceil(profile.length / dx)) + 1)
    x = np.linspace(profile.x[0], profile.x[-1], n)
    return Profile(x, np.interp(x, profile.x, profile.z), profile.periodic, profile.name)


def gaussian_filter(profile: Profile, cutoff: float, keep: str = "roughness") -> Profile:
    """ISO 16610-21 style Gaussian profile filter with cut-off wavelength `cutoff` [m].

    The weighting function s(x) = exp(−π (x/(α λc))²)/(α λc), α = sqrt(ln 2/π), is a Gaussian of
    standard deviation α λc / sqrt(2π); it passes 50 % amplitude at λc. The filtered line is the
    waviness; keep='roughness' (default) returns z − waviness, keep='waviness' the line itself.
    The profile is resampled uniformly first (median step). Ends: mirror extension (scipy 'reflect').
    """
    if not (math.isfinite(cutoff) and cutoff > 0):
        raise InputError(f"cut-off must be a positive length, got {cutoff!r}", where="cutoff")
    if keep not in ("roughness", "waviness"):
        raise InputError(f"keep must be roughness or waviness, got {keep!r}", where="keep")
    dx = float(np.median(np.diff(profile.x)))
    uni = resample(profile, dx)
    alpha = math.sqrt(math.log(2) / math.pi)
    sigma = alpha * cutoff / math.sqrt(2 * math.pi) / (uni.x[1] - uni.x[0])
    wav = gaussian_filter1d(uni.z, sigma, mode="wrap" if profile.periodic else "reflect")
    z = uni.z - wav if keep == "roughness" else wav
    return Profile(uni.x, z, profile.periodic, profile.name)


def prepare_measured(profile: Profile, cutoff: float | None = None) -> Profile:
    """The study's recipe for a measured profile: centerline-corrected, optionally Gaussian-filtered."""
    out = centerline(profile)
    if cutoff is not None:
        out = gaussian_filter(out, cutoff)
    return out


def load_profile(path: str | Path, units: str | None = None, cutoff: float | None = None) -> Profile:
    """A measured profile file ready for the centroid trace: read (`units` m | mm | um, default the
    file's own for a Dektak export, else mm), centerline-corrected and, with `cutoff` [m],
    Gaussian-filtered. Unknown units are refused before the file is read."""
    if units is not None:
        units_factor(units)
    return prepare_measured(read_profile(path, units=units), cutoff)
