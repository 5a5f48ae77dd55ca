"""`campaign report`: every table, figure and the HTML page of a campaign, and the fitted criterion
model `campaign predict --fit` uses.

Output folder (default: the campaign's output folder + "/report"):
  tables/   table_6_1_inputs, table_6_2_random (if any), results_<group>, correlations, lab_comparison
            — each .csv, .md, .tex (LaTeX: plain ASCII, booktabs); tables_preview.tex \\input's them all
  figures/  fig6_3, fig6_5, fig6_6, fig6_7, fig6_8, fig6_9, fig6_10a, (fig6_10b_lab), curves_<group>,
            network_<case> — each .png (300 dpi) and .pdf (networks: PNG); a figure with nothing to
            draw (Fig. 6.9 without flat-spaced surfaces) is left out and the page says why
  correlations.json   the fits (BilinearFit.to_dict rows)
  index.html          links them all
Seeds: every figure, results table and fit is per PHYSICAL case (its seeds share a physical_id,
interphase.case.physical_id; it is named by its label without `-sN`): the
mean over its seeds with a 95 % interval (tan δ, tan φ and E those of the ensembles table), fits with
the seed bootstrap (analysis.correlations.seed_ensemble, fit_study; docs/methods.md §7).
Memory: only the summaries table and, per figure, one case's series or contacts at a time are read.
Code: `analyse(summaries, …) → ReportModel` computes everything and writes nothing; `write(model, out)`
draws and writes it. The summaries and curves tables it writes are the campaign's result format
(campaign.results).
"""

from __future__ import annotations

import datetime as _dt
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.analysis.correlations import SPECS, SeedEnsemble, fit_study, prepare_points, seed_ensemble
from interphase.analysis.criterion import (CriterionModel, check_cases, check_summary, fit_rule, fitted_soil_tan_phi,
                                           held_out_errors, skill)
from interphase.analysis.ensemble_table import ensemble_tables
from interphase.analysis.soil_test import soil_test_readings
from interphase.campaign.results import open_campaign, recipe_notes, write_curves, write_summaries
from interphase.errors import InputError
from interphase.report import figures as F
from interphase.report import tables as T
from interphase.report.html import html_table
from interphase.version import __version__

MAX_CURVES = 60            # stress-ratio curves per group figure (more become unreadable)
NETWORK_CASES = 2          # force networks: the strongest and the weakest interface case
MAX_POLAR = 4              # Fig. 6.6 panels


@dataclass
class ReportResult:
    folder: Path
    files: list[Path] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    fits: list = field(default_factory=list)
    points: pd.DataFrame | None = None        # one row per physical case (SeedEnsemble.points): what is plotted
    ensembles: pd.DataFrame | None = None     # one row per physical case (analysis.ensemble_table)
    runs: pd.DataFrame | None = None          # one row per run (prepare_points), for the force networks
    ensemble: SeedEnsemble | None = None
    criterion_check: pd.DataFrame | None = None   # criterion_checks: the chain against every case
    not_drawn: list = field(default_factory=list)   # (figure title, why) of figures with nothing to draw


def ensemble_points(summaries: pd.DataFrame, store=None, *, e_note: float = 1.2) -> tuple[SeedEnsemble, pd.DataFrame | None]:
    """The physical cases' points and their seed ensemble, and the ensembles table (None without a
    store: then tan δ is the mean of the runs' own peaks and E the ratio of seed means)."""
    runs = prepare_points(summaries)
    table, states, pools = None, None, None
    if store is not None:
        table, states, pools = ensemble_tables(summaries, store, e_note=e_note)
    return seed_ensemble(runs, states, table, box_pools=pools), table


CHECK_COLUMNS = {"fold": "fold", "group": "group", "physical_case": "case", "friction_ps": "μs",
                 "theta_a_deg_92": "θa (> 92°) [°]", "branch": "branch", "theta_r_measured": "θr measured [°]",
                 "theta_r_predicted": "θr predicted [°]", "E_measured": "E measured", "E_predicted": "E predicted",
                 "tan_phi": "tan φ", "delta_measured_deg": "δ measured [°]", "delta_predicted_deg": "δ predicted [°]",
                 "error_deg": "error [°]", "note": "note"}


def criterion_checks(chain: CriterionModel, points: pd.DataFrame) -> pd.DataFrame | None:
    """check_cases with the campaign's own fits (fold 'in-sample') and, when there are at least two
    groups and the cases left without any one group still fit θa–θr per friction (MIN_POINTS at each
    friction), with fits made WITHOUT each group on that group (fold 'group held out': the criterion
    predicting surfaces it has not seen, as a user's new surface). Otherwise (one group, or a Group 1
    design with a few measured or flat surfaces beside it) each surface is held out instead, all its
    frictions together (fold 'surface held out', surfaces told apart by θa > 92°, a flat at 0); the
    lowest and highest θa are then outside the other surfaces' fits and stay unpredicted. The
    two-constant rule is fitted on the same cases in each fold (fit_rule). None without θa–θr and
    E–θr fits."""
    from interphase.analysis.correlations import MIN_POINTS, fit_study

    if not chain.theta_r or chain.efficiency is None or points.empty:
        return None
    folds = [check_cases(chain, points, fit_rule(points)).assign(fold="in-sample")]
    groups = points["group"].astype(str)
    surface = pd.to_numeric(points["theta_a_deg_92"], errors="coerce").round(6)
    friction = pd.to_numeric(points["friction_ps"], errors="coerce")
    fittable_without = lambda g: bool((friction[groups != g].value_counts() >= MIN_POINTS).all()
                                      and friction[groups != g].nunique() == friction.nunique())
    if groups.nunique() >= 2 and all(fittable_without(g) for g in groups.unique()):
        held = [(groups == g, f"without {g}", "group held out") for g in sorted(groups.unique())]
    elif surface.nunique() >= 3:
        held = [(surface == a, f"without θa {a:.1f}°", "surface held out") for a in sorted(surface.dropna().unique())]
    else:
        held = []
    keys = [SPECS[k] for k in ("fig6_8", "fig6_9", "fig6_10a")]
    for out, source, fold in held:
        rest = points[~out]
        model = criterion_from_fits(fit_study(rest, keys, n_boot=0), rest, source)
        folds.append(check_cases(model, points[out], fit_rule(rest)).assign(fold=fold))
    return pd.concat(folds, ignore_index=True)


def check_notes(checks: pd.DataFrame) -> list[str]:
    """One line per fold: the error distribution in degrees of δ and the largest miss."""
    notes = ["error = δ predicted − δ measured [°], δ = atan(tan δ) at the peak, seed means; predicted tan δ = "
             "E(θr(θa)) × the case's own tan φ. The study: < 4° against the lab."]
    for fold, g in checks.groupby("fold", sort=False):
        s = check_summary(g)
        if not s["n"]:
            notes.append(f"{fold}: no case the chain could take ({s['n_without']} without)")
            continue
        notes.append(f"{fold}: {s['n']} cases, error {s['mean']:+.2f}° ± {s['sd']:.2f}° (mean ± sd), 5–95 % "
                     f"{s['p5']:+.2f}° to {s['p95']:+.2f}°, {100 * s['within_4deg']:.0f} % within 4°, largest miss "
                     f"{s['max_abs']:.2f}° ({s['worst_case']}, {s['worst_group']})"
                     + (f"; {s['n_without']} case(s) outside the chain's reach" if s["n_without"] else ""))
        notes += _rule_note(fold, g)
        for r in skill(g).itertuples():
            gap = ("" if math.isnan(r.rms_gap_deg) else f"; rms − the criterion's {r.rms_gap_deg:+.2f}° "
                   f"({r.rms_gap_lo:+.2f} to {r.rms_gap_hi:+.2f}°, paired case bootstrap)")
            notes.append(f"{fold}, {r.subset}: {r.predictor}: {r.n} cases, rms {r.rms_deg:.2f}°, "
                         f"{100 * r.within_4deg:.0f} % within 4°" + gap)
    return notes


def _rule_note(fold: str, checks: pd.DataFrame) -> list[str]:
    """The two-constant rule's constants in a fold (held out: their range over the groups or surfaces
    left out)."""
    if "rule_a_deg" not in checks or not checks["rule_a_deg"].notna().any():
        return []
    a, b = checks["rule_a_deg"].dropna(), checks["rule_b"].dropna()
    span = lambda v, f: f"{v.min():{f}}" if v.nunique() == 1 else f"{v.min():{f}} to {v.max():{f}}"
    return [f"{fold}: δ = min(φμ + θa − a, atan(b tan φ)) fitted on the same cases as the criterion"
            f"{'' if fold == 'in-sample' else ' (without each ' + fold.split()[0] + ')'}: a = {span(a, '.2f')}°, "
            f"b = {span(b, '.3f')}"]


def write_criterion(model: CriterionModel, points: pd.DataFrame, path: Path, prov: str) -> Path:
    """criterion.json: the fitted chain with its seed-bootstrap refits and what it was fitted on
    (`campaign predict --fit FILE.json` reads it; the package ships the reproduction's)."""
    col = lambda c: points[c] if c in points else pd.Series(dtype=object)
    about = {"provenance": prov, "physical_cases": int(len(points)),
             "interface_runs": int(pd.to_numeric(col("seeds"), errors="coerce").fillna(1).sum()) if len(points) else 0,
             "groups": sorted(map(str, col("group").dropna().unique())),
             "frictions": sorted(float(x) for x in pd.to_numeric(col("friction_ps"), errors="coerce").dropna().unique())}
    path.write_text(json.dumps(model.to_dict(about), indent=1, allow_nan=False) + "\n")
    return path


def criterion_from_fits(fits, points: pd.DataFrame, source: str) -> CriterionModel:
    """The criterion's chain from fit_study's results (the fits the report draws, seed-bootstrap
    intervals included), as CriterionModel.from_points would fit them."""
    pick = lambda key, sl="all": next((f for f in fits if f.spec.key == key and f.slice == sl), None)
    reasons, theta_r = {}, {}
    for f in fits:
        if f.spec.key == "fig6_8" and f.fit is not None:
            theta_r["all" if f.slice == "all" else float(f.slice.split("=")[1])] = f.fit
    if "all" not in theta_r and pick("fig6_8") is not None:
        reasons["fig6_8"] = pick("fig6_8").reason
    out = {}
    for key in ("fig6_9", "fig6_10a"):
        f = pick(key)
        out[key] = f.fit if f is not None else None
        if f is not None and f.fit is None:
            reasons[key] = f.reason
    a, b = fit_rule(points)
    return CriterionModel(source=source, tan_phi=fitted_soil_tan_phi(points), theta_r=theta_r,
                          ratio=out["fig6_9"], efficiency=out["fig6_10a"], reasons=reasons,
                          rule=(a, b) if math.isfinite(a) else None)


def provenance(store=None, summaries: pd.DataFrame | None = None) -> str:
    """One line: package, engine builds and recipe ids of the cases, report template hash, date (UTC)."""
    from interphase.report.html import template_hash

    engines, thash = set(), set()
    if store is not None and summaries is not None and "case_id" in summaries:
        for cid in summaries["case_id"].astype(str):
            try:
                meta = json.loads((store.case_folder(cid) / "case.json").read_text())
            except (OSError, ValueError):
                continue
            prov = meta.get("provenance") or {}
            engines.add(str(prov.get("engine_version") or meta.get("engine_version") or meta.get("engine") or "?"))
            rid = prov.get("recipe_id") or meta.get("recipe_id") or meta.get("template_hash")   # older folders
            if rid:
                thash.add(str(rid))
    if not engines and summaries is not None:       # no case folders (committed tables): the summaries' columns
        col = next((c for c in ("engine_version", "engine") if c in summaries), None)
        engines |= set(summaries[col].dropna().astype(str)) if col else set()
        thash |= set(summaries["recipe_id"].dropna().astype(str)) if "recipe_id" in summaries and not thash else set()
    today = _dt.datetime.now(_dt.timezone.utc).date().isoformat()
    return (f"interphase-dem {__version__}; engine {', '.join(sorted(engines)) or 'unknown'}; "
            f"recipe {', '.join(sorted(thash)) or 'unknown'}; report template {template_hash()}; {today}")


def _profiles_for_polar(campaign, points) -> list[tuple[str, object]]:
    """Up to MAX_POLAR distinct dilative-looking profiles: one per group first (the study's 6.6 picks a
    Group 1 saw-tooth, a Group 2 spaced one, a random one and a measured one)."""
    from interphase.surface.builder import from_spec

    chosen, seen = [], set()
    if campaign is None:
        return chosen
    cases = [c for c in campaign.cases if c.role != "box" and c.case.profile is not None and c.case.profile.kind != "flat"]
    by_group: dict = {}
    for c in cases:
        by_group.setdefault(c.group, []).append(c)
    order = [g[len(g) // 2] for g in by_group.values()] + cases
    for c in order:
        spec = c.case.profile
        key = (spec.kind, spec.params, spec.path)
        if key in seen:
            continue
        seen.add(key)
        d50 = c.case.d50
        try:
            prof = from_spec(spec, d50, min(c.case.box_length_d50, 40.0) * d50)
        except InputError:
            continue
        label = f"{c.group}: {spec.kind} " + ", ".join(f"{k}={v:g}" for k, v in spec.params if k != "seed")
        chosen.append((label, prof))
        if len(chosen) >= MAX_POLAR:
            break
    return chosen


def curve_panels(rows: pd.DataFrame) -> dict[str, str]:
    """{label: its panel in the curves figure}: interface runs by friction (and gradation where the
    rows have both), box tests by gradation."""
    grads = rows.get("gradation", pd.Series("", index=rows.index)).fillna("").astype(str)
    both = grads.nunique() > 1
    out = {}
    for r, grad in zip(rows.itertuples(index=False), grads):
        if str(getattr(r, "test", "")) == "box":
            out[str(r.label)] = f"box test, {grad}" if grad else "box test"
            continue
        mu = pd.to_numeric(getattr(r, "friction_ps", math.nan), errors="coerce")
        name = f"tan φμ = {mu:g}" if math.isfinite(mu) else "interface"
        out[str(r.label)] = f"{name}, {grad}" if both and grad else name
    return out


def _curves(store, rows: pd.DataFrame) -> dict[str, pd.DataFrame]:
    out = {}
    for r in rows.head(MAX_CURVES).itertuples(index=False):
        path = store.case_folder(str(r.case_id)) / "series.parquet"
        try:
            s = pd.read_parquet(path, columns=None)
        except (OSError, ValueError):
            continue
        if "shear_disp" in s and "stress_ratio" in s:
            keep = [c for c in ("shear_disp", "stress_ratio", "stress_ratio_smooth") if c in s]
            out[str(r.label)] = s[keep]
    return out


#: the lab comparison table: analysis.validation.predict_rows columns → headings
LAB_COLUMNS = {"row": "line", "soil": "soil", "surface": "surface", "normal_stress_kpa": "σn [kPa]",
               "theta_a_deg": "θa [°]", "friction": "tan φμ [-]", "phi_deg": "φ [°]", "phi_from": "φ from",
               "delta_measured_deg": "δ measured [°]", "delta_predicted_deg": "δ predicted [°]",
               "delta_lo_deg": "δ lo [°]", "delta_hi_deg": "δ hi [°]", "error_predicted_deg": "error [°]",
               "error_soil_deg": "error, δ = φ [°]", "error_rule_deg": "error, δ = min(φμ + θa, φ) [°]",
               "error_fitted_rule_deg": "error, δ = min(φμ + θa − a, atan(b tan φ)) [°]",
               "source": "source", "table_or_figure": "table or figure", "note": "note"}


@dataclass
class ReportModel:
    """What a report says, computed from the runs and nothing written (`analyse`); `write` draws and
    writes it."""

    summaries: pd.DataFrame
    campaign: object = None
    provenance: str = ""
    ensemble: SeedEnsemble | None = None
    ensembles: pd.DataFrame | None = None     # one row per physical case (analysis.ensemble_table)
    fits: list = field(default_factory=list)
    chain: CriterionModel | None = None       # the criterion fitted on the campaign
    criterion_check: pd.DataFrame | None = None
    lab: pd.DataFrame | None = None           # analysis.validation.predict_rows on the --lab file
    tables: list = field(default_factory=list)   # report.tables.Table, in page order
    warnings: list[str] = field(default_factory=list)
    n_box: int = 0

    @property
    def points(self) -> pd.DataFrame:
        return self.ensemble.points

    @property
    def runs(self) -> pd.DataFrame:
        return self.ensemble.runs


def report_from_summaries(summaries: pd.DataFrame, out: str | Path, *, campaign=None, store=None,
                          lab: str | Path | None = None, n_boot: int = 199, seed: int = 0,
                          title: str | None = None) -> ReportResult:
    """Everything `campaign report` writes, from a summaries table (CampaignStore.summaries() shape):
    `write(analyse(...), out)`. `store` (for curves, networks, provenance) and `campaign` (input
    tables, Fig. 6.6) are optional."""
    lab_table = None
    if lab is not None:            # a bad lab file fails before anything is written
        from interphase.lab import read_lab

        lab_table = read_lab(lab)
    model = analyse(summaries, campaign=campaign, store=store, lab_table=lab_table, n_boot=n_boot, seed=seed)
    return write(model, out, store=store, title=title)


def analyse(summaries: pd.DataFrame, *, campaign=None, store=None, lab_table=None, n_boot: int = 199,
            seed: int = 0) -> ReportModel:
    """The report's content: seed ensembles, fits, the criterion and its checks, every table, the
    warnings. Reads the runs' curves (and case.json for the provenance) from `store`; writes nothing."""
    m = ReportModel(summaries, campaign, provenance(store, summaries))
    m.ensemble, m.ensembles = ensemble_points(summaries, store, e_note=T.E_NOTE)
    m.warnings += _cap_warnings(m.ensembles, campaign)
    points = m.points
    m.n_box = int(((summaries.get("test", pd.Series(dtype=str)) == "box")).sum()) if len(summaries) else 0
    if points.empty:
        m.warnings.append("no finished interface case: tables and figures are empty")
    if points["tan_phi"].isna().all() if len(points) else True:
        m.warnings.append("no paired box test finished: efficiency E (Figs 6.5, 6.10a) is undefined")
    m.fits = fit_study(points, n_boot=n_boot, seed=seed, ensemble=m.ensemble)
    m.chain = criterion_from_fits(m.fits, points, f"campaign {campaign.name if campaign else 'report'}")
    m.criterion_check = criterion_checks(m.chain, points)
    m.chain.held_out = held_out_errors(m.criterion_check)
    lab_warning = None
    if lab_table is not None:
        m.lab, lab_warning = _lab_rows(m.chain, lab_table)
    m.tables = _tables(m)
    if lab_warning:
        m.warnings.append(lab_warning)
    return m


def _cap_warnings(ens_table: pd.DataFrame | None, campaign) -> list[str]:
    """Sequential seeds: the ensembles table's note on the cases that stopped at the cap, not the
    target (in place), and the warning line."""
    if campaign is None or getattr(campaign, "seeds", None) is None or ens_table is None or ens_table.empty:
        return []
    from interphase.campaign.sequential import cap_notes

    cap = cap_notes(ens_table, campaign.seeds)
    ens_table["note"] = ["; ".join(x for x in (a, b) if x) for a, b in zip(ens_table["note"].fillna(""), cap)]
    if not cap.ne("").any():
        return []
    return [f"{int(cap.ne('').sum())} physical case(s) hit the seed cap ({campaign.seeds.max}) "
            f"before ± {campaign.seeds.halfwidth:g} in {campaign.seeds.quantity} (ensembles table)"]


def _lab_rows(fitted: CriterionModel, lab_table) -> tuple[pd.DataFrame, str | None]:
    """The laboratory rows predicted by the campaign's criterion, or by the study defaults (and a
    warning saying so) when the campaign has too few points to fit it."""
    from interphase.analysis.validation import predict_rows

    usable = bool(fitted.theta_r) and fitted.efficiency is not None and math.isfinite(fitted.tan_phi)
    warning = None if usable else ("lab comparison uses the STUDY DEFAULTS (the campaign has too few points to "
                                   "fit θa–θr and E–θr)")
    camp_tp = fitted.tan_phi if math.isfinite(fitted.tan_phi) else CriterionModel.study_defaults(0.0).tan_phi
    model_for = (lambda mu: fitted) if usable else (lambda mu: CriterionModel.study_defaults(mu, camp_tp))
    return predict_rows(lab_table, model_for, default_phi=(math.degrees(math.atan(camp_tp)),
                                                           "the campaign's simulated soil")), warning


def _tables(m: ReportModel) -> list:
    """Every table of the page, in order (and the warning on E above T.E_NOTE)."""
    tables: list[T.Table] = []
    if m.campaign is not None:
        tables += T.input_tables(m.campaign)
    tables += T.results_tables(m.points)
    if m.ensembles is not None:
        tables.append(T.ensembles_table(m.ensembles))
        high = m.ensembles[pd.to_numeric(m.ensembles["E"], errors="coerce") > T.E_NOTE]
        if len(high):
            m.warnings.append(f"{len(high)} physical case(s) with seed-ensemble E > {T.E_NOTE:g}: see the note "
                              "column of the ensembles table and docs/strength.md")
    readings = soil_test_readings(m.summaries)
    if not readings.empty:
        tables.append(T.soil_tests_table(readings))
    tables.append(T.coefficient_table(m.fits))
    if m.criterion_check is not None:
        shown = m.criterion_check[list(CHECK_COLUMNS)].rename(columns=CHECK_COLUMNS)
        tables.append(T.Table("criterion_check", "The criterion θa → θr → E against every simulated case",
                              shown, check_notes(m.criterion_check)))
    tables += T.findings_tables(m.points)
    if m.lab is not None:
        tables.append(T.Table("lab_comparison", "Predicted vs measured interface friction angle",
                              m.lab[list(LAB_COLUMNS)].rename(columns=LAB_COLUMNS),
                              ["δ = atan(E·tan φ); tan φ: the laboratory's own soil test where the file gives it, "
                               "else the campaign's simulated soil (column 'φ from'); baselines: δ = φ, "
                               "δ = min(φμ + θa, φ), and δ = min(φμ + θa − a, atan(b tan φ)) with a, b fitted on "
                               "the campaign's cases (docs/validation.md)."]))
    return tables


def short_label(case: str) -> str:
    """A physical case's label without what every case of a campaign shares (the test, the device,
    the gradation's word, the default preparation): 'sawtooth rt1 sw2 sr0, μs 0.2'."""
    parts = [p for p in str(case).split("-") if p not in ("interface", "box", "periodic", "periodic3d", "walled",
                                                            "user", "poly", "mono")]
    mu = next((p for p in parts if p.startswith("mu")), None)
    rest = [p for p in parts if p != mu]
    return " ".join(rest) + (f", μs {mu[2:]}" if mu else "")


def summary_markdown(ensembles: pd.DataFrame, provenance: str) -> str:
    """summary.md: one line per physical case, δ and φ in degrees with their 95 % intervals and E."""
    deg = lambda t: math.degrees(math.atan(t)) if pd.notna(t) else math.nan
    iv = lambda a, b: "" if not (pd.notna(a) and pd.notna(b)) else f" ({a:.1f}–{b:.1f})"
    rows = ["| group | case | seeds | δ [°] | φ of its soil test [°] | E |", "|---|---|---|---|---|---|"]
    for r in ensembles.itertuples():
        e = "" if pd.isna(r.E) else f"{r.E:.2f}" + ("" if pd.isna(r.E_lo) else f" ({r.E_lo:.2f}–{r.E_hi:.2f})")
        rows.append(f"| {r.group} | {short_label(r.case)} | {r.seeds} | {deg(r.tan_delta):.1f}"
                    f"{iv(deg(r.tan_delta_lo), deg(r.tan_delta_hi))} | {deg(r.tan_phi):.1f}"
                    f"{iv(deg(r.tan_phi_lo), deg(r.tan_phi_hi))} | {e} |")
    return ("# Summary: δ, φ and E per physical case (seed ensembles, 95 % intervals)\n\n" + "\n".join(rows)
            + f"\n\n_{provenance}_\n")


def write(m: ReportModel, out: str | Path, *, store=None, title: str | None = None) -> ReportResult:
    """Write a ReportModel to `out`: correlations.json, criterion.json, tables/ (with the summaries
    and curves tables of campaign.results), figures/ and index.html."""
    out = Path(out)
    tdir, fdir = out / "tables", out / "figures"
    tdir.mkdir(parents=True, exist_ok=True)
    fdir.mkdir(parents=True, exist_ok=True)
    res = ReportResult(out, warnings=list(m.warnings), fits=m.fits, points=m.points, ensembles=m.ensembles,
                       runs=m.runs, ensemble=m.ensemble, criterion_check=m.criterion_check)
    (out / "correlations.json").write_text(json.dumps([_clean(fr.row()) for fr in m.fits], indent=1,
                                                      allow_nan=False))
    res.files.append(out / "correlations.json")
    if len(m.summaries):
        res.files.append(write_summaries(m.summaries, tdir / "summaries.csv"))
        curves = write_curves(m.summaries, store, tdir / "curves.parquet")
        if curves is not None:
            res.files.append(curves)
    if m.chain.theta_r or m.chain.ratio is not None or m.chain.efficiency is not None:
        res.files.append(write_criterion(m.chain, m.points, out / "criterion.json", m.provenance))
    if m.ensembles is not None and len(m.ensembles):
        (out / "summary.md").write_text(summary_markdown(m.ensembles, m.provenance))
        res.files.append(out / "summary.md")
    table_entries = []
    for i, t in enumerate(m.tables):
        paths = T.write_table(t, tdir, m.provenance)
        res.files += paths
        table_entries.append({"title": t.title, "files": [p.relative_to(out).as_posix() for p in paths],
                              "inline": t.name.startswith(("table_", "correlations", "lab_", "ensembles")),
                              "html": html_table(t.df, t.notes), "anchor": f"table-{i}"})
    res.files.append(T.write_preview(m.tables, tdir))
    figs, res.not_drawn = _figures(m, fdir, store, res)
    for _, paths in figs:
        res.files += paths
    res.files.append(_page(m, out, figs, table_entries, res, title))
    return res


def _figures(m: ReportModel, fdir: Path, store, res: ReportResult) -> tuple[list, list]:
    """(figures drawn as (title, [png, pdf]), figures left out as (title, why))."""
    points, fits, summaries = m.points, m.fits, m.summaries
    figs: list[tuple[str, list[Path]]] = []
    not_drawn: list[tuple[str, str]] = []        # (title, why): a figure with nothing to draw is left out

    def add(title, paths, why=""):
        if paths:
            figs.append((title, paths))
        else:
            not_drawn.append((title, why or "nothing to draw"))

    corr = lambda keys, name, head: F.correlation_figure(points, fits, keys, name, fdir, head)
    corr_why = lambda keys: F.empty_reason(points, keys)
    fig3 = ["fig6_3a", "fig6_3b", "fig6_3c", "fig6_3d"]
    add("Fig. 6.3: strength vs θn and θr at the surface (a, b) and in the sampling region (c, d)",
        corr(fig3, "fig6_3", "Fig. 6.3: peak stress ratio vs principal directions θn, θr"), corr_why(fig3))
    add("Fig. 6.5: stress ratio and E vs Rnc(D50)", F.figure_6_5(points, fdir), F.rnc_reason(points))
    d50 = float(pd.to_numeric(summaries.get("d50", pd.Series([0.7e-3])), errors="coerce").dropna().median()) \
        if len(summaries) else 0.7e-3
    add("Fig. 6.6: polar distributions of centroid-trace normals",
        F.figure_6_6(_profiles_for_polar(m.campaign, points), d50 if math.isfinite(d50) else 0.7e-3, fdir),
        "no surface profile (the campaign file was not given, or it has only flat surfaces)")
    add("Fig. 6.7: peak stress ratio vs θa, both filters",
        corr(["fig6_7a", "fig6_7b"], "fig6_7", "Fig. 6.7: peak stress ratio vs θa"), corr_why(["fig6_7a", "fig6_7b"]))
    add("Fig. 6.8: θr vs θa per friction", corr(["fig6_8"], "fig6_8", "Fig. 6.8: θr vs θa (> 92°)"),
        corr_why(["fig6_8"]))
    add("Fig. 6.9: θr/θa vs θa for flat-spaced surfaces",
        corr(["fig6_9"], "fig6_9", "Fig. 6.9: flat-spaced surfaces"), corr_why(["fig6_9"]))
    add("Fig. 6.10a: efficiency vs θr", corr(["fig6_10a"], "fig6_10a", "Fig. 6.10a: failure criterion E(θr)"),
        corr_why(["fig6_10a"]))
    if m.criterion_check is not None:
        add("The criterion against every simulated case: δ predicted vs measured",
            F.criterion_check_figure(m.criterion_check, fdir))
    if m.lab is not None:
        add("Fig. 6.10b: laboratory data with the simulations", F.lab_figure(points, m.lab, fdir))
    if store is not None:
        allrows = summaries.copy()
        allrows["group"] = allrows.get("group", "").astype(str)
        for grp, g in allrows.groupby("group", sort=True):
            curves = _curves(store, g.sort_values("label"))
            if curves:
                add(f"Stress ratio vs shear displacement, {grp}",
                    F.stress_curves(curves, f"Stress ratio vs shear displacement: {grp} ("
                                    + (f"{len(curves)} runs" if len(curves) == len(g) else
                                       f"the first {len(curves)} of {len(g)} runs by label") + ")",
                                    f"curves_{T._safe(grp)}", fdir, curve_panels(g)))
        figs += _networks(store, m.runs, fdir, res, m.campaign)
    return figs, not_drawn


def _page(m: ReportModel, out: Path, figs: list, table_entries: list, res: ReportResult, title: str | None) -> Path:
    """index.html: the tables, the figures, what was not drawn and the warnings."""
    from markupsafe import Markup

    from interphase.report.html import render_page

    fig_entries = [{"title": t, "png": p[0].relative_to(out).as_posix(),
                    "pdf": p[1].relative_to(out).as_posix() if len(p) > 1 else None, "anchor": f"fig-{i}",
                    "width": _shown_width(p[0])} for i, (t, p) in enumerate(figs)]
    for e in table_entries:
        e["html"] = Markup(e["html"])
    name = m.campaign.name if m.campaign else "campaign"
    return render_page(out / "index.html", title=title or f"Report: {name}", provenance=m.provenance,
                       n_cases=len(m.runs), n_box=m.n_box, warnings=res.warnings, tables=table_entries,
                       figures=fig_entries, not_drawn=res.not_drawn)


def _networks(store, points: pd.DataFrame, fdir: Path, res: ReportResult, campaign=None) -> list:
    """Force network at the peak snapshot (summary `peak_snapshot`) of the strongest and the weakest
    interface case: grains to scale, the surface as sheared, the window (report.network)."""
    from interphase.report.network import case_network, run_case

    out = []
    cand = points.assign(_p=pd.to_numeric(points.get("peak_stress_ratio"), errors="coerce")).dropna(subset=["_p"])
    if "test" in cand:
        cand = cand[cand["test"].astype(str) == "interface"]
    if cand.empty or "peak_snapshot" not in cand:
        return out
    cand = cand.sort_values("_p")
    chosen = [cand.iloc[-1]] + ([cand.iloc[0]] if len(cand) > 1 else [])
    for r in chosen[:NETWORK_CASES]:
        folder = store.case_folder(str(r["case_id"]))
        snap = r.get("peak_snapshot")
        if not (folder / "contacts.parquet").exists() or snap is None or \
                (isinstance(snap, float) and not math.isfinite(snap)):
            res.warnings.append(f"no force network for {r['label']}: no contacts.parquet or peak snapshot")
            continue
        png = fdir / f"network_{T._safe(r['label'])}.png"
        case = run_case(folder, campaign, str(r["label"]))
        if case is None:
            res.warnings.append(f"force network of {r['label']} drawn without its surface: its Case could not be rebuilt")
        try:
            case_network(folder, int(snap), png, case=case, title=f"{r['label']}\npeak: snapshot {int(snap)}, "
                         f"tan δ = {r['_p']:.3f}")
        except InputError as exc:
            res.warnings.append(f"no force network for {r['label']}: {exc}")
            continue
        out.append((f"Force network at peak: {r['label']} (tan δ = {r['_p']:.3f})", [png]))
    return out


def build_animations(campaign_path: str | Path, keys, out: str | Path | None = None,
                     output: str | Path | None = None) -> list[Path]:
    """`campaign report --animate`: for each label or case id in `keys`, <out>/figures/
    animation_<label>.gif (report.network.animate_case). An unknown key fails (InputError) before
    anything is drawn."""
    from interphase.report.network import animate_case, find_run, run_case

    campaign, store, summ = open_campaign(campaign_path, output)
    try:
        rows = [find_run(summ, k) for k in keys]
        fdir = Path(out or Path(campaign.output) / "report") / "figures"
        paths = []
        for r in rows:
            folder = store.case_folder(str(r["case_id"]))
            label = str(r["label"])
            paths.append(animate_case(folder, fdir / f"animation_{T._safe(label)}.gif",
                                      case=run_case(folder, campaign, label), title=label))
    finally:
        store.close()
    return paths


#: CSS pixels per inch of figure on the page: a figure keeps its drawn proportions to the text (a one-panel
#: figure is not blown up to the page's width; max-width still shrinks a wide one to fit)
PAGE_PX_PER_INCH = 120


def _shown_width(png: Path) -> int:
    """The width [CSS px] a figure's PNG is shown at: its size in inches (DPI from the file, else
    figures.DPI) × PAGE_PX_PER_INCH."""
    from PIL import Image

    with Image.open(png) as im:
        dpi = float((im.info.get("dpi") or (F.DPI,))[0]) or F.DPI
        return int(round(im.size[0] / dpi * PAGE_PX_PER_INCH))


def _clean(d: dict) -> dict:
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else
                v.item() if isinstance(v, np.generic) else v) for k, v in d.items()}


def build_report(campaign_path: str | Path, out: str | Path | None = None, lab: str | Path | None = None,
                 n_boot: int = 199, output: str | Path | None = None, engines=None) -> ReportResult:
    """The report of a campaign's finished runs (`engines`: as results.open_campaign) in `out`
    (default RUNS/report). A report already there is never replaced: a given `out` that holds one is
    refused (InputError, a new name suggested); the default folder moves on to report-2, report-3, …"""
    given = _report_folder(out, None) if out is not None else None     # refused before the runs are read
    campaign, store, summ = open_campaign(campaign_path, output, engines)
    folder = given or _report_folder(None, Path(campaign.output) / "report")
    try:
        res = report_from_summaries(summ, folder, campaign=campaign, store=store,
                                    lab=lab, n_boot=n_boot)
    finally:
        store.close()
    res.warnings.extend(recipe_notes(summ.attrs))
    return res


def _report_folder(out, default: Path) -> Path:
    from interphase.campaign.folders import next_free

    taken = lambda p: p.is_dir() and any(p.iterdir())
    if out is None:
        folder = default
        n = 2
        while taken(folder):
            folder, n = default.with_name(f"{default.name}-{n}"), n + 1
        return folder
    if taken(Path(out)):
        raise InputError(f"{out} is not empty; what it holds is kept", where=f"-o {out}",
                         fix=f"write the report to a new folder, e.g. -o {next_free(out)}")
    return Path(out)


def fitted_model(campaign_path: str | Path, n_boot: int = 199) -> CriterionModel:
    """The criterion's correlations fitted on a campaign's finished cases (for `campaign predict --fit`)."""
    campaign, store, summ = open_campaign(campaign_path)
    try:
        ens, _ = ensemble_points(summ, store)
    finally:
        store.close()
    chain = [SPECS[k] for k in ("fig6_8", "fig6_9", "fig6_10a")]
    return criterion_from_fits(fit_study(ens.points, chain, n_boot=n_boot, ensemble=ens), ens.points,
                               f"campaign {campaign.name}")
