"""The failure criterion chain and `campaign predict`."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from interphase.analysis.correlations import prepare_points
from interphase.analysis.criterion import CriterionModel, predict, regular_flat_spacing
from interphase.cli import main
from interphase.errors import InputError
from interphase.report.synthetic import synthetic_summaries
from interphase.surface.profiles import sawtooth

DEKTAK = str(Path(__file__).parent / "data" / "dektak-1.csv")


def _run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_defaults_non_dilative_gives_tan_phimu_over_tan_phi():
    m = CriterionModel.study_defaults(0.2)
    p = predict(m, 0.2, math.nan, math.nan)
    assert p.branch == "non-dilative"
    assert p.theta_r_deg == pytest.approx(math.degrees(math.atan(0.2)))
    assert p.efficiency == pytest.approx(0.2 / m.tan_phi)
    assert p.tan_delta == pytest.approx(0.2)
    assert any("STUDY DEFAULTS" in n for n in p.notes)


def test_defaults_sawtooth_stronger_and_monotone_in_theta_a():
    m = CriterionModel.study_defaults(0.2)
    es = [predict(m, 0.2, a, a).efficiency for a in (0.0, 10.0, 20.0, 39.0)]
    assert all(b >= a for a, b in zip(es, es[1:])) and es[-1] > es[0] * 2


def test_regular_flat_spacing_rule():
    d50 = 0.7e-3
    s = sawtooth(1, 2, 1, d50=d50, length=0.03)
    assert regular_flat_spacing(s.x, s.z, d50)[0]
    s0 = sawtooth(1, 2, 0, d50=d50, length=0.03)
    assert not regular_flat_spacing(s0.x, s0.z, d50)[0]
    # irregular flats: spacing alternating 0.5 and 3 D50
    x = np.cumsum([0, 0.7, 0.7, 0.35, 0.7, 0.7, 2.1, 0.7, 0.7, 0.35, 0.7, 0.7, 2.1]) * 1e-3
    z = np.array([0, 0.7, 0, 0, 0.7, 0, 0, 0.7, 0, 0, 0.7, 0, 0]) * 1e-3
    ok, why = regular_flat_spacing(x, z, d50)
    assert not ok and "irregular" in why


@pytest.fixture(scope="module")
def fitted():
    return CriterionModel.from_points(prepare_points(synthetic_summaries(300, seed=5, noise_deg=0.5)),
                                      "campaign synthetic", n_boot=40)


def test_fitted_chain_uses_the_friction_fit_and_gives_intervals(fitted):
    assert {0.05, 0.2, 0.5} <= set(k for k in fitted.theta_r if k != "all")
    assert fitted.tan_phi == pytest.approx(0.55)
    p = predict(fitted, 0.2, 20.0, 19.0)
    truth_r = 11.31 + (35 - 11.31) * 20 / 40
    assert p.theta_r_deg == pytest.approx(truth_r, abs=1.5)
    lo, hi = p.theta_r_interval
    assert lo <= p.theta_r_deg <= hi
    assert p.efficiency_interval[0] <= p.efficiency <= p.efficiency_interval[1]
    assert p.tan_delta == pytest.approx(p.efficiency * 0.55)
    q = predict(fitted, 0.3, 0.0, 0.0)          # between the 0.2 and 0.5 fits: interpolated, said so
    assert any("interpolated" in n for n in q.notes)
    assert q.theta_r_deg == pytest.approx(math.degrees(math.atan(0.3)), abs=1.5)   # intercept ≈ φμ
    with pytest.raises(InputError, match="0.05–0.5") as exc:    # outside every fitted friction: refused
        predict(fitted, 0.9, 20.0, 19.0)
    assert "frictions" in str(exc.value) and "θa" in str(exc.value)


def test_fitted_flat_spaced_branch(fitted):
    p = predict(fitted, 0.2, 42.0, 30.0, flat_spaced=True)
    assert p.branch.startswith("flat-spaced") and p.filter == 90
    truth = (0.6 + 0.01 * (120 - 115)) * 30.0
    assert p.theta_r_deg == pytest.approx(truth, abs=2.0)


def test_refuses_theta_a_outside_fitted_range(fitted):
    with pytest.raises(InputError, match="outside the fitted range"):
        predict(fitted, 0.2, 75.0, 75.0)


def test_cli_predict_dektak_is_non_dilative(capsys):
    code, out, err = _run(capsys, "predict", DEKTAK, "--d50", "0.7", "--friction", "0.2", "--units", "um", "--json",
                          "--fit", "study-figures")
    assert code == 0, err
    d = json.loads(out)
    assert d["branch"] == "non-dilative" and d["fit_source"] == "study defaults"
    assert d["efficiency"] == pytest.approx(math.tan(math.atan(0.2)) / d["tan_phi"])
    code, text, _ = _run(capsys, "predict", DEKTAK, "--d50", "0.7", "--friction", "0.2", "--units", "um",
                         "--fit", "study-figures")
    assert code == 0 and "STUDY DEFAULTS" in text


def test_cli_predict_sawtooth_gives_higher_e(capsys, tmp_path):
    prof = tmp_path / "saw45.txt"
    assert main(["profile", "sawtooth", "--rt", "1", "--sw", "2", "-o", str(prof)]) == 0
    capsys.readouterr()
    _, out_flat, _ = _run(capsys, "predict", DEKTAK, "--d50", "0.7", "--friction", "0.2", "--units", "um", "--json", "--fit", "study-figures")
    code, out, err = _run(capsys, "predict", str(prof), "--d50", "0.7", "--friction", "0.2", "--json", "--fit", "study-figures")
    assert code == 0, err
    saw, flat = json.loads(out), json.loads(out_flat)
    assert saw["branch"].startswith("dilative") and saw["theta_a_deg"] == pytest.approx(39.3, abs=0.5)
    assert saw["efficiency"] > 2 * flat["efficiency"]


@pytest.mark.parametrize("argv, where", [
    (["--d50", "0", "--friction", "0.2", "--fit", "study"], "--d50"),
    (["--d50", "0.7", "--friction", "-1", "--fit", "study"], "--friction"),
    (["--d50", "0.7", "--friction", "0.2", "--tan-phi", "0", "--fit", "study"], "--tan-phi"),
])
def test_cli_predict_bad_input_exit_2(capsys, argv, where):
    code, _, err = _run(capsys, "predict", DEKTAK, "--units", "um", *argv)
    assert code == 2 and where in err and "Traceback" not in err


def test_cli_predict_flat_spaced_profile_takes_the_fig_6_9_branch(capsys, tmp_path):
    prof = tmp_path / "spaced.txt"
    assert main(["profile", "spaced", "--rt", "1", "--sw", "2", "--sr", "1", "-o", str(prof)]) == 0
    capsys.readouterr()
    code, out, err = _run(capsys, "predict", str(prof), "--d50", "0.7", "--friction", "0.05", "--json",
                          "--fit", "study-figures")
    assert code == 0, err
    d = json.loads(out)
    assert d["flat_spaced"] and d["branch"].startswith("flat-spaced") and d["theta_a_filter"] == 90
    code, out, err = _run(capsys, "predict", str(prof), "--d50", "0.7", "--friction", "0.05", "--filter", "92", "--json",
                         "--fit", "study-figures")
    assert code == 0 and json.loads(out)["branch"].startswith("dilative")


@pytest.mark.liggghts
def test_cli_predict_fit_without_enough_cases_says_why(capsys, quick_campaign):
    quick = quick_campaign
    capsys.readouterr()
    code, _, err = _run(capsys, "predict", DEKTAK, "--d50", "0.7", "--friction", "0.2", "--units", "um",
                        "--fit", str(quick))
    assert code == 2 and "no fit: n =" in err


def test_a_fitted_criterion_travels_as_json_with_its_intervals(fitted, tmp_path, capsys):
    """criterion.json (what `campaign report` writes and the package ships for the reproduction)
    gives back the same chain: predictions and bootstrap intervals on every branch."""
    from interphase.criterion_fits import load_criterion

    path = tmp_path / "criterion.json"
    path.write_text(json.dumps(fitted.to_dict({"physical_cases": 300, "groups": ["g1"]}), allow_nan=False))
    back = load_criterion(path)
    assert "300 physical cases" in back.source and set(back.theta_r) == set(fitted.theta_r)
    for mu, a in ((0.2, 30.0), (0.05, 10.0), (0.35, 45.0)):      # 0.35: blended between two frictions
        p, q = predict(fitted, mu, a, a), predict(back, mu, a, a)
        assert q.tan_delta == pytest.approx(p.tan_delta, rel=1e-9)
        assert q.tan_delta_interval == pytest.approx(p.tan_delta_interval, rel=1e-4)
        assert all(math.isfinite(v) for v in q.theta_r_interval + q.efficiency_interval)
    p, q = predict(fitted, 0.05, 30.0, 30.0, flat_spaced=True), predict(back, 0.05, 30.0, 30.0, flat_spaced=True)
    assert q.theta_r_deg == pytest.approx(p.theta_r_deg) and q.theta_r_interval == pytest.approx(p.theta_r_interval, rel=1e-4)

    prof = tmp_path / "saw45.txt"
    assert main(["profile", "sawtooth", "--rt", "1", "--sw", "2", "-o", str(prof)]) == 0
    capsys.readouterr()
    code, text, err = _run(capsys, "predict", str(prof), "--d50", "0.7", "--friction", "0.2", "--fit", str(path), "--json")
    assert code == 0, err
    d = json.loads(text)
    assert "300 physical cases" in d["fit_source"] and d["model_delta_deg_lo"] < d["delta_deg"] < d["model_delta_deg_hi"]

    path.write_text(json.dumps({"schema": "something else"}))
    code, _, err = _run(capsys, "predict", str(prof), "--d50", "0.7", "--friction", "0.2", "--fit", str(path))
    assert code == 2 and str(path) in err and "campaign report" in err


def test_predict_names_the_simulated_soil_it_answers_for(capsys, tmp_path):
    """No silent fall-back on the study's discs: without --soil or --fit, exit 2 naming both; `--fit
    study` is the reproduction's fit shipped with the package, its interval owning the held-out error."""
    from interphase.criterion_fits import REPRODUCTION

    assert REPRODUCTION.exists(), "the package ships the reproduction's criterion.json"
    prof = tmp_path / "saw45.txt"
    assert main(["profile", "sawtooth", "--rt", "1", "--sw", "2", "-o", str(prof)]) == 0
    capsys.readouterr()
    code, _, err = _run(capsys, "predict", str(prof), "--d50", "0.7", "--friction", "0.2")
    assert code == 2 and "--soil CARD" in err and "--fit study" in err, err
    code, out, err = _run(capsys, "predict", str(prof), "--d50", "0.7", "--friction", "0.2", "--fit", "study", "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["fit"] == "study" and "study" in d["fit_source"] and "STUDY DEFAULTS" not in " ".join(d["notes"])
    assert d["parts_deg"]["residual"] > d["parts_deg"]["fit"] > 0
    assert d["model_delta_deg_lo"] < d["delta_deg"] < d["model_delta_deg_hi"]


def test_figs_6_7_and_6_8_take_the_well_graded_cases_when_both_gradations_ran():
    from interphase.analysis.correlations import SPECS, subset

    pts = prepare_points(synthetic_summaries(300, seed=5, noise_deg=0.5))
    mono = (pts["gradation"] == "mono").to_numpy()
    assert 20 < mono.sum() < len(pts)
    # uniform grains made far off the well-graded line and with another soil: they must not move the chain
    skewed = pts.assign(theta_r_surface_deg=np.where(mono, pts["theta_r_surface_deg"] + 25.0, pts["theta_r_surface_deg"]),
                        tan_phi=np.where(mono, 0.40, pts["tan_phi"]))
    m = CriterionModel.from_points(skewed, "both", n_boot=0)
    ref = CriterionModel.from_points(pts[~mono], "well-graded", n_boot=0)
    assert m.theta_r["all"].c == pytest.approx(ref.theta_r["all"].c)
    assert np.allclose(m.theta_r["all"].coef, ref.theta_r["all"].coef)
    assert m.tan_phi == pytest.approx(0.55)
    for key in ("fig6_7a", "fig6_7b", "fig6_8"):
        assert (subset(skewed, SPECS[key])["gradation"] == "poly").all()
    assert (subset(skewed, SPECS["fig6_10a"])["gradation"] == "mono").sum() == mono.sum()   # 6.10a: both
    assert len(subset(skewed[mono], SPECS["fig6_8"])) > 0        # uniform grains alone keep their cases


def test_skill_puts_the_criterion_beside_its_baselines_on_the_same_cases():
    import pandas as pd

    from interphase.analysis.criterion import skill

    df = pd.DataFrame({"error_deg": [1.0, -1.0, 3.0, float("nan")], "error_soil_deg": [0.0, 0.0, 10.0, 1.0],
                       "error_rule_deg": [2.0, 2.0, 5.0, 1.0], "mobilised": [True, True, False, False]})
    s = skill(df).set_index(["subset", "predictor"])
    assert s.loc[("all", "criterion"), "n"] == 3                     # the NaN case is left out of every row
    assert s.loc[("all", "criterion"), "rms_deg"] == pytest.approx((11 / 3) ** 0.5)
    assert s.loc[("not fully mobilised", "δ = φ (the soil's own)"), "within_4deg"] == 0.0
    assert s.loc[("fully mobilised", "δ = min(φμ + θa, φ) (no fit)"), "mean_deg"] == 2.0


def test_skill_says_whether_the_cases_can_tell_the_criterion_from_a_baseline():
    """rms_gap: a baseline's rms minus the criterion's with a paired case-bootstrap interval; a
    baseline missing by 3° more on every case is decided worse, one with the criterion's errors
    of opposite sign is not told apart, and the criterion carries no gap of its own."""
    import pandas as pd

    from interphase.analysis.criterion import skill

    rng = np.random.default_rng(1)
    e = rng.normal(0, 1, 30)
    df = pd.DataFrame({"error_deg": e, "error_soil_deg": e + np.sign(e) * 3.0,
                       "error_rule_deg": -e, "mobilised": np.arange(30) % 2 == 0})
    s = skill(df).set_index(["subset", "predictor"])
    soil, rule = s.loc[("all", "δ = φ (the soil's own)")], s.loc[("all", "δ = min(φμ + θa, φ) (no fit)")]
    assert soil.rms_gap_lo > 0 and soil.rms_gap_lo < soil.rms_gap_deg < soil.rms_gap_hi
    assert rule.rms_gap_deg == pytest.approx(0.0, abs=1e-12) and rule.rms_gap_lo <= 0 <= rule.rms_gap_hi
    assert np.isnan(s.loc[("all", "criterion"), "rms_gap_deg"])
    assert s.loc[("fully mobilised", "δ = φ (the soil's own)"), "n"] == 15


def test_the_two_constant_rule_recovers_its_constants():
    import pandas as pd

    from interphase.analysis.criterion import fit_rule, rule_delta

    rng = np.random.default_rng(0)
    mu = rng.choice([0.05, 0.2, 0.5], 60)
    ta = rng.uniform(0, 60, 60)
    tp = np.full(60, 0.38)
    delta = rule_delta(mu, ta, tp, 2.5, 1.04)
    pts = pd.DataFrame({"friction_ps": mu, "theta_a_deg_92": ta, "tan_phi": tp,
                        "peak_stress_ratio": np.tan(np.radians(delta))})
    a, b = fit_rule(pts)
    assert a == pytest.approx(2.5, abs=1e-2) and b == pytest.approx(1.04, abs=1e-3)
    assert np.isnan(fit_rule(pts.iloc[:2])[0])
