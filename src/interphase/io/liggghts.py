"""LIGGGHTS output → ContactTable / History / Particles (interphase.tables), vectorised.

Dumps are split into ITEM blocks with one regular-expression pass over the file; each block's rows
are parsed in bulk by numpy and its columns looked up by the header names (`ITEM: ENTRIES c_pc[1]
…`, `ITEM: ATOMS id x z …`). Column meaning of compute pair/gran/local and wall/gran/local (fixed
order in LIGGGHTS 3.8.0, ENGINES.md): pairs 1-3 centre i, 4-6 centre j, 7-9 id i, id j, periodic
flag, 10-12 force on i, 13-18 normal/tangential parts, 19 area, 20 overlap, 21-23 contact point;
walls 1-3 contact point, 4-6 particle centre, 7-9 mesh index, triangle id, particle id, 10-12 force
on the particle, 19-20 area/overlap.

Frame: the decks move the surface (lower box) in −x, so the engine frame is the analysis frame
(shear_sign = +1, engine.json). Mesh index 0 in wall/gran is the rough surface ('ps'); others 'pw'.
"""

from __future__ import annotations

import io
import json
import re
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.engines.base import Results
from interphase.errors import InputError
from interphase.tables import CONTACT_COLUMNS, HISTORY_COLUMNS, PARTICLE_COLUMNS

_BLOCK = re.compile(
    rb"ITEM: TIMESTEP\s+(\d+)\s+ITEM: NUMBER OF (?:ENTRIES|ATOMS)\s+(\d+)\s+ITEM: BOX BOUNDS[^\n]*\n"
    rb"(?:[^\n]*\n){3}ITEM: (?:ENTRIES|ATOMS) ([^\n]*)\n")


def read_dump_blocks(path: str | Path) -> list[tuple[int, pd.DataFrame]]:
    """[(timestep, DataFrame with the header's column names)] for a LAMMPS/LIGGGHTS text dump."""
    raw = Path(path).read_bytes()
    out = []
    matches = list(_BLOCK.finditer(raw))
    for k, m in enumerate(matches):
        step, count, names = int(m.group(1)), int(m.group(2)), m.group(3).decode().split()
        end = matches[k + 1].start() if k + 1 < len(matches) else len(raw)
        body = raw[m.end():end]
        if count == 0:
            data = np.empty((0, len(names)))
        else:
            data = np.loadtxt(io.BytesIO(body), ndmin=2)
            if data.shape != (count, len(names)):
                raise InputError(f"block at step {step} has {data.shape} values, header says {count}×{len(names)}",
                                 where=str(path), fix="the dump is truncated or corrupt: rerun the case")
        out.append((step, pd.DataFrame(data, columns=names)))
    return out


def _shear_start(meta: dict) -> int:
    """Step at which shear starts: written by the deck to shear_start.txt once consolidation has
    reached the target platen force (read into meta by `_meta`); n_consolidate in older decks."""
    return int(meta.get("shear_start_step", meta["n_consolidate"]))


def _meta(folder: Path) -> dict:
    """engine.json plus the shear start step the engine wrote (shear_start.txt), if any."""
    meta = json.loads((folder / "engine.json").read_text())
    start = folder / "shear_start.txt"
    if start.exists():
        meta["shear_start_step"] = int(float(start.read_text().split()[0]))
    return meta


def _cols(df: pd.DataFrame, prefix: str, first: int, last: int) -> np.ndarray:
    """Columns c_ID[first..last] looked up by name."""
    return df[[f"{prefix}[{i}]" for i in range(first, last + 1)]].to_numpy()


def _contacts_from_blocks(blocks, prefix: str, wall: bool, meta: dict) -> pd.DataFrame:
    frames = []
    for step, df in blocks:
        if df.empty:
            continue
        if wall:
            p1 = _cols(df, prefix, 1, 3)            # contact point on the mesh
            p2 = _cols(df, prefix, 4, 6)            # particle centre
            mesh, pid = df[f"{prefix}[7]"].to_numpy(), df[f"{prefix}[9]"].to_numpy()
            id1, id2 = -1 - mesh, pid
            f2 = _cols(df, prefix, 10, 12)          # force on the particle = body 2
            kind = np.where(mesh == 0, "ps", "pw")
            cpt = p1
        else:
            p1, p2 = _cols(df, prefix, 1, 3), _cols(df, prefix, 4, 6)
            id1, id2 = df[f"{prefix}[7]"].to_numpy(), df[f"{prefix}[8]"].to_numpy()
            f2 = -_cols(df, prefix, 10, 12)         # the dump gives the force on i; body 2 = j
            kind = np.full(len(df), "pp")
            cpt = _cols(df, prefix, 21, 23)
        branch = p2 - p1
        nrm = np.linalg.norm(branch[:, [0, 2]], axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            nx, nz = branch[:, 0] / nrm, branch[:, 2] / nrm
        fx, fz = f2[:, 0], f2[:, 2]
        t = (step - _shear_start(meta)) * meta["dt"]
        frames.append(pd.DataFrame({
            "snapshot": step, "time": t, "shear_disp": t * meta["shear_velocity"], "kind": kind,
            "id1": id1.astype(np.int64), "id2": id2.astype(np.int64),
            "cx": cpt[:, 0], "cz": cpt[:, 2], "nx": nx, "nz": nz,
            "fn": fx * nx + fz * nz, "ft": -fx * nz + fz * nx, "fx": fx, "fz": fz,
            "x1": p1[:, 0], "z1": p1[:, 2], "x2": p2[:, 0], "z2": p2[:, 2],
            "overlap": df[f"{prefix}[20]"].to_numpy(),
        }))
    if not frames:
        return pd.DataFrame({c: pd.Series(dtype=float) for c in CONTACT_COLUMNS})
    return pd.concat(frames, ignore_index=True)


def read_contacts(folder: str | Path, meta: dict | None = None) -> pd.DataFrame:
    folder = Path(folder)
    meta = meta or _meta(folder)
    pairs = _contacts_from_blocks(read_dump_blocks(folder / "contacts_pair.dump"), "c_pc", False, meta)
    walls = _contacts_from_blocks(read_dump_blocks(folder / "contacts_wall.dump"), "c_wc", True, meta)
    out = pd.concat([pairs, walls], ignore_index=True)
    out["kind"] = pd.Categorical(out["kind"], categories=["pp", "ps", "pw"])
    snaps = np.sort(out["snapshot"].unique())
    out["snapshot"] = np.searchsorted(snaps, out["snapshot"]).astype(np.int64)   # 0, 1, 2 … in time order
    return out.sort_values(["snapshot", "kind", "id1", "id2"], kind="stable").reset_index(drop=True)[list(CONTACT_COLUMNS)]


def read_history(folder: str | Path, meta: dict | None = None) -> pd.DataFrame:
    """history.txt → History. The first row after a `run` shows mesh forces doubled (ENGINES.md):
    dropped. surface_fx/fz: force ON the surface (lower box) [N]; window_fx/fz: from the grains in
    the measuring window (Case.window); normal_force: platen force [N]."""
    folder = Path(folder)
    meta = meta or _meta(folder)
    h = pd.read_csv(folder / "history.txt", sep=r"\s+")
    h = h.iloc[1:].reset_index(drop=True)
    t = (h["step"].to_numpy() - _shear_start(meta)) * meta["dt"]
    return pd.DataFrame({
        "time": t, "shear_disp": t * meta["shear_velocity"],
        "surface_fx": h["surface_fx"], "surface_fz": h["surface_fz"],
        "normal_force": h["platen_fz"], "platen_z": h["platen_z"], "n_contacts": h["n_contacts"],
        "window_fx": h["window_fx"], "window_fz": h["window_fz"],
    })[list(HISTORY_COLUMNS)]


def read_particles(folder: str | Path, meta: dict | None = None) -> pd.DataFrame:
    folder = Path(folder)
    meta = meta or _meta(folder)
    frames = []
    blocks = read_dump_blocks(folder / "particles.dump")
    for k, (step, df) in enumerate(blocks):
        t = (step - _shear_start(meta)) * meta["dt"]
        frames.append(pd.DataFrame({"snapshot": k, "time": t, "shear_disp": t * meta["shear_velocity"],
                                    "id": df["id"].astype(np.int64), "x": df["x"], "z": df["z"],
                                    "vx": df["vx"], "vz": df["vz"], "radius": df["radius"]}))
    return pd.concat(frames, ignore_index=True)[list(PARTICLE_COLUMNS)]


def read_folder(folder: str | Path) -> Results:
    folder = Path(folder)
    meta = _meta(folder)
    return Results(read_contacts(folder, meta), read_history(folder, meta), read_particles(folder, meta))
