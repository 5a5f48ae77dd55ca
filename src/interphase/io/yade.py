"""YADE driver output → ContactTable / History / Particles (interphase.tables), vectorised.

Files written by the YADE driver (engines/yade_driver.py) in the case folder (plain CSV/JSON, so
YADE's own python needs nothing beyond the standard library):
  contacts.csv   step, b1, b2 (YADE body ids), contact point cx, cz, YADE normal nx, nz (b1 → b2),
                 force ON b2 fx, fz (normalForce + shearForce: exactly what YADE applied), overlap,
                 centres x1, z1, x2, z2 [m, N]
  particles.csv  step, id, x, z, vx, vz, r
  history.csv    step, surface_fx, surface_fz (force ON the moving wall group, summed O.forces),
                 platen_fz (force of the grains on the platen, +z), platen_z, n_contacts
  bodies.json    first grain id, grain count, [min, max] body ids of each wall group
  recipe.json    dt, steps, shear velocity (interphase.recipe, written with the input)
  shear_start.txt  the step the shear started at, when consolidation ended (time and shear
                 displacement count from it; folders without it: the first stretch's end)
Periodic device (recipe.json period = L): x is written inside [0, L) and body 2 of a contact across
the boundary is brought to the image beside body 1 (x2 −= L·round((x2 − x1)/L), as io/liggghts.py).
The driver already works in the analysis frame (x shear axis, z up, the surface moving −x), so only
ids and kinds are mapped: grain body i → particle id i − first + 1; wall group k → id1 = −1 − k,
kind 'ps' for group 0 (rough surface; the lower half in box tests, as the LIGGGHTS reader), else 'pw'.

Vertex contacts: a grain at a convex surface vertex touches both neighbouring facets at the same
point (same normal, same overlap); YADE applies both forces. Those rows are merged into one contact
with the summed force, so each grain–wall contact is counted once and the contact sums still equal
the force YADE reports on the wall bodies.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.errors import InputError
from interphase.recipe import read_record
from interphase.tables import CONTACT_COLUMNS, HISTORY_COLUMNS, PARTICLE_COLUMNS, Results

#: contact points closer than this [m] are the same point (a shared facet vertex)
SAME_POINT = 1e-10


def _read_csv(path: Path, columns: tuple[str, ...]) -> pd.DataFrame:
    if not path.exists():
        raise InputError(f"{path.name} is missing", where=str(path), fix="rerun the case: YADE did not finish")
    df = pd.read_csv(path, engine="c", dtype=float)
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise InputError(f"columns {missing} are missing", where=str(path),
                         fix="the file was not written by this package's YADE driver: rerun the case")
    return df


def _meta(folder: Path) -> dict:
    """The run's clock (recipe.json: dt, shear velocity; shear_start.txt: the step the shear started
    at, else the end of the first consolidation stretch) and the body ids (bodies.json)."""
    if not (folder / "bodies.json").exists():
        raise InputError("bodies.json is missing", where=str(folder / "bodies.json"), fix="rerun the case")
    rec = read_record(folder)
    b = json.loads((folder / "bodies.json").read_text())
    start = folder / "shear_start.txt"
    n0 = int(start.read_text().split()[0]) if start.exists() else rec.steps.n_consolidate
    return {"dt": rec.dt, "shear_start": n0, "shear_velocity": rec.shear_velocity, "period": rec.period,
            "first": b["first_grain"], "n_grains": b["n_grains"], "walls": b["walls"]}


def _clock(step: np.ndarray, meta: dict) -> tuple[np.ndarray, np.ndarray]:
    t = (step - meta["shear_start"]) * meta["dt"]
    return t, t * meta["shear_velocity"]


def _wall_group(ids: np.ndarray, walls) -> np.ndarray:
    """Wall-group index of each body id, −1 for grains."""
    out = np.full(ids.shape, -1, dtype=np.int64)
    for k, (lo, hi) in enumerate(walls):
        out[(ids >= lo) & (ids <= hi)] = k
    return out


def read_contacts(folder: str | Path, meta: dict | None = None) -> pd.DataFrame:
    folder = Path(folder)
    meta = meta or _meta(folder)
    raw = _read_csv(folder / "contacts.csv", ("step", "b1", "b2", "cx", "cz", "nx", "nz", "fx", "fz", "overlap",
                                               "x1", "z1", "x2", "z2"))
    b1, b2 = raw["b1"].to_numpy(np.int64), raw["b2"].to_numpy(np.int64)
    g1, g2 = _wall_group(b1, meta["walls"]), _wall_group(b2, meta["walls"])
    if ((g1 >= 0) & (g2 >= 0)).any():
        raise InputError("a wall–wall interaction was written", where=str(folder / "contacts.csv"),
                         fix="walls never touch each other in the driver: check bodies.json against the run")
    nx, nz = raw["nx"].to_numpy(), raw["nz"].to_numpy()
    fx, fz = raw["fx"].to_numpy(), raw["fz"].to_numpy()
    x1, z1, x2, z2 = (raw[c].to_numpy() for c in ("x1", "z1", "x2", "z2"))
    # a wall is always body 1 in the table; YADE puts the facet first, but do not rely on it
    swap = g2 >= 0
    if swap.any():
        b1, b2 = np.where(swap, b2, b1), np.where(swap, b1, b2)
        g1 = np.where(swap, g2, g1)
        nx, nz, fx, fz = np.where(swap, -nx, nx), np.where(swap, -nz, nz), np.where(swap, -fx, fx), np.where(swap, -fz, fz)
        x1, x2 = np.where(swap, x2, x1), np.where(swap, x1, x2)
        z1, z2 = np.where(swap, z2, z1), np.where(swap, z1, z2)
    wall = g1 >= 0
    cx, cz = raw["cx"].to_numpy(), raw["cz"].to_numpy()
    x1, z1 = np.where(wall, cx, x1), np.where(wall, cz, z1)      # wall contact: (x1, z1) = contact point
    if meta.get("period"):
        # x periodic: the driver writes x inside [0, L); a contact across the boundary is between one
        # body and the other's image, so bring body 2 to that image (as io/liggghts.py)
        x2 = x2 - meta["period"] * np.round((x2 - x1) / meta["period"])
    kind = np.where(~wall, "pp", np.where(g1 == 0, "ps", "pw"))
    pid = lambda b: b - meta["first"] + 1
    id1 = np.where(wall, -1 - g1, pid(b1))
    id2 = pid(b2)
    norm = np.hypot(nx, nz)                       # normals are in-plane unit vectors; renormalise rounding
    nx, nz = nx / norm, nz / norm
    df = pd.DataFrame({"step": raw["step"].to_numpy(np.int64), "kind": kind, "id1": id1, "id2": id2,
                       "cx": cx, "cz": cz, "nx": nx, "nz": nz, "fx": fx, "fz": fz,
                       "x1": x1, "z1": z1, "x2": x2, "z2": z2, "overlap": raw["overlap"].to_numpy()})
    df = _merge_vertex_contacts(df)
    t, u = _clock(df["step"].to_numpy(), meta)
    steps = np.unique(df["step"].to_numpy())
    df.insert(1, "time", t)
    df.insert(2, "shear_disp", u)
    df["snapshot"] = np.searchsorted(steps, df["step"].to_numpy()).astype(np.int64)
    nx, nz, fx, fz = (df[c].to_numpy() for c in ("nx", "nz", "fx", "fz"))
    df["fn"] = fx * nx + fz * nz
    df["ft"] = -fx * nz + fz * nx
    df["kind"] = pd.Categorical(df["kind"], categories=["pp", "ps", "pw"])
    df = df.sort_values(["snapshot", "kind", "id1", "id2"], kind="stable").reset_index(drop=True)
    return df[list(CONTACT_COLUMNS)]


def _merge_vertex_contacts(df: pd.DataFrame) -> pd.DataFrame:
    """One row per (snapshot, wall, grain, contact point): duplicates (a grain on a shared facet
    vertex) are summed in force; normal, point and overlap are the same for both and kept."""
    wall = df["id1"].to_numpy() < 0
    key = pd.DataFrame({"step": df["step"], "id1": df["id1"], "id2": df["id2"],
                        "qx": np.round(df["cx"].to_numpy() / SAME_POINT).astype(np.int64),
                        "qz": np.round(df["cz"].to_numpy() / SAME_POINT).astype(np.int64)})
    dup = wall & key.duplicated(keep=False).to_numpy()
    if not dup.any():
        return df
    d = df[dup]
    grouped = d.groupby([key.loc[dup, c] for c in ("step", "id1", "id2", "qx", "qz")], sort=False)
    merged = grouped.first()
    merged[["fx", "fz"]] = grouped[["fx", "fz"]].sum()
    merged = merged.reset_index(drop=True)
    return pd.concat([df[~dup], merged[df.columns]], ignore_index=True)


def read_history(folder: str | Path, meta: dict | None = None) -> pd.DataFrame:
    """history.csv → History: surface_fx/fz = force ON the surface (box: the lower half) [N];
    window_fx/fz = the part from the grains in the measuring window (Case.window);
    normal_force = force of the grains on the platen [N]; platen_z [m]."""
    folder = Path(folder)
    meta = meta or _meta(folder)
    h = _read_csv(folder / "history.csv", ("step", "surface_fx", "surface_fz", "platen_fz", "platen_z", "n_contacts",
                                           "window_fx", "window_fz"))
    t, u = _clock(h["step"].to_numpy(), meta)
    return pd.DataFrame({"time": t, "shear_disp": u, "surface_fx": h["surface_fx"], "surface_fz": h["surface_fz"],
                         "normal_force": h["platen_fz"], "platen_z": h["platen_z"],
                         "n_contacts": h["n_contacts"], "window_fx": h["window_fx"],
                         "window_fz": h["window_fz"]})[list(HISTORY_COLUMNS)]


def read_particles(folder: str | Path, meta: dict | None = None) -> pd.DataFrame:
    folder = Path(folder)
    meta = meta or _meta(folder)
    p = _read_csv(folder / "particles.csv", ("step", "id", "x", "z", "vx", "vz", "r"))
    step = p["step"].to_numpy(np.int64)
    t, u = _clock(step, meta)
    return pd.DataFrame({"snapshot": np.searchsorted(np.unique(step), step).astype(np.int64), "time": t,
                         "shear_disp": u, "id": p["id"].to_numpy(np.int64) - meta["first"] + 1,
                         "x": p["x"], "z": p["z"], "vx": p["vx"], "vz": p["vz"], "radius": p["r"]})[list(PARTICLE_COLUMNS)]


def read_folder(folder: str | Path) -> Results:
    folder = Path(folder)
    meta = _meta(folder)
    return Results(read_contacts(folder, meta), read_history(folder, meta), read_particles(folder, meta))


def write_parquet(folder: str | Path, results: Results | None = None) -> dict[str, Path]:
    """contacts/history/particles.parquet beside the YADE files; returns their paths."""
    folder = Path(folder)
    results = results or read_folder(folder)
    out = {}
    for name in ("contacts", "history", "particles"):
        df = getattr(results, name)
        if df is not None:
            out[name] = folder / f"{name}.parquet"
            df.to_parquet(out[name], index=False)
    return out
