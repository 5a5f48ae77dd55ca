"""docs/methods.md §2–4 test values: centroid trace, θa (both filters), Rn, and the invariances."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from interphase.surface.normals import principal_direction, segment_normals, theta_a, theta_a_filters
from interphase.surface.profiles import Profile, flat, random_profile, sawtooth
from interphase.surface.roughness import rn
from interphase.surface.trace import centroid_trace, dilate_half_disk

D50 = 0.7e-3

# docs/methods.md §3 table: α, h/D50, ψa (≥ 90°), ψa (> 92°)
TABLE = [(45, 1, 38.94, 39.35), (30, 1, 28.15, 28.36), (60, 1, 41.71, 42.49),
         (45, 0.5, 30.66, 31.50), (45, 2, 42.23, 42.42)]


def saw(alpha_deg, h, periods=3):
    sw = 2 * h / math.tan(math.radians(alpha_deg))
    return sawtooth(h, sw, 0.0, d50=D50, periods=periods)


def closed_form(alpha_deg, h, eps_deg):
    """ψa of docs/methods.md §3 from Lf and r (D50 units)."""
    a, e, r = math.radians(alpha_deg), math.radians(eps_deg), 0.5
    lf = h / math.sin(a) - r * math.tan(a)
    return math.degrees(a / 2 + 0.5 * math.atan2(lf * math.sin(a) + r * math.sin(a - e) * math.sin(e),
                                                 lf * math.cos(a) + r * math.sin(a - e) * math.cos(e)))


@pytest.mark.parametrize("alpha,h,psi90,psi92", TABLE)
def test_sawtooth_theta_a_table(alpha, h, psi90, psi92):
    for periods in (1, 3, 7):
        p = saw(alpha, h, periods)
        assert theta_a(p, D50, 90).theta_a_deg == pytest.approx(psi90, abs=0.05)
        assert theta_a(p, D50, 92).theta_a_deg == pytest.approx(psi92, abs=0.05)


@pytest.mark.parametrize("alpha,h,psi90,psi92", TABLE)
def test_closed_form_reproduces_table(alpha, h, psi90, psi92):
    assert closed_form(alpha, h, 0.0) == pytest.approx(psi90, abs=0.006)
    assert closed_form(alpha, h, 2.0) == pytest.approx(psi92, abs=0.006)


def test_ccw_reading_is_psi_plus_90():
    res = theta_a(saw(45, 1), D50, 92)
    assert res.theta_a_ccw_deg == pytest.approx(res.theta_a_deg + 90.0, abs=1e-9)
    assert res.dilative and res.reason == ""


def test_trace_amplitude_and_shape_45deg():
    p = saw(45, 1)
    tr = centroid_trace(p, D50)
    amp = (tr.z.max() - tr.z.min()) / D50
    r, a = 0.5, math.radians(45)
    assert amp == pytest.approx(1 + r - r / math.cos(a), abs=2e-4)   # 0.7929
    assert amp == pytest.approx(0.7929, abs=2e-4)
    # straight runs parallel to the faces: most segment normals are ±45° from vertical
    th, w = segment_normals(tr)
    on_face = np.isclose(np.abs(np.degrees(th) - 90), 45, atol=0.5)
    lf = 1 / math.sin(a) - r * math.tan(a)
    share_faces = 2 * lf / (2 * lf + r * 2 * a)    # per period: two runs + one arc of angle 2α
    assert w[on_face].sum() / w.sum() == pytest.approx(share_faces, abs=0.01)


def test_trace_is_a_dilation_not_a_closing():
    # a single narrow spike: a closing would leave the profile unchanged at the spike; the dilation
    # lifts the whole neighbourhood by up to r
    x = np.linspace(0, 10 * D50, 2001)
    z = np.where(np.abs(x - 5 * D50) < 1e-9, D50, 0.0)
    tr = centroid_trace(Profile(x, z, periodic=False), D50)
    assert tr.z.min() == pytest.approx(D50 / 2, rel=1e-3)
    assert tr.z.max() == pytest.approx(1.5 * D50, rel=1e-3)


def test_dilation_matches_bruteforce_on_random_profiles():
    rng = np.random.default_rng(7)
    for periodic in (False, True):
        z = np.cumsum(rng.normal(size=400))
        R = 23.7
        got = dilate_half_disk(z, R, periodic)
        K = int(R)
        u = np.arange(-K, K + 1)
        idx = np.arange(400)[:, None] + u[None, :]
        if periodic:
            brute = (z[idx % 400] + np.sqrt(R * R - u * u)).max(axis=1)
        else:
            brute = (z[idx[K:400 - K]] + np.sqrt(R * R - u * u)).max(axis=1)
        np.testing.assert_allclose(got, brute, rtol=0, atol=1e-12)


def test_raw_profile_gives_alpha_and_no_filter_gives_zero():
    for alpha in (30, 45, 60):
        p = saw(alpha, 1)
        th, w = segment_normals(p)
        keep = th > math.radians(92)
        assert math.degrees(principal_direction(th[keep], w[keep])) - 90 == pytest.approx(alpha, abs=1e-9)
        tr = centroid_trace(p, D50)
        th, w = segment_normals(tr)
        psi_all = math.degrees(principal_direction(th, w)) - 90
        assert abs((psi_all + 90) % 180 - 90) < 1e-6


def test_flat_is_non_dilative():
    res = theta_a(flat(20 * D50), D50, 92)
    assert math.isnan(res.theta_a_deg) and not res.dilative
    assert "non-dilative" in res.reason
    assert math.isnan(theta_a(flat(20 * D50), D50, 90).theta_a_deg)


def test_rn_triangle_wave():
    # α = 45°, h = D50: Rn = 0.75
    assert rn(saw(45, 1), D50) == pytest.approx(0.75, abs=2e-3)

    def formula(ell):
        if ell <= 1:
            return ell * (1 - ell / 4)
        if ell <= 2:
            return (ell - 1) + (2 - ell) * (ell / 4 + 0.5)
        return 1.0

    for period_d50 in (0.8, 1.5, 2.0, 3.0, 5.0):   # ℓ = 2L/λ = 2.5, 1.33, 1, 0.67, 0.4
        p = sawtooth(1.0, period_d50, 0.0, d50=D50, periods=4)
        assert rn(p, D50) == pytest.approx(formula(2 / period_d50), abs=3e-3)


def test_rnc_is_rn_of_trace():
    p = saw(45, 1)
    res = theta_a(p, D50, 92)
    assert res.rnc == pytest.approx(rn(centroid_trace(p, D50), D50))
    assert res.rnc < res.rn   # the trace smooths the profile


def test_mean_slope_excludes_flats():
    p = sawtooth(1, 2, 3, d50=D50, periods=3)   # spaced 45° triangles
    assert theta_a(p, D50, 90).mean_slope_deg == pytest.approx(45.0, abs=1e-9)


# ---- invariances (hypothesis) ---------------------------------------------------------------
@settings(max_examples=15, deadline=None)
@given(st.floats(0.3, 2.0), st.floats(0.8, 4.0), st.floats(0.0, 2.0), st.floats(0.0, 1.0))
def test_phase_shift_invariance(rt, sw, sr, phase):
    p = sawtooth(rt, sw, sr, d50=D50, periods=3)
    P = p.length
    shift = phase * P / 3
    # the same periodic surface seen from another origin: z_s(x) = z(x + shift)
    xs = (p.x[:-1] - p.x[0] - shift) % P
    order = np.argsort(xs)
    xs, zs = xs[order], p.z[:-1][order]
    z0 = np.interp(shift, p.x - p.x[0], p.z)
    keep = (xs > 1e-12 * P) & (xs < P * (1 - 1e-12))
    shifted = Profile(np.concatenate([[0.0], xs[keep], [P]]), np.concatenate([[z0], zs[keep], [z0]]), periodic=True)
    a, b = theta_a(p, D50, 92), theta_a(shifted, D50, 92)
    assert b.theta_a_deg == pytest.approx(a.theta_a_deg, abs=0.05)
    assert b.rnc == pytest.approx(a.rnc, abs=5e-3)


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 10_000))
def test_mirror_with_shear_sign_flipped(seed):
    p = random_profile(2, 1, 2, d50=D50, length=30 * D50, seed=seed)
    # shearing the other way = mirroring x: the resisting side becomes the faces rising toward −x
    m = p.mirrored()
    a = theta_a(p, D50, 92)
    b = theta_a(m.mirrored(), D50, 92)
    assert b.theta_a_deg == pytest.approx(a.theta_a_deg, abs=1e-9)
    # the trace commutes with the mirror: trace(mirror(p)) = mirror(trace(p))
    x = np.linspace(0, p.length, 6001)
    q = Profile(x, np.interp(x, p.x - p.x[0], p.z))
    np.testing.assert_allclose(centroid_trace(q.mirrored(), D50).z, centroid_trace(q, D50).z[::-1], atol=1e-15)


@settings(max_examples=10, deadline=None)
@given(st.floats(0.1, 10.0), st.sampled_from([(45, 1), (30, 1), (60, 1)]))
def test_scaling_x_z_d50_together(scale, shape):
    p = saw(*shape)
    a = theta_a(p, D50, 92)
    b = theta_a(p.scaled(scale), D50 * scale, 92)
    assert b.theta_a_deg == pytest.approx(a.theta_a_deg, abs=1e-6)
    assert b.rn == pytest.approx(a.rn, abs=1e-6)


def test_both_filters_from_one_trace_equal_the_single_filter_calls():
    p = random_profile(2, 1, 2, d50=D50, length=30 * D50, seed=4)
    both = theta_a_filters(p, D50, (92, 90))
    assert both[92] == theta_a(p, D50, 92) and both[90] == theta_a(p, D50, 90)


@pytest.mark.parametrize("rt, sw, sr", [(1, 2, 0), (1, 2, 2), (0.5, 0.4, 0.3)])
def test_one_period_of_a_sawtooth_gives_the_whole_profiles_values(rt, sw, sr):
    """The summary computes θa on one period (analysis.summary._profile_features)."""
    whole = theta_a_filters(sawtooth(rt, sw, sr, d50=D50, length=50 * D50), D50)
    one = theta_a_filters(sawtooth(rt, sw, sr, d50=D50, periods=1), D50)
    for f in (92, 90):
        for key in ("theta_a_deg", "rn", "rnc", "mean_slope_deg"):
            assert getattr(one[f], key) == pytest.approx(getattr(whole[f], key), rel=1e-9, abs=1e-9)


def test_an_asymmetric_tooth_with_equal_flanks_is_the_sawtooth():
    from interphase.surface.profiles import asymmetric_sawtooth

    for sr in (0.0, 1.5):
        a = asymmetric_sawtooth(0.3, 1.0, 1.0, sr, d50=D50, periods=4)
        s = sawtooth(0.3, 2.0, sr, d50=D50, periods=4)
        np.testing.assert_allclose(a.x, s.x, rtol=0, atol=1e-15)
        np.testing.assert_allclose(a.z, s.z, rtol=0, atol=1e-15)


@pytest.mark.parametrize("rt,rise,fall", [(0.25, 0.5, 1.5), (0.1, 0.3, 1.7), (0.5, 1.0, 3.0)])
def test_an_asymmetric_tooth_reads_its_loaded_flank(rt, rise, fall):
    """θa follows the flank the grains climb: the steep-loaded tooth reads more than the symmetric one
    of the same height and period, the gentle-loaded one less; and the tooth sheared the other way
    (the profile mirrored) is the tooth with its flanks swapped."""
    from interphase.surface.profiles import asymmetric_sawtooth

    steep = asymmetric_sawtooth(rt, rise, fall, d50=D50, periods=5)
    gentle = asymmetric_sawtooth(rt, fall, rise, d50=D50, periods=5)
    sym = sawtooth(rt, rise + fall, 0.0, d50=D50, periods=5)
    t = {k: theta_a(p, D50).theta_a_deg for k, p in (("steep", steep), ("gentle", gentle), ("sym", sym))}
    assert t["steep"] > t["sym"] > t["gentle"] > 0
    assert t["steep"] < math.degrees(math.atan(rt / rise))
    mirrored = Profile(steep.x[-1] - steep.x[::-1], steep.z[::-1], periodic=True)
    assert theta_a(mirrored, D50).theta_a_deg == pytest.approx(t["gentle"], abs=1e-9)
