"""Force-network picture of one contact snapshot (the study's Figure 6.2 style) as PNG, GIF and VTK.

Picture (`network_figure`, `draw_network`): the grains of the snapshot to scale (one circle per grain
of the Particles table, its real diameter; an EllipseCollection), the rough surface as the engine
had it at that snapshot (Case.surface() moved −x by the snapshot's shear displacement, filled
below), and every contact as a segment from (x1, z1) to (x2, z2) of the ContactTable: grain centre
to grain centre for 'pp', contact point to grain centre for wall and surface contacts. Line width ∝
|fn| (the largest normal force of the snapshot gets the widest line); 'pp' black, 'ps' (grain–
surface) red, 'pw' (platen, side walls) grey. The measuring window (Case.window) is marked by
dashed lines: the walled device's window lies WALL_ZONE_D50 inside the side walls, the periodic
device's is the whole cell [0, L]. Periodic device: the readers unwrap every branch (body 2 is put
at the image nearest body 1), so a contact across x = 0 or L is drawn short, reaching out of the
cell, and its image on the other side (and the grains' images) are drawn fainter so both ends show;
nothing is drawn box-wide. Coordinates in mm, x the shear axis (soil moves +x relative to the
surface), z up.

Animation (`animate_case`): the picture at every contact snapshot beside the stress-ratio curve of
series.parquet with a marker at the snapshot's shear displacement; a GIF (Pillow).

Artists carry gids the tests read: 'grains', 'grain-images', 'chains-pp', 'chains-ps', 'chains-pw'
(and '…-images'), 'surface', 'surface-fill', 'window', 'walls'.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.errors import InputError
from interphase.tables import require_columns

MAX_WIDTH = 4.0                 # [pt] widest line when the figure scale is not known
COLOURS = {"pp": "black", "ps": "tab:red", "pw": "0.55"}
KIND_CODE = {"pp": 0, "ps": 1, "pw": 2}
GRAIN_FACE, GRAIN_EDGE = "#e9e4d8", "#9a9384"
SURFACE_FACE, SURFACE_EDGE = "#7d8fa3", "#2f4053"
_NEED = ("snapshot", "kind", "x1", "z1", "x2", "z2", "fx", "fz", "fn", "ft")
_PART = ("snapshot", "x", "z", "radius")


def _snapshot(contacts: pd.DataFrame, snapshot) -> pd.DataFrame:
    require_columns(contacts, _NEED)
    c = contacts[contacts["snapshot"].to_numpy() == snapshot]
    ok = np.isfinite(c[["x1", "z1", "x2", "z2", "fx", "fz"]].to_numpy(float)).all(axis=1)
    c = c[ok]
    if c.empty:
        have = np.unique(contacts["snapshot"].to_numpy())
        raise InputError(f"snapshot {snapshot!r} has no usable contact", where="snapshot",
                         fix=f"pick one of {', '.join(map(str, have[:20]))}" if have.size else "the table is empty")
    return c


# ---- the case a run folder holds -------------------------------------------------------------
def run_case(folder, campaign=None, label: str | None = None):
    """The Case of a finished run folder: the campaign's case of that label when a campaign is
    given (its profile file included), else rebuilt from case.json's inputs (generated profiles
    only). None when neither works: the picture is then drawn without the surface."""
    from interphase.case import case_from_dict

    folder = Path(folder)
    try:
        rec = json.loads((folder / "case.json").read_text())
    except (OSError, ValueError):
        rec = {}
    label = label or rec.get("label")
    if campaign is not None and label:
        from interphase.campaign.plan import case_label

        for c in campaign.cases:
            if case_label(c.case) == label:
                return c.case
    inputs = dict(rec.get("inputs") or {})
    if not inputs:
        return None
    prof = inputs.pop("profile", None)
    if isinstance(prof, dict):
        if prof.get("kind") == "file":
            return None
        inputs["profile"] = {"kind": prof["kind"], **prof.get("params", {})}
    try:
        return case_from_dict(inputs, where=str(folder / "case.json"))
    except (InputError, TypeError, ValueError):
        return None


def surface_at(case, shear_disp: float, x0: float, x1: float) -> tuple[np.ndarray, np.ndarray] | None:
    """(x, z) [m] of the case's surface at shear displacement `shear_disp`, over [x0, x1]: the
    engines move it −x by the shear displacement (checked: the 'ps' contact points lie on it to
    1e-11 m); the periodic cell is repeated as the engine wraps it."""
    if case is None or case.test != "interface":
        return None
    s = case.surface()
    x, z = s.x - shear_disp, s.z
    if case.periodic:
        period = s.length
        k0 = math.floor((x0 - x[-1]) / period)
        k1 = math.ceil((x1 - x[0]) / period)
        ks = np.arange(k0, k1 + 1)
        x = (x[None, :-1] + ks[:, None] * period).ravel()
        z = np.tile(z[:-1], len(ks))
    keep = (x >= x0) & (x <= x1)
    idx = np.flatnonzero(keep)
    if idx.size == 0:
        return None
    lo, hi = max(idx[0] - 1, 0), min(idx[-1] + 2, len(x))       # one vertex beyond each end
    return x[lo:hi], z[lo:hi]


# ---- drawing ---------------------------------------------------------------------------------
def _images(x: np.ndarray, reach: np.ndarray, period: float, x0: float, x1: float):
    """Shifts (±period) of items at x with half-extent `reach` that show inside [x0, x1]: (index, shift)."""
    out_i, out_s = [], []
    for shift in (-period, period):
        sel = np.flatnonzero((x + shift + reach >= x0) & (x + shift - reach <= x1))
        out_i.append(sel)
        out_s.append(np.full(sel.size, shift))
    return np.concatenate(out_i), np.concatenate(out_s)


_MM = 1e3                       # m → mm: the picture's unit


def draw_network_on(ax, contacts: pd.DataFrame, snapshot, *, particles: pd.DataFrame | None = None,
                    case=None, profile=None, window: tuple[float, float] | None = None,
                    period: float | None = None, max_width: float | None = None, legend: bool = True,
                    smooth_grains: bool = True) -> dict:
    """Draw the network of `snapshot` on `ax` (mm). `case` gives the surface at the snapshot, the
    window, the periodic cell and the side walls; `profile` (a Profile or an (x, z) pair [m], drawn
    as given) and `window`/`period` [m] override it. Returns {gid: artist}."""
    from matplotlib.lines import Line2D

    c = _snapshot(contacts, snapshot)
    shear = float(c["shear_disp"].iloc[0]) if "shear_disp" in c else 0.0
    seg = np.stack([c[["x1", "z1"]].to_numpy(float), c[["x2", "z2"]].to_numpy(float)], axis=1)   # m
    fn = np.abs(c["fn"].to_numpy(float))
    fmax = float(fn.max()) if fn.size and fn.max() > 0 else 1.0
    grains = _snapshot_grains(particles, snapshot)
    if case is not None:
        window = window if window is not None else case.window
        if period is None and case.periodic:
            period = case.box_length
    box_l = case.box_length if case is not None else None
    d = float(np.median(2 * grains["radius"])) if grains is not None else (case.d50 if case is not None else
                                                                            float(np.median(np.hypot(*(seg[:, 1] - seg[:, 0]).T))))
    x0, x1 = _x_view(seg, grains, d, period, box_l)
    surf = surface_at(case, shear, x0, x1) if profile is None else (
        (np.asarray(profile.x, float), np.asarray(profile.z, float)) if hasattr(profile, "x")
        else tuple(np.asarray(p, float) for p in profile))
    bottom, top = _z_view(seg, grains, surf, d)

    ax.set_xlim(x0 * _MM, x1 * _MM)
    ax.set_ylim(bottom * _MM, top * _MM)
    ax.set_aspect("equal")
    art: dict = {}
    if max_width is None:           # about half a grain wide, in points, at the axes' scale
        fig = ax.figure
        w_in = fig.get_size_inches()[0] * ax.get_position().width
        max_width = float(np.clip(0.45 * d * _MM * 72.0 * w_in / ((x1 - x0) * _MM), 1.0, 8.0))
    if surf is not None:
        _draw_surface(ax, art, surf, bottom)
    if grains is not None:
        _draw_grains(ax, art, grains, period, (x0, x1), smooth_grains)
    lw = max_width * fn / fmax        # [pt], ∝ |fn|
    handles = _draw_chains(ax, art, seg, c["kind"].astype(str).to_numpy(), lw, period, (x0, x1))
    if window is not None:
        _draw_window(ax, art, window, period, (x0, x1))
        handles.append(Line2D([], [], color="tab:green", ls="--", lw=1.0,
                              label="periodic cell = window" if period else "measuring window"))
    if box_l is not None and not period:
        art["walls"] = [ax.axvline(w * _MM, color="0.2", lw=2.5, zorder=6, gid="walls") for w in (0.0, box_l)]
    art["max_width"], art["fmax"], art["shear_disp"] = max_width, fmax, shear
    if legend:
        ax.legend(handles=handles, loc="lower left", bbox_to_anchor=(0.0, 1.01), ncol=len(handles), fontsize=7,
                  frameon=False, borderaxespad=0.0)        # above the axes: never over the grains
    ax.set_xlabel("x [mm] (soil moves +x relative to the surface)")
    ax.set_ylabel("z [mm]")
    return art


def _snapshot_grains(particles: pd.DataFrame | None, snapshot) -> pd.DataFrame | None:
    """The Particles rows of `snapshot` (x, z, radius [m]), or None when there are none."""
    if particles is None:
        return None
    require_columns(particles, _PART, "Particles")
    grains = particles[particles["snapshot"].to_numpy() == snapshot]
    return None if grains.empty else grains


def _x_view(seg: np.ndarray, grains, d: float, period: float | None, box_l: float | None) -> tuple[float, float]:
    """(x0, x1) [m] shown: the periodic cell or the walled box with a grain's margin (`d` [m]),
    else the data's extent."""
    if period:
        return -0.6 * d, period + 0.6 * d
    if box_l is not None:
        return -1.0 * d, box_l + 1.0 * d
    xs = seg[:, :, 0] if grains is None else np.concatenate([seg[:, :, 0].ravel(), grains["x"].to_numpy(float)])
    return float(np.min(xs)) - 0.5 * d, float(np.max(xs)) + 0.5 * d


def _z_view(seg: np.ndarray, grains, surf, d: float) -> tuple[float, float]:
    """(bottom, top) [m] shown: contacts, grains and surface, with margins in grain diameters `d` [m]
    (more below, where the surface is filled)."""
    top = max(float(seg[:, :, 1].max()),
              float((grains["z"] + grains["radius"]).max()) if grains is not None else -np.inf) + 0.3 * d
    bottom_data = float(seg[:, :, 1].min())
    if grains is not None:
        bottom_data = min(bottom_data, float((grains["z"] - grains["radius"]).min()))
    if surf is not None:
        bottom_data = min(bottom_data, float(np.min(surf[1])))
    return bottom_data - 0.8 * d, top


def _draw_surface(ax, art: dict, surf, bottom: float) -> None:
    """The surface (x, z) [m]: filled down to `bottom` [m], the profile line on top."""
    sx, sz = surf[0] * _MM, surf[1] * _MM
    art["surface-fill"] = ax.fill_between(sx, sz, bottom * _MM, color=SURFACE_FACE, lw=0, zorder=1,
                                          gid="surface-fill")
    (art["surface"],) = ax.plot(sx, sz, color=SURFACE_EDGE, lw=1.0, zorder=4, gid="surface", label="surface")


def _grain_circles(ax, x, z, r, smooth: bool, **style):
    """Circles of radius r [m] at (x, z) [m], to scale in the axes' data units (mm)."""
    from matplotlib.collections import EllipseCollection

    return EllipseCollection(2 * r * _MM, 2 * r * _MM, np.zeros(r.size), units="xy",
                             offsets=np.column_stack([x, z]) * _MM, offset_transform=ax.transData,
                             facecolors=GRAIN_FACE, edgecolors=GRAIN_EDGE,
                             linewidths=0.4 if smooth else 0.3, antialiaseds=smooth, zorder=2, **style)


def _draw_grains(ax, art: dict, grains: pd.DataFrame, period: float | None, xview, smooth: bool) -> None:
    """The grains to scale; in a periodic cell their images across x = 0 and L, fainter."""
    gx, gz, gr = (grains[k].to_numpy(float) for k in ("x", "z", "radius"))
    coll = _grain_circles(ax, gx, gz, gr, smooth)
    coll.set_gid("grains")
    art["grains"] = ax.add_collection(coll)
    if period:
        i, s = _images(gx, gr, period, *xview)
        if i.size:
            im = _grain_circles(ax, gx[i] + s, gz[i], gr[i], smooth, alpha=0.45)
            im.set_gid("grain-images")
            art["grain-images"] = ax.add_collection(im)


def _draw_chains(ax, art: dict, seg: np.ndarray, kinds: np.ndarray, lw: np.ndarray, period: float | None,
                 xview) -> list:
    """The contacts as segments [m], width `lw` [pt] per contact, coloured by kind; in a periodic
    cell the images of those crossing x = 0 or L, fainter. Returns the legend handles."""
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D

    handles = []
    for kind, colour in COLOURS.items():
        sel = kinds == kind
        if not sel.any():
            continue
        lc = LineCollection(seg[sel] * _MM, linewidths=lw[sel], colors=colour, capstyle="round",
                            zorder=5 if kind == "ps" else 3, gid=f"chains-{kind}")
        art[f"chains-{kind}"] = ax.add_collection(lc)
        handles.append(Line2D([], [], color=colour, lw=2, label={"pp": "grain–grain", "ps": "grain–surface",
                                                                 "pw": "grain–wall/platen"}[kind] + f" ({int(sel.sum())})"))
        if period:
            mid = seg[sel].mean(axis=1)[:, 0]
            half = np.abs(seg[sel][:, 1, 0] - seg[sel][:, 0, 0]) / 2
            i, s = _images(mid, half, period, *xview)
            if i.size:
                segs = seg[sel][i].copy()
                segs[:, :, 0] += s[:, None]
                li = LineCollection(segs * _MM, linewidths=lw[sel][i], colors=colour, capstyle="round", alpha=0.5,
                                    zorder=5 if kind == "ps" else 3, gid=f"chains-{kind}-images")
                art[f"chains-{kind}-images"] = ax.add_collection(li)
    return handles


def _draw_window(ax, art: dict, window: tuple[float, float], period: float | None, xview) -> None:
    """The measuring window's edges [m], dashed; outside it (walled box only) a grey shade."""
    w0, w1 = window
    lines = [ax.axvline(w * _MM, color="tab:green", ls="--", lw=1.0, zorder=6) for w in (w0, w1)]
    for ln in lines:
        ln.set_gid("window")
    art["window"] = lines
    if not period:
        x0, x1 = xview
        for a, b in ((x0, w0), (w1, x1)):
            if b > a:
                ax.axvspan(a * _MM, b * _MM, color="0.5", alpha=0.12, lw=0, zorder=0.5)


def _fig_size(x_span: float, z_span: float, width: float = 10.0) -> tuple[float, float]:
    return width, max(2.5, min(12.0, width * z_span / max(x_span, 1e-12) + 0.9))


def network_figure(contacts: pd.DataFrame, snapshot, *, particles=None, case=None, profile=None,
                   title: str | None = None, width: float = 10.0):
    """(figure, artists) of one snapshot's network (see draw_network_on); the caller closes it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    c = _snapshot(contacts, snapshot)
    xs, zs = c[["x1", "x2"]].to_numpy(float), c[["z1", "z2"]].to_numpy(float)
    xspan = case.box_length if case is not None else np.ptp(xs)
    fig = plt.figure(figsize=_fig_size(xspan, np.ptp(zs) + 2 * (case.d50 if case is not None else 0), width))
    ax = fig.add_axes([0.07, 0.1, 0.9, 0.8])
    art = draw_network_on(ax, contacts, snapshot, particles=particles, case=case, profile=profile)
    ax.set_title(title or f"force network, snapshot {snapshot} (shear {art['shear_disp'] * 1e3:.2f} mm), "
                 f"max |fn| = {art['fmax']:.3g} N", fontsize=9, pad=16)     # the legend sits between
    return fig, art


def draw_network(contacts: pd.DataFrame, snapshot, png_path, profile=None, title: str | None = None,
                 dpi: int = 200, *, particles: pd.DataFrame | None = None, case=None) -> Path:
    """Draw the force network of `snapshot` to `png_path` (see network_figure). Returns the path."""
    import matplotlib.pyplot as plt

    fig, _ = network_figure(contacts, snapshot, particles=particles, case=case, profile=profile, title=title)
    path = Path(png_path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi, bbox_inches="tight", pad_inches=0.08)
    plt.close(fig)
    return path


def read_snapshot_tables(folder, snapshot=None) -> tuple[pd.DataFrame, pd.DataFrame | None]:
    """(contacts, particles) of a run folder, only `snapshot`'s rows when given; particles None
    when the folder has no particles.parquet."""
    folder = Path(folder)
    filt = [("snapshot", "==", int(snapshot))] if snapshot is not None else None
    contacts = pd.read_parquet(folder / "contacts.parquet", filters=filt)
    pp = folder / "particles.parquet"
    particles = pd.read_parquet(pp, columns=list(_PART), filters=filt) if pp.exists() else None
    return contacts, particles


def case_network(folder, snapshot, png_path, *, case=None, title: str | None = None, dpi: int = 200) -> Path:
    """The network picture of one snapshot of a finished run folder (contacts.parquet, particles.parquet)."""
    contacts, particles = read_snapshot_tables(folder, snapshot)
    return draw_network(contacts, int(snapshot), png_path, title=title, dpi=dpi, particles=particles, case=case)


def find_run(summaries: pd.DataFrame, key: str) -> pd.Series:
    """The finished run a label or case id names (an id prefix of ≥ 4 characters that names one run
    is taken too). InputError, with the nearest labels, when none or several match."""
    import difflib

    key = str(key).strip()
    labels = summaries["label"].astype(str) if "label" in summaries else pd.Series(dtype=str)
    ids = summaries["case_id"].astype(str) if "case_id" in summaries else pd.Series(dtype=str)
    hit = summaries[(labels == key) | (ids == key)]
    if hit.empty and len(key) >= 4:
        hit = summaries[ids.str.startswith(key)]
    if len(hit) == 1:
        return hit.iloc[0]
    if len(hit) > 1:
        raise InputError(f"{key!r} names {len(hit)} runs", where="--animate",
                         fix="give a case id: " + ", ".join(hit["case_id"].astype(str).head(5)))
    close = difflib.get_close_matches(key, list(labels.unique()), n=3, cutoff=0.5)
    raise InputError(f"no finished run with label or case id {key!r}", where="--animate",
                     fix=(f"did you mean {', '.join(close)}?" if close else
                          f"`campaign status` lists the {len(labels)} finished runs' labels"))


# ---- animation -------------------------------------------------------------------------------
def animate_case(folder, gif_path, *, case=None, title: str = "", dpi: int = 80, fps: float = 3.0,
                 max_frames: int = 24) -> Path:
    """GIF of a run folder: the network at every contact snapshot (left) beside the stress-ratio
    curve of series.parquet with a marker at the snapshot's shear displacement (right). One frame
    per contact snapshot, at most `max_frames` evenly spread (first and last kept): a 1000-grain
    frame costs ~0.1 MB."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter

    folder = Path(folder)
    if not (folder / "contacts.parquet").exists():
        raise InputError(f"{folder} has no contacts.parquet", where="--animate", fix="pick a finished run")
    contacts, particles = read_snapshot_tables(folder)
    require_columns(contacts, _NEED)
    snaps = np.unique(contacts["snapshot"].to_numpy())
    if snaps.size == 0:
        raise InputError(f"{folder} has no contact snapshot", where="--animate")
    if snaps.size > max_frames:
        snaps = snaps[np.unique(np.round(np.linspace(0, snaps.size - 1, max_frames)).astype(int))]
    u_snap = contacts.groupby("snapshot", sort=True)["shear_disp"].first().reindex(snaps).to_numpy(float)
    try:
        series = pd.read_parquet(folder / "series.parquet", columns=["shear_disp", "stress_ratio"])
        su, sr = series["shear_disp"].to_numpy(float), series["stress_ratio"].to_numpy(float)
    except (OSError, ValueError, KeyError):
        su = sr = np.array([])
    ok = np.isfinite(su) & np.isfinite(sr)
    su, sr = su[ok], sr[ok]

    zs = contacts[["z1", "z2"]].to_numpy(float)
    xspan = case.box_length if case is not None else float(np.ptp(contacts[["x1", "x2"]].to_numpy(float)))
    nw, nh = _fig_size(xspan, float(np.ptp(zs)) + 2 * (case.d50 if case is not None else 0), 6.5)
    fig = plt.figure(figsize=(nw + 3.6, nh))
    ax = fig.add_axes([0.06, 0.1, 0.6, 0.8])
    axc = fig.add_axes([0.74, 0.16, 0.24, 0.7])
    if su.size:
        axc.plot(su * 1e3, sr, color="tab:blue", lw=1.0)
    axc.set_xlabel("shear displacement [mm]", fontsize=8)
    axc.set_ylabel("stress ratio τ/σn [-]", fontsize=8)
    axc.tick_params(labelsize=7)
    axc.grid(alpha=0.3)
    (marker,) = axc.plot([], [], "o", color="tab:red", ms=6, zorder=5)

    def frame(i):
        ax.clear()
        s = snaps[i]
        art = draw_network_on(ax, contacts, s, particles=particles, case=case, legend=True, smooth_grains=False)
        ax.set_title(f"{title}\nsnapshot {int(s)}: shear {u_snap[i] * 1e3:.2f} mm, max |fn| = {art['fmax']:.3g} N",
                     fontsize=8, pad=16)
        ax.tick_params(labelsize=7)
        if su.size:
            marker.set_data([u_snap[i] * 1e3], [np.interp(u_snap[i], su, sr)])
        return []

    anim = FuncAnimation(fig, frame, frames=len(snaps), blit=False, repeat=False)
    path = Path(gif_path)
    path.parent.mkdir(parents=True, exist_ok=True)
    anim.save(str(path), writer=PillowWriter(fps=fps), dpi=dpi)
    plt.close(fig)
    return path


def network_polydata(contacts: pd.DataFrame, snapshot):
    """pyvista.PolyData of the snapshot: one line cell per contact (points in m, y = 0) with cell
    arrays force (|f| [N]), fn, ft [N], fx, fz [N] and kind (0 pp, 1 ps, 2 pw)."""
    try:
        import pyvista as pv
    except ImportError as exc:   # pyvista is the optional 'viz' extra
        raise InputError("VTK output needs pyvista", where="write_network_vtk",
                         fix="pip install 'interphase-dem[viz]'") from exc
    c = _snapshot(contacts, snapshot)
    n = len(c)
    pts = np.zeros((2 * n, 3))
    pts[0::2, 0], pts[0::2, 2] = c["x1"].to_numpy(float), c["z1"].to_numpy(float)
    pts[1::2, 0], pts[1::2, 2] = c["x2"].to_numpy(float), c["z2"].to_numpy(float)
    lines = np.column_stack([np.full(n, 2), np.arange(0, 2 * n, 2), np.arange(1, 2 * n, 2)]).ravel()
    mesh = pv.PolyData(pts, lines=lines)
    mesh.cell_data["force"] = np.hypot(c["fx"].to_numpy(float), c["fz"].to_numpy(float))
    for col in ("fn", "ft", "fx", "fz"):
        mesh.cell_data[col] = c[col].to_numpy(float)
    mesh.cell_data["kind"] = c["kind"].astype(str).map(KIND_CODE).to_numpy(np.int32)
    return mesh


def write_network_vtk(contacts: pd.DataFrame, snapshot, path) -> Path:
    """Write the snapshot's force network as VTK PolyData (.vtp) for ParaView (Tube filter, radius
    by 'force'). Returns the path."""
    path = Path(path)
    if path.suffix != ".vtp":
        path = path.with_suffix(".vtp")
    path.parent.mkdir(parents=True, exist_ok=True)
    network_polydata(contacts, snapshot).save(str(path))
    return path
