"""The soil commands of `campaign`: `element` (the soil's own tests), `density`, `calibrate` (grain
parameters from a laboratory target), `validate` and `lab-record`. Argument parsing and printing
only: each command calls its function of interphase.api."""

from __future__ import annotations

import sys

from interphase import api
from interphase.errors import InputError


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


def _stream(args):
    """Where a running command says what it does: stderr with --json (stdout stays parseable)."""
    return sys.stderr if args.json else sys.stdout


def _runs(args) -> dict:
    """The options every soil command that runs cases takes (_run_options), as the API's arguments."""
    return {"runs": args.runs, "executor": args.executor, "jobs": args.jobs, "rerun_failed": args.rerun_failed,
            "stream": _stream(args)}


def _num(v) -> float:
    """A result's number for the text: None (undefined, as JSON has it) reads nan."""
    return float("nan") if v is None else v


def _iv(r: dict, name: str, fmt: str = ".1f") -> str:
    """`name` of a result with its 95 % interval when it has one."""
    v, lo, hi = (_num(r[name + k]) for k in ("", "_lo", "_hi"))
    return f"{v:{fmt}}" + (f" ({lo:{fmt}}–{hi:{fmt}})" if lo == lo else "")


def _cmd_element(args, print_json) -> int:
    if args.test in ("triaxial", "biaxial") or ((args.confining_stress or args.record) and args.test is None):
        return _cmd_cell(args, print_json)
    if args.record or args.report:
        raise InputError("--record and --report are for the laboratory's test", where="--record/--report",
                         fix="add --test triaxial (3D) or --test biaxial (quasi-2D), or drop them")
    rows = api.element(args.card, args.normal_stress, args.seeds, shear_velocity=args.shear_velocity, **_runs(args))
    failed = rows[0]["failed"] if rows else []
    for line in failed:
        print(f"failed: {line}", file=sys.stderr)
    if failed:
        print("(a failed run is kept; `campaign element … --rerun-failed` runs it again)", file=sys.stderr)
    if args.json:
        print_json([{k: v for k, v in r.items() if k != "card"} for r in rows])   # one shape: a list, one entry per stress
    else:
        for r in rows:
            _print_element(r)
    return 0 if all(r["n_seeds"] for r in rows) else 1


def _print_element(r: dict) -> None:
    if not r["n_seeds"]:
        print(f"{r['card']} at {r['normal_stress'] / 1e3:g} kPa: no seed finished (the causes are above)")
        return
    print(f"{r['card']} at {r['normal_stress'] / 1e3:g} kPa, {r['n_seeds']} seeds: φ_peak {_iv(r, 'phi_peak_deg')}°, "
          f"φ_cs {_iv(r, 'phi_cs_deg')}°, ψ_max {_iv(r, 'psi_max_deg')}°, solid fraction {_iv(r, 'solid_fraction', '.3f')}, "
          f"peak at {_num(r['peak_disp']) * 1e3:.2f} of {_num(r['shear_distance']) * 1e3:.2f} mm")
    if r["note"]:
        print(f"  note: {r['note']}")


def _cmd_cell(args, print_json) -> int:
    if args.record:
        return _cmd_records(args, print_json)
    rows = api.cell(args.card, args.confining_stress, args.seeds, test=args.test,
                    relative_density=args.relative_density, report=args.report, **_runs(args))
    if args.json:
        print_json([{k: v for k, v in r.items() if k != "card"} for r in rows])   # one shape: a list, one entry per stress
        return 0 if all(r["n_seeds"] for r in rows) else 1
    for r in rows:
        dr = f", Dr {r['relative_density']:.2f}" if r["relative_density"] is not None else ""
        print(f"{r['card']}, {r['test']} at σ3′ {r['confining_stress'] / 1e3:g} kPa, {r['n_seeds']} seeds: "
              f"φ_peak {_iv(r, 'phi_peak_deg')}° at ε1 {100 * _num(r['eps1_at_peak']):.1f} %, ψ_max {_iv(r, 'psi_max_deg')}°, "
              f"φ at ε1 {100 * _num(r['eps1_end']):.0f} % {_iv(r, 'phi_cs_deg')}°, e0 {_iv(r, 'void_ratio', '.3f')}{dr} "
              f"(preparation {_num(r['preparation']):g})")
        if r["note"]:
            print(f"  note: {r['note']}")
    return 0 if all(r["n_seeds"] for r in rows) else 1


def _cmd_records(args, print_json) -> int:
    """`campaign element CARD --record FILE …`: the card's test at each record's σ3′ and Dr0, verdicts."""
    if args.confining_stress or args.relative_density is not None:
        raise InputError("a record sets the test's stress and density itself",
                         where="--confining-stress/--relative-density", fix="drop them, or drop --record")
    rows = api.records(args.card, args.record, args.seeds, test=args.test, report=args.report, **_runs(args))
    if args.json:
        print_json(rows)
    else:
        print(api.records_markdown(rows))
    return 0 if all(r["n_seeds"] for r in rows) else 1


def _cmd_density(args, print_json) -> int:
    out = api.density(args.card, args.seeds, **_runs(args))
    if args.json:
        print_json(out)
        return 0
    print(f"{out['card']}: e_min {out['e_min']:.4f}, e_max {out['e_max']:.4f} at {out['reference_stress'] / 1e3:g} kPa "
          f"({out['seeds']} seeds); preparation → e: " + ", ".join(
              f"{p:g} → {e:.4f}" for p, e in zip(out["preparations"], out["void_ratios"])))
    print(f"[density] {'written into' if out['written'] else 'already in'} {out['card']}")
    return 0


def _cmd_calibrate(args, print_json) -> int:
    result = api.calibrate(args.target, quick=args.quick, output=args.output, restore=args.restore, **_runs(args))
    if args.json:
        print_json(result)
    elif "density" in result:          # a record target's card: the cell's calibration
        _print_cell_calibration(result)
    else:
        _print_calibration(result)
    return 0


def _print_calibration(result: dict) -> None:
    nan = float("nan")
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

    res = api.validate(args.lab, soil=args.soil, fit=args.fit, simulate=args.simulate, seeds=args.seeds,
                       output=args.output, **_runs(args))
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
    rows = [api.lab_record(f) for f in args.files]           # every file read before anything is printed
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
