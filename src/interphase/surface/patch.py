"""A patch of an areal scan that closes on itself: the surface of the 3D periodic cell (an areal file
spec as Case.profile, docs/3d.md "A measured areal scan as the surface"). Engine-free, numpy over
whole grids; heights and lengths in metres, z up into the soil, x the shear axis (the soil moves +x
relative to the surface).

The cell is periodic in x over L and in y over W, so its surface must tile. A Patch holds heights
on (nx+1) × (ny+1) grid nodes over [0, L] × [0, W] whose last row and column repeat the first
(z[nx, :] == z[0, :], z[:, ny] == z[:, 0]: the periodic convention of surface.base in both
directions), zero mean over the cell. `make_patch` builds it in five steps:

1. Orientation (`oriented`). The scan's grid is turned so that the chosen direction of shear over
   the scan becomes the cell's +x: "+x" as measured, "-x" turned 180°, "+y" turned by −90°
   ((x, y) → (y, −x)), "-y" by +90°. A rotation, never a mirror: the patch is the measured surface
   sheared the chosen way, not its mirror image.
2. Missing points (`fill_small_holes`). A hole (4-connected missing points) that does not touch the
   scan's edge and whose measured rims lie at most HOLE_D50·D50 apart along x and along y is filled
   by harmonic interpolation from its rims (SurfaceTopography's interpolate_undefined_data): a
   grain of D50 bridging a gap of D50/2 sinks at most 1 − √(1 − 1/4) = 13 % of its radius into it,
   so the grain's path is set by the rims, whatever the bottom. Every window that still holds a
   missing point is refused: a wider hole is relief nobody measured, and filling it would invent
   faces that the grains then push against. (frt-1.frt: 6 single missing points inside its
   measured area are filled; the frame of missing points around it refuses the windows there.)
3. Window (`edge_mismatch`). Of every window of nx × ny grid steps (L = nx·hx and W = ny·hy nearest
   the cell asked for) at every grid position that holds no missing point, the one whose opposite
   edges match best. Its score: the rms over the edge lines of the difference between opposite
   edges, each difference less its mean along the edge (a constant difference is a tilt, which
   levelling removes at no cost), over the rms height of the four edge lines about their own
   least-squares lines (the scan's form, which opposite edges share, left out).
   So two unrelated edges score about 1, identical ones 0. The score reads the edges only, never
   the interior: the chosen window's relief is a sample of the scan's, not selected for being smooth
   (which an absolute mismatch would prefer: θa biased low) or for a single bump in its middle with
   flat edges (which a mismatch over the window's own rms height would prefer: measured on frt-1.frt,
   a 13.8 µm spike in a 6 × 4 D50 window scored 0.016). Every position is scored, not a coarse
   grid: summed-area tables give all the scores in a few passes over the scan.
4. Closure (`close_slopes`). The periodic surface whose slopes are nearest the window's: u minimises
   Σ over the grid's edges (Δu − Δz)², the trapezoidal rule for ∫|∇u − ∇z|² dA (the window's edge
   rows and columns, which the torus holds once, count half each), solved exactly by FFT on the
   torus. A window that already closes (a periodic surface) comes back unchanged, to rounding; a tilt
   goes entirely; each wavelength of the remaining edge mismatch is spread over about its own
   wavelength from the seam. In the least-squares sense, no closure changes the slopes less.
5. Resolution (`coarsened`). A patch whose step is finer than `min_step` (the builder's: the
   grains' contact scale, surface.base.CONTACT_STEP_D50·D50) is resampled linearly and
   periodically to the coarsest step not under it; a coarser one keeps the scan's own grid, so the
   mesh carries the heights as measured.

The alternatives, measured (studies/scan_patch_bias/scan_patch_bias.py, docs/3d.md):
- per-line ramps (`close_ramps`): each line less a linear ramp of its own edge mismatch (centred,
  with the corner twist counted once). Every slope along a line changes by that line's mismatch
  over L. But a rough edge's mismatch varies from line to line, so the slopes across the lines change
  by up to half the difference between the two edges' own slopes, over the whole cell;
- a mirrored tile (`mirror_tile`): a window of L/2 × W/2 reflected in x and in y closes exactly with
  no change of height, but one half of the cell is the other half mirrored. Sheared along +x the cell
  meets the scan's +x faces and its −x faces in equal measure, so its θa along either sense is
  about the mean of the two senses: biased for any scan whose senses differ (an anisotropic one),
  and every mirror line is a ridge or a trough of the slopes (a kink) that the scan does not have.
"""

from __future__ import annotations

import contextlib
import io
import math
import warnings
from dataclasses import dataclass

import numpy as np

from interphase.errors import InputError
from interphase.surface.areal import FILTERS, ArealThetaA, areal_step, theta_a_lines
from interphase.surface.base import AREAL_DIRECTIONS, Profile, Scan
from interphase.surface.mesh import grid_triangles

#: a hole whose measured rims lie at most this far apart [D50] along x and along y is filled
HOLE_D50 = 0.5


@dataclass(frozen=True, eq=False)
class Window:
    """A window of a scan in the cell's frame (turned by the direction): heights (nx+1, ny+1) [m],
    missing points filled (step 2 of the module docstring), not closed."""
    z: np.ndarray
    hx: float                       # grid step along the cell's x [m]
    hy: float
    origin: tuple[float, float]     # the window's corner nearest the scan's origin, in the file's frame [m]
    mismatch: float                 # the edge-mismatch score (relative; module docstring, step 3)
    direction: str
    name: str
    at: tuple[int, int] = (0, 0)    # the window's first node in the turned grid (`oriented`)


@dataclass(frozen=True, eq=False)
class Patch:
    """A closed patch (module docstring): heights z (nx+1, ny+1) [m] on x (nx+1,) from 0 to L and
    y (ny+1,) from 0 to W, periodic in both, zero mean over the cell."""
    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    name: str
    direction: str                  # the sense of shear over the scan the cell's +x is
    origin: tuple[float, float]     # the window's corner in the file's frame [m]
    mismatch: float                 # the window's edge-mismatch score (relative)
    closure_rms: float              # rms of what the closure changed, less that change's own plane (a
                                    # tilt: levelling) [m]
    closure_max: float              # the largest such change [m]

    def __post_init__(self):
        for a in (self.x, self.y, self.z):
            a.setflags(write=False)

    @property
    def length(self) -> float:
        return float(self.x[-1])

    @property
    def width(self) -> float:
        return float(self.y[-1])

    def silhouette(self) -> Profile:
        """The highest point across y at each grid x: a periodic Profile over [0, L] (the x–z picture
        of the whole depth; its highest point is the patch's)."""
        return Profile(self.x, self.z.max(axis=1), periodic=True, name=self.name)

    def triangles(self, y0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """The mesh (points [m], triangles) with y shifted by y0: two triangles a grid cell, normals up."""
        return grid_triangles(self.x, self.y + y0, self.z)

    def height_at(self, x, y) -> np.ndarray:
        """The mesh's height [m] at (x, y) [m] (periodic: any x, y), on the triangle beneath: the cell
        (i, j) split along its diagonal from (i, j) to (i+1, j+1), as `triangles` splits it."""
        nx, ny = self.z.shape[0] - 1, self.z.shape[1] - 1
        u = np.mod(np.asarray(x, float), self.length) / (self.length / nx)
        v = np.mod(np.asarray(y, float), self.width) / (self.width / ny)
        i = np.clip(np.floor(u).astype(int), 0, nx - 1)
        j = np.clip(np.floor(v).astype(int), 0, ny - 1)
        u, v = u - i, v - j
        z = self.z
        z00, z10, z01, z11 = z[i, j], z[i + 1, j], z[i, j + 1], z[i + 1, j + 1]
        lower = z00 + u * (z10 - z00) + v * (z11 - z10)      # u ≥ v: (i,j), (i+1,j), (i+1,j+1)
        upper = z00 + v * (z01 - z00) + u * (z11 - z01)      # v > u: (i,j), (i+1,j+1), (i,j+1)
        return np.where(u >= v, lower, upper)


def oriented(scan: Scan, direction: str) -> tuple[np.ndarray, float, float, np.ndarray, np.ndarray]:
    """(heights, hx, hy, I, J) of the scan turned so that `direction` is +x (module docstring, step
    1): heights indexed [i along the cell's x, j along its y], grid steps [m], and the file's own
    indices of every node, turned the same way."""
    if direction not in AREAL_DIRECTIONS:
        raise InputError(f"unknown direction {direction!r}", where=scan.name,
                         fix=f"use one of {', '.join(AREAL_DIRECTIONS)}")
    if not scan.areal:
        raise InputError("a line scan, not an areal one", where=scan.name,
                         fix="give an areal scan (a grid of heights) or drop areal = true")
    H = np.asarray(scan.heights, float)
    I, J = np.indices(H.shape)
    hx, hy = float(np.median(np.diff(scan.x))), float(np.median(np.diff(scan.y)))

    def turn(a):
        return {"+x": a, "-x": a[::-1, ::-1], "+y": a[::-1, :].T, "-y": a[:, ::-1].T}[direction]

    steps = (hx, hy) if direction in ("+x", "-x") else (hy, hx)
    return turn(H), steps[0], steps[1], turn(I), turn(J)


def fill_small_holes(Z: np.ndarray, hx: float, hy: float, d50: float) -> np.ndarray:
    """Z [m] with every hole whose measured rims lie at most HOLE_D50·D50 apart (along x and along y)
    and which does not touch the grid's edge filled by harmonic interpolation from its rims; every
    other missing point stays NaN (module docstring, step 2)."""
    from scipy import ndimage

    missing = ~np.isfinite(Z)
    if not missing.any():
        return Z
    label, n = ndimage.label(missing)             # 4-connected: a hole's 4-neighbours are all measured
    idx = np.arange(1, n + 1)
    I, J = np.indices(Z.shape)
    i0, i1 = ndimage.minimum(I, label, idx), ndimage.maximum(I, label, idx)
    j0, j1 = ndimage.minimum(J, label, idx), ndimage.maximum(J, label, idx)
    small = (((i1 - i0 + 2) * hx <= HOLE_D50 * d50) & ((j1 - j0 + 2) * hy <= HOLE_D50 * d50)
             & (i0 > 0) & (j0 > 0) & (i1 < Z.shape[0] - 1) & (j1 < Z.shape[1] - 1))
    fill = np.concatenate([[False], small])[label]
    if not fill.any():
        return Z
    work = np.where(missing & ~fill, 0.0, Z)      # wider holes: defined for the solver, NaN again below
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        from SurfaceTopography import Topography

        topo = Topography(np.ma.masked_array(np.nan_to_num(work), mask=fill), Z.shape, periodic=False)
        filled = np.asarray(topo.interpolate_undefined_data().heights(), float)
    return np.where(missing & ~fill, np.nan, filled)


def _box_sums(F: np.ndarray, nx: int, ny: int) -> np.ndarray:
    """Σ of F over every (nx+1) × (ny+1) block of nodes, by its corner (a, b): a summed-area table."""
    S = np.zeros((F.shape[0] + 1, F.shape[1] + 1))
    S[1:, 1:] = F.cumsum(0).cumsum(1)
    return S[nx + 1:, ny + 1:] - S[:-nx - 1, ny + 1:] - S[nx + 1:, :-ny - 1] + S[:-nx - 1, :-ny - 1]


def _run_sums(F: np.ndarray, n: int, axis: int) -> np.ndarray:
    """Σ of F over every run of n + 1 consecutive entries along `axis`, by its first entry."""
    S = np.concatenate([np.zeros_like(np.take(F, [0], axis)), np.cumsum(F, axis)], axis)
    return np.take(S, np.arange(n + 1, S.shape[axis]), axis) - np.take(S, np.arange(0, S.shape[axis] - n - 1), axis)


def _line_relief(Z0: np.ndarray, n: int, axis: int) -> np.ndarray:
    """Σ of the squared heights about their own least-squares line of every run of n + 1 nodes along
    `axis`, by its first node."""
    k = np.arange(Z0.shape[axis], dtype=float)
    K = k[:, None] if axis == 0 else k[None, :]
    sz, szz, skz = _run_sums(Z0, n, axis), _run_sums(Z0 * Z0, n, axis), _run_sums(K * Z0, n, axis)
    start = np.arange(sz.shape[axis], dtype=float)
    mid = (start[:, None] if axis == 0 else start[None, :]) + n / 2
    skk = (n + 1) * ((n + 1) ** 2 - 1) / 12                         # Σ (k − k̄)² over the run
    return szz - sz ** 2 / (n + 1) - (skz - mid * sz) ** 2 / skk


def edge_mismatch(Z: np.ndarray, nx: int, ny: int) -> np.ndarray:
    """The edge-mismatch score (module docstring, step 3) of the window of nx × ny steps at every
    corner (a, b) of the grid Z [m]: shape (N − nx, M − ny); inf where the window holds a missing
    point or its edges have no relief."""
    bad = ~np.isfinite(Z)
    Z0 = np.where(bad, 0.0, Z - (np.nanmean(Z) if not bad.all() else 0.0))
    n_bad = _box_sums(bad.astype(float), nx, ny)
    e = Z0[nx:, :] - Z0[:-nx, :]                  # x-edges: (a, j) → z(a + nx, j) − z(a, j)
    g = Z0[:, ny:] - Z0[:, :-ny]
    # Σ (d − mean d)² over each edge, for the differences d and for the edge lines themselves
    mismatch = (_run_sums(e * e, ny, 1) - _run_sums(e, ny, 1) ** 2 / (ny + 1)
                + _run_sums(g * g, nx, 0) - _run_sums(g, nx, 0) ** 2 / (nx + 1))
    line_y, line_x = _line_relief(Z0, ny, 1), _line_relief(Z0, nx, 0)   # x = const: (N, M − ny); y = const
    relief = line_y[:-nx] + line_y[nx:] + line_x[:, :-ny] + line_x[:, ny:]
    with np.errstate(invalid="ignore", divide="ignore"):
        score = np.sqrt(np.maximum(mismatch, 0.0) / relief)
    return np.where((n_bad > 0.5) | ~(relief > 0) | ~np.isfinite(score), np.inf, score)


def _steps(want: float, h: float, n_nodes: int, what: str, where: str) -> int:
    """Grid steps of the window along one of the cell's axes: the whole number nearest `want` [m]."""
    n = max(2, int(round(want / h)))
    if n > n_nodes - 1:
        raise InputError(f"the cell's {what} ({want * 1e3:.4g} mm) is more than the scan holds that way "
                         f"({(n_nodes - 1) * h * 1e3:.4g} mm)", where=where,
                         fix="a smaller cell (box_length_d50, box_depth_d50) or another direction")
    return n


def cut_window(scan: Scan, d50: float, length: float, depth: float, direction: str = "+x",
               window: tuple[float, float] | None = None) -> Window:
    """The window of about `length` × `depth` [m] of `scan` for shear along `direction` (module
    docstring, steps 1–3): the best-closing one, or the one whose corner nearest the scan's origin
    lies at `window` = (x0, y0) [m] in the file's frame (snapped to the grid)."""
    Z, hx, hy, I, J = oriented(scan, direction)
    Z = fill_small_holes(Z, hx, hy, d50)
    nx = _steps(length, hx, Z.shape[0], f"length (along {direction})", scan.name)
    ny = _steps(depth, hy, Z.shape[1], "depth (across the shear)", scan.name)
    score = edge_mismatch(Z, nx, ny)
    ci = np.minimum(I[:-nx, :-ny], I[nx:, ny:])          # every window's corner in the file's indices
    cj = np.minimum(J[:-nx, :-ny], J[nx:, ny:])
    if window is None:
        if not np.isfinite(score).any():
            raise InputError(f"no window of {nx * hx * 1e3:.4g} × {ny * hy * 1e3:.4g} mm is free of missing points "
                             f"(holes wider than {HOLE_D50:g}·D50 are not filled)", where=scan.name,
                             fix="a smaller cell, another direction, or a scan with fewer missing points")
        a, b = np.unravel_index(int(np.argmin(score)), score.shape)
    else:
        hxf, hyf = float(np.median(np.diff(scan.x))), float(np.median(np.diff(scan.y)))
        at = np.argwhere((ci == round(window[0] / hxf)) & (cj == round(window[1] / hyf)))
        if at.size == 0:
            raise InputError(f"no window of this cell has its corner at ({window[0] * 1e3:.4g}, {window[1] * 1e3:.4g}) mm",
                             where=scan.name, fix=f"x0 in 0–{ci.max() * hxf * 1e3:.4g} mm and y0 in "
                             f"{cj.min() * hyf * 1e3:.4g}–{cj.max() * hyf * 1e3:.4g} mm for shear along {direction}")
        a, b = at[0]
        if not np.isfinite(score[a, b]):
            raise InputError(f"the window at ({window[0] * 1e3:.4g}, {window[1] * 1e3:.4g}) mm holds missing points",
                             where=scan.name, fix="move it, or omit window (the best-closing window is chosen)")
    origin = (float(scan.x[ci[a, b]]), float(scan.y[cj[a, b]]))
    return Window(Z[a:a + nx + 1, b:b + ny + 1].copy(), hx, hy, origin, float(score[a, b]), direction, scan.name,
                  (int(a), int(b)))


def _wrapped(u: np.ndarray) -> np.ndarray:
    """Torus heights (nx, ny) → grid nodes (nx+1, ny+1), the first row and column repeated last."""
    u = np.concatenate([u, u[:1]], axis=0)
    return np.concatenate([u, u[:, :1]], axis=1)


def close_slopes(Zw: np.ndarray, hx: float, hy: float) -> np.ndarray:
    """The periodic surface (nx+1, ny+1) [m], zero mean, whose slopes are nearest the window's Zw in
    least squares (module docstring, step 4): the normal equations diagonalise in Fourier on the torus."""
    nx, ny = Zw.shape[0] - 1, Zw.shape[1] - 1
    gx, gy = np.diff(Zw, axis=0), np.diff(Zw, axis=1)            # (nx, ny+1), (nx+1, ny)
    Gx, Gy = gx[:, :ny].copy(), gy[:nx, :].copy()
    Gx[:, 0] = 0.5 * (gx[:, 0] + gx[:, ny])                      # the edge row the torus holds once
    Gy[0, :] = 0.5 * (gy[0, :] + gy[nx, :])
    wx, wy = hy / hx, hx / hy                                    # (Δu/h)² dA per edge
    ox = np.exp(2j * np.pi * np.fft.fftfreq(nx))[:, None]        # u[i+1] ↔ ox·û
    oy = np.exp(2j * np.pi * np.fft.fftfreq(ny))[None, :]
    num = wx * (np.conj(ox) - 1) * np.fft.fft2(Gx) + wy * (np.conj(oy) - 1) * np.fft.fft2(Gy)
    den = wx * np.abs(ox - 1) ** 2 + wy * np.abs(oy - 1) ** 2
    den[0, 0], num[0, 0] = 1.0, 0.0                              # the mean: zero
    return _wrapped(np.fft.ifft2(num / den).real)


def close_ramps(Zw: np.ndarray) -> np.ndarray:
    """The compared alternative: Zw less each line's centred linear ramp of its edge mismatch, along
    x and along y with the corner twist counted once (the bilinear correction), zero mean."""
    nx, ny = Zw.shape[0] - 1, Zw.shape[1] - 1
    e, g = Zw[nx, :] - Zw[0, :], Zw[:, ny] - Zw[:, 0]
    s, t = np.arange(nx + 1)[:, None] / nx - 0.5, np.arange(ny + 1)[None, :] / ny - 0.5
    u = Zw - (e[None, :] * s + g[:, None] * t - (e[ny] - e[0]) * s * t)
    u = u[:nx, :ny]
    return _wrapped(u - u.mean())


def mirror_tile(Zq: np.ndarray) -> np.ndarray:
    """The compared alternative: the window Zq (q+1, p+1) reflected in x and in y, a periodic
    (2q+1, 2p+1) surface with no change of height, zero mean."""
    u = np.concatenate([Zq, Zq[-2::-1]], axis=0)
    u = np.concatenate([u, u[:, -2::-1]], axis=1)
    return u - u[:-1, :-1].mean()


def _plane_residual(Zw: np.ndarray) -> np.ndarray:
    """Zw less its least-squares plane."""
    I, J = np.indices(Zw.shape, dtype=float)
    A = np.column_stack([np.ones(Zw.size), I.ravel(), J.ravel()])
    coef = np.linalg.lstsq(A, Zw.ravel(), rcond=None)[0]
    return Zw - (A @ coef).reshape(Zw.shape)


def coarsened(patch: Patch, min_step: float) -> Patch:
    """`patch` as it is when its steps are at least `min_step` [m]; else resampled linearly and
    periodically along each too-fine axis to the coarsest step not under min_step (module docstring,
    step 5)."""
    z, x, y = patch.z, patch.x, patch.y
    for axis, pos in ((0, x), (1, y)):
        n = pos.size - 1
        h = pos[-1] / n
        if h >= min_step * (1 - 1e-9):
            continue
        m = max(2, int(math.floor(pos[-1] / min_step * (1 + 1e-12))))
        new = np.linspace(0.0, pos[-1], m + 1)
        k = new / h
        i0 = np.clip(np.floor(k).astype(int), 0, n - 1)
        f = (k - i0)[:, None] if axis == 0 else (k - i0)[None, :]
        lo, hi = np.take(z, i0, axis), np.take(z, i0 + 1, axis)
        z = lo + f * (hi - lo)
        x, y = (new, y) if axis == 0 else (x, new)
    if z is patch.z:
        return patch
    z = z.copy()
    z[-1, :], z[:, -1] = z[0, :], z[:, 0]               # exactly periodic after rounding
    return Patch(x, y, z, patch.name, patch.direction, patch.origin, patch.mismatch, patch.closure_rms,
                 patch.closure_max)


def make_patch(scan: Scan, d50: float, length: float, depth: float, direction: str = "+x",
               window: tuple[float, float] | None = None, min_step: float = 0.0) -> Patch:
    """The closed patch of `scan` for a cell of about `length` × `depth` [m] sheared along `direction`
    (the module docstring's five steps); `window` pins the window's corner (x0, y0) [m] in the file's
    frame; `min_step` [m] the finest mesh step."""
    w = cut_window(scan, d50, length, depth, direction, window)
    u = close_slopes(w.z, w.hx, w.hy)
    change = _plane_residual(u - w.z)          # what the closure changed, its tilt (levelling) aside
    nx, ny = w.z.shape[0] - 1, w.z.shape[1] - 1
    patch = Patch(np.arange(nx + 1) * w.hx, np.arange(ny + 1) * w.hy, u, scan.name, direction, w.origin, w.mismatch,
                  float(np.sqrt(np.mean(change ** 2))), float(np.abs(change).max()))
    return coarsened(patch, min_step)


def periodic_lines(z: np.ndarray, h: float, d50: float) -> tuple[np.ndarray, np.ndarray, float]:
    """(positions, lines, dx) for θa of a periodic surface's lines along its first axis (z (n+1, m+1),
    step h [m]): each of the m distinct lines resampled on dx = h/k (areal.areal_step's choice) and
    wrapped by the grain's radius at each end, so that a grain rolled over the open line sees
    exactly one period (its trace spans [0, L])."""
    n, m = z.shape[0] - 1, z.shape[1] - 1
    lines = z[:, :m].T                                   # (m, n+1), the repeated line y = W left out
    dx = areal_step(h, m * n * h, d50)
    k = max(1, int(round(h / dx)))
    dx = h / k
    q = np.arange(n * k + 1)
    i0 = np.minimum(q // k, n - 1)
    f = (q - i0 * k) / k
    fine = lines[:, i0] + f * (lines[:, i0 + 1] - lines[:, i0])
    K = int(math.floor((d50 / 2) / dx))
    P = n * k                                            # fine samples per period
    if K > P:
        raise InputError(f"the cell ({n * h * 1e3:.4g} mm) is shorter than a grain's radius", where="patch")
    padded = np.concatenate([fine[:, P - K:P], fine, fine[:, 1:K + 1]], axis=1)
    return np.arange(padded.shape[1]) * dx, padded, dx


def theta_a_patch(patch: Patch, d50: float, filters=FILTERS) -> dict[str, dict[int, ArealThetaA]]:
    """θa of the patch as the cell shears it: {"+x": {filter: ArealThetaA}, "-x": {…}} of the normals
    pooled over its grid lines along x (surface.areal), each line read as periodic (`periodic_lines`:
    wrapped, not levelled, its trace exactly one period). "+x" is the cell's shear (soil moving +x),
    "-x" the cell sheared back. Rn and the mean slope count the wrapped D50/2 at each end twice
    (D50/L of their weight)."""
    s, lines, dx = periodic_lines(patch.z, patch.length / (patch.z.shape[0] - 1), d50)
    res = theta_a_lines(s, lines, d50, filters, dx=dx, where=f"{patch.name} (patch along x)", level=False)
    from dataclasses import replace

    return {sign + "x": {f: replace(r, direction=sign + "x") for f, r in res[sign].items()} for sign in "+-"}
