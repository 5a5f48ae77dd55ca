"""Order of the grains in the soil test ("box") and on rough teeth: does crystallisation of the
uniform discs explain why their soil test reads weaker than the same grains on teeth?
(Results: studies/uniform_order/results/uniform_order_2026-12-05.md.)

What it measures, per finished run folder (particles.parquet, series.parquet, case.json,
summary.json; from `campaign run studies/uniform_order/uniform_order.toml` or
studies/uniform_order/uniform_order_disordered.py), at the start of the shear (snapshot 0) and at its end (the last
snapshot, 6 mm):
  - |ψ6| per grain [-]: the 2D bond-orientational (hexatic) order, |mean over neighbours of
    exp(6iθ)|, where θ is the bond's angle in the x–z plane. Neighbours are the edges of a Delaunay
    triangulation (scipy.spatial) of the grain centres with their periodic images at x ± L (L the
    cell length), so no grain loses a neighbour at the periodic boundary. Edges longer than 2 d_max
    (the hull's spurious edges at the free top) are dropped. A triangular lattice gives 1; a
    disordered packing gives ~0.45 here. Reported per zone: the mean |ψ6|, the share of grains with
    |ψ6| > 0.7, and the lattice orientation arg(ψ6)/6 [°] as the share of ordered grains whose rows
    lie within ±7.5° of the shear direction ("horiz": rows parallel to the shear, the planes a
    crystal slips on in this test).
  - heights h [D50] above the boundary: the teeth's tips (max z of surface.stl) on the interface,
    the top of the frozen bed in the box (max z + r of its grains, the grains at the lowest height,
    which never move in z). Grains with h < 0.5 D50 (on teeth, those touching the surface) and those
    within 3 D50 of the highest grain top (the platen) are left out of every zone.
  - the normalised x-displacement profile U(h) [-] between two snapshots, by layers 1 D50 thick,
    with x unwrapped across the periodic boundary. U = 1 moves with the boundary (surface or bed,
    which travel −x); U = 0 moves with the top (the mean of the grains within 2 D50 of the highest
    centre). The active slip plane of an interval is the height of the largest drop of U between
    adjacent layers. Zones: "band" = within 1.5 D50 of the slip plane of the last 1 mm (at the
    start: of the first 1 mm); "outside" = at least 4 D50 from it; "endband" = the end band's
    grains at either time; fixed layers h 0.5–2, 2–5, 5–top. Over every 0.5-mm interval from 1 mm:
    slip_share = the largest jump's share of the whole drop (1 = one plane takes all the shear;
    ~1/n for a uniform shear over n layers); slip_plane_bottom3 / top3 = the share of intervals
    whose plane lies within 3 D50 of the boundary / of the top; slip_plane_h_d50 = its mean height.
  - the stress-ratio curve (series.parquet) smoothed over the tool's 0.5-D50 peak window:
    ratio_mean_1mm and ratio_sd_1mm (mean and sd from 1 mm of shear on; the sd measures stick–slip)
    and peak_over_mean [-].
  - the tool's shear_band_d50 recomputed as the tool does it (tool_band_asis_d50) and with x
    unwrapped (tool_band_unwrapped_d50), plus the number of grains crossing the periodic boundary
    between the snapshots it uses (n_wrapped_peak_interval): the committed value is a wrap artefact.
  - the run's own summary values (peak_stress_ratio, residual_stress_ratio, solid_fraction,
    a_region = the fabric anisotropy in the region at the peak snapshot).
  - E = tan δ / tan φ at the peak and at the critical state from the seed ensembles, as the tool's
    ensembles table reads them (analysis.ensemble.ensemble_efficiency).
Means over seeds come with their 95 % Student-t interval (interphase.analysis.ensemble.t_interval),
differences with a Welch 95 % interval.

Run, from the repository root:
    PYTHONPATH=src .venv/bin/python studies/uniform_order/uniform_order.py RUNS [--csv OUT.csv] [--box-runs RUNS2]
        per-run table, per-category summary (mono/poly × box/teeth) and E (Markdown)
    PYTHONPATH=src .venv/bin/python studies/uniform_order/uniform_order.py X --compare "LABEL=RUNS:TEST:GRADATION" ...
        sets side by side, Welch differences from the first, and each set's seed-mean peak
    PYTHONPATH=src .venv/bin/python studies/uniform_order/uniform_order.py X --figure OUT.png CASE_FOLDER ...
        the grains coloured by |ψ6| at the start and the end of the shear
Units: heights in D50, ratios, U and |ψ6| dimensionless, displacements in mm where printed. Needs
numpy, pandas, scipy and matplotlib (the project's venv); ~0.1 s per run.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from scipy.spatial import Delaunay

from interphase.analysis.difference import difference
from interphase.analysis.ensemble import t_interval

ORDERED = 0.7          # |ψ6| above which a grain counts as ordered (the tool's CRYSTALLINE_PSI6)
BAND_LEVEL = 0.1       # U at the band's top (interphase.analysis.strength.BAND_LEVEL)
EXCLUDE_LOW = 0.5      # grains closer than this [D50] above the boundary are left out of the zones
TOP_CLEAR = 3.0        # and those within this [D50] of the highest grain top (the platen)
BAND_HALF = 1.5        # the band: grains within this [D50] of the active slip plane
OUTSIDE_GAP = 4.0      # outside the band: grains at least this [D50] from it


# ---- order ---------------------------------------------------------------------------------------

def psi6(x, z, r, length: float) -> np.ndarray:
    """Complex ψ6 per grain (NaN for a grain with fewer than 2 neighbours): Delaunay of the centres
    with their images at x ± length; each original grain's edges to any copy count. Not the element
    test's analysis.element.hexatic_order, which returns the mean |ψ6| only, over contact-distance
    neighbours without periodic images: the zones here need each grain's value and orientation, and
    the cell's ends are where the grains cross."""
    n = x.size
    xs = np.concatenate([x, x - length, x + length])
    zs = np.concatenate([z, z, z])
    tri = Delaunay(np.column_stack([xs, zs]))
    s = tri.simplices
    e = np.concatenate([s[:, [0, 1]], s[:, [1, 2]], s[:, [2, 0]]])
    e = np.unique(np.sort(e, axis=1), axis=0)
    a, b = e[:, 0], e[:, 1]
    # keep the edges that touch an original grain; the bond seen from each original end
    dx, dz = xs[b] - xs[a], zs[b] - zs[a]
    rr = np.concatenate([r, r, r])
    ok = np.hypot(dx, dz) < 2.0 * 2 * rr.max()
    a, b, dx, dz = a[ok], b[ok], dx[ok], dz[ok]
    w = np.exp(6j * np.arctan2(dz, dx))          # a bond and its reverse give the same exp(6iθ)
    total = np.zeros(n, complex)
    count = np.zeros(n)
    for ends in (a, b):
        own = ends < n
        np.add.at(total, ends[own], w[own])
        np.add.at(count, ends[own], 1.0)
    # an edge between two copies of grain pairs is counted once per original end it has: edges
    # whose both ends are images are ignored, so each original grain sees each neighbour once
    # (its bonds to the left and right images are distinct Delaunay edges, as they should be)
    out = np.full(n, np.nan + 0j)
    good = count >= 2
    out[good] = total[good] / count[good]
    return out


# ---- geometry of a run ---------------------------------------------------------------------------

def stl_vertices(path: Path) -> np.ndarray:
    """(n, 3) vertices of an ASCII STL [m] (the run's surface.stl: a few hundred facets)."""
    rows = [line.split()[1:4] for line in path.read_text().splitlines() if line.lstrip().startswith("vertex")]
    return np.asarray(rows, float)


def cell_length(folder: Path, inp: dict) -> float:
    """The periodic cell's length [m]: the sheared surface's x extent on an interface (the cell
    closes on whole periods of the profile, Case.box_length), box_length_d50·D50 in the soil test."""
    stl = folder / "surface.stl"
    if inp["test"] == "interface" and stl.exists():
        return float(np.ptp(stl_vertices(stl)[:, 0]))
    return inp["box_length_d50"] * inp["d50"]


def boundary(folder: Path, test: str, snap0: pd.DataFrame) -> tuple[float, np.ndarray]:
    """(z of the boundary [m], bed mask over snap0's rows)."""
    z, r = snap0["z"].to_numpy(), snap0["radius"].to_numpy()
    if test == "box":
        bed = np.isclose(z, z.min(), rtol=0, atol=1e-9)
        return float(np.max(z[bed] + r[bed])), bed
    return float(stl_vertices(folder / "surface.stl")[:, 2].max()), np.zeros(z.size, bool)


def unwrap(dx: np.ndarray, length: float) -> np.ndarray:
    """Nearest-image x displacement [m] (as analysis.strength.displacement_profile with its period)."""
    return dx - length * np.round(dx / length)


def profile_u(a: pd.DataFrame, b: pd.DataFrame, zb: float, d50: float, length: float, moving: np.ndarray):
    """(layer lower edges h [D50], U per layer) between snapshots a and b (both sorted by id)."""
    ds = float(b["shear_disp"].iloc[0] - a["shear_disp"].iloc[0])
    u = unwrap(b["x"].to_numpy() - a["x"].to_numpy(), length)
    z = a["z"].to_numpy()
    h = (z - zb) / d50
    soil = ~moving
    far = soil & (z >= z[soil].max() - 2 * d50)
    U = (u - u[far].mean()) / (-ds)
    edges = np.arange(0.0, np.floor(h[soil].max()) + 1)
    k = np.floor(h).astype(int)
    sel = soil & (h >= 0)
    cnt = np.bincount(k[sel], minlength=edges.size)[: edges.size]
    tot = np.bincount(k[sel], weights=U[sel], minlength=edges.size)[: edges.size]
    with np.errstate(invalid="ignore", divide="ignore"):
        return edges, tot / cnt


def band_top(edges, U) -> float:
    """First height (layer centre, interpolated) at which U falls to BAND_LEVEL [D50]; 0 when the
    first layer is already below it (slip on the boundary); NaN if it never does."""
    c = edges + 0.5
    ok = np.isfinite(U)
    c, U = c[ok], U[ok]
    if U.size == 0:
        return math.nan
    if U[0] <= BAND_LEVEL:
        return 0.0
    below = np.flatnonzero(U <= BAND_LEVEL)
    if below.size == 0:
        return math.nan
    k = int(below[0])
    return float(c[k - 1] + (U[k - 1] - BAND_LEVEL) * (c[k] - c[k - 1]) / (U[k - 1] - U[k]))


def slip_planes(by, snaps, zb, d50, length, bed) -> dict:
    """Where the shear goes, interval by interval (each 0.5 mm snapshot interval from 1 mm on): the
    height [D50] of the largest drop of U between adjacent 1-D50 layers (the active slip plane), its
    share of the whole drop U(first layer) − U(top layer) (1: one plane takes all the shear, a block
    sliding on a lattice plane; ~1/n for a uniform shear over n layers), and its height as a fraction
    of the soil's height. Means over the intervals."""
    hs, shares, rel, below_top = [], [], [], []
    for s0, s1 in zip(snaps[2:-1], snaps[3:]):
        edges, U = profile_u(by[s0], by[s1], zb, d50, length, bed)
        ok = np.isfinite(U)
        if ok.sum() < 4:
            continue
        e, u = edges[ok], U[ok]
        drop = u[:-1] - u[1:]
        k = int(np.argmax(drop))
        total = u[0] - u[-1]
        top = e[-1] + 1.0
        hs.append(e[k] + 1.0)                          # the plane between layer k and k + 1
        shares.append(drop[k] / total if total > 0.2 else np.nan)
        rel.append((e[k] + 1.0) / top)
        below_top.append(top - (e[k] + 1.0))
    if not hs:
        return dict.fromkeys(("slip_plane_h_d50", "slip_plane_rel", "slip_plane_bottom3", "slip_plane_top3",
                              "slip_share"), math.nan)
    hs, rel, below_top = np.asarray(hs), np.asarray(rel), np.asarray(below_top)
    return dict(slip_plane_h_d50=float(hs.mean()), slip_plane_rel=float(rel.mean()),
                slip_plane_bottom3=float(np.mean(hs <= 3.0)), slip_plane_top3=float(np.mean(below_top <= 3.0)),
                slip_share=float(np.nanmean(shares)))


def fluctuation(folder: Path, d50: float) -> dict:
    """Stick–slip of the run's stress-ratio curve (series.parquet), smoothed over the tool's peak
    window (0.5 D50, analysis.strength.moving_average) and read from 1 mm of shear on: its mean
    (ratio_mean_1mm), standard deviation (ratio_sd_1mm) and its maximum over the whole shear less
    that mean (peak_over_mean) [-]."""
    from interphase.analysis.strength import PEAK_WINDOW_D50, moving_average
    s = pd.read_parquet(folder / "series.parquet", columns=["shear_disp", "stress_ratio"])
    x, r = s["shear_disp"].to_numpy(float), s["stress_ratio"].to_numpy(float)
    ok = np.isfinite(x) & np.isfinite(r)
    x, r = x[ok], r[ok]
    sm = moving_average(x, r, PEAK_WINDOW_D50 * d50)
    m = x > 0.001
    mean = float(np.nanmean(sm[m]))
    return dict(ratio_mean_1mm=mean, ratio_sd_1mm=float(np.nanstd(sm[m])), peak_over_mean=float(np.nanmax(sm)) - mean)


def n_wrapped(p: pd.DataFrame, summ: dict, length: float) -> int:
    """Grains whose x jumps by more than L/2 between the snapshots either side of the peak snapshot
    (they crossed the periodic boundary)."""
    key = summ.get("peak_snapshot")
    if key is None or not isinstance(key, (int, float)) or not math.isfinite(key):
        return -1
    snaps = np.sort(p["snapshot"].unique())
    i = int(np.searchsorted(snaps, key))
    a = p[p["snapshot"] == snaps[max(i - 1, 0)]].set_index("id")["x"]
    b = p[p["snapshot"] == snaps[min(i + 1, snaps.size - 1)]].set_index("id")["x"]
    return int((np.abs(b - a.reindex(b.index)) > length / 2).sum())


def tool_band(p: pd.DataFrame, summ: dict, d50: float, length: float, unwrap_x: bool) -> tuple[float, str]:
    """The tool's shear_band_d50 (analysis.summary_stages.shear_band: snapshots either side of the
    peak snapshot, z_ref = region_z0), recomputed without the periodic cell's length (unwrap_x False:
    what the committed summaries hold) and with it (unwrap_x True: what the tool now reads)."""
    from interphase.analysis import strength as st
    key = summ.get("peak_snapshot")
    if key is None or not isinstance(key, (int, float)) or not math.isfinite(key):
        return math.nan, "no peak snapshot"
    snaps = np.sort(p["snapshot"].unique())
    i = int(np.searchsorted(snaps, key))
    s0, s1 = snaps[max(i - 1, 0)], snaps[min(i + 1, snaps.size - 1)]
    prof = st.displacement_profile(p, s0, s1, summ["region_z0"], period=length if unwrap_x else None)
    return st.shear_band(prof["z"], prof["U"], summ["region_z0"], d50)


def zone_stats(p6: np.ndarray, mask: np.ndarray) -> tuple[float, float, float, int]:
    """(mean |ψ6|, fraction > ORDERED, share of ordered grains with horizontal rows, count)."""
    v = p6[mask & np.isfinite(p6)]
    if v.size == 0:
        return math.nan, math.nan, math.nan, 0
    m = np.abs(v)
    ang = np.degrees(np.angle(v[m > ORDERED])) / 6.0          # lattice orientation, (−30°, 30°]
    horiz = float(np.mean(np.abs(ang) < 7.5)) if ang.size else math.nan
    return float(m.mean()), float(np.mean(m > ORDERED)), horiz, int(v.size)


def analyse_run(folder: Path) -> dict:
    case = json.loads((folder / "case.json").read_text())
    inp = case["inputs"]
    summ = json.loads((folder / "summary.json").read_text())["row"]
    d50, length = inp["d50"], cell_length(folder, inp)
    p = pd.read_parquet(folder / "particles.parquet", columns=["snapshot", "shear_disp", "id", "x", "z", "radius"])
    snaps = np.sort(p["snapshot"].unique())
    by = {s: g.sort_values("id").reset_index(drop=True) for s, g in p.groupby("snapshot")}
    first, last = by[snaps[0]], by[snaps[-1]]
    zb, bed = boundary(folder, inp["test"], first)
    out = dict(case_id=case["case_id"], test=inp["test"], gradation=inp["gradation"], seed=inp["seed"],
               n_grains=len(first), boundary_z_d50=zb / d50)
    # displacement profiles: start (0 → 1 mm) and end (the last 1 mm); the active slip plane of each
    # (the largest drop of U between adjacent 1-D50 layers)
    plane = {}
    for tag, (s0, s1) in (("start", (snaps[0], snaps[min(2, snaps.size - 1)])), ("end", (snaps[-3], snaps[-1]))):
        edges, U = profile_u(by[s0], by[s1], zb, d50, length, bed)
        out[f"band_top_{tag}_d50"] = band_top(edges, U)
        out[f"slip_{tag}"] = float(1 - U[0]) if U.size and np.isfinite(U[0]) else math.nan
        out[f"U_{tag}"] = ";".join(f"{v:.2f}" for v in U)
        ok = np.isfinite(U)
        drop = U[ok][:-1] - U[ok][1:]
        plane[tag] = float(edges[ok][int(np.argmax(drop))] + 1.0) if drop.size else math.nan
        out[f"plane_{tag}_d50"] = plane[tag]
    out |= slip_planes(by, snaps, zb, d50, length, bed)
    for tag, snap in (("start", first), ("end", last)):
        x, z, r = (snap[c].to_numpy(float) for c in ("x", "z", "radius"))
        x = x % length
        p6 = psi6(x, z, r, length)
        h = (z - zb) / d50
        top = (np.max(z + r) - zb) / d50 - TOP_CLEAR
        soil = ~bed & (h >= EXCLUDE_LOW) & (h <= top)
        pe = plane["end"] if math.isfinite(plane["end"]) else 1.0
        zones = {
            # the band: within BAND_HALF of the slip plane of the last 1 mm (at the start: of the
            # first 1 mm); outside: at least OUTSIDE_GAP from it
            "band": soil & (np.abs(h - plane[tag]) <= BAND_HALF),
            "outside": soil & (np.abs(h - plane[tag]) >= OUTSIDE_GAP),
            "endband": soil & (np.abs(h - pe) <= BAND_HALF),
            "L0.5-2": soil & (h < 2),
            "L2-5": soil & (h >= 2) & (h < 5),
            "L5-top": soil & (h >= 5),
            "all": soil,
        }
        for name, mask in zones.items():
            m, fr, hz, n = zone_stats(p6, mask)
            out[f"psi6_{name}_{tag}"] = m
            out[f"frac07_{name}_{tag}"] = fr
            out[f"horiz_{name}_{tag}"] = hz
            out[f"n_{name}_{tag}"] = n
    for k in ("peak_stress_ratio", "residual_stress_ratio", "solid_fraction", "solid_fraction_end", "a_region",
              "shear_band_d50"):
        out[k] = summ.get(k, math.nan)
    out["shear_band_reason"] = summ.get("reasons", {}).get("shear_band_d50", "")
    out |= fluctuation(folder, d50)
    out["tool_band_asis_d50"], _ = tool_band(p, summ, d50, length, unwrap_x=False)
    out["tool_band_unwrapped_d50"], why = tool_band(p, summ, d50, length, unwrap_x=True)
    out["tool_band_unwrapped_reason"] = why
    out["n_wrapped_peak_interval"] = n_wrapped(p, summ, length)
    return out


# ---- summary -------------------------------------------------------------------------------------

def welch(a, b) -> tuple[float, float, float]:
    """mean(a) − mean(b) with its Welch 95 % interval (analysis.difference, whose sign is value − ref)."""
    d = difference(b, a, tol=1.0)
    return d.change, d.change_lo, d.change_hi


def fmt(v) -> str:
    v = np.asarray(v, float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return "n/a"
    if v.size < 2:
        return f"{v.mean():.3f} (n=1)"
    lo, hi = t_interval(v)
    return f"{v.mean():.3f} ({lo:.3f}–{hi:.3f}) n={v.size}"


METRICS = ["psi6_all_start", "frac07_all_start", "psi6_band_start", "psi6_outside_start", "psi6_endband_start",
           "frac07_endband_start",
           "psi6_L0.5-2_start", "psi6_L2-5_start", "psi6_L5-top_start",
           "psi6_band_end", "frac07_band_end", "psi6_outside_end", "frac07_outside_end",
           "psi6_L0.5-2_end", "frac07_L0.5-2_end", "psi6_L2-5_end", "psi6_L5-top_end",
           "horiz_band_start", "horiz_band_end", "horiz_outside_end",
           "horiz_all_start", "horiz_all_end",
           "band_top_start_d50", "band_top_end_d50", "slip_start", "slip_end", "plane_start_d50", "plane_end_d50",
           "slip_plane_h_d50", "slip_plane_rel", "slip_plane_bottom3", "slip_plane_top3", "slip_share",
           "peak_stress_ratio", "residual_stress_ratio", "ratio_mean_1mm", "ratio_sd_1mm", "peak_over_mean",
           "solid_fraction", "a_region",
           "shear_band_d50", "tool_band_asis_d50", "tool_band_unwrapped_d50", "n_wrapped_peak_interval"]


def summary_markdown(df: pd.DataFrame) -> str:
    lines = []
    cats = [(g, t) for g in ("mono", "poly") for t in ("box", "interface") if ((df.gradation == g) & (df.test == t)).any()]
    lines.append("| metric | " + " | ".join(f"{g} {t}" for g, t in cats) + " | mono box − teeth | poly box − teeth |")
    lines.append("|---" * (len(cats) + 3) + "|")
    for m in METRICS:
        row = [fmt(df[(df.gradation == g) & (df.test == t)][m]) for g, t in cats]
        for g in ("mono", "poly"):
            d, lo, hi = welch(df[(df.gradation == g) & (df.test == "box")][m], df[(df.gradation == g) & (df.test == "interface")][m])
            row.append("n/a" if not math.isfinite(d) else f"{d:+.3f} ({lo:+.3f}, {hi:+.3f})")
        lines.append(f"| {m} | " + " | ".join(row) + " |")
    return "\n".join(lines)


def curves(runs: Path, test: str, gradation: str) -> list:
    """(shear_disp [m], stress_ratio [-]) of every finished run of `test` and `gradation` in `runs`."""
    out = []
    for f in sorted(runs.iterdir()):
        if not (f / "DONE").exists() or not (f / "series.parquet").exists():
            continue
        inp = json.loads((f / "case.json").read_text())["inputs"]
        if inp["test"] == test and inp["gradation"] == gradation:
            s = pd.read_parquet(f / "series.parquet", columns=["shear_disp", "stress_ratio"])
            out.append((s["shear_disp"].to_numpy(float), s["stress_ratio"].to_numpy(float)))
    return out


def efficiency_lines(teeth_runs: Path, box_runs: Path, d50: float = 0.0007) -> list[str]:
    """E = tan δ / tan φ at the peak and at the critical state from the seed ensembles, as the
    tool's ensembles table reads them (analysis.ensemble.ensemble_efficiency, peak window 0.5 D50)."""
    from interphase.analysis.ensemble import ensemble_efficiency, ensemble_strength
    from interphase.analysis.strength import PEAK_WINDOW_D50
    lines = []
    for g in ("mono", "poly"):
        a, b = curves(teeth_runs, "interface", g), curves(box_runs, "box", g)
        if not a or not b:
            continue
        w = PEAK_WINDOW_D50 * d50
        e = ensemble_efficiency(a, b, w)
        sa, sb = ensemble_strength(a, w), ensemble_strength(b, w)
        lines.append(f"| {g} | {teeth_runs.name} ({len(a)}) | {box_runs.name} ({len(b)}) | "
                     f"{sa.peak:.3f} ({sa.peak_lo:.3f}–{sa.peak_hi:.3f}) | {sb.peak:.3f} ({sb.peak_lo:.3f}–{sb.peak_hi:.3f}) | "
                     f"{e.peak:.3f} ({e.peak_lo:.3f}–{e.peak_hi:.3f}) | "
                     f"{sa.critical:.3f} ({sa.critical_lo:.3f}–{sa.critical_hi:.3f}) | "
                     f"{sb.critical:.3f} ({sb.critical_lo:.3f}–{sb.critical_hi:.3f}) | "
                     f"{e.critical:.3f} ({e.critical_lo:.3f}–{e.critical_hi:.3f}) |")
    return lines


def figure(folders: list[Path], path: Path) -> None:
    """The grains of each run at the start and at the end of the shear, coloured by |ψ6|."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle
    fig, axes = plt.subplots(len(folders), 2, figsize=(12, 3.6 * len(folders)), squeeze=False)
    for row, folder in zip(axes, folders):
        inp = json.loads((folder / "case.json").read_text())["inputs"]
        d50, length = inp["d50"], cell_length(folder, inp)
        p = pd.read_parquet(folder / "particles.parquet", columns=["snapshot", "id", "x", "z", "radius"])
        snaps = np.sort(p["snapshot"].unique())
        for ax, snap, tag in zip(row, (snaps[0], snaps[-1]), ("start of shear", "end of shear (6 mm)")):
            g = p[p["snapshot"] == snap]
            x, z, r = (g[c].to_numpy(float) for c in ("x", "z", "radius"))
            x = x % length
            m = np.abs(psi6(x, z, r, length))
            pc = PatchCollection([Circle((a / d50, b / d50), c / d50) for a, b, c in zip(x, z, r)], cmap="viridis")
            pc.set_array(np.nan_to_num(m))
            pc.set_clim(0, 1)
            ax.add_collection(pc)
            ax.set_xlim(0, length / d50)
            ax.set_ylim(min(0, (z - r).min() / d50), (z + r).max() / d50)
            ax.set_aspect("equal")
            ax.set_title(f"{inp['test']} {inp['gradation']} seed {inp['seed']}: {tag}", fontsize=9)
            ax.set_xlabel("x [D50]")
            ax.set_ylabel("z [D50]")
    fig.colorbar(pc, ax=axes, shrink=0.6, label="|ψ6|")
    fig.savefig(path, dpi=110)


COMPARE_METRICS = ["psi6_all_start", "frac07_all_start", "psi6_L0.5-2_start", "psi6_L0.5-2_end", "psi6_band_end",
                   "frac07_band_end", "psi6_outside_end", "horiz_all_start", "horiz_all_end", "horiz_band_end",
                   "slip_share", "slip_plane_bottom3", "peak_stress_ratio", "residual_stress_ratio", "ratio_mean_1mm",
                   "ratio_sd_1mm", "peak_over_mean", "solid_fraction", "a_region"]


def seed_mean_peak(runs: Path, test: str, gradation: str, d50: float = 0.0007) -> str:
    """The seeds' curves smoothed (0.5 D50 window) on a common grid: the mean of the per-run maxima,
    the maximum of the seed-mean curve and where it sits [mm], the per-run peak positions (mean ± sd
    [mm]). A coherent peak (every seed peaking together) keeps the seed-mean maximum near the per-run
    one; stick–slip spikes at random displacements do not (what the ensembles' peak reads)."""
    from interphase.analysis.strength import PEAK_WINDOW_D50, moving_average
    cs = curves(runs, test, gradation)
    if not cs:
        return "n/a"
    end = min(float(np.nanmax(x)) for x, _ in cs)
    grid = np.linspace(0.0, end, 400)
    m = np.array([np.interp(grid, x, moving_average(x, r, PEAK_WINDOW_D50 * d50)) for x, r in cs])
    at = grid[m.argmax(1)] * 1e3
    mean = m.mean(0)
    return (f"per-run max {m.max(1).mean():.3f}, seed-mean curve max {mean.max():.3f} at {grid[mean.argmax()] * 1e3:.2f} mm, "
            f"per-run peaks at {at.mean():.2f} ± {at.std(ddof=1):.2f} mm")


def compare(specs: list[str]) -> str:
    """Markdown: each set (LABEL=RUNS_DIR:TEST:GRADATION) with its seed mean and interval, and its
    Welch difference from the first set."""
    sets, peaks = [], []
    for spec in specs:
        label, rest = spec.split("=", 1)
        runs, test, grad = rest.rsplit(":", 2)
        peaks.append(f"- {label}: {seed_mean_peak(Path(runs), test, grad)}")
        rows = [analyse_run(f) for f in sorted(Path(runs).iterdir()) if (f / "DONE").exists()]
        df = pd.DataFrame(rows)
        sets.append((label, df[(df.test == test) & (df.gradation == grad)]))
    head = "| metric | " + " | ".join(f"{lab} (n={len(d)})" for lab, d in sets) + " | " + \
        " | ".join(f"{lab} − {sets[0][0]}" for lab, _ in sets[1:]) + " |"
    lines = [head, "|---" * (2 * len(sets)) + "|"]
    for m in COMPARE_METRICS:
        row = [fmt(d[m]) for _, d in sets]
        for _, d in sets[1:]:
            dd, lo, hi = welch(d[m], sets[0][1][m])
            row.append("n/a" if not math.isfinite(dd) else f"{dd:+.3f} ({lo:+.3f}, {hi:+.3f})")
        lines.append(f"| {m} | " + " | ".join(row) + " |")
    return "\n".join(lines + [""] + peaks)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", type=Path)
    ap.add_argument("--csv", type=Path)
    ap.add_argument("--box-runs", type=Path, help="take the soil tests for E from this runs folder instead")
    ap.add_argument("--compare", nargs="+", metavar="LABEL=RUNS_DIR:TEST:GRADATION",
                    help="only compare these sets (RUNS is then ignored): means, intervals, Welch differences from the first")
    ap.add_argument("--figure", type=Path, nargs="+", metavar="PNG CASE_FOLDER",
                    help="only draw: PNG then the case folders (start and end of shear, grains coloured by |ψ6|)")
    args = ap.parse_args(argv)
    if args.compare:
        print(compare(args.compare))
        return 0
    if args.figure:
        figure([Path(f) for f in args.figure[1:]], Path(args.figure[0]))
        return 0
    rows = [analyse_run(f) for f in sorted(args.runs.iterdir()) if (f / "DONE").exists() and (f / "particles.parquet").exists()]
    df = pd.DataFrame(rows).sort_values(["gradation", "test", "seed"])
    if args.csv:
        df.to_csv(args.csv, index=False)
    cols = ["gradation", "test", "seed", "psi6_all_start", "psi6_band_end", "psi6_outside_end", "band_top_end_d50",
            "slip_end", "peak_stress_ratio", "residual_stress_ratio", "shear_band_reason"]
    pd.set_option("display.width", 250)
    print(df[cols].to_string(index=False, float_format=lambda v: f"{v:.3f}"))
    print()
    print(summary_markdown(df))
    lines = efficiency_lines(args.runs, args.box_runs or args.runs)
    if lines:
        print()
        print("| gradation | teeth runs (n) | box runs (n) | tan δ peak | tan φ peak | E peak | tan δ cs | tan φ cs | E cs |")
        print("|---|---|---|---|---|---|---|---|---|")
        print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
