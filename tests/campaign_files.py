"""Campaign and case files for the tests, written from Python values: the tiny real case several
test files run, and one TOML writer, so that a test states only what its own campaign changes.

    toml_text(campaign={"name": "c"}, case={**TINY_CASE, "seed": 2}, sweep={"profile.rt": [0.5, 1]})

Each keyword is a table, in the order given: a dict is written `[name]` (its dict values inline,
e.g. a profile); a list of dicts is an array of tables `[[name]]` whose dict values are its
sub-tables (`[group.case]`, `[group.sweep]`). Keys are written as given, so dotted keys
("profile.rt") stay dotted. The layout is fixed, line numbers included (tests that check the line
a message names rely on it): a table's header, one `key = value` line per key, one blank line
between tables, no blank line at the end.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

#: the test surface: a sawtooth of height Rt 1 D50 and width Sw 2 D50, no gap (Sr 0)
SAWTOOTH = {"kind": "sawtooth", "rt": 1, "sw": 2, "sr": 0}

#: the tiny real case (a few seconds of LIGGGHTS on a loaded core): a sawtooth Rt = Sw/2 = 1 D50 under
#: a 12 × 6 D50 box, grains of shear modulus 50 MPa, sheared 0.5 mm with a snapshot every 0.25 mm
#: (lengths in m, moduli in Pa); walled unless a test adds device = "periodic"
TINY_CASE = {
    "profile": SAWTOOTH,
    "shear_modulus": 50e6,
    "shear_distance": 0.0005,
    "snapshot_every": 0.00025,
    "box_length_d50": 12.0,
    "box_height_d50": 6.0,
}


def toml_value(v) -> str:
    """One TOML value: strings quoted, floats as Python writes them (TOML reads them back exactly),
    lists and dicts inline."""
    if isinstance(v, bool):                 # before int: a bool is an int to Python
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"no TOML for {v!r} in a test's campaign")
        return repr(v)
    if isinstance(v, (str, Path)):
        return json.dumps(str(v), ensure_ascii=False)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"no TOML for {type(v).__name__} in a test's campaign")


def _table(header: str, table: dict, sub_tables: bool = False) -> list[str]:
    """The lines of one table; with `sub_tables`, its dict values follow as [header.key] tables."""
    lines = [header]
    subs = []
    for key, value in table.items():
        if sub_tables and isinstance(value, dict):
            subs.append((key, value))
        else:
            lines.append(f"{key} = {toml_value(value)}")
    name = header.strip("[]")
    for key, value in subs:
        lines += _table(f"[{name}.{key}]", value)
    return lines


def toml_text(**tables) -> str:
    """The TOML text of `tables` (see the module's docstring for the layout)."""
    blocks = []
    for name, table in tables.items():
        if isinstance(table, dict):
            blocks.append(_table(f"[{name}]", table))
        else:
            blocks += [_table(f"[[{name}]]", entry, sub_tables=True) for entry in table]
    return "\n\n".join("\n".join(block) for block in blocks) + "\n"


def write_toml(path: Path, **tables) -> Path:
    """Write toml_text(**tables) to `path`; returns it."""
    path = Path(path)
    path.write_text(toml_text(**tables))
    return path
