"""A card's density scale fitted on the records of one stress (campaign/density_scale.py), with
bootstrap intervals over the sweep's seeds: where each record sits on the card's preparations, its
model Dr, and the line model Dr = lab_offset + lab_span · Dr.

    PYTHONPATH=src python studies/density_scale/density_scale.py soils/karlsruhe-fine-sand.toml \
        studies/density_scale/density_scale.toml --extra docs/soils/kfs_best_sample \
        --record lab/soils/karlsruhe-fine-sand/drained-triaxial/TMD12.dat \
        --record lab/soils/karlsruhe-fine-sand/drained-triaxial/TMD17.dat \
        --record lab/soils/karlsruhe-fine-sand/drained-triaxial/TMD22.dat \
        --save docs/soils/density_scale [--write]

The sweep: the campaign's finished runs (the card's grains at the records' stress over
preparations; or, without them, the committed copy in --save), plus the runs of --extra folders
(summaries.csv of cell_study.py) on the same grains and stress. φ_peak and ψ_max are each
specimen's own, averaged over the seeds (as a calibration reads a sample). Each record's model Dr
is read on the card's void-ratio map at that stress, in the folder `campaign element` uses, through
density.own_relative_density (token runs at the anchor; what a later check inverts). --write puts
lab_span and lab_offset into the card's [density].
"""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import numpy as np
import pandas as pd


BOOT = 2000


def sweep_runs(campaign: Path, save: Path | None, extra: list[Path], grains: dict, stress: float) -> pd.DataFrame:
    """One row per run: preparation, seed, phi_peak_deg, psi_max_deg, e0."""
    from interphase.report.cell_tables import cell_runs

    got = cell_runs(campaign)
    if got is not None:
        summ = got[0].assign(preparation=got[0]["preparation"].fillna(1.0))     # the default is stored blank
        if save:
            save.mkdir(parents=True, exist_ok=True)
            summ[["case_id", "label", "seed", "preparation", "normal_stress", "phi_peak_deg", "psi_max_deg",
                  "eps1_peak", "e0", "elapsed"]].to_csv(save / "summaries.csv", index=False, float_format="%.6g")
    else:
        summ = pd.read_csv(save / "summaries.csv")
    frames = [summ[["preparation", "seed", "phi_peak_deg", "psi_max_deg", "e0", "normal_stress"]]]
    for folder in extra:
        s = pd.read_csv(folder / "summaries.csv")
        s = s[np.isclose(s["friction_pp"], grains["friction_pp"]) & np.isclose(s["normal_stress"], stress)].copy()
        s["preparation"] = s["label"].str.extract(r"prep([0-9.]+)-s", expand=False).astype(float)
        frames.append(s[["preparation", "seed", "phi_peak_deg", "psi_max_deg", "e0", "normal_stress"]])
    runs = pd.concat(frames, ignore_index=True)
    return runs[np.isclose(runs["normal_stress"], stress)]


def anchors(runs: pd.DataFrame, records, rng=None):
    """[(preparation, misfit)] per record on the seed means (resampled within each preparation when rng)."""
    from interphase.campaign.density_scale import anchor_preparation

    g = runs.groupby("preparation")
    if rng is None:
        m = g[["phi_peak_deg", "psi_max_deg"]].mean()
    else:
        m = g[["phi_peak_deg", "psi_max_deg"]].apply(
            lambda d: d.iloc[rng.integers(0, len(d), len(d))].mean())
    return [anchor_preparation(m.index, m["phi_peak_deg"], m["psi_max_deg"], r.values["phi_peak_deg"],
                               r.values["psi_max_deg"]) for r in records]


def write_card(card_path: Path, span: float, offset: float) -> None:
    text = card_path.read_text()
    text = re.sub(r"(?m)^lab_offset = .*\n", "", text)
    text, n = re.subn(r"(?m)^lab_span = .*$", f"lab_span = {span:.4f}\nlab_offset = {offset:.4f}", text)
    if n != 1:
        raise SystemExit(f"{card_path}: no single [density] lab_span line to replace")
    card_path.write_text(text)


def main(argv=None) -> None:
    from interphase.campaign.calibrate_cell import nominal, read_record
    from interphase.campaign.cell_records import index_void_ratios
    from interphase.campaign.density import MAP_SEEDS, own_relative_density, read_limits, void_ratio_map
    from interphase.campaign.density_scale import fit_scale, model_dr
    from interphase.campaign.folders import element_runs
    from interphase.soil import load_card

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("card", type=Path)
    ap.add_argument("campaign", type=Path)
    ap.add_argument("--record", type=Path, action="append", required=True)
    ap.add_argument("--extra", type=Path, action="append", default=[])
    ap.add_argument("--save", type=Path, default=None)
    ap.add_argument("--write", action="store_true", help="put lab_span and lab_offset into the card")
    a = ap.parse_args(argv)

    card = load_card(a.card)
    e_lim = index_void_ratios(card)
    records = [read_record(p, e_lim, None) for p in a.record]
    stress = nominal(records[0].confining_stress)
    if any(nominal(r.confining_stress) != stress for r in records):
        raise SystemExit("the records must share one stress (the scale is fitted where the sweep ran)")
    runs = sweep_runs(a.campaign, a.save, a.extra, card.soil, stress)
    seeds = list(range(1, MAP_SEEDS + 1))
    out = element_runs(card.path, card.name, None)[0] / "density"

    found = anchors(runs, records)
    dr_model = [own_relative_density(card, stress, seeds, p, output=out) for p, _ in found]
    span, offset = fit_scale([r.relative_density for r in records], dr_model)

    prep_map, e_map = void_ratio_map(card, stress, seeds, output=out)
    index = read_limits(card, seeds, (prep_map, e_map), output=out)
    rng = np.random.default_rng(20261128)
    boot = []
    for _ in range(BOOT):
        ps = [p for p, _ in anchors(runs, records, rng)]
        d = [model_dr(prep_map, e_map, p, index) for p in ps]
        boot.append([*ps, *fit_scale([r.relative_density for r in records], d)])
    boot = np.asarray(boot)
    lo, hi = np.percentile(boot, [2.5, 97.5], axis=0)

    means = runs.groupby("preparation").agg(n=("seed", "size"), phi=("phi_peak_deg", "mean"),
                                            psi=("psi_max_deg", "mean"), e0=("e0", "mean"))
    print(f"sweep at {stress / 1e3:g} kPa (seed means):")
    print(means.round(3).to_string())
    rows = []
    for i, (r, (p, m), d) in enumerate(zip(records, found, dr_model)):
        rows.append({"record": r.path.stem, "relative_density": round(r.relative_density, 4),
                     "lab_phi_peak_deg": round(r.values["phi_peak_deg"], 2),
                     "lab_psi_max_deg": round(r.values["psi_max_deg"], 2),
                     "preparation": round(p, 4), "preparation_lo": round(lo[i], 4), "preparation_hi": round(hi[i], 4),
                     "misfit": round(m, 3), "model_relative_density": round(d, 4)})
    table = pd.DataFrame(rows)
    print(table.to_string(index=False))
    k = len(records)
    fit = {"stress": stress, "lab_span": round(span, 4), "lab_span_lo": round(lo[k], 4), "lab_span_hi": round(hi[k], 4),
           "lab_offset": round(offset, 4), "lab_offset_lo": round(lo[k + 1], 4),
           "lab_offset_hi": round(hi[k + 1], 4), "bootstrap": BOOT,
           "map": {"preparations": [float(p) for p in prep_map], "void_ratios": [round(float(e), 5) for e in e_map]}}
    print(json.dumps({k: v for k, v in fit.items() if k != "map"}))
    if a.save:
        a.save.mkdir(parents=True, exist_ok=True)
        table.to_csv(a.save / "anchors.csv", index=False)
        (a.save / "scale.json").write_text(json.dumps(fit, indent=1) + "\n")
    if a.write:
        write_card(card.path, span, offset)
        print(f"written to {card.path} [density]")


if __name__ == "__main__":
    main()
