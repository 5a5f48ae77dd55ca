"""Campaign files: validation before anything runs (ten+ malformed files, exit 2, located messages),
the study's five groups, sweeps/zips/groups/pairs, and case ids stable across runs and machines."""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path

import pytest

from interphase.campaign.plan import plan, time_limit_minutes
from interphase.campaign.schema import load_campaign
from interphase.case import canonical_json
from interphase.cli import main
from interphase.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
BAD = ROOT / "tests" / "data" / "campaigns_bad"
CAMPAIGNS = ROOT / "campaigns"
FAKE_ID = "0123456789abcdef"   # a recipe id for pure plan tests


@functools.lru_cache(maxsize=None)
def _shipped(name: str):
    """A shipped campaign file, loaded once for the tests that only read it (group5.toml reads its
    instrument files and takes ~10 s). test_real_ids_are_stable_across_loads_and_working_directories
    loads afresh."""
    return load_campaign(CAMPAIGNS / name)

# file → (line the message must point at, key it must name)
BAD_FILES = {
    "syntax_error.toml": (6, "TOML syntax error"),
    "unknown_key.toml": (6, "frction_ps"),
    "wrong_type.toml": (6, "normal_stress"),
    "negative_size.toml": (9, "box_length_d50"),
    "empty_sweep.toml": (8, "friction_ps"),
    "missing_profile.toml": (8, "no-such-trace.csv"),
    "duplicate_case.toml": (8, "duplicate case"),
    "unknown_executor.toml": (5, "executor"),
    "zip_mismatch.toml": (8, "profile.au"),
    "unknown_engine.toml": (3, "engines"),
    "unknown_section.toml": (7, "sweeps"),
    "negative_jobs.toml": (5, "jobs"),
    "bad_profile_param.toml": (8, "height"),
    "bad_box_seeds.toml": (8, "pairs.seeds"),
    "bad_specimen_from.toml": (4, "specimen_from"),
    "start_in_case.toml": (7, "specimen_from"),
}


def test_every_bad_file_is_listed():
    assert sorted(p.name for p in BAD.glob("*.toml")) == sorted(BAD_FILES)


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_bad_campaign_gives_one_located_message_and_exit_2(name, capsys, tmp_path):
    line, key = BAD_FILES[name]
    rc = main(["run", str(BAD / name), "--output", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert rc == 2
    assert len(err.strip().splitlines()) == 1, err          # one message, no traceback
    assert f"{name}:{line}:" in err, err                    # file and line
    assert key in err, err                                  # the key (or what is wrong with it)
    assert not (tmp_path / "out").exists()                  # validated before anything ran


def test_allowed_values_and_did_you_mean_are_given():
    with pytest.raises(InputError, match=r"allowed: local, slurm"):
        load_campaign(BAD / "unknown_executor.toml")
    with pytest.raises(InputError, match=r"did you mean 'friction_ps'"):
        load_campaign(BAD / "unknown_key.toml")
    with pytest.raises(InputError, match=r"did you mean 'liggghts'"):
        load_campaign(BAD / "unknown_engine.toml")


# ---- the study's groups ---------------------------------------------------------------------
@pytest.mark.parametrize("group, variable, values", [
    (1, "rt", [0.1, 0.2, 0.5, 1, 1.2, 1.5, 2, 3, 5]),
    (2, "sr", [0.2, 0.5, 1, 2, 3, 5, 8, 10]),
    (3, "sw", [0.2, 0.5, 1, 2, 3, 4, 5, 10]),
])
def test_groups_1_to_3_reproduce_table_6_1(group, variable, values):
    c = load_campaign(CAMPAIGNS / f"group{group}.toml")
    inter = [x for x in c.cases if x.role == "interface"]
    assert len(inter) == len(values) * 3 * 2 * 3
    assert sorted({x.case.profile.param(variable) for x in inter}) == sorted(values)
    const = {"rt": 1.0, "sr": 0.0, "sw": 2.0}
    for x in inter:
        for p, v in const.items():
            if p != variable and not (group == 1 and p == "rt"):
                assert x.case.profile.param(p) == v
    assert {x.case.friction_ps for x in inter} == {0.05, 0.2, 0.5}
    assert {x.case.gradation.name for x in inter} == {"mono", "poly"}
    assert {(x.case.friction_pp, x.case.friction_pw, x.case.density, x.case.poisson) for x in inter} == \
        {(0.5, 0.9, 2650.0, 0.3)}
    # one box test per soil (gradation and packing seed), shared by every surface and friction
    boxes = [x for x in c.cases if x.role == "box"]
    assert len(boxes) == 2 * 3 and all(x.pair is not None and c.cases[x.pair].role == "box" for x in inter)


def test_group4_reproduces_table_6_2():
    c = load_campaign(CAMPAIGNS / "group4.toml")
    exp = {x.case.name: (x.case.profile.param("au"), x.case.profile.param("ar"), x.case.profile.param("rtmax"))
           for x in c.cases if x.role == "interface"}
    assert exp == {"A": (1, 1, 2), "B": (2, 1, 2), "C": (2, 0.5, 2), "D": (4, 2, 4), "E": (2, 0.25, 1),
                   "F": (4, 0.25, 2), "G": (4, 4, 4)}
    assert sum(x.role == "interface" for x in c.cases) == 7 * 3 * 2 * 3


def test_the_precision_campaigns_are_the_study_s_cases():
    """The precision campaigns (studies/sequential_seeds/, studies/reproduction/) resume from the
    committed study table (--restore): their cases on seeds 1-3 must be exactly the study's (same
    canonical inputs, so the same case ids), each group's."""
    def cases(c, groups=None):
        return {(x.group, canonical_json(x.case.canonical())) for x in c.cases
                if x.role == "interface" and x.case.seed <= 3 and (groups is None or x.group in groups)}

    study = _shipped("study.toml")
    whole = _shipped("../studies/reproduction/study_sequential.toml")
    assert cases(whole) == cases(study) and len(cases(study)) == 378
    g1 = _shipped("../studies/sequential_seeds/group1_sequential.toml")
    assert cases(g1) == cases(study, {"group1"}) and len(cases(g1)) == 81
    assert whole.seeds.max == g1.seeds.max == 24 and whole.seeds.halfwidth == g1.seeds.halfwidth == 0.1


def test_group_files_share_the_study_settings():
    # the settings docs/convergence.md chose are in campaigns/study.toml; the per-group files must
    # not drift from them (profiles, gradations and frictions are each file's own)
    own = {"profile", "gradation", "friction_ps", "name"}
    ref = next(x.case for x in _shipped("study.toml").cases if x.role == "interface")
    keep = {k: v for k, v in ref.canonical().items() if k not in own and k != "seed"}
    for g in range(1, 6):
        c = _shipped(f"group{g}.toml")
        for x in c.cases:
            if x.role == "interface":
                got = {k: v for k, v in x.case.canonical().items() if k in keep}
                assert got == keep, (g, {k: (got[k], keep[k]) for k in keep if got[k] != keep[k]})
        assert {x.case.seed for x in c.cases} == {1, 2, 3}


def test_group5_reads_profile_files_relative_to_the_campaign(tmp_path):
    c = _shipped("group5.toml")
    prof = next(x for x in c.cases if x.role == "interface").case.profile
    assert prof.kind == "file" and Path(prof.path) == (CAMPAIGNS / "profiles" / "frt-1.frt").resolve()
    assert prof.sha256 == hashlib.sha256((CAMPAIGNS / "profiles" / "frt-1.frt").read_bytes()).hexdigest()
    assert (prof.axis, prof.line, prof.direction) == ("x", "1/3", "+")


def test_groups_zip_and_pairs(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text("""
[campaign]
name = "mix"
[case]
profile = {kind = "sawtooth", rt = 1, sw = 2, sr = 0}
[sweep]
seed = [1, 2]
[[group]]
name = "tall"
[group.sweep]
profile.rt = [1, 2]
[[group]]
name = "flat"
[group.case]
profile = {kind = "flat"}
friction_ps = 0.05
[pairs]
case = {shear_distance = 0.004}
""")
    c = load_campaign(f, output=tmp_path / "o")
    assert [g.name for g in c.groups] == ["tall", "flat"]
    assert c.groups[0].variables == ("seed", "profile.rt")
    inter = [x for x in c.cases if x.role == "interface"]
    assert len(inter) == 2 * 2 + 2
    boxes = [x for x in c.cases if x.role == "box"]
    # one box test per distinct soil (here: per seed), with the override, walls at friction_pw
    assert sorted(b.case.seed for b in boxes) == [1, 2]
    assert all(b.case.shear_distance == 0.004 and b.case.friction_ps == b.case.friction_pw for b in boxes)
    for x in inter:
        assert c.cases[x.pair].case.seed == x.case.seed
    assert c.output == tmp_path / "o"

    # [pairs] seeds: every soil's box test on further seeds too (the paired ones not repeated),
    # the interface cases and their pairing unchanged
    f.write_text(f.read_text().replace("case = {shear_distance = 0.004}",
                                       "case = {shear_distance = 0.004}\nseeds = [2, 3, 4]"))
    more = load_campaign(f, output=tmp_path / "o")
    boxes = [x for x in more.cases if x.role == "box"]
    assert sorted(b.case.seed for b in boxes) == [1, 2, 3, 4]
    assert all(b.case.shear_distance == 0.004 for b in boxes)
    assert [x.case for x in more.cases if x.role == "interface"] == [x.case for x in inter]
    assert [more.cases[x.pair].case for x in more.cases if x.role == "interface"] == [c.cases[x.pair].case for x in inter]


# ---- case ids -------------------------------------------------------------------------------
GOLDEN_TOML = """
[campaign]
name = "golden"
[case]
test = "interface"
profile = {kind = "sawtooth", rt = 1, sw = 2, sr = 0}
d50 = 0.0007
gradation = "poly"
friction_pp = 0.5
friction_ps = 0.5
friction_pw = 0.9
rolling_friction = 0.1
density = 2650.0
shear_modulus = 1e9
poisson = 0.3
restitution = 0.5
normal_stress = 100e3
shear_velocity = 0.05
shear_distance = 0.003
snapshot_every = 0.00025
box_length_d50 = 40
box_height_d50 = 20
seed = 1
[pairs]
box = false
"""
GOLDEN_JSON = ('{"box_height_d50":20.0,"box_length_d50":40.0,"d50":0.0007,"density":2650.0,"device":"walled",'
               '"friction_pp":0.5,"friction_ps":0.5,"friction_pw":0.9,"friction_side":0.0,"gradation":"poly",'
               '"n_grains":null,"normal_stress":100000.0,"poisson":0.3,'
               '"profile":{"kind":"sawtooth","params":{"rt":1.0,"sr":0.0,"sw":2.0}},"restitution":0.5,'
               '"rolling_friction":0.1,"seed":1,"shear_distance":0.003,"shear_modulus":1000000000.0,'
               '"shear_velocity":0.05,"snapshot_every":0.00025,"test":"interface"}')
GOLDEN_ID = "d8f8e0a0bc51"


def test_case_id_is_golden_and_follows_the_recipe(tmp_path):
    f = tmp_path / "golden.toml"
    f.write_text(GOLDEN_TOML)
    c = load_campaign(f)
    (case,) = [x.case for x in c.cases]
    # the id is the hash of these exact bytes: the same on every machine
    assert canonical_json(case.canonical()) == GOLDEN_JSON
    payload = canonical_json({"case": case.canonical(), "engine": "liggghts", "recipe": FAKE_ID})
    assert hashlib.sha256(payload.encode()).hexdigest()[:12] == GOLDEN_ID
    (p,) = plan(c, identity=lambda name: FAKE_ID)
    assert p.case_id == GOLDEN_ID
    # a new recipe gives new ids (new folders; old results kept)
    assert plan(c, identity=lambda name: "fedcba9876543210")[0].case_id != GOLDEN_ID
    # and so does any physical input; a label does not
    f.write_text(GOLDEN_TOML.replace("seed = 1", "seed = 2"))
    assert plan(load_campaign(f), identity=lambda name: FAKE_ID)[0].case_id != GOLDEN_ID
    f.write_text(GOLDEN_TOML.replace("seed = 1", "seed = 1\nname = \"a label\""))
    assert plan(load_campaign(f), identity=lambda name: FAKE_ID)[0].case_id == GOLDEN_ID


def test_real_ids_are_stable_across_loads_and_working_directories(tmp_path, monkeypatch):
    first = [p.case_id for p in plan(load_campaign(CAMPAIGNS / "group1.toml"))]
    monkeypatch.chdir(tmp_path)
    again = [p.case_id for p in plan(load_campaign(CAMPAIGNS / "group1.toml"))]
    assert first == again and len(set(first)) == len(first) == 168


def test_time_limits_grow_with_case_size():
    c = load_campaign(CAMPAIGNS / "group1.toml")
    small = c.cases[0].case.replace(box_length_d50=12.0, box_height_d50=5.0, shear_distance=0.001)
    assert time_limit_minutes(small) < time_limit_minutes(c.cases[0].case)
    assert time_limit_minutes(c.cases[0].case, fixed=7.5) == 8


def test_a_box_case_is_one_test_however_declared():
    # the box has no rough surface: declared with a surface friction it is still the paired box
    from interphase.case import Case, case_id

    plain = Case(test="box", friction_pw=0.9)
    declared = Case(test="box", friction_ps=0.2, friction_pw=0.9)
    assert declared.friction_ps == 0.9 and declared.label() == plain.label() and "mu0.9" in plain.label()
    assert case_id(declared, "liggghts", "r") == case_id(plain, "liggghts", "r")


SAME_SPECIMEN = """\
[campaign]
name = "xc"
engines = ["yade", "liggghts"]
specimen_from = "liggghts"

[case]
test = "interface"
device = "periodic"
profile = {kind = "flat"}
n_grains = 60
box_length_d50 = 12.0

[sweep]
seed = [1, 2]

[pairs]
box = false
"""


def test_specimen_from_starts_the_other_engine_from_the_source_run(tmp_path, capsys):
    """With specimen_from, every YADE case starts from the LIGGGHTS run of the same case: its id hashes
    that run's id (known before anything runs), the LIGGGHTS ids are those of a campaign without it,
    the LIGGGHTS cases come first, and a dry run lists a YADE case whose specimen is not made yet
    without rendering it."""
    f = tmp_path / "xc.toml"
    f.write_text(SAME_SPECIMEN)
    c = load_campaign(f, output=tmp_path / "out")
    assert c.specimen_from == "liggghts"
    planned = plan(c, identity=lambda name: FAKE_ID + name)
    assert [p.engine for p in planned] == ["liggghts"] * 2 + ["yade"] * 2
    lig = {p.label: p for p in planned if p.engine == "liggghts"}
    f.write_text(SAME_SPECIMEN.replace('specimen_from = "liggghts"\n', ""))
    plain = plan(load_campaign(f, output=tmp_path / "out"), identity=lambda name: FAKE_ID + name)
    assert {p.case_id for p in plain if p.engine == "liggghts"} == {p.case_id for p in lig.values()}
    own = {p.label: p.case_id for p in plain if p.engine == "yade"}
    for p in planned:
        if p.engine == "yade":
            src = lig[p.label]
            assert p.case.start.case_id == src.case_id and p.case.start.engine == "liggghts"
            assert p.case.start.folder == str(tmp_path / "out" / src.case_id)
            assert p.case_id != own[p.label] and p.params["start"] == f"liggghts:{src.case_id}"
            assert p.case.replace(start=None) == src.case          # the same physical case
    f.write_text(SAME_SPECIMEN)
    assert main(["run", str(f), "--runs", str(tmp_path / "out"), "--dry-run", "--render"]) == 0
    out = capsys.readouterr().out
    assert out.count("starts from liggghts:") == 2 and out.count("  run  ") == 4
    # the two liggghts runs are rendered, the two that start from them are not (their specimen is not made)
    assert len(list((tmp_path / "out" / ".dry-run").glob("*/in.deck"))) == 2


def test_an_element_cell_is_estimated_by_its_own_steps():
    """A cell case's estimate counts the cell's steps (consolidation, chunks, settle, axial compression at
    the cell's time step) over its grains, not an interface deck's shear: a density map's token
    compression (0.2 %) costs a fraction of the full triaxial (40 %), and twice the grains about twice."""
    import tomllib

    from interphase.campaign.plan import estimate_seconds
    from interphase.case import case_from_dict

    soil = tomllib.loads((CAMPAIGNS.parent / "soils" / "karlsruhe-fine-sand.toml").read_text())["soil"]
    base = dict(test="triaxial", device="periodic3d", n_grains=1000, normal_stress=100e3, strain_rate=10.0,
                axial_strain=0.4, **{k: soil[k] for k in ("d50", "density", "shear_modulus", "friction_pp",
                                                          "rolling_friction", "gradation")})
    full = estimate_seconds(case_from_dict(base, where="test"))
    token = estimate_seconds(case_from_dict(base | {"axial_strain": 0.002}, where="test"))
    double = estimate_seconds(case_from_dict(base | {"n_grains": 2000}, where="test"))
    assert token < full / 3 and 1.7 < double / full < 2.3
    assert 30 < token < 300          # 1000 grains at G 500 MPa: 66–182 s each measured, two processes a core
