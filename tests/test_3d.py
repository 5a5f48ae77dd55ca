"""The 3D device (device = "periodic3d", docs/3d.md): identity, rendering, the 3D surface tensors,
and one tiny case run for real in LIGGGHTS against physical invariants."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from interphase.analysis import anisotropy as an_
from interphase.case import Case, case_from_dict
from interphase.engines.base import EngineProfile
from interphase.engines.device import device
from interphase.engines.liggghts import Liggghts
from interphase.engines.yade import Yade
from interphase.errors import InputError
from interphase.material import Gradation
from interphase.surface.spec import ProfileSpec

SAW = ProfileSpec.make("sawtooth", rt=1, sw=2, sr=0)
#: 6 × 4 × 4 D50, uniform grains (~110), G = 50 MPa: a couple of seconds of LIGGGHTS
TINY3D = dict(profile=SAW, device="periodic3d", box_length_d50=6, box_depth_d50=4, box_height_d50=4,
              gradation=Gradation("mono"), shear_modulus=50e6, shear_distance=1e-3, snapshot_every=0.25e-3,
              friction_ps=0.5)


def test_depth_is_in_the_identity_of_3d_cases_only():
    flat = ProfileSpec.make("flat")
    two_d = Case(profile=flat, device="periodic")
    assert "box_depth_d50" not in two_d.canonical()               # 2D ids stay as they were
    deep = Case(profile=flat, device="periodic3d", box_depth_d50=6)
    assert deep.canonical()["box_depth_d50"] == 6.0 and deep.canonical()["device"] == "periodic3d"
    assert deep.periodic and deep.three_d and not two_d.three_d
    assert deep.thickness == deep.box_depth == pytest.approx(6 * deep.d50)     # F = σ·L·W
    assert deep.label().startswith("interface-periodic3d-flat")
    assert math.isnan(two_d.box_depth) and two_d.thickness == two_d.d50
    with pytest.raises(InputError, match="only the 3D device has a depth"):
        Case(profile=flat, device="periodic", box_depth_d50=6)
    with pytest.raises(InputError, match="box_depth_d50"):
        Case(profile=flat, device="periodic3d", box_depth_d50=0)
    assert case_from_dict({"profile": {"kind": "flat"}, "device": "periodic3d", "box_depth_d50": 5}).box_depth_d50 == 5.0


def test_yade_refuses_the_3d_device():
    with pytest.raises(InputError, match="LIGGGHTS only"):
        Yade(profile=EngineProfile("yade")).render(Case(**TINY3D))


@pytest.mark.parametrize("test", ["interface", "box"])
def test_the_3d_deck_is_periodic_in_y_and_its_walls_span_the_depth(test):
    case = Case(**TINY3D) if test == "interface" else Case(**{**TINY3D, "profile": None, "test": "box"})
    files = Liggghts(profile=EngineProfile("liggghts")).render(case)
    deck, data = files["in.deck"], files["grains.data"]
    W, L = case.box_depth, case.box_length
    assert re.search(r"^boundary\s+p p f$", deck, re.MULTILINE)
    assert "setforce" not in deck                                   # grains free in y
    assert "particles.dump id x y z vx vy vz radius" in deck
    ylo, yhi = (float(v) for v in re.search(r"^(\S+) (\S+) ylo yhi", data, re.MULTILINE).groups())
    assert (ylo, yhi) == (-W / 2, W / 2)
    atoms = np.loadtxt(data.split("Atoms\n\n", 1)[1].splitlines(), ndmin=2)
    x, y, z, d = atoms[:, 4], atoms[:, 5], atoms[:, 6], atoms[:, 2]
    assert np.all((x > 0) & (x < L) & (y > -W / 2) & (y < W / 2))
    assert np.unique(np.round(y / case.d50, 1)).size >= 3           # the grains fill the depth
    # no two grains overlap, images across the x and y boundaries included
    dx = x[:, None] - x[None, :]
    dy = y[:, None] - y[None, :]
    dx -= L * np.round(dx / L)
    dy -= W * np.round(dy / W)
    dist = np.sqrt(dx ** 2 + dy ** 2 + (z[:, None] - z[None, :]) ** 2) + np.eye(len(x)) * 1e9
    assert np.all(dist >= (d[:, None] + d[None, :]) / 2)
    # every mesh extruded over exactly the cell's depth
    for name in ("platen.stl", "surface.stl" if test == "interface" else "floor.stl"):
        ys = [float(ln.split()[2]) for ln in files[name].splitlines() if ln.strip().startswith("vertex")]
        assert min(ys) == -W / 2 and max(ys) == W / 2, name
    dev = device(case)
    assert dev.platen_force == pytest.approx(case.normal_stress * L * W)
    assert f"target_val {-dev.platen_force!r}" in deck
    assert '"depth": ' in files["recipe.json"]


def _table(fx, fy, fz, nx, ny, nz):
    n = len(fx)
    return pd.DataFrame(dict(snapshot=np.zeros(n, int), kind=pd.Categorical(["ps"] * n, ["pp", "ps", "pw"]),
                             nx=nx, ny=ny, nz=nz, fx=fx, fy=fy, fz=fz,
                             fn=np.asarray(fx) * nx + np.asarray(fy) * ny + np.asarray(fz) * nz,
                             ft=-np.asarray(fx) * nz + np.asarray(fz) * nx))


def test_the_3d_surface_tensors_read_in_plane_as_the_2d_ones():
    rng = np.random.default_rng(3)
    n = 40
    th = rng.uniform(0.3, 2.8, n)                  # normals in the upper half of the x–z plane
    nx, nz = np.cos(th), np.sin(th)
    fx, fz = rng.normal(-0.3, 0.5, n), rng.uniform(0.5, 2.0, n)
    flat = _table(fx, np.zeros(n), fz, nx, np.zeros(n), nz)
    two_d = an_.surface_anisotropy(flat.drop(columns=["ny", "fy"]))
    three_d = an_.surface_anisotropy(flat)
    for col in ("theta_r_deg", "ar", "theta_n_deg", "an", "force_angle_deg", "stress_ratio", "lee_share"):
        assert three_d[col].iloc[0] == pytest.approx(two_d[col].iloc[0], rel=1e-12, abs=1e-12), col
    assert three_d["r_yy"].iloc[0] == 0 and three_d["fy_share"].iloc[0] == 0
    assert three_d["fabric_yy"].iloc[0] == 0 and three_d["principal_tilt_y_deg"].iloc[0] == pytest.approx(0, abs=1e-6)
    # each force split into ±fy twins: the in-plane readings stay, the out-of-plane share is exact
    fy = 0.4 * np.abs(fz)
    twins = _table(np.r_[fx, fx], np.r_[fy, -fy], np.r_[fz, fz], np.r_[nx, nx], np.zeros(2 * n), np.r_[nz, nz])
    t = an_.surface_anisotropy(twins)
    assert t["theta_r_deg"].iloc[0] == pytest.approx(an_.resultant_direction_3d(fx, fy, fz)["theta_r_deg"].iloc[0])
    mag = np.sqrt(fx ** 2 + fy ** 2 + fz ** 2)
    assert t["r_yy"].iloc[0] == pytest.approx(np.sum(fy ** 2 / mag) / np.sum(mag), rel=1e-12)
    assert t["fy_share"].iloc[0] == pytest.approx(np.sum(fy) / np.sum(mag), rel=1e-12)
    assert t["stress_ratio"].iloc[0] == pytest.approx(-fx.sum() / fz.sum())
    assert t["principal_tilt_y_deg"].iloc[0] == pytest.approx(0, abs=1e-6)     # the twins cancel R_xy, R_yz
    # forces all along one 3D direction: θr its in-plane tilt, R_yy its y² share, the axis tilted out
    f = np.array([-0.5, 0.5, 1.0])
    one = an_.resultant_direction_3d([f[0]] * 3, [f[1]] * 3, [f[2]] * 3)
    assert one["theta_r_deg"].iloc[0] == pytest.approx(math.degrees(math.atan2(0.5, 1.0)))
    assert one["r_yy"].iloc[0] == pytest.approx(0.25 / 1.5)
    assert one["principal_tilt_y_deg"].iloc[0] == pytest.approx(math.degrees(math.asin(0.5 / math.sqrt(1.5))))


@pytest.mark.liggghts
def test_a_tiny_3d_case_carries_the_platen_load_and_keeps_its_grains(tmp_path):
    """6 × 4 × 4 D50 (~110 uniform grains), a 45° saw-tooth extruded in y, μs 0.5, 1 mm of shear
    (measured: ~3 s). Invariants: the surface carries the platen's load (mean of −Fz over the
    shear within 3 % of σ·L·W, every row within 25 %, the summary's load-balance band); every grain
    stays in the cell (none lost, centres between the surface's valleys and the platen, y within
    the period); θr and the stress ratio are finite, the out-of-plane share in [0, 1]."""
    from interphase.campaign.runner import run_single
    from interphase.io.liggghts import read_folder

    from .conftest import need_binary

    need_binary("liggghts")
    case = Case(**TINY3D)
    res = run_single(case, "liggghts", tmp_path / "case")
    assert res["status"] == "done", {k: res.get(k) for k in ("cause", "error", "message", "log_tail")}
    r = read_folder(tmp_path / "case")
    h = r.history[r.history["shear_disp"] >= 0]
    target = case.normal_stress * case.box_length * case.box_depth
    load = -h["surface_fz"].to_numpy()
    assert len(h) > 50 and abs(load.mean() / target - 1) < 0.03, (load.mean(), target)
    assert np.all(np.abs(load / target - 1) < 0.25)
    assert np.all(np.abs(h["normal_force"].to_numpy() / target - 1) < 0.25)
    p = r.particles
    n0 = device(case).n_grains
    assert (p.groupby("snapshot").size() == n0).all()
    W = case.box_depth
    assert p["y"].between(-W / 2, W / 2).all() and p["x"].between(0, case.box_length).all()
    assert p["y"].std() > 0.25 * W                                  # still spread over the depth
    prof = case.surface()
    platen_top = h["platen_z"].max()
    assert (p["z"] - p["radius"] > prof.z.min() - 0.05 * case.d50).all() and (p["z"] < platen_top).all()
    s = res["summary"]
    for key in ("peak_stress_ratio", "theta_r_surface_deg", "theta_r_surface_mean_deg",
                "stress_ratio_surface_contacts", "r_yy_surface", "fy_share_surface"):
        assert math.isfinite(s[key]), key
    assert 0.05 < s["peak_stress_ratio"] < 1.5 and 0 <= s["r_yy_surface"] <= 1 and 0 <= s["fy_share_surface"] <= 1
    assert s["n_contacts_surface"] > 0 and s["fabric_yy_surface"] < 1e-6      # an extruded profile: normals in x–z


ACROSS = ProfileSpec.make("sawtooth", rt=0.2, sw=2, sr=0)


def test_relief_across_the_shear_is_a_3d_interface_field_with_its_own_identity():
    areal = Case(**TINY3D, profile_y=ACROSS)
    extruded = Case(**TINY3D)
    assert "profile_y" not in extruded.canonical()                  # every existing id stays
    assert areal.canonical()["profile_y"] == ACROSS.canonical()
    assert "-y-sawtooth-rt0.2" in areal.label()
    assert areal.box_depth == pytest.approx(4 * areal.d50)          # whole periods of the relief
    parsed = case_from_dict({**{k: v for k, v in TINY3D.items() if k not in ("profile", "gradation")},
                             "gradation": "mono", "profile": {"kind": "sawtooth", "rt": 1, "sw": 2, "sr": 0},
                             "profile_y": {"kind": "sawtooth", "rt": 0.2, "sw": 2, "sr": 0}})
    assert parsed == areal
    with pytest.raises(InputError, match="profile_y"):
        Case(profile=SAW, device="periodic", profile_y=ACROSS)
    with pytest.raises(InputError, match="profile_y"):
        case_from_dict({"profile": {"kind": "flat"}, "device": "periodic3d", "profile_y": {"rt": 1}})


def test_the_areal_mesh_is_the_sum_of_the_two_profiles_with_normals_up():
    case = Case(**TINY3D, profile_y=ACROSS)
    dev = device(case)
    points, tri = dev.surface_mesh
    p, q, W = case.surface(), case.surface_across(), case.box_depth
    expected = np.interp(points[:, 0], p.x, p.z) + np.interp(points[:, 1] + W / 2, q.x, q.z)
    assert np.allclose(points[:, 2], expected, atol=1e-15)
    assert points[:, 1].min() == -W / 2 and points[:, 1].max() == pytest.approx(W / 2)
    a, b, c = (points[tri[:, k]] for k in range(3))
    normal = np.cross(b - a, c - a)
    assert np.all(normal[:, 2] > 0)
    area = 0.5 * np.linalg.norm(normal, axis=1)
    projected = 0.5 * normal[:, 2]
    assert projected.sum() == pytest.approx(case.box_length * W)     # the cell tiled once, no gap, no overlap
    assert area.sum() > projected.sum()
    stl = Liggghts(profile=EngineProfile("liggghts")).render(case)["surface.stl"]
    assert stl.count("endfacet") == len(tri)


@pytest.mark.liggghts
def test_a_tiny_areal_case_keeps_every_grain_above_its_surface(tmp_path):
    """The tiny case on the areal surface z = p(x) + q(y) (45° teeth along the shear, 0.2 D50 teeth
    across it; measured ~3 s). Invariants: the surface carries the platen's load; every grain centre
    at every snapshot lies at least its radius (less 5 % of D50 of overlap) above the surface beneath
    it, the surface displaced by the shear; the surface normals have a y part (the mesh the engine
    used is areal: an extruded profile gives exactly 0)."""
    from interphase.campaign.runner import run_single
    from interphase.io.liggghts import read_folder

    from .conftest import need_binary

    need_binary("liggghts")
    case = Case(**TINY3D, profile_y=ACROSS)
    res = run_single(case, "liggghts", tmp_path / "case")
    assert res["status"] == "done", {k: res.get(k) for k in ("cause", "error", "message", "log_tail")}
    r = read_folder(tmp_path / "case")
    h = r.history[r.history["shear_disp"] >= 0]
    target = case.normal_stress * case.box_length * case.box_depth
    assert abs(-h["surface_fz"].mean() / target - 1) < 0.03
    p, q = case.surface(), case.surface_across()
    L, W = case.box_length, case.box_depth
    g = r.particles
    below = (np.interp((g["x"] + g["shear_disp"]) % L, p.x, p.z)      # the surface slides −x
             + np.interp((g["y"] + W / 2) % W, q.x, q.z))
    gap = g["z"] - below - g["radius"]
    assert gap.min() > -0.05 * case.d50, gap.min() / case.d50
    assert (g.groupby("snapshot").size() == device(case).n_grains).all()
    s = res["summary"]
    assert 1e-3 < s["fabric_yy_surface"] < 0.2 and math.isfinite(s["theta_r_surface_deg"])


@pytest.mark.liggghts
def test_a_tiny_3d_interface_case_on_the_karlsruhe_card_shears_its_grains(tmp_path):
    """The 3D card's grains (soils/karlsruhe-fine-sand.toml: its sieve curve, friction, rolling
    friction, preparation and 500 MPa, filled in by the card as a campaign's `soil` does) in a
    6 × 5 × 4 D50 cell over the 45° teeth at μs 0.5, 1 D50 of shear (measured: ~18 s of CPU); a
    4 D50 deep cell is refused with the depth its largest grains need. Invariants: the case carries
    the card's fields; the grains in the dump are the card's sizes (within its sieve range, more than
    three of them); the surface carries the platen's load; none is lost; the peak stress ratio and
    θr are finite."""
    from interphase.campaign.runner import run_single
    from interphase.io.liggghts import read_folder
    from interphase.soil import load_card, merge_soil

    from .conftest import need_binary

    need_binary("liggghts")
    card = load_card(Path(__file__).resolve().parents[1] / "soils" / "karlsruhe-fine-sand.toml")
    table = {k: v for k, v in TINY3D.items() if k not in ("gradation", "shear_modulus")}
    d50 = float(card.soil["d50"])
    table |= dict(shear_distance=1.0 * d50, snapshot_every=0.25 * d50)     # the tiny case's shear in D50
    thin = run_single(case_from_dict(merge_soil(table, card, "test")), "liggghts", tmp_path / "thin")
    assert thin["status"] == "failed" and thin["cause"] == "input_error"       # 4 D50 < 2.5 pitches of d_max
    assert "at least 4.2 D50 long and deep" in thin["message"] and "1.62 D50" in thin["message"], thin["message"]
    case = case_from_dict(merge_soil(table | {"box_depth_d50": 5}, card, "test"))
    for key in ("friction_pp", "rolling_friction", "preparation", "shear_modulus", "d50"):
        assert getattr(case, key) == pytest.approx(float(card.soil[key])), key
    res = run_single(case, "liggghts", tmp_path / "case")
    assert res["status"] == "done", {k: res.get(k) for k in ("cause", "error", "message", "log_tail")}
    r = read_folder(tmp_path / "case")
    sizes = np.asarray(card.soil["gradation"]["sizes"], float)
    diam = 2 * r.particles["radius"].to_numpy()
    assert diam.min() >= 0.99 * sizes.min() and diam.max() <= 1.01 * sizes.max()
    assert np.unique(diam.round(9)).size > 3
    h = r.history[r.history["shear_disp"] >= 0]
    target = case.normal_stress * case.box_length * case.box_depth
    assert abs(-h["surface_fz"].mean() / target - 1) < 0.03
    assert (r.particles.groupby("snapshot").size() == device(case).n_grains).all()
    s = res["summary"]
    assert 0.05 < s["peak_stress_ratio"] < 1.5 and math.isfinite(s["theta_r_surface_deg"])
