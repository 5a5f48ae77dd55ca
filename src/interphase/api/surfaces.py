"""Surfaces: θa of a profile file or an areal scan, the study's generated profiles, the profile's
picture (`campaign theta-a`, `campaign profile KIND`, `campaign profile plot`). Lengths in metres."""

from __future__ import annotations

import math
import os
from pathlib import Path

from interphase.api import checks
from interphase.errors import InputError

PathLike = str | os.PathLike


def theta_a(profile: PathLike, d50: float | None, *, filt: int = 92, units: str | None = None,
            cutoff: float | None = None, axis: str | None = None) -> dict:
    """θa, Rn, Rnc and the mean asperity slope of a profile file or areal scan for grains of median
    diameter `d50` [m], as `campaign theta-a --json`: the +x reading at the top level and every
    shear direction under `directions` (a line: +x, −x; a scan: +x, −x, +y, −y, each line of `axis`
    a profile). `filt`: keep trace normals > 92° or ≥ 90°; `cutoff` [m]: Gaussian filter of a line
    (default unfiltered); `units` of the file (um | mm | m). An areal result also carries
    `size_mm` (the scan's extent) and `min_run_d50` (the shortest run kept)."""
    from interphase.surface.readers import read_scan

    d50 = checks.d50(d50)
    scan = read_scan(str(profile), units)      # unknown units are refused before the file is read
    if scan.areal:
        return _theta_a_areal(profile, scan, d50, filt, cutoff, axis)
    if axis == "y":
        raise InputError("a line scan has only the x axis", where="--axis", fix="omit --axis for a line")
    from interphase.surface.normals import theta_a as _theta_a

    prof = _measured(profile, units, cutoff)
    res = _theta_a(prof, d50, filt)
    back = _theta_a(prof.mirrored(), d50, filt)      # shear in −x: the other flanks resist
    return res.to_dict() | {"profile": os.fspath(profile), "d50_mm": round(d50 * 1e3, 12), "areal": False,
                            "units": scan.units, "reader": scan.reader,
                            "directions": {"+x": res.to_dict() | {"direction": "+x"},
                                           "-x": back.to_dict() | {"direction": "-x"}}}


def _measured(path: PathLike, units, cutoff):
    """A measured line profile, centerline-corrected and, with `cutoff` [m], Gaussian-filtered."""
    from interphase.surface.readers import load_profile

    if cutoff is not None and not cutoff > 0:
        shown = f"{cutoff * 1e3:g} mm" if checks.is_number(cutoff) and math.isfinite(cutoff) else repr(cutoff)
        raise InputError(f"must be a positive length, got {shown}", where="--cutoff")
    return load_profile(str(path), units, cutoff)


def _theta_a_areal(profile, scan, d50: float, filt: int, cutoff, axis) -> dict:
    """An areal scan: every grid line along the axis is a profile; θa in the four shear directions."""
    from interphase.surface.areal import MIN_RUN_D50, theta_a_scan

    if cutoff is not None:
        raise InputError("a Gaussian cut-off is not applied to areal scans yet", where="--cutoff",
                         fix="omit --cutoff (each run is levelled by its own least-squares line)")
    axis = axis or "x"
    other = "y" if axis == "x" else "x"
    res = theta_a_scan(scan, d50, (filt,), axes=(axis,))      # the chosen axis: its errors are the user's
    missing = {}
    try:
        res |= theta_a_scan(scan, d50, (filt,), axes=(other,))
    except InputError as exc:       # the other axis may hold no run long enough: say so in its rows
        missing = {other: str(exc)}
    nx, ny = scan.shape
    directions = {d: (res[d][filt].to_dict() if d in res else {"direction": d, "error": missing[d[1]]})
                  for d in ("+x", "-x", "+y", "-y")}
    return res[f"+{axis}"][filt].to_dict() | {
        "profile": os.fspath(profile), "d50_mm": round(d50 * 1e3, 12), "areal": True, "axis": axis,
        "shape": [nx, ny], "units": scan.units, "reader": scan.reader, "missing_points": scan.n_missing,
        "directions": directions, "size_mm": [float(scan.x[-1]) * 1e3, float(scan.y[-1]) * 1e3],
        "min_run_d50": MIN_RUN_D50}


#: the generated profiles' kinds and the sizes each takes (in D50)
PROFILE_KINDS = {"sawtooth": ("rt", "sw"), "spaced": ("rt", "sw", "sr"), "random": ("au", "ar", "rtmax", "seed")}


def make_profile(kind: str, output: PathLike, *, d50: float = 0.7e-3, length: float = 30e-3, **sizes) -> dict:
    """Write one of the study's generated profiles to `output` (a new file: two columns x z in mm),
    as `campaign profile KIND`: `kind` sawtooth (Groups 1 and 3: rt, sw), spaced (Group 2: rt, sw,
    sr) or random (Group 4: au, ar, rtmax and an integer seed); sizes in D50, `d50` and `length` [m].
    Returns the file, its vertex count and its length [m]."""
    import numpy as np

    from interphase.surface.profiles import random_profile, sawtooth

    if kind not in PROFILE_KINDS:
        raise InputError(f"unknown kind {kind!r}", where="campaign profile", fix=f"one of {', '.join(PROFILE_KINDS)}")
    if set(sizes) != set(PROFILE_KINDS[kind]):
        raise InputError(f"{kind} takes {', '.join(PROFILE_KINDS[kind])}, got {', '.join(sorted(sizes)) or 'none'}",
                         where=f"campaign profile {kind}", fix=f"give --{' --'.join(PROFILE_KINDS[kind])}")
    d50 = checks.d50(d50)
    if not (checks.is_number(length) and length > 0):
        shown = f"{length * 1e3:g} mm" if checks.is_number(length) else repr(length)
        raise InputError(f"must be > 0, got {shown}", where="--length")
    output = checks.new_file(output)
    if kind == "random":
        prof = random_profile(sizes["au"], sizes["ar"], sizes["rtmax"], d50=d50, length=length, seed=sizes["seed"])
    else:
        prof = sawtooth(sizes["rt"], sizes["sw"], sizes.get("sr", 0.0), d50=d50, length=length)
    np.savetxt(output, np.column_stack([prof.x, prof.z]) * 1e3, fmt="%.9g",
               header=f"x_mm z_mm  {prof.name} D50={d50 * 1e3:g}mm", comments="# ")
    return {"output": output, "vertices": int(prof.x.size), "length": float(prof.length)}


def plot_profile(profile: PathLike, output: PathLike | None = None, *, d50: float = 0.7e-3,
                 units: str | None = None, filt: int = 92) -> Path:
    """The profile, its centroid trace and the polar distribution of trace normals as a PNG, as
    `campaign profile plot`: `output` a new file (default PROFILE.png beside it); `d50` [m]. Returns
    the file written."""
    from interphase.surface.plot import plot_profile as _plot

    out = checks.new_file(output if output is not None else os.fspath(profile).rsplit(".", 1)[0] + ".png")
    _plot(_measured(profile, units, None), checks.d50(d50), out, filt)
    return out
