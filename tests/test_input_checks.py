"""Issue 32 item 3: every input checked once, at load, by the one schema that `render`, `run-case`
and `run` share; the shipped quick.toml passes its own checks; study.toml keeps its committed ids."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from interphase.campaign.plan import plan
from interphase.campaign.schema import load_campaign
from interphase.cli import main
from interphase.soil import SOIL_FIELDS

ROOT = Path(__file__).resolve().parents[1]
CASE = '[case]\ntest = "interface"\nprofile = {kind = "sawtooth", rt = 1, sw = 2, sr = 0}\n'
CAMPAIGN = '[campaign]\nname = "c"\n' + CASE


def _all_three(tmp_path, case_extra: str, sweep: str = ""):
    """(render rc, stderr), (run-case rc, stderr), (run --dry-run rc, stderr+stdout) on one input."""
    case = tmp_path / "case.toml"
    case.write_text(CASE + case_extra)
    camp = tmp_path / "camp.toml"
    camp.write_text(CAMPAIGN + case_extra + "[pairs]\nbox = false\n" + sweep)
    return case, camp


@pytest.mark.parametrize("extra,sweep,needle", [
    ("seed = -1\n", "", "seed"),
    ("", "[sweep]\nseed = [1, -1]\n", "seed"),
    ("profile = {kind = 'random', au = 1, ar = 1, rtmax = 1, seed = -3}\n", "", "profile.seed"),
    ("shear_velocity = 50\n", "", "shear_velocity"),
    ("", "[sweep]\nshear_velocity = [0.01, 50]\n", "shear_velocity"),
])
def test_bad_seeds_and_speeds_are_one_clear_error_in_every_command(tmp_path, capsys, extra, sweep, needle):
    if extra.startswith("profile"):
        case = tmp_path / "case.toml"
        case.write_text('[case]\ntest = "interface"\n' + extra)
        camp = tmp_path / "camp.toml"
        camp.write_text('[campaign]\nname = "c"\n[case]\ntest = "interface"\n' + extra + "[pairs]\nbox = false\n")
    else:
        case, camp = _all_three(tmp_path, extra, sweep)
    commands = [["run", str(camp), "--dry-run"], ["status", str(camp)]]
    if not sweep:
        commands += [["render", str(case), "-o", str(tmp_path / "r")], ["run-case", str(case), "-o", str(tmp_path / "k")]]
    for cmd in commands:
        assert main(cmd) == 2, cmd
        err = capsys.readouterr().err
        assert "Traceback" not in err and needle in err and err.count("\n") == 1, (cmd, err)
        assert (str(case) if cmd[0] in ("render", "run-case") else str(camp)) in err
    assert not (tmp_path / "r").exists() and not (tmp_path / "k").exists()


def test_an_implausible_value_warns_alike_in_render_and_run(tmp_path, capsys):
    case, camp = _all_three(tmp_path, "shear_velocity = 0.2\nfriction_ps = 3\n")
    assert main(["render", str(case), "-o", str(tmp_path / "r")]) == 0
    render_err = capsys.readouterr().err
    assert main(["run", str(camp), "--dry-run"]) == 0
    run_out = capsys.readouterr().out
    for text in (render_err, run_out):
        assert "inertial number" in text and "friction_ps = 3" in text, text


def test_quick_passes_its_own_checks_and_study_keeps_its_ids():
    quick = load_campaign(ROOT / "campaigns" / "quick.toml")
    assert quick.warnings() == []
    ids = {p.case_id for p in plan(load_campaign(ROOT / "campaigns" / "study.toml"))}
    committed = set(pd.read_csv(ROOT / "docs" / "reproduction" / "summaries.csv")["case_id"])
    assert len(committed) == 398 and committed == ids


def test_unstated_converged_settings_are_named(tmp_path):
    _, camp = _all_three(tmp_path, "")
    (note,) = [w for w in load_campaign(camp).warnings() if "convergence study" in w]
    assert "device = 'walled'" in note and "chosen: 'periodic'" in note and "ids" in note
    assert "box_length_d50 = 40.0 (chosen: 60.0" in note and "box_height_d50 = 20.0 (chosen: 35.0" in note
    _, camp = _all_three(tmp_path, 'device = "periodic"\nshear_velocity = 0.02\nshear_modulus = 50e6\n'
                         "shear_distance = 0.006\nbox_length_d50 = 40\nbox_height_d50 = 25\n")
    assert load_campaign(camp).warnings() == []


def test_the_soft_stiffness_variant_is_the_card_at_another_g_only():
    """studies/kfs_3d_stiffness/g50_20x15x5.toml copies the 3D card's grains (a card is not
    overridden field by field): its cases are the card file's, case for case, but for G."""
    def cases(name):
        camp = load_campaign(ROOT / "studies" / "kfs_3d_stiffness" / name)
        return {(x.role, x.case.seed): x.case.canonical() for x in camp.cases}

    card, soft = cases("g500_20x15x5.toml"), cases("g50_20x15x5.toml")
    assert card.keys() == soft.keys() and len(card) == 6
    for k in card:
        diff = {f for f in card[k] if card[k][f] != soft[k].get(f)} | (soft[k].keys() - card[k].keys())
        assert diff == {"shear_modulus"}, (k, diff)
        assert (card[k]["shear_modulus"], soft[k]["shear_modulus"]) == (500e6, 50e6)
    # the cell study runs on the same softened grains
    grains = {f: v for f, v in next(iter(soft.values())).items() if f in SOIL_FIELDS}
    assert grains.keys() == set(SOIL_FIELDS)
    cell = load_campaign(ROOT / "studies" / "kfs_3d_cell" / "cell_3d.toml")
    for x in cell.cases:
        assert {f: v for f, v in x.case.canonical().items() if f in SOIL_FIELDS} == grains


def test_a_soil_cards_fields_count_as_stated():
    # the card's G fills every case: no note may say it takes the 29 GPa default
    import tomllib

    camp = load_campaign(ROOT / "studies" / "kfs_group1_2d" / "group1_kfs_2d.toml")
    assert "shear_modulus" in camp.stated
    assert not [w for w in camp.warnings() if "convergence study" in w]
    card = tomllib.loads((ROOT / "soils" / "karlsruhe-fine-sand-2d.toml").read_text())["soil"]
    assert {c.case.shear_modulus for c in camp.cases} == {card["shear_modulus"]} != {29e9}
