"""`campaign crosscheck`: tolerance table parsing, the verdict on seed ensembles (paired difference,
interval, agree/differ/undecided). The real cross-check of both engines (3 seeds of a tiny sliding
flat) is tests/test_crosscheck_power.py::test_real_crosscheck_table_files_and_json, on the runs that
module's power test shares."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pandas as pd
import pytest

from interphase.analysis.difference import difference
from interphase.campaign.crosscheck import (DEFAULT_TOLERANCES, ENGINES, CrosscheckReport, crosscheck, engine_table,
                                          physical_case, split_crosscheck)
from interphase.errors import InputError

CAMPAIGN = """\
[campaign]
name = "xc-tiny"
engines = ["liggghts", "yade"]

[execution]
executor = "local"
jobs = 2

[case]
test = "interface"
profile = {kind = "flat"}
shear_modulus = 50e6
friction_ps = 0.2
shear_distance = 0.001
snapshot_every = 0.0005
box_length_d50 = 20.0
box_height_d50 = 10.0
n_grains = 200

[sweep]
seed = [1, 2]

[pairs]
box = false

[crosscheck]
stress_ratio_rel = 0.10
angle_deg = 3.0
"""


def test_crosscheck_table_is_blanked_keeping_line_numbers():
    text = "[campaign]\nname = 'a'\n[crosscheck]\nangle_deg = 2.5\n[case]\nd50 = 0.0007\n"
    stripped, tol = split_crosscheck(text, "x.toml")
    assert tol == {"critical_ratio_abs": 0.03, "angle_deg": 2.5, "overlap_rel": 0.10}
    assert len(stripped.splitlines()) == len(text.splitlines())
    assert "crosscheck" not in stripped and stripped.splitlines()[5] == "d50 = 0.0007"


def test_no_crosscheck_table_gives_the_defaults():
    text = "[campaign]\nname = 'a'\n"
    assert split_crosscheck(text, "x.toml") == (text, {"critical_ratio_abs": 0.03, "angle_deg": 3.0, "overlap_rel": 0.10})
    # the peak's and the peak snapshot's tolerances are optional: set, they are added
    _, tol = split_crosscheck(text + "[crosscheck]\nstress_ratio_rel = 0.1\npeak_angle_deg = 4\n", "x.toml")
    assert tol == DEFAULT_TOLERANCES | {"stress_ratio_rel": 0.1, "peak_angle_deg": 4.0}


@pytest.mark.parametrize("body, line, words", [
    ("[crosscheck]\nangle = 3\n", 2, "unknown key 'angle'"),
    ("[crosscheck]\nstress_ratio_rel = 0.1\nangle_deg = -1\n", 3, "positive number"),
    ("[crosscheck]\nangle_deg = 'three'\n", 2, "positive number"),
])
def test_bad_tolerances_name_file_line_and_key(body, line, words):
    with pytest.raises(InputError) as err:
        split_crosscheck("[campaign]\n" + body, "cc.toml")
    msg = str(err.value)
    assert f"cc.toml:{line + 1}" in msg and words in msg


def test_judged_in_limits_a_tolerance_to_groups_and_reports_it_elsewhere():
    _, tol = split_crosscheck('[crosscheck]\njudged_in = {critical_ratio_abs = ["sliding"]}\n', "x.toml")
    assert tol["judged_in"] == {"critical_ratio_abs": ("sliding",)} and tol["critical_ratio_abs"] == 0.03
    s = {f"{name}-s{k}": {e: {"residual_stress_ratio": v + (0.001 if e == "yade" else 0), "overlap_mean_d50": 0.015}
                          for e in ENGINES}
         for name, v in (("slide", 0.2), ("roll", 0.3)) for k in (1, 2, 3)}
    groups = {lab: "sliding" if lab.startswith("slide") else "rolling" for lab in s}
    t = engine_table(s, {}, tol, groups).set_index(["level", "physical", "metric"]).loc["ensemble"]
    assert t.loc[("slide", "residual_stress_ratio"), "verdict"] == "agree"
    roll = t.loc[("roll", "residual_stress_ratio")]
    assert pd.isna(roll.verdict) and roll["diff"] == pytest.approx(0.001)  # reported, with its interval
    assert t.loc[("roll", "overlap_mean_d50"), "verdict"] == "agree"        # other tolerances judge everywhere


@pytest.mark.parametrize("body, words", [
    ('judged_in = ["sliding"]', "must be a table"),
    ('judged_in = {angle = ["a"]}', "unknown tolerance 'angle'"),
    ('judged_in = {angle_deg = []}', "non-empty list"),
])
def test_bad_judged_in_is_located(body, words):
    with pytest.raises(InputError, match=words) as err:
        split_crosscheck("[campaign]\n[crosscheck]\n" + body + "\n", "cc.toml")
    assert "cc.toml:3" in str(err.value)


def test_judged_in_names_a_group_of_the_campaign(tmp_path):
    from interphase.campaign.crosscheck import load

    f = tmp_path / "xc.toml"
    f.write_text(CAMPAIGN.replace("angle_deg = 3.0", 'judged_in = {angle_deg = ["slidng"]}'))
    with pytest.raises(InputError, match="no group 'slidng'") as err:
        load(f)
    assert "xc-tiny" in str(err.value.fix) and "box" in str(err.value.fix)


TOL = {"stress_ratio_rel": 0.10, "angle_deg": 3.0}


def _runs(lig, yad, key="peak_stress_ratio", name="c"):
    """summaries of one physical case: seed k+1 gets lig[k], yad[k] (None: that engine has no result)."""
    out = {}
    for k, (a, b) in enumerate(zip(lig, yad)):
        out[f"{name}-s{k + 1}"] = {eng: {key: v} for eng, v in (("liggghts", a), ("yade", b)) if v is not None}
    return out


def _row(summaries, metric="peak_stress_ratio", tol=TOL):
    t = engine_table(summaries, {}, tol)
    e = t[(t.level == "ensemble") & (t.metric == metric)]
    assert len(e) == 1
    return e.iloc[0]


@pytest.mark.parametrize("label, phys, seed", [
    ("interface-flat-mu0.2-mono-s1", "interface-flat-mu0.2-mono", 1),
    ("box (box-mono-s12)", "box (box-mono)", 12),
    ("no-seed-here", "no-seed-here", None),
])
def test_physical_case_drops_the_seed_suffix(label, phys, seed):
    assert physical_case(label) == (phys, seed)


def test_paired_difference_with_its_interval_and_tolerance_from_the_mean():
    """YADE − LIGGGHTS per seed, averaged, with the paired 95 % t interval of
    analysis.difference; stress_ratio_rel becomes rel × mean of the two engines' means."""
    lig, yad = [0.40, 0.50, 0.45], [0.52, 0.64, 0.59]
    r = _row(_runs(lig, yad))
    d = difference(lig, yad, 0.10 * 0.5 * (0.45 + 0.5833333333), paired=True)
    assert r.seeds == 3 and r.liggghts == pytest.approx(0.45) and r.yade == pytest.approx(0.58333333)
    assert r["diff"] == pytest.approx(d.change) and (r.diff_lo, r.diff_hi) == pytest.approx((d.change_lo, d.change_hi))
    assert r.tolerance == pytest.approx(d.tol) and r.verdict == d.verdict == "differ"
    assert r.diff_lo > r.tolerance


def test_pairing_removes_the_packing_scatter():
    """Seeds scatter ±0.1 between packings, but each packing gives both engines the same value
    within 0.002: the paired interval is narrow and the engines agree (unpaired they would not)."""
    lig = [0.40, 0.60, 0.50, 0.45]
    yad = [v + e for v, e in zip(lig, (0.002, -0.001, 0.001, 0.0))]
    r = _row(_runs(lig, yad))
    assert r.verdict == "agree" and pd.isna(r.seeds_needed)
    assert difference(lig, yad, r.tolerance, paired=False).verdict == "undecided"
    assert r.pair_r > 0.99                       # what the pairing bought: the table shows it
    assert "| +1.00 |" in _report(_runs(lig, yad)).markdown()


def test_undecided_says_how_many_seeds_would_decide():
    lig, yad = [0.50, 0.55, 0.45], [0.53, 0.50, 0.52]        # differences +0.03 −0.05 +0.07
    r = _row(_runs(lig, yad))
    d = difference(lig, yad, r.tolerance, paired=True)
    assert r.verdict == "undecided" and r.diff_lo < r.tolerance < r.diff_hi
    assert r.seeds_needed == d.seeds_needed and r.seeds_needed > 3 and r.more_seeds == r.seeds_needed - 3


def test_angles_are_judged_against_an_absolute_tolerance():
    r = _row(_runs([30.0, 32.0, 31.0], [30.5, 32.4, 31.2], key="theta_r_surface_mean_deg"), "theta_r_surface_mean_deg")
    assert r.tolerance == 3.0 and r.tolerance_rule == "absolute" and r.verdict == "agree"
    r = _row(_runs([30.0, 32.0, 31.0], [36.0, 38.5, 37.0], key="theta_r_surface_mean_deg"), "theta_r_surface_mean_deg")
    assert r.verdict == "differ"


def test_one_seed_is_undecided_and_never_a_verdict_on_its_own():
    """A single seed has no interval: undecided, seeds needed unknown. Its per-seed row carries
    the values and difference but no verdict."""
    s = _runs([0.30], [0.30])
    r = _row(s)
    assert r.seeds == 1 and r.verdict == "undecided" and pd.isna(r.seeds_needed)
    t = engine_table(s, {}, TOL)
    seed = t[(t.level == "seed") & (t.metric == "peak_stress_ratio")].iloc[0]
    assert seed["diff"] == 0 and pd.isna(seed.verdict) and seed.case == "c-s1" and seed.physical == "c"


def test_seeds_only_one_engine_finished_are_left_out_of_the_pairs():
    r = _row(_runs([0.20, 0.20, 0.90], [0.20, 0.20, None]))
    assert r.seeds == 2 and r.liggghts == pytest.approx(0.20) and r.verdict == "agree"


def test_reported_metrics_and_undefined_ones_carry_no_verdict():
    """shear_disp_at_peak and dilation_at_peak: difference and interval, no verdict; θ of a box
    test (neither engine defines it) is not judged at all."""
    s = _runs([1e-3, 2e-3, 1.5e-3], [1.1e-3, 2.2e-3, 1.4e-3], key="shear_disp_at_peak")
    r = _row(s, "shear_disp_at_peak")
    assert pd.isna(r.verdict) and math.isfinite(r.diff_lo) and r.seeds == 3
    box = {f"box (b-s{k})": {e: {"peak_stress_ratio": 0.5 + 0.01 * k} for e in ENGINES} for k in (1, 2)}
    t = engine_table(box, {}, TOL)
    judged = t[(t.level == "ensemble") & t.verdict.notna()]
    assert list(judged.metric) == ["peak_stress_ratio"] and judged.iloc[0].physical == "box (b)"


def test_default_tolerances_judge_time_averages_and_report_the_peak():
    """Without stress_ratio_rel / peak_angle_deg the peak and the peak snapshot's angles are reported
    (difference and interval, no verdict); the critical-state ratio is judged against an absolute
    tolerance, the mean overlap against a relative one."""
    s = {f"c-s{k}": {"liggghts": {"peak_stress_ratio": p, "residual_stress_ratio": 0.30 + 0.01 * k,
                                  "overlap_mean_d50": 0.0150 + 0.0002 * k, "theta_r_surface_deg": 20.0},
                     "yade": {"peak_stress_ratio": p + 0.1, "residual_stress_ratio": 0.305 + 0.01 * k,
                              "overlap_mean_d50": 0.0151 + 0.0002 * k, "theta_r_surface_deg": 30.0}}
         for k, p in ((1, 0.40), (2, 0.45), (3, 0.50))}
    t = engine_table(s, {}, DEFAULT_TOLERANCES).set_index(["level", "metric"]).loc["ensemble"]
    assert pd.isna(t.loc["peak_stress_ratio", "verdict"]) and t.loc["peak_stress_ratio", "diff"] == pytest.approx(0.1)
    assert pd.isna(t.loc["theta_r_surface_deg", "verdict"])
    r = t.loc["residual_stress_ratio"]
    assert r.tolerance == 0.03 and r.tolerance_rule == "absolute" and r.verdict == "agree"
    o = t.loc["overlap_mean_d50"]
    assert o.tolerance == pytest.approx(0.10 * 0.5 * (0.0154 + 0.0155)) and o.verdict == "agree"
    md = CrosscheckReport("x", Path("/tmp/x"), DEFAULT_TOLERANCES, engine_table(s, {}, DEFAULT_TOLERANCES)).markdown()
    assert "| c | peak_stress_ratio | 3 |" in md and "| reported |" in md


def test_a_theta_only_one_engine_gives_is_undecided():
    s = {"c-s1": {"liggghts": {"theta_r_surface_mean_deg": 30.0}, "yade": {"theta_r_surface_mean_deg": None}},
         "c-s2": {"liggghts": {"theta_r_surface_mean_deg": 31.0}, "yade": {}}}
    r = _row(s, "theta_r_surface_mean_deg")
    assert r.seeds == 0 and r.verdict == "undecided" and r.liggghts == pytest.approx(30.5)


def _report(summaries, missing=()):
    return CrosscheckReport("x", Path("/tmp/x"), TOL, engine_table(summaries, {}, TOL), list(missing))


def test_exit_state_passes_only_when_every_judged_row_agrees():
    agree = _runs([0.20, 0.21, 0.22], [0.201, 0.209, 0.221])
    undecided = _runs([0.50, 0.55, 0.45], [0.53, 0.50, 0.52], name="u")
    differ = _runs([0.40, 0.50, 0.45], [0.52, 0.64, 0.59], name="d")
    assert _report(agree).passed
    assert not _report(agree | undecided).passed
    assert not _report(agree | differ).passed
    assert not _report(agree, missing=[("c-s4", "yade", "failed")]).passed
    assert _report(agree | differ).counts() == {"agree": 1, "differ": 1, "undecided": 0}
    # the words say which: undecided is no failure of an engine but a want of seeds
    assert _report(agree).outcome.startswith("agree")
    assert _report(agree | differ).outcome.startswith("differ: 1 of")
    assert _report(agree, missing=[("c-s4", "yade", "failed")]).outcome.startswith("incomplete")
    u = _report(agree | undecided)
    more = int(u.judged.loc[u.judged["verdict"] == "undecided", "more_seeds"].max())
    assert u.outcome.startswith(f"undecided: {more} more seeds") and more > 0


def test_markdown_and_json_carry_interval_verdict_and_seeds_needed():
    rep = _report(_runs([0.50, 0.55, 0.45], [0.53, 0.50, 0.52], name="u"))
    md = rep.markdown()
    assert "| u | peak_stress_ratio | 3 |" in md and "**undecided**" in md and "more)" in md
    assert "verdict: undecided: " in md and "more seeds" in md and "FAIL" not in md and "u-s1" not in md             # per-seed rows only with all_rows
    assert "u-s1" in rep.markdown(all_rows=True)
    data = json.loads(json.dumps(rep.to_json()))
    row = next(r for r in data["rows"] if r["metric"] == "peak_stress_ratio")
    assert row["verdict"] == "undecided" and row["seeds_needed"] >= 4
    assert row["diff_lo"] < row["diff"] < row["diff_hi"] and row["tolerance"] > 0
    assert data["passed"] is False and data["verdicts"]["undecided"] == 1
    assert {r["case"] for r in data["seed_rows"]} == {"u-s1", "u-s2", "u-s3"}
    assert all(r["verdict"] is None for r in data["seed_rows"])


@pytest.fixture(scope="module")
def xc_file(tmp_path_factory):
    folder = tmp_path_factory.mktemp("xc")
    path = folder / "xc.toml"
    path.write_text(CAMPAIGN)
    return path, folder / "out"


def test_a_crosscheck_file_is_a_campaign_too(xc_file):
    """`campaign run` reads a cross-check file as it is: the schema skips [crosscheck], whose
    tolerances only `campaign crosscheck` reads (and validates)."""
    from interphase.campaign.crosscheck import load
    from interphase.campaign.schema import load_campaign

    path, _ = xc_file
    plain = load_campaign(path)
    campaign, tol, readable, _ = load(path)
    assert readable == path
    assert [c.case for c in plain.cases] == [c.case for c in campaign.cases]
    assert tol and all(v > 0 for v in tol.values())


def test_missing_file_is_an_input_error(tmp_path):
    with pytest.raises(InputError, match="cannot read"):
        crosscheck(tmp_path / "nope.toml", run=False)


def test_interrupted_run_stops_the_crosscheck(tmp_path, monkeypatch):
    """Ctrl-C / SIGTERM during the first engine's runs must stop the cross-check, not go on to the
    second engine (it did: the interrupted LIGGGHTS half returned and YADE started). run_campaign is
    replaced by one that reports an interruption; the real interruption path of run_campaign is
    tested in tests/test_campaign_run.py."""
    from interphase.campaign import run as run_mod
    from interphase.campaign.run import RunReport

    calls = []

    def interrupted_run(path, *, engines=None, **kw):
        calls.append(*(e.name for e in engines))      # one engine value per run
        return RunReport(campaign="xc-tiny", output=tmp_path, interrupted=True)

    monkeypatch.setattr(run_mod, "run_campaign", interrupted_run)
    f = tmp_path / "xc.toml"
    f.write_text(CAMPAIGN)
    with pytest.raises(KeyboardInterrupt):
        crosscheck(f, output=tmp_path / "out")
    assert calls == ["liggghts"]
