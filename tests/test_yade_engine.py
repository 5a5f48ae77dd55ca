"""Real YADE runs on tiny quasi-2D cases (200 grains, soft G), the same cases and physics checks as
tests/test_liggghts.py, plus YADE-specific output checks. 1 mm of shear with a contact snapshot every
0.25 mm (LIGGGHTS's tests: 2 mm, every 0.5 mm): YADE's shear costs ~6.5 s per mm of these cases on the
busy 2 cores, and what the checks read is there by 1 mm (measured 2026-11-23 on 2 mm runs: the flats
slide at μs from 0.1 mm; the peaks — saw-tooth 0.53 against the flat's 0.33, box 0.53 at 0.74 mm — and
the 0.5–1 mm means are as far from their bounds as over 2 mm)."""

from __future__ import annotations

import functools
import json

import numpy as np
import pandas as pd
import pytest

from interphase.engines.base import EngineError, EngineProfile, get_engine
from interphase.engines.yade import Yade, classify, contact_parameters
from interphase.material import Gradation
from interphase.tables import CONTACT_COLUMNS, HISTORY_COLUMNS, PARTICLE_COLUMNS
from tests.conftest import need_binary
from tests.engine_runs import TINY_GRAINS, cached_runner, tiny_case
from tests.reader_contract import ReaderContract

pytestmark = pytest.mark.yade

TINY = TINY_GRAINS | dict(shear_distance=1e-3, snapshot_every=0.25e-3)
SAW = ("sawtooth", dict(rt=1.0, sw=2.0, sr=0.0))
tiny = functools.partial(tiny_case, TINY)


@pytest.fixture(scope="session")
def yade_engine():
    need_binary("yade")
    return Yade()


@pytest.fixture(scope="session")
def yrun(yade_engine, tmp_path_factory):
    return cached_runner(yade_engine, tmp_path_factory, "yade")


def ratio(history) -> pd.Series:
    return history.surface_fx / -history.surface_fz


def steady_ratio(history, start=0.5e-3):
    """Mean surface stress ratio ΣFx/Σ(−Fz) over shear displacement ≥ start [m]."""
    return float(ratio(history[history.shear_disp >= start]).mean())


def peak_ratio(history, window=9):
    return float(ratio(history).rolling(window, center=True).mean().max())


def test_flat_surface_ratio_equals_particle_surface_friction(yrun):
    # μs 0 carries no tangential force from the first step of the shear (0.000 in every 0.25 mm of
    # 1 mm): half the shear suffices, its second half read
    for mu, shear in ((0.0, 0.5e-3), (0.2, TINY["shear_distance"])):
        _, res = yrun(tiny(friction_ps=mu, shear_distance=shear))
        assert steady_ratio(res.history, shear / 2) == pytest.approx(mu, abs=0.05 if mu else 0.01)


def test_grains_roll_on_a_flat_without_rolling_resistance(yrun):
    """μr = 0: bottom grains may roll, so a rough flat (μs = 0.5) mobilises less than μs. With the
    former mapping (eta = 0, krot > 0: YADE's rolling spring then has no cap) every grain slid and
    the ratio was exactly 0.500 for the whole shear. Half a millimetre of shear, its second half read:
    0.25 there (0.11 over 0.5–1 mm of a 1 mm run), far below the 0.500 of grains that all slide."""
    _, res = yrun(tiny(friction_ps=0.5, rolling_friction=0.0, shear_distance=0.5e-3))
    assert steady_ratio(res.history, 0.25e-3) < 0.45


def test_sawtooth_is_clearly_stronger_than_flat(yrun):
    _, flat = yrun(tiny(friction_ps=0.5))
    _, saw = yrun(tiny(profile=SAW, friction_ps=0.5))
    assert peak_ratio(saw.history) > peak_ratio(flat.history) + 0.15
    # and over the whole shear, not only at a spike
    assert steady_ratio(saw.history, 0.5e-3) > steady_ratio(flat.history, 0.5e-3)


def test_box_peak_in_range(yrun):
    _, box = yrun(tiny(test="box", friction_ps=0.5))
    assert 0.4 <= peak_ratio(box.history) <= 0.9


def test_platen_holds_the_normal_force(yrun):
    case = tiny(friction_ps=0.2)
    _, res = yrun(case)
    target = case.normal_stress * case.box_length * case.thickness
    np.testing.assert_allclose(res.history.normal_force.median(), target, rtol=0.02)
    assert (res.history.normal_force.between(0.8 * target, 1.2 * target)).mean() > 0.95


@pytest.mark.parametrize("profile", [("flat", {}), SAW], ids=["flat", "sawtooth"])
def test_summed_surface_contacts_equal_the_surface_force(yrun, profile):
    """Σ contact forces of each snapshot = the force YADE reports on the surface facets (O.forces),
    both components, to 1e−3: YADE's contact force is exactly what it applied (no damping term is
    added at sliding contacts)."""
    _, res = yrun(tiny(profile=profile, friction_ps=0.2 if profile[0] == "flat" else 0.5))
    c, h = res.contacts, res.history
    ps = c[c.kind == "ps"].groupby("time")[["fx", "fz"]].sum()
    assert len(ps) == 5
    for t, row in ps.iterrows():
        hr = h.iloc[int(np.argmin(np.abs(h.time.to_numpy() - t)))]
        assert hr.time == pytest.approx(t, abs=1e-12)
        assert -row.fz == pytest.approx(hr.surface_fz, rel=1e-3)
        assert -row.fx == pytest.approx(hr.surface_fx, rel=1e-3, abs=1e-3 * abs(hr.surface_fz))
    # the measuring window: the 'ps' contacts of grains centred in Case.window = window_fx/fz
    case = tiny(profile=profile)
    x0, x1 = case.window
    win = c[(c.kind == "ps") & (c.x2 > x0) & (c.x2 < x1)].groupby("time")[["fx", "fz"]].sum()
    for t, row in win.iterrows():
        hr = h.iloc[int(np.argmin(np.abs(h.time.to_numpy() - t)))]
        assert -row.fz == pytest.approx(hr.window_fz, rel=1e-3)
        assert -row.fx == pytest.approx(hr.window_fx, rel=1e-3, abs=1e-3 * abs(hr.window_fz))


def test_each_grain_surface_contact_counted_once(yrun):
    """A grain on a convex saw-tooth vertex touches two facets at the same point in YADE; the
    reader merges them: no (snapshot, grain, point) appears twice, and the raw file did have some."""
    folder, res = yrun(tiny(profile=SAW, friction_ps=0.5))
    ps = res.contacts[res.contacts.kind == "ps"]
    assert not ps.duplicated(["snapshot", "id2", "cx", "cz"]).any()
    raw = pd.read_csv(folder / "contacts.csv")
    lo, hi = json.loads((folder / "bodies.json").read_text())["walls"][0]
    raw_ps = raw[raw.b1.between(lo, hi)]
    point = raw_ps.assign(qx=(raw_ps.cx / 1e-10).round(), qz=(raw_ps.cz / 1e-10).round())   # same point to 0.1 nm
    doubled = point.duplicated(["step", "b2", "qx", "qz"]).sum()
    assert doubled > 0                                   # the saw-tooth does produce vertex contacts
    assert len(ps) == len(raw_ps) - doubled


def test_tables_follow_the_contract(yrun):
    _, res = yrun(tiny(friction_ps=0.2))
    assert tuple(res.contacts.columns) == CONTACT_COLUMNS
    assert tuple(res.history.columns) == HISTORY_COLUMNS
    assert tuple(res.particles.columns) == PARTICLE_COLUMNS
    c = res.contacts
    assert c.snapshot.nunique() == 5                     # 1 mm / 0.25 mm + the start of shear
    assert sorted(res.particles.id.unique()) == list(range(1, 201))
    pw = c[c.kind == "pw"]
    assert set(pw.id1.unique()) <= {-2, -3}              # sides = −2, platen = −3 (LIGGGHTS mesh order)
    # wall contacts: branch from the contact point to the grain centre is along n
    w = c[c.kind != "pp"]
    branch = np.column_stack([w.x2 - w.x1, w.z2 - w.z1])
    np.testing.assert_allclose(np.einsum("ij,ij->i", branch, np.column_stack([w.nx, w.nz])),
                               np.hypot(*branch.T), rtol=1e-6)


class TestYadeReader(ReaderContract):
    @pytest.fixture
    def finished(self, yrun):           # `yrun` caches per session: the case runs once
        return yrun(tiny(friction_ps=0.2))


def test_parquet_files_written(yrun, tmp_path):
    from interphase.io.yade import write_parquet

    folder, res = yrun(tiny(friction_ps=0.2))
    paths = write_parquet(folder, res)
    back = pd.read_parquet(paths["history"])
    pd.testing.assert_frame_equal(back, res.history)


def test_render_is_data_and_the_script_carries_no_values(yade_engine):
    a, b = yade_engine.render(tiny(friction_ps=0.2)), yade_engine.render(tiny(friction_ps=0.5, seed=7))
    assert set(a) == {"driver.py", "params.json", "recipe.json"}
    assert a["driver.py"] == b["driver.py"]              # values live only in params.json
    assert a["params.json"] != b["params.json"]
    p = json.loads(a["params.json"])
    assert p["material"]["mu_ps"] == 0.2 and len(p["grains"]["x"]) == 200
    compile(a["driver.py"], "driver.py", "exec")
    box = yade_engine.render(tiny(test="box"))
    assert box["driver.py"] != a["driver.py"] and "direct shear box" in box["driver.py"]


def test_contact_parameters_mapping():
    """E = 2G(1+ν); betan = √(5/6)·|ln e|/√(ln²e+π²) (LIGGGHTS' dashpot); eta = μr/2."""
    c = tiny(restitution=0.5, rolling_friction=0.1)
    p = contact_parameters(c)
    assert p["E"] == pytest.approx(2 * 50e6 * 1.3)
    assert p["betan"] == pytest.approx(np.sqrt(5 / 6) * 0.2155, abs=2e-4)
    assert p["eta"] == pytest.approx(0.05) and p["krot"] > 0
    assert contact_parameters(tiny(restitution=1.0))["betan"] == 0.0


def test_facet_contacts_get_the_liggghts_wall_stiffness():
    """YADE's facet–sphere Hertz coefficient 4/3·E*·√R* with R* = (2r·r)/(3r) (facet refR1 = 2r)
    and the stiffened wall equals LIGGGHTS' wall contact 4/3·E/(2(1−ν²))·√r."""
    c = tiny()
    p = contact_parameters(c)
    r, nu = 0.35e-3, p["nu"]
    e_star = 1.0 / ((1 - nu ** 2) / p["E"] + (1 - nu ** 2) / p["E_wall"])
    yade = 4 / 3 * e_star * np.sqrt(2 * r * r / (3 * r))
    liggghts = 4 / 3 * p["E"] / (2 * (1 - nu ** 2)) * np.sqrt(r)
    assert yade == pytest.approx(liggghts, rel=1e-12)


def test_python_error_is_an_engine_error_with_its_last_line(yade_engine, tmp_path):
    yade_engine.write_input(tiny(), tmp_path)
    p = json.loads((tmp_path / "params.json").read_text())
    del p["material"]
    (tmp_path / "params.json").write_text(json.dumps(p))
    with pytest.raises(EngineError) as err:
        yade_engine.execute(tmp_path)
    assert err.value.cause == "engine_error"
    assert "KeyError" in str(err.value).splitlines()[0] and "material" in str(err.value).splitlines()[0]
    assert "Traceback" in err.value.log_tail


def test_lost_grains_are_an_engine_error(yade_engine, tmp_path):
    """No surface under the soil: grains fall out of the domain during consolidation."""
    yade_engine.write_input(tiny(shear_distance=0.5e-3, snapshot_every=0.5e-3), tmp_path)
    p = json.loads((tmp_path / "params.json").read_text())
    p["walls"][0]["triangles"] = [[-1.0, 0.0, -1.0, -0.999, 0.0, -1.0, -0.9995, 0.0006, -1.0]]
    (tmp_path / "params.json").write_text(json.dumps(p))
    with pytest.raises(EngineError) as err:
        yade_engine.execute(tmp_path)
    assert err.value.cause == "lost_atoms"


def test_platen_that_never_settles_is_an_engine_error_and_shear_is_skipped(yade_engine, tmp_path):
    """As in LIGGGHTS: consolidation out of chunks with the platen force outside its band (here a
    band no force can be in, and one chunk) is a `not_consolidated` failure naming the force, and
    the shear never ran. No force is ever in that band, so the consolidation and its chunk are cut to
    200 steps each: the same verdict without the ~20 000 steps of a real consolidation."""
    yade_engine.write_input(tiny(shear_distance=0.5e-3, snapshot_every=0.5e-3), tmp_path)
    p = json.loads((tmp_path / "params.json").read_text())
    p["platen_force_lo"], p["platen_force_hi"], p["steps"]["n_chunks_max"] = 1e9, -1e9, 1
    assert p["steps"]["n_consolidate"] > 200 and p["steps"]["n_chunk"] > 200
    p["steps"]["n_consolidate"] = p["steps"]["n_chunk"] = 200
    (tmp_path / "params.json").write_text(json.dumps(p))
    with pytest.raises(EngineError) as err:
        yade_engine.execute(tmp_path)
    assert err.value.cause == "not_consolidated"
    assert str(err.value).startswith("[not_consolidated] NOT CONSOLIDATED: platen force ")
    assert not (tmp_path / "shear_start.txt").exists()
    assert len((tmp_path / "history.csv").read_text().splitlines()) <= 1    # no row (at most the header)


def test_well_graded_soil_consolidates_before_shear(yrun):
    """Well-graded grains settle far below the platen's start (lattice at d_max): the shear waits
    for the platen to reach its target (it once started at the first check before the loop, and the
    platen never touched the soil: NaN strength); the clock starts where the shear did. A 12 × 8 D50
    cell of 100 grains and 0.5 mm of shear (the claim is the consolidation; measured 2026-11-23 on the
    busy 2 cores: 32 s). With LIGGGHTS' platen law (YADE recipe 3) the platen settles within the first
    stretch; with YADE's former 0.1 m/s it took 6 chunks."""
    case = tiny(profile=SAW, friction_ps=0.5, gradation=Gradation("poly"), n_grains=100, box_length_d50=12,
                box_height_d50=8, shear_distance=0.5e-3)
    folder, res = yrun(case)
    p = json.loads((folder / "params.json").read_text())
    start = int((folder / "shear_start.txt").read_text())
    assert start >= p["steps"]["n_consolidate"]
    assert (start - p["steps"]["n_consolidate"]) % p["steps"]["n_chunk"] == 0
    target = case.normal_stress * case.box_length * case.thickness
    # the platen bears on the soil from the first row of the shear, and holds σ through it
    assert abs(res.history.normal_force.iloc[0] - target) < 0.05 * target
    assert abs(res.history.normal_force.mean() - target) < 0.1 * target
    assert res.history.shear_disp.iloc[0] == 0.0


def test_timeout_is_classified(tmp_path):
    need_binary("yade")
    eng = Yade(profile=EngineProfile(binary="yade", timeout=2.0))
    eng.write_input(tiny(), tmp_path)
    with pytest.raises(EngineError) as err:
        eng.execute(tmp_path)
    assert err.value.cause == "timeout"


def test_classify_and_profile(monkeypatch):
    assert classify(0, "Running script driver.py\ninterphase: finished 10 steps") == (None, "")
    assert classify(0, "Running script driver.py")[0] == "engine_error"        # ended early
    assert classify(-9, "Running script")[0] == "killed"
    tb = "Traceback (most recent call last):\n  File \"driver.py\", line 3\nValueError: bad facet vertices\n"
    assert classify(1, tb) == ("bad_mesh", "ValueError: bad facet vertices")
    monkeypatch.setenv("INTERPHASE_YADE_THREADS", "2")
    monkeypatch.setenv("INTERPHASE_YADE_BINARY", "/opt/yade/bin/yade")
    eng = get_engine("yade")
    assert eng.profile.threads == 2 and "-j" in eng.command()
    monkeypatch.setenv("INTERPHASE_YADE_THREADS", "two")
    from interphase.errors import InputError
    with pytest.raises(InputError, match="INTERPHASE_YADE_THREADS"):
        Yade.default_profile()


def test_version_from_the_binary(yade_engine):
    assert yade_engine.version().startswith("YADE 20")


def test_facet_contacts_carry_the_liggghts_wall_rolling_law(yrun):
    """Grain–facet contacts get epsd2's wall rolling stiffness kt(R* = r)·r² and cap μr·r·Fn, set
    per interaction by the driver (the Ip2 functor's single krot/eta fit grain pairs): at the end of a
    real run every facet contact older than the 10-step update period holds them."""
    folder, _ = yrun(tiny(profile=SAW, friction_ps=0.5))
    rolling = json.loads((folder / "rolling.json").read_text())
    p = contact_parameters(tiny(profile=SAW, friction_ps=0.5))
    assert rolling["kr_wall"] == pytest.approx(p["krot_wall"]) and p["krot_wall"] > 4 * p["krot"]
    assert rolling["facet_contacts"] > 10
    assert rolling["matched"] >= 0.9 * rolling["facet_contacts"]


# ---- the periodic device (engines/device.py `_periodic`), as tests/test_liggghts.py's periodic tests;
# 1 mm of shear, as the walled cases: the flat at μs 0.2 reads 0.195-0.200 over 0.5-1 mm, and the
# surface and the bed travel 1 mm, more than a grain's diameter, past x = L, so what wraps has to wrap
PERIODIC = dict(device="periodic", friction_ps=0.5, shear_distance=1e-3)


def crossing(folder) -> int:
    """Raw contacts.csv rows whose bodies sit on opposite sides of the x boundary (x written in
    [0, L); a wall contact's body 1 is its contact point)."""
    raw = pd.read_csv(folder / "contacts.csv")
    first_wall = min(w[0] for w in json.loads((folder / "bodies.json").read_text())["walls"])   # after the grains
    x1 = np.where(raw.b1 >= first_wall, raw.cx, raw.x1)
    return int((np.abs(raw.x2 - x1) > 20 * 0.7e-3 / 2).sum())


def test_periodic_device_shears_without_walls(yrun):
    # x periodic: the surface force carries the platen's whole load, no grain is lost, the surface
    # wraps (grains near x = L still rest on its teeth), contacts across the boundary are unwrapped
    case = tiny(profile=SAW, **PERIODIC)
    folder, res = yrun(case)
    h = res.history[res.history.shear_disp > 0.2e-3]
    assert (-h.surface_fz / h.normal_force.abs()).mean() == pytest.approx(1.0, abs=0.03)
    assert h.normal_force.mean() == pytest.approx(case.normal_stress * case.box_length * case.thickness, rel=0.03)
    assert (h.window_fx == h.surface_fx).all() and (h.window_fz == h.surface_fz).all()     # no window
    last = res.particles[res.particles.snapshot == res.particles.snapshot.max()]
    assert len(last) == 200 and last.x.between(0, case.box_length).all()
    assert last[last.x > 18 * 0.7e-3].z.min() > 0.1e-3          # resting on teeth, not fallen through
    c = res.contacts
    assert crossing(folder) > 0                                   # some contacts do cross x = 0 / L
    assert (np.hypot(c.x2 - c.x1, c.z2 - c.z1) < 1.05e-3).all()  # no branch spans the box
    assert set(c[c.kind != "pp"].id1.unique()) <= {-1, -2}        # surface, platen: no side walls
    assert len(json.loads((folder / "bodies.json").read_text())["walls"]) == 2
    # a flat at μs 0.2 slides at μs, as between walls: from 0.1 mm on, so half a millimetre of shear,
    # its second half read (0.206 there; 0.198 over 0.5–1 mm of a 1 mm run)
    _, flat = yrun(tiny(**(PERIODIC | dict(friction_ps=0.2, shear_distance=0.5e-3))))
    assert steady_ratio(flat.history, 0.25e-3) == pytest.approx(0.2, abs=0.02)


def test_periodic_soil_bed_loads_its_surface(yrun):
    # the soil's own test in the periodic device: a frozen bed of its grains on a moving floor; the
    # bed and floor carry the platen's load and resist the shear like a rough surface
    case = tiny(test="box", **PERIODIC)
    folder, res = yrun(case)
    h = res.history[res.history.shear_disp > 0.2e-3]
    assert (-h.surface_fz / h.normal_force.abs()).mean() == pytest.approx(1.0, abs=0.03)
    assert 0.2 < (h.surface_fx / -h.surface_fz).mean() < 0.8
    # the bed rides with the floor: each bed grain moved −x by the shear travel (modulo L), no more
    bed = np.array(json.loads((folder / "params.json").read_text())["bed"]) + 1
    p = res.particles[res.particles.id.isin(bed)]
    first, last = (p[p.snapshot == k].set_index("id") for k in (0, p.snapshot.max()))
    travel = last.shear_disp.iloc[0]
    L = case.box_length
    moved = (last.x - first.x + travel + L / 2) % L - L / 2
    assert len(bed) > 5 and np.abs(moved).max() < 1e-9 and (last.z == first.z).all()
