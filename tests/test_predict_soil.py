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
    """A copy of the 3D card without its own [criterion] (which names files beside the shipped card)."""
    card = tmp_path / "sand.toml"
    card.write_text(CARD.read_text().split("\n[criterion]")[0] + extra)
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
    for key in ("theta_a_deg", "efficiency", "tan_delta", "delta_deg", "model_delta_deg_lo", "model_delta_deg_hi"):
        assert out[key] == same[key], key
    # the card's answer owns its misfit against its records; the fit alone has no records
    assert out["delta_deg_lo"] < out["model_delta_deg_lo"] <= out["delta_deg"] <= out["model_delta_deg_hi"] < out["delta_deg_hi"]
    assert out["parts_deg"]["card"] > 0 and (same["delta_deg_lo"], same["delta_deg_hi"]) == (same["model_delta_deg_lo"], same["model_delta_deg_hi"])


def test_a_card_without_a_fit_or_a_contradicting_d50_is_refused(tmp_path, capsys):
    code, err = _predict(capsys, "--soil", str(_card(tmp_path)))
    assert code == 2 and "[criterion] fit" in err and "sand.toml" in err
    card = _card(tmp_path, f'\n[criterion]\nfit = "{FIT}"\n')
    code, err = _predict(capsys, "--soil", str(card), "--d50", "0.7")
    assert code == 2 and "--d50" in err and "0.14 mm" in err
    code, err = _predict(capsys, "--soil", str(card), "--fit", str(FIT))
    assert code == 2 and "not both" in err
    code, err = _predict(capsys)
    assert code == 2 and "--soil CARD" in err and "--fit study" in err


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


@pytest.mark.parametrize("card_name, cell", [("karlsruhe-fine-sand-2d.toml", "2d"),
                                              ("karlsruhe-fine-sand.toml", "3d")])
def test_each_kfs_card_ships_the_fit_of_its_own_group1(tmp_path, capsys, card_name, cell):
    """Each Karlsruhe card (quasi-2D and 3D) names the criterion fitted on its own Group 1
    (studies/kfs_group1_<cell>/results/criterion.json): predict --soil answers on a tooth inside the
    fitted θa range with δ and its interval, from θa–θr lines fitted per friction (nine or more
    surfaces a friction), and the fit's tan φ is the committed ensembles' soil test (one set of runs);
    the shipped Dektak line (θa 2.5° at this D50) is inside the range the flats give;
    a profile beyond the steepest tooth is refused, naming the file and --simulate."""
    import pandas as pd

    card = ROOT / "soils" / card_name
    saw = tmp_path / "saw.txt"
    assert main(["profile", "sawtooth", "--rt", "0.5", "--sw", "2", "--d50", "0.14", "--length", "6",
                 "-o", str(saw)]) == 0
    capsys.readouterr()
    code = main(["predict", str(saw), "--friction", "0.2", "--soil", str(card), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["soil"] == str(card) and out["d50_mm"] == 0.14
    fit = json.loads(Path(out["fit"]).read_text())
    assert fit["source"].startswith(f"campaign group1-kfs-{cell}")
    assert {"0.05", "0.2", "0.5"} <= set(fit["theta_r"]), fit["reasons"]
    ens = pd.read_csv(ROOT / "studies" / f"kfs_group1_{cell}" / "results" / "ensembles.csv")
    assert fit["tan_phi"] == pytest.approx(ens["tan_phi"].median(), rel=1e-9)
    assert out["delta_deg_lo"] < out["delta_deg"] < out["delta_deg_hi"]
    code, out = _predict(capsys, "--soil", str(card), "--json")  # dektak-1 at D50 0.14 mm: θa 2.5°
    assert code == 0 and 0 < out["theta_a_deg"] < 5.65, out       # under Group 1's lowest tooth: the
    assert out["delta_deg_lo"] <= out["delta_deg"] <= out["delta_deg_hi"]   # flat and lines cover it
    steep = tmp_path / "steep.txt"                                 # θa beyond the steepest tooth's 73.7°
    assert main(["profile", "sawtooth", "--rt", "12", "--sw", "2", "--d50", "0.14", "--length", "6",
                 "-o", str(steep)]) == 0
    capsys.readouterr()
    code = main(["predict", str(steep), "--friction", "0.2", "--soil", str(card)])
    err = capsys.readouterr().err
    assert code == 2 and "outside the fitted range" in err and "--simulate" in err, err
    assert f"error: {steep}: θa" in err, err                       # the error names the file


def test_a_card_simulates_in_the_cell_its_criterion_stands_on(tmp_path, capsys):
    """--simulate's interface cell (campaign.validate.interface_case): the shipped 3D card names its
    Group 1 campaign, so a surface is sheared in that campaign's 3D cell at its 50 MPa, with the card's
    grains; the quasi-2D card in its own campaign's quasi-2D cell; a 3D card naming no campaign in
    the chosen 3D cell at its own stiffness, never as discs; a campaign of other grains is refused."""
    from interphase.campaign.element import write_campaign
    from interphase.campaign.validate import PROTOCOL_3D, interface_case, protocol_for
    from interphase.errors import InputError
    from interphase.soil import load_card

    card3 = load_card(CARD)
    case, why = interface_case(card3)
    assert case["device"] == "periodic3d" and case["box_depth_d50"] == 10 and case["shear_modulus"] == 50e6
    assert "group1_kfs_3d.toml" in why and "G 50 MPa" in why
    assert {k: case[k] for k in card3.soil if k != "shear_modulus"} == {k: v for k, v in card3.soil.items()
                                                                          if k != "shear_modulus"}
    card2 = load_card(ROOT / "soils" / "karlsruhe-fine-sand-2d.toml")
    case2, why2 = interface_case(card2)
    assert case2["device"] == "periodic" and case2["soil"] == str(card2.path) and "group1_kfs_2d.toml" in why2
    bare, why3 = interface_case(load_card(_card(tmp_path)))
    assert bare == {"soil": str(tmp_path / "sand.toml"), **protocol_for(0.00014, PROTOCOL_3D)} and "3D" in why3
    other = _card(tmp_path, f'\n[criterion]\ncampaign = "{ROOT / "studies" / "kfs_group1_2d" / "group1_kfs_2d.toml"}"\n')
    with pytest.raises(InputError, match="not this card") as e:
        interface_case(load_card(other))
    assert "[criterion] campaign" in str(e.value)

    # the generated campaign plans the 3D cell's interface case and its soil test: the very cases
    # (the same ids) Group 1 ran, whose committed runs the fit stands on
    path = write_campaign(tmp_path / "sim" / "simulate.toml", name="predict", sweep={"seed": [1]}, executor="local",
                          case={**case, "profile": {"kind": "sawtooth", "rt": 1.0, "sw": 2.0, "sr": 0.0},
                                "normal_stress": 1e5, "friction_ps": 0.5}, description="test")
    capsys.readouterr()
    assert main(["run", str(path), "--dry-run", "--plain"]) == 0
    out = capsys.readouterr().out
    assert "interface-periodic3d-sawtooth-rt1-" in out and "box-periodic3d-box" in out, out
    import pandas as pd

    g1 = pd.read_csv(ROOT / "studies" / "kfs_group1_3d" / "results" / "summaries.csv", dtype=str)
    same = g1[g1["label"].isin(["box-periodic3d-box-mu0.9-user-prep0.387-s1",
                                "interface-periodic3d-sawtooth-rt1-sr0-sw2-mu0.5-user-prep0.387-s1"])]
    assert len(same) == 2 and all(cid in out for cid in same["case_id"]), out
    # so --simulate restores those soil tests from the fit's committed runs instead of running them
    from interphase.campaign.restore import restorable_ids
    from interphase.campaign.validate import _fit_runs

    table = _fit_runs(card3)
    assert table == ROOT / "studies" / "kfs_group1_3d" / "results" / "summaries.csv"
    box = same.loc[same["label"].str.startswith("box-"), "case_id"].iloc[0]
    assert box in restorable_ids(table) and _fit_runs(load_card(_card(tmp_path))) is None


def test_the_api_answers_as_the_command(tmp_path, capsys):
    """ip.predict(…, soil=CARD) gives the command's δ and fit; ip.predict_dem refuses what the
    command refuses (an areal scan, a D50 that is not the card's), naming the argument."""
    import interphase as ip

    card = ROOT / "soils" / "karlsruhe-fine-sand-2d.toml"
    saw = tmp_path / "saw.txt"
    assert main(["profile", "sawtooth", "--rt", "0.5", "--sw", "2", "--d50", "0.14", "--length", "6",
                 "-o", str(saw)]) == 0
    capsys.readouterr()
    assert main(["predict", str(saw), "--friction", "0.2", "--soil", str(card), "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)
    api = ip.predict(saw, friction=0.2, soil=card).to_dict()
    for key in ("theta_a_deg", "efficiency", "delta_deg", "delta_deg_lo", "delta_deg_hi", "fit", "soil", "d50_mm"):
        assert api[key] == cli[key], key
    with pytest.raises(ip.InputError, match="not both"):
        ip.predict(saw, friction=0.2, soil=card, fit=str(FIT))
    with pytest.raises(ip.InputError, match="d50"):
        ip.predict_dem(saw, 0.2, card, d50=0.7e-3, runs=tmp_path / "runs")
    with pytest.raises(ip.InputError, match="one line"):
        ip.predict_dem(ROOT / "campaigns" / "profiles" / "frt-1.frt", 0.2, card, runs=tmp_path / "runs")
    with pytest.raises(ip.InputError, match="seeds"):
        ip.predict_dem(saw, 0.2, card, seeds=2, runs=tmp_path / "runs")
    assert not (tmp_path / "runs").exists()


def test_simulate_on_an_areal_scan_shears_its_patch_in_the_3d_cell_with_the_fits_soil_tests(tmp_path, capsys):
    """`predict SCAN --soil 3D-CARD --simulate --axis y`: the scan itself (not one line) is the 3D cell's
    surface, its best-closing patch with the soil moving +y (surface/patch.py), in the cell the card's
    criterion stands on; the soil tests are Group 1's own ids, so a run restores them from the fit's
    committed runs and runs only the interface cases (the dry run says so). The engine runs a patch of
    this scan in tests/test_scan_patch.py's tiny case."""
    from interphase.campaign.validate import _fit_runs, simulate_campaign
    from interphase.soil import load_card

    scan = ROOT / "campaigns" / "profiles" / "frt-1.frt"
    card = load_card(CARD)
    surface = {"kind": "file", "path": str(scan), "areal": True, "direction": "+y"}
    path, cell = simulate_campaign(card, surface, 0.3, [1, 2, 3], output=tmp_path / "sim")
    assert "group1_kfs_3d.toml" in cell
    capsys.readouterr()
    assert main(["run", str(path), "--dry-run", "--list", "--plain", "--restore", str(_fit_runs(card))]) == 0
    out = capsys.readouterr().out
    assert out.count("interface-periodic3d-frt-1-areal-py") == 3, out
    assert "3 restore" in out and "3 run" in out and out.count("box-periodic3d-box-mu0.9-user-prep0.387-s") == 3, out
    card2 = load_card(ROOT / "soils" / "karlsruhe-fine-sand-2d.toml")
    with pytest.raises(Exception, match="one line"):
        simulate_campaign(card2, surface, 0.3, [1, 2, 3], output=tmp_path / "sim2")
    assert not (tmp_path / "sim2").exists()
