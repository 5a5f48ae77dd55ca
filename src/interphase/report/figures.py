"""The study's figures (6.3, 6.5–6.10) as PNG and PDF, matplotlib Agg.

Points: one per physical case (report.build.ensemble_points): the mean over its seeds, with 95 %
error bars (`<col>_lo`, `<col>_hi`: Student t over the seeds; tan δ, E: the ensembles table's) in x
and y wherever the quantity varies by seed — none in x for θa and Rnc, which the surface alone sets,
none for a case with one seed. Colour = particle–surface friction tan φμ, marker = group, hollow =
mono-disperse, filled = poly-disperse. Fits are drawn over their fitted x range with their bootstrap
band (the seed bootstrap when the points have seeds); a correlation without a fit draws its points
and says why ("no fit: n = 3 < 7"). Angles are ψ, degrees from vertical, unless an axis says ccw.
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
DPI = 110


def save(fig, folder: Path, stem: str) -> list[Path]:
    """PNG and PDF of `fig`, then close it."""
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


def fit_view(ax, points: pd.DataFrame, x: str, y: str, reach: float = 0.5) -> None:
    """Axis limits that show every point and each error bar up to `reach` × the points' span beyond
    them: a seed interval of two seeds (t = 12.7) can be ten times the spread of the points, and
    would otherwise shrink them to a line. Longer bars run off the edge."""
    for col, setter in ((x, ax.set_xlim), (y, ax.set_ylim)):
        if col not in points or points.empty:
            continue
        v = pd.to_numeric(points[col], errors="coerce").to_numpy(float)
        v = v[np.isfinite(v)]
        if not v.size:
            continue
        lo, hi = float(v.min()), float(v.max())
        span = max(hi - lo, 1e-9 * max(abs(lo), abs(hi), 1.0))
        for end, f in (("_lo", min), ("_hi", max)):
            if col + end in points:
                e = pd.to_numeric(points[col + end], errors="coerce").to_numpy(float)
                e = e[np.isfinite(e)]
                if e.size:
                    bound = lo - reach * span if end == "_lo" else hi + reach * span
                    edge = f(float(f(e)), lo if end == "_lo" else hi)
                    lo, hi = (max(edge, bound), hi) if end == "_lo" else (lo, min(edge, bound))
        pad = 0.05 * max(hi - lo, span)
        setter(lo - pad, hi + pad)


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
    what = (f"n = {n} physical cases, seed means ± 95 %" if len(seeds) and (seeds > 1).any() else f"n = {n}")
    ax.set_title(f"Fig. {spec.figure}: {spec.title}\n({what})", fontsize=9)
    ax.grid(alpha=0.3)


def _legend(fig, axes, points=None) -> None:
    """One key for the whole figure: colour = friction, marker = group, filled = poly-disperse."""
    from matplotlib.lines import Line2D

    if points is None or points.empty:
        return
    colour, marker = _styles(points)
    h = [Line2D([], [], ls="", marker="o", color=c, label=f"tan φμ = {mu:g}") for mu, c in colour.items()]
    h += [Line2D([], [], ls="", marker=m, color="0.35", mfc="none", label=str(g)) for g, m in marker.items()]
    h += [Line2D([], [], ls="", marker="o", color="0.35", mfc="none", label="mono-disperse"),
          Line2D([], [], ls="", marker="o", color="0.35", label="poly-disperse")]
    fig.legend(handles=h, loc="lower center", ncol=min(6, len(h)), fontsize=7, frameon=False)


def correlation_figure(points, fit_results, keys, stem: str, folder: Path, suptitle: str) -> list[Path]:
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
    fig.tight_layout(rect=(0, 0.1 if nrow == 1 else 0.06, 1, 0.96))
    return save(fig, folder, stem)


def figure_6_5(points, folder: Path) -> list[Path]:
    """Peak stress ratio and E against Rnc(D50) (no fit: the study shows Rnc does not correlate uniquely)."""
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
    fig.tight_layout(rect=(0, 0.12, 1, 0.95))
    return save(fig, folder, "fig6_5")


def figure_6_6(profiles: list[tuple[str, object]], d50: float, folder: Path, bins: int = 72) -> list[Path]:
    """Polar (upper half-plane) length-weighted distributions of centroid-trace normals of selected
    profiles, θ ccw from +x; kept side (> 92°) shaded; θa (> 92°) as an arrow."""
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
    if not profiles:
        fig.text(0.5, 0.5, "no surface profiles in this campaign", ha="center", color="C3")
    fig.suptitle(f"Fig. 6.6: centroid-trace normal distributions (D50 = {d50 * 1e3:g} mm; θ ccw from +x)", fontsize=10)
    fig.tight_layout()
    return save(fig, folder, "fig6_6")


def stress_curves(curves: dict[str, pd.DataFrame], title: str, stem: str, folder: Path) -> list[Path]:
    """Stress ratio vs shear displacement, one curve per case (smoothed where the series has it)."""
    fig, ax = plt.subplots(figsize=(8, 5))
    for i, (label, s) in enumerate(sorted(curves.items())):
        if "stress_ratio_smooth" in s:      # raw faint, the peak-finding moving average on top
            ax.plot(s["shear_disp"] * 1e3, s["stress_ratio"], lw=0.5, alpha=0.3, color=f"C{i % 10}")
        y = s["stress_ratio_smooth"] if "stress_ratio_smooth" in s else s["stress_ratio"]
        ax.plot(s["shear_disp"] * 1e3, y, lw=1.2, color=f"C{i % 10}", label=label)
    ax.set_xlabel("shear displacement [mm]")
    ax.set_ylabel("stress ratio [-] (surface ΣFx/Σ−Fz; box τ/σ)")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    if not curves:
        ax.text(0.5, 0.5, "no stored series for these cases", transform=ax.transAxes, ha="center", color="C3")
    elif len(curves) <= 12:
        ax.legend(fontsize=7)
    fig.tight_layout()
    return save(fig, folder, stem)


def lab_figure(points, lab: pd.DataFrame, folder: Path, tan_phi: float) -> list[Path]:
    """Fig. 6.10b style: simulated and measured peak efficiency against θa (> 92°); a lab row with only
    tan δ is converted with its own tan_phi, else `tan_phi` (the campaign's or the default's). Without
    any finite tan φ the figure shows tan δ instead."""
    colour, marker = _styles(points)
    tp = lab["tan_phi"].fillna(tan_phi)
    lab_e = lab["efficiency"].fillna(lab["tan_delta"] / tp)
    use_e = lab_e.notna().any() and points.get("efficiency", pd.Series(dtype=float)).notna().any()
    y = "efficiency" if use_e else "peak_stress_ratio"
    lab_y = lab_e if use_e else lab["tan_delta"].fillna(lab["efficiency"] * tp)
    fig, ax = plt.subplots(figsize=(8, 5.6))
    scatter(ax, points, "theta_a_deg_92", y, colour, marker)
    for i, (mat, g) in enumerate(lab.assign(_y=lab_y).groupby("material", sort=True)):
        ax.scatter(g["theta_a_deg"].fillna(0.0), g["_y"], s=110, marker="*", color=f"C{(i + 6) % 10}",
                   edgecolors="k", linewidths=0.6, label=f"lab: {mat}", zorder=5)
    ax.set_xlabel("θa, filter > 92° [° from vertical] (non-dilative at 0)")
    ax.set_ylabel("efficiency E [-]" if use_e else "peak stress ratio tan δ [-]")
    ax.set_title("Fig. 6.10b: laboratory data (stars) with the simulations", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower right")
    _legend(fig, ax, points)
    fig.tight_layout(rect=(0, 0.1, 1, 1))
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
