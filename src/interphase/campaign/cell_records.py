"""A soil card against laboratory records (`campaign element CARD --record FILE … [--report DIR]`):
the laboratory's test on the model at each record's σ3′ (the nearest 50 kPa, calibrate_cell.nominal)
and relative density Dr0, the verdicts, and the report a reviewer asks for (docs/soils.md).

Dr0 of a record is (e_max − e0)/(e_max − e_min) on the sand's own index void ratios, read from the
card's [target] (a card written by `campaign calibrate` carries them). Verdicts: within when the
model's 95 % seed interval lies inside the record's value ± the calibration's TOLERANCES (φ_peak
1.5°, ψ_max 2°), outside when it lies wholly beyond, else undecided.

The report of the rows: report/verification.py."""

from __future__ import annotations

import io
from collections import defaultdict
from pathlib import Path

from interphase.errors import InputError


def index_void_ratios(card) -> tuple[float, float]:
    """(e_min, e_max) of the laboratory sand the card stands for, from its [target]."""
    t = card.extra.get("target", {})
    try:
        e_lim = (float(t["e_min"]), float(t["e_max"]))
    except (KeyError, TypeError, ValueError):
        raise InputError("the card has no laboratory e_min and e_max to turn a record's e0 into a relative density",
                         where=f"{card.path}: [target] e_min, e_max",
                         fix="add the sand's index void ratios there (a card from `campaign calibrate` of a "
                             "record target has them), or run --confining-stress with --relative-density") from None
    if not 0 < e_lim[0] < e_lim[1]:
        raise InputError(f"e_min {e_lim[0]} must be positive and below e_max {e_lim[1]}",
                         where=f"{card.path}: [target] e_min, e_max", fix="the sand's index void ratios")
    return e_lim


def model_runs(runs: Path, card, test: str, relative_density) -> dict[float, list[tuple]]:
    """{σ3′ [Pa]: [(ε1, εv, R), …]} of the finished seeds of the element tests `run_cell` ran in
    `runs` at `relative_density` (one read of its campaign for every stress)."""
    from interphase.campaign.cell import cell_campaign_file
    from interphase.campaign.element import CELL_SERIES, run_cases

    path = cell_campaign_file(runs, card, test, relative_density)
    # every seed has run (run_cell just ran them): this reads them back, its progress lines unwanted
    planned, series, _ = run_cases(path, columns=CELL_SERIES, stream=io.StringIO())
    out = defaultdict(list)
    for p in planned:
        if (s := series.get(p.case_id)) is not None:
            out[p.case.normal_stress].append((s["eps1"].to_numpy(float), s["epsv"].to_numpy(float),
                                              s["ratio"].to_numpy(float)))
    return out


def check_record(card, path: Path, seeds, runs: Path, **run_kw) -> tuple[dict, tuple]:
    """(row, (title, record table, model runs)) of one record: the card's test at the record's σ3′
    and Dr0 (resumable: finished seeds are read, not rerun)."""
    from interphase.analysis.triaxial import shear_state
    from interphase.campaign.calibrate import TOLERANCES, verdict
    from interphase.campaign.calibrate_cell import nominal
    from interphase.campaign.cell import run_cell
    from interphase.io.lab_triaxial import read_triaxial

    e_lim = index_void_ratios(card)
    rec = read_triaxial(path)
    t = rec.table
    lab = shear_state(t.eps1, t.epsv, t.ratio, t.e)
    dr = (e_lim[1] - rec.e0) / (e_lim[1] - e_lim[0])
    sigma, asked = nominal(rec.sigma3_start), min(1.0, max(0.0, dr))
    (r,) = run_cell(card, [sigma], seeds, relative_density=asked, output=runs, **run_kw)
    test = card.cell["test"]
    row = {"record": Path(path).stem, "confining_stress": sigma, "relative_density": dr,
           "model_relative_density": r.relative_density, "lab_phi": lab.phi_peak_deg, "lab_psi": lab.psi_max_deg,
           "lab_eps1_peak": lab.eps1_peak,
           **{k: v for k, v in r.to_dict().items() if k.startswith(("phi_", "psi_"))},
           "eps1_at_peak": r.eps1_at_peak, "void_ratio": r.void_ratio, "n_seeds": r.n_seeds,
           "preparation": r.preparation}
    for q, lq in (("phi_peak_deg", "lab_phi"), ("psi_max_deg", "lab_psi")):
        row[q + "_verdict"] = verdict(row[lq], row[q + "_lo"], row[q + "_hi"], TOLERANCES[q])
    title = f"{Path(path).stem}: {sigma / 1e3:g} kPa, Dr {dr:.2f}"
    return row, (title, t, model_runs(runs, card, test, asked)[sigma])
