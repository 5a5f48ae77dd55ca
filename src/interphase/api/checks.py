"""The input checks of the API functions, made before any work: the command calls the same
functions, so a script and `campaign` refuse the same input with the same message. Each check raises
InputError naming the value as the command's option spells it (`--d50`, `--seeds`, `-o FILE`): the
name a reader of either finds in docs/cli.md. Values are SI (metres, pascals, m/s)."""

from __future__ import annotations

import math
import os
from pathlib import Path

from interphase.errors import InputError


def is_number(value) -> bool:
    """A real number (a bool is not one)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def positive(value, where: str, unit: str, example: str) -> float:
    """`value` [unit] as a float when finite and > 0, else InputError (`example`: a value to give)."""
    if not (is_number(value) and math.isfinite(value) and value > 0):
        raise InputError(f"must be > 0 {unit}, got {value!r}", where=where, fix=f"e.g. {where} {example}")
    return float(value)


def positive_all(values, where: str, unit: str, example: str, missing: str, fix: str) -> list[float]:
    """Each of `values` (one number or several) checked by `positive`; none is refused as `missing`
    with `fix`."""
    values = list(values) if isinstance(values, (list, tuple)) else [] if values is None else [values]
    if not values:
        raise InputError(missing, where=where, fix=fix)
    return [positive(v, where, unit, example) for v in values]


def seeds(n, fewest: int = 1, where: str = "--seeds") -> int:
    """The number of packing seeds 1…n: an integer ≥ `fewest`."""
    fix = f"give the number of packing seeds, e.g. {max(3, fewest)}"
    if not (isinstance(n, int) and not isinstance(n, bool)):
        raise InputError(f"must be an integer ≥ {fewest}, got {n!r}", where=where, fix=fix)
    if n < fewest:
        why = "" if fewest == 1 else " (the fewest seeds a peak's interval is given for)"
        raise InputError(f"must be ≥ {fewest}{why}, got {n}", where=where, fix=fix)
    return n


def at_least_zero(n, where: str) -> int:
    if not (isinstance(n, int) and not isinstance(n, bool) and n >= 0):
        raise InputError(f"must be ≥ 0, got {n!r}", where=where)
    return n


#: what a missing grain size is needed for, where nothing else says it
D50_FIX = "give --d50 MM, the grains' median diameter: θa is read with a disc of that size"


def d50(value, where: str = "--d50", fix: str = D50_FIX) -> float:
    """A median grain diameter [m], finite and > 0 (said in mm: the command's unit)."""
    if value is None:
        raise InputError("no grain size given", where=where, fix=fix)
    if not (is_number(value) and math.isfinite(value) and value > 0):
        shown = f"{value * 1e3:g} mm" if is_number(value) and math.isfinite(value) else repr(value)
        raise InputError(f"must be a positive diameter, got {shown}", where=where)
    return float(value)


def new_file(path) -> Path:
    """An output file that is refused, before any work is done, when it exists (nothing a user owns
    is overwritten: a new name is suggested) or when its folder does not."""
    from interphase.campaign.folders import next_free

    given = os.fspath(path)
    parent = Path(path).resolve().parent
    if not parent.is_dir():
        raise InputError(f"folder {str(parent)!r} does not exist", where=f"-o {given}",
                         fix="create the folder first or write somewhere else")
    if Path(path).exists():
        raise InputError(f"{given} exists; it is kept as it is", where=f"-o {given}",
                         fix=f"write to a new name, e.g. -o {next_free(path)}")
    return Path(path)
