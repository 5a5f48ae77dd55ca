"""What closing an areal scan's patch does to its θa (issue 72 item 1; docs/3d.md, "A measured areal
scan as the surface"): the numbers of that section's tables.

    PYTHONPATH=src python studies/scan_patch_bias/scan_patch_bias.py [--windows N] [--d50 MM]

For each surface (the shipped FRT scans; a self-affine surface synthesised periodic over the cell,
3 × 3 periods of it with the middle one as the window, which closes already; one synthesised over
4 × 4 cells, whose windows do not) and each orientation of the cell (+x, +y; −x and −y are the
same windows read the other way), on the Karlsruhe 3D card's cell (30 × 10 D50 at D50 0.14 mm),
θa (filter 92, degrees from vertical, NaN: non-dilative) of:
  raw       the chosen window as measured, its lines read open and levelled (surface.areal.theta_a_lines),
  raw_ext   the same lines extended by D50/2 of the scan at each end, so that the grain's trace
            covers the whole window as it does on the periodic cell (NaN where the scan ends),
  closed    the closed patch as the cell shears it (surface.patch.theta_a_patch: periodic lines),
  ramps     the window closed by per-line ramps instead (patch.close_ramps), read the same way,
  mirror    the window's lower-left L/2 × W/2 mirrored into a cell (patch.mirror_tile), read the same
            way, against half, that quarter's own open reading,
with the chosen window's edge-mismatch score, the closure's change of height (rms, largest) and
the share of the window's slope energy each closure changes (change: least squares; change_ramps:
ramps). Then, over N windows drawn at random among the complete ones (seeded; both senses of each),
the closure's effect: the mean and the largest |closed − raw_ext|, |ramps − raw_ext| and
|closed − raw| over the readings where both are defined, and the mean shares of slope energy changed.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from interphase.surface.areal import theta_a_lines
from interphase.surface.base import Scan
from interphase.surface.patch import (Patch, close_ramps, close_slopes, cut_window, edge_mismatch,
                                      fill_small_holes, make_patch, mirror_tile, oriented, theta_a_patch)
from interphase.surface.readers import read_scan

ROOT = Path(__file__).resolve().parents[2]
SCANS = {"frt-1": ROOT / "campaigns" / "profiles" / "frt-1.frt", "frt-2": ROOT / "campaigns" / "profiles" / "frt-2.frt"}
L_D50, W_D50 = 30, 10


def synthetic(nx: int, ny: int, h: float, seed: int, long_cutoff: float, tiles: int = 1) -> Scan:
    """A self-affine surface (H 0.8, rms slope 0.3, short cut-off 4 steps, roll-off at `long_cutoff`
    [m]) periodic over nx × ny steps of h [m], given as a scan of `tiles` × `tiles` periods plus the
    closing node."""
    import contextlib
    import io
    import warnings

    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        from SurfaceTopography.Generation import fourier_synthesis

        t = fourier_synthesis((nx, ny), (nx * h, ny * h), hurst=0.8, rms_slope=0.3, short_cutoff=4 * h,
                              long_cutoff=long_cutoff, rng=seed)
        z = np.asarray(t.heights(), float)
    z = np.tile(z, (tiles, tiles)) if tiles > 1 else z
    z = np.concatenate([z, z[:1]], 0)
    z = np.concatenate([z, z[:, :1]], 1)
    return Scan(z, np.arange(z.shape[0]) * h, np.arange(z.shape[1]) * h, f"synthetic-{seed}", "m", "synthetic")


def _theta(x, Z, d50, level=True):
    r = theta_a_lines(x, Z, d50, (92,), level=level)
    return r["+"][92].theta_a_deg, r["-"][92].theta_a_deg


def _closed(z, hx, hy, name, d50):
    nx, ny = z.shape[0] - 1, z.shape[1] - 1
    p = Patch(np.arange(nx + 1) * hx, np.arange(ny + 1) * hy, z, name, "+x", (0.0, 0.0), math.nan, math.nan, math.nan)
    r = theta_a_patch(p, d50, (92,))
    return r["+x"][92].theta_a_deg, r["-x"][92].theta_a_deg


def _extended(Z, a, b, nx, ny, pad):
    if a - pad < 0 or a + nx + 1 + pad > Z.shape[0]:
        return None
    E = Z[a - pad:a + nx + 1 + pad, b:b + ny + 1]
    return E if np.isfinite(E).all() else None


def window_readings(Zf, hx, hy, a, b, nx, ny, d50):
    """θa (+, −) of one window: raw, raw+, closed, closed read open."""
    w = Zf[a:a + nx + 1, b:b + ny + 1]
    x = np.arange(nx + 1) * hx
    pad = int(math.ceil(0.5 * d50 / hx))
    E = _extended(Zf, a, b, nx, ny, pad)
    raw_ext = _theta(np.arange(E.shape[0]) * hx, E.T, d50) if E is not None else (math.nan, math.nan)
    u, v = close_slopes(w, hx, hy), close_ramps(w)
    return dict(raw=_theta(x, w.T, d50), raw_ext=raw_ext, closed=_closed(u, hx, hy, "w", d50),
                ramps=_closed(v, hx, hy, "w", d50), change=slope_change(w, u), change_ramps=slope_change(w, v))


def slope_change(w, u):
    """Σ over the grid's edges of the closure's change of slope (u − w, less its mean along each axis:
    the tilt, which levelling takes for free), over the same sum of the window's own slopes: the share
    of the window's slope energy the closure changes."""
    def energy(f):
        gx, gy = np.diff(f, axis=0), np.diff(f, axis=1)
        return float(np.sum((gx - gx.mean()) ** 2) + np.sum((gy - gy.mean()) ** 2))
    return energy(u - w) / energy(w)


def table_rows(name: str, scans, d50: float, n_windows: int, seed: int = 1):
    """The table's rows of one surface: `scans` {orientation: (Scan, window corner or None)}."""
    L, W = L_D50 * d50, W_D50 * d50
    for direction, (scan, pin) in scans.items():
        win = cut_window(scan, d50, L, W, direction, pin)
        patch = make_patch(scan, d50, L, W, direction, pin)
        Z, hx, hy, _, _ = oriented(scan, direction)
        Zf = fill_small_holes(Z, hx, hy, d50)
        nx, ny = win.z.shape[0] - 1, win.z.shape[1] - 1
        r = window_readings(Zf, hx, hy, *win.at, nx, ny, d50)
        ramps = _closed(close_ramps(win.z), hx, hy, name, d50)
        q = win.z[:nx // 2 + 1, :ny // 2 + 1]
        mirror = _closed(mirror_tile(q), hx, hy, name, d50)
        half = _theta(np.arange(q.shape[0]) * hx, q.T, d50)
        # the closure over N random complete windows
        score = edge_mismatch(Zf, nx, ny)
        ok = np.argwhere(np.isfinite(score))
        rng = np.random.default_rng(seed)
        d_ext, d_ramps, d_raw, change, change_ramps = [], [], [], [], []
        for k in rng.choice(len(ok), min(n_windows, len(ok)), replace=False):
            s = window_readings(Zf, hx, hy, *ok[k], nx, ny, d50)
            change.append(s["change"])
            change_ramps.append(s["change_ramps"])
            for i in (0, 1):
                if np.isfinite(s["closed"][i]) and np.isfinite(s["raw_ext"][i]):
                    d_ext.append(s["closed"][i] - s["raw_ext"][i])
                    d_ramps.append(s["ramps"][i] - s["raw_ext"][i])
                if np.isfinite(s["closed"][i]) and np.isfinite(s["raw"][i]):
                    d_raw.append(s["closed"][i] - s["raw"][i])
        other = {"+x": "-x", "+y": "-y"}[direction]
        for i, sense in ((0, direction), (1, other)):
            yield dict(surface=name, d50_mm=d50 * 1e3, direction=sense, origin_mm=tuple(round(v * 1e3, 3) for v in win.origin),
                       cell=f"{nx} × {ny}", score=win.mismatch, closure_rms_nm=patch.closure_rms * 1e9,
                       closure_max_nm=patch.closure_max * 1e9, raw=r["raw"][i], raw_ext=r["raw_ext"][i],
                       closed=r["closed"][i], ramps=ramps[i], half=half[i], mirror=mirror[i],
                       change=r["change"], change_ramps=r["change_ramps"], mean_change=float(np.mean(change)),
                       mean_change_ramps=float(np.mean(change_ramps)),
                       n_windows=len(d_ext), mean_ext=np.mean(d_ext) if d_ext else math.nan,
                       max_ext=np.max(np.abs(d_ext)) if d_ext else math.nan,
                       mean_ramps=np.mean(d_ramps) if d_ramps else math.nan,
                       max_ramps=np.max(np.abs(d_ramps)) if d_ramps else math.nan,
                       mean_raw=np.mean(d_raw) if d_raw else math.nan,
                       max_raw=np.max(np.abs(d_raw)) if d_raw else math.nan)


def _fmt(v):
    if isinstance(v, float):
        return "NaN" if math.isnan(v) else (f"{v:.2f}" if abs(v) >= 0.01 or v == 0 else f"{v:.1e}")
    return str(v)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--windows", type=int, default=12, help="random complete windows per orientation")
    ap.add_argument("--d50", type=float, default=0.14, help="D50 [mm]")
    args = ap.parse_args(argv)
    d50 = args.d50 * 1e-3
    h = 24e-6
    nx, ny = int(round(L_D50 * d50 / h)), int(round(W_D50 * d50 / h))
    surfaces = {k: {d: (read_scan(v), None) for d in ("+x", "+y")} for k, v in SCANS.items()}
    # periodic over the cell (L × W along the shear and across it), 3 × 3 periods: the middle one
    across = {"+x": (nx, ny), "+y": (ny, nx)}
    surfaces["self-affine, periodic"] = {
        d: (synthetic(*across[d], h, 7, ny * h, tiles=3), (across[d][0] * h, across[d][1] * h)) for d in ("+x", "+y")}
    surfaces["self-affine, 4 × 4 cells"] = {d: (synthetic(4 * nx, 4 * ny, h, 8, ny * h), None) for d in ("+x", "+y")}
    first = ["surface", "d50_mm", "direction", "origin_mm", "cell", "score", "closure_rms_nm", "closure_max_nm",
             "change", "change_ramps", "raw", "raw_ext", "closed", "ramps", "half", "mirror"]
    second = ["surface", "direction", "n_windows", "mean_ext", "max_ext", "mean_ramps", "max_ramps", "mean_raw",
              "max_raw", "mean_change", "mean_change_ramps"]
    rows = [row for name, scans in surfaces.items() for row in table_rows(name, scans, d50, args.windows)]
    for cols in (first, second):
        print("| " + " | ".join(cols) + " |")
        print("|" + "---|" * len(cols))
        for row in rows:
            print("| " + " | ".join(_fmt(row[c]) for c in cols) + " |")
        print()

if __name__ == "__main__":
    main()
