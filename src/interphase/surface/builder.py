"""From a user's input to a spec, and from a spec to a Profile: the one place that does either.

`file_spec` is what a loader of user input (a campaign's case table) calls for a measured surface:
it checks the file, hashes it (the SHA-256 is the spec's identity, not the path) and, with a line
chosen by axis/line, reads the scan now, so that a line outside the scan or a file no reader takes
is refused when the campaign is loaded, not when a case runs. `from_spec` builds the Profile a spec
refers to; `periodic_cell` the surface of the periodic device; `areal_patch` an areal scan's closed
patch, the 3D cell's surface (surface/patch.py), meshed at the grains' contact scale or coarser.
"""

from __future__ import annotations

import functools
import hashlib
import math
from pathlib import Path

import numpy as np

from interphase.errors import InputError
from interphase.surface.base import CONTACT_STEP_D50, Profile
from interphase.surface.filters import gaussian_filter, prepare_measured
from interphase.surface.lines import line_profile, parse_line, scan_profile
from interphase.surface.mesh import min_angle_deg
from interphase.surface.patch import Patch, make_patch
from interphase.surface.profiles import (asymmetric_sawtooth, close, flat, random_profile, sawtooth, selfaffine_profile,
                                         tile)
from interphase.surface.readers import read_scan
from interphase.surface.spec import ProfileSpec

#: Shortest face a periodic cell's cut may leave [D50]. Far below what a grain can feel, and above
#: the thinnest face LIGGGHTS meshes: its triangles must have angles ≥ 0.256°, so a face shorter than
#: wall width × tan 0.256° (~8.5 µm for the ~1.9 mm wide wall of the study's grains) is refused. No
#: cell of the shipped campaigns had a face at a cut between that and 2 % of D50 (14 µm): the cut
#: faces that LIGGGHTS did mesh are unchanged (random profiles A-G ≥ 0.29 mm, FRT lines ≥ 17 µm).
MIN_FACE_D50 = 0.02
#: The smallest angle LIGGGHTS accepts in a mesh triangle [°] (fix mesh/surface's default
#: `curvature` 1e-5, acos(1 − 1e-5)): a segment of an extruded profile shorter than the wall's width
#: × tan of it gives a sliver the engine refuses (bad_mesh) before the run starts.
LIGGGHTS_MIN_ANGLE_DEG = 0.256




def mesh_step(d50: float, wall_width: float | None = None) -> float:
    """The step [m] a measured line is resampled to when it cannot be meshed as measured (a sample
    step under `min_face`): CONTACT_STEP_D50·D50, or twice the thinnest segment LIGGGHTS meshes over
    `wall_width` [m] (the walls' extent across the shear) where that is longer. A Dektak line (77 nm
    steps) under the Karlsruhe sand (D50 0.14 mm) becomes 14 µm; the study's FRT lines (24 µm steps
    under 0.7 mm grains, 0.034 D50) mesh as measured and stay point for point."""
    return max(CONTACT_STEP_D50 * d50, 2 * _thinnest(wall_width))


def min_face(d50: float, wall_width: float | None = None) -> float:
    """The shortest face a periodic cell's cut may leave [m]: MIN_FACE_D50·D50, or the thinnest face
    LIGGGHTS meshes over `wall_width` where that is longer (a 3D cell's 10 D50 deep walls)."""
    return max(MIN_FACE_D50 * d50, _thinnest(wall_width))


def _thinnest(wall_width: float | None) -> float:
    """The shortest segment whose extruded triangles LIGGGHTS accepts [m] (0 without extrusion)."""
    return wall_width * math.tan(math.radians(LIGGGHTS_MIN_ANGLE_DEG)) if wall_width else 0.0


def file_sha256(path: str | Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def file_spec(path: str | Path, units: str | None = "m", cutoff: float | None = None, where: str = "profile",
              axis: str | None = None, line: int | str | None = None, direction: str = "+", areal: bool = False,
              window: tuple[float, float] | None = None) -> ProfileSpec:
    """The spec of a measured profile file, its SHA-256 taken now; with axis/line the scan is read
    now and the line checked against it; an areal patch's scan is read now and must be areal."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"profile file {str(p)!r} does not exist", where=f"{where}.path",
                         fix="give the path of an existing profile file (relative to the campaign file)")
    if isinstance(line, float) and line.is_integer():
        line = int(line)
    spec = ProfileSpec(kind="file", path=str(p), units=units, sha256=file_sha256(p), cutoff=cutoff, where=where,
                       axis=axis, line=line, direction=direction, areal=areal,
                       window=tuple(window) if isinstance(window, list) else window)
    if spec.areal:
        scan = read_scan(p, units)
        if not scan.areal:
            raise InputError(f"{p} is a line, not an areal scan", where=f"{where}.areal",
                             fix="remove areal = true (a line is sheared as a profile)")
        return spec
    if axis is not None or line is not None:
        _, Z = read_scan(p, units).lines(axis or "x")
        if line is not None:
            parse_line(line, Z.shape[0], f"{where}.line ({p})")
    return spec


def from_spec(spec: ProfileSpec, d50: float, length: float, wall_width: float | None = None) -> Profile:
    """The Profile a Case refers to, starting at x = 0 and covering at least `length` m; a measured
    line sampled finer than a device meshes is resampled to the grains' contact scale (`_meshable`;
    `wall_width` [m] is the extent its surface is extruded over, None where it is not)."""
    if spec.areal:
        raise InputError("an areal scan's patch is the surface of the 3D cell, not a profile", where=spec.where,
                         fix='use device = "periodic3d" (or remove areal = true to shear a line of the scan)')
    if spec.kind == "flat":
        return flat(length)
    if spec.kind == "sawtooth":
        return sawtooth(spec.param("rt"), spec.param("sw"), spec.param("sr"), d50=d50, length=length)
    if spec.kind == "asymmetric":
        return asymmetric_sawtooth(*(spec.param(k) for k in ("rt", "rise", "fall", "sr")), d50=d50, length=length)
    if spec.kind == "random":
        return random_profile(spec.param("au"), spec.param("ar"), spec.param("rtmax"), d50=d50, length=length,
                              seed=int(spec.param("seed")))
    if spec.kind == "selfaffine":
        return tile(selfaffine_profile(spec.param("hurst"), spec.param("rms_slope"), spec.param("long_cutoff"),
                                       spec.param("short_cutoff"), spec.param("length"), int(spec.param("seed")),
                                       d50=d50), length)
    return tile(_meshable(_measured(spec, d50), d50, wall_width), length)


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


def _meshable(prof: Profile, d50: float, wall_width: float | None) -> Profile:
    """`prof` as measured when no sample step is under min_face(d50, wall_width); else linearly
    interpolated on a uniform grid of mesh_step(d50, wall_width) or just above."""
    if float(np.diff(prof.x).min()) >= min_face(d50, wall_width):
        return prof
    step = mesh_step(d50, wall_width)
    x = np.linspace(prof.x[0], prof.x[-1], max(2, int(prof.length // step) + 1))
    return Profile(x, np.interp(x, prof.x, prof.z), prof.periodic, prof.name)


def periodic_cell(spec: ProfileSpec, d50: float, length: float, wall_width: float | None = None) -> Profile:
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
    return close(from_spec(spec, d50, 2 * length, wall_width), length, min_face=min_face(d50, wall_width))


@functools.lru_cache(maxsize=16)
def areal_patch(spec: ProfileSpec, d50: float, length: float, depth: float) -> Patch:
    """The closed patch of an areal file spec for a 3D cell of about `length` × `depth` [m]
    (surface.patch.make_patch; cached: every Case of a campaign's seeds shares one): its window and
    direction as the spec gives them, meshed no finer than mesh_step(d50) (CONTACT_STEP_D50·D50:
    the FRT scans' 24 µm grid under the Karlsruhe sand's 0.14 mm grains, 0.17 D50, stays as measured;
    a finer scan is resampled up to it). Refused when a mesh triangle has an angle under
    LIGGGHTS_MIN_ANGLE_DEG (the engine would refuse the mesh)."""
    scan = read_scan(spec.path, units=spec.units)
    patch = make_patch(scan, d50, length, depth, spec.direction, spec.window, min_step=mesh_step(d50))
    angle = min_angle_deg(*patch.triangles())
    if angle < LIGGGHTS_MIN_ANGLE_DEG:
        raise InputError(f"the patch's mesh has a triangle with an angle of {angle:.3g}° (LIGGGHTS takes ≥ "
                         f"{LIGGGHTS_MIN_ANGLE_DEG}°)", where=spec.where,
                         fix="another window or direction, or a larger D50 (a coarser mesh)")
    return patch
