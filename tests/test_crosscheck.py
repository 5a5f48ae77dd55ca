"""`campaign crosscheck`: tolerance table parsing, the comparison, seed means, and one real run of
both engines on a tiny flat case (LIGGGHTS ~2 s + YADE ~5 s)."""

from __future__ import annotations

import json
import math

import pytest

from interphase.campaign.crosscheck import METRICS, compare, crosscheck, seed_means, split_crosscheck
from interphase.cli import main
from interphase.errors import InputError
from tests.conftest import need_binary

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

[pairs]
box = false

[crosscheck]
stress_ratio_rel = 0.10
angle_deg = 3.0
"""


def test_crosscheck_table_is_blanked_keeping_line_numbers():
    text = "[campaign]\nname = 'a'\n[crosscheck]\nangle_deg = 2.5\n[case]\nd50 = 0.0007\n"
    stripped, tol = split_crosscheck(text, "x.toml")
    assert tol == {"stress_ratio_rel": 0.10, "angle_deg": 2.5}
    assert len(stripped.splitlines()) == len(text.splitlines())
    assert "crosscheck" not in stripped and stripped.splitlines()[5] == "d50 = 0.0007"


def test_no_crosscheck_table_gives_the_defaults():
    text = "[campaign]\nname = 'a'\n"
    assert split_crosscheck(text, "x.toml") == (text, {"stress_ratio_rel": 0.10, "angle_deg": 3.0})


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


def test_compare_differences_and_verdicts():
    summaries = {"a": {"liggghts": {"peak_stress_ratio": 0.50, "theta_r_surface_deg": 30.0},
                       "yade": {"peak_stress_ratio": 0.55, "theta_r_surface_deg": 34.0}},
                 "b": {"liggghts": {"peak_stress_ratio": 0.20}, "yade": {"peak_stress_ratio": None}}}
    t = compare(summaries, {"a": "interface", "b": "interface"}, {"stress_ratio_rel": 0.10, "angle_deg": 3.0})
    r = t.set_index(["case", "metric"])
    assert r.loc[("a", "peak_stress_ratio"), "rel_diff"] == pytest.approx(0.05 / 0.525)
    assert r.loc[("a", "peak_stress_ratio"), "passed"] == True          # noqa: E712  9.5 % ≤ 10 %
    assert r.loc[("a", "theta_r_surface_deg"), "abs_diff"] == pytest.approx(4.0)
    assert r.loc[("a", "theta_r_surface_deg"), "passed"] == False       # noqa: E712
    assert r.loc[("b", "peak_stress_ratio"), "passed"] is None          # one engine has no value
    assert math.isnan(r.loc[("a", "dilation_at_peak"), "abs_diff"])


def test_seed_means_use_seeds_both_engines_finished():
    row = lambda v: {"peak_stress_ratio": v}
    summaries = {"c-s1": {"liggghts": row(0.4), "yade": row(0.5)},
                 "c-s2": {"liggghts": row(0.6), "yade": row(0.7)},
                 "c-s3": {"liggghts": row(9.9)},                      # YADE failed: left out of both means
                 "box (b-s1)": {"liggghts": row(0.5), "yade": row(0.5)},
                 "box (b-s2)": {"liggghts": row(0.7), "yade": row(0.7)}}
    means, roles = seed_means(summaries, {})
    assert set(means) == {"c [2 seeds]", "box (b) [2 seeds]"}
    assert means["c [2 seeds]"]["liggghts"]["peak_stress_ratio"] == pytest.approx(0.5)
    assert means["c [2 seeds]"]["yade"]["peak_stress_ratio"] == pytest.approx(0.6)
    assert means["c [2 seeds]"]["yade"]["peak_stress_ratio_sd"] == pytest.approx(math.sqrt(0.02))


@pytest.fixture(scope="module")
def xc_file(tmp_path_factory):
    folder = tmp_path_factory.mktemp("xc")
    path = folder / "xc.toml"
    path.write_text(CAMPAIGN)
    return path, folder / "out"


@pytest.fixture(scope="module")
def tiny_campaign(xc_file):
    need_binary("liggghts")
    need_binary("yade")
    return xc_file


@pytest.mark.liggghts
@pytest.mark.yade
def test_real_crosscheck_of_a_flat_case(tiny_campaign, capsys):
    """Both engines run; on a flat surface at μs = 0.2 they agree on the stress ratio within 10 %,
    and the table and files name both engines' values."""
    path, out = tiny_campaign
    report = crosscheck(path, output=out)
    t = report.table.set_index("metric")
    assert not report.missing
    assert len(report.table) == len(METRICS) and (report.table.case == "interface-flat-mu0.2-mono-s1").all()
    lig, yad = t.loc["peak_stress_ratio", "liggghts"], t.loc["peak_stress_ratio", "yade"]
    assert lig == pytest.approx(0.2, abs=0.05) and yad == pytest.approx(0.2, abs=0.05)
    assert t.loc["peak_stress_ratio", "passed"] == True                 # noqa: E712
    assert (out / "crosscheck.csv").exists() and "| peak_stress_ratio |" in (out / "crosscheck.md").read_text()
    assert not list(path.parent.glob(".xc.crosscheck-*.toml"))          # the stripped copy is removed
    # the CLI reuses the finished cases (no rerun) and prints JSON
    capsys.readouterr()
    code = main(["crosscheck", str(path), "--output", str(out), "--json", "--no-run"])
    data = json.loads(capsys.readouterr().out)
    assert code in (0, 1) and code == (0 if data["passed"] else 1)
    assert {r["metric"] for r in data["rows"]} >= {"peak_stress_ratio", "theta_r_surface_deg"}


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

    def interrupted_run(path, *, engine=None, **kw):
        calls.append(engine)
        return RunReport(campaign="xc-tiny", output=tmp_path, interrupted=True)

    monkeypatch.setattr(run_mod, "run_campaign", interrupted_run)
    f = tmp_path / "xc.toml"
    f.write_text(CAMPAIGN)
    with pytest.raises(KeyboardInterrupt):
        crosscheck(f, output=tmp_path / "out")
    assert calls == ["liggghts"]
