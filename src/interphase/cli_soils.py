"""The soil commands of `campaign`: `element` (the soil's own test) and `calibrate` (grain parameters
from a laboratory target). Argument parsing and printing only; the work is in interphase.soil,
campaign.element and campaign.calibrate."""

from __future__ import annotations

import sys


def add_soils(sub, print_json) -> None:
    p = sub.add_parser("element", help="the soil's element test: φ_peak, φ_cs, ψ_max and solid fraction with seed "
                       "intervals (periodic shear cell of the soil alone)")
    p.add_argument("card", help="soil card (soils/NAME.toml)")
    p.add_argument("--normal-stress", type=float, action="append", metavar="PA",
                   help="direct shear: normal stress [Pa] (repeatable)")
    p.add_argument("--test", choices=("shear", "triaxial", "biaxial"), default=None,
                   help="shear (the periodic direct shear, the default with --normal-stress), or the laboratory's "
                   "triaxial (3D) / biaxial (quasi-2D) compression (the default with --confining-stress: the card's "
                   "[cell] test)")
    p.add_argument("--confining-stress", type=float, action="append", metavar="PA",
                   help="triaxial/biaxial: confining stress σ3′ [Pa] (repeatable)")
    p.add_argument("--relative-density", type=float, default=None, metavar="DR",
                   help="triaxial/biaxial: relative density, a fraction (default: the card's [cell] relative_density, else its preparation)")
    p.add_argument("--record", action="append", default=None, metavar="FILE",
                   help="triaxial/biaxial: a laboratory record (repeatable); the card's test runs at its σ3′ (the "
                   "nearest 50 kPa) and Dr0 (on the card's [target] e_min, e_max), with verdicts against it")
    p.add_argument("--report", default=None, metavar="DIR",
                   help="triaxial/biaxial: write the model-against-laboratory report there (verification.csv/.md, "
                   "curves, angles)")
    p.add_argument("--seeds", type=int, default=3, help="packing seeds 1…N (default 3)")
    p.add_argument("--shear-velocity", type=float, default=None, metavar="M/S",
                   help="shear speed [m/s] (default: the card's [element] speed, else 0.02: quasi-static)")
    _run_options(p, runs="runs/element/<card name> beside the card")
    p.set_defaults(func=lambda a: _cmd_element(a, print_json))

    p = sub.add_parser("density", help="the void ratios a card's grains reach by the cell's preparation: e_min "
                       "(frictionless), e_max (the grains' own friction) and between; written into the card's [density]")
    p.add_argument("card", help="soil card (soils/NAME.toml)")
    p.add_argument("--seeds", type=int, default=3, help="packing seeds 1…N (default 3)")
    _run_options(p, runs="runs/density/<card name> beside the card")
    p.set_defaults(func=lambda a: _cmd_density(a, print_json))

    p = sub.add_parser("calibrate", help="calibrate grain parameters to a laboratory soil (GrainLearning: "
                       "Bayesian, iterative); writes a soil card with its posterior")
    p.add_argument("target", help="calibration target (TOML: soil, laboratory values with their source, free "
                   "parameters with ranges)")
    p.add_argument("--quick", action="store_true", help="the smallest budget (tests, a first look); the card is "
                   "NAME-quick and says so")
    p.add_argument("-o", "--output", default=None, metavar="CARD",
                   help="the soil card to write, never over another card (default: [target] card, else "
                   "soils/<target name>.toml beside the target file)")
    p.add_argument("--restore", default=None, metavar="PACK",
                   help="first bring back the finished runs a `campaign pack` of this calibration's runs folder "
                   "holds (rows taken by case id), so a calibration goes on on a fresh machine")
    _run_options(p, runs="[target] runs, else runs/calibrate/<target name> beside the target file")
    p.set_defaults(func=lambda a: _cmd_calibrate(a, print_json))

    p = sub.add_parser("validate", help="the criterion (and, with --simulate, the DEM on the calibrated soil) "
                       "against laboratory interface tests: predicted vs measured δ, with both baselines")
    p.add_argument("lab", help="laboratory CSV (lab/README.md: one row per published test, with its source)")
    p.add_argument("--soil", default=None, metavar="CARD",
                   help="soil card (default: the shipped card of the rows' soil, named in the output)")
    p.add_argument("--fit", default=None, help="the criterion's fits: criterion.json, a campaign file or 'study' "
                   "(default: the reproduction's, shipped)")
    p.add_argument("--simulate", action="store_true", help="also run every row in the DEM on the card's soil")
    p.add_argument("--seeds", type=int, default=3, help="packing seeds 1…N for --simulate (default 3)")
    p.add_argument("-o", "--output", default=None, metavar="DIR",
                   help="folder for the table and figure, new or holding this same validation (default: "
                   "runs/validate/<lab file name> beside the lab file)")
    _run_options(p, runs="runs/validate/<lab file name>/runs beside the lab file; --simulate's runs")
    p.set_defaults(func=lambda a: _cmd_validate(a, print_json))

    p = sub.add_parser("lab-record", help="a laboratory drained triaxial record (lab/soils/): φ_peak, ε1 at peak, "
                       "ψ_max and the end state (docs/soils.md, Laboratory records)")
    p.add_argument("files", nargs="+", metavar="FILE", help="record(s): Karlsruhe .dat or Ottawa F-65 .csv")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=lambda a: _cmd_lab_record(a, print_json))


def _run_options(p, runs: str) -> None:
    """The options every soil command that runs cases takes: where (--runs: every run the command
    makes), how (--executor, --jobs, --rerun-failed) and how it prints (--json)."""
    p.add_argument("--runs", default=None, metavar="DIR", help=f"runs folder of every run (default: {runs})")
    p.add_argument("--executor", choices=("local", "slurm"), default=None)
    p.add_argument("--jobs", type=int, default=None, help="cases at a time (default: one per core)")
    p.add_argument("--rerun-failed", action="store_true", help="run failed cases again")
    p.add_argument("--json", action="store_true", help="print JSON")


def _check_seeds(n: int) -> None:
    from interphase.errors import InputError

    if n < 1:
        raise InputError(f"must be ≥ 1, got {n}", where="--seeds", fix="give the number of packing seeds, e.g. 3")


def _positive(value, flag: str, unit: str, example: str) -> None:
    import math

    from interphase.errors import InputError

    if not (math.isfinite(value) and value > 0):
        raise InputError(f"must be > 0 {unit}, got {value!r}", where=flag, fix=f"e.g. {flag} {example}")


def _quick_note(card, stream) -> None:
    """Every command that reads a --quick card says so."""
    if card.quick:
        runs = card.extra.get("calibration", {}).get("runs", "?")
        print(f"warning: {card.path} is a --quick calibration ({runs} runs): a first look, not a calibrated soil",
              file=stream)


def _cmd_element(args, print_json) -> int:
    from interphase.campaign.element import element_failures, run_element
    from interphase.campaign.folders import element_runs
    from interphase.errors import InputError
    from interphase.soil import load_card

    card = load_card(args.card)
    _quick_note(card, sys.stderr)
    _check_seeds(args.seeds)
    if args.test in ("triaxial", "biaxial") or ((args.confining_stress or args.record) and args.test is None):
        return _cmd_cell(args, print_json)
    if args.record or args.report:
        raise InputError("--record and --report are for the laboratory's test", where="--record/--report",
                         fix="add --test triaxial (3D) or --test biaxial (quasi-2D), or drop them")
    if not args.normal_stress:
        raise InputError("no stress given", where="--normal-stress",
                         fix="direct shear: --normal-stress PA; the laboratory's test: --confining-stress PA")
    for s in args.normal_stress:
        _positive(s, "--normal-stress", "Pa", "100e3")
    if args.shear_velocity is not None:
        _positive(args.shear_velocity, "--shear-velocity", "m/s", "0.02")
    stream = sys.stderr if args.json else sys.stdout
    runs, runs_from = element_runs(card.path, card.name, args.runs)
    print(f"element {card.name}: runs folder {runs} ({runs_from})", file=stream, flush=True)
    results = run_element(card, args.normal_stress, range(1, args.seeds + 1), output=runs, executor=args.executor,
                          jobs=args.jobs, stream=stream, rerun_failed=args.rerun_failed,
                          shear_velocity=args.shear_velocity)
    failed = element_failures(card, runs) if any(r.n_seeds < args.seeds for r in results) else []
    for line in failed:
        print(f"failed: {line}", file=sys.stderr)
    if failed:
        print("(a failed run is kept; `campaign element … --rerun-failed` runs it again)", file=sys.stderr)
    if args.json:
        rows = [r.to_dict() | {"runs": str(runs), "card_quick": card.quick, "failed": failed} for r in results]
        print_json(rows)          # one shape: a list, one entry per stress
        return 0 if all(r.n_seeds for r in results) else 1
    for r in results:
        _print_element(card, r)
    return 0 if all(r.n_seeds for r in results) else 1


def _print_element(card, r) -> None:
    def iv(name, fmt=".1f"):
        v, lo, hi = (getattr(r, name + k) for k in ("", "_lo", "_hi"))
        return f"{v:{fmt}}" + (f" ({lo:{fmt}}–{hi:{fmt}})" if lo == lo else "")
    if not r.n_seeds:
        print(f"{card.name} at {r.normal_stress / 1e3:g} kPa: no seed finished (the causes are above)")
        return
    print(f"{card.name} at {r.normal_stress / 1e3:g} kPa, {r.n_seeds} seeds: φ_peak {iv('phi_peak_deg')}°, "
          f"φ_cs {iv('phi_cs_deg')}°, ψ_max {iv('psi_max_deg')}°, solid fraction {iv('solid_fraction', '.3f')}, "
          f"peak at {r.peak_disp * 1e3:.2f} of {r.shear_distance * 1e3:.2f} mm")
    if r.note:
        print(f"  note: {r.note}")


def _cmd_cell(args, print_json) -> int:
    from interphase.campaign.cell import run_cell
    from interphase.campaign.folders import element_runs
    from interphase.errors import InputError
    from interphase.soil import load_card

    if args.record:
        return _cmd_records(args, print_json)
    if not args.confining_stress:
        raise InputError("no confining stress given", where="--confining-stress",
                         fix="e.g. --confining-stress 100e3, or --record FILE to test at a laboratory record's")
    for s in args.confining_stress:
        _positive(s, "--confining-stress", "Pa", "100e3")
    card = load_card(args.card)
    stream = sys.stderr if args.json else sys.stdout
    runs, runs_from = element_runs(card.path, card.name, args.runs)
    print(f"element {card.name}: runs folder {runs} ({runs_from})", file=stream, flush=True)
    results = run_cell(card, args.confining_stress, range(1, args.seeds + 1), test=args.test,
                       relative_density=args.relative_density, output=runs, executor=args.executor,
                       jobs=args.jobs, stream=stream, rerun_failed=args.rerun_failed)
    if args.report:
        from interphase.campaign.cell_records import model_runs
        from interphase.report.verification import write_report

        test = args.test or card.cell["test"]
        dr = card.relative_density if args.relative_density is None else args.relative_density
        curves = model_runs(runs, card, test, dr)
        pairs = [(f"{r.test}, {r.confining_stress / 1e3:g} kPa, Dr {r.relative_density:.2f}", None,
                  curves[r.confining_stress]) for r in results]
        for p in write_report(args.report, [], pairs):
            print(f"report: {p}", file=stream)
    if args.json:
        rows = [r.to_dict() for r in results]
        print_json(rows)          # one shape: a list, one entry per stress
        return 0 if all(r.n_seeds for r in results) else 1
    for r in results:
        def iv(name, fmt=".1f"):
            v, lo, hi = (getattr(r, name + k) for k in ("", "_lo", "_hi"))
            return f"{v:{fmt}}" + (f" ({lo:{fmt}}–{hi:{fmt}})" if lo == lo else "")
        dr = f", Dr {r.relative_density:.2f}" if r.relative_density == r.relative_density else ""
        print(f"{card.name}, {r.test} at σ3′ {r.confining_stress / 1e3:g} kPa, {r.n_seeds} seeds: "
              f"φ_peak {iv('phi_peak_deg')}° at ε1 {100 * r.eps1_at_peak:.1f} %, ψ_max {iv('psi_max_deg')}°, "
              f"φ at ε1 {100 * r.eps1_end:.0f} % {iv('phi_cs_deg')}°, e0 {iv('void_ratio', '.3f')}{dr} "
              f"(preparation {r.preparation:g})")
        if r.note:
            print(f"  note: {r.note}")
    return 0 if all(r.n_seeds for r in results) else 1


def _cmd_records(args, print_json) -> int:
    """`campaign element CARD --record FILE …`: the card's test at each record's σ3′ and Dr0, verdicts."""
    from pathlib import Path

    from interphase.campaign.cell_records import check_record, index_void_ratios
    from interphase.campaign.folders import element_runs
    from interphase.report.verification import markdown, write_report
    from interphase.errors import InputError
    from interphase.soil import load_card

    card = load_card(args.card)
    if args.confining_stress or args.relative_density is not None:
        raise InputError("a record sets the test's stress and density itself",
                         where="--confining-stress/--relative-density", fix="drop them, or drop --record")
    test = args.test or card.cell["test"]
    if test != card.cell["test"]:
        raise InputError(f"the card's cell runs the {card.cell['test']} test, not {test}", where="--test",
                         fix=f"--test {card.cell['test']}, or a card of the other test")
    index_void_ratios(card)                 # before any run: a card without them is refused at once
    stream = sys.stderr if args.json else sys.stdout
    runs, runs_from = element_runs(card.path, card.name, args.runs)
    print(f"element {card.name}: runs folder {runs} ({runs_from})", file=stream, flush=True)
    rows, pairs = [], []
    for path in args.record:
        row, pair = check_record(card, Path(path), list(range(1, args.seeds + 1)), runs, executor=args.executor,
                                 jobs=args.jobs, stream=stream, rerun_failed=args.rerun_failed)
        rows.append(row)
        pairs.append(pair)
    if args.report:
        for p in write_report(args.report, rows, pairs):
            print(f"report: {p}", file=stream)
    if args.json:
        print_json(rows)
    else:
        import pandas as pd

        print(markdown(pd.DataFrame(rows)))
    return 0 if all(r["n_seeds"] for r in rows) else 1


def _cmd_density(args, print_json) -> int:
    from interphase.campaign.density import measure_density
    from interphase.soil import load_card

    from interphase.campaign.density import density_runs

    _check_seeds(args.seeds)
    card = load_card(args.card)
    stream = sys.stderr if args.json else sys.stdout
    runs, runs_from = density_runs(card, args.runs)
    print(f"density {card.name}: runs folder {runs} ({runs_from})", file=stream, flush=True)
    out = measure_density(card, range(1, args.seeds + 1), output=runs, executor=args.executor, jobs=args.jobs,
                          stream=stream, rerun_failed=args.rerun_failed)
    if args.json:
        print_json(out)
        return 0
    print(f"{out['card']}: e_min {out['e_min']:.4f}, e_max {out['e_max']:.4f} at {out['reference_stress'] / 1e3:g} kPa "
          f"({out['seeds']} seeds); preparation → e: " + ", ".join(
              f"{p:g} → {e:.4f}" for p, e in zip(out["preparations"], out["void_ratios"])))
    print(f"[density] {'written into' if out['written'] else 'already in'} {out['card']}")
    return 0


def _cmd_calibrate(args, print_json) -> int:
    from interphase.campaign.calibrate import calibrate
    from interphase.campaign.calibrate_cell import calibrate_cell, is_cell_target

    if is_cell_target(args.target):
        result = calibrate_cell(args.target, quick=args.quick, card_path=args.output, output=args.runs,
                                executor=args.executor, jobs=args.jobs, stream=sys.stderr if args.json else sys.stdout,
                                rerun_failed=args.rerun_failed, restore=args.restore)
        if args.json:
            print_json(result)
        else:
            _print_cell_calibration(result)
        return 0

    nan = float("nan")
    result = calibrate(args.target, quick=args.quick, card_path=args.output, output=args.runs,
                       executor=args.executor, jobs=args.jobs, stream=sys.stderr if args.json else sys.stdout,
                       rerun_failed=args.rerun_failed, restore=args.restore)
    if args.json:
        print_json(result)
        return 0
    quick = " (--quick: a first look, not a calibrated soil)" if result["calibration"].get("quick") else ""
    print(f"soil card {'read back' if result.get('reused') else 'written'}: {result['card']}{quick}")
    for k, v in result["chosen"].items():
        post = result["posterior"].get(k, {})
        print(f"  {k} = {v:.4g} ({post.get('lo', nan):.4g}–{post.get('hi', nan):.4g})")
    for a in result["achieved"]:
        print(f"  {a['quantity']}: target {a['target']:.1f}°, achieved {a['value']:.1f}° "
              f"({a.get('lo', nan):.1f}–{a.get('hi', nan):.1f}): {a.get('verdict', '?')}")
    for v in result["verification"]:
        for c in v["checks"]:
            print(f"  held out, {v['normal_stress'] / 1e3:g} kPa, {c['quantity']}: laboratory {c['laboratory']:.1f}°, "
                  f"measured {c['measured']:.1f}° ({c.get('lo', nan):.1f}–{c.get('hi', nan):.1f}): {c.get('verdict', '?')}")
    return 0


def _print_cell_calibration(result: dict) -> None:
    print(f"soil card written: {result['card']} (e_min {result['density']['e_min']:.3f}, e_max "
          f"{result['density']['e_max']:.3f})")
    for k, v in result["chosen"].items():
        print(f"  {k} = {v:.4g} ({result['posterior'][k]['lo']:.4g}–{result['posterior'][k]['hi']:.4g})")
    for v in [{"record": "fitted", "checks": result["achieved"]}, *result["verification"]]:
        for c in v["checks"]:
            iv = f" ({c['lo']:.1f}–{c['hi']:.1f})" if c.get("lo") is not None and c["lo"] == c["lo"] else ""
            print(f"  {v['record']}, {c['quantity']}: laboratory {c['laboratory']:.2f}, model {c['measured']:.2f}{iv}"
                  + (f": {c['verdict']}" if "verdict" in c else ""))


def _cmd_validate(args, print_json) -> int:
    import json

    from interphase.api import validate
    _check_seeds(args.seeds)
    res = validate(args.lab, soil=args.soil, fit=args.fit, simulate=args.simulate, seeds=args.seeds,
                   output=args.output, runs=args.runs, executor=args.executor, jobs=args.jobs,
                   rerun_failed=args.rerun_failed, stream=sys.stderr if args.json else sys.stdout)
    df, sk, miss = res["table"], res["skill"], res["largest_miss"]
    if args.json:
        print_json(res | {"table": json.loads(df.to_json(orient="records")),
                          "skill": json.loads(sk.to_json(orient="records")), "folder": str(res["folder"]),
                          "files": [str(f) for f in res["files"]]})
        return 0
    print((res["folder"] / "validation.md").read_text())
    for n in res["notes"]:
        print("note:", n)
    if miss:
        print(f"largest miss: line {miss['row']} ({miss['soil']}, {miss['surface']}, {miss['normal_stress_kpa']:g} kPa): "
              f"{miss['error_deg']:+.1f}° ({miss['source']}, {miss['table_or_figure']})")
    print(("kept (unchanged): " if res.get("kept") else "written: ") + ", ".join(str(f) for f in res["files"]))
    return 0


def _cmd_lab_record(args, print_json) -> int:
    from interphase.api import lab_record

    rows = [lab_record(f) for f in args.files]           # every file read before anything is printed
    if args.json:
        print_json(rows)
        return 0
    for r in rows:
        end = (f"last {100 * r['end_span']:g} % ({100 * r['eps1_end_from']:.1f}–{100 * r['eps1_last']:.1f} %): "
               f"φ {r['phi_end_deg']:.1f}°, e {r['e_end']:.3f}, −dεv/dε1 {r['dilatancy_end']:.2f}")
        print(f"{r['file']}: e0 {r['e0']:.4f}, σ3′ {r['sigma3_start'] / 1e3:.1f} kPa, {r['rows']} rows | "
              f"φ_peak {r['phi_peak_deg']:.1f}° at ε1 {100 * r['eps1_peak']:.1f} %, ψ_max {r['psi_max_deg']:.1f}° "
              f"(−dεv/dε1 {r['dilatancy_max']:.2f} from ε1 {100 * r['eps1_psi']:.1f} %) | end: {end}")
    return 0
