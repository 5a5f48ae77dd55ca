"""Lines of a Scan, pure geometry on arrays (no file is read): the valid runs of a line with missing
points, the choice of a grid line (axis, index or "k/n", direction) and its Profile.

A line is chosen from an areal scan by axis (x: the file's first axis, lines of fixed y; y: lines
of fixed x), index and direction ("+": as measured, "-": mirrored, the same surface sheared the
other way). `line_profile` returns that line levelled by its least-squares line; a line with missing
points gives its longest valid run.
"""

from __future__ import annotations

import math
import re

import numpy as np

from interphase.errors import InputError
from interphase.surface.base import DIRECTIONS, Profile, Scan
from interphase.surface.filters import centerline

_K_OF_N = re.compile(r"\s*(\d+)\s*/\s*(\d+)\s*")


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


def longest_run(z: np.ndarray) -> tuple[int, int] | None:
    """(start, stop) of the longest run of finite values of the 1-D `z` (the first of equals), None
    when there is none."""
    _, start, stop = valid_runs(np.isfinite(z)[None, :])
    if start.size == 0:
        return None
    j = int(np.argmax(stop - start))
    return int(start[j]), int(stop[j])


def spread_index(n_lines: int, k: int, n: int) -> int:
    """Index of the k-th (1-based) of n lines spread evenly over n_lines: the middle of the k-th of n
    equal bands."""
    return min(n_lines - 1, int(math.floor((k - 0.5) * n_lines / n)))


def parse_line(line, n_lines: int, where: str) -> int:
    """A line choice → index: an integer index (0-based, negative counts from the end) or "k/n", the
    k-th of n lines spread evenly over the scan."""
    if isinstance(line, str):
        m = _K_OF_N.fullmatch(line)
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


def scan_profile(scan: Scan) -> Profile:
    """The Profile of a line scan as measured (positions as in the file, not levelled). Missing
    points: the longest valid run. An areal scan is refused (choose a line: `line_profile`)."""
    if scan.areal:
        nx, ny = scan.shape
        raise InputError(f"an areal scan ({nx} × {ny} points), not a line", where=scan.name,
                         fix="choose a line (profile axis/line in the campaign) or give the scan to `campaign theta-a`")
    x, z = scan.x, scan.heights
    if not np.all(np.isfinite(z)):
        run = longest_run(z)
        if run is None:
            raise InputError("the line has no measured point", where=scan.name, fix="give a measured profile")
        x, z = x[run[0]:run[1]], z[run[0]:run[1]]
    if x.size < 3:
        raise InputError(f"only {x.size} data points", where=scan.name, fix="a profile needs at least 3 points")
    return Profile(x, z, periodic=False, name=scan.name)


def line_profile(scan: Scan, axis: str = "x", line=None, direction: str = "+", d50: float | None = None) -> Profile:
    """The Profile of one grid line [m], levelled by its least-squares line, starting at x = 0:
    `line` an index or "k/n" (default: the middle line; a line scan has one), direction "+" as
    measured, "-" mirrored. Missing points: the longest valid run of the line."""
    if direction not in DIRECTIONS:
        raise InputError(f"unknown direction {direction!r}", where=scan.name, fix="use '+' or '-'")
    s, Z = scan.lines(axis)
    i = Z.shape[0] // 2 if line is None else parse_line(line, Z.shape[0], scan.name)
    z = Z[i]
    run = longest_run(z)
    if run is None:
        raise InputError(f"line {i} along {axis} has no measured point", where=scan.name,
                         fix="choose another line")
    a, b = run
    if b - a < 3:
        raise InputError(f"line {i} along {axis}: its longest run of measured points has {b - a} points",
                         where=scan.name, fix="choose another line")
    x, zz = s[a:b] - s[a], z[a:b]
    if d50 is not None and x[-1] <= d50:
        raise InputError(f"line {i} along {axis}: its longest valid run is {x[-1] * 1e3:.4g} mm, shorter than one "
                         f"grain diameter (D50 = {d50 * 1e3:g} mm)", where=scan.name,
                         fix="choose another line or a smaller D50")
    prof = centerline(Profile(x, zz, periodic=False, name=scan.name))
    if direction == "-":
        m = prof.mirrored()
        prof = Profile(m.x - m.x[0], m.z, False, scan.name)
    return prof
