"""`campaign predict … --soil CARD`: the criterion a soil card names as fitted on its own interface
runs, with the card's D50; the same numbers as that fit given by hand."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from interphase.cli import main

ROOT = Path(__file__).resolve().parents[1]
PROFILE = ROOT / "campaigns" / "profiles" / "dektak-1.csv"
FIT = ROOT / "src" / "interphase" / "data" / "criterion_reproduction.json"   # a committed fit (any soil's)
CARD = ROOT / "soils" / "karlsruhe-fine-sand.toml"


def _card(tmp_path, extra: str = "") -> Path:
    card = tmp_path / "sand.toml"
    card.write_text(CARD.read_text() + extra)
    return card


def _predict(capsys, *args) -> tuple[int, dict | str]:
    code = main(["predict", str(PROFILE), "--friction", "0.2", *args])
    out, err = capsys.readouterr()
    return code, (json.loads(out) if code == 0 and "--json" in args else err)


def test_soil_uses_the_fit_its_card_names_and_its_d50(tmp_path, capsys):
    card = _card(tmp_path, f'\n[criterion]\nfit = "{FIT}"\n')
    code, out = _predict(capsys, "--soil", str(card), "--json")
    assert code == 0, out
    code, same = _predict(capsys, "--fit", str(FIT), "--d50", "0.14", "--json")
    assert code == 0, same
    assert out["d50_mm"] == 0.14 and out["soil"] == str(card) and out["fit"] == str(FIT)
    assert out["fit_source"].startswith(json.loads(FIT.read_text())["source"])
    for key in ("theta_a_deg", "efficiency", "tan_delta", "delta_deg", "delta_deg_lo", "delta_deg_hi"):
        assert out[key] == same[key], key
    assert out["delta_deg_lo"] <= out["delta_deg"] <= out["delta_deg_hi"]


def test_a_card_without_a_fit_or_a_contradicting_d50_is_refused(tmp_path, capsys):
    code, err = _predict(capsys, "--soil", str(_card(tmp_path)))
    assert code == 2 and "[criterion] fit" in err and "sand.toml" in err
    card = _card(tmp_path, f'\n[criterion]\nfit = "{FIT}"\n')
    code, err = _predict(capsys, "--soil", str(card), "--d50", "0.7")
    assert code == 2 and "--d50" in err and "0.14 mm" in err
    code, err = _predict(capsys, "--soil", str(card), "--fit", str(FIT))
    assert code == 2 and "not both" in err
    code, err = _predict(capsys)
    assert code == 2 and "--d50" in err


def test_simulate_needs_a_card_and_three_seeds(tmp_path, capsys):
    code, err = _predict(capsys, "--simulate")
    assert code == 2 and "--soil CARD" in err
    code, err = _predict(capsys, "--simulate", "--soil", str(_card(tmp_path)), "--seeds", "2",
                         "--runs", str(tmp_path / "runs"))
    assert code == 2 and "--seeds" in err and not (tmp_path / "runs").exists()


def test_simulate_refuses_what_only_the_criterion_uses(tmp_path, capsys):
    card = str(_card(tmp_path))
    for extra in (["--tan-phi", "0.7"], ["--fit", str(FIT)], ["--d50", "0.7"]):
        code, err = _predict(capsys, "--simulate", "--soil", card, "--runs", str(tmp_path / "runs"), *extra)
        assert code == 2 and extra[0] in err and not (tmp_path / "runs").exists(), err


def test_the_quasi2d_card_ships_the_fit_of_its_own_group1(tmp_path, capsys):
    """soils/karlsruhe-fine-sand-2d.toml names the criterion fitted on its Group 1
    (docs/reproduction/real_sand/2d/criterion.json): predict --soil answers on a tooth inside the
    fitted θa range with δ and its interval, from θa–θr lines fitted per friction (eight surfaces a
    friction), and the fit's tan φ is the committed ensembles' soil test (one set of runs); a
    measured profile outside the fitted θa range is refused, naming --simulate."""
    import pandas as pd

    card = ROOT / "soils" / "karlsruhe-fine-sand-2d.toml"
    saw = tmp_path / "saw.txt"
    assert main(["profile", "sawtooth", "--rt", "0.5", "--sw", "2", "--d50", "0.14", "--length", "6",
                 "-o", str(saw)]) == 0
    capsys.readouterr()
    code = main(["predict", str(saw), "--friction", "0.2", "--soil", str(card), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["soil"] == str(card) and out["d50_mm"] == 0.14
    fit = json.loads(Path(out["fit"]).read_text())
    assert fit["source"].startswith("campaign group1-kfs-2d")
    assert {"0.05", "0.2", "0.5"} <= set(fit["theta_r"]), fit["reasons"]
    ens = pd.read_csv(ROOT / "docs" / "reproduction" / "real_sand" / "2d" / "ensembles.csv")
    assert fit["tan_phi"] == pytest.approx(ens["tan_phi"].median(), rel=1e-9)
    assert out["delta_deg_lo"] < out["delta_deg"] < out["delta_deg_hi"]
    code, err = _predict(capsys, "--soil", str(card))            # dektak-1 at D50 0.14 mm: θa 2.5°
    assert code == 2 and "outside the fitted range" in err and "--simulate" in err, err
