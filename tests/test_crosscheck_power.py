"""Can the cross-check see a wrong YADE mapping? (groundwork of its power study, studies/crosscheck_power/)

The YADE side is run with a deliberate mis-mapping — particle–surface friction × k, rolling
resistance off, stiffness × k — WITHOUT a production flag: campaign.mismapped's `MismappedYade`
alters the data the YADE engine renders (params.json), and `mismapped_yade(...)` gives it as an
engine value (engines.base.EngineSpec), which `crosscheck(..., engines=...)` takes as it takes any
argument: campaign planning, case ids and runs go through the ordinary code. Its recipe id mixes in
the alteration, so its cases never share a folder (a case id) with the true mapping's or with another
alteration's.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from interphase.campaign.crosscheck import METRICS, crosscheck
from interphase.cli import main
from interphase.campaign.mismapped import copy_done, mismapped_yade
from interphase.engines.base import engine_spec
from interphase.engines.yade import Yade
from tests.campaign_files import toml_text
from tests.conftest import need_binary

#: the gross mis-mapping of the power study: each alteration alone or together
GROSS = {"friction": 1.3, "rolling": False, "stiffness": 4.0}


def test_mismapping_alters_only_the_named_parameters():
    """Rendering only (no engine): the altered params.json differs from the true one in exactly the
    named values, and each alteration has its own case identity."""
    from interphase.case import Case, ProfileSpec

    case = Case(test="interface", profile=ProfileSpec("flat"), friction_ps=0.5, rolling_friction=0.1, shear_modulus=50e6, n_grains=200)
    true = json.loads(Yade().render(case)["params.json"])
    spec = mismapped_yade(**GROSS)
    bad = json.loads(spec.build().render(case)["params.json"])
    m, b = true["material"], bad["material"]
    assert b["mu_ps"] == pytest.approx(1.3 * m["mu_ps"]) and m["mu_ps"] == 0.5
    assert m["krot"] > 0 and m["eta"] > 0 and b["krot"] == b["eta"] == b["krot_wall"] == b["mu_r"] == 0
    assert b["E"] == pytest.approx(4 * m["E"]) and b["E_wall"] == pytest.approx(4 * m["E_wall"])
    changed = {k for k in m if m[k] != b[k]}
    assert changed == {"mu_ps", "krot", "eta", "krot_wall", "mu_r", "E", "E_wall"}
    assert {k: v for k, v in true.items() if k != "material"} == {k: v for k, v in bad.items() if k != "material"}
    hashes = {Yade().recipe_id(), spec.recipe_id(), mismapped_yade(friction=1.3).recipe_id()}
    assert len(hashes) == 3 and engine_spec("yade").recipe_id() == Yade().recipe_id()
    # the value travels to a worker whole: the engine it builds there is the mis-mapped one
    import pickle

    again = pickle.loads(pickle.dumps(spec))
    assert again == spec and json.loads(again.build().render(case)["params.json"]) == bad


# ---- the power of the standard set's judged metrics, tiny (issue 16 item 3) ------------------------
# The standard set (campaigns/crosscheck.toml) judges time averages: the critical-state stress ratio
# (residual_stress_ratio), θr over the loaded snapshots and the mean contact overlap. Each deliberate
# mis-mapping must come out DIFFER on the metric it moves while the true mapping AGREES, on the same
# LIGGGHTS runs. Tiny periodic cells (12 × 8 D50, uniform grains, 0.5 mm at 0.05 m/s, a snapshot every
# 0.125 mm; the flat slides at μs from ~0.1 mm, so the residual window, the last 20 % = 0.4–0.5 mm,
# is the sliding state):
# - flat μs = 0.2 (every bottom grain slides: the ratio is μs in both engines, scatter ~0): the true
#   mapping agrees on the critical ratio; friction × 1.3 moves it to 0.26 (differ); stiffness × 2
#   moves the mean overlap by 2^(-2/3) = 0.63× (Hertz), far outside ±10 % (differ). Each moves one
#   metric only, so the two alterations run together, one YADE run a seed: each verdict is read on the
#   metric its alteration moves, at the value that alteration alone predicts.
# - uniform ("mono") grains, not the standard set's well-graded ones: on a sliding flat the ratio is μs
#   whatever the grading, and a YADE run takes ~1/3 of the time (measured 2026-11-23 on the busy 2
#   cores: ~15 s against ~45 s; the well-graded lattice starts higher and its small grains shorten the
#   time step). The standard set needs well-graded grains for its rolling cases (docs/crosscheck.md).
# - stiffness × 2, not the power table's × 4: on this uniform cell YADE's platen did not settle on 4×
#   stiffer contacts at the unchanged time step (seeds 1 and 3 `not_consolidated` after 40 chunks, as
#   seed 2 of the standard set's × 4 run, docs/crosscheck.md); × 2 is the finer error and still differs.
# - rolling resistance off: measured at 250 grains (docs/crosscheck.md, power table).
# Why not friction on the flat at μs = 0.5: there the grains roll over the surface (ratio 0.31, well
# below μs) and μs does not hold the load — LIGGGHTS with μs 0.65 gave the same critical ratio and θr
# (0.31, 15.0° vs 0.31, 15.1°, seeds 1–3, 250 grains): no metric of that case can see friction × 1.3.
# The true mapping's runs are also this suite's real cross-check of both engines (the table, its
# files, the JSON of the CLI): one module-scoped run serves both tests.

TINY_PERIODIC_TABLES = dict(
    campaign={"name": "xc-power-tiny", "engines": ["liggghts", "yade"], "specimen_from": "liggghts"},
    execution={"executor": "local", "jobs": 2},
    case={"test": "interface", "device": "periodic", "profile": {"kind": "flat"}, "gradation": "mono",
          "d50": 0.0007, "shear_modulus": 50e6, "friction_ps": 0.2, "rolling_friction": 0.1, "restitution": 0.5,
          "shear_velocity": 0.05, "shear_distance": 0.0005, "snapshot_every": 0.000125,
          "box_length_d50": 12.0, "box_height_d50": 8.0},
    sweep={"seed": [1, 2, 3]},
    pairs={"box": False},
    crosscheck={"critical_ratio_abs": 0.03, "angle_deg": 3.0, "overlap_rel": 0.10, "stress_ratio_rel": 0.10})
TINY_PERIODIC = toml_text(**TINY_PERIODIC_TABLES)


@pytest.fixture(scope="module")
def true_mapping(tmp_path_factory):
    """`crosscheck()` of TINY_PERIODIC with the true YADE, through the ordinary code (the local
    executor's spawned workers): (campaign file, output folder, report). Run once for this module."""
    need_binary("liggghts")
    need_binary("yade")
    folder = tmp_path_factory.mktemp("xc-power")
    path = folder / "xc.toml"
    path.write_text(TINY_PERIODIC)
    return path, folder / "true", crosscheck(path, output=folder / "true")


def _print_rows(name: str, report) -> None:
    j = report.judged.set_index("metric")
    for m in ("residual_stress_ratio", "overlap_mean_d50"):
        r = j.loc[m]
        print(f"\n{name}: {m} LIGGGHTS {r.liggghts:.4g} YADE {r.yade:.4g} diff {r['diff']:+.3g} "
              f"[{r.diff_lo:+.3g}, {r.diff_hi:+.3g}] tol ±{r.tolerance:.3g} → {r.verdict}")


@pytest.mark.liggghts
@pytest.mark.yade
def test_real_crosscheck_table_files_and_json(true_mapping, capsys):
    """Both engines (true mapping) on 3 packing seeds of the sliding flat: every metric has its row,
    the peak (judged here: the file sets stress_ratio_rel) is μs = 0.2 in both and AGREES with a
    narrow interval, the time to peak is reported only; the table and files carry the verdicts, and the
    CLI reuses the finished cases (--no-run) and prints JSON, exit 0 only if everything agrees.
    (Formerly tests/test_crosscheck.py::test_real_crosscheck_of_a_flat_case, on walled cases of its own.)"""
    path, out, report = true_mapping
    assert not report.missing
    e = report.ensembles.set_index("metric")
    assert len(report.ensembles) == len(METRICS)
    assert (report.ensembles.physical == "interface-periodic-flat-mu0.2-mono").all()
    assert set(report.seeds.case) == {f"interface-periodic-flat-mu0.2-mono-s{s}" for s in (1, 2, 3)}
    r = e.loc["peak_stress_ratio"]
    assert r.seeds == 3 and r.liggghts == pytest.approx(0.2, abs=0.01) and r.yade == pytest.approx(0.2, abs=0.01)
    assert r.verdict == "agree" and -r.tolerance <= r.diff_lo <= r.diff_hi <= r.tolerance
    assert pd.isna(e.loc["shear_disp_at_peak", "verdict"])                      # reported only
    assert set(report.judged.metric) == {m for m, _, _, key in METRICS if key in report.tolerances}
    assert {"residual_stress_ratio", "theta_r_surface_mean_deg", "overlap_mean_d50", "peak_stress_ratio"} \
        <= set(report.judged.metric)
    assert (out / "crosscheck.csv").exists() and "| peak_stress_ratio | 3 |" in (out / "crosscheck.md").read_text()
    # the same-specimen protocol: YADE sheared LIGGGHTS' consolidated grains under its platen
    runs = {json.loads((f / "case.json").read_text())["case_id"]: f for f in out.iterdir() if (f / "DONE").exists()}
    yade = [f for f in runs.values() if json.loads((f / "case.json").read_text())["engine"] == "yade"]
    assert len(yade) == 3
    for f in yade:
        start = json.loads((f / "case.json").read_text())["inputs"]["start"]
        src = runs[start["case_id"]]
        assert start["engine"] == "liggghts" and json.loads((src / "case.json").read_text())["engine"] == "liggghts"
        grains = json.loads((f / "params.json").read_text())["grains"]
        lig = pd.read_parquet(src / "particles.parquet")
        lig0 = lig[lig.snapshot == lig.snapshot.min()].sort_values("id")
        assert grains["x"] == lig0.x.tolist() and grains["z"] == lig0.z.tolist()
        # ... and after YADE's own first stretch under the same servo the specimen is still that one:
        # at the start of its shear a grain lies a median 0.005-0.011 D50 from where it lay in LIGGGHTS
        # (seeds 1-3), where YADE consolidating the same lattice itself puts it 0.092 D50 away (seed 1,
        # measured 2026-11-23)
        y = pd.read_parquet(f / "particles.parquet")
        y0 = y[y.snapshot == y.snapshot.min()].sort_values("id")
        period = 12 * 0.0007
        dx = (y0.x.to_numpy() - lig0.x.to_numpy() + period / 2) % period - period / 2
        moved = np.hypot(dx, y0.z.to_numpy() - lig0.z.to_numpy())
        assert len(y0) == len(lig0) and np.median(moved) < 0.04 * 0.0007, np.median(moved) / 0.0007
    capsys.readouterr()
    code = main(["crosscheck", str(path), "--output", str(out), "--json", "--no-run"])
    data = json.loads(capsys.readouterr().out)
    assert code == (0 if data["passed"] else 1)
    assert data["passed"] == all(r["verdict"] == "agree" for r in data["rows"] if r["verdict"] is not None)
    row = next(r for r in data["rows"] if r["metric"] == "peak_stress_ratio")
    assert row["verdict"] == "agree" and {"diff_lo", "diff_hi", "seeds_needed", "tolerance"} <= set(row)


@pytest.mark.liggghts
@pytest.mark.yade
def test_each_mismapping_differs_on_its_metric_while_the_true_mapping_agrees(true_mapping):
    """The true mapping, and friction × 1.3 with stiffness × 2 in one YADE run per seed, on the same
    three LIGGGHTS runs of a tiny periodic flat at μs = 0.2 (uniform grains), YADE shearing LIGGGHTS'
    specimens (specimen_from): the true mapping AGREES on both metrics; the altered one DIFFERS on
    each, by what each alteration alone predicts, so each verdict is its own alteration's. On a
    sliding flat the critical-state ratio is μs whatever the stiffness (so 1.3 × 0.2 = 0.26), and the
    mean overlap follows the stiffness (Hertz: × 2^(−2/3) = 0.63 at one load) whatever the friction.
    Measured (0.5 mm of shear, 3 seeds): true: ratio −0.0008 [−0.0044, +0.0027] against ±0.03 →
    agree, overlap +0.00018 against ±0.0013 → agree (with each engine consolidating its own specimen
    it was undecided at 3 seeds); friction × 1.3: YADE ratio 0.258 → differ; stiffness × 2: overlap
    × 0.71 → differ. Rolling off is not in this test: on a sliding flat it changes nothing, and on the
    rolling-held flat at μs 0.5 its effect needs the standard set's cell (the power table,
    studies/crosscheck_power/crosscheck_power.py)."""
    path, true_out, true_report = true_mapping
    assert not true_report.missing
    j = true_report.judged.set_index("metric")
    _print_rows("true", true_report)
    assert j.loc["residual_stress_ratio", "verdict"] == "agree"
    assert j.loc["overlap_mean_d50", "verdict"] == "agree"
    out = true_out.parent / "friction-and-stiffness"
    copy_done(true_out, out)                              # the same LIGGGHTS runs: no rerun
    report = crosscheck(path, output=out, engines=("liggghts", mismapped_yade(friction=1.3, stiffness=2.0)))
    assert not report.missing
    _print_rows("friction x 1.3 and stiffness x 2", report)
    # the alteration reached the engine: every YADE folder ran with it
    yade_params = [json.loads(p.read_text()) for p in out.glob("*/params.json")]
    true_e = json.loads(next(true_out.glob("*/params.json")).read_text())["material"]["E"]
    assert len(yade_params) == 3
    assert all(p["material"]["mu_ps"] == pytest.approx(0.26) and p["material"]["E"] == pytest.approx(2 * true_e)
               for p in yade_params)
    bad = report.judged.set_index("metric")
    ratio, overlap = bad.loc["residual_stress_ratio"], bad.loc["overlap_mean_d50"]
    assert ratio.verdict == "differ" and ratio.yade == pytest.approx(0.26, abs=0.01)
    assert overlap.verdict == "differ"
    assert 0.55 < overlap.yade / j.loc["overlap_mean_d50", "yade"] < 0.75       # Hertz 0.63; measured 0.71
    # the per-seed rows are information, never a verdict
    seeds = report.seeds[report.seeds.metric == "residual_stress_ratio"]
    assert len(seeds) == 3 and seeds.verdict.isna().all()
    assert not report.passed
