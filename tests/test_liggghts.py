"""Real LIGGGHTS runs on tiny quasi-2D cases (200 grains, soft G, 2 mm of shear: ~2 s each)."""

from __future__ import annotations

import functools

import numpy as np
import pandas as pd
import pytest

from interphase.engines.base import EngineError
from interphase.engines.liggghts import Liggghts
from interphase.errors import InputError
from interphase.surface.spec import ProfileSpec
from interphase.tables import CONTACT_COLUMNS, HISTORY_COLUMNS, PARTICLE_COLUMNS
from tests.conftest import need_binary
from tests.engine_runs import TINY_GRAINS, cached_runner, tiny_case
from tests.reader_contract import ReaderContract

pytestmark = pytest.mark.liggghts

TINY = TINY_GRAINS | dict(shear_distance=2e-3, snapshot_every=0.5e-3)
tiny = functools.partial(tiny_case, TINY)


@pytest.fixture(scope="session")
def engine():
    need_binary("liggghts")
    return Liggghts()


@pytest.fixture(scope="session")
def run(engine, tmp_path_factory):
    return cached_runner(engine, tmp_path_factory, "lig")


def steady_ratio(history, start=1.0e-3):
    """Mean surface stress ratio ΣFx/Σ(−Fz) over shear displacement ≥ start [m]."""
    h = history[history.shear_disp >= start]
    return float((h.surface_fx / -h.surface_fz).mean())


def peak_ratio(history, window=9):
    r = (history.surface_fx / -history.surface_fz).rolling(window, center=True).mean()
    return float(r.max())


def test_flat_surface_ratio_equals_particle_surface_friction(run):
    for mu in (0.0, 0.2):
        _, res = run(tiny(friction_ps=mu))
        assert steady_ratio(res.history) == pytest.approx(mu, abs=0.05 if mu else 0.01)


def test_sawtooth_is_clearly_stronger_than_flat(run):
    _, flat = run(tiny(friction_ps=0.5))
    _, saw = run(tiny(profile=("sawtooth", dict(rt=1.0, sw=2.0, sr=0.0)), friction_ps=0.5))
    assert peak_ratio(saw.history) > peak_ratio(flat.history) + 0.15


def test_box_peak_in_range(run):
    _, box = run(tiny(test="box", friction_ps=0.5))
    assert 0.4 <= peak_ratio(box.history) <= 0.9


PERIODIC = dict(device="periodic", friction_ps=0.5)


def test_periodic_device_shears_without_walls(run):
    # x periodic: the surface force carries the platen's whole load, no grain is lost, the surface
    # wraps (grains near x = L still rest on it after 2 mm), contacts across the boundary are unwrapped
    saw = ("sawtooth", dict(rt=1.0, sw=2.0, sr=0.0))
    folder, res = run(tiny(profile=saw, **PERIODIC))
    h = res.history[res.history.shear_disp > 0.2e-3]
    assert (-h.surface_fz / h.normal_force.abs()).mean() == pytest.approx(1.0, abs=0.03)
    last = res.particles[res.particles.snapshot == res.particles.snapshot.max()]
    assert len(last) == 200 and last.x.between(0, 20 * 0.7e-3).all()
    assert last[last.x > 18 * 0.7e-3].z.min() > 0.1e-3          # resting on teeth, not fallen through
    c = res.contacts
    assert (np.hypot(c.x2 - c.x1, c.z2 - c.z1) < 1.05e-3).all()  # no branch spans the box
    assert not (folder / "sides.stl").exists() and not (folder / "balance.txt").exists()
    # a flat at μs 0.2 slides at μs, as between walls
    _, flat = run(tiny(**(PERIODIC | dict(friction_ps=0.2))))
    assert steady_ratio(flat.history) == pytest.approx(0.2, abs=0.02)


def test_periodic_soil_bed_loads_its_surface(run):
    # the soil's own test in the periodic device: a frozen bed of its grains on a moving floor; the
    # bed and floor carry the platen's load and resist the shear like a rough surface
    _, res = run(tiny(test="box", **PERIODIC))
    h = res.history[res.history.shear_disp > 0.2e-3]
    assert (-h.surface_fz / h.normal_force.abs()).mean() == pytest.approx(1.0, abs=0.03)
    assert 0.2 < (h.surface_fx / -h.surface_fz).mean() < 0.8


def test_tables_follow_the_contract(run):
    folder, res = run(tiny(friction_ps=0.2))
    assert tuple(res.contacts.columns) == CONTACT_COLUMNS
    assert tuple(res.history.columns) == HISTORY_COLUMNS
    assert tuple(res.particles.columns) == PARTICLE_COLUMNS
    c = res.contacts
    assert set(c.kind.unique()) <= {"pp", "ps", "pw"} and (c.kind == "ps").any() and (c.kind == "pp").any()
    np.testing.assert_allclose(np.hypot(c.nx, c.nz), 1.0, atol=1e-9)
    np.testing.assert_allclose(c.fn, c.fx * c.nx + c.fz * c.nz, atol=1e-12)
    np.testing.assert_allclose(c.ft, -c.fx * c.nz + c.fz * c.nx, atol=1e-12)
    ps = c[c.kind == "ps"]
    assert (ps.nz > 0.9).all()                 # flat surface: normals point up into the grains
    assert (ps.fn > 0).all()                   # compression positive
    assert c.snapshot.nunique() == 5           # 2 mm / 0.5 mm + the start of shear
    assert res.particles.id.nunique() == 200


class TestLiggghtsReader(ReaderContract):
    @pytest.fixture
    def finished(self, run):           # `run` caches per session: the case runs once
        return run(tiny(friction_ps=0.2))



def _copy_finished(run, tmp_path):
    import shutil
    folder, res = run(tiny(friction_ps=0.2))
    shutil.copytree(folder, tmp_path / "case")
    return tmp_path / "case", res


def test_truncated_dump_is_refused_with_the_file_named(engine, run, tmp_path):
    folder, _ = _copy_finished(run, tmp_path)
    dump = folder / "contacts_pair.dump"
    raw = dump.read_bytes()
    dump.write_bytes(raw[: len(raw) - 500])            # the engine died mid-write
    with pytest.raises(InputError, match="contacts_pair.dump") as err:
        engine.read_results(folder)
    assert "rerun" in err.value.fix


def test_block_with_other_columns_is_refused(engine, run, tmp_path):
    folder, _ = _copy_finished(run, tmp_path)
    dump = folder / "particles.dump"
    text = dump.read_text()
    last = text.rindex("ITEM: ATOMS id x z vx vz radius")
    dump.write_text(text[:last] + text[last:].replace("ITEM: ATOMS id x z vx vz radius", "ITEM: ATOMS id z x vx vz radius", 1))
    with pytest.raises(InputError, match="particles.dump"):
        engine.read_results(folder)


def test_dump_missing_a_column_is_refused_with_its_name(engine, run, tmp_path):
    folder, _ = _copy_finished(run, tmp_path)
    dump = folder / "contacts_wall.dump"
    dump.write_text(dump.read_text().replace("c_wc[20]", "c_wc[99]"))
    with pytest.raises(InputError, match=r"c_wc\[20\]") as err:
        engine.read_results(folder)
    assert err.value.where.endswith("contacts_wall.dump")


def test_irregular_whitespace_reads_the_same(engine, run, tmp_path):
    folder, res = _copy_finished(run, tmp_path)
    dump = folder / "contacts_wall.dump"
    lines = dump.read_text().splitlines(keepends=True)   # the bulk CSV pass refuses doubled spaces; loadtxt reads them
    dump.write_text("".join(ln if ln.startswith("ITEM") else ln.replace(" ", "  ") for ln in lines))
    again = engine.read_results(folder)
    pd.testing.assert_frame_equal(again.contacts, res.contacts)


def test_summed_surface_contacts_equal_mesh_force(run):
    """Normal (z) component on a flat surface, where every contact slides and no ridge doubles a
    contact: to 1e−3. (x is off by the tangential damping term that LIGGGHTS dumps but does not apply
    at sliding contacts, docs/engines.md; see docs/liggghts.md.)"""
    _, res = run(tiny(friction_ps=0.2))
    c, h = res.contacts, res.history
    ps = c[c.kind == "ps"].groupby("time")[["fx", "fz"]].sum()
    checked = 0
    for t, row in ps.iloc[1:].iterrows():      # the first snapshot is the shear's first step
        hr = h.iloc[int(np.argmin(np.abs(h.time.to_numpy() - t)))]
        assert hr.time == pytest.approx(t, abs=1e-12)
        assert -row.fz == pytest.approx(hr.surface_fz, rel=1e-3)
        checked += 1
    assert checked >= 3


def test_summed_sawtooth_contacts_equal_mesh_force_both_components(run):
    """On a 45° saw-tooth with no damping (e = 1) the dumped contact forces are the applied ones:
    summed particle–surface contacts equal the mesh force in x AND z to 1e−3 of the normal force.
    With damping they differ by the damping term the dump re-evaluates (docs/liggghts.md)."""
    _, res = run(tiny(profile=("sawtooth", dict(rt=1.0, sw=2.0, sr=0.0)), friction_ps=0.5, restitution=1.0,
                   seed=2))   # undamped: seed 1 flings a grain out of the open side (docs)
    c, h = res.contacts, res.history
    ps = c[c.kind == "ps"].groupby("time")[["fx", "fz"]].sum()
    checked = 0
    for t, row in ps.iterrows():
        hr = h.iloc[int(np.argmin(np.abs(h.time.to_numpy() - t)))]
        if abs(hr.time - t) > 1e-12:
            continue                      # the shear's first step has no history row (dropped)
        scale = abs(hr.surface_fz)
        assert abs(-row.fx - hr.surface_fx) < 1e-3 * scale
        assert abs(-row.fz - hr.surface_fz) < 1e-3 * scale
        checked += 1
    assert checked >= 3
    assert (c[c.kind == "ps"].nx < -0.5).any()     # faces, not a flat: the check covers inclined normals


def test_window_force_is_the_window_grains_surface_contacts(run):
    """History's window_fx/fz (the deck's per-grain wall-force sum over grains centred in
    Case.window) equals the summed 'ps' contacts of those grains at every snapshot, both components,
    to 1e−3 (undamped, as above), and differs from the whole-surface force where grains outside
    the window touch the surface."""
    case = tiny(profile=("sawtooth", dict(rt=1.0, sw=2.0, sr=0.0)), friction_ps=0.5, restitution=1.0, seed=2)
    _, res = run(case)
    c, h = res.contacts, res.history
    x0, x1 = case.window
    ps = c[c.kind == "ps"]
    win = ps[(ps.x2 > x0) & (ps.x2 < x1)].groupby("time")[["fx", "fz"]].sum()
    checked = outside = 0
    for t, row in win.iterrows():
        hr = h.iloc[int(np.argmin(np.abs(h.time.to_numpy() - t)))]
        if abs(hr.time - t) > 1e-12:
            continue
        scale = abs(hr.window_fz)
        assert abs(-row.fx - hr.window_fx) < 1e-3 * scale
        assert abs(-row.fz - hr.window_fz) < 1e-3 * scale
        outside += abs(hr.surface_fz - hr.window_fz) > 1e-3 * scale
        checked += 1
    assert checked >= 3 and outside == checked


def test_no_duplicated_surface_contacts(run):
    """One contact per grain and surface point: a ridge touched by a grain is one row (the engine
    applies every row it reports, so a duplicate doubles that force)."""
    _, res = run(tiny(profile=("sawtooth", dict(rt=1.0, sw=2.0, sr=0.0)), friction_ps=0.5))
    ps = res.contacts[res.contacts.kind == "ps"]
    assert not ps.duplicated(["snapshot", "id2", "cx", "cz"]).any()
    ridge = (ps.nx.abs() < 0.6) & (ps.nz < 0.99)    # neither a 45° face nor a flat: a ridge contact
    assert ridge.any()


def test_side_walls_clear_grains_trapped_in_valleys():
    from interphase.engines.device import wall_gap
    from interphase.surface.builder import from_spec
    d50, dmin, dmax = 0.7e-3, 0.665e-3, 0.735e-3
    flat = from_spec(ProfileSpec.make("flat"), d50, 20 * d50)
    saw = from_spec(ProfileSpec.make("sawtooth", rt=1.0, sw=2.0, sr=0.0), d50, 20 * d50)
    assert wall_gap(flat, dmin, dmax, d50) == pytest.approx(0.05 * dmin)
    # largest grain in a 45° valley of depth D50: top at r/sin45 + r − Rt above the peaks
    r = dmax / 2
    assert wall_gap(saw, dmin, dmax, d50) == pytest.approx(r * np.sqrt(2) + r - d50 + 0.05 * dmin, rel=1e-2)
    # well-graded grains (0.35–1.05 mm): the largest sticks out 0.57 mm, more than d_min/2 but less
    # than D50: the gap lets it pass (it jammed at the wall in most seeds when shut)
    pmin, pmax = 0.35e-3, 1.05e-3
    r = pmax / 2
    assert wall_gap(saw, pmin, pmax, d50) == pytest.approx(r * np.sqrt(2) + r - d50 + 0.05 * pmin, rel=1e-2)
    assert 0.5 * pmin < wall_gap(saw, pmin, pmax, d50) < d50
    # a shallow saw-tooth (Rt = 0.2 D50): grains ride on the peaks; a gap for the largest would let
    # median grains out, so the edge sits 0.05·d_min above the peaks
    shallow = from_spec(ProfileSpec.make("sawtooth", rt=0.2, sw=2.0, sr=0.0), d50, 20 * d50)
    assert wall_gap(shallow, pmin, pmax, d50) == pytest.approx(0.05 * pmin)


def test_platen_holds_the_normal_stress_during_shear(run):
    """Consolidation ends only when the platen carries σ·L·t; shear then runs at that stress."""
    case = tiny(friction_ps=0.2)
    _, res = run(case)
    target = case.normal_stress * case.box_length * case.thickness
    f = res.history.normal_force.to_numpy()
    assert abs(f.mean() - target) < 0.1 * target
    assert abs(f[0] - target) < 0.1 * target


def test_hostile_value_in_the_deck_is_refused(engine):
    """A name carrying a newline and a `shell` command, or a NaN, stops the real template."""
    from interphase.engines.device import device
    from interphase.engines.liggghts import deck_values
    from interphase.engines.render import environment
    p = deck_values(device(tiny()))
    tpl = environment(engine.templates).get_template("interface_shear.in.j2")
    assert "fix surf" in tpl.render(**p)
    with pytest.raises(InputError):
        tpl.render(**(p | {"moving": "surf\nshell rm -rf /"}))
    with pytest.raises(InputError):
        tpl.render(**(p | {"dt": float("nan")}))
    with pytest.raises(InputError):
        tpl.render(**(p | {"platen_force": "1\nshell rm -rf /"}))
    with pytest.raises(Exception):      # StrictUndefined: a missing value is an error, not ""
        tpl.render(**{k: v for k, v in p.items() if k != "dt"})


def test_timeout_is_an_engine_error(tmp_path):
    need_binary("liggghts")
    from dataclasses import replace
    eng = Liggghts()
    eng = Liggghts(profile=replace(eng.profile, timeout=0.3))
    eng.write_input(tiny(), tmp_path)
    with pytest.raises(EngineError) as err:
        eng.execute(tmp_path)
    assert err.value.cause == "timeout"


def test_classify_causes():
    from interphase.engines.liggghts import classify
    assert classify(0, "Loop time of 1 on 1 procs") is None
    assert classify(1, "ERROR: Lost atoms: original 200 current 199") == "lost_atoms"
    assert classify(-9, "") == "killed"
    assert classify(1, "ERROR: Unknown command: shell") == "engine_error"


def test_hostile_value_cannot_be_rendered(engine):
    with pytest.raises(InputError):
        ProfileSpec.make("sawtooth", rt="1\nshell rm -rf /", sw=2, sr=0)
    from interphase.engines.render import name, num
    with pytest.raises(InputError):
        name("surf\nshell rm -rf /")
    with pytest.raises(InputError):
        num("0.1\nshell rm -rf /")
    with pytest.raises(InputError):
        num(float("nan"))
    deck = engine.render(tiny())["in.deck"]
    assert "shell" not in deck


def test_lost_grain_is_an_engine_error(engine, tmp_path):
    """A surface mesh that does not lie under the soil: grains fall out of the domain."""
    engine.write_input(tiny(shear_distance=0.5e-3, snapshot_every=0.5e-3), tmp_path)
    far = "solid s\nfacet normal 0 0 1\n outer loop\n  vertex -0.0026 -0.0003 0\n  vertex -0.0025 -0.0003 0\n" \
          "  vertex -0.0025 0.0003 0\n endloop\nendfacet\nendsolid s\n"
    (tmp_path / "surface.stl").write_text(far)
    with pytest.raises(EngineError) as err:
        engine.execute(tmp_path)
    assert err.value.cause == "lost_atoms"
    assert "ERROR" in err.value.log_tail


def test_platen_that_never_settles_is_an_engine_error_and_shear_is_skipped(engine, tmp_path):
    """The consolidation loop runs out without the platen force in its band (here: a band no force
    can be in, and one chunk): the run is a `not_consolidated` failure naming the force, and the
    shear never ran (it would shear the soil under another stress)."""
    import re

    engine.write_input(tiny(shear_distance=0.5e-3, snapshot_every=0.5e-3), tmp_path)
    deck = (tmp_path / "in.deck").read_text()
    deck, n_loop = re.subn(r"variable kc loop \d+", "variable kc loop 1", deck)
    deck, n_band = re.subn(r'if "\$\{pfc\} > \S+ && \$\{pfc\} < \S+"', 'if "${pfc} > 1e9 && ${pfc} < -1e9"', deck)
    assert n_loop == n_band == 1
    (tmp_path / "in.deck").write_text(deck)
    with pytest.raises(EngineError) as err:
        engine.execute(tmp_path)
    assert err.value.cause == "not_consolidated"
    assert re.search(r"NOT CONSOLIDATED: platen force -?[0-9.e+-]+ N", str(err.value))
    assert "NOT CONSOLIDATED" in err.value.log_tail
    assert not (tmp_path / "contacts_pair.dump").exists() and not (tmp_path / "shear_start.txt").exists()


def test_unreadable_stl_is_an_engine_error(engine, tmp_path):
    engine.write_input(tiny(), tmp_path)
    (tmp_path / "surface.stl").write_text("solid broken\nfacet normal 0 0 1\n outer loop\n  vertex 0 0\n")
    with pytest.raises(EngineError) as err:
        engine.execute(tmp_path)
    assert err.value.cause in ("bad_mesh", "engine_error")
    assert "ERROR" in err.value.log_tail or err.value.returncode != 0


def test_render_is_data_and_deterministic(engine):
    a, b = engine.render(tiny()), engine.render(tiny())
    assert a == b
    assert set(a) >= {"in.deck", "grains.data", "surface.stl", "sides.stl", "platen.stl", "engine.json", "recipe.json"}
    assert "rolling_friction epsd2" in a["in.deck"] and "setforce NULL 0.0 NULL" in a["in.deck"]


def test_grains_leaving_under_a_side_wall_are_removed_not_lost(run):
    """Spaced saw-tooth (2 D50 of flat between teeth), μs = 0.2, seed 1: grains on the flats slide
    out under the left wall; before the side openings deleted them, one met the next tooth outside
    the box and was shot out of the domain (Lost atoms). Now the run finishes, the grains that left
    are counted in balance.txt, and none vanished otherwise."""
    case = tiny(profile=("sawtooth", dict(rt=1, sw=2, sr=2)), friction_ps=0.2, seed=1)
    folder, res = run(case)
    b = np.loadtxt(folder / "balance.txt", skiprows=1)
    assert b[-1, 2] >= 1
    assert (b[:, 1] + b[:, 2] >= case.n_grains).all()
    counts = res.particles.groupby("snapshot").size()
    assert counts.iloc[0] - counts.iloc[-1] <= b[-1, 2]


def test_grain_balance_names_a_leak(tmp_path):
    """check_grain_balance reads balance.txt: grains + removed < placed is a leak (the deck's
    `thermo_modify lost warn` would otherwise hide it)."""
    from interphase.engines.device import device
    from interphase.engines.liggghts import check_grain_balance

    (tmp_path / "recipe.json").write_text(device(tiny()).record("liggghts").to_json())   # 200 grains
    head = "step n_grains n_removed\n"
    (tmp_path / "balance.txt").write_text(head + "0 200 0\n100 200 1\n200 199 1\n")
    assert check_grain_balance(tmp_path) is None
    (tmp_path / "balance.txt").write_text(head + "0 200 0\n100 199 0\n200 197 1\n")
    assert "1 grain(s) left the domain by step 100" in check_grain_balance(tmp_path)


def test_dumps_without_blocks_read_as_empty_tables(engine, run, tmp_path):
    folder, _ = _copy_finished(run, tmp_path)
    for name in ("contacts_pair.dump", "contacts_wall.dump", "particles.dump"):
        (folder / name).write_text("")
    res = engine.read_results(folder)
    assert res.contacts.empty and list(res.contacts.columns) == list(CONTACT_COLUMNS)
    assert res.particles.empty and list(res.particles.columns) == list(PARTICLE_COLUMNS)


def test_a_finely_sampled_measured_line_shears_like_a_flat(run):
    """The shipped Dektak line (77 nm steps, 0.46 µm of relief) in the periodic device: meshed at
    surface.builder.mesh_step, LIGGGHTS takes it (at its own steps the mesh was refused, bad_mesh),
    and a surface this flat under 0.7 mm grains slides at μs like the flat."""
    from pathlib import Path

    from interphase.case import Case
    from interphase.surface.builder import file_spec

    dektak = Path(__file__).resolve().parents[1] / "campaigns" / "profiles" / "dektak-1.csv"
    case = Case(test="interface", profile=file_spec(dektak, units=None), **(TINY | PERIODIC | dict(friction_ps=0.2)))
    _, res = run(case)
    assert steady_ratio(res.history) == pytest.approx(0.2, abs=0.02)
