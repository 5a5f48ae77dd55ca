"""Issue 39 item 2: the seed scatter against the cell's size, and what E ± 0.05 over the study would
cost with each size (studies/scatter_size/scatter_size.toml: the soil test and saw-teeth Rt/D50 0.2
and 1 at μs 0.5, cells 40 × 25, 60 × 35, 80 × 50 D50, 8 seeds each; studies/scatter_size/
scatter_split.toml: the same three tests at the crossed cells 40 × 35 and 60 × 25, which tell the
height's effect from the length's).

    PYTHONPATH=src python studies/scatter_size/scatter_size.py [--save] [--trials N]

Reads each campaign's runs, or without them its committed copy (studies/scatter_size/results/
scatter_size/ and scatter_split/: summaries.csv, curves.parquet); --save writes those copies from
the runs. Per cell (box_length_d50 × box_height_d50), per test: the seeds; the per-seed SD of the
leave-one-out peak (tan φ of the soil test, tan δ of each surface: analysis.ensemble.seed_states as
the report reads them) with its 95 % chi-square interval, and of E per seed (the seed's interface
peak over its paired soil test's); the mean wall per run (`elapsed`, one run per core; of the runs
made on this machine when the table says which, `ran_here`: the restored 40 × 25 runs ran
elsewhere); and the price of a half-width: the seeds for a 95 % half-width h are n ≈ (t·sd/h)², so
a size's core-hours for a given h scale as sd² × wall per run (printed relative to 40 × 25).
Then the study at E ± 0.05 with each size: studies/sequential_seeds/sequential_bill.py's projection (the sequential
rule on Normal(case mean, case sd) draws of every physical case of the committed study, cap 24 or
48 interface seeds, soil on 40 or 80 seeds) with every case's interface sd scaled by the size's measured ratio to 40 × 25
(mean over the two surfaces), the soil's by its ratio, and each run's wall by the size's ratio.
A measurement: exit 0 whatever it finds.
"""

from __future__ import annotations

import argparse
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from interphase.analysis.ensemble import ratio_interval, t_interval
from interphase.analysis.seed_draws import populations, project, run_times
from interphase.campaign.compare import compare, seed_values
from interphase.campaign.results import CommittedCurves, write_curves

HERE = Path(__file__).resolve().parent
ROOT = Path(__file__).resolve().parents[2]
REPRO = ROOT / "docs" / "reproduction"
#: each campaign and the folder its committed copy lives in
CAMPAIGNS = {HERE / f"{name}.toml": HERE / "results" / name
             for name in ("scatter_size", "scatter_split")}
CELL = ["box_length_d50", "box_height_d50"]
REFERENCE = (40.0, 25.0)


def load(campaign: Path, committed: Path, save: bool):
    """(summaries, curve store) of the campaign's runs (saved to `committed` if `save`), else of its
    committed copy; None when it has neither."""
    try:
        from interphase.campaign.results import open_campaign

        _, store, summ = open_campaign(campaign)
        if summ.empty:
            raise FileNotFoundError("no finished run yet")
    except Exception as exc:      # noqa: BLE001 — no runs here: the committed copy
        print(f"(no runs of {campaign.name}: {str(exc).splitlines()[0]}; reading {committed})")
        if not (committed / "summaries.csv").is_file():
            return None
        return (pd.read_csv(committed / "summaries.csv", dtype={"case_id": str, "pair_id": str}),
                CommittedCurves(committed / "curves.parquet"))
    import json

    from interphase.campaign.restore import is_restored

    # a restored run's wall is the machine's that ran it: the price compares walls of runs made here
    summ["ran_here"] = [not is_restored(json.loads((store.case_folder(c) / "case.json").read_text()))
                        for c in summ["case_id"].astype(str)]
    # a run made for this campaign in an earlier session comes back restored from the committed copy:
    # it keeps that copy's ran_here (made for this campaign, not the study's 40 x 25 runs)
    if (committed / "summaries.csv").is_file():
        kept = pd.read_csv(committed / "summaries.csv", dtype={"case_id": str}, usecols=["case_id", "ran_here"])
        earlier = set(kept.loc[kept["ran_here"].astype(bool), "case_id"])
        summ["ran_here"] = summ["ran_here"] | summ["case_id"].astype(str).isin(earlier)
    if save:
        committed.mkdir(parents=True, exist_ok=True)
        summ.to_csv(committed / "summaries.csv", index=False)
        write_curves(summ, store, committed / "curves.parquet")
    return summ, store


def sd_interval(v: np.ndarray) -> tuple[float, float, float]:
    """Sample SD (ddof 1) with its 95 % chi-square interval."""
    n, s = v.size, float(np.std(v, ddof=1))
    return s, s * math.sqrt((n - 1) / stats.chi2.ppf(0.975, n - 1)), s * math.sqrt((n - 1) / stats.chi2.ppf(0.025, n - 1))


def cell_rows(summ: pd.DataFrame, all_seeds: pd.DataFrame) -> pd.DataFrame:
    """One row per (cell, test, quantity): seeds, mean, SD and its interval, wall per run [s]
    (`all_seeds`: `cell_seeds` of `summ`)."""
    rows = []
    for cell, s in summ.groupby(CELL, sort=True):
        seeds = all_seeds[(all_seeds[CELL[0]] == cell[0]) & (all_seeds[CELL[1]] == cell[1])]
        here = s["ran_here"].astype(bool) if "ran_here" in s else pd.Series(True, index=s.index)
        per_case = s.assign(_case=s["label"].str.replace(r"-s\d+$", "", regex=True), _here=here).groupby("_case")
        wall = per_case.apply(lambda g: g.loc[g["_here"], "elapsed"].mean() if g["_here"].any()
                              else g["elapsed"].mean(), include_groups=False)
        wall_here = per_case["_here"].any()
        for case, g in seeds.groupby("case", sort=True):
            test = g["test"].iloc[0]
            for q, col in ((("tan_phi", "peak"),) if test == "box" else (("tan_delta", "peak"), ("E", "E"))):
                v = pd.to_numeric(g[col], errors="coerce").dropna().to_numpy(float)
                if v.size < 2:
                    continue
                sd, lo, hi = sd_interval(v)
                mean_lo, mean_hi = t_interval(v)
                rows.append(dict(length=cell[0], height=cell[1], case=case, test=test, quantity=q, seeds=v.size,
                                 mean=v.mean(), mean_lo=mean_lo, mean_hi=mean_hi, sd=sd, sd_lo=lo,
                                 sd_hi=hi, wall_s=float(wall.get(case, math.nan)),
                                 wall_here=bool(wall_here.get(case, False))))
    return pd.DataFrame(rows)


def cell_seeds(summ: pd.DataFrame, store) -> pd.DataFrame:
    """`seed_values` per cell (the labels do not name the cell, and a leave-one-out peak must not mix
    cells), with the cell's fields, each run's own maximum (`peak_stress_ratio`) and where it is
    (`shear_disp_at_peak`, m)."""
    return pd.concat([seed_values(s, store) for _, s in summ.groupby(CELL)], ignore_index=True).merge(
        summ[["case_id", "peak_stress_ratio", "shear_disp_at_peak", *CELL]].astype({"case_id": str}), on="case_id")


def levels(seeds: pd.DataFrame) -> pd.DataFrame:
    """One row per (cell, test): the mean of each seed's value by three readings of its strength, each
    with its 95 % t interval: the leave-one-out peak (the tool's bagged one: each seed read where
    bootstrap means of the other seeds peak, analysis.ensemble.peak_values), the run's own maximum (lifted by the run's noise) and the critical
    state (mean over the last 40 % of the shear); and the SD of where the runs peak (mm): a mean
    curve of seeds that peak apart has a lower, flatter peak."""
    rows = []
    for (length, height, case), g in seeds.groupby([*CELL, "case"], sort=True):
        row = dict(length=length, height=height, case=case, test=g["test"].iloc[0], seeds=len(g))
        for name, col in (("loo_peak", "peak"), ("own_max", "peak_stress_ratio"), ("critical", "critical")):
            v = pd.to_numeric(g[col], errors="coerce").dropna().to_numpy(float)
            row[name], (row[f"{name}_lo"], row[f"{name}_hi"]) = v.mean(), t_interval(v)
        row["peak_at_sd_mm"] = 1e3 * float(np.std(g["shear_disp_at_peak"].to_numpy(float), ddof=1))
        rows.append(row)
    return pd.DataFrame(rows)


def study_soil():
    """(summaries, curve store) of the study's own 40 × 25 soil test on all its 40 seeds (the
    committed sequential study, docs/reproduction/precision/study). Seeds 1–8 are the 40 × 25 cell's
    here; the 40 say how far those eight stand from the soil's mean, and are the reference a larger
    cell's soil is compared and priced against (its SD known to ±25 %, not to a factor of two)."""
    d = ROOT / "docs" / "reproduction" / "precision" / "study"
    summ = pd.read_csv(d / "summaries.csv", dtype={"case_id": str, "pair_id": str})
    return summ[summ["test"].eq("box") & summ["gradation"].eq("poly")], CommittedCurves(d / "curves.parquet")


def changes(seeds: pd.DataFrame, soil40: pd.DataFrame) -> pd.DataFrame:
    """Every cell against the study's 40 × 25 (`campaign compare`'s Welch difference and verdict at its
    tolerances): the soil test against its 40 seeds, each surface against its 8."""
    ref = seeds[(seeds["box_length_d50"] == REFERENCE[0]) & (seeds["box_height_d50"] == REFERENCE[1])]
    ref = pd.concat([ref[ref["test"].ne("box")], soil40], ignore_index=True)
    out = [compare(ref, g).assign(length=cell[0], height=cell[1])
           for cell, g in seeds.groupby(CELL, sort=True) if cell != REFERENCE]
    return pd.concat(out, ignore_index=True)


def efficiencies(seeds: pd.DataFrame, soil40: pd.DataFrame) -> pd.DataFrame:
    """E as the study's tables read it, a ratio of means (tan δ's over the cell's soil test's, with
    `ratio_interval`), at the peak and at the critical state, per cell and surface; at 40 × 25 over
    the soil's 40 seeds, so that seeds 1–8's low draw does not stand for the cell."""
    rows = []
    for (length, height), c in seeds.groupby(CELL, sort=True):
        soil = soil40 if (length, height) == REFERENCE else c[c["test"].eq("box")]
        for case, g in c[c["test"].eq("interface")].groupby("case", sort=True):
            row = dict(length=length, height=height, case=case)
            for name, col in (("E", "peak"), ("E_cs", "critical")):
                a, b = g[col].to_numpy(float), soil[col].to_numpy(float)
                row[name] = a.mean() / b.mean()
                row[f"{name}_lo"], row[f"{name}_hi"] = (float(x) for x in ratio_interval(
                    a.mean(), a.std(ddof=1), a.size, b.mean(), b.std(ddof=1), b.size))
            rows.append(row)
    return pd.DataFrame(rows)


def surface_name(case: str) -> str:
    """'soil', 'rt0.2', 'rt1' or the case as it is (the study's soil row)."""
    if case.startswith("study"):
        return case
    m = re.search(r"rt[\d.]+", case)
    return m.group(0) if m else "soil"


def price(t: pd.DataFrame) -> pd.DataFrame:
    """sd² × wall per run of each row over the same case's at 40 × 25: a size's relative core-hours
    for a given half-width (same quantity, same surface)."""
    t = t.copy()
    t["surface"] = t["case"].map(surface_name)
    ref = t[(t["length"] == REFERENCE[0]) & (t["height"] == REFERENCE[1])].set_index(["surface", "quantity"])
    key = list(zip(t["surface"], t["quantity"]))
    t["sd_ratio"] = t["sd"].to_numpy() / ref["sd"].reindex(key).to_numpy()
    t["wall_ratio"] = t["wall_s"].to_numpy() / ref["wall_s"].reindex(key).to_numpy()
    t["price_ratio"] = t["sd_ratio"] ** 2 * t["wall_ratio"]
    return t


def study_bill(t: pd.DataFrame, trials: int) -> None:
    """The study at E ± 0.05 with each size (analysis.seed_draws.project on scaled populations)."""
    study = pd.read_csv(REPRO / "summaries.csv")
    pops = populations(study, CommittedCurves(REPRO / "curves.parquet"))
    times, box_time, today, _ = run_times(study)
    soils = len({p["b"].tobytes() for p in pops})
    print("\n| cell [D50] | interface sd × | soil sd × | wall × (interface, soil) | cap | soil seeds | cases reaching ± 0.05 | mean seeds | core-hours |")
    print("|---|---|---|---|---|---|---|---|---|")
    for (length, height), c in t.groupby(["length", "height"], sort=True):
        iface = c[(c["test"] == "interface") & (c["quantity"] == "tan_delta")]
        soil = c[c["test"] == "box"]
        if iface.empty or soil.empty:
            continue
        ka, kb = float(iface["sd_ratio"].mean()), float(soil["sd_ratio"].iloc[0])
        wa, wb = float(iface["wall_ratio"].mean()), float(soil["wall_ratio"].iloc[0])
        scaled = [dict(p, a=p["a"].mean() + ka * (p["a"] - p["a"].mean()), b=p["b"].mean() + kb * (p["b"] - p["b"].mean()))
                  for p in pops]
        for cap, m in ((24, 40), (24, 80), (48, 80)):
            r = project(scaled, {k: v * wa for k, v in times.items()}, "E", 0.05, cap, m, trials,
                        np.random.default_rng(1))
            h = r["hours"] + soils * m * box_time * wb / 3600
            print(f"| {length:g} × {height:g} | {ka:.2f} | {kb:.2f} | {wa:.2f}, {wb:.2f} | {cap} | {m} "
                  f"| {r['reached']:.0%} | {r['seeds']:.1f} | {h:.0f} |")


def strengths(seeds: pd.DataFrame, soil40: pd.DataFrame) -> None:
    """What each cell reads (three readings of strength), E as the study reads it, and each cell
    against 40 × 25: the tables docs/convergence.md "Cell size" quotes (`cell_seeds` of the campaigns'
    runs and of the study's soil test)."""
    print("\nWhat each cell reads (mean of the seeds, 95 % t interval), by three readings of a run's strength:")
    print("\n| cell [D50] | test | seeds | leave-one-out peak | run's own maximum | critical state | SD of where runs peak [mm] |")
    print("|---|---|---|---|---|---|---|")
    lv = pd.concat([levels(seeds), levels(soil40).assign(case="study soil, every seed")], ignore_index=True)
    for r in lv.sort_values(["test", "case", "length", "height"]).itertuples():
        cells = " | ".join(f"{getattr(r, k):.3f} ({getattr(r, k + '_lo'):.3f}–{getattr(r, k + '_hi'):.3f})"
                           for k in ("loo_peak", "own_max", "critical"))
        print(f"| {r.length:g} × {r.height:g} | {surface_name(r.case)} | {r.seeds} | {cells} | {r.peak_at_sd_mm:.2f} |")
    print("\nE as the study's tables read it (ratio of the seed means; at 40 × 25 over the soil's 40 seeds):")
    print("\n| cell [D50] | surface | E at the peak (95 %) | E critical (95 %) |")
    print("|---|---|---|---|")
    for r in efficiencies(seeds, soil40).sort_values(["case", "length", "height"]).itertuples():
        print(f"| {r.length:g} × {r.height:g} | {surface_name(r.case)} | {r.E:.3f} ({r.E_lo:.3f}–{r.E_hi:.3f}) "
              f"| {r.E_cs:.3f} ({r.E_cs_lo:.3f}–{r.E_cs_hi:.3f}) |")
    print("\nEach cell against the study's 40 × 25 (the soil test against its 40 seeds; Welch 95 %, "
          "`campaign compare`'s tolerances):")
    print("\n| cell [D50] | test | quantity | 40 × 25 | this cell | change (95 %) | verdict |")
    print("|---|---|---|---|---|---|---|")
    for r in changes(seeds, soil40).sort_values(["case", "metric", "length"]).itertuples():
        if r.metric in ("theta_r_deg", "surface_contacts_per_d50"):
            continue
        print(f"| {r.length:g} × {r.height:g} | {surface_name(r.case)} | {r.metric} | {r.ref:.3f} ({r.n_ref}) "
              f"| {r.value:.3f} ({r.n_value}) | {r.change:+.3f} ({r.change_lo:+.3f} to {r.change_hi:+.3f}) | {r.verdict} |")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--save", action="store_true", help="write each campaign's runs to its committed copy")
    ap.add_argument("--trials", type=int, default=2000)
    args = ap.parse_args(argv)
    # a cell belongs to one campaign, so its rows are read on that campaign's own runs and store
    read = [r for r in (load(c, d, args.save) for c, d in CAMPAIGNS.items()) if r is not None]
    seeds = [cell_seeds(*r) for r in read]          # the leave-one-out peaks, read once
    rows = pd.concat([cell_rows(r[0], sd) for r, sd in zip(read, seeds)], ignore_index=True)
    soil_summ, soil_store = study_soil()
    soil_seeds = cell_seeds(soil_summ, soil_store)
    # the 40 x 25 soil row from its 40 seeds; its wall stays the one timed here (the study's ran elsewhere)
    ref = (rows["length"] == REFERENCE[0]) & (rows["height"] == REFERENCE[1]) & rows["test"].eq("box")
    soil40 = cell_rows(soil_summ, soil_seeds).assign(wall_s=rows.loc[ref, "wall_s"].iloc[0],
                                                     wall_here=rows.loc[ref, "wall_here"].iloc[0])
    t = price(pd.concat([rows[~ref], soil40], ignore_index=True))
    print("| cell [D50] | test | quantity | seeds | mean (95 %) | SD per seed (95 %) | wall per run [s] | SD × | wall × | price × (sd² × wall) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in t.sort_values(["surface", "quantity", "length"]).itertuples():
        print(f"| {r.length:g} × {r.height:g} | {r.surface} | {r.quantity} | {r.seeds} "
              f"| {r.mean:.3f} ({r.mean_lo:.3f}–{r.mean_hi:.3f}) | {r.sd:.4f} ({r.sd_lo:.4f}–{r.sd_hi:.4f}) "
              f"| {r.wall_s:.0f}{'' if r.wall_here else ' *'} | {r.sd_ratio:.2f} | {r.wall_ratio:.2f} | {r.price_ratio:.2f} |")
    if not t["wall_here"].all():
        print("\n\\* wall of restored runs only, made on another machine: its wall × and price × compare machines, "
              "not sizes, until a run of that cell and test is made here")
    strengths(pd.concat(seeds, ignore_index=True), soil_seeds)
    study_bill(t, args.trials)


if __name__ == "__main__":
    main()
