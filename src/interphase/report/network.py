"""Force-network picture of one contact snapshot (the study's Figure 6.2 style) as PNG and VTK.

Every contact is a segment from (x1, z1) to (x2, z2) of the ContactTable: grain centre to grain
centre for 'pp', contact point to grain centre for wall and surface contacts ('ps' drawn to the
contact point on the surface). Line width ∝ |f| (the largest force gets MAX_WIDTH points); 'pp'
black, 'ps' red, 'pw' grey. Coordinates in mm. The surface profile, when given, is drawn as it is:
pass it positioned for the snapshot (shifted by the surface's displacement).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from interphase.errors import InputError
from interphase.tables import require_columns

MAX_WIDTH = 4.0
COLOURS = {"pp": "black", "ps": "tab:red", "pw": "0.55"}
KIND_CODE = {"pp": 0, "ps": 1, "pw": 2}
_NEED = ("snapshot", "kind", "x1", "z1", "x2", "z2", "fx", "fz", "fn", "ft")


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


def draw_network(contacts: pd.DataFrame, snapshot, png_path, profile=None, title: str | None = None,
                 dpi: int = 200) -> Path:
    """Draw the force network of `snapshot` to `png_path`. `profile`: an interphase Profile or an
    (x, z) pair in metres, drawn as a line. Returns the path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    c = _snapshot(contacts, snapshot)
    seg = np.stack([c[["x1", "z1"]].to_numpy(float), c[["x2", "z2"]].to_numpy(float)], axis=1) * 1e3
    mag = np.hypot(c["fx"].to_numpy(float), c["fz"].to_numpy(float))
    fmax = mag.max() if mag.max() > 0 else 1.0
    kinds = c["kind"].astype(str).to_numpy()
    xs, zs = seg[:, :, 0], seg[:, :, 1]
    width = max(4.0, min(16.0, 1.2 * (xs.max() - xs.min()) / max(zs.max() - zs.min(), 1e-9) * 3.0))
    fig, ax = plt.subplots(figsize=(width, width * (zs.max() - zs.min() + 1e-9) / (xs.max() - xs.min() + 1e-9) + 0.8))
    for kind, colour in COLOURS.items():
        sel = kinds == kind
        if sel.any():
            ax.add_collection(LineCollection(seg[sel], linewidths=MAX_WIDTH * mag[sel] / fmax, colors=colour,
                                             capstyle="round", label=f"{kind} ({int(sel.sum())})"))
    if profile is not None:
        px, pz = (profile.x, profile.z) if hasattr(profile, "x") else profile
        px, pz = np.asarray(px, float) * 1e3, np.asarray(pz, float) * 1e3
        keep = (px >= xs.min() - 1) & (px <= xs.max() + 1)
        ax.plot(px[keep], pz[keep], color="tab:blue", lw=1.0, label="surface")
    ax.set_xlim(xs.min() - 0.2, xs.max() + 0.2)
    ax.set_ylim(min(zs.min(), ax.get_ylim()[0]) - 0.2, zs.max() + 0.2)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm] (soil moves +x relative to the surface)")
    ax.set_ylabel("z [mm]")
    shear = float(c["shear_disp"].iloc[0]) * 1e3 if "shear_disp" in c else float("nan")
    ax.set_title(title or f"force network, snapshot {snapshot} (shear {shear:.2f} mm), max |f| = {fmax:.3g} N")
    ax.legend(loc="upper right", fontsize=7)
    fig.tight_layout()
    path = Path(png_path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
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
