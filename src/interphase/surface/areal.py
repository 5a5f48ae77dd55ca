"""θa of an areal scan: every grid line along the shear axis is a profile (docs/methods.md, "Areal scans").

Rule. The lines along the axis are split at missing points into valid runs; runs shorter than
MIN_RUN_D50·D50 are dropped (and counted). Each run is levelled by its own least-squares line,
resampled linearly on a uniform step dx (a whole fraction of the scan's step) and rolled over by a
grain of diameter D50: its centroid trace is defined where the grain lies wholly over the run
(r = D50/2 lost at each end, as for an open line). The trace segments of all runs are pooled — one
normal distribution — and θa is its principal direction over the normals facing the shear (the
filters of normals.py); the per-run θa give the spread (5 and 95 % quantiles over the runs that
have one). Rn, Rnc and the mean asperity slope are pooled the same way (all windows, all faces).

Directions: shear in +x along the chosen axis reads the trace normals θ; −x (the profile mirrored)
reads π − θ from the same trace; ±y do the same on the other axis's lines. Everything is numpy over
the concatenated runs; the only Python loops are over blocks of ~32 k samples and the K = r/dx shifts
of the half-disk dilation (the same exact-on-the-grid max as trace.dilate_half_disk).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from interphase.errors import InputError
from interphase.surface.base import Scan, check_axis
from interphase.surface.lines import valid_runs
from interphase.surface.normals import FILTERS, FLAT_TOLERANCE_DEG, keep_mask
from interphase.surface.roughness import running

MIN_RUN_D50 = 5.0
#: sample shifts (samples × K) one axis may cost; sets the step of large scans (see areal_step)
AREAL_WORK_BUDGET = 1.5e8
FINEST_STEPS_PER_D50 = 2000
DIRECTIONS = ("+x", "-x", "+y", "-y")
_BLOCK = 1 << 15


@dataclass(frozen=True)
class ArealThetaA:
    direction: str              # "+x", "-x", "+y", "-y": the soil's motion relative to the surface
    theta_a_deg: float          # ψa of the pooled normals, degrees from vertical; NaN if non-dilative
    theta_a_ccw_deg: float
    spread_deg: tuple[float, float]   # 5 and 95 % quantiles of the per-run ψa (NaN if no run has one)
    filter: int
    d50: float
    rn: float                   # pooled Rn of the levelled runs (windows of D50)
    rnc: float                  # pooled Rnc(D50) of their centroid traces
    mean_slope_deg: float       # pooled mean asperity slope (flats < 2° excluded)
    n_lines: int                # grid lines along the axis
    n_runs: int                 # valid runs used
    n_dropped: int              # valid runs shorter than MIN_RUN_D50·D50, dropped
    n_runs_dilative: int        # runs with a θa of their own
    n_points: int               # trace points pooled
    trace_share: float          # share of the scan's line length (lines × span) under the pooled trace
    step: float                 # resampling step dx [m]
    kept_fraction: float
    max_tilt_deg: float
    dilative: bool
    reason: str

    def to_dict(self) -> dict:
        d = asdict(self)
        d["spread_deg"] = list(self.spread_deg)
        return d


@dataclass
class _Axis:
    """The pooled runs of one axis: levelled profile and trace, run ids, step."""
    n_lines: int
    n_runs: int
    n_dropped: int
    step: float
    slope: np.ndarray = field(repr=False)         # dc/dx of every trace segment
    wc2: np.ndarray = field(repr=False)           # w·cos 2θ of its normal (θ ccw from +axis, w its length)
    ws2: np.ndarray = field(repr=False)           # w·sin 2θ
    weight: np.ndarray = field(repr=False)
    seg_run: np.ndarray = field(repr=False)       # run of each trace segment
    rn: float = math.nan
    rnc: float = math.nan
    slope_deg: float = math.nan
    n_points: int = 0
    trace_share: float = math.nan


def areal_step(data_step: float, total_length: float, d50: float) -> float:
    """Resampling step [m]: the scan's step divided by a whole number m, as fine as D50/2000 allows
    but with (samples × K shifts) within AREAL_WORK_BUDGET: dx ≈ max(D50/2000, sqrt(L·D50/(2·budget)))."""
    target = max(d50 / FINEST_STEPS_PER_D50, math.sqrt(total_length * d50 / (2 * AREAL_WORK_BUDGET)))
    m = max(1, math.ceil(data_step / target - 1e-9))
    return data_step / m


def dilate_blocks(z: np.ndarray, radius_steps: float) -> np.ndarray:
    """trace.dilate_half_disk for an open profile (positions K … n−K−1), in blocks that stay in cache."""
    K = int(math.floor(radius_steps))
    n = z.size
    m = n - 2 * K
    if m <= 0:
        return np.empty(0)
    h = np.sqrt(np.maximum(radius_steps ** 2 - np.arange(K + 1, dtype=float) ** 2, 0.0))
    out = np.empty(m)
    tmp = np.empty(min(_BLOCK, m))
    for b0 in range(0, m, _BLOCK):
        b1 = min(m, b0 + _BLOCK)
        L = b1 - b0
        o = out[b0:b1]
        np.add(z[K + b0:K + b1], h[0], out=o)
        t = tmp[:L]
        for k in range(1, K + 1):
            np.maximum(z[K + b0 + k:K + b1 + k], z[K + b0 - k:K + b1 - k], out=t)
            t += h[k]
            np.maximum(o, t, out=o)
    return out


def _window_rt(z: np.ndarray, run: np.ndarray, pos: np.ndarray, run_len: np.ndarray, w: int) -> tuple[float, int]:
    """Sum of (max − min) over every window of w samples lying inside one run, and their count."""
    if z.size < w:
        return 0.0, 0
    # windows starting at i = 0 … z.size − w; a window inside its run starts no later than that
    ok = (pos + w - 1 <= run_len[run] - 1)[: z.size - w + 1]
    rt = running(z, w, np.maximum) - running(z, w, np.minimum)
    return float(np.sum(rt[ok])), int(np.count_nonzero(ok))


def _level_runs(run: np.ndarray, x: np.ndarray, z: np.ndarray, nr: np.ndarray) -> np.ndarray:
    """z less each run's own least-squares line (x centred per run: no cancellation)."""
    R = nr.size
    cnt = nr.astype(float)
    xm = np.bincount(run, x, R) / cnt
    zm = np.bincount(run, z, R) / cnt
    xc = x - xm[run]
    b = np.bincount(run, xc * (z - zm[run]), R) / np.bincount(run, xc * xc, R)
    return z - zm[run] - b[run] * xc


def _prepare_axis(s: np.ndarray, Z: np.ndarray, d50: float, dx: float | None, where: str,
                  level: bool = True) -> _Axis:
    n_lines, n = Z.shape
    if n < 2:
        raise InputError("the scan has fewer than 2 points along the axis", where=where, fix="choose the other axis")
    h = float(np.median(np.diff(s)))
    line, start, stop = valid_runs(np.isfinite(Z))
    length = (stop - start - 1) * h
    keep = length >= MIN_RUN_D50 * d50 * (1 - 1e-9)
    n_dropped = int(np.count_nonzero(~keep))
    line, start, stop = line[keep], start[keep], stop[keep]
    R = line.size
    if R == 0:
        longest = float(length.max()) if length.size else 0.0
        raise InputError(f"no valid run of measured points along this axis is {MIN_RUN_D50:g}·D50 = "
                         f"{MIN_RUN_D50 * d50 * 1e3:.4g} mm long (longest {longest * 1e3:.4g} mm; "
                         f"{n_dropped} runs dropped)", where=where,
                         fix="give a larger scan, a smaller --d50, or the other --axis")
    nr = stop - start
    # gather the kept runs back to back: run id and position within the run of every data point
    run = np.repeat(np.arange(R), nr)
    first = np.concatenate([[0], np.cumsum(nr)[:-1]])
    pos = np.arange(run.size) - first[run]
    z = Z[line[run], start[run] + pos]
    x = pos * h
    if level:               # each run levelled by its own least-squares line
        z = _level_runs(run, x, z, nr)
    # mean asperity slope on the data segments (linear resampling keeps every face's slope)
    seg = pos < nr[run] - 1
    dz = np.diff(z)[seg[:-1]]
    ang = np.degrees(np.abs(np.arctan2(dz, h)))
    face = ang > FLAT_TOLERANCE_DEG
    slope = float(np.mean(ang[face])) if face.any() else math.nan
    # resample on dx = h/m: each data segment gives m samples, each run's last point closes it
    total = float(np.sum((nr - 1) * h))
    if dx is None:
        dx = areal_step(h, total, d50)
    m = max(1, int(round(h / dx)))
    dx = h / m
    nf = (nr - 1) * m + 1
    ffirst = np.concatenate([[0], np.cumsum(nf)[:-1]])
    zf = np.empty(int(nf.sum()))
    i0 = np.flatnonzero(seg)
    frac = np.arange(m) / m
    # segments come in run order, so their samples fill every place but the runs' last points
    body = np.ones(zf.size, bool)
    body[ffirst + nf - 1] = False
    zf[body] = (z[i0, None] + (z[i0 + 1] - z[i0])[:, None] * frac).ravel()
    zf[~body] = z[first + nr - 1]
    frun = np.repeat(np.arange(R), nf)
    fpos = np.arange(zf.size) - ffirst[frun]
    # Rn: every window of D50 inside a run, pooled
    w = int(round(d50 / dx)) + 1
    srt, nwin = _window_rt(zf, frun, fpos, nf, w)
    rn = srt / nwin / d50 if nwin else math.nan
    # centroid trace: the dilation over the concatenated runs, kept where the grain lies inside its run
    r = d50 / 2
    K = int(math.floor(r / dx))
    c = dilate_blocks(zf / dx, r / dx) * dx           # positions K … N−K−1
    crun, cpos = frun[K:K + c.size], fpos[K:K + c.size]
    inside = (cpos >= K) & (cpos <= nf[crun] - 1 - K)
    c, crun = c[inside], crun[inside]
    nt = nf - 2 * K
    tpos = cpos[inside] - K
    same = crun[1:] == crun[:-1]
    dc = np.diff(c)[same]
    # θ = atan2(dx, −dc): e^{2iθ} = (dc² − dx² − 2i·dx·dc)/w², no trigonometry needed
    weight = np.hypot(dx, dc)
    wc2 = (dc * dc - dx * dx) / weight
    ws2 = -2 * dx * dc / weight
    srtc, nwinc = _window_rt(c, crun, tpos, nt, w)
    rnc = srtc / nwinc / d50 if nwinc else math.nan
    return _Axis(n_lines, R, n_dropped, dx, dc / dx, wc2, ws2, weight, crun[1:][same], rn, rnc, slope, int(c.size),
                 _trace_share(nt, dx, n_lines * float(s[-1] - s[0])))


def _trace_share(trace_points: np.ndarray, dx: float, line_length: float) -> float:
    """The share of the lines' total length [m] under the runs' traces: missing points, dropped runs
    and the grain's half-width at each run's ends leave the rest unseen."""
    return float(np.sum(np.maximum(trace_points - 1, 0)) * dx / line_length) if line_length > 0 else math.nan


def _kept(t: np.ndarray, filt: int) -> tuple[np.ndarray, np.ndarray]:
    """normals.keep_mask in slopes: θ = 90° + atan(t) for a segment of slope t, so θ > 92° ⇔ t > tan 2°
    and θ ≥ 90° ⇔ t ≥ 0 (same tolerance); also which kept ones lie strictly beyond 90°."""
    if filt == 92:
        keep = t > math.tan(math.radians(2.0))
        return keep, keep
    if filt == 90:
        return t >= -1e-12, t > 1e-12
    return keep_mask(np.zeros(0), filt), None      # raises the unknown-filter message


def _result(ax: _Axis, direction: str, filt: int, d50: float) -> ArealThetaA:
    sign = 1.0 if direction[0] == "+" else -1.0      # mirrored: θ → π − θ, slope → −slope, sin 2θ → −sin 2θ
    t = sign * ax.slope
    w = ax.weight
    keep, beyond = _kept(t, filt)
    c2, s2 = ax.wc2[keep], sign * ax.ws2[keep]
    wk = w[keep]
    tilt = float(np.degrees(np.arctan(np.max(np.abs(t))))) if t.size else 0.0
    ccw = math.nan
    if wk.size and np.any(wk > 0) and np.any(beyond):
        ccw = float(np.mod(0.5 * math.atan2(s2.sum(), c2.sum()), np.pi))
    # per run: the same principal direction of that run's kept normals
    runs = ax.seg_run[keep]
    rc = np.bincount(runs, c2, ax.n_runs)
    rs = np.bincount(runs, s2, ax.n_runs)
    has = np.bincount(runs, minlength=ax.n_runs) > 0
    if filt == 90:
        has &= np.bincount(ax.seg_run[beyond], minlength=ax.n_runs) > 0
    per_run = np.degrees(np.mod(0.5 * np.arctan2(rs[has], rc[has]), np.pi)) - 90.0
    spread = tuple(float(v) for v in np.percentile(per_run, [5, 95])) if per_run.size else (math.nan, math.nan)
    reason = ""
    if math.isnan(ccw):
        reason = (f"non-dilative: no centroid-trace normal beyond the {filt}° filter at D50 = {d50 * 1e3:g} mm "
                  f"(largest normal tilt {tilt:.3g}°)")
    return ArealThetaA(
        direction=direction,
        theta_a_deg=math.degrees(ccw) - 90.0 if not math.isnan(ccw) else math.nan,
        theta_a_ccw_deg=math.degrees(ccw) if not math.isnan(ccw) else math.nan,
        spread_deg=spread, filter=filt, d50=d50, rn=ax.rn, rnc=ax.rnc, mean_slope_deg=ax.slope_deg,
        n_lines=ax.n_lines, n_runs=ax.n_runs, n_dropped=ax.n_dropped, n_runs_dilative=int(per_run.size),
        n_points=ax.n_points, trace_share=ax.trace_share, step=ax.step,
        kept_fraction=float(wk.sum() / w.sum()) if w.sum() > 0 else 0.0,
        max_tilt_deg=tilt, dilative=not math.isnan(ccw), reason=reason)


def theta_a_lines(s: np.ndarray, Z: np.ndarray, d50: float, filters=FILTERS, dx: float | None = None,
                  where: str = "scan", level: bool = True) -> dict[str, dict[int, ArealThetaA]]:
    """{"+": {filter: …}, "-": {…}} for the lines Z (n_lines, n_points) [m] at positions s [m]:
    "+" the soil moving toward +s, "-" toward −s (the lines mirrored). `level` False keeps the lines'
    heights as given (a periodic surface's lines, which levelling would tilt: surface.patch)."""
    if not (isinstance(d50, (int, float)) and math.isfinite(d50) and d50 > 0):
        raise InputError(f"D50 must be a positive length, got {d50!r}", where="--d50")
    for filt in filters:
        if filt not in FILTERS:
            raise InputError(f"unknown filter {filt!r}", where="--filter", fix="use 92 or 90")
    ax = _prepare_axis(np.asarray(s, float), np.atleast_2d(np.asarray(Z, float)), d50, dx, where, level)
    return {sign: {f: _result(ax, sign + "s", f, d50) for f in filters} for sign in "+-"}


def theta_a_scan(scan: Scan, d50: float, filters=FILTERS, axes=("x", "y"), dx: float | None = None
                 ) -> dict[str, dict[int, ArealThetaA]]:
    """{direction: {filter: ArealThetaA}} for shear along each of `axes` in both senses ("+x", "-x", …)."""
    out = {}
    for axis in axes:
        check_axis(axis, "--axis")
        s, Z = scan.lines(axis)
        res = theta_a_lines(s, Z, d50, filters, dx, where=f"{scan.name} (lines along {axis})")
        for sign in "+-":
            out[sign + axis] = {f: _relabel(r, sign + axis) for f, r in res[sign].items()}
    return out


def _relabel(r: ArealThetaA, direction: str) -> ArealThetaA:
    from dataclasses import replace

    return replace(r, direction=direction)
