"""The Python API: what the `campaign` command does, from a script or a notebook.

    import interphase as ip
    c = ip.load_campaign("campaigns/quick.toml")          # validated, nothing runs
    cases = ip.plan(c)                                     # [PlannedCase]: case_id, label, case, ...
    ip.run(c)                                              # RunReport; resumable, as `campaign run`
    ip.status(c)                                           # DataFrame, one row per planned case
    df = ip.summaries(c)                                   # DataFrame, one row per finished run
    ens = ip.ensembles(c)                                  # DataFrame, one row per physical case
    a = ip.predict("profile.csv", soil="soils/karlsruhe-fine-sand.toml", friction=0.3, normal_stress=200e3)
    print(a.paragraph())                                   # Answer: δ, its two intervals and their parts
    d = ip.predict_dem("profile.csv", 0.2, "soils/karlsruhe-fine-sand-2d.toml")  # the DEM instead (runs)
    r = ip.lab_record("lab/soils/karlsruhe-fine-sand/drained-triaxial/TMD11.dat")   # dict: φ_peak, ψ_max, …

Every function takes a campaign file's path or a loaded `Campaign`, and `runs=` where the runs
folder is not the one the file names (`--runs` of the command). Units are SI in every table
(m, Pa, m/s), angles in degrees as the column names say (`*_deg`; ψ from vertical, docs/methods.md);
bad input raises `interphase.errors.InputError` naming the file, the field and the fix.
Nothing heavy is imported until a function is called.
"""

from __future__ import annotations

import os
from pathlib import Path

PathLike = str | os.PathLike


def load_campaign(path: PathLike, runs: PathLike | None = None):
    """Read and check a campaign file (TOML): a `Campaign` with `.name`, `.cases` (every case
    built, or none when `.lazy`: more than 20000, see `plan`), `.size` (the count), `.output` (the
    runs folder: `runs`, else the file's [campaign] output relative to the file, else runs/NAME
    beside it), `.output_from` (which of those) and `.warnings()` (implausible values, unstated
    settings). Nothing runs."""
    from interphase.campaign.schema import load_campaign as _load

    return _load(path, output=runs)


def _campaign(campaign, runs=None):
    from interphase.campaign.schema import Campaign

    if isinstance(campaign, Campaign):
        if runs is not None and Path(runs).resolve() != campaign.output:
            return load_campaign(campaign.path, runs)
        return campaign
    return load_campaign(campaign, runs)


def plan(campaign, engine: str | None = None, *, lazy: bool = False):
    """The planned runs of a campaign: `PlannedCase(case_id, engine, case, group, role, label,
    pair_id, physical_id, params)`, box tests first. The case id hashes the case's inputs, the engine
    and its recipe: the same on every machine; the physical id hashes the inputs without the seed
    (every seed of a case shares it: what the ensembles pool). `lazy=True` gives a generator (any size, built one case at a
    time); else a list. `engine` replaces the file's engines."""
    from interphase.campaign.plan import iter_plan
    from interphase.campaign.plan import plan as _plan

    c = _campaign(campaign)
    engines = (engine,) if engine else None
    return iter_plan(c, engines) if lazy else _plan(c, engines)


def run(campaign, *, runs: PathLike | None = None, engine: str | None = None, executor: str | None = None,
        jobs: int | None = None, rerun_failed: bool = False, dry_run: bool = False, yes: bool = False,
        quiet: bool = False):
    """Run what is not finished (as `campaign run`): returns a `RunReport` (`.statuses` {case id:
    status}, `.exit_code` 0 when every case finished). Progress goes to stdout (`quiet`: nowhere).
    More than 10000 cases need `yes=True`."""
    import io

    from interphase.campaign.run import run_campaign

    c = _campaign(campaign, runs)
    return run_campaign(c.path, output=runs if runs is not None else c.output, engines=(engine,) if engine else None,
                        executor=executor, jobs=jobs, rerun_failed=rerun_failed, dry_run=dry_run, yes=yes,
                        stream=io.StringIO() if quiet else None, live=False)


def status(campaign, *, runs: PathLike | None = None):
    """One row per planned case (as `campaign status --json`): case_id, engine, group, label, role,
    status (pending, done, failed, killed, interrupted, incomplete, corrupt, stale), cause, message,
    elapsed [s], attempts. Raises InputError when the runs folder does not exist."""
    from interphase.campaign.run import campaign_status
    from interphase.errors import InputError

    c = _campaign(campaign, runs)
    if not c.output.is_dir():
        raise InputError(f"the runs folder {c.output} does not exist ({c.output_from})", where=str(c.path),
                         fix="run the campaign first, or give runs= where its runs are")
    return campaign_status(c.path, output=c.output)[2]


def summaries(campaign, *, runs: PathLike | None = None):
    """One row per finished run the campaign file asks for, of one recipe per engine (as the
    report's tables/summaries.csv): the case's parameters (SI) and its summary (peak_stress_ratio,
    tan_delta-like ratios [-], theta_r_*_deg, shear_disp_at_peak [m], …), `pair_id` = its box
    test. Raises InputError when nothing has run."""
    from interphase.campaign.results import open_campaign

    c = _campaign(campaign, runs)
    _, store, rows = open_campaign(c.path, c.output)
    store.close()
    return rows


def ensembles(campaign, *, runs: PathLike | None = None):
    """One row per physical case (its seeds pooled): tan δ, tan φ and E at the peak and at the
    critical state, each with its 95 % interval and the number of seeds (the report's ensembles
    table; docs/methods.md). Raises InputError when nothing has run."""
    from interphase.campaign.results import campaign_ensembles

    c = _campaign(campaign, runs)
    return campaign_ensembles(c.path, c.output)


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

    return _predict(profile, friction=friction, smooth_delta_deg=smooth_delta_deg, soil=soil, fit=fit, d50=d50,
                    tan_phi=tan_phi, normal_stress=normal_stress, relative_density=relative_density, units=units,
                    axis=axis, filt=filt)


def predict_dem(profile: PathLike, friction: float, soil: PathLike, *, seeds: int = 3,
                normal_stress: float = 100e3, runs: PathLike | None = None, jobs: int | None = None,
                units: str | None = None, d50: float | None = None, stream=None) -> dict:
    """The DEM instead of the criterion (as `campaign predict … --soil CARD --simulate --json`): the
    profile as measured sheared with the card's grains at `normal_stress` [Pa] and particle–surface
    `friction`, packing seeds 1…`seeds`, in the cell the card's criterion stands on
    (campaign.validate.interface_case), with the card's soil test; a generated campaign in `runs`
    (default runs/predict/<card>/<profile name> beside the card), resumable. Returns tan δ, E and δ
    with their 95 % intervals, tan φ, the seeds, the cell and the campaign file. A line profile
    only: an areal scan is refused (a campaign can take one line of it)."""
    import sys

    from interphase.campaign.folders import beside, given
    from interphase.campaign.validate import check_dem_request, simulate_profile
    from interphase.errors import InputError
    from interphase.soil import card_d50_mm, load_card
    from interphase.surface.readers import load_profile, read_scan

    check_dem_request(friction, seeds, normal_stress)
    card = load_card(soil)
    card_d50_mm(card, None if d50 is None else d50 * 1e3, "the DEM uses the card's grains", where="d50")
    if read_scan(str(profile), units).areal:
        raise InputError("an areal scan: the DEM shears one line of it", where=str(profile),
                         fix="write a campaign whose profile is one line of the scan, e.g. profile = {kind = \"file\", "
                             f"path = \"{profile}\", axis = \"x\", line = \"1/3\"}} (campaigns/study.toml's Group 5), "
                             "or use the criterion (`campaign predict` without --simulate), which pools every line")
    prof = load_profile(str(profile), units, None)
    out_dir, runs_from = (given(runs, "--runs") if runs else
                          beside(card.path, f"runs/predict/{card.name}/{Path(profile).stem}", "--runs"))
    print(f"predict --simulate: runs folder {out_dir} ({runs_from})", file=stream or sys.stderr, flush=True)
    out = simulate_profile(card, prof.x, prof.z, friction, range(1, seeds + 1), output=out_dir,
                           normal_stress=normal_stress, jobs=jobs, stream=stream)
    return out | {"profile": str(profile), "soil": str(card.path), "friction": friction,
                  "normal_stress": normal_stress}


def element(card: PathLike, normal_stress: float | list[float], seeds: int = 3, *, runs: PathLike | None = None,
            shear_velocity: float | None = None, executor: str | None = None, jobs: int | None = None,
            rerun_failed: bool = False):
    """The element test of a soil card (docs/soils.md) at one or more normal stresses [Pa], packing
    seeds 1…`seeds`, as `campaign element`: a list of dicts with phi_peak_deg, phi_cs_deg,
    psi_max_deg and solid_fraction (each with _lo/_hi, 95 % over the seeds), has_peak, order_psi6
    and a note. `runs`: the runs folder (default runs/element/NAME beside the card);
    `shear_velocity` [m/s] replaces the card's speed. Resumable. Bad input raises InputError before
    anything is written."""
    import math

    from interphase.campaign.element import run_element
    from interphase.errors import InputError
    from interphase.soil import load_card

    stresses = list(normal_stress) if isinstance(normal_stress, (list, tuple)) else [normal_stress]
    for s in stresses:
        if not (isinstance(s, (int, float)) and math.isfinite(s) and s > 0):
            raise InputError(f"must be > 0 Pa, got {s!r}", where="normal_stress", fix="e.g. 100e3")
    if isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1:
        raise InputError(f"must be an integer ≥ 1, got {seeds!r}", where="seeds")
    if shear_velocity is not None and not (math.isfinite(shear_velocity) and shear_velocity > 0):
        raise InputError(f"must be > 0 m/s, got {shear_velocity!r}", where="shear_velocity")
    return [r.to_dict() for r in run_element(load_card(card), stresses, range(1, seeds + 1), output=runs,
                                             executor=executor, jobs=jobs, rerun_failed=rerun_failed,
                                             shear_velocity=shear_velocity)]


def calibrate(target: PathLike, *, quick: bool = False, output: PathLike | None = None,
              runs: PathLike | None = None, executor: str | None = None, jobs: int | None = None,
              rerun_failed: bool = False):
    """Calibrate grain parameters to a laboratory target (docs/soils.md), as `campaign calibrate`;
    writes the soil card and returns what it holds (chosen parameters, posterior, achieved and
    held-out checks). `output`: the card (default [target] card, else soils/NAME.toml beside the
    target; NAME-quick with `quick`); `runs`: every run's folder. A card already there is read back
    when it is this calibration's, else refused (InputError): no card is ever replaced. Resumable."""
    from interphase.campaign.calibrate import calibrate as _calibrate
    from interphase.campaign.calibrate_cell import calibrate_cell, is_cell_target

    fn = calibrate_cell if is_cell_target(target) else _calibrate
    return fn(target, quick=quick, card_path=output, output=runs, executor=executor, jobs=jobs, rerun_failed=rerun_failed)


#: shipped soil cards by a pattern of a laboratory soil's name (soils/ beside the lab file's folder, or
#: of the source tree): the 3D card of a sand that has two; only the sand the card was calibrated on
#: (Ottawa 20/30, the study's, is not Ottawa F-65)
SHIPPED_CARDS = ((r"ottawa\s*f-?65", "ottawa-f65.toml"), (r"karlsruhe", "karlsruhe-fine-sand.toml"))


def _shipped_card(soils, lab_path: Path):
    """The one shipped card whose name matches every soil of a lab file, or None."""
    import re

    found = set()
    roots = (lab_path.resolve().parent / "soils", lab_path.resolve().parent.parent / "soils",
             Path(__file__).resolve().parents[2] / "soils")
    for soil in soils:
        name = next((card for key, card in SHIPPED_CARDS if re.search(key, str(soil).lower())), None)
        found.add(next((r / name for r in roots if name and (r / name).is_file()), None))
    return found.pop() if len(found) == 1 else None


def _validation_card(table, soil, simulate: bool, notes: list):
    from interphase.errors import InputError
    from interphase.soil import load_card

    card = load_card(soil) if soil else None
    if card is None:
        shipped = _shipped_card(sorted(set(table.rows["soil"])), table.path)
        card = load_card(shipped) if shipped else None
        if card is not None:
            notes.append(f"soil card: {card.path} (shipped, chosen by the soil's name; soil= to choose)")
        elif simulate or table.rows["soil_phi_peak"].isna().any():
            raise InputError(f"no single shipped card for the soils {', '.join(sorted(set(table.rows['soil'])))}",
                             where="--soil", fix="give --soil soils/NAME.toml")
    if card is not None and card.quick:
        notes.append(f"soil card {card.path} is a --quick calibration: a first look, not a calibrated soil")
    return card


def validate(lab: PathLike, *, soil: PathLike | None = None, fit: str | None = None, simulate: bool = False,
             seeds: int = 3, output: PathLike | None = None, runs: PathLike | None = None,
             executor: str | None = None, jobs: int | None = None, rerun_failed: bool = False,
             stream=None) -> dict:
    """The criterion (and with `simulate`, the DEM on the soil card) against a laboratory file
    (lab/README.md; docs/validation.md), as `campaign validate`. Returns a dict: table (DataFrame, one
    row per test: δ measured, predicted with its interval, both baselines, errors [°]), skill
    (DataFrame), largest_miss, notes, folder and files written (validation.csv, skill.csv,
    validation.md, validation.png/.pdf under `output`, default runs/validate/<file name> beside the
    lab file; --simulate's runs in `runs`, default runs/validate/<file name>/runs beside it). A
    folder holding another validation is refused (InputError), one holding this same one is kept."""
    from interphase.analysis.validation import largest_miss, predict_rows, skill
    from interphase.campaign.folders import validate_folders
    from interphase.lab import read_lab
    from interphase.criterion_fits import criterion_model

    table = read_lab(lab)
    (out, out_from), (runs_at, runs_from) = validate_folders(table.path, output, runs)
    _check_validation_folder(out)
    notes: list[str] = [f"folder {out} ({out_from})"]
    card = _validation_card(table, soil, simulate, notes)
    models: dict = {}
    model_for = lambda mu: models[mu] if mu in models else models.setdefault(mu, criterion_model(mu, fit))
    df = predict_rows(table, model_for, card)
    notes += sorted({f"criterion: {m.source}" for m in models.values()})
    if simulate:
        from interphase.campaign.validate import simulate as _simulate, with_dem

        notes.append(f"DEM runs in {runs_at} ({runs_from})")
        df = with_dem(df, _simulate(table, card, range(1, int(seeds) + 1), output=runs_at, executor=executor,
                                    jobs=jobs, stream=stream, rerun_failed=rerun_failed))
    sk = skill(df)
    files, kept = _write_validation(out, df, sk)
    return {"lab": str(table.path), "rows": len(df), "folder": out, "folder_from": out_from, "notes": notes,
            "table": df, "skill": sk, "largest_miss": largest_miss(df), "files": files, "kept": kept}


VALIDATION_FILES = ("validation.csv", "skill.csv", "validation.md")


def _check_validation_folder(out: Path) -> None:
    """Refuse a folder that holds anything but a validation (and its runs/): nothing finished is replaced."""
    from interphase.campaign.folders import next_free
    from interphase.errors import InputError

    if not out.is_dir():
        return
    other = [p.name for p in out.iterdir() if p.name != "runs" and p.name not in VALIDATION_FILES
             and not p.name.startswith("validation.")]
    if other:
        raise InputError(f"{out} is not empty and holds no validation ({', '.join(sorted(other)[:3])} …)",
                         where=f"-o {out}", fix=f"give a new or empty folder, e.g. -o {next_free(out)}")


def _write_validation(out: Path, df, sk) -> tuple[list, bool]:
    """Write the tables and the figure into `out`; ([files], kept). A finished validation there is
    kept when it is this one (the same tables), else refused: it is never replaced."""
    from interphase.campaign.folders import next_free
    from interphase.errors import InputError
    from interphase.report.validation import markdown, validation_figure

    cols = {"row": "line", "soil": "soil", "surface": "surface", "normal_stress_kpa": "σn [kPa]", "theta_a_deg": "θa [°]",
            "delta_measured_deg": "δ lab [°]", "delta_predicted_deg": "δ criterion [°]", "delta_lo_deg": "lo",
            "delta_hi_deg": "hi", "error_predicted_deg": "error [°]", "delta_rule_deg": "δ rule [°]",
            "delta_soil_deg": "δ = φ [°]", "delta_fitted_rule_deg": "δ fitted rule [°]"}
    if "delta_dem_deg" in df:
        cols |= {"delta_dem_deg": "δ DEM [°]", "error_dem_deg": "DEM error [°]"}
    texts = {"validation.csv": df.to_csv(index=False), "skill.csv": sk.to_csv(index=False),
             "validation.md": markdown(df, cols) + "\n" + markdown(sk, {
                 "subset": "rows", "prediction": "prediction", "n": "n", "rms_deg": "rms [°]",
                 "max_abs_deg": "max [°]", "within_4": "share within 4°"})}
    held = {name: (out / name).read_text() for name in VALIDATION_FILES if (out / name).is_file()}
    if held:
        if held == texts:
            return [out / name for name in VALIDATION_FILES] + sorted(out.glob("validation.p*")), True
        raise InputError(f"{out} holds another validation (its tables differ from this one's); it is kept",
                         where=f"-o {out}", fix=f"write this one to a new folder, e.g. -o {next_free(out)} "
                         "(--simulate's runs are reused: they live in --runs)")
    out.mkdir(parents=True, exist_ok=True)
    for name, text in texts.items():
        (out / name).write_text(text)
    return [out / name for name in VALIDATION_FILES] + list(validation_figure(df, out)), False


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
