"""Soils: a card's own tests (`campaign element`: the periodic direct shear, the laboratory's
triaxial or biaxial cell, the card at laboratory records' stress and density), its void-ratio limits
(`campaign density`), its calibration (`campaign calibrate`) and a laboratory triaxial record read
alone (`campaign lab-record`). Stresses in Pa, speeds in m/s, angles in degrees.

The functions that run cases write their runs folder (where it came from) and the engines'
progress to `stream` (default stdout), a card's --quick note to stderr, before anything runs; each
result is a list of dicts, one per stress or record, or one dict."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from interphase.api import checks
from interphase.errors import InputError

PathLike = str | os.PathLike


def _card(card: PathLike, seeds: int):
    """The soil card (a laboratory record or anything else refused, naming the fix), its --quick
    note said on stderr, and the seed count checked: what every test of a card starts with."""
    from interphase.soil import load_card

    c = load_card(card)
    if c.quick:
        runs = c.extra.get("calibration", {}).get("runs", "?")
        print(f"warning: {c.path} is a --quick calibration ({runs} runs): a first look, not a calibrated soil",
              file=sys.stderr)
    checks.seeds(seeds)
    return c


def _runs_said(card, runs, stream, verb: str = "element") -> Path:
    from interphase.campaign.folders import element_runs

    folder, runs_from = element_runs(card.path, card.name, runs)
    print(f"{verb} {card.name}: runs folder {folder} ({runs_from})", file=stream or sys.stdout, flush=True)
    return folder


def element(card: PathLike, normal_stress: float | list[float], seeds: int = 3, *, runs: PathLike | None = None,
            shear_velocity: float | None = None, executor: str | None = None, jobs: int | None = None,
            rerun_failed: bool = False, stream=None) -> list[dict]:
    """The element test of a soil card (docs/soils.md: the periodic direct shear) at one or more
    normal stresses [Pa], packing seeds 1…`seeds`, as `campaign element --json`: one dict per stress
    with phi_peak_deg, phi_cs_deg, psi_max_deg and solid_fraction (each with _lo/_hi, 95 % over the
    seeds; None where undefined), n_seeds, has_peak, order_psi6, a note, runs (the folder),
    card_quick and failed (what each failed run says) — and card (its name). `runs`: the runs folder
    (default runs/element/NAME beside the card); `shear_velocity` [m/s] replaces the card's speed.
    Resumable. Bad input raises InputError before anything is written."""
    from interphase.campaign.element import element_failures, run_element

    c = _card(card, seeds)
    stresses = checks.positive_all(normal_stress, "--normal-stress", "Pa", "100e3", "no stress given",
                                   "direct shear: --normal-stress PA; the laboratory's test: --confining-stress PA")
    if shear_velocity is not None:
        checks.positive(shear_velocity, "--shear-velocity", "m/s", "0.02")
    folder = _runs_said(c, runs, stream)
    results = run_element(c, stresses, range(1, seeds + 1), output=folder, executor=executor, jobs=jobs,
                          stream=stream or sys.stdout, rerun_failed=rerun_failed, shear_velocity=shear_velocity)
    failed = element_failures(c, folder) if any(r.n_seeds < seeds for r in results) else []
    return [r.to_dict() | {"runs": str(folder), "card_quick": c.quick, "failed": failed, "card": c.name}
            for r in results]


def cell(card: PathLike, confining_stress: float | list[float], seeds: int = 3, *, test: str | None = None,
         relative_density: float | None = None, report: PathLike | None = None, runs: PathLike | None = None,
         executor: str | None = None, jobs: int | None = None, rerun_failed: bool = False,
         stream=None) -> list[dict]:
    """The laboratory's element test of a card (`test` triaxial in 3D, biaxial in quasi-2D; default
    the card's [cell] test) at one or more confining stresses σ3′ [Pa], as `campaign element --test
    … --json`: one dict per stress with phi_peak_deg, psi_max_deg, phi_cs_deg (φ at the end strain),
    void_ratio (each with _lo/_hi), eps1_at_peak, eps1_end, relative_density, preparation, n_seeds,
    a note — and card (its name). `relative_density` [-] (default the card's); `report`: a folder
    for the curves and angles (its files said on `stream`)."""
    from interphase.campaign.cell import run_cell

    c = _card(card, seeds)
    stresses = checks.positive_all(confining_stress, "--confining-stress", "Pa", "100e3", "no confining stress given",
                                   "e.g. --confining-stress 100e3, or --record FILE to test at a laboratory record's")
    folder = _runs_said(c, runs, stream)
    results = run_cell(c, stresses, range(1, seeds + 1), test=test, relative_density=relative_density,
                       output=folder, executor=executor, jobs=jobs, stream=stream or sys.stdout,
                       rerun_failed=rerun_failed)
    if report is not None:
        from interphase.campaign.cell_records import model_runs
        from interphase.report.verification import write_report

        dr = c.relative_density if relative_density is None else relative_density
        curves = model_runs(folder, c, test or c.cell["test"], dr)
        pairs = [(f"{r.test}, {r.confining_stress / 1e3:g} kPa, Dr {r.relative_density:.2f}", None,
                  curves[r.confining_stress]) for r in results]
        for p in write_report(report, [], pairs):
            print(f"report: {p}", file=stream or sys.stdout)
    return [r.to_dict() | {"card": c.name} for r in results]


def records(card: PathLike, files: list[PathLike], seeds: int = 3, *, test: str | None = None,
            report: PathLike | None = None, runs: PathLike | None = None, executor: str | None = None,
            jobs: int | None = None, rerun_failed: bool = False, stream=None) -> list[dict]:
    """The card's laboratory test at each laboratory record's σ3′ (the nearest 50 kPa) and Dr0 (on the
    card's [target] e_min, e_max), with verdicts against the record, as `campaign element CARD
    --record FILE … --json`: one dict per record of `files` (`records_markdown` prints them as a table).
    `report`: a folder for verification.csv/.md, the curves and the angles."""
    from interphase.campaign.cell_records import check_record, index_void_ratios
    from interphase.report.verification import write_report

    c = _card(card, seeds)
    if test is not None and test != c.cell["test"]:
        raise InputError(f"the card's cell runs the {c.cell['test']} test, not {test}", where="--test",
                         fix=f"--test {c.cell['test']}, or a card of the other test")
    index_void_ratios(c)                 # before any run: a card without them is refused at once
    folder = _runs_said(c, runs, stream)
    rows, pairs = [], []
    for path in files:
        row, pair = check_record(c, Path(path), list(range(1, seeds + 1)), folder, executor=executor, jobs=jobs,
                                 stream=stream or sys.stdout, rerun_failed=rerun_failed)
        rows.append(row)
        pairs.append(pair)
    if report is not None:
        for p in write_report(report, rows, pairs):
            print(f"report: {p}", file=stream or sys.stdout)
    return rows


def records_markdown(rows: list[dict]) -> str:
    """The rows of `records` as the Markdown table docs/soils.md shows."""
    import pandas as pd

    from interphase.report.verification import markdown

    return markdown(pd.DataFrame(rows))


def density(card: PathLike, seeds: int = 3, *, runs: PathLike | None = None, executor: str | None = None,
            jobs: int | None = None, rerun_failed: bool = False, stream=None) -> dict:
    """The void ratios a card's grains reach by the cell's preparation, as `campaign density --json`:
    e_min (frictionless), e_max (the grains' own friction) at the reference stress [Pa], the
    preparations and their void ratios; written into the card's [density] (`written`: now, else
    already there). `runs`: default runs/density/NAME beside the card."""
    from interphase.campaign.density import density_runs, measure_density
    from interphase.soil import load_card

    checks.seeds(seeds)
    c = load_card(card)
    folder, runs_from = density_runs(c, runs)
    print(f"density {c.name}: runs folder {folder} ({runs_from})", file=stream or sys.stdout, flush=True)
    return measure_density(c, range(1, seeds + 1), output=folder, executor=executor, jobs=jobs,
                           stream=stream or sys.stdout, rerun_failed=rerun_failed)


def calibrate(target: PathLike, *, quick: bool = False, output: PathLike | None = None,
              runs: PathLike | None = None, restore: PathLike | None = None, executor: str | None = None,
              jobs: int | None = None, rerun_failed: bool = False, stream=None) -> dict:
    """Calibrate grain parameters to a laboratory target (docs/soils.md), as `campaign calibrate
    --json`; writes the soil card and returns what it holds (chosen parameters, posterior, achieved
    and held-out checks). `output`: the card (default [target] card, else soils/NAME.toml beside the
    target; NAME-quick with `quick`); `runs`: every run's folder; `restore`: a `campaign pack` of
    those runs brought back first. A card already there is read back when it is this
    calibration's, else refused (InputError): no card is ever replaced. Resumable."""
    from interphase.campaign.calibrate import calibrate as _calibrate
    from interphase.campaign.calibrate_cell import calibrate_cell, is_cell_target

    fn = calibrate_cell if is_cell_target(target) else _calibrate
    return fn(target, quick=quick, card_path=output, output=runs, executor=executor, jobs=jobs,
              stream=stream or sys.stdout, rerun_failed=rerun_failed, restore=restore)


def lab_record(path: PathLike, *, e0: float | None = None) -> dict:
    """One laboratory drained triaxial record (lab/soils/*/: Karlsruhe .dat, Ottawa F-65 .csv) read
    and summarised as `campaign lab-record` prints it: the record's start (e0, σ3′ [Pa], layout,
    rows) and its ShearState (φ_peak, ε1 at peak, ψ_max, end state; definitions in
    interphase.analysis.triaxial). A record that cannot be read raises InputError naming the file,
    the line and the column."""
    from interphase.analysis.triaxial import shear_state
    from interphase.io.lab_triaxial import read_triaxial

    rec = read_triaxial(path, e0=e0)
    t = rec.table
    state = shear_state(t.eps1, t.epsv, t.ratio, t.e)
    return ({"file": str(rec.path), "layout": rec.layout, "rows": len(t), "e0": rec.e0,
             "sigma3_start": rec.sigma3_start} | state.to_dict())
