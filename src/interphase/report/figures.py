"""The study's figures (6.3, 6.5–6.10) as PNG and PDF, matplotlib Agg.

Points: one per physical case (report.build.ensemble_points): the mean over its seeds, with 95 %
error bars (`<col>_lo`, `<col>_hi`: Student t over the seeds; tan δ, E: the ensembles table's) in x
and y wherever the quantity varies by seed — none in x for θa and Rnc, which the surface alone sets,
none for a case with one seed. Colour = particle–surface friction tan φμ, marker = group, hollow =
mono-disperse, filled = poly-disperse. Fits are drawn over their fitted x range with their bootstrap
band (the seed bootstrap when the points have seeds); a correlation without a fit draws its points
and says why ("no fit: n = 3 < 7"). Angles are ψ, degrees from vertical, unless an axis says ccw.

For a paper: each figure is a PDF and a 300 dpi PNG; every legend lies inside the image (the figure
key is laid out in as many columns as fit the figure's width, and the panels leave it room), each key
entry looks different (colours as swatches, groups as markers, gradation as hollow/filled boxes); the
axes hold every point with its whole 95 % bar. A figure with nothing to draw is not drawn: its
function returns no paths and `empty_reason` says why (the report page prints it).
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from interphase.analysis.correlations import SEED_INVARIANT, SPECS, subset  # noqa: E402

MARKERS = "osD^vP*Xph<>"
DPI = 300              # PNG resolution: a journal's for line art with points
KEY_FONTSIZE = 7


def legend_overflow(fig) -> list[str]:
    """The legends of `fig` that reach outside its image (by more than half a pixel), as text; [] when
    all lie inside. Draws the figure to measure them."""
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    box = fig.bbox
    legends = list(fig.legends) + [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    out = []
    for leg in legends:
        bb = leg.get_window_extent(r)
        if bb.x0 < box.x0 - 0.5 or bb.y0 < box.y0 - 0.5 or bb.x1 > box.x1 + 0.5 or bb.y1 > box.y1 + 0.5:
            out.append(f"legend {[t.get_text() for t in leg.get_texts()][:3]}… at {bb.bounds} outside {box.bounds}")
    return out


def save(fig, folder: Path, stem: str) -> list[Path]:
    """PNG (DPI) and PDF of `fig`, then close it."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = [folder / f"{stem}.png", folder / f"{stem}.pdf"]
    fig.savefig(paths[0], dpi=DPI)
    fig.savefig(paths[1])
    plt.close(fig)
    return paths


def _styles(points: pd.DataFrame):
    fr = sorted(pd.to_numeric(points.get("friction_ps", pd.Series(dtype=float)), errors="coerce").dropna().unique())
    groups = sorted(points["group"].astype(str).unique()) if "group" in points else []
    colour = {mu: f"C{i % 10}" for i, mu in enumerate(fr)}
    marker = {g: MARKERS[i % len(MARKERS)] for i, g in enumerate(groups)}
    return colour, marker


def _errors(p: pd.DataFrame, col: str, centre: pd.Series) -> np.ndarray | None:
    """(2, n) distances from `centre` to `<col>_lo` and `<col>_hi` (0 where not finite), or None when
    the column has no interval or does not vary by seed."""
    if col in SEED_INVARIANT or f"{col}_lo" not in p or f"{col}_hi" not in p:
        return None
    lo = centre - pd.to_numeric(p[f"{col}_lo"], errors="coerce")
    hi = pd.to_numeric(p[f"{col}_hi"], errors="coerce") - centre
    err = np.vstack([lo.to_numpy(float), hi.to_numpy(float)])
    err = np.where(np.isfinite(err), np.maximum(err, 0.0), 0.0)
    return err if err.any() else None


def scatter(ax, points: pd.DataFrame, x: str, y: str, colour, marker, legend: bool = True) -> int:
    """Draw the points with their seed error bars (see the module doc); returns how many were finite."""
    n = 0
    if x not in points or y not in points or points.empty:
        return 0
    xs = pd.to_numeric(points[x], errors="coerce")
    ys = pd.to_numeric(points[y], errors="coerce")
    ok = xs.notna() & ys.notna() & np.isfinite(xs) & np.isfinite(ys)
    p = points[ok].assign(_x=xs[ok], _y=ys[ok])
    # one scatter call per (friction, group, gradation) keeps 1000-case campaigns fast
    for (mu, grp, grad), g in p.groupby([p["friction_ps"].fillna(-1), p["group"].astype(str),
                                         p.get("gradation", pd.Series("", index=p.index)).astype(str)], sort=True):
        c = colour.get(mu, "0.3")
        xerr, yerr = _errors(g, x, g["_x"]), _errors(g, y, g["_y"])
        if xerr is not None or yerr is not None:
            ax.errorbar(g["_x"], g["_y"], xerr=xerr, yerr=yerr, fmt="none", ecolor=c, elinewidth=0.8,
                        capsize=1.5, alpha=0.7, zorder=1, gid="seed-interval")
        ax.scatter(g["_x"], g["_y"], s=22, marker=marker.get(grp, "o"), edgecolors=c,
                   facecolors=c if grad == "poly" else "none", linewidths=1.0,
                   label=None, zorder=2, gid="physical-case")
        n += len(g)
    return n


def fit_view(ax, points: pd.DataFrame, x: str, y: str) -> None:
    """Axis limits that hold every point and the whole of each 95 % bar (`<col>_lo`, `<col>_hi`),
    padded by 5 %. The intervals respect their quantity's range and exist from 3 seeds on
    (analysis.ensemble.seed_interval), so no bar is long enough to shrink the points to a line."""
    for col, setter in ((x, ax.set_xlim), (y, ax.set_ylim)):
        if col not in points or points.empty:
            continue
        v = pd.to_numeric(points[col], errors="coerce").to_numpy(float)
        ok = np.isfinite(v)
        if not ok.any():
            continue
        ends = [v[ok]]
        if col not in SEED_INVARIANT:
            ends += [pd.to_numeric(points[col + e], errors="coerce").to_numpy(float)[ok]
                     for e in ("_lo", "_hi") if col + e in points]
        allv = np.concatenate(ends)
        allv = allv[np.isfinite(allv)]
        lo, hi = float(allv.min()), float(allv.max())
        span = max(hi - lo, 1e-9 * max(abs(lo), abs(hi), 1.0))
        setter(lo - 0.05 * span, hi + 0.05 * span)


def draw_fits(ax, fits, colour) -> None:
    """Fit lines (pooled: black; per friction: that friction's colour, dashed; per gradation: grey,
    dotted for uniform grains); a note for missing fits."""
    notes = []
    for fr in fits:
        if fr.fit is None:
            notes.append(f"{fr.slice}: {fr.reason}")
            continue
        lo, hi = fr.fit.x_range
        xx = np.linspace(lo, hi, 200)
        if fr.slice == "all":
            b_lo, b_hi = fr.fit.predict_band(xx)
            if np.isfinite(b_lo).any():
                ax.fill_between(xx, b_lo, b_hi, color="0.5", alpha=0.18, lw=0, zorder=0)
            ci = fr.fit.c_interval_bootstrap
            ax.plot(xx, fr.fit.predict(xx), "k-", lw=1.6, label=f"fit (all): c = {fr.fit.c:.3g} "
                    f"[{ci[0]:.3g}, {ci[1]:.3g}] ({fr.fit.bootstrap} bootstrap), R² = {fr.fit.r2:.2f}")
        else:
            by, _, value = fr.slice.partition("=")
            style = (dict(ls="--", color=colour.get(float(value), "0.4")) if by == "friction_ps"
                     else dict(ls=":" if value == "mono" else "-.", color="0.25"))     # per gradation
            ci = fr.fit.c_interval_bootstrap
            ax.plot(xx, fr.fit.predict(xx), lw=1.2, label=f"fit {fr.slice}: c = {fr.fit.c:.3g}"
                    + (f" [{ci[0]:.3g}, {ci[1]:.3g}]" if by != "friction_ps" and np.isfinite(ci).all() else ""), **style)
    if notes:
        ax.text(0.02, 0.98, "\n".join(notes[:6]), transform=ax.transAxes, va="top", ha="left", fontsize=8,
                color="C3", bbox=dict(facecolor="white", alpha=0.8, edgecolor="C3"))


def correlation_panel(ax, points, spec_key: str, fit_results, colour, marker, legend=True) -> None:
    spec = SPECS[spec_key]
    pts = subset(points, spec)
    n = scatter(ax, pts, spec.x, spec.y, colour, marker, legend)
    draw_fits(ax, [f for f in fit_results if f.spec.key == spec_key], colour)
    fit_view(ax, pts, spec.x, spec.y)
    ax.set_xlabel(spec.x_label)
    ax.set_ylabel(spec.y_label)
    seeds = pd.to_numeric(pts.get("seeds", pd.Series(dtype=float)), errors="coerce")
    bars = any(f"{c}_lo" in pts and np.isfinite(pd.to_numeric(pts[f"{c}_lo"], errors="coerce")).any()
               for c in (spec.x, spec.y) if c not in SEED_INVARIANT)
    what = (f"n = {n} physical cases, seed means ± 95 %" if bars else
            f"n = {n} physical cases, seed means; no interval below 3 seeds" if len(seeds) and (seeds > 1).any()
            else f"n = {n}")
    ax.set_title(f"Fig. {spec.figure}: {spec.title}\n({what})", fontsize=9)
    ax.grid(alpha=0.3)


def key_handles(points) -> list:
    """The figure key: colour = friction (swatches), marker = group (grey, hollow), gradation = hollow
    or filled (boxes; only when the points have both), each entry distinct from every other."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    if points is None or points.empty:
        return []
    colour, marker = _styles(points)
    h = [Patch(facecolor=c, edgecolor=c, label=f"tan φμ = {mu:g}") for mu, c in colour.items()]
    h += [Line2D([], [], ls="", marker=m, color="0.35", mfc="none", label=str(g)) for g, m in marker.items()]
    grads = set(points.get("gradation", pd.Series(dtype=str)).dropna().astype(str))
    if {"mono", "poly"} <= grads:
        h += [Patch(facecolor="none", edgecolor="0.35", label="hollow: mono-disperse"),
              Patch(facecolor="0.35", edgecolor="0.35", label="filled: poly-disperse")]
    return h


def place_key(fig, handles, top: float = 0.96) -> None:
    """The key below the panels in as many columns as fit the figure's width, and the panels laid
    out (tight_layout) above it: nothing of it outside the image."""
    if not handles:
        fig.tight_layout(rect=(0, 0, 1, top))
        return
    r = fig.canvas.get_renderer()
    for ncol in range(min(len(handles), 8), 0, -1):
        leg = fig.legend(handles=handles, loc="lower center", bbox_to_anchor=(0.5, 0.005), ncol=ncol,
                         fontsize=KEY_FONTSIZE, frameon=False, handlelength=1.2, columnspacing=1.2)
        bb = leg.get_window_extent(r)
        if bb.width <= 0.98 * fig.bbox.width or ncol == 1:
            break
        leg.remove()
    fig.tight_layout(rect=(0, min(0.6, (bb.height + 6) / fig.bbox.height), 1, top))


def _legend(fig, axes, points=None) -> None:
    """One key for the whole figure (`key_handles`), placed by `place_key`."""
    place_key(fig, key_handles(points))


def empty_reason(points: pd.DataFrame, keys) -> str:
    """Why the correlation panels `keys` would be empty ("" when any has a point to draw)."""
    for key in keys:
        spec = SPECS[key]
        pts = subset(points, spec) if len(points) else points
        if spec.x in pts and spec.y in pts:
            xs, ys = (pd.to_numeric(pts[c], errors="coerce") for c in (spec.x, spec.y))
            if (np.isfinite(xs) & np.isfinite(ys)).any():
                return ""
    specs = [SPECS[k] for k in keys]
    where = {s.subset for s in specs if s.subset} or {""}
    sub = f" among the {'/'.join(sorted(where)).replace('_', '-')} surfaces" if where != {""} else ""
    return (f"no physical case{sub} has both " + "; ".join(f"{s.x_label} and {s.y_label}" for s in specs)
            + " (n = 0)")


def correlation_figure(points, fit_results, keys, stem: str, folder: Path, suptitle: str) -> list[Path]:
    """The correlation panels `keys` (SPECS) with the figure key; no paths (nothing drawn) when every
    panel would be empty (`empty_reason`)."""
    if empty_reason(points, keys):
        return []
    colour, marker = _styles(points)
    ncol = 2 if len(keys) > 1 else 1
    nrow = math.ceil(len(keys) / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(6.2 * ncol, 4.6 * nrow + 1.2), squeeze=False)
    for ax, key in zip(axes.ravel(), keys):
        correlation_panel(ax, points, key, fit_results, colour, marker)
        if ax.get_legend_handles_labels()[0]:       # only fit lines carry labels
            ax.legend(fontsize=7, loc="best")
    for ax in axes.ravel()[len(keys):]:
        ax.set_visible(False)
    fig.suptitle(suptitle, fontsize=11)
    _legend(fig, axes, points)
    return save(fig, folder, stem)


def figure_6_5(points, folder: Path) -> list[Path]:
    """Peak stress ratio and E against Rnc(D50) (no fit: the study shows Rnc does not correlate uniquely);
    nothing drawn (no paths) without a point with Rnc and tan δ."""
    if rnc_reason(points):
        return []
    colour, marker = _styles(points)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.4))
    for ax, (y, lab) in zip(axes, (("peak_stress_ratio", "peak stress ratio tan δ [-]"),
                                   ("efficiency", "efficiency E = tan δ / tan φ [-]"))):
        n = scatter(ax, points, "rnc", y, colour, marker)
        fit_view(ax, points, "rnc", y)
        ax.set_xlabel("Rnc(D50) [-] (centroid trace)")
        ax.set_ylabel(lab)
        ax.set_title(f"Fig. 6.5: {lab.split(' [')[0]} vs Rnc (n = {n} physical cases)", fontsize=9)
        ax.grid(alpha=0.3)
        if n == 0:
            ax.text(0.5, 0.5, f"no points with both Rnc and {y}", transform=ax.transAxes, ha="center", color="C3")
    fig.suptitle("Fig. 6.5: strength vs normalised roughness Rnc(D50)")
    _legend(fig, axes, points)
    return save(fig, folder, "fig6_5")


def rnc_reason(points: pd.DataFrame) -> str:
    """Why Fig. 6.5 would be empty ("" when it has a point)."""
    if "rnc" in points and "peak_stress_ratio" in points:
        both = np.isfinite(pd.to_numeric(points["rnc"], errors="coerce")) & \
            np.isfinite(pd.to_numeric(points["peak_stress_ratio"], errors="coerce"))
        if both.any():
            return ""
    return "no physical case has both Rnc(D50) and a peak stress ratio (n = 0)"


def figure_6_6(profiles: list[tuple[str, object]], d50: float, folder: Path, bins: int = 72) -> list[Path]:
    """Polar (upper half-plane) length-weighted distributions of centroid-trace normals of selected
    profiles, θ ccw from +x; kept side (> 92°) shaded; θa (> 92°) as an arrow. Nothing drawn (no
    paths) without a profile."""
    if not profiles:
        return []
    from interphase.surface.normals import keep_mask, segment_normals, theta_a
    from interphase.surface.trace import centroid_trace

    k = max(1, len(profiles))
    fig = plt.figure(figsize=(4.2 * k, 4.0))
    edges = np.linspace(0, math.pi, bins + 1)
    mids = 0.5 * (edges[:-1] + edges[1:])
    for i, (label, prof) in enumerate(profiles):
        ax = fig.add_subplot(1, k, i + 1, projection="polar")
        th, w = segment_normals(centroid_trace(prof, d50))
        hist, _ = np.histogram(th, bins=edges, weights=w)
        hist = hist / max(hist.sum(), 1e-300)
        ax.bar(edges[:-1], hist, width=np.diff(edges), align="edge",
               color=np.where(keep_mask(mids, 92), "C0", "0.75"), edgecolor="none")
        res = theta_a(prof, d50, 92)
        if res.dilative and hist.max() > 0:
            ax.annotate("", xy=(math.radians(res.theta_a_ccw_deg), hist.max()), xytext=(0, 0),
                        arrowprops=dict(color="C3", width=1.2))
        ax.set_thetamin(0)
        ax.set_thetamax(180)
        ax.set_yticklabels([])
        ta = f"θa = {res.theta_a_deg:.1f}°" if res.dilative else "θa undefined (non-dilative)"
        ax.set_title(f"({chr(97 + i)}) {label}\n{ta}", fontsize=8)
    fig.suptitle(f"Fig. 6.6: centroid-trace normal distributions (D50 = {d50 * 1e3:g} mm; θ ccw from +x)", fontsize=10)
    fig.tight_layout()
    return save(fig, folder, "fig6_6")


CURVE_PANEL_COLS = 2      # curve panels per row


def short_names(names) -> dict[str, str]:
    """{name: the name without the `-`-separated words every name shares} ("quick-rt0.5-mu0.2" and
    "quick-rt1-mu0.2" → "rt0.5", "rt1"); a name left empty keeps its full form."""
    names = list(names)
    words = [n.split("-") for n in names]
    common = set.intersection(*(set(w) for w in words)) if len(names) > 1 else set()
    return {n: "-".join(x for x in w if x not in common) or n for n, w in zip(names, words)}


def stress_curves(curves: dict[str, pd.DataFrame], title: str, stem: str, folder: Path,
                  panels: dict[str, str] | None = None) -> list[Path]:
    """Stress ratio [-] vs shear displacement [mm], faceted: one panel per `panels[label]` (e.g.
    "tan φμ = 0.2"; one panel without `panels`), one colour per physical case (a label without its
    `-sN`), its seeds in that colour; each panel's legend, right of it and inside the image, names
    its physical cases by what tells them apart (`short_names`) and their seed counts. No paths
    (nothing drawn) without a curve."""
    from interphase.analysis.ensemble import physical_case

    if not curves:
        return []
    panels = panels or {}
    by_panel: dict[str, dict[str, list[str]]] = {}
    for label in sorted(curves):
        by_panel.setdefault(str(panels.get(label, "")), {}).setdefault(physical_case(label), []).append(label)
    short = short_names({c for cases in by_panel.values() for c in cases})
    names = sorted(by_panel)
    ncol = min(CURVE_PANEL_COLS, len(names))
    nrow = math.ceil(len(names) / ncol)
    most = max(len(c) for c in by_panel.values())
    key_cols = 1 if most <= 14 else 2
    key_width = 0.09 * max(len(v) for v in short.values()) + 0.9
    fig, axes = plt.subplots(nrow, ncol, figsize=(ncol * (4.6 + key_cols * key_width), nrow * max(3.4, 0.2 * most / key_cols + 1.2)),
                             squeeze=False, layout="constrained")
    for ax, name in zip(axes.ravel(), names):
        cases = by_panel[name]
        cmap = plt.get_cmap("tab10" if len(cases) <= 10 else "tab20" if len(cases) <= 20 else "viridis")
        for i, (case, labels) in enumerate(sorted(cases.items(), key=lambda kv: _natural(short[kv[0]]))):
            c = cmap(i % 20 if len(cases) <= 20 else i / max(len(cases) - 1, 1))
            for j, label in enumerate(labels):
                s = curves[label]
                y = s["stress_ratio_smooth"] if "stress_ratio_smooth" in s else s["stress_ratio"]
                ax.plot(s["shear_disp"] * 1e3, y, lw=0.9, color=c, alpha=0.85,
                        label=f"{short[case]} ({len(labels)} seed{'s' if len(labels) > 1 else ''})" if j == 0 else None)
        ax.set_xlabel("shear displacement [mm]")
        ax.set_ylabel("stress ratio [-]")
        ax.set_title(name or title, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncol=key_cols, loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False,
                  handlelength=1.5, columnspacing=1.0)
    for ax in axes.ravel()[len(names):]:
        ax.set_visible(False)
    fig.suptitle(f"{title}\n(surface ΣFx/Σ−Fz; box τ/σ; one colour per physical case, its seeds alike)", fontsize=10)
    return save(fig, folder, stem)


def _natural(text: str):
    """Sort key that orders rt0.5 before rt1 before rt10."""
    import re

    return [float(t) if re.fullmatch(r"\d+(\.\d+)?", t) else t for t in re.split(r"(\d+(?:\.\d+)?)", text)]


def lab_figure(points, lab: pd.DataFrame, folder: Path) -> list[Path]:
    """Fig. 6.10b style: simulated and measured peak efficiency against θa (> 92°, 0 = non-dilative);
    `lab` is analysis.validation.predict_rows' table (E measured = tan δ / tan φ of each row's φ)."""
    colour, marker = _styles(points)
    fig, ax = plt.subplots(figsize=(8, 5.6))
    scatter(ax, points, "theta_a_deg_92", "efficiency", colour, marker)
    for i, (soil, g) in enumerate(lab.groupby("soil", sort=True)):
        ax.scatter(g["theta_a_deg"], g["efficiency_measured"], s=110, marker="*", color=f"C{(i + 6) % 10}",
                   edgecolors="k", linewidths=0.6, label=f"lab: {soil}", zorder=5)
    ax.set_xlabel("θa, filter > 92° [° from vertical] (non-dilative at 0)")
    ax.set_ylabel("efficiency E [-]")
    ax.set_title("Fig. 6.10b: laboratory data (stars) with the simulations", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower right")
    place_key(fig, key_handles(points), top=1.0)
    return save(fig, folder, "fig6_10b_lab")


def criterion_check_figure(checks: pd.DataFrame, folder: Path) -> list[Path]:
    """δ predicted by the chain against δ measured (seed means), one panel per fold, with the 1:1
    line and the study's ±4° band."""
    folds = list(dict.fromkeys(checks["fold"]))
    fig, axes = plt.subplots(1, len(folds), figsize=(5.2 * len(folds), 4.8), squeeze=False)
    vals = pd.concat([checks["delta_measured_deg"], checks["delta_predicted_deg"]]).dropna()
    lo, hi = (float(vals.min()) - 2, float(vals.max()) + 2) if len(vals) else (0.0, 40.0)
    groups = sorted(checks["group"].astype(str).unique())
    colours = {g: plt.cm.tab10(i % 10) for i, g in enumerate(groups)}
    for ax, fold in zip(axes[0], folds):
        g = checks[checks["fold"] == fold]
        ax.fill_between([lo, hi], [lo - 4, hi - 4], [lo + 4, hi + 4], color="0.9", label="±4° (the study's criterion)")
        ax.plot([lo, hi], [lo, hi], color="0.4", lw=1)
        for grp, gg in g.groupby(g["group"].astype(str)):
            ax.scatter(gg["delta_measured_deg"], gg["delta_predicted_deg"], s=22, color=colours[grp], label=grp,
                       edgecolor="k", linewidth=0.4)
        n = int(g["error_deg"].notna().sum())
        ax.set(xlim=(lo, hi), ylim=(lo, hi), xlabel="δ measured [°] (seed mean)", ylabel="δ predicted [°]",
               title=f"{fold} ({n} cases)")
        ax.set_aspect("equal")
        ax.legend(fontsize=7, loc="upper left")
    fig.suptitle("The criterion θa → θr → E against every simulated case")
    fig.tight_layout()
    return save(fig, folder, "criterion_check")
