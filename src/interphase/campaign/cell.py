"""The laboratory's element test (triaxial / biaxial, engines/cell.py) of a soil card through the
campaign machinery: a generated campaign of cell cases (one group per confining stress, its
preparation from the relative density asked for, campaign/density.py), run resumably, read back as
`analysis.cell_ensemble.CellResult`s."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from interphase.campaign.element import CELL_SERIES, run_cases, write_campaign
from interphase.soil import SoilCard


def cell_of(cases, series: dict, summ: pd.DataFrame, *, e_limits=(np.nan, np.nan)):
    """The CellResult of the planned `cases` (one soil at one confining stress, its seeds)."""
    from interphase.analysis.cell_ensemble import cell_result

    runs, voids = [], []
    for p in cases:
        s = series.get(p.case_id)
        if s is None:
            continue
        runs.append((s["eps1"].to_numpy(float), s["epsv"].to_numpy(float), s["ratio"].to_numpy(float)))
        voids.append(float(s["e"].iloc[0]))
    first = cases[0].case
    return cell_result(first.test, first.normal_stress, runs, voids, e_limits=e_limits, preparation=first.preparation)


def cell_campaign_file(output: Path, card: SoilCard, test: str, relative_density: float | None) -> Path:
    """The generated campaign file `run_cell` writes (and reads back) in `output`."""
    return Path(output) / (f"{test}-{card.name}" + ("" if relative_density is None else f"-dr{relative_density:g}")
                           + ".toml")


def run_cell(card: SoilCard, confining_stresses, seeds, *, test: str | None = None, relative_density: float | None = None,
             output: Path | None = None, executor: str | None = None, jobs: int | None = None, stream=None,
             rerun_failed: bool = False, **changes):
    """The laboratory's element test (triaxial or biaxial, the card's [cell]) of `card` at each
    confining stress [Pa] on packing seeds `seeds`. At `relative_density` (a fraction), each stress's
    preparation is the one whose specimen consolidated to that stress has e = e_max − Dr (e_max − e_min),
    on the model's index limits (campaign.density.preparation_at: as the laboratory's Dr0, one void
    ratio after consolidation at every stress); without it, the card's [cell] relative_density, else
    the card's preparation. Either way the results carry the relative density on those limits.
    Returns CellResults."""
    from interphase.campaign.density import preparation_at

    from interphase.campaign.folders import element_runs

    test = test or card.cell["test"]
    relative_density = card.relative_density if relative_density is None else relative_density
    output = element_runs(card.path, card.name, output)[0]
    stresses = [float(s) for s in confining_stresses]
    seeds = [int(s) for s in seeds]
    mapped = {s: preparation_at(card, relative_density, s, seeds, test=test, output=output / "density",
                                executor=executor, jobs=jobs, stream=stream, rerun_failed=rerun_failed)
              for s in stresses}
    prep = {s: card.soil.get("preparation", 1.0) if mapped[s][0] is None else mapped[s][0] for s in stresses}
    base = card.cell_case(stresses[0], test=test, **changes)
    for k in ("normal_stress", "seed", "preparation"):
        base.pop(k, None)
    path = cell_campaign_file(output, card, test, relative_density)
    name = path.stem
    groups = [{"name": f"s{s:g}", "case": {"normal_stress": s, "preparation": prep[s]}, "sweep": {"seed": seeds}}
              for s in stresses]
    path = write_campaign(path, name=name, case=base, groups=groups,
                          description=f"{test} test of the soil card {card.path}")
    planned, series, summ = run_cases(path, executor=executor, jobs=jobs, stream=stream,
                                           rerun_failed=rerun_failed, columns=CELL_SERIES)
    results = [cell_of(cases, series, summ, e_limits=mapped[s][1])
               for s in stresses for cases in [[p for p in planned if p.case.normal_stress == s]]]
    return [_unreached(r, relative_density if mapped[r.confining_stress][0] is not None else None) for r in results]


#: a specimen further than this from the asked relative density was not made at it (the records' own
#: tolerance on Dr, campaign.cell_records)
DR_TOLERANCE = 0.05


def _unreached(result, asked: float | None):
    """The result with a note where the preparation could not make the asked relative density (the
    map's bound: its loosest or densest packing at that stress), so that a result is never read at a
    density it does not have."""
    import dataclasses
    import math

    made = result.relative_density
    if asked is None or not math.isfinite(made) or abs(made - asked) <= DR_TOLERANCE:
        return result
    side = "loosest" if made > asked else "densest"
    note = (f"asked Dr {asked:.2f}, made Dr {made:.2f}: preparation {result.preparation:g} is the {side} packing "
            f"this cell's preparation makes at {result.confining_stress / 1e3:g} kPa")
    return dataclasses.replace(result, note="; ".join(x for x in (note, result.note) if x))
