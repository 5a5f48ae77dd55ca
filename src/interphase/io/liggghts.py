"""LIGGGHTS output → ContactTable / History / Particles (interphase.tables), vectorised.

Dumps are split into ITEM blocks with one regular-expression pass over the file; the rows of all
blocks are parsed in one bulk pass and their columns looked up by the header names
(`ITEM: ENTRIES c_pc[1] …`, `ITEM: ATOMS id x z …`). Column meaning of compute pair/gran/local and
wall/gran/local (fixed order in LIGGGHTS 3.8.0, docs/engines.md): pairs 1-3 centre i, 4-6 centre j,
7-9 id i, id j, periodic flag, 10-12 force on i, 13-18 normal/tangential parts, 19 area, 20 overlap,
21-23 contact point; walls 1-3 contact point, 4-6 particle centre, 7-9 mesh index, triangle id,
particle id, 10-12 force on the particle, 19-20 area/overlap.

3D device (recipe.json `depth`): contacts are unwrapped in y too and carry the columns
tables.CONTACT_COLUMNS_3D; nx, nz are then components of the 3D unit normal (see `_contacts_3d`).

Frame: the decks move the surface (lower box) in −x, so the engine frame is the analysis frame
(shear_sign = +1, recipe.json). Mesh index 0 in wall/gran is the rough surface ('ps'); others 'pw'.
"""

from __future__ import annotations

import io
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.csv as pacsv

from interphase.errors import InputError
from interphase.recipe import read_record
from interphase.tables import CONTACT_COLUMNS, CONTACT_COLUMNS_3D, HISTORY_COLUMNS, PARTICLE_COLUMNS, Results

_BLOCK = re.compile(
    rb"ITEM: TIMESTEP\s+(\d+)\s+ITEM: NUMBER OF (?:ENTRIES|ATOMS)\s+(\d+)\s+ITEM: BOX BOUNDS[^\n]*\n"
    rb"(?:[^\n]*\n){3}ITEM: (?:ENTRIES|ATOMS) ([^\n]*)\n")


def read_dump(path: str | Path) -> pd.DataFrame:
    """Every block of a LAMMPS/LIGGGHTS text dump in one table: the header's column names plus
    `timestep`. All blocks must share the header (interphase decks write one fixed column list).

    The block bodies are joined and parsed in one pass by pyarrow's CSV reader (rows end in a space,
    so there is one empty trailing field); numpy's loadtxt takes over for irregular whitespace."""
    path = Path(path)
    raw = path.read_bytes()
    matches = list(_BLOCK.finditer(raw))
    if not matches:
        return pd.DataFrame({"timestep": pd.Series(dtype=np.int64)})
    names = matches[0].group(3).decode().split()
    for m in matches[1:]:
        if m.group(3).decode().split() != names:
            raise InputError(f"block at step {int(m.group(1))} has columns {m.group(3).decode().strip()!r}, "
                             f"the first block {' '.join(names)!r}", where=str(path),
                             fix="write one column list per dump file (the interphase decks do)")
    steps = np.array([int(m.group(1)) for m in matches], dtype=np.int64)
    counts = np.array([int(m.group(2)) for m in matches], dtype=np.int64)
    ends = [m.start() for m in matches[1:]] + [len(raw)]
    body = b"".join(raw[m.end():e] for m, e in zip(matches, ends))
    data = _parse_rows(body, len(names), int(counts.sum()), path)
    df = pd.DataFrame(data, columns=names)
    df["timestep"] = np.repeat(steps, counts)
    df.attrs["path"] = str(path)
    return df


def _parse_rows(body: bytes, n_cols: int, n_rows: int, path: Path) -> np.ndarray:
    """rows × n_cols float array of whitespace-separated numbers; InputError if the count is off."""
    msg = f"the blocks do not hold the {n_rows}×{n_cols} numbers their headers announce"
    bad = InputError(msg, where=str(path), fix="the dump is truncated or corrupt: rerun the case")
    if not body.strip():
        if n_rows:
            raise bad
        return np.empty((0, n_cols))
    try:
        table = pacsv.read_csv(pa.py_buffer(body),
                               read_options=pacsv.ReadOptions(autogenerate_column_names=True),
                               parse_options=pacsv.ParseOptions(delimiter=" "))
        extra = table.columns[n_cols:]
        if table.num_columns < n_cols or any(c.null_count != len(c) for c in extra):
            raise ValueError("irregular columns")
        data = np.column_stack([c.to_numpy().astype(float, copy=False) for c in table.columns[:n_cols]])
    except (pa.ArrowInvalid, ValueError):
        try:   # irregular whitespace, or a damaged file that loadtxt will name
            data = np.loadtxt(io.BytesIO(body), ndmin=2)
        except ValueError as exc:
            raise InputError(f"{msg}: {exc}", where=str(path), fix=bad.fix) from None
    if data.shape != (n_rows, n_cols):
        raise bad
    return data


def _meta(folder: Path) -> dict:
    """The run's clock: dt [s], shear velocity [m/s] (recipe.json) and the step the shear started at
    (shear_start.txt, written by the deck once consolidation reached the target platen force;
    without it, the end of the first consolidation stretch)."""
    rec = read_record(folder)
    start = folder / "shear_start.txt"
    n0 = int(float(start.read_text().split()[0])) if start.exists() else rec.steps.n_consolidate
    return {"dt": rec.dt, "shear_velocity": rec.shear_velocity, "shear_start": n0, "period": rec.period,
            "depth": rec.depth}


def _cols(df: pd.DataFrame, prefix: str, first: int, last: int) -> np.ndarray:
    """Columns c_ID[first..last] looked up by name; InputError naming a missing one."""
    names = [f"{prefix}[{i}]" for i in range(first, last + 1)]
    missing = [n for n in names if n not in df.columns]
    if missing:
        raise InputError(f"column {missing[0]} is missing from the dump's header", where=df.attrs.get("path", "dump"),
                         fix="the deck's compute must write every column (docs/engines.md): re-render and rerun")
    return df[names].to_numpy()


def _contacts_from_dump(df: pd.DataFrame, prefix: str, wall: bool, meta: dict) -> dict[str, np.ndarray]:
    """ContactTable columns (kind as codes 0 pp, 1 ps, 2 pw) for every row of a local dump."""
    if wall:
        p1 = _cols(df, prefix, 1, 3)            # contact point on the mesh
        p2 = _cols(df, prefix, 4, 6)            # particle centre
        mesh, pid = _cols(df, prefix, 7, 7)[:, 0], _cols(df, prefix, 9, 9)[:, 0]
        id1, id2 = -1 - mesh, pid
        f2 = _cols(df, prefix, 10, 12)          # force on the particle = body 2
        kind = np.where(mesh == 0, 1, 2).astype(np.int8)
        cpt = p1
    else:
        p1, p2 = _cols(df, prefix, 1, 3), _cols(df, prefix, 4, 6)
        id1, id2 = _cols(df, prefix, 7, 7)[:, 0], _cols(df, prefix, 8, 8)[:, 0]
        f2 = -_cols(df, prefix, 10, 12)         # the dump gives the force on i; body 2 = j
        kind = np.zeros(len(df), np.int8)
        cpt = _cols(df, prefix, 21, 23)
    if meta.get("period"):
        # x periodic: the dump gives each body's position inside [0, L]; a contact across the
        # boundary is between one body and the other's image, so bring body 2 to that image
        p2 = p2.copy()
        p2[:, 0] -= meta["period"] * np.round((p2[:, 0] - p1[:, 0]) / meta["period"])
    if meta.get("depth"):
        return _contacts_3d(df, prefix, meta, p1, p2, f2, id1, id2, kind, cpt)
    branch = p2 - p1
    nrm = np.hypot(branch[:, 0], branch[:, 2])
    with np.errstate(invalid="ignore", divide="ignore"):
        nx, nz = branch[:, 0] / nrm, branch[:, 2] / nrm
    fx, fz = f2[:, 0], f2[:, 2]
    t = (df["timestep"].to_numpy() - meta["shear_start"]) * meta["dt"]
    return {
        "snapshot": df["timestep"].to_numpy(), "time": t, "shear_disp": t * meta["shear_velocity"], "kind": kind,
        "id1": id1.astype(np.int64), "id2": id2.astype(np.int64),
        "cx": cpt[:, 0], "cz": cpt[:, 2], "nx": nx, "nz": nz,
        "fn": fx * nx + fz * nz, "ft": -fx * nz + fz * nx, "fx": fx, "fz": fz,
        "x1": p1[:, 0], "z1": p1[:, 2], "x2": p2[:, 0], "z2": p2[:, 2],
        "overlap": _cols(df, prefix, 20, 20)[:, 0],
    }


def _contacts_3d(df, prefix, meta, p1, p2, f2, id1, id2, kind, cpt) -> dict[str, np.ndarray]:
    """The 3D device's contacts (docs/3d.md): body 2 brought to the image nearest body 1 in y too
    (period = the cell's depth); n the 3D unit normal (nx, ny, nz), fn = f·n; ft the in-plane
    tangential force, f·t̂ with t̂ = (−nz, 0, nx)/|(nx, nz)| (the 2D t when ny = 0); the 3D columns
    cy, ny, fy, y1, y2 (tables.CONTACT_COLUMNS_3D) beside the 2D ones."""
    p2 = p2.copy()
    p2[:, 1] -= meta["depth"] * np.round((p2[:, 1] - p1[:, 1]) / meta["depth"])
    branch = p2 - p1
    nrm = np.linalg.norm(branch, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        nx, ny, nz = (branch[:, i] / nrm for i in range(3))
        ft = (-f2[:, 0] * nz + f2[:, 2] * nx) / np.hypot(nx, nz)
    fx, fy, fz = f2[:, 0], f2[:, 1], f2[:, 2]
    t = (df["timestep"].to_numpy() - meta["shear_start"]) * meta["dt"]
    return {
        "snapshot": df["timestep"].to_numpy(), "time": t, "shear_disp": t * meta["shear_velocity"], "kind": kind,
        "id1": id1.astype(np.int64), "id2": id2.astype(np.int64),
        "cx": cpt[:, 0], "cz": cpt[:, 2], "nx": nx, "nz": nz,
        "fn": fx * nx + fy * ny + fz * nz, "ft": ft, "fx": fx, "fz": fz,
        "x1": p1[:, 0], "z1": p1[:, 2], "x2": p2[:, 0], "z2": p2[:, 2],
        "overlap": _cols(df, prefix, 20, 20)[:, 0],
        "cy": cpt[:, 1], "ny": ny, "fy": fy, "y1": p1[:, 1], "y2": p2[:, 1],
    }


def read_contacts(folder: str | Path, meta: dict | None = None) -> pd.DataFrame:
    folder = Path(folder)
    meta = meta or _meta(folder)
    dumps = [(read_dump(folder / "contacts_pair.dump"), "c_pc", False),
             (read_dump(folder / "contacts_wall.dump"), "c_wc", True)]
    parts = [_contacts_from_dump(df, prefix, wall, meta) for df, prefix, wall in dumps if len(df)]
    columns = list(CONTACT_COLUMNS) + (list(CONTACT_COLUMNS_3D) if meta.get("depth") else [])
    if not parts:
        return pd.DataFrame({c: pd.Series(dtype=float) for c in columns})
    cols = {c: np.concatenate([p[c] for p in parts]) for c in parts[0]}
    steps = np.unique(cols["snapshot"])
    cols["snapshot"] = np.searchsorted(steps, cols["snapshot"]).astype(np.int64)   # 0, 1, 2 … in time order
    order = np.lexsort((cols["id2"], cols["id1"], cols["kind"], cols["snapshot"]))
    cols = {c: v[order] for c, v in cols.items()}
    cols["kind"] = pd.Categorical.from_codes(cols["kind"], categories=["pp", "ps", "pw"])
    return pd.DataFrame(cols)[columns]


def read_history(folder: str | Path, meta: dict | None = None) -> pd.DataFrame:
    """history.txt → History. The first row after a `run` shows mesh forces doubled (docs/engines.md):
    dropped. surface_fx/fz: force ON the surface (lower box) [N]; window_fx/fz: from the grains in
    the measuring window (Case.window); normal_force: platen force [N]."""
    folder = Path(folder)
    meta = meta or _meta(folder)
    h = pd.read_csv(folder / "history.txt", sep=r"\s+")
    h = h.iloc[1:].reset_index(drop=True)
    t = (h["step"].to_numpy() - meta["shear_start"]) * meta["dt"]
    return pd.DataFrame({
        "time": t, "shear_disp": t * meta["shear_velocity"],
        "surface_fx": h["surface_fx"], "surface_fz": h["surface_fz"],
        "normal_force": h["platen_fz"], "platen_z": h["platen_z"], "n_contacts": h["n_contacts"],
        "window_fx": h["window_fx"], "window_fz": h["window_fz"],
    })[list(HISTORY_COLUMNS)]


def read_particles(folder: str | Path, meta: dict | None = None) -> pd.DataFrame:
    folder = Path(folder)
    meta = meta or _meta(folder)
    df = read_dump(folder / "particles.dump")
    if not len(df):
        return pd.DataFrame({c: pd.Series(dtype=float) for c in PARTICLE_COLUMNS})
    steps = df["timestep"].to_numpy()
    t = (steps - meta["shear_start"]) * meta["dt"]
    out = pd.DataFrame({"snapshot": np.unique(steps, return_inverse=True)[1].astype(np.int64), "time": t,
                        "shear_disp": t * meta["shear_velocity"], "id": df["id"].to_numpy().astype(np.int64),
                        "x": df["x"].to_numpy(), "z": df["z"].to_numpy(), "vx": df["vx"].to_numpy(),
                        "vz": df["vz"].to_numpy(), "radius": df["radius"].to_numpy()})[list(PARTICLE_COLUMNS)]
    if meta.get("depth") and "y" in df.columns:      # the 3D device's dump: y and vy too
        out["y"], out["vy"] = df["y"].to_numpy(), df["vy"].to_numpy()
    return out


def read_folder(folder: str | Path) -> Results:
    folder = Path(folder)
    meta = _meta(folder)
    return Results(read_contacts(folder, meta), read_history(folder, meta), read_particles(folder, meta))
