"""Column contracts of the two tables every engine reader produces and every analysis consumes.

ContactTable: one row per contact per snapshot, in the analysis frame of docs/methods.md §0 (x = shear
axis with the soil moving +x relative to the surface, z up into the soil). Units: m, N, s.
  n = unit normal from body 1 to body 2 (wall/surface contact: from the contact point into the
  particle, body 2 is the particle); force columns are the force ON body 2;
  fn = f·n (positive in compression), ft = f·t with t = (−nz, nx).
  kind: 'pp' particle–particle, 'ps' particle–rough surface, 'pw' particle–other wall.
  For wall contacts id1 = -1 - (wall index) and (x1, z1) = the contact point.
Particles: one row per grain per snapshot (same snapshots as contacts): centre x, z [m], velocity
vx, vz [m/s] in the analysis frame, radius [m]; for velocity profiles, shear bands, inertial number.
History: one row per output step. surface_fx/surface_fz: force ON the surface (box test: on the
upper half across the shear plane) [N]; window_fx/window_fz: the part of it from the grains in the
measuring window (Case.window, away from the side walls; box test: = surface_fx/fz) [N], which the
strength analysis uses; normal_force: platen force [N]; platen_z [m].
"""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd

CONTACT_COLUMNS = (
    "snapshot", "time", "shear_disp", "kind", "id1", "id2",
    "cx", "cz", "nx", "nz", "fn", "ft", "fx", "fz",
    "x1", "z1", "x2", "z2", "overlap",
)
#: the 3D device's extra contact columns (docs/3d.md): contact point y, normal y, force y, centres' y.
#: With them nx, ny, nz are the 3D unit normal (the 2D functions, which renormalise (nx, nz), see its
#: projection on the x–z plane), fn = f·n in 3D and ft the in-plane f·t̂, t̂ = (−nz, 0, nx)/|(nx, nz)|.
CONTACT_COLUMNS_3D = ("cy", "ny", "fy", "y1", "y2")
HISTORY_COLUMNS = (
    "time", "shear_disp", "surface_fx", "surface_fz", "normal_force", "platen_z", "n_contacts",
    "window_fx", "window_fz",
)
PARTICLE_COLUMNS = ("snapshot", "time", "shear_disp", "id", "x", "z", "vx", "vz", "radius")
CONTACT_KINDS = ("pp", "ps", "pw")


@dataclass
class Results:
    """What an engine reader returns for one finished run: the three tables above."""

    contacts: pd.DataFrame                  # CONTACT_COLUMNS
    history: pd.DataFrame                   # HISTORY_COLUMNS
    particles: pd.DataFrame | None = None   # PARTICLE_COLUMNS


class MissingColumnError(ValueError):
    """A table lacks a column of its contract; the message names it."""


def require_columns(df: pd.DataFrame, columns, what: str = "ContactTable") -> None:
    """Refuse a table missing any of `columns`, naming the first missing ones."""
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise MissingColumnError(
            f"{what} is missing column(s) {', '.join(missing)}; "
            f"expected {', '.join(columns)}"
        )
