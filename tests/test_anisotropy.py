"""Contact anisotropy (docs/methods.md §5): exact recovery, noisy recovery, θr examples, the sign check,
invariances (hypothesis) and degenerate input."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from interphase.analysis.anisotropy import (
    SLIDE_FRACTION, sliding_share,
    apply_shear_sign, binned_method, qp_sff, region_anisotropy, resultant_direction, surface_anisotropy,
    tensor_method,
)
from interphase.tables import CONTACT_COLUMNS, MissingColumnError

R = np.radians
MODEL = dict(a=0.4, theta_a=100.0, an=0.6, theta_n=110.0, at=0.25, theta_t=95.0, f0=1.7)


def model_forces(theta):
    fn = MODEL["f0"] * (1 + MODEL["an"] * np.cos(2 * (theta - R(MODEL["theta_n"]))))
    ft = -MODEL["f0"] * MODEL["at"] * np.sin(2 * (theta - R(MODEL["theta_t"])))
    return fn, ft


def exact_set():
    theta = np.arange(36) * np.pi / 36
    w = 1 + MODEL["a"] * np.cos(2 * (theta - R(MODEL["theta_a"])))
    fn, ft = model_forces(theta)
    return theta, w, fn, ft


def contacts_table(nx, nz, fn, ft, kind="pp", snapshot=0, centre=(0.0, 0.0), branch=1e-3):
    """A ContactTable from normals and force components (f = fn·n + ft·t on body 2)."""
    nx, nz, fn, ft = (np.asarray(v, dtype=float) for v in (nx, nz, fn, ft))
    fx, fz = fn * nx - ft * nz, fn * nz + ft * nx
    x2, z2 = centre[0] + 0.5 * branch * nx, centre[1] + 0.5 * branch * nz
    x1, z1 = centre[0] - 0.5 * branch * nx, centre[1] - 0.5 * branch * nz
    n = nx.size
    return pd.DataFrame({
        "snapshot": np.full(n, snapshot), "time": 0.0, "shear_disp": 0.0, "kind": kind,
        "id1": np.arange(n), "id2": np.arange(n) + n, "cx": np.full(n, centre[0]), "cz": np.full(n, centre[1]),
        "nx": nx, "nz": nz, "fn": fn, "ft": ft, "fx": fx, "fz": fz,
        "x1": x1, "z1": z1, "x2": x2, "z2": z2, "overlap": 0.0,
    })[list(CONTACT_COLUMNS)]


def test_exact_recovery_tensor_method():
    theta, w, fn, ft = exact_set()
    out = tensor_method(np.cos(theta), np.sin(theta), fn, ft, weight=w).iloc[0]
    assert out["a"] == pytest.approx(0.4, abs=1e-10)
    assert out["theta_fabric_ccw_deg"] == pytest.approx(100.0, abs=1e-10)
    assert out["an"] == pytest.approx(0.6, abs=1e-10)
    assert out["theta_n_ccw_deg"] == pytest.approx(110.0, abs=1e-10)
    assert out["at"] == pytest.approx(0.25, abs=1e-10)
    assert out["theta_t_ccw_deg"] == pytest.approx(95.0, abs=1e-10)
    assert out["f0"] == pytest.approx(1.7, abs=1e-10)
    # ψ reading: degrees from vertical
    assert out["theta_n_deg"] == pytest.approx(20.0, abs=1e-10)
    assert out["reason"] == ""


def test_exact_recovery_binning_method():
    theta, w, fn, ft = exact_set()
    b = binned_method(np.cos(theta), np.sin(theta), fn, ft, weight=w)
    assert b["a"] == pytest.approx(0.4, abs=1e-10)
    assert math.degrees(b["theta_fabric"]) == pytest.approx(100.0, abs=1e-10)
    assert b["an"] == pytest.approx(0.6, abs=1e-10)
    assert math.degrees(b["theta_n"]) == pytest.approx(110.0, abs=1e-10)
    assert b["at"] == pytest.approx(0.25, abs=1e-10)
    assert math.degrees(b["theta_t"]) == pytest.approx(95.0, abs=1e-10)
    assert b["f0"] == pytest.approx(1.7, abs=1e-10)


def test_qp_stress_force_fabric_value():
    theta, w, fn, ft = exact_set()
    o = tensor_method(np.cos(theta), np.sin(theta), fn, ft, weight=w).iloc[0]
    assert qp_sff(o["a"], o["theta_fabric"], o["an"], o["theta_n"], o["at"], o["theta_t"]) == pytest.approx(0.548539, abs=5e-7)


def noisy_sample(n=400_000, seed=7):
    """Directions drawn from E(θ) by jittered inverse-CDF sampling (full circle: axial pp normals
    point either way), fn and ft from the model with 20 % multiplicative and additive noise."""
    rng = np.random.default_rng(seed)
    grid = np.linspace(0, 2 * np.pi, 200_001)
    cdf = grid + 0.5 * MODEL["a"] * (np.sin(2 * (grid - R(MODEL["theta_a"]))) + np.sin(2 * R(MODEL["theta_a"])))
    cdf /= cdf[-1]
    u = (np.arange(n) + rng.random(n)) / n
    theta = np.interp(u, cdf, grid)
    fn, ft = model_forces(theta)
    fn = fn * (1 + 0.2 * rng.standard_normal(n)) + 0.1 * rng.standard_normal(n)
    ft = ft + 0.2 * MODEL["f0"] * MODEL["at"] * rng.standard_normal(n)
    perm = rng.permutation(n)
    return theta[perm], fn[perm], ft[perm]


def test_noisy_sample_both_methods():
    theta, fn, ft = noisy_sample()
    nx, nz = np.cos(theta), np.sin(theta)
    t = tensor_method(nx, nz, fn, ft).iloc[0]
    b = binned_method(nx, nz, fn, ft)
    for res, (ka, kn, kt) in ((t, ("theta_fabric_ccw_deg", "theta_n_ccw_deg", "theta_t_ccw_deg")),
                              ({**b, **{k + "_ccw_deg": math.degrees(b[k]) for k in ("theta_fabric", "theta_n", "theta_t")}},
                               ("theta_fabric_ccw_deg", "theta_n_ccw_deg", "theta_t_ccw_deg"))):
        assert res["a"] == pytest.approx(0.4, abs=0.005)
        assert res["an"] == pytest.approx(0.6, abs=0.005)
        assert res["at"] == pytest.approx(0.25, abs=0.005)
        assert res["f0"] == pytest.approx(1.7, abs=0.005)
        assert res[ka] == pytest.approx(100.0, abs=0.1)
        assert res[kn] == pytest.approx(110.0, abs=0.1)
        assert res[kt] == pytest.approx(95.0, abs=0.1)


@pytest.mark.parametrize("psi", [-40.0, 0.0, 17.5, 60.0, 89.0])
def test_parallel_forces_give_their_tilt(psi):
    mags = np.array([0.3, 1.0, 2.5, 7.0])
    fx, fz = -mags * math.sin(R(psi)), mags * math.cos(R(psi))
    out = resultant_direction(fx, fz).iloc[0]
    assert out["theta_r_deg"] == pytest.approx(psi, abs=1e-10)
    assert out["ar"] == pytest.approx(2.0, abs=1e-12)      # all along one axis: R1 = 1, R2 = 0


def test_two_forces_theta_r_and_summed_angle():
    # magnitude 2 at ψ = 0°, 1 at ψ = 60°
    fx = np.array([0.0, -math.sin(R(60))])
    fz = np.array([2.0, math.cos(R(60))])
    out = resultant_direction(fx, fz).iloc[0]
    assert out["theta_r_deg"] == pytest.approx(15.00, abs=1e-10)
    assert out["force_angle_deg"] == pytest.approx(19.1, abs=0.05)
    assert out["force_angle_deg"] == pytest.approx(math.degrees(math.atan(math.sin(R(60)) / 2.5)), abs=1e-12)


def test_sign_check_resisting_surface():
    """Soil pushed +x over the surface; the surface resists: on each grain the surface pushes up and
    toward −x. θr, θn and the summed-force angle are positive (toward −x) and μs = ΣFx/Σ(−Fz) with F
    the force on the surface is positive."""
    psi_n = np.array([45.0, 40.0, 50.0, 45.0, 10.0])    # resisting faces: normals up-left (2nd quadrant)
    nx, nz = -np.sin(R(psi_n)), np.cos(R(psi_n))
    fn = np.array([2.0, 1.5, 1.8, 2.2, 0.3])
    ft = 0.2 * fn        # t = (−nz, nx) points down the face toward −x: friction opposing the +x slip
    c = contacts_table(nx, nz, fn, ft, kind="ps")
    assert (c["fx"] < 0).all() and (c["fz"] > 0).all()
    s = surface_anisotropy(c).iloc[0]
    assert s["theta_r_deg"] > 0 and s["theta_n_deg"] > 0 and s["force_angle_deg"] > 0
    F_x, F_z = -c["fx"].sum(), -c["fz"].sum()            # force on the surface
    assert s["stress_ratio"] == pytest.approx(F_x / -F_z, rel=1e-12)
    assert s["stress_ratio"] > 0
    # ψF from the contact forces as given (f = fn·n + ft·t), not from the function's own sums
    gx, gz = np.sum(fn * nx - ft * nz), np.sum(fn * nz + ft * nx)
    assert s["force_angle_deg"] == pytest.approx(math.degrees(math.atan2(-gx, gz)), abs=1e-10)
    # the same contacts written with the surface moving +x: mirrored tables, shear_sign = −1
    m = apply_shear_sign(c, -1)
    assert surface_anisotropy(m).iloc[0]["theta_r_deg"] < 0
    back = surface_anisotropy(m, shear_sign=-1).iloc[0]
    assert back["theta_r_deg"] == pytest.approx(s["theta_r_deg"], abs=1e-12)
    assert back["stress_ratio"] == pytest.approx(s["stress_ratio"], abs=1e-12)


def test_surface_theta_n_is_force_weighted():
    # two faces: a heavily loaded one at ψ = 45° and a lightly loaded one at ψ = −45°
    psi_n = np.array([45.0, -45.0])
    c = contacts_table(-np.sin(R(psi_n)), np.cos(R(psi_n)), [3.0, 1.0], [0.0, 0.0], kind="ps")
    s = surface_anisotropy(c).iloc[0]
    # Σ fn n⊗n / Σ fn = diag-ish mix: direction from ½ arg(3 e^{2i·135°} + e^{2i·45°})
    expect = math.degrees(0.5 * np.angle(3 * np.exp(2j * R(135)) + np.exp(2j * R(45)))) % 180 - 90
    assert s["theta_n_deg"] == pytest.approx(expect, abs=1e-10)
    assert s["an"] == pytest.approx(abs(3 * np.exp(2j * R(135)) + np.exp(2j * R(45))) / 4 * 2, abs=1e-12)


# ---- invariances ----------------------------------------------------------------------------

def random_contacts(seed, n):
    rng = np.random.default_rng(seed)
    theta = rng.uniform(0, 2 * np.pi, n)
    fn = rng.uniform(0.1, 2.0, n) * (1 + 0.5 * np.cos(2 * (theta - 1.9)))
    ft = 0.3 * fn * rng.uniform(-1, 1, n)
    return theta, fn, ft


def all_directions(theta, fn, ft):
    nx, nz = np.cos(theta), np.sin(theta)
    t = tensor_method(nx, nz, fn, ft).iloc[0]
    fx, fz = fn * nx - ft * nz, fn * nz + ft * nx
    r = resultant_direction(fx, fz).iloc[0]
    return t, r


def _ang_close(a, b, period=180.0, tol=1e-7):
    d = (a - b + period / 2) % period - period / 2
    return abs(d) < tol


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(5, 300), beta=st.floats(-3.0, 3.0))
def test_rotation_rotates_every_direction(seed, n, beta):
    theta, fn, ft = random_contacts(seed, n)
    t0, r0 = all_directions(theta, fn, ft)
    t1, r1 = all_directions(theta + beta, fn, ft)
    b = math.degrees(beta)
    for key in ("theta_fabric_deg", "theta_n_deg", "theta_t_deg"):
        if math.isnan(t0[key]):   # a few contacts with a strong fabric: the correction g ≤ 0 somewhere
            assert math.isnan(t1[key]) and t1["reason"] == t0["reason"] != "", key
            continue
        assert _ang_close(t1[key], t0[key] + b, tol=1e-6), key
    assert _ang_close(r1["theta_r_deg"], r0["theta_r_deg"] + b, tol=1e-6)
    assert _ang_close(r1["force_angle_deg"], r0["force_angle_deg"] + b, period=360.0, tol=1e-6)
    for key in ("a", "an", "at", "f0"):
        if math.isnan(t0[key]):     # undefined (g ≤ 0 somewhere) stays undefined when rotated
            assert math.isnan(t1[key]), key
            continue
        assert t1[key] == pytest.approx(t0[key], rel=1e-9, abs=1e-12)
    assert r1["ar"] == pytest.approx(r0["ar"], rel=1e-9, abs=1e-12)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(3, 200), scale=st.floats(1e-3, 1e3))
def test_scaling_forces_scales_f0_only(seed, n, scale):
    theta, fn, ft = random_contacts(seed, n)
    t0, r0 = all_directions(theta, fn, ft)
    t1, r1 = all_directions(theta, fn * scale, ft * scale)
    for key, factor in (("f0", scale), ("a", 1.0), ("an", 1.0), ("at", 1.0)):
        if math.isnan(t0[key]):     # undefined (g ≤ 0 somewhere) stays undefined when scaled
            assert math.isnan(t1[key]), key
            continue
        assert t1[key] == pytest.approx(factor * t0[key], rel=1e-9, abs=1e-12), key
    for key in ("theta_fabric_deg", "theta_n_deg", "theta_t_deg"):
        if math.isnan(t0[key]):
            assert math.isnan(t1[key]) and t1["reason"] == t0["reason"] != "", key
            continue
        assert _ang_close(t1[key], t0[key], tol=1e-6), key
    assert _ang_close(r1["theta_r_deg"], r0["theta_r_deg"], tol=1e-6)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(3, 200))
def test_permuting_rows_changes_nothing(seed, n):
    theta, fn, ft = random_contacts(seed, n)
    c = contacts_table(np.cos(theta), np.sin(theta), fn, ft)
    c["kind"] = np.where(np.arange(n) % 3 == 0, "ps", "pp")
    c["nz"] = np.where(c["kind"] == "ps", np.abs(c["nz"]), c["nz"])
    perm = np.random.default_rng(seed).permutation(n)
    rect = (-1.0, 1.0, -1.0, 1.0)
    for fn_ in (lambda d: surface_anisotropy(d), lambda d: region_anisotropy(d, rect)):
        a = fn_(c).drop(columns="reason")
        b = fn_(c.iloc[perm].reset_index(drop=True)).drop(columns="reason")
        pd.testing.assert_frame_equal(a, b, rtol=1e-9, atol=1e-12)


def test_lee_share_lowers_the_summed_angle_not_theta_r():
    """A 45° saw-tooth valley: forces normal to the resisting face (ψn = 45°, 3 N in all) and to the
    lee face (ψn = −45°, 1 N) and a flat contact (ψn = 0°, 0.5 N; neither side): the lee share is
    1/4.5, θr stays on the resisting face (the lee force is orthogonal to it) while the summed angle
    falls to atan2((3 − 1)·√½, (3 + 1)·√½ + 0.5)."""
    psi_n = np.array([45.0, 45.0, -45.0, 0.0])
    fn = np.array([1.0, 2.0, 1.0, 0.5])
    c = contacts_table(-np.sin(R(psi_n)), np.cos(R(psi_n)), fn, np.zeros(4), kind="ps")
    s = surface_anisotropy(c).iloc[0]
    assert s["lee_share"] == pytest.approx(1.0 / 4.5, abs=1e-12)
    alone = surface_anisotropy(c.iloc[[0, 1]]).iloc[0]
    assert alone["lee_share"] == 0.0 and alone["theta_r_deg"] == pytest.approx(45.0, abs=1e-10)
    # a lee force orthogonal to the resisting ones leaves R's principal axes in place
    assert surface_anisotropy(c.iloc[[0, 1, 2]]).iloc[0]["theta_r_deg"] == pytest.approx(45.0, abs=1e-10)
    h = math.sqrt(0.5)
    expect = math.degrees(math.atan2(3 * h - 1 * h, 3 * h + 1 * h + 0.5))
    assert s["force_angle_deg"] == pytest.approx(expect, abs=1e-10) and s["force_angle_deg"] < s["theta_r_deg"]
    # the lee side is the +x-leaning side in the analysis frame: a run written mirrored agrees
    back = surface_anisotropy(apply_shear_sign(c, -1), shear_sign=-1).iloc[0]
    assert back["lee_share"] == pytest.approx(s["lee_share"], abs=1e-15)
    # no usable force: NaN, like θr
    zero = c.assign(fx=0.0, fz=0.0, fn=0.0)
    assert math.isnan(surface_anisotropy(zero).iloc[0]["lee_share"])


def test_sliding_share_counts_contacts_at_the_coulomb_limit():
    """μ 0.2: contacts at |ft|/fn 0.2 and 0.199 (≥ 0.99 μ) slide, 0.19 and 0 stick, either sign of ft;
    an unloaded contact (fn 0) counts in neither; a grain–grain contact is not the surface's. Per
    snapshot; a snapshot without a loaded surface contact reads NaN, as does μ 0."""
    fn = np.array([1.0, 2.0, 1.0, 1.0, 0.0])
    ft = np.array([0.2, -0.398, 0.19, 0.0, 0.0])
    a = contacts_table(np.zeros(5), np.ones(5), fn, ft, kind="ps", snapshot=3)
    b = contacts_table(np.zeros(2), np.ones(2), [1.0, 1.0], [0.5, 0.5], kind="pp", snapshot=3)
    empty = contacts_table(np.zeros(1), np.ones(1), [0.0], [0.0], kind="ps", snapshot=7)
    share = sliding_share(pd.concat([a, b, empty], ignore_index=True), 0.2)
    assert share.loc[3] == pytest.approx(2 / 4, abs=1e-12) and math.isnan(share.loc[7])
    assert 0.199 >= SLIDE_FRACTION * 0.2 > 0.19
    assert sliding_share(a, 0.2, snapshots=[3]).iloc[0] == pytest.approx(0.5)
    assert math.isnan(sliding_share(a, 0.0).iloc[0])
    # a 3D table: the whole tangential part counts, not only its in-plane component
    a3 = a.assign(cy=0.0, ny=0.0, fy=[0.0, 0.0, 0.1, 0.0, 0.0], y1=0.0, y2=0.0)
    assert sliding_share(a3, 0.2).iloc[0] == pytest.approx(3 / 4, abs=1e-12)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(3, 200))
@example(seed=8564, n=5)
def test_mirror_with_shear_sign_gives_same_psi(seed, n):
    theta, fn, ft = random_contacts(seed, n)
    theta = np.mod(theta, np.pi)                         # surface contacts: upper half plane
    c = contacts_table(np.cos(theta), np.sin(theta), fn, ft, kind="ps")
    m = apply_shear_sign(c, -1)                          # as written by a run moving the surface +x
    a = surface_anisotropy(c).iloc[0]
    mirrored = surface_anisotropy(m).iloc[0]
    back = surface_anisotropy(m, shear_sign=-1).iloc[0]
    for key in ("theta_r_deg", "theta_n_deg"):
        assert _ang_close(back[key], a[key], tol=1e-9)
        assert _ang_close(mirrored[key], -a[key], tol=1e-9)   # mirroring alone flips ψ
    assert back["stress_ratio"] == pytest.approx(a["stress_ratio"], rel=1e-12, abs=1e-15)
    t = tensor_method(m["nx"], m["nz"], m["fn"], m["ft"]).iloc[0]
    t0 = tensor_method(c["nx"], c["nz"], c["fn"], c["ft"]).iloc[0]
    # a few contacts can make the fabric too anisotropic for the second-order model (seed 8564, n 5:
    # a = 1.05): then both frames refuse the same way, with the same reason, and the fabric still mirrors
    assert t["reason"] == t0["reason"]
    assert _ang_close(t["theta_fabric_deg"], -t0["theta_fabric_deg"], tol=1e-6)
    for key in ("theta_n_deg", "theta_t_deg"):
        if t0["reason"]:
            assert math.isnan(t[key]) and math.isnan(t0[key])
        else:
            assert _ang_close(t[key], -t0[key], tol=1e-6)


# ---- degenerate input -----------------------------------------------------------------------

def test_no_contacts():
    out = tensor_method([], [], [], []).iloc[0]
    assert math.isnan(out["a"]) and math.isnan(out["an"]) and "fewer than" in out["reason"]
    r = resultant_direction([], []).iloc[0]
    assert math.isnan(r["theta_r_deg"]) and r["reason"]


def test_one_contact():
    out = tensor_method([0.0], [1.0], [1.0], [0.0]).iloc[0]
    assert math.isnan(out["theta_n_deg"]) and "fewer than 2" in out["reason"]
    assert math.isnan(resultant_direction([0.0], [1.0]).iloc[0]["theta_r_deg"])


def test_all_zero_forces():
    theta = np.linspace(0, np.pi, 10, endpoint=False)
    out = tensor_method(np.cos(theta), np.sin(theta), np.zeros(10), np.zeros(10)).iloc[0]
    assert out["a"] == pytest.approx(0.0, abs=1e-12)      # the fabric is still defined
    assert math.isnan(out["an"]) and "f0" in out["reason"]
    r = resultant_direction(np.zeros(10), np.zeros(10)).iloc[0]
    assert math.isnan(r["theta_r_deg"]) and "zero" in r["reason"]


def test_nan_rows_dropped_and_counted():
    theta, fn, ft = random_contacts(3, 50)
    nx, nz = np.cos(theta), np.sin(theta)
    clean = tensor_method(nx, nz, fn, ft).iloc[0]
    fn2 = np.append(fn, [np.nan, 1.0])
    nx2, nz2, ft2 = np.append(nx, [1.0, 0.0]), np.append(nz, [0.0, 0.0]), np.append(ft, [0.0, 0.0])
    dirty = tensor_method(nx2, nz2, fn2, ft2).iloc[0]
    assert dirty["n_dropped"] == 2 and "dropped" in dirty["reason"]
    assert dirty["an"] == pytest.approx(clean["an"], rel=1e-12)
    all_nan = tensor_method([np.nan] * 4, [1.0] * 4, [1.0] * 4, [0.0] * 4).iloc[0]
    assert math.isnan(all_nan["a"]) and "fewer than" in all_nan["reason"]


def test_snapshot_without_surface_contacts_is_nan_with_reason():
    theta, fn, ft = random_contacts(1, 20)
    c0 = contacts_table(np.cos(theta), np.abs(np.sin(theta)), fn, ft, kind="ps", snapshot=0)
    c1 = contacts_table(np.cos(theta), np.sin(theta), fn, ft, kind="pp", snapshot=1)
    s = surface_anisotropy(pd.concat([c0, c1], ignore_index=True))
    assert list(s.index) == [0, 1]
    assert np.isfinite(s.loc[0, "theta_r_deg"])
    assert math.isnan(s.loc[1, "theta_r_deg"]) and "no particle–surface contacts" in s.loc[1, "reason"]


def test_missing_column_is_named():
    theta, fn, ft = random_contacts(1, 5)
    c = contacts_table(np.cos(theta), np.sin(theta), fn, ft).drop(columns="ft")
    with pytest.raises(MissingColumnError, match="ft"):
        surface_anisotropy(c)
    with pytest.raises(MissingColumnError, match="ft"):
        region_anisotropy(c, (0, 1, 0, 1))


def test_region_selects_contact_points_inside():
    theta, fn, ft = random_contacts(5, 40)
    a = contacts_table(np.cos(theta), np.sin(theta), fn, ft, centre=(0.5, 0.5))
    b = contacts_table(np.cos(theta + 1), np.sin(theta + 1), fn * 3, ft, centre=(5.0, 5.0))
    both = pd.concat([a, b], ignore_index=True)
    only_a = region_anisotropy(both, (0.0, 1.0, 0.0, 1.0)).iloc[0]
    ref = tensor_method(a["nx"], a["nz"], a["fn"], a["ft"]).iloc[0]
    assert only_a["n_contacts"] == 40
    assert only_a["an"] == pytest.approx(ref["an"], rel=1e-12)
    assert np.isfinite(only_a["qp_sff"])
