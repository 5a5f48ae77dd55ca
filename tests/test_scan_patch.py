"""A measured areal scan as the 3D cell's surface (surface/patch.py, docs/3d.md "A measured areal scan
as the surface"): the closure against known answers (a periodic surface comes back unchanged; a
non-periodic one closes exactly and its θa moves within a stated bound), the window choice on a
surface whose best window is known, the four directions, the mesh (normals up, the cell covered
once), the spec's identity, the case and the device built on it, and one tiny case on a patch of
frt-1.frt run for real in LIGGGHTS against physical invariants."""

from __future__ import annotations

import contextlib
import io
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from interphase.case import Case, case_from_dict
from interphase.engines.device import device
from interphase.errors import InputError
from interphase.material import Gradation
from interphase.surface.areal import theta_a_lines
from interphase.surface.base import Scan
from interphase.surface.builder import areal_patch, file_spec
from interphase.surface.patch import (HOLE_D50, close_slopes, cut_window, edge_mismatch, fill_small_holes, make_patch,
                                      oriented, theta_a_patch)
from interphase.surface.spec import ProfileSpec

ROOT = Path(__file__).resolve().parents[1]
FRT1 = ROOT / "campaigns" / "profiles" / "frt-1.frt"
D50 = 0.14e-3
H = 0.1 * D50                   # the synthetic grids' step: the mesh's finest (CONTACT_STEP_D50)


def selfaffine(nx: int, ny: int, seed: int, rms_slope: float = 0.3) -> np.ndarray:
    """A self-affine surface (H 0.8, short cut-off 4 steps, roll-off at the shorter side) periodic
    over nx × ny steps of H: heights (nx, ny) [m], one period, no closing node."""
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        from SurfaceTopography.Generation import fourier_synthesis

        t = fourier_synthesis((nx, ny), (nx * H, ny * H), hurst=0.8, rms_slope=rms_slope, short_cutoff=4 * H,
                              long_cutoff=min(nx, ny) * H, rng=seed)
    return np.asarray(t.heights(), float)


def wrapped(z: np.ndarray, tiles=(1, 1)) -> np.ndarray:
    """`tiles` periods of z with the closing row and column: grid nodes of a periodic surface."""
    z = np.tile(z, tiles)
    z = np.concatenate([z, z[:1]], 0)
    return np.concatenate([z, z[:, :1]], 1)


def scan_of(z: np.ndarray, name: str = "synthetic") -> Scan:
    return Scan(z, np.arange(z.shape[0]) * H, np.arange(z.shape[1]) * H, name, "m", "synthetic")


def test_the_closure_of_a_periodic_surface_changes_nothing():
    z = selfaffine(80, 50, 3)
    node = wrapped(z)
    u = close_slopes(node, H, H)
    assert np.max(np.abs(u - (node - z.mean()))) < 1e-9 * np.std(z)
    # the patch of a scan of 3 × 3 periods at the middle period: the surface itself, closed at no cost
    scan = scan_of(wrapped(z, (3, 3)))
    p = make_patch(scan, D50, 80 * H, 50 * H, "+x", window=(80 * H, 50 * H))
    assert p.origin == pytest.approx((80 * H, 50 * H)) and p.z.shape == (81, 51)
    assert np.max(np.abs(p.z - (node - z.mean()))) < 1e-9 * np.std(z)
    assert p.mismatch < 1e-9 and p.closure_rms < 1e-9 * np.std(z)
    # every window of a periodic scan closes: the best one scores 0 wherever it lies
    assert edge_mismatch(scan.heights, 80, 50).min() < 1e-9
    # θa of the patch as the cell shears it is the surface's own: the same lines read open over the
    # real continuation (D50/2 of the next period at each end) differ only by their levelling
    t = theta_a_patch(p, D50)
    pad = int(math.ceil(0.5 * D50 / H))
    ext = scan.heights[80 - pad:161 + pad, 50:101]
    open_ = theta_a_lines(np.arange(ext.shape[0]) * H, ext.T, D50)
    for sense in "+-":
        assert abs(t[sense + "x"][92].theta_a_deg - open_[sense][92].theta_a_deg) < 0.3


def test_a_non_periodic_surface_closes_exactly_and_its_theta_a_moves_little():
    """The window of a surface periodic over 4 × 4 cells does not close by itself; its patch does
    (opposite edges equal) and θa (filter 92, both senses) moves from the window's open reading by
    less than 0.6° (studies/scan_patch_bias/scan_patch_bias.py on such a surface: −0.25° on average, at most 0.57°
    over 42 readings; docs/3d.md);
    the closure never adds slope energy (the least-squares closure takes it: Pythagoras)."""
    z = wrapped(selfaffine(320, 200, 5))
    scan = scan_of(z)
    p = make_patch(scan, D50, 80 * H, 50 * H)
    assert np.array_equal(p.z[-1, :], p.z[0, :]) and np.array_equal(p.z[:, -1], p.z[:, 0])
    assert abs(p.z[:-1, :-1].mean()) < 1e-12 * np.std(z)
    w = cut_window(scan, D50, 80 * H, 50 * H)
    assert w.mismatch > 0.05 and p.closure_rms > 0              # there was something to close
    raw = theta_a_lines(np.arange(81) * H, w.z.T, D50)
    t = theta_a_patch(p, D50)
    for sense in "+-":
        r, c = raw[sense][92].theta_a_deg, t[sense + "x"][92].theta_a_deg
        assert math.isfinite(r) and abs(c - r) < 0.6, (sense, r, c)
    slope2 = lambda a: np.sum(np.diff(a, axis=0) ** 2) + np.sum(np.diff(a, axis=1) ** 2)
    from interphase.surface.patch import _plane_residual

    assert slope2(p.z) < slope2(_plane_residual(w.z))


def test_the_chosen_window_is_the_one_that_closes():
    """Noise everywhere but one block, a periodic surface of exactly the cell's size: that block is
    the window chosen, in every direction (a square cell, so each direction's cell fits it)."""
    rng = np.random.default_rng(4)
    z = rng.normal(0.0, 2e-6, (200, 160))
    block = wrapped(selfaffine(60, 60, 9, rms_slope=0.1))
    z[70:131, 40:101] = block
    scan = scan_of(z)
    for direction in ("+x", "-x", "+y", "-y"):
        w = cut_window(scan, D50, 60 * H, 60 * H, direction)
        assert w.origin == pytest.approx((70 * H, 40 * H)), direction
        assert w.mismatch < 1e-9
    # a pinned window is taken as given, the best one aside
    w = cut_window(scan, D50, 60 * H, 60 * H, "+x", window=(10 * H, 20 * H))
    assert w.origin == pytest.approx((10 * H, 20 * H)) and w.mismatch > 0.5
    with pytest.raises(InputError, match="no window of this cell has its corner"):
        cut_window(scan, D50, 60 * H, 60 * H, "+x", window=(1.0, 0.0))


def test_the_four_directions_turn_the_scan_and_minus_x_is_plus_x_sheared_back():
    rng = np.random.default_rng(2)
    h = rng.normal(size=(7, 5))
    scan = Scan(h, np.arange(7) * 1e-5, np.arange(5) * 2e-5, "s", "m", "test")
    Z, hx, hy, I, J = oriented(scan, "+x")
    assert np.array_equal(Z, h) and (hx, hy) == pytest.approx((1e-5, 2e-5))
    Z, *_ = oriented(scan, "-x")
    assert np.array_equal(Z, np.rot90(h, 2))
    Z, hx, hy, I, J = oriented(scan, "+y")
    assert np.array_equal(Z, np.rot90(h, -1)) and (hx, hy) == pytest.approx((2e-5, 1e-5))
    assert np.array_equal(Z, h[I, J])                          # the file's own indices turned alike
    Z, *_ = oriented(scan, "-y")
    assert np.array_equal(Z, np.rot90(h, 1))
    # a surface sheared −x is the +x patch turned 180°: the same window, its θa the +x patch's read back
    z = wrapped(selfaffine(240, 150, 11))
    s = scan_of(z)
    plus, minus = make_patch(s, D50, 80 * H, 50 * H, "+x"), make_patch(s, D50, 80 * H, 50 * H, "-x")
    assert plus.origin == pytest.approx(minus.origin)
    assert np.allclose(minus.z, np.rot90(plus.z, 2), rtol=0, atol=1e-12 * np.std(z))
    tp, tm = theta_a_patch(plus, D50), theta_a_patch(minus, D50)
    assert tm["+x"][92].theta_a_deg == pytest.approx(tp["-x"][92].theta_a_deg, abs=1e-9)
    with pytest.raises(InputError, match="unknown direction"):
        oriented(scan, "+z")


def test_small_holes_are_filled_from_their_rims_and_wider_ones_refuse_their_windows():
    z = wrapped(selfaffine(120, 80, 6))
    z[50, 40] = np.nan                                         # one point: rims 2 steps = 0.2 D50 apart
    z[10:20, 10:20] = np.nan                                   # 1.1 D50 across: not filled
    f = fill_small_holes(z, H, H, D50)
    assert f[50, 40] == pytest.approx(np.mean([z[49, 40], z[51, 40], z[50, 39], z[50, 41]]))   # harmonic
    assert np.isnan(f[10:20, 10:20]).all() and 11 * H > HOLE_D50 * D50
    score = edge_mismatch(f, 40, 30)
    assert np.isinf(score[:20, :20]).all() and np.isfinite(score[30:, 30:]).all()
    w = cut_window(scan_of(z), D50, 40 * H, 30 * H)
    assert np.isfinite(w.z).all()


def test_the_patch_mesh_has_normals_up_and_covers_the_cell_once():
    p = make_patch(scan_of(wrapped(selfaffine(200, 120, 1))), D50, 60 * H, 40 * H)
    points, tri = p.triangles(-p.width / 2)
    a, b, c = (points[tri[:, k]] for k in range(3))
    normal = np.cross(b - a, c - a)
    assert np.all(normal[:, 2] > 0)
    assert 0.5 * normal[:, 2].sum() == pytest.approx(p.length * p.width, rel=1e-12)   # projected: L × W
    assert points[:, 0].min() == 0 and points[:, 0].max() == pytest.approx(p.length)
    assert points[:, 1].min() == pytest.approx(-p.width / 2) and points[:, 1].max() == pytest.approx(p.width / 2)
    # the mesh's heights: the nodes, each triangle's centroid on its plane, periodic in x and y
    X, Y = np.meshgrid(p.x, p.y, indexing="ij")
    assert np.allclose(p.height_at(X, Y), p.z, atol=1e-15)
    cen = (a + b + c) / 3
    assert np.allclose(p.height_at(cen[:, 0], cen[:, 1] + p.width / 2), cen[:, 2], atol=1e-15)
    assert np.allclose(p.height_at(cen[:, 0] + p.length, cen[:, 1] - p.width / 2), cen[:, 2], atol=1e-15)


def test_a_scan_finer_than_the_contact_scale_is_meshed_at_it_and_a_coarser_one_as_measured(tmp_path):
    fine = scan_of(wrapped(selfaffine(300, 200, 2)))     # 0.1 D50 steps under grains of 0.3 D50 … 3 D50
    p = make_patch(fine, 3 * D50, 90 * H, 60 * H, min_step=0.1 * 3 * D50)
    assert p.z.shape == (31, 21) and p.x[1] == pytest.approx(0.1 * 3 * D50)
    assert np.array_equal(p.z[-1], p.z[0]) and np.array_equal(p.z[:, -1], p.z[:, 0])
    q = make_patch(fine, D50, 90 * H, 60 * H, min_step=0.1 * D50)
    assert q.z.shape == (91, 61)


def test_an_areal_spec_has_its_own_identity_and_older_specs_keep_theirs():
    spec = file_spec(FRT1, units=None, areal=True)
    c = spec.canonical()
    assert c["areal"] is True and c["patch"] == "edge-match/lsq-slopes" and "direction" not in c and "window" not in c
    assert spec.direction == "+x" and spec.label() == "frt-1-areal"
    assert file_spec(FRT1, units=None, areal=True, direction="+").canonical() == c
    side = file_spec(FRT1, units=None, areal=True, direction="-y", window=[0.002, 0.003])
    assert side.canonical()["direction"] == "-y" and side.canonical()["window"] == [0.002, 0.003]
    assert side.label() == "frt-1-areal-my-at2-3mm" and side != spec
    line = file_spec(FRT1, units=None, axis="x", line=250)
    assert "areal" not in line.canonical() and "patch" not in line.canonical()
    for bad, match in ((dict(areal=True, line=3), "no axis or line"), (dict(areal=True, direction="+z"), "unknown direction"),
                       (dict(window=[0.0, 0.0]), "window is for an areal"),
                       (dict(areal=True, window=[0.1]), "window must be two lengths"),
                       (dict(areal=True, cutoff=1e-3), "not filtered")):
        with pytest.raises(InputError, match=match):
            file_spec(FRT1, units=None, **bad)
    with pytest.raises(InputError, match="axis, line, direction, areal and window are for file"):
        ProfileSpec(kind="flat", areal=True)
    with pytest.raises(InputError, match="not an areal scan"):
        file_spec(ROOT / "campaigns" / "profiles" / "dektak-1.csv", units="um", areal=True)


#: a 3D cell of 6 × 4 × 4 D50 on a patch of frt-1.frt under single-sized grains of 0.14 mm (the
#: Karlsruhe sand's D50), soft (50 MPa): ~110 grains
TINY_SCAN = dict(device="periodic3d", d50=D50, gradation={"sizes": [D50], "fractions": [1.0]}, box_length_d50=6,
                 box_depth_d50=4, box_height_d50=4, shear_modulus=50e6, shear_distance=1.0 * D50,
                 snapshot_every=0.25 * D50, friction_ps=0.5)


def tiny_scan_case(**profile) -> Case:
    return case_from_dict(TINY_SCAN | {"profile": {"kind": "file", "path": str(FRT1), "areal": True} | profile})


def test_a_case_on_an_areal_scan_is_a_3d_interface_case_whose_grains_start_above_its_patch():
    case = tiny_scan_case()
    patch = case.surface_patch()
    assert patch is areal_patch(case.profile, D50, 6 * D50, 4 * D50)          # one patch, cached
    assert case.box_length == pytest.approx(patch.length) and case.box_depth == pytest.approx(patch.width)
    assert case.box_length == pytest.approx(35 * 24e-6) and case.box_depth == pytest.approx(23 * 24e-6)
    assert case.surface().z.max() == patch.z.max() and case.surface_across() is None
    assert "-frt-1-areal-" in case.label() and case.canonical()["profile"]["areal"] is True
    dev = device(case)
    points, tri = dev.surface_mesh
    assert points[:, 1].min() == pytest.approx(-case.box_depth / 2)
    pk = dev.packing
    assert np.all(pk.z - pk.diameter / 2 > patch.z.max())           # every grain above the highest point
    assert dev.bounds[2] < patch.z.min()
    from interphase.analysis.summary_stages import profile_features

    v = profile_features(case).values
    t = theta_a_patch(patch, D50)["+x"]
    assert v["theta_a_deg_92"] == pytest.approx(t[92].theta_a_deg, nan_ok=True)
    assert v["theta_a_deg_90"] == pytest.approx(t[90].theta_a_deg) and v["rn"] == pytest.approx(t[92].rn)
    other = tiny_scan_case(direction="+y")
    assert other.canonical()["profile"]["direction"] == "+y" and other.surface_patch().direction == "+y"
    with pytest.raises(InputError, match="3D cell's interface test only"):
        case_from_dict({"profile": {"kind": "file", "path": str(FRT1), "areal": True}, "device": "periodic"})
    with pytest.raises(InputError, match="its own relief across"):
        Case(profile=case.profile, device="periodic3d", profile_y=ProfileSpec.make("flat"))


def test_a_3d_card_case_on_frt1_renders_a_mesh_liggghts_takes():
    """The Karlsruhe 3D card's cell (30 × 15 × 10 D50 at D50 0.14 mm) on frt-1.frt: 175 × 58 grid
    steps of the scan (24 µm, 0.17 D50: meshed as measured), two triangles each, every angle above
    LIGGGHTS' smallest, the STL holding all of them."""
    from interphase.engines.base import EngineProfile
    from interphase.engines.liggghts import Liggghts
    from interphase.surface.builder import LIGGGHTS_MIN_ANGLE_DEG
    from interphase.surface.mesh import min_angle_deg

    case = case_from_dict(TINY_SCAN | dict(box_length_d50=30, box_depth_d50=10, box_height_d50=15, n_grains=200,
                                           profile={"kind": "file", "path": str(FRT1), "areal": True}))
    patch = case.surface_patch()
    assert patch.z.shape == (176, 59)
    points, tri = device(case).surface_mesh
    assert len(tri) == 2 * 175 * 58 and min_angle_deg(points, tri) > LIGGGHTS_MIN_ANGLE_DEG
    stl = Liggghts(profile=EngineProfile("liggghts")).render(case)["surface.stl"]
    assert stl.count("endfacet") == len(tri)


#: the 6 × 4 D50 window of frt-1.frt with the most relief at D50 0.14 mm (0.126 D50 from its lowest
#: to its highest point, θa 13.5° both ways; most of the scan is flatter than 0.03 D50 at this size)
ROUGH_WINDOW = [0.002064, 0.001872]


@pytest.mark.liggghts
def test_a_tiny_3d_case_on_a_patch_of_frt1_keeps_its_grains_above_it_and_carries_the_load(tmp_path):
    """The tiny cell (6 × 4 × 4 D50, 108 grains of 0.14 mm, 50 MPa) on frt-1.frt's roughest patch of
    that size, μs 0.5, 1 D50 of shear (measured: 18 s of LIGGGHTS CPU, most of it the consolidation's
    59 000 steps). Invariants: every grain lies above the mesh beneath it at the start, and at every
    snapshot from the end of the consolidation on (the surface displaced by the shear) its centre
    lies at least its radius above it less 0.1 D50 (the engine's own grain–surface overlaps reach 4 %
    of D50 here, mean 1.3 %; a grain through the mesh reads −1 D50 or less), and never less than the
    deepest grain–surface contact the engine reports; none is lost; the surface
    carries the platen's load: the mean of −Fz over the shear within 3 % of σ·L·W and every row within
    25 % (test_3d.py's bands for the areal case)."""
    from interphase.campaign.runner import run_single
    from interphase.io.liggghts import read_folder

    from .conftest import need_binary

    need_binary("liggghts")
    case = tiny_scan_case(window=ROUGH_WINDOW)
    patch = case.surface_patch()
    assert patch.z.max() - patch.z.min() > 0.1 * D50
    pk = device(case).packing
    assert np.all(pk.z - pk.diameter / 2 - patch.height_at(pk.x, pk.y + case.box_depth / 2) > 0)   # the start
    res = run_single(case, "liggghts", tmp_path / "case")
    assert res["status"] == "done", {k: res.get(k) for k in ("cause", "error", "message", "log_tail")}
    r = read_folder(tmp_path / "case")
    h = r.history[r.history["shear_disp"] >= 0]
    target = case.normal_stress * case.box_length * case.box_depth
    load = -h["surface_fz"].to_numpy()
    assert len(h) > 20 and abs(load.mean() / target - 1) < 0.03, (load.mean(), target)
    assert np.all(np.abs(load / target - 1) < 0.25)
    g = r.particles
    below = patch.height_at(g["x"].to_numpy() + g["shear_disp"].to_numpy(), g["y"].to_numpy() + case.box_depth / 2)
    gap = g["z"].to_numpy() - below - g["radius"].to_numpy()
    assert gap.min() > -0.1 * D50, gap.min() / D50
    # no grain lies deeper in the surface than the engine's own deepest grain–surface contact: the
    # mesh read here is the one LIGGGHTS sheared (measured: the two agree to 1e-6 D50)
    ps = r.contacts[r.contacts["kind"].eq("ps").to_numpy()]
    assert gap.min() >= -ps["overlap"].max() - 1e-3 * D50
    assert g["shear_disp"].min() <= 1e-12                          # the first snapshot: the end of consolidation
    assert (g.groupby("snapshot").size() == pk.n).all()
    s = res["summary"]
    assert 0.05 < s["peak_stress_ratio"] < 1.5 and math.isfinite(s["theta_r_surface_deg"])
    assert s["fabric_yy_surface"] > 0                              # the mesh is areal: normals with a y part
