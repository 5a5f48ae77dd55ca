"""The plain types of surface/: a Profile (a polyline z(x) in metres) and a Scan (a measured line
or areal grid in metres). They import nothing of surface/: every other module builds on them.

Periodic convention: a periodic profile stores one closing vertex, z[-1] == z[0], and its period is
x[-1] − x[0]; z(x + period) = z(x).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from interphase.errors import InputError

#: The finest mesh step [D50]: a measured line that cannot be meshed as measured is resampled to it,
#: and a self-affine line's grid may not be finer (surface.spec): the grains'
#: contact scale. At 100 kPa their Hertz contacts are 0.08–0.17 D50 across (mean overlaps 0.3–1.5 %
#: of D50 at G 500–50 MPa); on facets much shorter than that LIGGGHTS resolves one grain's contact
#: as several facet and edge contacts whose normals tilt away from every facet's. Measured on the
#: Karlsruhe card's Dektak line at μs 0.05 (docs/methods.md, studies/kfs_group1_2d/mesh_step_check.py, 3 seeds):
#: facets of 0.026 D50 read tan δ 0.070 with 31 % of the surface contacts tilted 1–20° on a mesh
#: whose facets tilt < 2°; facets of 0.1 D50 read 0.055 with 5 %; the flat 0.050.
CONTACT_STEP_D50 = 0.1

AXES = ("x", "y")
#: the sense of shear along a line: "+" as measured, "-" mirrored
DIRECTIONS = ("+", "-")
#: the direction of shear over an areal scan (the soil's motion relative to the surface, in the
#: scan's own frame); the 3D cell's patch is turned so that it shears along the cell's +x
AREAL_DIRECTIONS = ("+x", "-x", "+y", "-y")
#: the rule surface/patch.py cuts and closes an areal scan's patch by: part of the identity of every
#: areal case (a new rule is a new name, so no case id outlives the surface it named)
AREAL_PATCH_RULE = "edge-match/lsq-slopes"


@dataclass(frozen=True, eq=False)
class Profile:
    x: np.ndarray          # [m], strictly increasing
    z: np.ndarray          # [m], up into the soil
    periodic: bool = False
    name: str = ""

    def __post_init__(self):
        x = np.asarray(self.x, dtype=float)
        z = np.asarray(self.z, dtype=float)
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "z", z)
        if x.ndim != 1 or x.shape != z.shape or x.size < 2:
            raise InputError("a profile needs at least two (x, z) points of equal count", where=self.name or "profile")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(z))):
            raise InputError("profile contains NaN or infinite values", where=self.name or "profile")
        if np.any(np.diff(x) <= 0):
            raise InputError("profile x must increase strictly", where=self.name or "profile")

    @property
    def length(self) -> float:
        """Horizontal extent [m] (the period for a periodic profile)."""
        return float(self.x[-1] - self.x[0])

    def scaled(self, factor: float) -> "Profile":
        return Profile(self.x * factor, self.z * factor, self.periodic, self.name)

    def mirrored(self) -> "Profile":
        """x → −x (then re-sorted): the same surface sheared the other way (shear_sign flipped)."""
        return Profile(-self.x[::-1], self.z[::-1], self.periodic, self.name)


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
    if axis not in AXES:
        raise InputError(f"unknown axis {axis!r}", where=where, fix="use x (the file's first axis) or y")
    return axis
