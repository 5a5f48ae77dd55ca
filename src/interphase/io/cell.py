"""A cell run's output (triaxial / biaxial, engines/cell.py) → its history table.

history.txt (LIGGGHTS `fix print`, a title line then one row per history step from the start of the
axial compression): step, cell lengths lx ly lz [m], contact stresses sxx syy szz [Pa] (quasi-2D:
per the thickness t), kinetic energy [J], contacts. cell.json: the solid volume [m³] (2D: section
area × t), the thickness, the grain count.

The table (compression positive, engineering strains from the first row, the start of the shear):
  time [s], eps1 = (lz0 − lz)/lz0, epsv = (V0 − V)/V0 (2D: V = lx·lz·t, an area strain),
  e = V/V_solid − 1 (2D: the area void ratio of the disc sections), sigma1 = szz,
  sigma3 = mean lateral stress (3D: (sxx + syy)/2; 2D: sxx), ratio = sigma1/sigma3,
  p = mean stress (3D: (σ1 + 2σ3)/3; 2D: (σ1 + σ3)/2), q = σ1 − σ3, sxx, syy, szz, ke, n_contacts.
"""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from interphase.errors import InputError
from interphase.recipe import read_record
from interphase.tables import Results

CELL_HISTORY_COLUMNS = ("time", "eps1", "epsv", "e", "sigma1", "sigma3", "ratio", "p", "q", "sxx", "syy", "szz",
                        "ke", "n_contacts")


def read_cell_history(folder: str | Path) -> pd.DataFrame:
    folder = Path(folder)
    meta = json.loads((folder / "cell.json").read_text())
    rec = read_record(folder)
    path = folder / "history.txt"
    raw = pd.read_csv(path, sep=r"\s+", comment=None, skiprows=1, header=None,
                      names=["step", "lx", "ly", "lz", "sxx", "syy", "szz", "ke", "n_contacts"])
    if raw.empty:
        raise InputError("no history rows (the run stopped before its axial compression)", where=str(path),
                         fix="see engine.log for why")
    three_d = bool(meta["three_d"])
    vol = raw["lx"] * raw["lz"] * (raw["ly"] if three_d else meta["thickness"])
    lat = (raw["sxx"] + raw["syy"]) / 2 if three_d else raw["sxx"]
    s1 = raw["szz"]
    out = pd.DataFrame({
        "time": (raw["step"] - raw["step"].iloc[0]) * rec.dt,
        "eps1": (raw["lz"].iloc[0] - raw["lz"]) / raw["lz"].iloc[0],
        "epsv": (vol.iloc[0] - vol) / vol.iloc[0],
        "e": vol / meta["solid"] - 1.0,
        "sigma1": s1, "sigma3": lat, "ratio": s1 / lat,
        "p": (s1 + 2 * lat) / 3 if three_d else (s1 + lat) / 2, "q": s1 - lat,
        "sxx": raw["sxx"], "syy": raw["syy"], "szz": raw["szz"], "ke": raw["ke"], "n_contacts": raw["n_contacts"],
    })
    return out.astype(float)


def read_cell_folder(folder: str | Path) -> Results:
    """Results of a cell run: no contact table (an empty one), the cell history."""
    return Results(contacts=pd.DataFrame(), history=read_cell_history(folder), particles=None)
