"""The `campaign` command: parses arguments and calls the library; no logic of its own.

Every user error (InputError) ends with one message on stderr and exit code 2, never a traceback.
Every command that prints numbers has --json.
"""

from __future__ import annotations

import argparse
import json
import sys

from interphase.errors import InputError
from interphase.version import __version__


def _jsonable(obj):
    """NaN/inf → null (strict JSON); numpy scalars → Python numbers."""
    import math

    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if hasattr(obj, "item") and not isinstance(obj, (str, bytes)):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def _print_json(obj) -> None:
    print(json.dumps(_jsonable(obj), indent=2, sort_keys=True, allow_nan=False))


# ---- surface toolkit: theta-a, profile ------------------------------------------------------
def _add_surface(sub) -> None:
    p = sub.add_parser("theta-a", help="θa, Rn, Rnc and mean asperity slope of a profile file or areal scan")
    p.add_argument("profile", help="profile or areal scan: any format SurfaceTopography reads (FRT, SUR, MNT, "
                   "OPDx, HFM, Mitutoyo XLSX, Dektak CSV, …) or two columns x z")
    p.add_argument("--axis", default=None, choices=("x", "y"),
                   help="areal scans: the shear axis whose grid lines are the profiles (default x, the file's first "
                   "axis); θa is printed for shear in +x, −x, +y, −y either way")
    p.add_argument("--d50", type=float, default=None, help="median grain diameter [mm] (default with --soil: the card's)")
    p.add_argument("--filter", type=int, default=92, choices=(92, 90),
                   help="keep trace normals > 92° (default, construction surfaces) or ≥ 90° (regular flat spacing)")
    p.add_argument("--units", default=None, help="units of the file's x and z: um | mm | m "
                   "(default: the file's own for a Dektak export, else mm)")
    p.add_argument("--cutoff", type=float, default=None, help="Gaussian filter cut-off λc [mm] (default: unfiltered)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_cmd_theta_a)

    p = sub.add_parser("profile", help="generate, convert or plot surface profiles")
    psub = p.add_subparsers(dest="profile_command", required=True, metavar="KIND")
    common = dict(d50=("--d50", dict(type=float, default=0.7, help="D50 [mm] (sizes below are in D50)")),
                  length=("--length", dict(type=float, default=30.0, help="profile length [mm]")))
    for kind, params, text in (
        ("sawtooth", ("rt", "sw"), "Groups 1 and 3: triangles, no spacing"),
        ("spaced", ("rt", "sw", "sr"), "Group 2: triangles with flat spacing Sr"),
        ("random", ("au", "ar", "rtmax", "seed"), "Group 4: random segments (Au, Ar, Rtmax, seed)"),
    ):
        q = psub.add_parser(kind, help=text)
        for name in params:
            q.add_argument(f"--{name}", type=int if name == "seed" else float, required=True,
                           help="integer seed" if name == "seed" else f"{name} [D50]")
        for flag, kw in common.values():
            q.add_argument(flag, **kw)
        q.add_argument("-o", "--output", required=True, help="output file (two columns x z in mm)")
        q.set_defaults(func=_cmd_profile_make, kind=kind)
    q = psub.add_parser("plot", help="profile, centroid trace and polar normal distribution to PNG")
    q.add_argument("profile")
    q.add_argument("--d50", type=float, default=0.7, help="D50 [mm]")
    q.add_argument("--units", default=None, help="um | mm | m (default: file's own, else mm)")
    q.add_argument("--filter", type=int, default=92, choices=(92, 90))
    q.add_argument("-o", "--output", default=None, help="PNG path (default: PROFILE.png)")
    q.set_defaults(func=_cmd_profile_plot)


def _d50_m(value: float | None) -> float:
    import math

    if value is None:
        raise InputError("no grain size given", where="--d50",
                         fix="give --d50 MM, the grains' median diameter: θa is read with a disc of that size")
    if not (math.isfinite(value) and value > 0):
        raise InputError(f"must be a positive diameter in mm, got {value!r}", where="--d50")
    return value * 1e-3


def _output_path(path: str) -> str:
    """Refuse, before any work is done, an output file that exists (nothing a user owns is
    overwritten: a new name is suggested) or whose folder does not."""
    from pathlib import Path

    from interphase.campaign.folders import next_free

    parent = Path(path).resolve().parent
    if not parent.is_dir():
        raise InputError(f"folder {str(parent)!r} does not exist", where=f"-o {path}",
                         fix="create the folder first or write somewhere else")
    if Path(path).exists():
        raise InputError(f"{path} exists; it is kept as it is", where=f"-o {path}",
                         fix=f"write to a new name, e.g. -o {next_free(path)}")
    return path


def _load_measured(path: str, units, cutoff_mm=None):
    from interphase.surface.readers import load_profile

    if cutoff_mm is not None and not cutoff_mm > 0:
        raise InputError(f"must be a positive length in mm, got {cutoff_mm!r}", where="--cutoff")
    return load_profile(path, units, None if cutoff_mm is None else cutoff_mm * 1e-3)


def _cmd_theta_a(args) -> int:
    from interphase.surface.readers import read_scan

    d50 = _d50_m(args.d50)
    scan = read_scan(args.profile, args.units)      # unknown --units are refused before the file is read
    if scan.areal:
        return _theta_a_areal(args, scan, d50)
    if args.axis == "y":
        raise InputError("a line scan has only the x axis", where="--axis", fix="omit --axis for a line")
    from interphase.surface.normals import theta_a

    prof = _load_measured(args.profile, args.units, args.cutoff)
    res = theta_a(prof, d50, args.filter)
    back = theta_a(prof.mirrored(), d50, args.filter)      # shear in −x: the other flanks resist
    out = res.to_dict() | {"profile": args.profile, "d50_mm": args.d50, "areal": False,
                           "units": scan.units, "reader": scan.reader,
                           "directions": {"+x": res.to_dict() | {"direction": "+x"},
                                          "-x": back.to_dict() | {"direction": "-x"}}}
    if args.json:
        _print_json(out)
        return 0
    print(f"profile            {args.profile}  (D50 = {args.d50:g} mm, filter {args.filter}°)")
    for d, r in (("+x", res), ("-x", back)):
        if r.dilative:
            print(f"θa ({d})            {r.theta_a_deg:.2f}° from vertical  ({r.theta_a_ccw_deg:.2f}° ccw from {d})")
        else:
            print(f"θa ({d})            undefined — {r.reason}")
    print(f"Rn, Rnc(D50)       {res.rn:.4f}, {res.rnc:.4f}")
    print(f"mean asperity slope {res.mean_slope_deg:.2f}° (flats < 2° excluded)")
    print(f"trace points       {res.n_points}")
    return 0


def _theta_a_areal(args, scan, d50: float) -> int:
    """An areal scan: every grid line along the axis is a profile; θa in the four shear directions."""
    from interphase.surface.areal import MIN_RUN_D50, theta_a_scan

    if args.cutoff is not None:
        raise InputError("a Gaussian cut-off is not applied to areal scans yet", where="--cutoff",
                         fix="omit --cutoff (each run is levelled by its own least-squares line)")
    axis = args.axis or "x"
    other = "y" if axis == "x" else "x"
    res = theta_a_scan(scan, d50, (args.filter,), axes=(axis,))      # the chosen axis: its errors are the user's
    missing = {}
    try:
        res |= theta_a_scan(scan, d50, (args.filter,), axes=(other,))
    except InputError as exc:       # the other axis may hold no run long enough: say so in its rows
        missing = {other: str(exc)}
    main_res = res[f"+{axis}"][args.filter]
    nx, ny = scan.shape
    directions = {d: (res[d][args.filter].to_dict() if d in res else {"direction": d, "error": missing[d[1]]})
                  for d in ("+x", "-x", "+y", "-y")}
    out = main_res.to_dict() | {"profile": args.profile, "d50_mm": args.d50, "areal": True, "axis": axis,
                                "shape": [nx, ny], "units": scan.units, "reader": scan.reader,
                                "missing_points": scan.n_missing, "directions": directions}
    if args.json:
        _print_json(out)
        return 0
    print(f"scan               {args.profile}  (areal {nx} × {ny}, {scan.x[-1] * 1e3:.4g} × {scan.y[-1] * 1e3:.4g} mm, "
          f"{scan.n_missing} missing points; {scan.reader})")
    print(f"                   D50 = {args.d50:g} mm, filter {args.filter}°; lines split at missing points, runs "
          f"< {MIN_RUN_D50:g}·D50 dropped, each run levelled")
    if main_res.dilative:
        print(f"θa (+{axis})            {main_res.theta_a_deg:.2f}° from vertical  ({main_res.theta_a_ccw_deg:.2f}° ccw "
              f"from +{axis})")
    else:
        print(f"θa (+{axis})            undefined — {main_res.reason}")
    print("shear  θa [°]   per-run 5–95 % [°]   runs  dropped  with θa   Rn      Rnc     slope [°]")
    for d in ("+x", "-x", "+y", "-y"):
        if d not in res:
            print(f"{d:<6} —  {missing[d[1]]}")
            continue
        r = res[d][args.filter]
        ta = f"{r.theta_a_deg:6.2f}" if r.dilative else "   n-d"
        sp = f"{r.spread_deg[0]:6.2f} – {r.spread_deg[1]:6.2f}" if r.n_runs_dilative else "      —        "
        print(f"{d:<6} {ta}   {sp}      {r.n_runs:5d}  {r.n_dropped:7d}  {r.n_runs_dilative:7d}   "
              f"{r.rn:.4f}  {r.rnc:.4f}  {r.mean_slope_deg:6.2f}")
    print("(n-d: non-dilative, no pooled trace normal beyond the filter)")
    return 0


def _cmd_profile_make(args) -> int:
    import numpy as np

    from interphase.surface.profiles import random_profile, sawtooth

    d50 = _d50_m(args.d50)
    if not args.length > 0:
        raise InputError(f"must be > 0, got {args.length!r}", where="--length")
    length = args.length * 1e-3
    if args.kind == "random":
        prof = random_profile(args.au, args.ar, args.rtmax, d50=d50, length=length, seed=args.seed)
    else:
        prof = sawtooth(args.rt, args.sw, getattr(args, "sr", 0.0), d50=d50, length=length)
    np.savetxt(_output_path(args.output), np.column_stack([prof.x, prof.z]) * 1e3, fmt="%.9g",
               header=f"x_mm z_mm  {prof.name} D50={args.d50:g}mm", comments="# ")
    print(f"wrote {args.output} ({prof.x.size} vertices, {prof.length * 1e3:.3f} mm)")
    return 0


def _cmd_profile_plot(args) -> int:
    from interphase.surface.plot import plot_profile

    out = _output_path(args.output or (args.profile.rsplit(".", 1)[0] + ".png"))
    plot_profile(_load_measured(args.profile, args.units), _d50_m(args.d50), out, args.filter)
    print(f"wrote {out}")
    return 0


# ---- single cases and engines: render, run-case ----------------------------------------------
def _add_engine(sub) -> None:
    for cmd, text in (("render", "write a case's engine input files (dry run) and list them"),
                      ("run-case", "render, run and read one case; print where its results are")):
        p = sub.add_parser(cmd, help=text)
        p.add_argument("case", help="TOML file with a [case] table (Case fields, SI units)")
        p.add_argument("-o", "--output", required=True,
                       help="the case folder to write: new or empty" + (
                           "; never a case folder (nothing finished is overwritten)" if cmd == "render" else
                           ", or this same case's folder (finished: read back, not rerun)"))
        p.add_argument("--engine", default="liggghts", help="liggghts | yade")
        p.add_argument("--json", action="store_true", help="print JSON")
        p.set_defaults(func=_cmd_render if cmd == "render" else _cmd_run_case)


def _load_case(path: str):
    """(Case, warnings) of a case file: the checks `campaign run` makes on a campaign's cases."""
    from interphase.campaign.checks import case_file_warnings, load_case_file

    case = load_case_file(path)
    warnings = case_file_warnings(path, case)
    return case, warnings


def _warn(warnings, as_json: bool) -> None:
    """Warnings on stderr (stdout stays parseable with --json)."""
    for w in warnings:
        print(f"warning: {w}", file=sys.stderr)


def _cmd_render(args) -> int:
    from interphase.campaign.guard import check_render_folder
    from interphase.engines.base import get_engine

    engine = get_engine(args.engine)
    case, warnings = _load_case(args.case)
    check_render_folder(args.output)
    _warn(warnings, args.json)
    files = engine.write_input(case, args.output)
    if args.json:
        _print_json({"folder": args.output, "files": sorted(files), "warnings": warnings})
    else:
        print("\n".join(f"{args.output}/{name}" for name in sorted(files)))
    return 0


def _cmd_run_case(args) -> int:
    from pathlib import Path

    from interphase.campaign.runner import run_single

    folder = Path(args.output)
    case, warnings = _load_case(args.case)
    _warn(warnings, args.json)
    res = run_single(case, args.engine, folder)
    if res["status"] != "done":
        print(f"campaign run-case: {args.engine} {res['status']}: {res['cause']}: {res['message']}", file=sys.stderr)
        return 1
    if res["skipped"]:
        print(f"campaign run-case: {folder} already holds this case, finished: its result is read back, "
              "nothing was rerun", file=sys.stderr)
    row = res["summary"]
    out = {"folder": str(folder), "skipped": res["skipped"], "summary": str(folder / "summary.json"),
           **{name: str(folder / f"{name}.parquet") for name in ("contacts", "history", "particles", "series")},
           **{k: row.get(k) for k in ("peak_stress_ratio", "shear_disp_at_peak", "peak_at_end", "peak_snapshot",
                                      "theta_r_surface_deg", "theta_r_surface_mean_deg", "surface_force_angle_deg")},
           "warnings": warnings}
    if args.json:
        _print_json(out)
    else:
        for k, v in out.items():
            if k != "warnings":
                print(f"{k:24s} {v}")
    return 0


# ---- campaigns: run, status, crosscheck --------------------------------------------------------
RUNS_HELP = ("the campaign's runs folder (default: the file's [campaign] output, relative to the file, else "
             "runs/NAME beside the file)")


def _add_campaign(sub) -> None:
    p = sub.add_parser("run", help="run a campaign (skips finished cases; resumable; local pool or SLURM)")
    p.add_argument("campaign", help="campaign file (TOML)")
    p.add_argument("--engine", default=None, help="run with this engine instead of the file's: liggghts | yade")
    p.add_argument("--executor", default=None, choices=("local", "slurm"),
                   help="where cases run (default: the file's [execution].executor)")
    p.add_argument("--jobs", type=int, default=None, help="local: cases at a time (default: the file's, else one per core); "
                   "slurm: array tasks at a time")
    p.add_argument("--rerun-failed", action="store_true", help="run failed and SLURM-killed cases again")
    p.add_argument("--rerun-stale", action="store_true",
                   help="run again the cases finished under another recipe or engine build (see `campaign status`)")
    p.add_argument("--dry-run", action="store_true", help="the count, a sample and what would run; run nothing")
    p.add_argument("--render", action="store_true", help="with --dry-run: write the decks of the cases that would run")
    p.add_argument("--list", action="store_true", dest="list_all", help="with --dry-run: list every case, not a sample")
    p.add_argument("--yes", action="store_true", help="go on with a campaign of more than 10000 cases")
    p.add_argument("--runs", "-o", "--output", dest="runs", default=None, metavar="DIR",
                   help=RUNS_HELP + "; -o/--output is the same: what `run` writes")
    p.add_argument("--plain", action="store_true", help="plain progress lines even on a terminal")
    p.add_argument("--json", action="store_true", help="progress on stderr, then one JSON summary on stdout")
    p.add_argument("--restore", default=None, metavar="SUMMARIES_CSV",
                   help="first bring back the finished runs of a summaries table (`campaign report`'s "
                        "tables/summaries.csv, e.g. a committed copy) whose case ids this campaign plans: "
                        "a campaign goes on on another machine without rerunning them (no dumps come back)")
    p.set_defaults(func=_cmd_campaign_run)

    p = sub.add_parser("stop", help="ask a running `campaign run` (local) to start no new case and end when its "
                       "running cases have finished: nothing half-run is lost")
    p.add_argument("campaign", help="campaign file (TOML)")
    p.add_argument("--runs", default=None, metavar="DIR", help=RUNS_HELP)
    p.set_defaults(func=_cmd_campaign_stop)

    p = sub.add_parser("status", help="state of every case of a campaign, with failure causes")
    p.add_argument("campaign", help="campaign file (TOML)")
    p.add_argument("--engine", default=None, help="the engine the campaign ran with, if not the file's")
    p.add_argument("--runs", default=None, metavar="DIR", help=RUNS_HELP)
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_cmd_campaign_status)


def _engines(name: str | None):
    """`--engine NAME` as the engine value the run path carries (None: the file's engines)."""
    from interphase.engines.base import engine_spec

    return None if name is None else (engine_spec(name),)


def _cmd_campaign_run(args) -> int:
    from interphase.campaign.run import run_campaign

    report = run_campaign(args.campaign, engines=_engines(args.engine), executor=args.executor, jobs=args.jobs,
                          rerun_failed=args.rerun_failed, rerun_stale=args.rerun_stale, dry_run=args.dry_run,
                          output=args.runs, restore=args.restore, yes=args.yes, render=args.render,
                          list_all=args.list_all, stream=sys.stderr if args.json else None,
                          live=False if (args.plain or args.json) else None)
    code = 0 if args.dry_run else report.exit_code
    if args.json:
        counts: dict = {}
        for status in report.statuses.values():
            counts[status] = counts.get(status, 0) + 1
        _print_json({"campaign": report.campaign, "runs": str(report.output), "dry_run": args.dry_run,
                     "planned": report.planned, "counts": counts, "ran": report.ran,
                     "interrupted": report.interrupted, "exit_code": code})
    return code


def _cmd_campaign_stop(args) -> int:
    import time

    from interphase.campaign import store as st
    from interphase.campaign.executors import STOP_FILE
    from interphase.campaign.schema import load_campaign

    campaign = load_campaign(args.campaign, output=args.runs)
    if not campaign.output.is_dir():
        raise InputError(f"the runs folder {campaign.output} does not exist ({campaign.output_from})",
                         where=args.campaign, fix="nothing runs there; give --runs DIR if it ran elsewhere")
    with st.CampaignStore(campaign.output) as store:
        if not store.run_active():
            raise InputError(f"no `campaign run` is running in {campaign.output}", where=args.campaign,
                             fix="nothing to stop (`campaign status` shows its cases)")
    (campaign.output / STOP_FILE).write_text(f"asked by `campaign stop` at {time.strftime('%Y-%m-%d %H:%M:%S')}\n")
    print(f"campaign {campaign.name}: wrote {campaign.output / STOP_FILE}: a local run starts no new case and ends "
          "when its running cases have finished (Ctrl-C or SIGTERM stops them now); SLURM runs: scancel its jobs")
    return 0


def _cmd_campaign_status(args) -> int:
    from interphase.campaign.run import campaign_status

    campaign, planned, df = campaign_status(args.campaign, output=args.runs, engines=_engines(args.engine))
    if not campaign.output.is_dir():
        raise InputError(f"the runs folder {campaign.output} does not exist ({campaign.output_from})",
                         where=args.campaign, fix=f"run `campaign run {args.campaign}` first, or give --runs DIR "
                         "where its runs are")
    counts = df["status"].value_counts().to_dict()
    seeds = df.attrs.get("seeds")
    if args.json:
        extra = {} if seeds is None else {"seeds": seeds.astype(object).where(seeds.notna(), None).to_dict(orient="records")}
        _print_json({"campaign": campaign.name, "runs": str(campaign.output), "runs_from": campaign.output_from,
                     "counts": counts,
                     "cases": df.astype(object).where(df.notna(), None).to_dict(orient="records"), **extra})
        return 0
    import shutil

    width = max(80, min(shutil.get_terminal_size((80, 24)).columns, 120))
    print("\n".join(status_text(campaign, df, width)))
    return 0


def status_text(campaign, df, width: int = 80) -> list[str]:
    """`campaign status`'s lines of campaign_status's (Campaign, DataFrame): the counts, the runs
    folder, one row per case, what is wrong with failed or corrupt ones, one line per kind of stale,
    and the seed rounds."""
    counts = df["status"].value_counts().to_dict()
    lines = [_wrap(f"{campaign.name}: " + ", ".join(f"{v} {k}" for k, v in sorted(counts.items())), width),
             _wrap(f"runs folder {campaign.output} ({campaign.output_from})", width), *status_rows(df, width)]
    bad = df[df["status"].isin(("corrupt", "failed"))]
    for r in bad.itertuples():       # what is wrong and the fix, under the table (wrapped, not cut)
        if isinstance(r.message, str) and r.message:
            lines.append(_wrap(f"{str(r.case_id)[:8]} {r.status}: {r.message}", width))
    stale = df[df["status"] == "stale"]
    for kind, rows in stale.groupby("cause"):   # one line per kind: a recipe change makes every case stale
        lines.append(_wrap(f"{len(rows)} stale ({kind}), e.g. {str(rows['case_id'].iloc[0])[:8]}: "
                           f"{rows['message'].iloc[0]}", width))
    seeds = df.attrs.get("seeds")
    return lines + (seed_rows(seeds, width) if seeds is not None else [])


def seed_rows(seeds, width: int = 80) -> list[str]:
    """Sequential seeds ([seeds]): one line per physical case: seeds finished / asked for, the
    interval of the target quantity at the last round judged and its half-width, the state."""
    if seeds.empty:
        return []
    r0 = seeds.iloc[0]
    lines = [f"seeds: target ± {r0.target:g} in {r0.quantity}, cap {int(r0.cap)} seeds",
             f"{'case':<{width - 58}} {'seeds':>9} {r0.quantity:>7} {'95 % interval':>15} {'± half':>7}  state"]
    room = width - 58
    for r in seeds.itertuples():
        name = f"{r.group}/{r.case}"
        name = name if len(name) <= room else "…" + name[len(name) - room + 1:]
        ival = f"{r.lo:.3f}–{r.hi:.3f}" if r.lo == r.lo and r.hi == r.hi else "–"
        lines.append(f"{name:<{room}} {f'{r.finished}/{r.wanted}':>9} {r.value:>7.3f} {ival:>15} "
                     f"{r.halfwidth:>7.3f}  {r.state}")
    return lines


def status_rows(df, width: int = 80) -> list[str]:
    """One line per case in `width` columns: short id, engine, label, status, cause. A label too long
    for its column loses the start it shares with the other labels (`…` in its place), then, if
    still too long, more of its start: the end, which tells cases apart (`-mu0.2-poly-s1`), stays.
    Full ids, labels and messages: `campaign status --json`."""
    labels = [str(x) for x in df["label"]] if len(df) else []
    room = width - (8 + 1 + 8 + 1 + 1 + 11 + 1 + 14)
    common = _common_prefix(labels) if len(labels) > 1 else ""
    lines = [f"{'id':<8} {'engine':<8} {'label':<{room}} {'status':<11} cause"]
    for r in df.itertuples():
        label = str(r.label)
        if len(label) > room and common:
            label = "…" + label[len(common):]
        if len(label) > room:
            label = "…" + label[len(label) - room + 1:]
        cause = r.cause if isinstance(r.cause, str) else ""
        lines.append(f"{str(r.case_id)[:8]:<8} {str(r.engine)[:8]:<8} {label:<{room}} {str(r.status)[:11]:<11} "
                     f"{cause[:14]}".rstrip())
    return lines


def _common_prefix(labels: list[str]) -> str:
    """The start every label shares, cut back to a '-' (whole label parts only)."""
    import os

    prefix = os.path.commonprefix(labels)
    return prefix[:prefix.rfind("-") + 1] if "-" in prefix else ""


def _wrap(text: str, width: int) -> str:
    """`text` wrapped between words only: a path or a command longer than the line stays whole (a
    terminal folds it; copied, it still works), and continuation lines are indented."""
    import textwrap

    return textwrap.fill(text, width=width, break_long_words=False, break_on_hyphens=False,
                         subsequent_indent="  ")


# ---- engine cross-check: crosscheck -----------------------------------------------------------
def _add_crosscheck(sub) -> None:
    p = sub.add_parser("crosscheck", help="run a campaign with LIGGGHTS and YADE and judge them on paired seed ensembles "
                       "(agree / differ / undecided per metric)")
    p.add_argument("campaign", help="campaign file (TOML) with an optional [crosscheck] table of tolerances")
    p.add_argument("--jobs", type=int, default=None, help="cases at a time (default: the file's, else one per core)")
    p.add_argument("--runs", "-o", "--output", dest="runs", default=None, metavar="DIR",
                   help=RUNS_HELP + "; -o/--output is the same: what `crosscheck` writes (and crosscheck.csv there)")
    p.add_argument("--rerun-failed", action="store_true", help="run failed cases again")
    p.add_argument("--no-run", action="store_true", help="compare what has finished; run nothing")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_cmd_crosscheck)


def _cmd_crosscheck(args) -> int:
    """Exit 0 if every judged metric agrees (paired seed ensembles) and every case finished, else 1."""
    from interphase.campaign.crosscheck import crosscheck

    report = crosscheck(args.campaign, jobs=args.jobs, output=args.runs, rerun_failed=args.rerun_failed,
                        run=not args.no_run, stream=sys.stderr if args.json else sys.stdout)
    if args.json:
        _print_json(report.to_json())
    else:
        print(report.markdown())
        print(f"tolerances: {report.tolerances}; table written to {report.output / 'crosscheck.csv'} and .md")
        print(f"verdict: {report.outcome} (the rows above)")
    return 0 if report.passed else 1


# ---- results: report, predict ------------------------------------------------------------------
def _add_report(sub) -> None:
    p = sub.add_parser("report", help="tables (CSV/Markdown/LaTeX), figures 6.3–6.10 (PNG/PDF), fits and an HTML page")
    p.add_argument("campaign", help="campaign file (TOML) whose cases have run")
    p.add_argument("-o", "--output", "--out", dest="output", default=None, metavar="DIR",
                   help="the report folder to write (default: RUNS/report)")
    p.add_argument("--runs", default=None, metavar="DIR", help=RUNS_HELP)
    p.add_argument("--lab", default=None, help="laboratory CSV (lab/README.md: published tests with their surfaces' "
                   "geometry) — overlaid on Fig. 6.10 and tabulated against the prediction and both baselines")
    p.add_argument("--bootstrap", type=int, default=199, help="bootstrap refits per correlation (default 199)")
    p.add_argument("--animate", action="append", default=None, metavar="LABEL_OR_ID",
                   help="write only figures/animation_<label>.gif of this run (label or case id; repeatable): "
                   "the force network at every contact snapshot beside the stress-ratio curve")
    p.add_argument("--json", action="store_true", help="print JSON (files, warnings)")
    p.set_defaults(func=_cmd_report)

    p = sub.add_parser("pack", help="a runs folder's finished runs as tables (per campaign folder: summaries.csv and "
                       "curves.parquet), to commit and restore elsewhere (`campaign calibrate --restore`)")
    p.add_argument("runs", help="runs folder (a campaign's or a calibration's, with every campaign folder under it)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="the folder to write the tables into")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_cmd_pack)

    p = sub.add_parser("predict", help="the interface friction angle δ of a sand on a surface, with its intervals")
    p.add_argument("profile", help="profile or areal scan: a Dektak export, two columns x z, or any format "
                   "SurfaceTopography reads (an areal scan is read along --axis, every grid line pooled)")
    p.add_argument("--soil", default=None, metavar="CARD",
                   help="your sand: a soil card (soils/NAME.toml, or NAME of a shipped card: the 3D one by the sand's "
                   "name); E from the criterion fitted on its own runs, tan φ from its own soil test at the stress "
                   "and density asked, δ with the model's and the sand's 95 %% prediction intervals")
    p.add_argument("--friction", type=float, default=None, metavar="MU",
                   help="particle–surface friction μ = tan φμ [-]")
    p.add_argument("--smooth-delta", type=float, default=None, metavar="DEG",
                   help="instead of --friction: δ [°] the sand reads on a smooth plate of the surface's material "
                   "(μ = tan of it)")
    p.add_argument("--normal-stress", type=float, default=None, metavar="PA",
                   help="normal stress [Pa] (default 100e3); with --soil, tan φ is the card's soil test there")
    p.add_argument("--relative-density", type=float, default=None, metavar="DR",
                   help="with --soil: relative density [-] of the sand (default: the card's calibrated state)")
    p.add_argument("--fit", default=None, help="instead of --soil, a simulated soil's fit: 'study' (the reproduction "
                   "on the study's discs, tan φ 0.374), 'study-figures' (readings of its figures), a criterion.json "
                   "written by `campaign report`, or a campaign file; needs --d50")
    p.add_argument("--d50", type=float, default=None, help="median grain diameter [mm] (with --fit; a card has its own)")
    p.add_argument("--tan-phi", type=float, default=None,
                   help="with --fit: tan φ of the soil (a tangent, not degrees; default the fit's simulated soil)")
    p.add_argument("--axis", choices=("x", "y"), default=None, help="areal scans: shear along +x (default) or +y")
    p.add_argument("--units", default=None, help="um | mm | m (default: the file's own for a Dektak export, else mm)")
    p.add_argument("--filter", type=int, default=None, choices=(92, 90),
                   help="force the branch: 92 (Fig. 6.8) or 90 (flat-spaced, Fig. 6.9); default: chosen from the profile")
    p.add_argument("--simulate", action="store_true",
                   help="with --soil: run the DEM on the profile with the card's grains instead (a generated "
                   "campaign in --runs, resumable; in the cell of the campaign the card names in [criterion] campaign)")
    p.add_argument("--seeds", type=int, default=3, help="--simulate: packing seeds 1…N (default 3)")
    p.add_argument("--runs", default=None, metavar="DIR",
                   help="--simulate: runs folder (default runs/predict/<card name> beside the card)")
    p.add_argument("--jobs", type=int, default=None, help="--simulate: cases at a time (default: one per core)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_cmd_predict)


def _add_compare(sub) -> None:
    p = sub.add_parser("compare", help="what one changed setting does: two campaigns' physical cases compared "
                       "on seed ensembles (agree / differ / undecided); or one campaign's cells (--by)")
    p.add_argument("reference", help="campaign file (TOML) of the reference settings")
    p.add_argument("variant", nargs="?", default=None,
                   help="campaign file (TOML) that changes one setting (not with --by)")
    p.add_argument("--by", action="append", default=[], metavar="FIELD=VALUE",
                   help="compare within one campaign: split its runs by FIELD (a case field its sweep varies "
                        "and its labels do not name, e.g. box_depth_d50), the cell with FIELD=VALUE the "
                        "reference; repeat for several fields")
    p.add_argument("-o", "--output", "--out", dest="output", default=None, metavar="CSV",
                   help="also write the table to this CSV file")
    p.add_argument("--json", action="store_true", help="print JSON rows")
    p.set_defaults(func=_cmd_compare)


def _cmd_compare(args) -> int:
    from interphase.campaign.compare import compare_campaigns, compare_within

    if bool(args.variant) == bool(args.by):
        raise InputError("compare needs a second campaign file or --by FIELD=VALUE, not both nor neither",
                         where=f"campaign compare {args.reference}",
                         fix="campaign compare REF.toml VARIANT.toml, or campaign compare CAMPAIGN.toml "
                             "--by box_depth_d50=10")
    if args.by:
        table = compare_within(args.reference, _by_fields(args.by))
        where, paths = f"{args.reference}, {' '.join(args.by)}", (args.reference,)
    else:
        table = compare_campaigns(args.reference, args.variant)
        where, paths = f"{args.reference}, {args.variant}", (args.reference, args.variant)
    if table.empty:
        raise InputError("no physical case finished on both sides", where=where,
                         fix="labels must match apart from the seed: vary only what the label does not name")
    if args.output:
        table.to_csv(_output_path(args.output), index=False)
    if not args.json:
        for path in paths:
            print(f"read the runs of {path} in {_runs_folder(path)}")
        if args.by:
            print(f"reference cell: {table.attrs['reference']}")
    if args.json:
        _print_json(table.to_dict(orient="records"))
        return 0
    for r in table.itertuples(index=False):
        need = ""
        if r.verdict == "undecided":
            n = r.seeds_needed
            need = (f" (≈{int(n)} seeds per side would decide)" if n is not None and n == n
                    else " (no seed count within reach decides it at this scatter)")
        cell = f"[{r.variant}] " if args.by else ""
        print(f"{cell}{r.case}  {r.metric}: {r.ref:.4g} ({r.ref_lo:.4g}–{r.ref_hi:.4g}) → {r.value:.4g} "
              f"({r.value_lo:.4g}–{r.value_hi:.4g}); change {r.change:+.4g} ({r.change_lo:+.4g} to {r.change_hi:+.4g}) "
              f"vs ±{r.tol:.3g}: {r.verdict}{need}")
    return 0


def _by_fields(items: list[str]) -> dict[str, float]:
    """--by FIELD=VALUE arguments as {field: value}."""
    out = {}
    for item in items:
        field, _, value = item.partition("=")
        try:
            if not field.strip():
                raise ValueError
            out[field.strip()] = float(value)
        except ValueError:
            raise InputError(f"--by {item}: not FIELD=VALUE with a number", where="campaign compare",
                             fix="e.g. --by box_depth_d50=10") from None
    return out


def _runs_folder(campaign_path: str, runs: str | None = None):
    """The runs folder a campaign file names (schema.campaign_output: no case is built)."""
    from interphase.campaign.schema import campaign_output

    return campaign_output(campaign_path, runs)[0]


def _cmd_pack(args) -> int:
    from interphase.campaign.pack import pack_runs

    written = pack_runs(args.runs, args.output)
    if args.json:
        _print_json({"tables": [{"path": str(p), "runs": n} for p, n in written]})
    else:
        for p, n in written:
            print(f"{p}: {n} finished run(s)")
    return 0


def _cmd_report(args) -> int:
    from interphase.report.build import build_report

    if args.bootstrap < 0:
        raise InputError(f"must be ≥ 0, got {args.bootstrap}", where="--bootstrap")
    if args.animate:
        from interphase.report.build import build_animations

        paths = build_animations(args.campaign, args.animate, out=args.output, output=args.runs)
        if args.json:
            _print_json({"files": [str(p) for p in paths], "warnings": []})
        else:
            for p in paths:
                print(f"wrote {p}")
        return 0
    res = build_report(args.campaign, out=args.output, lab=args.lab, n_boot=args.bootstrap, output=args.runs)
    runs = _runs_folder(args.campaign, args.runs)
    if args.json:
        _print_json({"folder": str(res.folder), "runs": str(runs), "files": [str(f) for f in res.files],
                     "warnings": res.warnings})
        return 0
    print(f"read the runs in {runs}")
    for w in res.warnings:
        print(f"warning: {w}", file=sys.stderr)
    print(f"wrote {len(res.files)} files to {res.folder}; open {res.folder / 'index.html'}")
    return 0


def _cmd_predict_dem(args) -> int:
    """`campaign predict PROFILE --friction MU --soil CARD --simulate`: the DEM instead of the fit."""
    from pathlib import Path

    from interphase.api import predict_dem
    from interphase.campaign.validate import check_dem_request
    from interphase.soil import card_d50_mm, load_card

    if args.soil is None:
        raise InputError("--simulate runs the DEM with a soil card's grains", where="--simulate",
                         fix="add --soil CARD (soils/NAME.toml)")
    from interphase.answer import friction_from

    if args.normal_stress is None:
        args.normal_stress = 100e3
    args.friction = friction_from(args.friction, args.smooth_delta)
    if args.relative_density is not None:
        raise InputError("--simulate runs the card at its own preparation", where="--relative-density",
                         fix="drop --relative-density, or drop --simulate (the criterion reads the card's table)")
    check_dem_request(args.friction, args.seeds, args.normal_stress, ("--friction", "--seeds", "--normal-stress"))
    for flag, value in (("--fit", args.fit), ("--tan-phi", args.tan_phi), ("--filter", args.filter)):
        if value is not None:
            raise InputError(f"{flag} is the criterion's; --simulate runs the DEM instead", where=flag,
                             fix=f"drop {flag}, or drop --simulate")
    card_d50_mm(load_card(args.soil), args.d50, "the DEM uses the card's grains")
    stream = sys.stderr if args.json else sys.stdout
    out = predict_dem(args.profile, args.friction, args.soil, seeds=args.seeds, normal_stress=args.normal_stress,
                      runs=args.runs, jobs=args.jobs, units=args.units, stream=stream)
    if args.json:
        _print_json(out)
        return 0
    print(f"DEM on {args.profile} with {Path(out['soil']).stem} in {out['cell']} (μs {args.friction:g}, "
          f"{args.normal_stress / 1e3:g} kPa, {out['seeds']} seeds): tan δ {out['tan_delta']:.3f} "
          f"[{out['tan_delta_lo']:.3f}, {out['tan_delta_hi']:.3f}], "
          f"δ {out['delta_deg']:.2f}° [{out['delta_deg_lo']:.2f}, {out['delta_deg_hi']:.2f}], "
          f"E {out['E']:.3f} [{out['E_lo']:.3f}, {out['E_hi']:.3f}], tan φ {out['tan_phi']:.3f}")
    return 0


def _cmd_predict(args) -> int:
    """`campaign predict`: the answer (interphase.answer) printed as one paragraph, or as JSON."""
    from interphase.api import predict

    if args.simulate:
        return _cmd_predict_dem(args)
    ans = predict(args.profile, friction=args.friction, smooth_delta_deg=args.smooth_delta, soil=args.soil,
                  fit=args.fit, d50=None if args.d50 is None else _d50_m(args.d50), tan_phi=args.tan_phi,
                  normal_stress=args.normal_stress, relative_density=args.relative_density, units=args.units,
                  axis=args.axis, filt=args.filter)
    if args.json:
        _print_json(ans.to_dict())
    else:
        print(ans.paragraph())
    return 0


class _Parser(argparse.ArgumentParser):
    """argparse takes "-100e3" for an option (its negative-number pattern knows no exponent), so
    `--normal-stress -100e3` failed with "expected one argument" instead of reaching the command's
    own check ("must be > 0 Pa"). Every number, exponent or not, is a value here."""

    def __init__(self, *args, **kwargs):
        import re

        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-inf$|^-nan$")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="campaign",
        description="DEM interface-shear campaigns (LIGGGHTS, YADE) and the θa → θr → E criterion.",
    )
    parser.add_argument("--version", action="version", version=f"interphase-dem {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    _add_surface(sub)
    _add_engine(sub)
    _add_campaign(sub)
    _add_crosscheck(sub)
    _add_compare(sub)
    _add_report(sub)
    from interphase.cli_soils import add_soils

    add_soils(sub, _print_json)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except InputError as exc:
        print(f"campaign {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"campaign {args.command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # `campaign … | head`: the reader left; not an error of ours, and no traceback
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
