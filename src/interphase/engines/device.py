"""The soil box of the interface test, shared by both engines so that they shear the same device.

Frame: x = shear axis, z up; lengths in metres.
"""

from __future__ import annotations

import numpy as np

# consolidation under the servo platen, the same protocol in both engines: a first stretch, then
# chunks of a quarter of it until the platen force lies within the tolerance of its target
CONSOLIDATION_TIME = 0.02   # [s] the first stretch
CONSOLIDATION_CHUNKS = 40   # at most this many chunks, then the case fails as 'not_consolidated'
PLATEN_TOLERANCE = 0.03     # consolidation ends when |F_platen − F_target| < this × F_target


def wall_gap(profile, d_min: float, d_max: float, d50: float) -> float:
    """Height of the left side wall's bottom edge above the surface's highest point [m].

    A grain resting in a valley of the surface rides along with it; if it sticks out above the
    peaks by p, a wall edge lower than that catches it and the grain jams between the wall and the
    rising face (forces 10× typical, overlaps of 25 % D50, measured). So the edge sits p + 0.05·d_min
    above the peaks, p from the centroid trace of the largest grain (its highest local minimum),
    letting trapped grains leave with the surface as in the physical device. Free grains smaller
    than the gap can leave too; they are removed at the side planes and counted (`grains_left`).
    Only when that gap would let a free grain of median size through (p + 0.05·d_min ≥ D50: flat or
    shallow valleys, where grains ride on the peaks instead of in the valleys) the edge sits
    0.05·d_min above the peaks. The bound was d_min/2 until 2026-11-23: with well-graded grains
    (d_min = D50/2) it shut the 45° saw-tooth's 0.57 mm gap, and the largest grains jammed at the
    left wall in most seeds (max overlaps 0.31–0.63 D50, wall forces 7–20 N against a 2.9 N
    platen; with the gap 0.09–0.28 D50 and 2–6 grains removed per run; docs/liggghts.md)."""
    from interphase.surface.trace import centroid_trace

    tr = centroid_trace(profile, d_max, dx=d_max / 1000)   # p to ~1e-3·d_max; the default step cost 0.15 s
    c = tr.z
    minima = (c[1:-1] <= c[:-2]) & (c[1:-1] <= c[2:])
    p = float(np.max(c[1:-1][minima]) + d_max / 2 - profile.z.max()) if minima.any() else d_max
    gap = p + 0.05 * d_min
    return gap if gap < d50 else 0.05 * d_min


def side_walls(profile, length: float, d_min: float, d_max: float, d50: float,
               wall_top: float) -> list[list[float]]:
    """The interface box's two side walls as segments [x0, z0, x1, z1] [m] (left normal +x, right −x).

    The surface moves −x: valleys leave the box under the LEFT wall, carrying the grains trapped in
    them, so that wall's bottom sits `wall_gap` above the peaks. Valleys enter under the RIGHT wall
    empty, so it sits 0.05·d_min above the peaks: with the left wall's gap there, grains on the
    flats of spaced profiles were pushed out under it by the soil, met the next tooth outside and
    were shot away (lost atoms in 2 of 3 seeds, spaced saw-tooth μs = 0.2, measured)."""
    top = float(profile.z.max())
    left = top + wall_gap(profile, d_min, d_max, d50)
    right = top + 0.05 * d_min
    return [[0.0, wall_top, 0.0, left], [length, right, length, wall_top]]
