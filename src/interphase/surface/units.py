"""Length units of surface files: one table, one check.

`UNITS` are the names a user may give (--units, `units = "..."` in a campaign); `UNIT_FACTORS` adds
the other names instrument files declare (read through SurfaceTopography). Metres per unit.
"""

from __future__ import annotations

from interphase.errors import InputError

#: the units a user may choose → metres per unit
UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6}
#: every unit name a file may declare (the user's names and SurfaceTopography's) → metres per unit
UNIT_FACTORS = {**UNITS, "µm": 1e-6, "μm": 1e-6, "nm": 1e-9, "Å": 1e-10, "pm": 1e-12}
UNITS_FIX = "give the units of the file's x and z (--units um | mm | m, or units = \"...\" in the campaign)"


def units_factor(units: str, where: str = "--units") -> float:
    """Metres per unit for a user's choice 'm' | 'mm' | 'um'; anything else is an InputError."""
    if units not in UNITS:
        raise InputError(f"unknown units {units!r}", where=where, fix=f"use one of {', '.join(UNITS)}")
    return UNITS[units]
