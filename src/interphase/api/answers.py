"""The answer: δ of a sand on a surface from the criterion (`campaign predict`), or from the DEM
run on the profile with a soil card's grains (`campaign predict --simulate`). Stresses in Pa, grain
sizes in m, friction as a coefficient μ = tan φμ, angles in degrees."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from interphase.api import checks
from interphase.errors import InputError

PathLike = str | os.PathLike


def predict(profile: PathLike, *, friction: float | None = None, soil: PathLike | None = None,
            normal_stress: float | None = None, relative_density: float | None = None,
            smooth_delta_deg: float | None = None, fit: str | None = None, d50: float | None = None,
            tan_phi: float | None = None, units: str | None = None, axis: str | None = None,
            filt: int | None = None):
    """δ of a sand on a surface (as `campaign predict`): an `interphase.answer.Answer` (`.delta_deg`,
    `.model_delta_deg_lo/_hi`, `.delta_deg_lo/_hi`, `.parts_deg`, `.paragraph()`, `.to_dict()`).
    `soil`: your sand's card (path, or a shipped card's name); `friction` = μ = tan φμ [-] or
    `smooth_delta_deg` [°] on a smooth plate; `normal_stress` [Pa]; `relative_density` [-]. Instead of
    a card, `fit` ('study', 'study-figures', a criterion.json or a campaign file) with `d50` [m] and
    optionally `tan_phi` [-]. `axis`: an areal scan's shear direction; `filt`: force the branch (92/90).
    Bad input raises InputError, as the command refuses it."""
    from interphase.answer import predict as _predict

    if d50 is not None:
        d50 = checks.d50(d50)
    return _predict(profile, friction=friction, smooth_delta_deg=smooth_delta_deg, soil=soil, fit=fit, d50=d50,
                    tan_phi=tan_phi, normal_stress=normal_stress, relative_density=relative_density, units=units,
                    axis=axis, filt=filt)


#: the fewest packing seeds the DEM's answer is given for (a peak's interval needs three)
DEM_SEEDS = 3


def predict_dem(profile: PathLike, friction: float | None = None, soil: PathLike | None = None, *,
                smooth_delta_deg: float | None = None, seeds: int = 3, normal_stress: float = 100e3,
                runs: PathLike | None = None, jobs: int | None = None, units: str | None = None,
                d50: float | None = None, axis: str | None = None, stream=None) -> dict:
    """The DEM instead of the criterion (as `campaign predict … --soil CARD --simulate --json`): the
    surface as measured sheared with the card's grains at `normal_stress` [Pa] and particle–surface
    `friction` (or `smooth_delta_deg`, as `predict`), packing seeds 1…`seeds` (≥ 3), in the cell the
    card's criterion stands on (campaign.validate.interface_case), with the card's soil test; a
    generated campaign in `runs` (default runs/predict/<card>/<profile name> beside the card),
    resumable; progress to `stream` (default stderr). Returns tan δ, E and δ with their 95 %
    intervals, tan φ, θa of the surface sheared, the seeds, the cell and the campaign file. A line is
    sheared as measured; an areal scan (a 3D card's cell only) as the patch of the scan whose opposite
    edges match best, the soil moving along +`axis` (x or y; surface/patch.py). `d50` [m], if given,
    must be the card's."""
    from interphase.answer import friction_from
    from interphase.campaign.folders import beside, given
    from interphase.campaign.validate import simulate_profile
    from interphase.soil import card_d50_mm, load_card
    from interphase.surface.base import check_axis
    from interphase.surface.readers import load_profile, read_scan

    if soil is None:
        raise InputError("--simulate runs the DEM with a soil card's grains", where="--simulate",
                         fix="add --soil CARD (soils/NAME.toml)")
    mu = friction_from(friction, smooth_delta_deg)
    checks.seeds(seeds, fewest=DEM_SEEDS)
    normal_stress = checks.positive(normal_stress, "--normal-stress", "Pa", "100e3")
    card = load_card(soil)
    card_d50_mm(card, None if d50 is None else checks.d50(d50) * 1e3, "the DEM uses the card's grains")
    out_dir, runs_from = (given(runs, "--runs") if runs else
                          beside(card.path, f"runs/predict/{card.name}/{Path(profile).stem}", "--runs"))
    if read_scan(str(profile), units).areal:
        surface = {"kind": "file", "path": str(Path(profile).resolve()), "areal": True,
                   "direction": f"+{check_axis(axis or 'x', '--axis')}"}
        if units is not None:
            surface["units"] = units
    else:
        prof = load_profile(str(profile), units, None)
        surface = (prof.x, prof.z)
    print(f"predict --simulate: runs folder {out_dir} ({runs_from})", file=stream or sys.stderr, flush=True)
    out = simulate_profile(card, surface, mu, range(1, seeds + 1), output=out_dir,
                           normal_stress=normal_stress, jobs=jobs, stream=stream)
    return out | {"profile": str(profile), "soil": str(card.path), "friction": mu, "normal_stress": normal_stress}
