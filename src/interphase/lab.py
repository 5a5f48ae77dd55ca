"""Laboratory interface-shear results (`lab/*.csv`): one row per published test, read by header name.

Each column's unit is the suffix after its last underscore; a reader converts to SI (m, Pa) and
degrees. A row holds what its source published, never an estimate; a value read off a figure gives
its reading error.

Required columns:
  soil                 the granular material (free text, e.g. "Ottawa 20/30 sand")
  d50_<mm|um|m>        its median grain diameter
  surface              the rebuilt surface: flat | sawtooth (symmetric triangles) | ramp (a
                       slope of horizontal length `asperity_width`, then a vertical face: the
                       "snake-skin" asperity; `direction` + climbs the slope, − meets the face)
  normal_stress_<kpa|pa|mpa>
  delta_peak_<deg|rad>  measured peak interface friction angle (or tan_delta_peak, [-])
  source               the citation (authors, year, title, journal or thesis)
  table_or_figure      where in the source the row's numbers are printed
Surface geometry (sawtooth, ramp): asperity_height_<mm|um|m> and asperity_width_<mm|um|m> (the
base of one tooth), or one of them with asperity_angle_<deg|rad> (the slope from horizontal);
root_spacing_<mm|um|m>: flat between teeth (default 0); direction: + | − (ramp only, default +).
Optional: delta_cs_<deg|rad>, reading_error_<deg|rad> (digitised), friction (particle–surface
tan φμ [-]) with friction_source, soil_phi_peak_<deg|rad> (the soil's own peak angle in that
laboratory), density (free text), note.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.errors import InputError

UNITS = {
    "length": {"mm": 1e-3, "um": 1e-6, "m": 1.0},
    "stress": {"kpa": 1e3, "pa": 1.0, "mpa": 1e6},
    "angle": {"deg": 1.0, "rad": 180.0 / math.pi},
}
#: field → (dimension, SI/deg name it is stored under)
FIELDS = {
    "d50": "length", "normal_stress": "stress", "delta_peak": "angle", "delta_cs": "angle",
    "reading_error": "angle", "asperity_height": "length", "asperity_width": "length",
    "asperity_angle": "angle", "root_spacing": "length", "soil_phi_peak": "angle",
}
PLAIN = ("soil", "surface", "source", "table_or_figure", "friction", "friction_source", "density", "note",
         "direction", "tan_delta_peak", "surface_name")
REQUIRED = ("soil", "d50", "surface", "normal_stress", "source", "table_or_figure")
SURFACES = ("flat", "sawtooth", "ramp")
_FIX = "see lab/README.md for the columns and units"


@dataclass(frozen=True)
class LabTable:
    path: Path
    rows: pd.DataFrame      # SI lengths [m] and stresses [Pa], angles [°]; `row` = the CSV line


def _columns(df: pd.DataFrame, p: Path) -> dict[str, str]:
    """field name → CSV column, units checked (an unknown unit names the column and the units known)."""
    out: dict[str, str] = {}
    for col in df.columns:
        name = str(col).strip()
        if name in PLAIN:
            out[name] = col
            continue
        m = re.fullmatch(r"(.+)_([a-z]+)", name)
        field, unit = (m.group(1), m.group(2)) if m else (name, "")
        if field not in FIELDS:
            continue                  # a column the tool does not use is kept in the file, not read
        known = UNITS[FIELDS[field]]
        if unit not in known:
            raise InputError(f"column {name!r}: unit {unit or '(none)'!r} cannot be read for {field}",
                             where=f"{p}: {name}", fix=f"name it {field}_<unit> with unit one of {', '.join(known)}")
        if field in out:
            raise InputError(f"{field} is given twice ({out[field]!r} and {name!r})", where=f"{p}: {name}",
                             fix="keep one column per quantity")
        out[field] = col
    return out


def read_lab(path: str | Path) -> LabTable:
    """Read and check a laboratory CSV; every message names the file, the CSV line and the field."""
    p = Path(path)
    try:
        df = pd.read_csv(p, dtype=str, keep_default_na=False, comment=None)
    except FileNotFoundError:
        raise InputError("file not found", where=str(p), fix=_FIX) from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise InputError(f"not a readable CSV ({exc})", where=str(p), fix=_FIX) from None
    cols = _columns(df, p)
    for need in REQUIRED:
        if need not in cols:
            unit = f"_<{'|'.join(UNITS[FIELDS[need]])}>" if need in FIELDS else ""
            raise InputError(f"missing column {need}{unit}", where=str(p), fix=_FIX)
    if "delta_peak" not in cols and "tan_delta_peak" not in cols:
        raise InputError("missing column delta_peak_<deg|rad> (or tan_delta_peak)", where=str(p), fix=_FIX)

    out = pd.DataFrame({"row": np.arange(len(df)) + 2})        # CSV line: header is line 1
    text = {k: df[c].astype(str).str.strip() for k, c in cols.items()}
    for k in ("soil", "surface", "source", "table_or_figure", "friction_source", "density", "note", "direction",
              "surface_name"):
        out[k] = text[k].to_numpy() if k in text else ""

    def bad(i: int, field: str, msg: str, fix: str | None = None) -> InputError:
        return InputError(msg, where=f"{p}:{int(out['row'].iloc[i])}: {cols.get(field, field)}", fix=fix or _FIX)

    for k in (*FIELDS, "friction", "tan_delta_peak"):
        if k not in text:
            out[k] = np.nan
            continue
        num = pd.to_numeric(text[k], errors="coerce")
        wrong = num.isna() & (text[k] != "")
        if wrong.any():
            i = int(np.flatnonzero(wrong.to_numpy())[0])
            raise bad(i, k, f"{text[k].iloc[i]!r} is not a number",
                      "numbers only; the unit belongs in the column name")
        scale = UNITS[FIELDS[k]][str(cols[k]).strip().rsplit("_", 1)[1]] if k in FIELDS else 1.0
        out[k] = num.to_numpy(float) * scale

    for i in range(len(out)):
        r = out.iloc[i]
        for k in ("soil", "source", "table_or_figure"):
            if not r[k]:
                raise bad(i, k, f"empty {k}", "every row names its material and the table or figure it was "
                                              "read from; never a number without its source")
        for k in ("d50", "normal_stress"):
            if not (r[k] > 0):
                raise bad(i, k, f"{k} must be > 0")
        if not (math.isfinite(r["delta_peak"]) or math.isfinite(r["tan_delta_peak"])):
            raise bad(i, "delta_peak", "no measured peak (delta_peak or tan_delta_peak)")
        if math.isfinite(r["delta_peak"]) and not 0 < r["delta_peak"] < 90:
            raise bad(i, "delta_peak", f"{r['delta_peak']:g}° is not an angle of friction (0–90°)")
        if math.isfinite(r["friction"]) and not r["friction"] >= 0:
            raise bad(i, "friction", "particle–surface friction tan φμ must be ≥ 0")
        tooth_geometry(r, lambda field, msg, fix=None, i=i: bad(i, field, msg, fix))
    delta = np.where(np.isfinite(out["delta_peak"]), out["delta_peak"],
                     np.degrees(np.arctan(out["tan_delta_peak"].to_numpy(float))))
    out["delta_peak"] = delta
    return LabTable(p, out)


def tooth_geometry(r, bad) -> tuple[float, float, float]:
    """(height, width, root spacing) [m] of a row's teeth; flat → zeros. Checks the surface fields."""
    kind = r["surface"].lower()
    if kind not in SURFACES:
        raise bad("surface", f"cannot rebuild a {r['surface']!r} surface", f"use one of {', '.join(SURFACES)}, "
                  "or compute θa from a measured profile with `campaign theta-a`")
    if kind == "flat":
        return 0.0, 0.0, 0.0
    h, w, a = r["asperity_height"], r["asperity_width"], r["asperity_angle"]
    run = w if kind == "ramp" else w / 2       # horizontal length of one rising face
    if math.isfinite(a):
        if not 0 < a < 90:
            raise bad("asperity_angle", f"{a:g}° is not a slope (0–90° from horizontal)")
        if math.isfinite(h) and math.isfinite(w):
            if abs(math.degrees(math.atan2(h, run)) - a) > 1.0:
                raise bad("asperity_angle", f"{a:g}° disagrees with height {h * 1e3:g} mm and width {w * 1e3:g} mm "
                          f"({math.degrees(math.atan2(h, run)):.1f}°)", "give two of the three, or three that agree")
        elif math.isfinite(h):
            run = h / math.tan(math.radians(a))
            w = run if kind == "ramp" else 2 * run
        elif math.isfinite(w):
            h = run * math.tan(math.radians(a))
    if not (math.isfinite(h) and h > 0):
        raise bad("asperity_height", f"a {kind} surface needs asperity_height > 0 (or asperity_width and asperity_angle)")
    if not (math.isfinite(w) and w > 0):
        raise bad("asperity_width", f"a {kind} surface needs asperity_width > 0 (or asperity_height and asperity_angle)")
    sr = r["root_spacing"] if math.isfinite(r["root_spacing"]) else 0.0
    if sr < 0:
        raise bad("root_spacing", "root spacing must be ≥ 0")
    if kind == "ramp" and r["direction"] not in ("", "+", "-", "−"):
        raise bad("direction", f"{r['direction']!r}: use + (up the slope) or - (against the vertical face)")
    return h, w, sr


def profile_of(row, d50: float | None = None):
    """The rebuilt surface of a lab row (interphase.surface.profiles.Profile, metres), periodic.
    Geometry in the row's own millimetres; `d50` [m] only sets how many periods are drawn."""
    from interphase.surface.profiles import Profile, flat, sawtooth

    def never(field, msg, fix=None):
        raise InputError(msg, where=field, fix=fix)

    h, w, sr = tooth_geometry(row, never)
    kind = row["surface"].lower()
    d = float(row["d50"]) if d50 is None else d50
    if kind == "flat":
        return flat(40 * d, name="flat")
    if kind == "sawtooth":
        return sawtooth(h / d, w / d, sr / d, d50=d, periods=max(1, math.ceil(40 * d / (w + sr))),
                        name=f"sawtooth h{h * 1e3:g} w{w * 1e3:g} s{sr * 1e3:g} mm")
    lam = w + sr
    n = max(1, math.ceil(40 * d / lam))
    eps = 1e-6 * w            # the vertical face as a face of slope 1e6 (a profile is a function)
    one_x = [0.0, w - eps, w] + ([w + sr] if sr > 0 else [])
    one_z = [0.0, h, 0.0] + ([0.0] if sr > 0 else [])
    k = np.arange(n)[:, None] * lam
    x = np.concatenate([(np.array(one_x[:-1]) + k).ravel(), [n * lam]])
    z = np.concatenate([np.tile(one_z[:-1], n), [0.0]])
    prof = Profile(x, z, periodic=True, name=f"ramp h{h * 1e3:g} w{w * 1e3:g} s{sr * 1e3:g} mm")
    return prof.mirrored() if row["direction"] in ("-", "−") else prof
