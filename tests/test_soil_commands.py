"""Issue 40 items 1, 2, 4, 5 (engine-free; where a command would run the engine, the runs are
replaced by fixed results): a calibration never replaces a card and a --quick card says it is
quick; outputs resolve beside the card, target or lab file, said with where that came from; the
element test's options (speed, failures, negative numbers); calibration targets' plausibility and
the verdicts' rule."""

from __future__ import annotations

import hashlib
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from interphase.analysis.element import ElementResult
from interphase.cli import main

DATA = Path(__file__).parent / "data" / "soils"


def _element(phi_peak=38.0, phi_cs=28.0, psi=15.0, width=0.5, sigma=100e3):
    return ElementResult(normal_stress=sigma, n_seeds=2, phi_peak_deg=phi_peak, phi_peak_deg_lo=phi_peak - width,
                         phi_peak_deg_hi=phi_peak + width, phi_cs_deg=phi_cs, phi_cs_deg_lo=phi_cs - width,
                         phi_cs_deg_hi=phi_cs + width, psi_max_deg=psi, psi_max_deg_lo=psi - width,
                         psi_max_deg_hi=psi + width, solid_fraction=0.87, solid_fraction_lo=0.86,
                         solid_fraction_hi=0.88, peak_disp=1e-3, shear_distance=2e-3, has_peak=True)


@pytest.fixture
def no_engine(monkeypatch):
    """calibrate without the engine: GrainLearning's sampling and the final element tests replaced
    by fixed results (what is tested is where the card goes and what it says)."""
    from interphase.campaign import calibrate as cal

    calls = []

    def sample(plan, executor, jobs, stream, rerun_failed):
        calls.append(plan.name)
        return None, [{"iteration": 0}], [3]

    monkeypatch.setattr(cal, "_sample", sample)
    monkeypatch.setattr(cal, "_posterior", lambda calib, names, target: (
        {n: 0.5 for n in names}, {n: {"mean": 0.5, "lo": 0.4, "hi": 0.6} for n in names}, 2.0))

    def final(card, target, n_seeds, runs, executor, jobs, stream, rerun_failed=False):
        runs.mkdir(parents=True, exist_ok=True)
        r = _element()
        return r, [{"quantity": c["quantity"], "target": c["laboratory"], "value": c["measured"], "lo": c["lo"],
                    "hi": c["hi"], "difference": c["difference"], "verdict": c["verdict"]}
                   for c in cal.check_angles(target.values, r)], [], 2

    monkeypatch.setattr(cal, "_final_checks", final)
    return calls


def _sha(p: Path) -> str:
    return hashlib.sha256(p.read_bytes()).hexdigest()


def test_quick_twice_beside_a_full_card_leaves_it_byte_identical(tmp_path, capsys, no_engine, monkeypatch):
    """`calibrate --quick` overwrote the shipped full card (149 runs) with a 6-run quick card."""
    monkeypatch.chdir("/")                       # nothing depends on the current folder
    target = tmp_path / "targets" / "tiny.toml"
    target.parent.mkdir()
    shutil.copy(DATA / "tiny_target.toml", target)
    full = target.parent / "soils" / "tiny.toml"
    assert main(["calibrate", str(target)]) == 0          # the full card (engine replaced)
    out = capsys.readouterr().out
    assert f"card {full} (the default soils/tiny.toml beside tiny.toml" in out
    assert f"runs folder {target.parent / 'runs' / 'calibrate' / 'tiny'}" in out
    before = _sha(full)
    for _ in range(2):
        assert main(["calibrate", str(target), "--quick"]) == 0
        assert _sha(full) == before
    quick = full.with_name("tiny-quick.toml")
    text = quick.read_text()
    assert text.startswith("# QUICK CALIBRATION") and 'name = "tiny-quick"' in text
    assert no_engine == ["tiny", "tiny-quick"]            # the second --quick read its card back, ran nothing
    out = capsys.readouterr().out
    assert "read back" in out and "--quick" in out
    # -o onto the full card: refused, with a free name offered; the card untouched
    for _ in range(2):
        assert main(["calibrate", str(target), "--quick", "-o", str(full)]) == 2
        err = capsys.readouterr().err
        assert str(full) in err and "never replaces" in err and "tiny-2.toml" in err
    assert _sha(full) == before
    # the same full calibration again: read back, nothing rerun, nothing rewritten
    assert main(["calibrate", str(target), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["reused"] is True and _sha(full) == before
    assert no_engine == ["tiny", "tiny-quick"]


def test_a_quick_card_says_so_in_every_command_that_reads_it(tmp_path, capsys, no_engine):
    target = tmp_path / "tiny.toml"
    shutil.copy(DATA / "tiny_target.toml", target)
    assert main(["calibrate", str(target), "--quick"]) == 0
    card = tmp_path / "soils" / "tiny-quick.toml"
    from interphase.soil import load_card

    assert load_card(card).quick and not load_card(DATA / "tiny_card.toml").quick
    capsys.readouterr()
    # element: the warning comes before anything runs (here: a refused stress stops it right after)
    assert main(["element", str(card), "--normal-stress", "100e3", "--seeds", "0"]) == 2
    assert "--quick calibration" in capsys.readouterr().err
    lab = tmp_path / "lab.csv"
    lab.write_text("soil,d50_mm,surface,asperity_height_mm,asperity_width_mm,root_spacing_mm,normal_stress_kpa,"
                   "delta_peak_deg,soil_phi_peak_deg,source,table_or_figure\n"
                   "Ottawa (synthetic),0.72,flat,,,,100,12,,synthetic test row,none\n")
    assert main(["validate", str(lab), "--soil", str(card)]) == 0
    assert "--quick calibration" in capsys.readouterr().out
    camp = tmp_path / "c.toml"
    camp.write_text(f'[campaign]\nname = "c"\n[case]\nsoil = "{card}"\ntest = "box"\ndevice = "periodic"\n')
    from interphase.campaign.schema import load_campaign

    assert any("--quick calibration" in w for w in load_campaign(camp).warnings())


def test_validate_folder_beside_the_lab_file_kept_or_refused(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir("/")
    lab = tmp_path / "lab" / "tests.csv"
    lab.parent.mkdir()
    lab.write_text("soil,d50_mm,surface,asperity_height_mm,asperity_width_mm,root_spacing_mm,normal_stress_kpa,"
                   "delta_peak_deg,soil_phi_peak_deg,source,table_or_figure\n"
                   "Ottawa (synthetic),0.72,sawtooth,0.5,1.0,0,100,30,36,synthetic test row,none\n")
    folder = lab.parent / "runs" / "validate" / "tests"
    assert main(["validate", str(lab), "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["folder"] == str(folder) and "beside tests.csv" in res["folder_from"]
    sums = {p.name: _sha(p) for p in folder.iterdir()}
    assert main(["validate", str(lab)]) == 0                   # the same validation: kept
    assert "kept (unchanged)" in capsys.readouterr().out
    assert main(["validate", str(lab), "--fit", "study-figures"]) == 2    # another one: refused, nothing replaced
    err = capsys.readouterr().err
    assert str(folder) in err and "tests-2" in err
    assert {p.name: _sha(p) for p in folder.iterdir()} == sums
    other = tmp_path / "busy"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    assert main(["validate", str(lab), "-o", str(other)]) == 2
    assert "not empty" in capsys.readouterr().err and (other / "notes.txt").read_text() == "mine"


def test_element_runs_beside_the_card_at_a_quasi_static_speed(tmp_path, monkeypatch, capsys):
    """At its own defaults the element test printed the not-quasi-static warning (0.05 m/s, I ≈ 1.6e-3)
    with no option to change the speed; its runs went to ./runs/element under the current folder."""
    from interphase.analysis.quasistatic import inertial_estimate
    from interphase.campaign import element as el
    from interphase.case import case_from_dict
    from interphase.soil import load_card

    shutil.copy(DATA / "tiny_card.toml", tmp_path / "tiny_card.toml")
    card = load_card(tmp_path / "tiny_card.toml")
    assert inertial_estimate(case_from_dict(card.element_case(100e3))) < 1e-3
    seen = {}

    def fake_run_cases(path, **kw):
        from interphase.campaign.plan import plan
        from interphase.campaign.schema import load_campaign

        c = load_campaign(path)
        seen.update(path=path, speeds={x.case.shear_velocity for x in c.cases}, warnings=c.warnings())
        return plan(c), {}, __import__("pandas").DataFrame()

    monkeypatch.setattr(el, "run_cases", fake_run_cases)
    monkeypatch.chdir("/")
    el.run_element(card, [100e3], [1])
    assert seen["path"] == tmp_path / "runs" / "element" / "tiny-card" / "element-tiny-card.toml"
    assert seen["speeds"] == {0.02} and not any("quasi-static" in w for w in seen["warnings"])
    el.run_element(card, [100e3], [1], output=tmp_path / "r", shear_velocity=0.01)
    assert seen["speeds"] == {0.01} and seen["path"].parent == tmp_path / "r"


@pytest.mark.parametrize("argv, words", [
    (["--normal-stress", "-100e3"], "must be > 0 Pa"),
    (["--normal-stress", "100e3", "--shear-velocity", "-0.02"], "must be > 0 m/s"),
    (["--normal-stress", "100e3", "--seeds", "-1"], "must be ≥ 1"),
])
def test_negative_numbers_reach_the_commands_own_message(capsys, argv, words):
    assert main(["element", str(DATA / "tiny_card.toml"), *argv]) == 2
    err = capsys.readouterr().err
    assert words in err and "expected one argument" not in err


def test_element_offers_only_options_it_has_and_says_why_a_run_failed(tmp_path, capsys):
    """A failed run printed nan angles and advised --rerun-failed, which `element` did not take."""
    from interphase.cli import build_parser

    args = build_parser().parse_args(["element", "c.toml", "--normal-stress", "1e5", "--rerun-failed"])
    assert args.rerun_failed
    from interphase.campaign.element import failures

    # a generated element campaign with one failed case recorded as the runner records it
    from interphase.campaign.element import write_campaign
    from interphase.campaign.plan import plan
    from interphase.campaign.schema import load_campaign
    from interphase.campaign.store import CampaignStore

    path = write_campaign(tmp_path / "element-x.toml", name="element-x", case={"test": "box", "device": "periodic",
                          "box_length_d50": 12.0, "box_height_d50": 8.0}, sweep={"seed": [1]})
    (p,) = plan(load_campaign(path))
    with CampaignStore(tmp_path, create=True) as store:
        store.register([p])
        folder = store.case_folder(p.case_id)
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "case.json").write_text(json.dumps({"label": p.label, "engine": "liggghts"}))
        (folder / "failure.json").write_text(json.dumps({"status": "failed", "cause": "engine_error",
                                                         "message": "ERROR: Lost atoms: original 300 current 2"}))
    (line,) = failures(path)
    assert "engine_error" in line and "Lost atoms" in line


def test_card_value_errors_name_line_and_table_once(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text((DATA / "tiny_card.toml").read_text().replace("friction_pp = 0.5", "friction_pp = -1"))
    assert main(["element", str(bad), "--normal-stress", "1e5"]) == 2
    err = capsys.readouterr().err
    line = next(i for i, ln in enumerate(bad.read_text().splitlines(), 1) if ln.startswith("friction_pp"))
    assert f"bad.toml:{line}: [soil] friction_pp" in err and "[soil]: [soil]" not in err


# ---- item 5: plausibility at load, verdicts ------------------------------------------------------
@pytest.mark.parametrize("old, new, field, words", [
    ("phi_peak_deg = 38.0", "phi_peak_deg = 0.66", "phi_peak_deg", "radians"),
    ("phi_peak_deg = 38.0", "phi_peak_deg = 85.0", "phi_peak_deg", "15–60°"),
    ("phi_cs_deg = 28.0", "phi_cs_deg = 0.49", "phi_cs_deg", "radians"),
    ("psi_max_deg = 15.0", "psi_max_deg = 40.0", "psi_max_deg", "not below φ_peak"),
])
def test_an_implausible_target_exits_2_before_anything_runs(tmp_path, capsys, no_engine, old, new, field, words):
    """A target in radians (φ_peak 0.66) or at 85° loaded without a word and would spend 149 runs."""
    text = (DATA / "tiny_target.toml").read_text()
    assert old in text
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace(old, new, 1))
    assert main(["calibrate", str(bad)]) == 2
    err = capsys.readouterr().err
    line = next(i for i, ln in enumerate(bad.read_text().splitlines(), 1) if ln.startswith(field))
    assert f"bad.toml:{line}: [target] {field}" in err and words in err and no_engine == []


def test_a_verdict_says_within_only_with_an_interval_inside_the_tolerance():
    """A --quick card called a 37°-wide interval "within"."""
    from interphase.campaign.calibrate import check_angles

    lab = {"phi_peak_deg": 38.0}
    verdict = lambda r: check_angles(lab, r)[0]["verdict"]
    assert verdict(_element(phi_peak=38.5, width=0.8)) == "within"
    assert verdict(_element(phi_peak=38.5, width=18.5)) == "undecided"         # the point within, the interval not
    one_seed = _element(phi_peak=38.0)
    one_seed = type(one_seed)(**{**one_seed.__dict__, "phi_peak_deg_lo": math.nan, "phi_peak_deg_hi": math.nan})
    assert verdict(one_seed) == "undecided"
    assert verdict(_element(phi_peak=45.0, width=1.0)) == "outside"


def test_the_shipped_full_card_is_read_back_not_replaced(capsys, no_engine):
    """The issue's case: `campaign calibrate soils/targets/synthetic-recovery.toml --quick` replaced the
    shipped card (149 runs, 34 min) with a 6-run quick card."""
    root = Path(__file__).resolve().parents[1]
    target, card = root / "soils" / "targets" / "synthetic-recovery.toml", root / "soils" / "synthetic-recovery.toml"
    before = _sha(card)
    assert main(["calibrate", str(target), "--json"]) == 0           # this card's own calibration: read back
    res = json.loads(capsys.readouterr().out)
    assert res["reused"] and res["calibration"]["runs"] == 149 and no_engine == []
    assert {a["verdict"] for a in res["achieved"]} == {"undecided"}   # today's rule: intervals wider than ±1.5°
    assert main(["calibrate", str(target), "--quick", "-o", str(card)]) == 2
    assert "never replaces" in capsys.readouterr().err and _sha(card) == before
