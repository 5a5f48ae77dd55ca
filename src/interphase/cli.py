"""The `campaign` command: parses arguments, calls one function of the Python API (interphase.api)
per verb and prints what it returns. Every check and every computation is the API's, so a script
and the command refuse and answer alike; what is here is the options, the text and the JSON.

Every user error (InputError) ends with one message on stderr and exit code 2, never a traceback.
Every command that prints numbers has --json.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

from interphase import api
from interphase.cli_text import status_text
from interphase.errors import InputError
from interphase.version import __version__


def _jsonable(obj):
    """NaN/inf → null (strict JSON); numpy scalars → Python numbers; paths → strings."""
    import math

    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    if hasattr(obj, "item") and not isinstance(obj, (str, bytes)):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def _print_json(obj) -> None:
    print(json.dumps(_jsonable(obj), indent=2, sort_keys=True, allow_nan=False))


def _without(d: dict, *keys) -> dict:
    """`d` without the keys an API result carries for the text only (the JSON stays as it is)."""
    return {k: v for k, v in d.items() if k not in keys}


def _mm(value):
    """An option given in mm, in metres (the API's unit); None stays None."""
    return None if value is None else value * 1e-3


def _given(**options) -> dict:
    """The options given (not None): the API's defaults stand for the rest."""
    return {k: v for k, v in options.items() if v is not None}


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
    for kind, text in (("sawtooth", "Groups 1 and 3: triangles, no spacing"),
                       ("spaced", "Group 2: triangles with flat spacing Sr"),
                       ("random", "Group 4: random segments (Au, Ar, Rtmax, seed)")):
        params = api.PROFILE_KINDS[kind]
        q = psub.add_parser(kind, help=text)
        for name in params:
            q.add_argument(f"--{name}", type=int if name == "seed" else float, required=True,
                           help="integer seed" if name == "seed" else f"{name} [D50]")
        for flag, kw in common.values():
            q.add_argument(flag, **kw)
        q.add_argument("-o", "--output", required=True, help="output file (two columns x z in mm)")
        q.set_defaults(func=_cmd_profile_make, kind=kind, sizes=params)
    q = psub.add_parser("plot", help="profile, centroid trace and polar normal distribution to PNG")
    q.add_argument("profile")
    q.add_argument("--d50", type=float, default=0.7, help="D50 [mm]")
    q.add_argument("--units", default=None, help="um | mm | m (default: file's own, else mm)")
    q.add_argument("--filter", type=int, default=92, choices=(92, 90))
    q.add_argument("-o", "--output", default=None, help="PNG path (default: PROFILE.png)")
    q.set_defaults(func=_cmd_profile_plot)


def _cmd_theta_a(args) -> int:
    out = api.theta_a(args.profile, _mm(args.d50), filt=args.filter, units=args.units, cutoff=_mm(args.cutoff),
                      axis=args.axis)
    if args.json:
        _print_json(_without(out, "size_mm", "min_run_d50"))
    elif out["areal"]:
        _print_theta_a_areal(out, args.filter)
    else:
        _print_theta_a_line(out, args.filter)
    return 0


def _print_theta_a_line(out: dict, filt: int) -> None:
    print(f"profile            {out['profile']}  (D50 = {out['d50_mm']:g} mm, filter {filt}°)")
    for d, r in out["directions"].items():
        if r["dilative"]:
            print(f"θa ({d})            {r['theta_a_deg']:.2f}° from vertical  ({r['theta_a_ccw_deg']:.2f}° ccw from {d})")
        else:
            print(f"θa ({d})            undefined — {r['reason']}")
    print(f"Rn, Rnc(D50)       {out['rn']:.4f}, {out['rnc']:.4f}")
    print(f"mean asperity slope {out['mean_slope_deg']:.2f}° (flats < 2° excluded)")
    print(f"trace points       {out['n_points']}")


def _print_theta_a_areal(out: dict, filt: int) -> None:
    """An areal scan: every grid line along the axis is a profile; θa in the four shear directions."""
    (nx, ny), (sx, sy), axis = out["shape"], out["size_mm"], out["axis"]
    print(f"scan               {out['profile']}  (areal {nx} × {ny}, {sx:.4g} × {sy:.4g} mm, "
          f"{out['missing_points']} missing points; {out['reader']})")
    print(f"                   D50 = {out['d50_mm']:g} mm, filter {filt}°; lines split at missing points, runs "
          f"< {out['min_run_d50']:g}·D50 dropped, each run levelled")
    if out["dilative"]:
        print(f"θa (+{axis})            {out['theta_a_deg']:.2f}° from vertical  ({out['theta_a_ccw_deg']:.2f}° ccw "
              f"from +{axis})")
    else:
        print(f"θa (+{axis})            undefined — {out['reason']}")
    print("shear  θa [°]   per-run 5–95 % [°]   runs  dropped  with θa   Rn      Rnc     slope [°]")
    for d, r in out["directions"].items():
        if "error" in r:
            print(f"{d:<6} —  {r['error']}")
            continue
        ta = f"{r['theta_a_deg']:6.2f}" if r["dilative"] else "   n-d"
        sp = f"{r['spread_deg'][0]:6.2f} – {r['spread_deg'][1]:6.2f}" if r["n_runs_dilative"] else "      —        "
        print(f"{d:<6} {ta}   {sp}      {r['n_runs']:5d}  {r['n_dropped']:7d}  {r['n_runs_dilative']:7d}   "
              f"{r['rn']:.4f}  {r['rnc']:.4f}  {r['mean_slope_deg']:6.2f}")
    print("(n-d: non-dilative, no pooled trace normal beyond the filter)")


def _cmd_profile_make(args) -> int:
    res = api.make_profile(args.kind, args.output, d50=_mm(args.d50), length=_mm(args.length),
                           **{name: getattr(args, name) for name in args.sizes})
    print(f"wrote {res['output']} ({res['vertices']} vertices, {res['length'] * 1e3:.3f} mm)")
    return 0


def _cmd_profile_plot(args) -> int:
    out = api.plot_profile(args.profile, args.output, d50=_mm(args.d50), units=args.units, filt=args.filter)
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


def _cmd_render(args) -> int:
    res = api.render(args.case, args.output, engine=args.engine, stream=sys.stderr)
    if args.json:
        _print_json(res)
    else:
        print("\n".join(f"{res['folder']}/{name}" for name in res["files"]))
    return 0


def _cmd_run_case(args) -> int:
    res = api.run_case(args.case, args.output, engine=args.engine, stream=sys.stderr)
    if res["status"] != "done":
        print(f"campaign run-case: {args.engine} {res['status']}: {res['cause']}: {res['message']}", file=sys.stderr)
        return 1
    if res["skipped"]:
        print(f"campaign run-case: {res['folder']} already holds this case, finished: its result is read back, "
              "nothing was rerun", file=sys.stderr)
    out = _without(res, "status")
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


def _cmd_campaign_run(args) -> int:
    report = api.run(args.campaign, runs=args.runs, engine=args.engine, executor=args.executor, jobs=args.jobs,
                     rerun_failed=args.rerun_failed, rerun_stale=args.rerun_stale, dry_run=args.dry_run,
                     restore=args.restore, yes=args.yes, render=args.render, list_all=args.list_all,
                     stream=sys.stderr if args.json else None, live=False if (args.plain or args.json) else None)
    if args.json:
        counts: dict = {}
        for status in report.statuses.values():
            counts[status] = counts.get(status, 0) + 1
        _print_json({"campaign": report.campaign, "runs": str(report.output), "dry_run": report.dry_run,
                     "planned": report.planned, "counts": counts, "ran": report.ran,
                     "interrupted": report.interrupted, "exit_code": report.exit_code})
    return report.exit_code


def _cmd_campaign_stop(args) -> int:
    res = api.stop(args.campaign, runs=args.runs)
    print(f"campaign {res['campaign']}: wrote {res['file']}: a local run starts no new case and ends "
          "when its running cases have finished (Ctrl-C or SIGTERM stops them now); SLURM runs: scancel its jobs")
    return 0


def _cmd_campaign_status(args) -> int:
    from types import SimpleNamespace

    df = api.status(args.campaign, runs=args.runs, engine=args.engine)
    campaign = SimpleNamespace(name=df.attrs["campaign"], output=df.attrs["runs"], output_from=df.attrs["runs_from"])
    if args.json:
        seeds = df.attrs["seeds"]
        extra = {} if seeds is None else {"seeds": seeds.astype(object).where(seeds.notna(), None).to_dict(orient="records")}
        _print_json({"campaign": campaign.name, "runs": str(campaign.output), "runs_from": campaign.output_from,
                     "counts": df["status"].value_counts().to_dict(),
                     "cases": df.astype(object).where(df.notna(), None).to_dict(orient="records"), **extra})
        return 0
    import shutil

    width = max(80, min(shutil.get_terminal_size((80, 24)).columns, 120))
    print("\n".join(status_text(campaign, df, width)))
    return 0


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
    report = api.crosscheck(args.campaign, runs=args.runs, jobs=args.jobs, rerun_failed=args.rerun_failed,
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
    table = api.compare(args.reference, args.variant, by=_by_fields(args.by), output=args.output)
    if args.json:
        _print_json(table.to_dict(orient="records"))
        return 0
    for path, runs in table.attrs["runs"]:
        print(f"read the runs of {path} in {runs}")
    if args.by:
        print(f"reference cell: {table.attrs['reference']}")
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


def _cmd_pack(args) -> int:
    tables = api.pack(args.runs, args.output)
    if args.json:
        _print_json({"tables": tables})
    else:
        for t in tables:
            print(f"{t['path']}: {t['runs']} finished run(s)")
    return 0


def _cmd_report(args) -> int:
    if args.animate:
        paths = api.animations(args.campaign, args.animate, output=args.output, runs=args.runs)
        if args.json:
            _print_json({"files": paths, "warnings": []})
        else:
            for p in paths:
                print(f"wrote {p}")
        return 0
    res = api.report(args.campaign, output=args.output, runs=args.runs, lab=args.lab, bootstrap=args.bootstrap)
    if args.json:
        _print_json(res)
        return 0
    print(f"read the runs in {res['runs']}")
    for w in res["warnings"]:
        print(f"warning: {w}", file=sys.stderr)
    print(f"wrote {len(res['files'])} files to {res['folder']}; open {res['folder'] / 'index.html'}")
    return 0


#: the criterion's options, which `predict --simulate` (the DEM) does not take
CRITERION_ONLY = (("--relative-density", "relative_density", "--simulate runs the card at its own preparation",
                   "drop --relative-density, or drop --simulate (the criterion reads the card's table)"),
                  ("--fit", "fit", None, None), ("--tan-phi", "tan_phi", None, None), ("--filter", "filter", None, None))


def _cmd_predict_dem(args) -> int:
    """`campaign predict PROFILE --friction MU --soil CARD --simulate`: the DEM instead of the fit."""
    from pathlib import Path

    for flag, name, message, fix in CRITERION_ONLY:
        if getattr(args, name) is not None:
            raise InputError(message or f"{flag} is the criterion's; --simulate runs the DEM instead", where=flag,
                             fix=fix or f"drop {flag}, or drop --simulate")
    out = api.predict_dem(args.profile, args.friction, args.soil, smooth_delta_deg=args.smooth_delta, seeds=args.seeds,
                          runs=args.runs, jobs=args.jobs, units=args.units, d50=_mm(args.d50), axis=args.axis,
                          stream=sys.stderr if args.json else sys.stdout, **_given(normal_stress=args.normal_stress))
    if args.json:
        _print_json(out)
        return 0
    print(f"DEM on {args.profile} with {Path(out['soil']).stem} in {out['cell']} (μs {out['friction']:g}, "
          f"{out['normal_stress'] / 1e3:g} kPa, {out['seeds']} seeds): tan δ {out['tan_delta']:.3f} "
          f"[{out['tan_delta_lo']:.3f}, {out['tan_delta_hi']:.3f}], "
          f"δ {out['delta_deg']:.2f}° [{out['delta_deg_lo']:.2f}, {out['delta_deg_hi']:.2f}], "
          f"E {out['E']:.3f} [{out['E_lo']:.3f}, {out['E_hi']:.3f}], tan φ {out['tan_phi']:.3f}; θa of the surface "
          f"sheared {out['theta_a_deg_92']:.2f}°")
    return 0


def _cmd_predict(args) -> int:
    """`campaign predict`: the answer (interphase.answer) printed as one paragraph, or as JSON."""
    if args.simulate:
        return _cmd_predict_dem(args)
    ans = api.predict(args.profile, friction=args.friction, smooth_delta_deg=args.smooth_delta, soil=args.soil,
                      fit=args.fit, d50=_mm(args.d50), tan_phi=args.tan_phi, normal_stress=args.normal_stress,
                      relative_density=args.relative_density, units=args.units, axis=args.axis, filt=args.filter)
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
