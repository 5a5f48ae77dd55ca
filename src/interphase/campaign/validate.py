"""`campaign validate --simulate`: every laboratory row as an interface case of the calibrated soil,
through the campaign machinery (a generated campaign file, resumable, local or SLURM).

One group per row: the rebuilt surface (its geometry in D50 units of the laboratory's soil, so the
card's grains meet teeth of the same relative size), the row's normal stress and particle–surface
friction, packing seeds 1…N, and the paired soil test of the card's grains at that stress. The
interface cell (`interface_case`) is the one the card's criterion stands on: the [case] of the
campaign its `[criterion] campaign` names; without one, the campaigns' protocol in the card's D50
units (PROTOCOL: the 40 × 25 D50 periodic cell at 0.02 m/s over 6 mm of 0.7 mm grains, i.e. 8.6 D50;
docs/convergence.md), in the quasi-2D device for a quasi-2D card and in the chosen 3D cell
(PROTOCOL_3D, 30 × 15 × 10 D50; docs/3d.md) for a 3D one. Never the element test's cell.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.campaign.element import write_campaign
from interphase.errors import InputError

PROTOCOL = {"test": "interface", "device": "periodic", "shear_velocity": 0.02, "shear_distance": 0.006,
            "snapshot_every": 0.0005, "box_length_d50": 40.0, "box_height_d50": 25.0, "friction_pw": 0.9}
PROTOCOL_D50 = 0.0007      # [m] the grains PROTOCOL's lengths (6 mm of shear, snapshots every 0.5 mm) are for


#: a 3D card's interface cell without a campaign of its own: the cell study's choice (docs/3d.md:
#: 30 × 15 × 10 D50, periodic in x and y), the rest of PROTOCOL as it is
PROTOCOL_3D = PROTOCOL | {"device": "periodic3d", "box_length_d50": 30.0, "box_height_d50": 15.0, "box_depth_d50": 10.0}
#: what a row or a profile sets, never taken from a campaign's [case]
CASE_OWN = ("profile", "friction_ps", "normal_stress", "seed")


def protocol_for(d50: float, protocol: dict = PROTOCOL) -> dict:
    """PROTOCOL for grains of median diameter `d50` [m]: the shear and the snapshot spacing in the same
    D50 units (8.6 D50 and 0.71 D50), the speed as it is (the inertial number depends on the speed and
    the cell's height in D50, not on D50). A 0.14 mm sand sheared 6 mm would go 43 D50, five times
    the study's shear and its cost."""
    k = float(d50) / PROTOCOL_D50
    # rounded so that the study's own grains keep the study's numbers and a case id does not carry float noise
    return protocol | {"shear_distance": round(protocol["shear_distance"] * k, 12),
                       "snapshot_every": round(protocol["snapshot_every"] * k, 12)}


def interface_case(card, protocol: dict | None = None) -> tuple[dict, str]:
    """The [case] fields a card's interface cases run with, the surface, stress, friction and seed
    aside (CASE_OWN), and where they come from (a sentence).

    - `protocol` given: the card's grains (`soil`) in it;
    - the card's `[criterion] campaign` (relative to the card): that campaign's [case], the cell,
      device, stiffness and shear its fitted criterion stands on, so that the DEM answers the same
      experiment as the fit (a stiffness set there, as the 3D Group 1's 50 MPa, stays). Its grains
      must be the card's: `soil` naming the card, or the card's own fields;
    - else PROTOCOL in the card's D50 units: the quasi-2D device for a quasi-2D card (its [cell] a
      biaxial test), PROTOCOL_3D for a 3D card, whose spheres were calibrated as spheres.
    An InputError names the card's field and the fix when the campaign cannot be used."""
    import tomllib

    from interphase.soil import load_card

    d50 = float(card.soil["d50"])
    if protocol is not None:
        return {"soil": str(card.path), **protocol}, "the given protocol"
    ref = card.extra.get("criterion", {}).get("campaign")
    where = f"{card.path}: [criterion] campaign"
    if ref is None:
        if card.cell["test"] == "biaxial":
            return ({"soil": str(card.path), **protocol_for(d50)},
                    "the campaigns' quasi-2D cell (40 × 25 D50; the card names no campaign)")
        return ({"soil": str(card.path), **protocol_for(d50, PROTOCOL_3D)},
                "the chosen 3D cell (30 × 15 × 10 D50, the card's stiffness; the card names no campaign)")
    path = Path(ref) if Path(ref).is_absolute() else (card.path.parent / str(ref)).resolve()
    try:
        case = dict(tomllib.loads(path.read_text()).get("case", {}))
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise InputError(f"cannot read the campaign {path}: {exc}", where=where,
                         fix="the path is relative to the card: the campaign its criterion was fitted on") from None
    if not case:
        raise InputError(f"the campaign {path} has no [case] table", where=where,
                         fix="name the campaign file of the card's Group 1 (its [case] holds the cell)")
    case = {k: v for k, v in case.items() if k not in CASE_OWN}
    if "soil" in case:
        soil = Path(case["soil"]) if Path(case["soil"]).is_absolute() else (path.parent / case["soil"]).resolve()
        if load_card(soil).path != card.path:
            raise InputError(f"the campaign {path} shears the grains of {soil}, not this card's", where=where,
                             fix="name the campaign run on this card")
        case["soil"] = str(card.path)
    else:
        other = sorted(k for k, v in card.soil.items() if k != "shear_modulus" and case.get(k) != v)
        if other:
            raise InputError(f"the campaign {path} gives other grains than the card ({other[0]!r})", where=where,
                             fix="name the campaign run on this card's grains")
    g = case.get("shear_modulus", card.soil.get("shear_modulus"))
    return case, f"the [case] of {path} ({case.get('device', 'periodic')}, G {float(g) / 1e6:g} MPa)"


def profile_spec(row, d50: float, folder: Path) -> dict:
    """The campaign profile of a lab row in the card's D50 units (sawtooth, flat; a ramp as a file)."""
    from interphase.lab import tooth_geometry, profile_of

    def never(field, msg, fix=None):
        raise InputError(msg, where=field, fix=fix)

    kind = row["surface"].lower()
    if kind == "flat":
        return {"kind": "flat"}
    h, w, sr = tooth_geometry(row, never)
    lab_d50 = float(row["d50"])
    if kind == "sawtooth":
        return {"kind": "sawtooth", "rt": h / lab_d50, "sw": w / lab_d50, "sr": sr / lab_d50}
    prof = profile_of(row, lab_d50).scaled(d50 / lab_d50)
    path = folder / "profiles" / f"row{int(row['row'])}.csv"
    path.parent.mkdir(parents=True, exist_ok=True)
    pd.DataFrame({"x": prof.x, "z": prof.z}).to_csv(path, index=False, header=False)
    return {"kind": "file", "path": str(path.resolve()), "units": "m"}


def simulate(table, card, seeds, *, output: Path, executor: str | None = None, jobs: int | None = None,
             stream=None, protocol: dict | None = None, rerun_failed: bool = False) -> pd.DataFrame:
    """DEM δ at the peak (seed ensemble, 95 % interval) per laboratory row: columns row,
    delta_dem_deg, delta_dem_lo_deg, delta_dem_hi_deg, phi_dem_deg, dem_seeds. `protocol`: the
    interface cases' Case fields (default PROTOCOL)."""
    from interphase.campaign.element import run_cases
    from interphase.campaign.results import campaign_ensembles

    output = Path(output)
    from interphase.analysis.validation import row_friction

    case, _ = interface_case(card, protocol)
    groups = []
    for _, r in table.rows.iterrows():
        groups.append({"name": f"row{int(r['row'])}",
                       "case": {"profile": profile_spec(r, float(card.soil["d50"]), output),
                                "normal_stress": float(r["normal_stress"]),
                                "friction_ps": row_friction(r)[0]}})
    path = write_campaign(output / "simulate.toml", name="validate", case=case, groups=groups,
                          sweep={"seed": [int(s) for s in seeds]}, executor=executor or "local",
                          description=f"{table.path} on the soil card {card.path}")
    run_cases(path, executor=executor, jobs=jobs, stream=stream or sys.stderr, rerun_failed=rerun_failed)
    try:
        ens = campaign_ensembles(path)
    except InputError:
        ens = pd.DataFrame(columns=["group", "tan_delta", "tan_delta_lo", "tan_delta_hi", "tan_phi", "seeds"])
    deg = lambda t: np.degrees(np.arctan(pd.to_numeric(t, errors="coerce")))
    out = pd.DataFrame({"row": ens["group"].astype(str).str.removeprefix("row").astype(int),
                        "delta_dem_deg": deg(ens["tan_delta"]), "delta_dem_lo_deg": deg(ens["tan_delta_lo"]),
                        "delta_dem_hi_deg": deg(ens["tan_delta_hi"]), "phi_dem_deg": deg(ens["tan_phi"]),
                        "dem_seeds": ens["seeds"]}) if len(ens) else pd.DataFrame(
        columns=["row", "delta_dem_deg", "delta_dem_lo_deg", "delta_dem_hi_deg", "phi_dem_deg", "dem_seeds"])
    return out


def with_dem(pred: pd.DataFrame, dem: pd.DataFrame) -> pd.DataFrame:
    df = pred.merge(dem, on="row", how="left")
    df["error_dem_deg"] = df["delta_dem_deg"] - df["delta_measured_deg"]
    return df


def _fit_runs(card) -> Path | None:
    """The committed summaries beside the card's `[criterion] fit` (the runs its criterion was fitted
    on, their paired soil tests among them), or None. A DEM answer in the same cell at the same
    stress plans the same soil tests (the same case ids), so they come back finished instead of
    running again; a row of any other inputs is never taken (campaign.restore)."""
    fit = card.extra.get("criterion", {}).get("fit")
    if not fit:
        return None
    table = (Path(fit) if Path(fit).is_absolute() else card.path.parent / str(fit)).resolve().parent / "summaries.csv"
    return table if table.exists() else None


def simulate_campaign(card, surface, friction: float, seeds, *, output: Path, normal_stress: float = 100e3,
                      executor: str | None = None, protocol: dict | None = None) -> tuple[Path, str]:
    """The generated campaign `simulate_profile` runs, written to `output`/simulate.toml: (its path,
    the cell's provenance). `surface`: a profile line (x, z) [m] as measured (the teeth keep their
    physical size against the card's grains), or a profile table (an areal scan's patch: {"kind":
    "file", "path", "areal": true, "direction"}), which needs a 3D cell (refused before anything is
    written)."""
    output = Path(output)
    base, cell = interface_case(card, protocol)
    if isinstance(surface, dict) and base.get("device") != "periodic3d":
        raise InputError(f"an areal scan: the quasi-2D DEM shears one line of it ({cell})", where=str(surface.get("path")),
                         fix="write a campaign whose profile is one line of the scan, e.g. profile = {kind = \"file\", "
                             f"path = \"{surface.get('path')}\", axis = \"x\", line = \"1/3\"}} (campaigns/study.toml's "
                             "Group 5), give a 3D card, or use the criterion (`campaign predict` without --simulate), "
                             "which pools every line")
    output.mkdir(parents=True, exist_ok=True)
    if isinstance(surface, dict):
        profile = dict(surface)
    else:
        prof = output / "profile.csv"
        x, z = surface
        pd.DataFrame({"x": np.asarray(x, float), "z": np.asarray(z, float)}).to_csv(prof, index=False, header=False)
        profile = {"kind": "file", "path": str(prof.resolve()), "units": "m"}
    case = {**base, "profile": profile, "normal_stress": float(normal_stress), "friction_ps": float(friction)}
    path = write_campaign(output / "simulate.toml", name="predict", case=case, sweep={"seed": [int(s) for s in seeds]},
                          executor=executor or "local", description=f"a profile on the soil card {card.path}")
    return path, cell


def simulate_profile(card, surface, friction: float, seeds, *, output: Path, normal_stress: float = 100e3,
                     executor: str | None = None, jobs: int | None = None, stream=None, protocol: dict | None = None,
                     rerun_failed: bool = False) -> dict:
    """`campaign predict … --soil CARD --simulate`: the DEM on one surface (`simulate_campaign`) with
    the card's grains at `normal_stress` [Pa] and particle–surface `friction`, packing seeds `seeds`,
    with the card's soil test, in the card's interface cell (`interface_case`), its soil tests restored
    from the fit's committed runs where they are the same cases (`_fit_runs`); resumable, local or
    SLURM. Returns tan δ, E and δ at the seed ensemble's peak with their 95 % intervals, tan φ, θa of
    the surface as the cell shears it (filter 92, ° from vertical), the seeds, the campaign file and
    the cell (where it came from)."""
    from interphase.campaign.element import run_cases
    from interphase.campaign.results import campaign_ensembles

    path, cell = simulate_campaign(card, surface, friction, seeds, output=output, normal_stress=normal_stress,
                                   executor=executor, protocol=protocol)
    run_cases(path, executor=executor, jobs=jobs, stream=stream or sys.stderr, rerun_failed=rerun_failed,
              restore=_fit_runs(card))
    ens = campaign_ensembles(path)
    ens = ens[ens["test"] == "interface"] if "test" in ens else ens
    if ens.empty:
        raise InputError("no interface run finished", where=str(output),
                         fix="see `campaign status` of the campaign there; --rerun-failed runs failed ones again")
    r = ens.iloc[0]
    deg = lambda t: float(np.degrees(np.arctan(float(t))))
    return {"campaign": str(path), "cell": cell, "seeds": int(r["seeds"]), "tan_phi": float(r["tan_phi"]),
            "theta_a_deg_92": float(r["theta_a_deg_92"]) if "theta_a_deg_92" in r else math.nan,
            "tan_delta": float(r["tan_delta"]), "tan_delta_lo": float(r["tan_delta_lo"]),
            "tan_delta_hi": float(r["tan_delta_hi"]), "E": float(r["E"]), "E_lo": float(r["E_lo"]),
            "E_hi": float(r["E_hi"]), "delta_deg": deg(r["tan_delta"]), "delta_deg_lo": deg(r["tan_delta_lo"]),
            "delta_deg_hi": deg(r["tan_delta_hi"])}
