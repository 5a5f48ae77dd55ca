"""Campaigns: load, plan, run, stop, status, their results (summaries, ensembles, the report), the
engine cross-check, what one changed setting does, and a runs folder packed as tables.

Every function takes a campaign file's path or a loaded `Campaign`, and `runs=` where the runs
folder is not the one the file names (`--runs` of the command)."""

from __future__ import annotations

import os
from pathlib import Path

from interphase.api import checks
from interphase.errors import InputError

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


def _path_and_runs(campaign, runs) -> tuple:
    """(campaign file, runs folder or None) of a path or a loaded Campaign: for the functions that
    load the file themselves."""
    from interphase.campaign.schema import Campaign

    if isinstance(campaign, Campaign):
        return campaign.path, runs if runs is not None else campaign.output
    return campaign, runs


def runs_folder(campaign, runs: PathLike | None = None) -> Path:
    """The runs folder a campaign file names, from its [campaign] table alone (no case is built)."""
    from interphase.campaign.schema import campaign_output

    path, runs = _path_and_runs(campaign, runs)
    return campaign_output(path, runs)[0]


def plan(campaign, engine: str | None = None, *, lazy: bool = False):
    """The planned runs of a campaign: `PlannedCase(case_id, engine, case, group, role, label,
    pair_id, physical_id, params)`, box tests first. The case id hashes the case's inputs, the engine
    and its recipe: the same on every machine; the physical id hashes the inputs without the seed
    (every seed of a case shares it: what the ensembles pool). `lazy=True` gives a generator (any
    size, built one case at a time); else a list. `engine` replaces the file's engines."""
    from interphase.campaign.plan import iter_plan
    from interphase.campaign.plan import plan as _plan

    c = _campaign(campaign)
    engines = (engine,) if engine else None
    return iter_plan(c, engines) if lazy else _plan(c, engines)


def run(campaign, *, runs: PathLike | None = None, engine: str | None = None, executor: str | None = None,
        jobs: int | None = None, rerun_failed: bool = False, rerun_stale: bool = False, dry_run: bool = False,
        restore: PathLike | None = None, render: bool = False, list_all: bool = False, yes: bool = False,
        quiet: bool = False, stream=None, live: bool | None = False):
    """Run what is not finished (as `campaign run`): returns a `RunReport` (`.statuses` {case id:
    status}, `.exit_code` 0 when every case finished or for a dry run, `.planned`, `.ran`). Progress
    goes to `stream` (default stdout; `quiet`: nowhere); `live`: the live table (None: on a
    terminal). More than 10000 cases need `yes=True`. `restore`: a summaries table whose finished
    runs come back first; `dry_run` says what would run (`render`: with its decks, `list_all`: every
    case)."""
    import io

    from interphase.campaign.run import run_campaign

    path, out = _path_and_runs(campaign, runs)
    return run_campaign(path, output=out, engines=(engine,) if engine else None, executor=executor, jobs=jobs,
                        rerun_failed=rerun_failed, rerun_stale=rerun_stale, dry_run=dry_run, restore=restore,
                        yes=yes, render=render, list_all=list_all, stream=io.StringIO() if quiet else stream, live=live)


def _existing_runs(c, fix: str | None = None) -> None:
    if not c.output.is_dir():
        raise InputError(f"the runs folder {c.output} does not exist ({c.output_from})", where=str(c.path),
                         fix=fix or f"run `campaign run {c.path}` first, or give --runs DIR (runs= in Python) where "
                                    "its runs are")


def stop(campaign, *, runs: PathLike | None = None) -> dict:
    """Ask a running `campaign run` (local) to start no new case and end when its running cases have
    finished (as `campaign stop`): writes the runs folder's STOP file. Returns {campaign (its name),
    file}. Refused (InputError) when the runs folder does not exist or no run is running there."""
    import time

    from interphase.campaign import store as st
    from interphase.campaign.executors import STOP_FILE

    c = _campaign(campaign, runs)
    _existing_runs(c, "nothing runs there; give --runs DIR (runs= in Python) if it ran elsewhere")
    with st.CampaignStore(c.output) as store:
        if not store.run_active():
            raise InputError(f"no `campaign run` is running in {c.output}", where=str(c.path),
                             fix="nothing to stop (`campaign status` shows its cases)")
    (c.output / STOP_FILE).write_text(f"asked by `campaign stop` at {time.strftime('%Y-%m-%d %H:%M:%S')}\n")
    return {"campaign": c.name, "file": c.output / STOP_FILE}


def status(campaign, *, runs: PathLike | None = None, engine: str | None = None):
    """One row per planned case (as `campaign status --json`): case_id, engine, group, label, role,
    status (pending, done, failed, killed, interrupted, incomplete, corrupt, stale), cause, message,
    elapsed [s], attempts. `.attrs`: campaign (its name), runs (the folder), runs_from (where that
    came from) and seeds (sequential seeds: one row per physical case, else None). Raises InputError
    when the runs folder does not exist. `engine`: the engine it ran with, if not the file's."""
    from interphase.campaign.run import campaign_status

    path, runs = _path_and_runs(campaign, runs)
    c, _, df = campaign_status(path, output=runs, engines=(engine,) if engine else None)
    _existing_runs(c)
    df.attrs |= {"campaign": c.name, "runs": c.output, "runs_from": c.output_from}
    df.attrs.setdefault("seeds", None)
    return df


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


def crosscheck(campaign, *, runs: PathLike | None = None, jobs: int | None = None, rerun_failed: bool = False,
               run: bool = True, stream=None):
    """Run (or, with `run=False`, only read) every case with LIGGGHTS and YADE and judge them on paired
    seed ensembles, as `campaign crosscheck`: a `CrosscheckReport` (`.passed`, `.outcome`,
    `.markdown()`, `.to_json()`, `.tolerances`, `.output`: the runs folder, crosscheck.csv/.md
    written there)."""
    from interphase.campaign.crosscheck import crosscheck as _crosscheck

    path, out = _path_and_runs(campaign, runs)
    return _crosscheck(path, jobs=jobs, output=out, rerun_failed=rerun_failed, run=run, stream=stream)


def compare(reference, variant=None, *, by: dict[str, float] | None = None, output: PathLike | None = None):
    """What one changed setting does, as `campaign compare`: the physical cases of two campaign files
    (`reference`, `variant`), or of one campaign split by `by` {field: the reference cell's value},
    judged on seed ensembles (agree / differ / undecided per metric). Returns the table, one row per
    case and metric; `.attrs["runs"]` [(campaign file, runs folder read)], with `by` also
    `.attrs["reference"]`. `output`: a new CSV file the table is also written to."""
    from interphase.campaign.compare import compare_campaigns, compare_within

    if (variant is None) == (not by):
        raise InputError("compare needs a second campaign file or --by FIELD=VALUE, not both nor neither",
                         where=f"campaign compare {reference}",
                         fix="campaign compare REF.toml VARIANT.toml, or campaign compare CAMPAIGN.toml "
                             "--by box_depth_d50=10")
    if output is not None:
        output = checks.new_file(output)
    if by:
        table = compare_within(reference, by)
        where, paths = f"{reference}, {' '.join(f'{k}={v:g}' for k, v in by.items())}", (reference,)
    else:
        table = compare_campaigns(reference, variant)
        where, paths = f"{reference}, {variant}", (reference, variant)
    if table.empty:
        raise InputError("no physical case finished on both sides", where=where,
                         fix="labels must match apart from the seed: vary only what the label does not name")
    table.attrs["runs"] = [(p, runs_folder(p)) for p in paths]
    if output is not None:
        table.to_csv(output, index=False)
    return table


def pack(runs: PathLike, output: PathLike) -> list[dict]:
    """A runs folder's finished runs as tables, as `campaign pack`: under `output`, per campaign
    folder, summaries.csv and curves.parquet (to commit, and restore elsewhere). Returns one
    {path, runs (the finished runs it holds)} per table."""
    from interphase.campaign.pack import pack_runs

    return [{"path": p, "runs": n} for p, n in pack_runs(runs, output)]


def report(campaign, *, output: PathLike | None = None, runs: PathLike | None = None, lab: PathLike | None = None,
           bootstrap: int = 199) -> dict:
    """The report of a campaign's finished runs, as `campaign report`: tables, figures, the fits
    (criterion.json) and an HTML page in `output` (default RUNS/report, then report-2, …; a given
    folder that holds anything is refused). `lab`: a laboratory CSV to set against the prediction;
    `bootstrap`: refits per correlation. Returns {folder, runs (the runs folder read), files,
    warnings}."""
    from interphase.report.build import build_report

    checks.at_least_zero(bootstrap, "--bootstrap")
    path, runs = _path_and_runs(campaign, runs)
    res = build_report(path, out=output, lab=lab, n_boot=bootstrap, output=runs)
    return {"folder": res.folder, "runs": runs_folder(path, runs), "files": list(res.files), "warnings": res.warnings}


def animations(campaign, runs_or_labels: list[str], *, output: PathLike | None = None,
               runs: PathLike | None = None) -> list[Path]:
    """The force network of each run (a label or case id) at every contact snapshot beside its
    stress-ratio curve, as `campaign report --animate`: OUTPUT/figures/animation_<label>.gif (default
    RUNS/report). Returns the files written; an unknown run is refused before anything is drawn."""
    from interphase.report.build import build_animations

    path, runs = _path_and_runs(campaign, runs)
    return build_animations(path, runs_or_labels, out=output, output=runs)
