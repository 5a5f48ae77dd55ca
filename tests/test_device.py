"""One device, two serialisers: both engines' rendered files state the same test device.

The quantities are read back from what each engine writes (LIGGGHTS: in.deck, the STL meshes,
grains.data; YADE: params.json), not from the Device object, and compared: walls and their gaps,
exit planes, platen, domain bounds, measuring window, time step, consolidation and shear step
counts, snapshot and history intervals, grains. No engine runs here.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from interphase.case import Case
from interphase.engines import device as device_module
from interphase.engines.base import EngineProfile
from interphase.engines.liggghts import Liggghts
from interphase.engines.yade import Yade
from interphase.errors import InputError
from interphase.material import Gradation
from interphase.recipe import RECIPE, Recipe, RunRecord, Steps, read_record
from interphase.surface.spec import ProfileSpec

ROOT = Path(__file__).resolve().parents[1]

SMALL = dict(shear_modulus=50e6, n_grains=200, box_length_d50=20, box_height_d50=10, shear_distance=2e-3,
             snapshot_every=0.5e-3, friction_ps=0.5)
CASES = {
    # the 45° saw-tooth with well-graded grains: the left wall's gap differs from the right's
    "sawtooth45": Case(profile=ProfileSpec.make("sawtooth", rt=1, sw=2, sr=0), gradation=Gradation("poly"), **SMALL),
    "box": Case(test="box", **SMALL),
    # x periodic, no side walls, a saw-tooth platen; the box test is the soil against a frozen bed
    "periodic_sawtooth": Case(profile=ProfileSpec.make("sawtooth", rt=1, sw=2, sr=0), device="periodic", **SMALL),
    "periodic_flat": Case(profile=ProfileSpec.make("flat"), device="periodic", **SMALL),
    "periodic_box": Case(test="box", device="periodic", **SMALL),
}


def _engines():
    """Both engines with plain profiles: rendering needs no binary."""
    return Liggghts(profile=EngineProfile("liggghts")), Yade(profile=EngineProfile("yade"))


def stl_segments(text: str) -> tuple[list[tuple[float, float, float, float]], float]:
    """(segments (x0, z0, x1, z1), y reach) of an STL written as two triangles per segment: the first
    half of the facets are (x0, −w, z0), (x1, −w, z1), (x1, +w, z1)."""
    v = np.array([[float(c) for c in ln.split()[1:]] for ln in text.splitlines() if ln.strip().startswith("vertex")])
    tri = v.reshape(-1, 3, 3)
    first = tri[: len(tri) // 2]
    return [(a[0], a[2], b[0], b[2]) for a, b, _ in first], float(first[0][2][1])


def facet_segments(triangles) -> tuple[list[tuple[float, float, float, float]], float]:
    """(segments, y reach) of YADE's in-plane facets [x0, 0, z0, x1, 0, z1, apex x, width, apex z]."""
    return [(t[0], t[2], t[3], t[5]) for t in triangles], triangles[0][7]


def liggghts_device(files: dict) -> dict:
    """The shared quantities as the LIGGGHTS files state them."""
    deck = files["in.deck"]

    def find(pattern, cast=float):
        m = re.search(pattern, deck, re.MULTILINE)
        assert m, pattern
        return [cast(g) for g in m.groups()] if len(m.groups()) > 1 else cast(m.group(1))
    runs = [int(n) for n in re.findall(r"^run\s+(\d+)", deck, re.MULTILINE)]
    interface = "surface.stl" in files
    moving, reach = stl_segments(files[next(f for f in ("surface.stl", "lower.stl", "floor.stl") if f in files)])
    fixed = next((stl_segments(files[f])[0] for f in ("sides.stl", "upper.stl") if f in files), [])
    platen, _ = stl_segments(files["platen.stl"])
    data = files["grains.data"]
    xlo, xhi = (float(s) for s in re.search(r"^(\S+) (\S+) xlo xhi", data, re.MULTILINE).groups())
    zlo, zhi = (float(s) for s in re.search(r"^(\S+) (\S+) zlo zhi", data, re.MULTILINE).groups())
    atoms = np.loadtxt(data.split("Atoms\n\n", 1)[1].splitlines(), ndmin=2)
    bed = re.search(r"^group bed id ([\d ]+)$", deck, re.MULTILINE)
    com_x, com_z, force = find(r"servo file platen\.stl type 3 com (\S+) 0\.0 (\S+) ctrlPV force .* target_val (\S+)")
    out = dict(
        moving=moving, fixed=fixed, platen=platen, reach=reach, platen_com=(com_x, com_z), platen_force=-force,
        platen_band=tuple(find(r'if "\$\{pfc\} > (\S+) && \$\{pfc\} < (\S+)"')),
        dt=find(r"^timestep\s+(\S+)"), skin=find(r"^neighbor\s+(\S+) bin"),
        shear_velocity=-find(r"move/mesh mesh \S+ linear (\S+) "),
        steps=dict(n_consolidate=runs[0], n_chunk=runs[1], n_shear=runs[2],
                   n_chunks_max=find(r"^variable kc loop (\d+)", int),
                   n_snapshot=find(r"^dump dpc all local (\d+)", int), n_history=find(r"^fix hist all print (\d+)", int)),
        bounds=(xlo, xhi, zlo, zhi), grains=atoms[:, [4, 6, 2]] * [1, 1, 0.5],          # x, z, radius
        window=tuple(find(r"^variable win atom \(x>(\S+)\)\*\(x<(\S+)\)\*\(z<(\S+)\)")) if interface else None,
        exits=None, period=xhi - xlo if re.search(r"^boundary\s+p f f", deck, re.MULTILINE) else None,
        bed=[int(i) - 1 for i in bed.group(1).split()] if bed else [],          # LIGGGHTS atom ids from 1
    )
    if "exit_left.stl" in files:
        out["exits"] = [stl_segments(files[f"exit_{side}.stl"])[0][0][0] for side in ("left", "right")]
    return out


def yade_device(files: dict) -> dict:
    """The shared quantities as YADE's params.json states them."""
    p = json.loads(files["params.json"])
    walls = {w["index"]: facet_segments(w["triangles"]) for w in p["walls"]}
    platen = walls[2][0]
    xs = [x for s in platen for x in (s[0], s[2])]
    g = p["grains"]
    return dict(
        moving=walls[0][0], fixed=walls.get(1, ([], 0))[0], platen=platen, reach=walls[0][1],
        platen_com=(0.5 * (min(xs) + max(xs)), p["platen_z"]), platen_force=p["platen_force"],
        platen_band=(p["platen_force_lo"], p["platen_force_hi"]), dt=p["dt"], skin=None,
        shear_velocity=p["shear_velocity"], steps={k: p["steps"][k] for k in p["steps"]},
        bounds=tuple(p["bounds"]), grains=np.column_stack([g["x"], g["z"], g["r"]]),
        window=tuple(p["window"]) if p["window"] else None, exits=p["exits"], period=p["period"], bed=p["bed"],
    )


@pytest.mark.parametrize("name", list(CASES))
def test_both_engines_render_one_device(name):
    case = CASES[name]
    lig_engine, yade_engine = _engines()
    before = device_module.device.cache_info()
    lig_files, yade_files = lig_engine.render(case), yade_engine.render(case)
    after = device_module.device.cache_info()
    # computed at most once for both engines (not at all when an earlier test computed it)
    assert after.misses - before.misses <= 1 and after.hits - before.hits >= 1
    lig, yade = liggghts_device(lig_files), yade_device(yade_files)
    for key in ("moving", "fixed", "platen", "reach", "platen_force", "platen_band", "dt", "shear_velocity",
                "steps", "bounds", "window", "exits", "period", "bed"):
        assert lig[key] == yade[key], key          # exact: both write full float precision
    assert lig["platen_com"][1] == yade["platen_com"][1] == lig["platen"][0][1]          # platen z
    assert lig["platen_com"][0] == pytest.approx(yade["platen_com"][0], rel=1e-15)        # its centre
    np.testing.assert_allclose(lig["grains"], yade["grains"], rtol=1e-11)                 # data file: 12 digits
    # the snapshot schedule: every snapshot a history row, shear starting on a dump step
    s = lig["steps"]
    assert s["n_snapshot"] % s["n_history"] == 0
    assert s["n_consolidate"] % s["n_snapshot"] == 0 and s["n_chunk"] % s["n_snapshot"] == 0
    assert s["n_snapshot"] * lig["dt"] == pytest.approx(case.snapshot_every / case.shear_velocity, rel=0.02)
    # recipe.json: one record, the same for both engines but for the engine's name
    lig_rec, yade_rec = (json.loads(f["recipe.json"]) for f in (lig_files, yade_files))
    assert lig_rec.pop("engine") == "liggghts" and yade_rec.pop("engine") == "yade"
    assert lig_rec == yade_rec
    assert lig_rec["steps"] == s and lig_rec["dt"] == lig["dt"] and lig_rec["n_grains"] == len(lig["grains"])
    if case.periodic:
        # no side walls or exits; x periodic over the box, which the surface spans exactly
        L = case.box_length
        assert lig["fixed"] == [] and lig["exits"] is None and lig["period"] == yade["period"] == L
        assert min(x for s in yade["moving"] for x in (s[0], s[2])) == 0.0
        assert max(x for s in yade["moving"] for x in (s[0], s[2])) == pytest.approx(L, rel=1e-15)
        assert (lig["bed"] != []) == (case.test == "box")
        assert lig["window"] == (yade["window"] if case.test == "box" else (0.0, L, lig["window"][2]))
        assert json.loads(yade_files["recipe.json"])["period"] == L
        assert "periodic" in yade_files["driver.py"]
    elif case.test == "interface":
        # side-wall gaps above the surface's highest point: the right wall 0.05·d_min, the left one
        # the valley gap (wider on the 45° saw-tooth), the same in both engines
        top = max(max(z0, z1) for _, z0, _, z1 in yade["moving"])
        for dev in (lig, yade):
            (_, _, _, left_bottom), (_, right_bottom, _, _) = dev["fixed"]
            assert right_bottom - top == pytest.approx(0.05 * case.gradation.d_min, rel=1e-9)
            assert left_bottom - top > 0.05 * case.gradation.d_min
        assert lig["exits"] == yade["exits"] == [0.0, case.box_length]
        assert lig["window"][:2] == pytest.approx(case.window, rel=1e-15)
    else:
        assert lig["window"] is None and yade["window"] is None and lig["exits"] is None


def test_device_is_cached_per_case_and_frozen():
    case = CASES["box"]
    assert device_module.device(case) is device_module.device(case.replace())
    with pytest.raises(AttributeError):
        device_module.device(case).dt = 1.0


def test_recipe_record_round_trips_and_old_folders_are_read(tmp_path):
    dev = device_module.device(CASES["sawtooth45"])
    rec = dev.record("yade")
    back = RunRecord.from_dict(json.loads(rec.to_json()))
    assert back == rec and back.recipe == RECIPE
    assert isinstance(back.steps, Steps) and back.steps.most == (rec.steps.n_consolidate + rec.steps.n_chunks_max
                                                                 * rec.steps.n_chunk + rec.steps.n_shear)
    # folders written before recipe.json: LIGGGHTS' engine.json (flat), YADE's params.json (nested)
    lig = tmp_path / "lig"
    lig.mkdir()
    files = _engines()[0].render(CASES["sawtooth45"])
    (lig / "engine.json").write_text(files["engine.json"])
    old = read_record(lig)
    assert old.recipe is None and (old.dt, old.steps, old.n_grains, old.window) == (rec.dt, rec.steps, rec.n_grains,
                                                                                   rec.window)
    y = tmp_path / "yade"
    y.mkdir()
    p = json.loads(_engines()[1].render(CASES["sawtooth45"])["params.json"]) | dict(n_grains=rec.n_grains)
    (y / "params.json").write_text(json.dumps(p))
    assert read_record(y).steps == rec.steps and read_record(y).engine == "yade"
    with pytest.raises(InputError, match="recipe.json is missing"):
        read_record(tmp_path)


def test_a_changed_recipe_changes_the_device():
    slow = Recipe(history_points=100, consolidation_time=0.04)
    a, b = device_module.device(CASES["box"]), device_module.device(CASES["box"], slow)
    assert b.steps.n_consolidate > a.steps.n_consolidate and b.steps.n_history >= a.steps.n_history
    assert b.steps.n_shear == a.steps.n_shear and b.moving == a.moving


def test_an_engine_renders_its_recipe_and_its_case_ids_follow_it():
    slow = Recipe(history_points=100)
    base, other = Liggghts(profile=EngineProfile("liggghts")), Liggghts(profile=EngineProfile("liggghts"), recipe=slow)
    a, b = base.render(CASES["box"]), other.render(CASES["box"])
    assert json.loads(b["recipe.json"])["recipe"]["history_points"] == 100
    assert liggghts_device(b)["steps"]["n_history"] > liggghts_device(a)["steps"]["n_history"]
    assert other.recipe_id() != base.recipe_id()


def test_side_walls_clear_the_peaks_for_every_study_profile():
    # deep valleys (Group 1 Rt/D50 ≥ 2) and Group 4's B, D, G once put the left wall's edge inside
    # the teeth: every interface case of the study's campaigns now has both edges above the peaks
    from pathlib import Path

    from interphase.campaign.schema import load_campaign
    from interphase.surface.builder import from_spec

    root = Path(__file__).resolve().parents[1] / "campaigns"
    seen = set()
    for name in ("group1", "group2", "group3", "group4", "group5"):
        for pc in load_campaign(root / f"{name}.toml").cases:
            c = pc.case
            key = (c.profile, c.gradation, c.box_length_d50)
            if c.test != "interface" or key in seen:
                continue
            seen.add(key)
            prof = from_spec(c.profile, c.d50, c.box_length)
            top = float(prof.z.max())
            walls = device_module.side_walls(prof, c.box_length, c.gradation.d_min, c.gradation.d_max, c.d50, top + 1)
            for x0, z0, x1, z1 in walls:
                assert min(z0, z1) > top, (name, c.label())
    assert len(seen) > 40


def test_periodic_device_has_no_side_walls_and_a_toothed_platen():
    saw = ProfileSpec.make("sawtooth", rt=1, sw=2, sr=0)
    case = Case(profile=saw, device="periodic", **SMALL)
    dev = device_module.device(case)
    L = case.box_length
    assert dev.periodic and dev.fixed == () and dev.exits is None and dev.bed == ()
    assert dev.bounds[:2] == (0.0, L) and dev.window[:2] == (0.0, L) and case.window == (0.0, L)
    xs = [x for s in dev.moving for x in (s[0], s[2])]
    assert min(xs) == 0.0 and max(xs) == pytest.approx(L)            # the surface is exactly [0, L]
    tips = [s[3] for s in dev.platen[::2]]                             # teeth 1 D50 deep, pointing down
    assert len(dev.platen) == 2 * round(L / (2 * case.d50)) and min(tips) < dev.platen_com[1] - 0.99 * case.d50
    assert min(tips) > dev.packing.top                                 # and clear of the grains
    assert dev.record("liggghts").period == L
    # one device per case through the cache: its grains are read-only, walled or periodic
    walled = device_module.device(Case(profile=saw, **SMALL))
    assert not any(a.flags.writeable for d in (dev, walled) for a in (d.packing.x, d.packing.z, d.packing.diameter))
    box = device_module.device(Case(test="box", device="periodic", **SMALL))
    bed = np.array(box.bed)
    assert bed.size > 5 and np.allclose(box.packing.z[bed], box.packing.z.min())
    floor = box.moving[0][1]
    assert (box.packing.z[bed] - box.packing.diameter[bed] / 2 > floor).all()   # the bed rests above it


def test_periodic_device_closes_every_surface_into_its_cell():
    from interphase.surface.normals import theta_a_filters
    from interphase.surface.profiles import Profile, close

    # a saw-tooth keeps whole periods: 20 D50 of 3 D50 teeth is a 21 D50 cell (7 periods)
    saw = Case(profile=ProfileSpec.make("sawtooth", rt=1, sw=3, sr=0), device="periodic", **SMALL)
    assert saw.box_length == pytest.approx(21 * saw.d50) and saw.surface().x[-1] == pytest.approx(saw.box_length)
    assert device_module.device(saw).record("liggghts").period == saw.box_length
    # Group 4's random law: the cell ends where the walk returns to its start height, every face as
    # generated, so θa is the walled case's within a degree or two
    for name, au, ar, rtmax in (("A", 1, 1, 2), ("D", 4, 2, 4), ("G", 4, 4, 4)):
        spec = ProfileSpec.make("random", au=au, ar=ar, rtmax=rtmax, seed=1)
        walled = Case(profile=spec, box_length_d50=60, shear_distance=5e-3, snapshot_every=5e-4)
        cell = walled.replace(device="periodic")
        s = cell.surface()
        assert s.periodic and s.z[-1] == s.z[0] and s.x[0] == 0 and s.x[-1] == cell.box_length
        assert abs(cell.box_length / cell.d50 - 60) < 2 * au                 # within a segment or two
        t_w, t_p = (theta_a_filters(c.sheared_surface(), c.d50, (92,))[92].theta_a_deg for c in (walled, cell))
        assert abs(t_p - t_w) < 2.0, name
        assert cell.window == (0.0, cell.box_length) and device_module.device(cell).bounds[1] == cell.box_length
    # a profile that never comes back to its start height cannot close: say so, with the fix
    ramp = Profile(np.linspace(0, 0.05, 50), np.linspace(0, 0.01, 50), name="ramp.csv")
    with pytest.raises(InputError, match="ramp.csv") as e:
        close(ramp, 0.02)
    assert "walled" in e.value.fix
    # a cut next to a sample leaves no sliver: the mean-height crossing 0.15 µm from a sample of the
    # shipped FRT scan's line x 1/3 made a 0.15 µm face that LIGGGHTS refused (bad_mesh); every face
    # at a cut is now ≥ 2 % of D50, and every other face is the profile's own
    from interphase.surface.builder import MIN_FACE_D50, file_spec

    frt = Case(profile=file_spec(ROOT / "campaigns" / "profiles" / "frt-1.frt", axis="x", line="1/3"),
               device="periodic", **SMALL).surface()
    faces = np.hypot(np.diff(frt.x), np.diff(frt.z))
    assert faces.min() >= MIN_FACE_D50 * 0.7e-3 and np.median(faces) == pytest.approx(24e-6, rel=0.01)
    # YADE builds it (engines/yade_driver.py): it renders without refusal
    files = Yade(profile=EngineProfile("yade")).render(Case(profile=ProfileSpec.make("flat"), device="periodic", **SMALL))
    assert json.loads(files["params.json"])["period"] == 20 * 0.7e-3


@pytest.mark.parametrize("device_kind, test", [("walled", "interface"), ("periodic", "interface"), ("periodic", "box")])
def test_a_started_case_takes_the_source_runs_grains_and_platen(tmp_path, device_kind, test):
    """Case.start: the grains of the source run's first snapshot (by id) and its platen height at the
    start of the shear replace the lattice and the platen, in both engines' files; the rest of the
    device (walls, bounds, the periodic box's frozen bed) stays; a source of another case is refused."""
    import pandas as pd

    from interphase.case import Start

    kw = dict(SMALL, device=device_kind, test=test, gradation=Gradation("poly"))
    if test == "interface":
        kw["profile"] = ProfileSpec.make("sawtooth", rt=1, sw=2, sr=0)
    case = Case(**kw)
    plain = device_module.device(case)
    lattice = plain.packing
    sunk = lattice.z - 0.3 * case.d50                  # a "consolidated" specimen: the lattice, lower
    n = lattice.n
    pd.DataFrame({"snapshot": np.repeat([0, 1], n), "shear_disp": np.repeat([0.0, 2.5e-4], n),
                  "id": np.tile(np.arange(n, 0, -1), 2),                # written in another order
                  "x": np.tile(lattice.x[::-1], 2), "z": np.tile(sunk[::-1], 2),
                  "radius": np.tile(lattice.diameter[::-1] / 2, 2)}).to_parquet(tmp_path / "particles.parquet")
    platen = plain.platen_com[1] - 0.004
    pd.DataFrame({"shear_disp": [1e-5, 2e-5], "platen_z": [platen, platen + 1e-6]}).to_parquet(tmp_path / "history.parquet")
    started = case.replace(start=Start("liggghts", "0123456789ab", str(tmp_path)))
    dev = device_module.device(started)
    assert np.array_equal(dev.packing.x, lattice.x) and np.array_equal(dev.packing.z, sunk)
    assert dev.platen_com[1] == pytest.approx(platen)
    assert np.allclose(np.array(dev.platen)[:, [1, 3]] - np.array(plain.platen)[:, [1, 3]], platen - plain.platen_com[1])
    assert dev.bounds == plain.bounds and dev.moving == plain.moving and dev.fixed == plain.fixed
    assert dev.bed == plain.bed
    params = json.loads(Yade().render(started)["params.json"])
    assert params["grains"]["z"] == sunk.tolist() and params["platen_z"] == pytest.approx(platen)
    data = Liggghts().render(started)["grains.data"]
    assert f"{sunk[0]:.12g}" in data.split("Atoms")[1].splitlines()[2]
    assert started.canonical()["start"] == {"engine": "liggghts", "case_id": "0123456789ab"}
    assert "start" not in case.canonical()
    other = case.replace(seed=2, start=Start("liggghts", "0123456789ab", str(tmp_path)))
    with pytest.raises(InputError, match="not a run of this case") as err:
        device_module.device(other)
    assert str(tmp_path) in str(err.value)
    missing = case.replace(start=Start("liggghts", "fedcba987654", str(tmp_path / "nowhere")))
    with pytest.raises(InputError, match="fedcba987654"):
        device_module.device(missing)


def _smallest_angle_deg(points: np.ndarray, tri: np.ndarray) -> float:
    """The smallest interior angle of any triangle [°]."""
    p = points[tri]                                     # (n, 3 vertices, xyz)
    worst = 180.0
    for i in range(3):
        a, b = p[:, (i + 1) % 3] - p[:, i], p[:, (i + 2) % 3] - p[:, i]
        cos = np.einsum("ij,ij->i", a, b) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
        worst = min(worst, float(np.degrees(np.arccos(np.clip(cos, -1, 1))).min()))
    return worst


@pytest.mark.parametrize("device", ["periodic", "walled", "periodic3d"])
def test_a_finely_sampled_line_is_meshed_as_the_engine_accepts(device):
    """A Dektak line (77 nm steps, 0.46 µm of relief) under sand-sized grains: the surface the case
    gives the engines is resampled to the grains' contact scale (surface.builder.mesh_step, 0.1 D50
    or more), its cut faces no shorter than min_face, so every triangle of the extruded wall keeps an
    angle above LIGGGHTS's 0.256° (its refusal, bad_mesh, before a run)."""
    from interphase.surface.builder import LIGGGHTS_MIN_ANGLE_DEG, file_spec, mesh_step, min_face
    from interphase.surface.mesh import extruded_triangles

    kw = dict(box_depth_d50=10.0) if device == "periodic3d" else {}
    sand = Gradation(name="user", sizes=(0.10e-3, 0.14e-3, 0.2e-3), fractions=(0.3, 0.4, 0.3))
    case = Case(test="interface", device=device, d50=0.14e-3, gradation=sand, n_grains=200, box_length_d50=40,
                box_height_d50=10, profile=file_spec(ROOT / "campaigns" / "profiles" / "dektak-1.csv", units=None), **kw)
    prof = case.surface()
    steps = np.diff(prof.x)
    assert steps.min() >= min_face(case.d50, case.wall_width) * (1 - 1e-9)          # a cut's face
    assert np.median(steps) >= mesh_step(case.d50, case.wall_width) >= 0.1 * case.d50   # the contact scale
    dev = device_module.device(case)
    points, tri = extruded_triangles(prof, -dev.wall_reach, dev.wall_reach)
    assert _smallest_angle_deg(points, tri) > LIGGGHTS_MIN_ANGLE_DEG


def test_the_study_measured_lines_keep_every_point():
    """mesh_step changes no surface already run: the study's FRT lines (Group 5 in both gradations,
    24 µm steps under 0.7 mm grains) come out point for point as the full-resolution line."""
    from interphase.campaign.schema import load_campaign
    from interphase.surface.builder import periodic_cell

    files = {}
    for name in ("group5.toml", "study.toml"):
        camp = load_campaign(ROOT / "campaigns" / name)
        files |= {(repr(c.case.profile), c.case.gradation.name): c.case for c in camp.cases
                  if c.case.profile is not None and c.case.profile.kind == "file"}
    assert len(files) >= 4 and {g for _, g in files} == {"mono", "poly"}
    for case in files.values():
        full = periodic_cell(case.profile, case.d50, case.box_length_d50 * case.d50)
        got = case.surface()
        assert got.x.size == full.x.size and np.array_equal(got.x, full.x) and np.array_equal(got.z, full.z)
