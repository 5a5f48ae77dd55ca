"""Issue 69 item 1: one code path. Each bad input is fed to `campaign VERB …` (interphase.cli.main:
exit 2, one message on stderr, no traceback) and to the API function the verb calls (InputError),
and the command's message is the API's word for word: the check lives behind the API, once.
Engine-free: every refusal comes before anything is written or run."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

import interphase.api as api
from interphase.cli import main
from interphase.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
PROFILE = ROOT / "tests" / "data" / "dektak-1.csv"          # a Dektak export: µm, its own units
QUICK = ROOT / "campaigns" / "quick.toml"
CARD_2D = ROOT / "soils" / "karlsruhe-fine-sand-2d.toml"
CARD_3D = ROOT / "soils" / "karlsruhe-fine-sand.toml"
RECORD = ROOT / "lab" / "soils" / "karlsruhe-fine-sand" / "drained-triaxial" / "TMD11.dat"
FIT = ["--fit", "study", "--d50", "0.7", "--friction", "0.2"]
STUDY = {"fit": "study", "d50": 0.7e-3, "friction": 0.2}


@pytest.fixture(scope="module")
def at(tmp_path_factory) -> dict[str, str]:
    """The files the bad inputs name: a generated profile, a file and a folder a user owns, a soil
    card, a case file and a campaign that puts the 3D card in the quasi-2D device."""
    tmp = tmp_path_factory.mktemp("one_path")
    saw = api.make_profile("sawtooth", tmp / "saw.txt", d50=0.7e-3, length=10e-3, rt=1.0, sw=2.0)["output"]
    (tmp / "mine.txt").write_text("my own file")
    (tmp / "busy").mkdir()
    (tmp / "busy" / "notes.txt").write_text("mine")
    shutil.copy(ROOT / "tests" / "data" / "soils" / "tiny_card.toml", tmp / "card.toml")
    (tmp / "case.toml").write_text('[case]\ntest = "box"\ndevice = "periodic"\nbox_length_d50 = 12.0\n'
                                   'box_height_d50 = 8.0\nshear_velocity = 0.02\n')
    (tmp / "card3d_in_2d.toml").write_text(
        f'[campaign]\nname = "c3d"\n[case]\nsoil = "{CARD_3D}"\ntest = "interface"\ndevice = "periodic"\n'
        'box_length_d50 = 40.0\nbox_height_d50 = 25.0\nprofile = {kind = "sawtooth", rt = 1.0, sw = 2.0, sr = 0.0}\n'
        '[sweep]\nseed = [1]\n')
    names = {"saw": saw, "mine": tmp / "mine.txt", "busy": tmp / "busy", "card": tmp / "card.toml",
             "case": tmp / "case.toml", "c3d": tmp / "card3d_in_2d.toml", "nothing": tmp / "nothing",
             "profile": PROFILE, "quick": QUICK, "card2d": CARD_2D, "record": RECORD}
    return {k: str(v) for k, v in names.items()}


# (what is refused, the command's words, the API's call, words both messages hold); {name} is a file of `at`
CASES = [
    # the answer: tan φ, friction and grain size as the criterion takes them
    ("tan φ in degrees", ["predict", "{profile}", *FIT, "--tan-phi", "36"],
     lambda at: api.predict(at["profile"], **STUDY, tan_phi=36), "an angle in degrees"),
    ("tan φ zero", ["predict", "{profile}", *FIT, "--tan-phi", "0"],
     lambda at: api.predict(at["profile"], **STUDY, tan_phi=0.0), "must be a tangent > 0"),
    ("tan φ negative", ["predict", "{profile}", *FIT, "--tan-phi", "-0.5"],
     lambda at: api.predict(at["profile"], **STUDY, tan_phi=-0.5), "must be a tangent > 0"),
    ("friction in degrees", ["predict", "{profile}", "--fit", "study", "--d50", "0.7", "--friction", "30"],
     lambda at: api.predict(at["profile"], fit="study", d50=0.7e-3, friction=30.0), "an angle in degrees"),
    ("no friction", ["predict", "{profile}", "--fit", "study", "--d50", "0.7"],
     lambda at: api.predict(at["profile"], fit="study", d50=0.7e-3), "friction once"),
    ("negative d50 for predict", ["predict", "{profile}", "--fit", "study", "--d50", "-1", "--friction", "0.2"],
     lambda at: api.predict(at["profile"], fit="study", d50=-1e-3, friction=0.2), "positive diameter"),
    ("no d50 for a fit", ["predict", "{profile}", "--fit", "study", "--friction", "0.2"],
     lambda at: api.predict(at["profile"], fit="study", friction=0.2), "no grain size"),
    ("a lab record as the card", ["predict", "{profile}", "--friction", "0.2", "--soil", "{record}"],
     lambda at: api.predict(at["profile"], friction=0.2, soil=at["record"]), "a laboratory record, not a soil card"),
    # the DEM instead: its card, seeds and stress
    ("simulate without a card", ["predict", "{saw}", "--friction", "0.2", "--simulate"],
     lambda at: api.predict_dem(at["saw"], 0.2), "--soil CARD"),
    ("simulate with two seeds", ["predict", "{saw}", "--friction", "0.2", "--simulate", "--soil", "{card2d}",
                                 "--seeds", "2"],
     lambda at: api.predict_dem(at["saw"], 0.2, at["card2d"], seeds=2), "must be ≥ 3"),
    ("simulate at a negative stress", ["predict", "{saw}", "--friction", "0.2", "--simulate", "--soil", "{card2d}",
                                       "--normal-stress", "-100e3"],
     lambda at: api.predict_dem(at["saw"], 0.2, at["card2d"], normal_stress=-100e3), "must be > 0 Pa"),
    ("simulate with friction in degrees", ["predict", "{saw}", "--friction", "30", "--simulate", "--soil", "{card2d}"],
     lambda at: api.predict_dem(at["saw"], 30.0, at["card2d"]), "an angle in degrees"),
    ("simulate with another d50", ["predict", "{saw}", "--friction", "0.2", "--simulate", "--soil", "{card2d}",
                                   "--d50", "0.7"],
     lambda at: api.predict_dem(at["saw"], 0.2, at["card2d"], d50=0.7e-3), "not the card's D50"),
    ("simulate with a lab record", ["predict", "{saw}", "--friction", "0.2", "--simulate", "--soil", "{record}"],
     lambda at: api.predict_dem(at["saw"], 0.2, at["record"]), "a laboratory record, not a soil card"),
    # surfaces: grain size, cut-off, axis, the output file
    ("theta-a without d50", ["theta-a", "{profile}"], lambda at: api.theta_a(at["profile"], None), "no grain size given"),
    ("theta-a with d50 nan", ["theta-a", "{profile}", "--d50", "nan"],
     lambda at: api.theta_a(at["profile"], float("nan")), "positive diameter"),
    ("theta-a with a negative cut-off", ["theta-a", "{profile}", "--d50", "0.7", "--cutoff", "-1"],
     lambda at: api.theta_a(at["profile"], 0.7e-3, cutoff=-1e-3), "--cutoff"),
    ("theta-a along y of a line", ["theta-a", "{profile}", "--d50", "0.7", "--axis", "y"],
     lambda at: api.theta_a(at["profile"], 0.7e-3, axis="y"), "only the x axis"),
    ("profile over an existing file", ["profile", "sawtooth", "--rt", "1", "--sw", "2", "-o", "{mine}"],
     lambda at: api.make_profile("sawtooth", at["mine"], rt=1.0, sw=2.0), "exists; it is kept"),
    ("profile of negative length", ["profile", "sawtooth", "--rt", "1", "--sw", "2", "--length", "-5", "-o", "{nothing}"],
     lambda at: api.make_profile("sawtooth", at["nothing"], rt=1.0, sw=2.0, length=-5e-3), "--length"),
    ("profile of d50 zero", ["profile", "random", "--au", "1", "--ar", "2", "--rtmax", "1", "--seed", "3",
                             "--d50", "0", "-o", "{nothing}"],
     lambda at: api.make_profile("random", at["nothing"], d50=0.0, au=1.0, ar=2.0, rtmax=1.0, seed=3),
     "positive diameter"),
    ("plot over an existing file", ["profile", "plot", "{saw}", "-o", "{mine}"],
     lambda at: api.plot_profile(at["saw"], at["mine"]), "exists; it is kept"),
    # one case: its folder
    ("render into a folder a user owns", ["render", "{case}", "-o", "{busy}"],
     lambda at: api.render(at["case"], at["busy"]), "not empty"),
    ("run-case into a folder a user owns", ["run-case", "{case}", "-o", "{busy}"],
     lambda at: api.run_case(at["case"], at["busy"]), "not empty"),
    # campaigns: the 3D card in the quasi-2D device, runs folders, the report's folder and bootstrap
    ("a 3D card in a quasi-2D device", ["run", "{c3d}", "--dry-run"],
     lambda at: api.run(at["c3d"], dry_run=True, quiet=True), "calibrated in 3D"),
    ("status of no runs", ["status", "{quick}", "--runs", "{nothing}"],
     lambda at: api.status(at["quick"], runs=at["nothing"]), "does not exist"),
    ("stop of no runs", ["stop", "{quick}", "--runs", "{nothing}"],
     lambda at: api.stop(at["quick"], runs=at["nothing"]), "does not exist"),
    ("compare with nothing to compare", ["compare", "{quick}"], lambda at: api.compare(at["quick"]),
     "not both nor neither"),
    ("report into a folder a user owns", ["report", "{quick}", "-o", "{busy}"],
     lambda at: api.report(at["quick"], output=at["busy"]), "is not empty"),
    ("report with negative bootstrap", ["report", "{quick}", "--bootstrap", "-1"],
     lambda at: api.report(at["quick"], bootstrap=-1), "--bootstrap"),
    ("pack of no runs", ["pack", "{nothing}", "-o", "{nothing}"], lambda at: api.pack(at["nothing"], at["nothing"]),
     "no runs folder"),
    # soils: seeds, stresses, speeds, a lab record where a card is wanted
    ("element with no seed", ["element", "{card}", "--normal-stress", "1e5", "--seeds", "0"],
     lambda at: api.element(at["card"], 1e5, seeds=0), "--seeds"),
    ("element at a negative stress", ["element", "{card}", "--normal-stress", "-100e3"],
     lambda at: api.element(at["card"], -100e3), "must be > 0 Pa"),
    ("element at no stress", ["element", "{card}"], lambda at: api.element(at["card"], None), "no stress given"),
    ("element at a negative speed", ["element", "{card}", "--normal-stress", "1e5", "--shear-velocity", "-0.02"],
     lambda at: api.element(at["card"], 1e5, shear_velocity=-0.02), "must be > 0 m/s"),
    ("element of a lab record", ["element", "{record}", "--normal-stress", "1e5"],
     lambda at: api.element(at["record"], 1e5), "a laboratory record, not a soil card"),
    ("cell at a zero confining stress", ["element", "{card}", "--test", "triaxial", "--confining-stress", "0"],
     lambda at: api.cell(at["card"], 0.0, test="triaxial"), "--confining-stress"),
    ("cell with no seed", ["element", "{card}", "--test", "triaxial", "--confining-stress", "1e5", "--seeds", "0"],
     lambda at: api.cell(at["card"], 1e5, seeds=0, test="triaxial"), "--seeds"),
    ("records with no seed", ["element", "{card}", "--record", "{record}", "--seeds", "-1"],
     lambda at: api.records(at["card"], [at["record"]], seeds=-1), "--seeds"),
    ("density with no seed", ["density", "{card}", "--seeds", "0"], lambda at: api.density(at["card"], seeds=0),
     "--seeds"),
    ("density of a lab record", ["density", "{record}"], lambda at: api.density(at["record"]),
     "a laboratory record, not a soil card"),
    ("validate with no seed", ["validate", "{nothing}", "--seeds", "0"], lambda at: api.validate(at["nothing"], seeds=0),
     "--seeds"),
]


@pytest.mark.parametrize("what, argv, call, words", CASES, ids=[c[0] for c in CASES])
def test_the_command_and_the_api_refuse_alike(at, capsys, what, argv, call, words):
    before = sorted(p.name for p in Path(at["busy"]).parent.rglob("*"))
    assert main([a.format(**at) for a in argv]) == 2, what
    err = capsys.readouterr().err
    assert "Traceback" not in err
    with pytest.raises(InputError) as exc:
        call(at)
    assert words in str(exc.value), str(exc.value)
    assert f"error: {exc.value}" in err, err          # the command's message is the API's
    assert sorted(p.name for p in Path(at["busy"]).parent.rglob("*")) == before       # nothing written


def test_the_api_rejects_what_the_command_cannot_even_parse():
    """Types argparse would have refused reach the API from a script: refused too, not crashed on."""
    with pytest.raises(InputError, match="--seeds"):
        api.element(CARD_2D, 1e5, seeds=2.5)
    with pytest.raises(InputError, match="--normal-stress"):
        api.element(CARD_2D, "100e3")
    with pytest.raises(InputError, match="--d50"):
        api.theta_a(PROFILE, "0.7")
    with pytest.raises(InputError, match="takes rt, sw"):
        api.make_profile("sawtooth", "x.txt", rt=1.0)
