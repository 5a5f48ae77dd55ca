"""The soil's element test through the campaign machinery: a generated campaign file of box cases
(the card's soil at its element protocol), run by `campaign.run.run_campaign` (resumable, local or
SLURM, a finished case never run twice: identity is the hash of the inputs), and read back as
`analysis.element.ElementResult`s.

The generated file (`<output>/<name>.toml`) is the record of what ran; running the same command
again reuses every finished case.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd
import tomli_w

from interphase.analysis.element import ElementResult, element_result, hexatic_order
from interphase.soil import SoilCard


def write_campaign(path: Path, *, name: str, case: dict, sweep: dict | None = None, zip_: dict | None = None,
                   groups: list[dict] | None = None, executor: str = "local", jobs: int = 0,
                   description: str = "") -> Path:
    """A campaign file (plain data → TOML: [case], [sweep], [zip], [[group]]); `output` is the file's
    own folder. Rewritten only when its content changes."""
    data = {"campaign": {"name": name, "description": description, "engines": ["liggghts"], "output": "."},
            "execution": {"executor": executor, "jobs": int(jobs)}, "case": case}
    if sweep:
        data["sweep"] = sweep
    if zip_:
        data["zip"] = zip_
    if groups:
        data["group"] = groups
    path.parent.mkdir(parents=True, exist_ok=True)
    text = tomli_w.dumps(data)
    if not path.exists() or path.read_text() != text:
        path.write_text(f"# written by interphase-dem ({name}); running it again reuses every finished case\n" + text)
    return path


#: the series columns the element tests read: the periodic shear's, and the cell's (io/cell.py)
SHEAR_SERIES = ("shear_disp", "stress_ratio", "platen_z")
CELL_SERIES = ("eps1", "epsv", "e", "ratio")


def run_cases(path: Path, *, executor: str | None = None, jobs: int | None = None, stream=None,
              rerun_failed: bool = False, columns=SHEAR_SERIES, restore: Path | None = None):
    """Run a generated campaign file (its finished runs first restored from a pack when the command
    restores from one: restore.restoring; else from the summaries table `restore`, if given, whose
    rows of planned case ids come back finished); returns (planned cases, {case_id: series DataFrame of
    `columns`}, summaries table of the finished ones). Failed cases are reported by the run and left
    out of the results (`failures` says why); `rerun_failed` runs them again."""
    from interphase.campaign.plan import plan
    from interphase.campaign.restore import packed_table
    from interphase.campaign.run import run_campaign
    from interphase.campaign.schema import load_campaign
    from interphase.campaign.store import CampaignStore

    campaign = load_campaign(path)
    report = run_campaign(path, executor=executor, jobs=jobs, stream=stream or sys.stderr, live=False,
                          rerun_failed=rerun_failed, restore=packed_table(campaign.output) or restore)
    if report.interrupted:      # Ctrl-C, SIGTERM, a full disk: the command stops here, not only this campaign
        raise KeyboardInterrupt(report.stopped or "interrupted")
    planned = plan(campaign)
    series = {}
    with CampaignStore(campaign.output) as store:
        summ = store.summaries()
        done = set(summ["case_id"]) if len(summ) else set()
        for p in planned:
            if p.case_id in done:
                try:
                    folder = store.case_folder(p.case_id)
                    series[p.case_id] = pd.read_parquet(folder / "series.parquet", columns=list(columns))
                    series[p.case_id].attrs["folder"] = str(folder)
                except (OSError, ValueError, KeyError):
                    pass
    return planned, series, summ.set_index("case_id") if len(summ) else summ


def element_of(cases, series: dict, summ: pd.DataFrame, d50: float, normal_stress: float) -> ElementResult:
    """The ElementResult of the planned `cases` (one physical soil at one stress, its seeds)."""
    runs, order = [], []
    for p in cases:
        s = series.get(p.case_id)
        if s is None:
            continue
        sf = float(summ.loc[p.case_id, "solid_fraction"]) if "solid_fraction" in summ.columns else np.nan
        runs.append((s["shear_disp"].to_numpy(float), s["stress_ratio"].to_numpy(float),
                     s["platen_z"].to_numpy(float), sf))
        order.append(_start_order(Path(s.attrs.get("folder", ""))))
    return element_result(runs, d50, normal_stress, order)


def _start_order(folder: Path) -> float:
    """Hexatic order of the grains at a run's first contact snapshot (the start of its shear)."""
    try:
        p = pd.read_parquet(folder / "particles.parquet", columns=["snapshot", "x", "z", "radius"])
    except (OSError, ValueError, KeyError):
        return np.nan
    first = p[p["snapshot"] == p["snapshot"].min()]
    return hexatic_order(first["x"].to_numpy(float), first["z"].to_numpy(float), first["radius"].to_numpy(float))


def failures(path: Path) -> list[str]:
    """One line per case of a generated campaign file that did not finish: its label, status and
    the engine's cause and message as the runner recorded them."""
    from interphase.campaign.schema import load_campaign
    from interphase.campaign.store import INDEX, CampaignStore

    campaign = load_campaign(path)
    if not (campaign.output / INDEX).exists():
        return []
    with CampaignStore(campaign.output) as store:
        rows = store.status()
    bad = rows[~rows["status"].isin(("done", "pending"))]
    return [f"{r.label}: {r.status}" + (f" ({r.cause})" if isinstance(r.cause, str) and r.cause else "")
            + (f": {r.message}" if isinstance(r.message, str) and r.message else "") for r in bad.itertuples()]


def run_element(card: SoilCard, normal_stresses, seeds, *, output: Path | None = None, executor: str | None = None,
                jobs: int | None = None, stream=None, rerun_failed: bool = False,
                shear_velocity: float | None = None) -> list[ElementResult]:
    """The element test of `card` at each normal stress [Pa] on packing seeds `seeds`, in `output`
    (default: runs/element/NAME beside the card, campaign.folders); `shear_velocity` [m/s] replaces
    the card's [element] speed."""
    from interphase.campaign.folders import element_runs

    output = element_runs(card.path, card.name, output)[0]
    stresses = [float(s) for s in normal_stresses]
    base = card.element_case(stresses[0], **({} if shear_velocity is None else {"shear_velocity": shear_velocity}))
    base.pop("normal_stress"), base.pop("seed")
    path = write_campaign(output / f"element-{card.name}.toml", name=f"element-{card.name}", case=base,
                          sweep={"normal_stress": stresses, "seed": [int(s) for s in seeds]},
                          description=f"element test of the soil card {card.path}")
    planned, series, summ = run_cases(path, executor=executor, jobs=jobs, stream=stream, rerun_failed=rerun_failed)
    return [element_of(cases, series, summ, cases[0].case.d50, s)
            for s in stresses for cases in [[p for p in planned if p.case.normal_stress == s]]]


def element_failures(card: SoilCard, output=None) -> list[str]:
    """`failures` of the element test's generated file of `card` in `output` (run_element's folder)."""
    from interphase.campaign.folders import element_runs

    path = element_runs(card.path, card.name, output)[0] / f"element-{card.name}.toml"
    return failures(path) if path.exists() else []
