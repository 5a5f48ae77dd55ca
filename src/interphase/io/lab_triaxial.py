"""Laboratory element-test records (drained triaxial compression) read into one table.

Two layouts, both found by header name, never by column position:

- **whitespace columns with a units line** (Karlsruhe fine sand, `lab/soils/karlsruhe-fine-sand/`):
  a line of names (separated by two or more spaces or tabs: a name may hold one space, "Void
  ratio"), a line of units in brackets, then numbers. Stresses `q`, `p` are effective (drained).
  The void-ratio column's unit line says "[%]" but its values are e itself: it is read as e [-].
- **CSV with `#` comment lines** (Ottawa F-65, `lab/soils/ottawa-f65/`): the unit after the last
  underscore of a name (`vertical_strain_pct`, `pore_pressure_kPa`). Stresses are TOTAL: σ′ =
  total − pore pressure. e is e0 − (1 + e0)·εv with e0 from a comment `e_0 = X` (or `e0=`).

The table (`TriaxialRecord.table`) holds, per data row: `line` (the file's line number), `eps1`
[-], `epsv` [-] (compression positive: dilation is negative), `e` [-], `ratio` = σ1′/σ3′ [-],
`p` = (σ1′ + 2σ3′)/3 [Pa], `q` = σ1′ − σ3′ [Pa]. A record that cannot be read raises InputError
naming the file, the line and the column.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.errors import InputError

#: quantity → header names it is found under (compared lower-case, unit suffix removed)
NAMES = {
    "eps1": ("eps1", "vertical_strain", "axial_strain", "eps_a"),
    "epsv": ("epsv", "volumetric_strain", "eps_v"),
    "e": ("void ratio", "void_ratio", "e"),
    "q": ("q", "deviator_stress"),
    "p": ("p", "mean_effective_stress"),
    "sigma1": ("vertical_stress", "axial_stress"),
    "sigma3": ("horizontal_stress", "radial_stress", "cell_pressure"),
    "u": ("pore_pressure",),
}
#: unit → factor to SI (strains to [-], stresses to Pa)
UNITS = {"%": 1e-2, "pct": 1e-2, "-": 1.0, "": 1.0, "kpa": 1e3, "pa": 1.0, "mpa": 1e6}
#: what each layout needs: effective q, p (drained records) or total stresses with pore pressure
EFFECTIVE = ("eps1", "epsv", "q", "p")
TOTAL = ("eps1", "epsv", "sigma1", "sigma3", "u")
MIN_ROWS = 5
MIN_SPAN = 0.01          # ε1 must span at least one dilatancy window (1 %)
COLUMNS = ("line", "eps1", "epsv", "e", "ratio", "p", "q")
_FIX = "see lab/soils/README.md for the record layouts"


@dataclass(frozen=True)
class TriaxialRecord:
    path: Path
    table: pd.DataFrame        # COLUMNS; SI strains [-] and stresses [Pa]
    layout: str                # "effective q, p" | "total stresses − pore pressure"
    e0: float                  # void ratio at the first row (NaN when the record gives none)
    sigma3_start: float        # σ3′ at the first row [Pa]


@dataclass(frozen=True)
class _Raw:
    """A record split into cells: names with units, cells as text, the file line of each row."""
    path: Path
    names: list[str]           # the quantity's name, unit suffix removed
    headers: list[str]         # each column's name as the file writes it (named in messages)
    units: list[str]
    cells: pd.DataFrame        # str, one column per name
    lines: np.ndarray          # 1-based file line of each row
    header_line: int
    comments: str


def _lines(p: Path) -> pd.Series:
    try:
        text = p.read_text(encoding="utf-8", errors="strict")
    except FileNotFoundError:
        raise InputError("file not found", where=str(p), fix=_FIX) from None
    except (UnicodeDecodeError, IsADirectoryError) as exc:
        raise InputError(f"not a text record ({exc.__class__.__name__})", where=str(p), fix=_FIX) from None
    s = pd.Series(text.splitlines(), dtype=object).str.strip()
    s.index = np.arange(1, len(s) + 1)              # 1-based line numbers
    return s


def _split(p: Path) -> _Raw:
    """Names, units and cells of either layout; rows are the non-blank lines after the header."""
    s = _lines(p)
    body = s[(s != "") & ~s.str.startswith("#")]
    if body.empty:
        raise InputError("no header line", where=str(p), fix=_FIX)
    comments = "\n".join(s[s.str.startswith("#")])
    head_no = int(body.index[0])
    head = body.iloc[0]
    if "," in head:
        raw = [n.strip() for n in head.split(",")]
        names, units = zip(*(_name_unit(n) for n in raw))
        headers = raw
        data, sep = body.iloc[1:], ","
    else:
        names = headers = [n.strip() for n in re.split(r"\s{2,}|\t", head) if n.strip()]
        if len(body) < 2:
            raise InputError("no units line under the names", where=f"{p}:{head_no}", fix=_FIX)
        units = [u.strip("[] ").lower() for u in body.iloc[1].split()]
        if len(units) != len(names):
            raise InputError(f"{len(names)} names but {len(units)} units", where=f"{p}:{int(body.index[1])}",
                             fix="one [unit] per column name")
        data, sep = body.iloc[2:], r"\s+"
    cells = data.str.split(sep, regex=sep != ",", expand=True) if len(data) else pd.DataFrame()
    if cells.shape[1] > len(names):
        extra = cells.iloc[:, len(names):].notna().any(axis=1).to_numpy()
        i = int(np.flatnonzero(extra)[0])
        raise InputError(f"more cells than the {len(names)} named columns", where=f"{p}:{int(data.index[i])}",
                         fix="one cell per named column")
    cells = cells.reindex(columns=range(len(names)))
    cells.columns = list(names)
    return _Raw(p, list(names), list(headers), [str(u).lower() for u in units], cells, data.index.to_numpy(int),
                head_no, comments)


def _name_unit(name: str) -> tuple[str, str]:
    """'vertical_strain_pct' → ('vertical_strain', 'pct'); a name without a known unit keeps it ''."""
    m = re.fullmatch(r"(.+)_([A-Za-z%]+)", name)
    if m and m.group(2).lower() in UNITS:
        return m.group(1), m.group(2).lower()
    return name, ""


def _find(raw: _Raw) -> dict[str, int]:
    """quantity → column index, by header name."""
    found: dict[str, int] = {}
    low = [n.lower() for n in raw.names]
    for quantity, aliases in NAMES.items():
        hits = [i for i, n in enumerate(low) if n in aliases]
        if hits:
            found[quantity] = hits[0]
    return found


def _numbers(raw: _Raw, col: int, quantity: str) -> np.ndarray:
    """One column as SI floats; a missing or non-numeric cell names its line and column."""
    name, unit = raw.headers[col], raw.units[col]
    if quantity == "e":
        unit = "-"                      # the Karlsruhe header's "[%]" on e is wrong: the values are e
    if unit not in UNITS:
        raise InputError(f"column {name!r}: unit {unit!r} cannot be read",
                         where=f"{raw.path}:{raw.header_line}: {name}", fix=f"use one of {', '.join(UNITS)}")
    text = raw.cells.iloc[:, col]
    num = pd.to_numeric(text, errors="coerce")
    bad = num.isna() | ~np.isfinite(num.to_numpy(float))
    if bad.any():
        i = int(np.flatnonzero(bad.to_numpy())[0])
        cell = text.iloc[i]
        what = "missing cell" if cell is None or cell == "" else f"{cell!r} is not a number"
        raise InputError(what, where=f"{raw.path}:{int(raw.lines[i])}: {name}", fix="numbers only, one per column")
    return num.to_numpy(float) * UNITS[unit]


def _e0_from_comments(comments: str) -> float:
    m = re.search(r"\be_?0\s*=\s*([0-9.]+)", comments)
    return float(m.group(1)) if m else float("nan")


def _stresses(raw: _Raw, cols: dict[str, int]) -> tuple[np.ndarray, np.ndarray, str]:
    """(σ1′, σ3′) [Pa] and the layout: total − pore pressure when a pore-pressure column is
    there, else effective q and p."""
    need = TOTAL if "u" in cols else EFFECTIVE
    missing = [q for q in need if q not in cols]
    if missing:
        wanted = "; ".join(f"{q}: {' or '.join(NAMES[q])}" for q in missing)
        raise InputError(f"missing column(s) {wanted}", where=f"{raw.path}:{raw.header_line}: {', '.join(missing)}",
                         fix=_FIX)
    if "u" in cols:
        u = _numbers(raw, cols["u"], "u")
        s1, s3 = _numbers(raw, cols["sigma1"], "sigma1") - u, _numbers(raw, cols["sigma3"], "sigma3") - u
        return s1, s3, "total stresses − pore pressure"
    q, p = _numbers(raw, cols["q"], "q"), _numbers(raw, cols["p"], "p")
    return p + 2 * q / 3, p - q / 3, "effective q, p"


def _check(raw: _Raw, cols: dict[str, int], eps1: np.ndarray, s3: np.ndarray) -> None:
    name = raw.headers[cols["eps1"]]
    if len(eps1) < MIN_ROWS:
        last = int(raw.lines[-1]) if len(raw.lines) else raw.header_line
        raise InputError(f"only {len(eps1)} data rows (need ≥ {MIN_ROWS})", where=f"{raw.path}:{last}: {name}",
                         fix="a record of the whole test")
    if eps1.max() - eps1.min() < MIN_SPAN:
        raise InputError(f"axial strain spans {100 * (eps1.max() - eps1.min()):.3g} %, less than the 1 % "
                         "dilatancy window", where=f"{raw.path}:{int(raw.lines[-1])}: {name}",
                         fix="a record of the whole test")
    low = np.flatnonzero(~(s3 > 0))
    if low.size:
        raise InputError("σ3′ ≤ 0 (no effective confinement)", where=f"{raw.path}:{int(raw.lines[low[0]])}",
                         fix="check the stress and pore-pressure columns")


def read_triaxial(path: str | Path, e0: float | None = None) -> TriaxialRecord:
    """Read one drained triaxial record (either layout above); `e0` overrides the record's own
    initial void ratio when the record has no e column."""
    raw = _split(Path(path))
    cols = _find(raw)
    s1, s3, layout = _stresses(raw, cols)
    eps1 = _numbers(raw, cols["eps1"], "eps1")
    epsv = _numbers(raw, cols["epsv"], "epsv")
    _check(raw, cols, eps1, s3)
    if "e" in cols:
        e = _numbers(raw, cols["e"], "e")
    else:
        start = _e0_from_comments(raw.comments) if e0 is None else float(e0)
        e = start - (1 + start) * epsv                  # εv = −Δe/(1 + e0), compression positive
    table = pd.DataFrame({"line": raw.lines, "eps1": eps1, "epsv": epsv, "e": e, "ratio": s1 / s3,
                          "p": (s1 + 2 * s3) / 3, "q": s1 - s3}, columns=list(COLUMNS))
    return TriaxialRecord(raw.path, table, layout, float(e[0]), float(s3[0]))
