"""A profile as a quasi-2D extruded surface: triangles and ASCII STL (meshio) for the engines.

Each profile segment (x0, z0)→(x1, z1) becomes the rectangle y ∈ [y_min, y_max], split into two
triangles wound so that their normals point up (+z, into the soil).
"""

from __future__ import annotations

from pathlib import Path

import meshio
import numpy as np

from interphase.surface.profiles import Profile


def extruded_triangles(profile: Profile, y_min: float, y_max: float) -> tuple[np.ndarray, np.ndarray]:
    """(points (2N, 3) [m], triangles (2(N−1), 3) int): vertices at y_min are 0..N−1, at y_max N..2N−1."""
    n = profile.x.size
    lo = np.column_stack([profile.x, np.full(n, y_min), profile.z])
    hi = np.column_stack([profile.x, np.full(n, y_max), profile.z])
    points = np.vstack([lo, hi])
    i = np.arange(n - 1)
    # (A, B, C) and (A, C, D) with A = lo[i], B = lo[i+1], C = hi[i+1], D = hi[i]: normal (−dz, 0, dx)·Δy
    tri = np.vstack([np.column_stack([i, i + 1, n + i + 1]), np.column_stack([i, n + i + 1, n + i])])
    return points, tri


def stl_mesh(profile: Profile, y_min: float, y_max: float) -> meshio.Mesh:
    points, tri = extruded_triangles(profile, y_min, y_max)
    return meshio.Mesh(points, [("triangle", tri)])


def write_stl(profile: Profile, path: str | Path, y_min: float, y_max: float) -> Path:
    """ASCII STL (LIGGGHTS reads only ASCII) of the extruded profile."""
    path = Path(path)
    meshio.write(path, stl_mesh(profile, y_min, y_max), file_format="stl", binary=False)
    return path
