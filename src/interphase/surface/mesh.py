"""Surfaces as triangles and ASCII STL (meshio) for the engines.

An extruded profile: each segment (x0, z0)→(x1, z1) becomes the rectangle y ∈ [y_min, y_max], split
into two triangles. An areal surface on a grid (`grid_triangles`: a scan's patch, surface/patch.py;
z(x, y) = p(x) + q(y) on the grid of both profiles' vertices, `separable_triangles`): two triangles
per grid cell. Every triangle is wound so that its normal points up (+z, into the soil).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from interphase.surface.base import Profile

# meshio is imported where an STL is written, not here: it costs ~0.1 CPU-s (it loads rich), which
# every process importing the engines paid, cell runs (no surface) included


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


def separable_triangles(along: Profile, across: Profile, y0: float) -> tuple[np.ndarray, np.ndarray]:
    """The areal surface z(x, y) = along.z(x) + across.z(y − y0) [m] over the grid of both profiles'
    vertices (`across.x` are its y coordinates, shifted by y0): (points (N·M, 3), triangles
    (2(N−1)(M−1), 3) int). Both profiles are piecewise linear with kinks only at their vertices, so
    within a grid cell z = a + b·x + c·y is a plane: the two triangles are the surface exactly."""
    return grid_triangles(along.x, across.x + y0, along.z[:, None] + across.z[None, :])


def grid_triangles(x: np.ndarray, y: np.ndarray, Z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Heights Z (N, M) [m] on the grid x (N,) × y (M,) [m] as triangles: (points (N·M, 3), triangles
    (2(N−1)(M−1), 3) int), vertex (i, j) at row i·M + j. Each grid cell is split along its diagonal
    from (i, j) to (i+1, j+1): (i,j), (i+1,j), (i+1,j+1) and (i,j), (i+1,j+1), (i,j+1), both
    counter-clockwise seen from +z, so every normal points up whatever the heights."""
    x, y, Z = np.asarray(x, float), np.asarray(y, float), np.asarray(Z, float)
    n, m = x.size, y.size
    X, Y = np.meshgrid(x, y, indexing="ij")
    points = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    k = (np.arange(n - 1)[:, None] * m + np.arange(m - 1)[None, :]).ravel()   # vertex (i, j) of each cell
    tri = np.vstack([np.column_stack([k, k + m, k + m + 1]), np.column_stack([k, k + m + 1, k + 1])])
    return points, tri


def min_angle_deg(points: np.ndarray, triangles: np.ndarray) -> float:
    """The smallest interior angle of any triangle [°] (what LIGGGHTS' mesh check reads)."""
    p = [points[triangles[:, k]] for k in range(3)]
    out = np.inf
    for k in range(3):      # the angle at vertex k, between its two edges
        u, v = p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]
        cos = np.einsum("ij,ij->i", u, v) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))
        out = min(out, float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))).min()))
    return out


def stl_mesh(profile: Profile, y_min: float, y_max: float) -> meshio.Mesh:
    import meshio

    points, tri = extruded_triangles(profile, y_min, y_max)
    return meshio.Mesh(points, [("triangle", tri)])


def write_stl(profile: Profile, path: str | Path, y_min: float, y_max: float) -> Path:
    """ASCII STL (LIGGGHTS reads only ASCII) of the extruded profile."""
    import meshio

    path = Path(path)
    meshio.write(path, stl_mesh(profile, y_min, y_max), file_format="stl", binary=False)
    return path


def segment_triangles(segments: np.ndarray, y_min: float, y_max: float) -> tuple[np.ndarray, np.ndarray]:
    """Walls from x–z segments: `segments` (M, 4) rows x0, z0, x1, z1 [m], each extruded in y as two
    triangles; the normal is (x1−x0, z1−z0) turned +90° (left of the direction of travel)."""
    s = np.asarray(segments, dtype=float).reshape(-1, 4)
    m = s.shape[0]
    a = np.column_stack([s[:, 0], np.full(m, y_min), s[:, 1]])
    b = np.column_stack([s[:, 2], np.full(m, y_min), s[:, 3]])
    c = np.column_stack([s[:, 2], np.full(m, y_max), s[:, 3]])
    d = np.column_stack([s[:, 0], np.full(m, y_max), s[:, 1]])
    points = np.vstack([a, b, c, d])
    i = np.arange(m)
    tri = np.vstack([np.column_stack([i, m + i, 2 * m + i]), np.column_stack([i, 2 * m + i, 3 * m + i])])
    return points, tri


def stl_text(points: np.ndarray, triangles: np.ndarray) -> str:
    """ASCII STL of a triangle set, as text (meshio's writer into memory)."""
    import io

    import meshio

    buf = io.StringIO()
    meshio.stl.write(buf, meshio.Mesh(points, [("triangle", triangles)]), binary=False)
    return buf.getvalue()


def inplane_triangles(profile: Profile, width: float) -> tuple[np.ndarray, np.ndarray]:
    """One triangle per segment with an edge IN the particle plane y = 0: (x0, 0, z0), (x1, 0, z1),
    and an apex at the segment's midpoint pushed to y = width.

    Why: a rectangle of two triangles puts its diagonal across y = 0, where a grain touching the
    face can register a contact with both triangles (a double contact, seen in LIGGGHTS dumps). With
    the in-plane edge, each grain–segment contact is one contact; neighbouring triangles share only
    the profile vertex. Normals point up (+z). Points are (x, y, z) [m].
    """
    x, z = profile.x, profile.z
    n = x.size
    base = np.column_stack([x, np.zeros(n), z])
    apex = np.column_stack([0.5 * (x[:-1] + x[1:]), np.full(n - 1, width), 0.5 * (z[:-1] + z[1:])])
    points = np.vstack([base, apex])
    i = np.arange(n - 1)
    # (x0, x1, apex at +y): normal = (B−A)×(C−A) has z-component dx·width > 0
    tri = np.column_stack([i, i + 1, n + i])
    return points, tri
