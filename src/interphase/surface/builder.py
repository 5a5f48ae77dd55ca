"""From a user's input to a spec, and from a spec to a Profile: the one place that does either.

`file_spec` is what a loader of user input (a campaign's case table) calls for a measured surface:
it checks the file, hashes it (the SHA-256 is the spec's identity, not the path) and, with a line
chosen by axis/line, reads the scan now, so that a line outside the scan or a file no reader takes
is refused when the campaign is loaded, not when a case runs. `from_spec` builds the Profile a spec
refers to; `periodic_cell` the surface of the periodic device.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from interphase.errors import InputError
from interphase.surface.base import Profile
from interphase.surface.filters import gaussian_filter, prepare_measured
from interphase.surface.lines import line_profile, parse_line, scan_profile
from interphase.surface.profiles import close, flat, random_profile, sawtooth, selfaffine_profile, tile
from interphase.surface.readers import read_scan
from interphase.surface.spec import ProfileSpec

#: Shortest face a periodic cell's cut may leave [D50]. Far below what a grain can feel, and above
#: the thinnest face LIGGGHTS meshes: its triangles must have angles ≥ 0.256°, so a face shorter than
#: wall width × tan 0.256° (~8.5 µm for the ~1.9 mm wide wall of the study's grains) is refused. No
#: cell of the shipped campaigns had a face at a cut between that and 2 % of D50 (14 µm): the cut
#: faces that LIGGGHTS did mesh are unchanged (random profiles A-G ≥ 0.29 mm, FRT lines ≥ 17 µm).
MIN_FACE_D50 = 0.02


def file_sha256(path: str | Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def file_spec(path: str | Path, units: str | None = "m", cutoff: float | None = None, where: str = "profile",
              axis: str | None = None, line: int | str | None = None, direction: str = "+") -> ProfileSpec:
    """The spec of a measured profile file, its SHA-256 taken now; with axis/line the scan is read
    now and the line checked against it."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"profile file {str(p)!r} does not exist", where=f"{where}.path",
                         fix="give the path of an existing profile file (relative to the campaign file)")
    if isinstance(line, float) and line.is_integer():
        line = int(line)
    spec = ProfileSpec(kind="file", path=str(p), units=units, sha256=file_sha256(p), cutoff=cutoff, where=where,
                       axis=axis, line=line, direction=direction)
    if axis is not None or line is not None:
        _, Z = read_scan(p, units).lines(axis or "x")
        if line is not None:
            parse_line(line, Z.shape[0], f"{where}.line ({p})")
    return spec


def from_spec(spec: ProfileSpec, d50: float, length: float) -> Profile:
    """The Profile a Case refers to, starting at x = 0 and covering at least `length` m."""
    if spec.kind == "flat":
        return flat(length)
    if spec.kind == "sawtooth":
        return sawtooth(spec.param("rt"), spec.param("sw"), spec.param("sr"), d50=d50, length=length)
    if spec.kind == "random":
        return random_profile(spec.param("au"), spec.param("ar"), spec.param("rtmax"), d50=d50, length=length,
                              seed=int(spec.param("seed")))
    if spec.kind == "selfaffine":
        return tile(selfaffine_profile(spec.param("hurst"), spec.param("rms_slope"), spec.param("long_cutoff"),
                                       spec.param("short_cutoff"), spec.param("length"), int(spec.param("seed")),
                                       d50=d50), length)
    return tile(_measured(spec, d50), length)


def _measured(spec: ProfileSpec, d50: float) -> Profile:
    """A file spec's line, read once: a line file as measured, centerline-corrected (and filtered);
    a chosen line, or an areal scan's middle line along x, levelled (and filtered)."""
    scan = read_scan(spec.path, units=spec.units)
    if spec.axis is None and spec.line is None and spec.direction == "+" and not scan.areal:
        return prepare_measured(scan_profile(scan), cutoff=spec.cutoff)
    prof = line_profile(scan, spec.axis or "x", spec.line, spec.direction, d50=d50)   # levelled, longest run
    if spec.cutoff is not None:
        prof = gaussian_filter(prof, spec.cutoff)
    return prof


def periodic_cell(spec: ProfileSpec, d50: float, length: float) -> Profile:
    """The surface of the periodic device for a requested cell of about `length` m, from x = 0:
    flat, `length` exactly; a saw-tooth, the whole number of its periods nearest `length` (at least
    one); a random or measured profile, `close`d where it returns to its starting height, with no
    face at a cut shorter than MIN_FACE_D50·D50."""
    if spec.kind == "flat":
        return flat(length)
    if spec.kind == "sawtooth":
        lam = (spec.param("sw") + spec.param("sr")) * d50
        return sawtooth(spec.param("rt"), spec.param("sw"), spec.param("sr"), d50=d50,
                        periods=max(1, round(length / lam)))
    return close(from_spec(spec, d50, 2 * length), length, min_face=MIN_FACE_D50 * d50)
