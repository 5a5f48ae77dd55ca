"""The Python API: what the `campaign` command does, from a script or a notebook.

    import interphase as ip
    c = ip.load_campaign("campaigns/quick.toml")          # validated, nothing runs
    cases = ip.plan(c)                                     # [PlannedCase]: case_id, label, case, ...
    ip.run(c)                                              # RunReport; resumable, as `campaign run`
    ip.status(c)                                           # DataFrame, one row per planned case
    df = ip.summaries(c)                                   # DataFrame, one row per finished run
    ens = ip.ensembles(c)                                  # DataFrame, one row per physical case
    p = ip.predict("profile.csv", d50_mm=0.7, friction=0.2)   # dict: θa → θr → E → tan δ

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


def predict(profile: PathLike, d50_mm: float, friction: float, *, fit: str | None = None,
            tan_phi: float | None = None, units: str | None = None) -> dict:
    """The criterion chain for a surface profile (as `campaign predict --json`): θa → θr → E →
    tan δ. `d50_mm` [mm], `friction` = tan φμ particle–surface [-]; `fit`: a campaign file, a
    criterion.json or 'study' (default: the reproduction's fits shipped with the package);
    `tan_phi` of your soil (default: the fits' simulated soil). Returns a dict: theta_a_deg,
    theta_r_deg, efficiency, tan_delta, delta_deg with their intervals, branch, notes."""
    import math

    from interphase.analysis.criterion import predict_profile
    from interphase.errors import InputError
    from interphase.report.build import criterion_model
    from interphase.surface.readers import load_profile

    if not (isinstance(d50_mm, (int, float)) and math.isfinite(d50_mm) and d50_mm > 0):
        raise InputError(f"must be a positive diameter in mm, got {d50_mm!r}", where="d50_mm")
    if not (isinstance(friction, (int, float)) and math.isfinite(friction) and friction >= 0):
        raise InputError(f"must be a friction coefficient ≥ 0, got {friction!r}", where="friction")
    model = criterion_model(friction, fit, tan_phi)
    res = predict_profile(model, load_profile(str(profile), units, None), d50_mm * 1e-3, friction, None)
    return res.to_dict() | {"profile": str(profile), "d50_mm": d50_mm}


def element(card: PathLike, normal_stress: float | list[float], seeds: int = 3, *, runs: PathLike | None = None):
    """The element test of a soil card (docs/soils.md) at one or more normal stresses [Pa], packing
    seeds 1…`seeds`: a list of dicts with phi_peak_deg, phi_cs_deg, psi_max_deg and solid_fraction
    (each with _lo/_hi, 95 % over the seeds), has_peak, order_psi6 and a note. Resumable."""
    from interphase.campaign.element import run_element
    from interphase.soil import load_card

    stresses = normal_stress if isinstance(normal_stress, (list, tuple)) else [normal_stress]
    return [r.to_dict() for r in run_element(load_card(card), stresses, range(1, int(seeds) + 1), output=runs)]


def calibrate(target: PathLike, *, quick: bool = False, card: PathLike | None = None, runs: PathLike | None = None):
    """Calibrate grain parameters to a laboratory target (docs/soils.md); writes the soil card and
    returns what it holds (chosen parameters, posterior, achieved and held-out checks). Resumable."""
    from interphase.campaign.calibrate import calibrate as _calibrate

    return _calibrate(target, quick=quick, card_path=card, output=runs)


#: shipped soil cards by a laboratory soil's name (soils/ of the source tree or the working folder)
SHIPPED_CARDS = (("ottawa", "ottawa-20-30.toml"), ("glass", "glass-beads-0.7.toml"))


def _shipped_card(soils):
    """The one shipped card whose name matches every soil of a lab file, or None."""
    found = set()
    for soil in soils:
        name = next((card for key, card in SHIPPED_CARDS if key in str(soil).lower()), None)
        roots = (Path.cwd() / "soils", Path(__file__).resolve().parents[2] / "soils")
        found.add(next((r / name for r in roots if name and (r / name).is_file()), None))
    return found.pop() if len(found) == 1 else None


def validate(lab: PathLike, *, soil: PathLike | None = None, fit: str | None = None, simulate: bool = False,
             seeds: int = 3, output: PathLike | None = None, executor: str | None = None, jobs: int | None = None,
             stream=None) -> dict:
    """The criterion (and with `simulate`, the DEM on the soil card) against a laboratory file
    (lab/README.md; docs/validation.md), as `campaign validate`. Returns a dict: table (DataFrame, one
    row per test: δ measured, predicted with its interval, both baselines, errors [°]), skill
    (DataFrame), largest_miss, notes, folder and files written (validation.csv, skill.csv,
    validation.md, validation.png/.pdf under `output`, default runs/validate/<file name>)."""
    from interphase.analysis.validation import largest_miss, predict_rows, skill
    from interphase.errors import InputError
    from interphase.lab import read_lab
    from interphase.report.build import criterion_model
    from interphase.report.validation import markdown, validation_figure
    from interphase.soil import load_card

    table = read_lab(lab)
    out = Path(output) if output else Path("runs") / "validate" / table.path.stem
    notes: list[str] = []
    card = load_card(soil) if soil else None
    if card is None:
        shipped = _shipped_card(sorted(set(table.rows["soil"])))
        card = load_card(shipped) if shipped else None
        if card is not None:
            notes.append(f"soil card: {card.path} (shipped, chosen by the soil's name; soil= to choose)")
        elif simulate or table.rows["soil_phi_peak"].isna().any():
            raise InputError(f"no single shipped card for the soils {', '.join(sorted(set(table.rows['soil'])))}",
                             where="--soil", fix="give --soil soils/NAME.toml")
    models: dict = {}
    model_for = lambda mu: models[mu] if mu in models else models.setdefault(mu, criterion_model(mu, fit))
    df = predict_rows(table, model_for, card)
    notes += sorted({f"criterion: {m.source}" for m in models.values()})
    if simulate:
        from interphase.campaign.validate import simulate as _simulate, with_dem

        df = with_dem(df, _simulate(table, card, range(1, int(seeds) + 1), output=out / "runs", executor=executor,
                                    jobs=jobs, stream=stream))
    sk = skill(df)
    out.mkdir(parents=True, exist_ok=True)
    df.to_csv(out / "validation.csv", index=False)
    sk.to_csv(out / "skill.csv", index=False)
    cols = {"row": "line", "soil": "soil", "surface": "surface", "normal_stress_kpa": "σn [kPa]", "theta_a_deg": "θa [°]",
            "delta_measured_deg": "δ lab [°]", "delta_predicted_deg": "δ criterion [°]", "delta_lo_deg": "lo",
            "delta_hi_deg": "hi", "error_predicted_deg": "error [°]", "delta_rule_deg": "δ rule [°]",
            "delta_soil_deg": "δ = φ [°]", "delta_fitted_rule_deg": "δ fitted rule [°]"}
    if "delta_dem_deg" in df:
        cols |= {"delta_dem_deg": "δ DEM [°]", "error_dem_deg": "DEM error [°]"}
    (out / "validation.md").write_text(markdown(df, cols) + "\n" + markdown(sk, {
        "subset": "rows", "prediction": "prediction", "n": "n", "rms_deg": "rms [°]", "max_abs_deg": "max [°]",
        "within_4": "share within 4°"}))
    files = [out / "validation.csv", out / "skill.csv", out / "validation.md", *validation_figure(df, out)]
    return {"lab": str(table.path), "rows": len(df), "folder": out, "notes": notes, "table": df, "skill": sk,
            "largest_miss": largest_miss(df), "files": files}
