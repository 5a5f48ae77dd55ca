"""Strength (docs/methods.md §6): stress ratio signs, peak under noise, residual, dilation, efficiency,
inertial number, shear rate and shear band."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from interphase.analysis import strength as st
from interphase.tables import MissingColumnError


def history(shear_disp, ratio, normal=1.0, platen_z=None):
    s = np.asarray(shear_disp, dtype=float)
    return pd.DataFrame({
        "time": s / 0.05, "shear_disp": s, "surface_fx": np.asarray(ratio) * normal,
        "surface_fz": -np.full(s.size, normal), "normal_force": np.full(s.size, normal),
        "platen_z": np.zeros(s.size) if platen_z is None else platen_z, "n_contacts": 100,
        "window_fx": np.asarray(ratio) * normal, "window_fz": -np.full(s.size, normal),
    })


def test_surface_ratio_sign_and_box_ratio():
    h = history([0, 1e-4], [0.3, 0.4], normal=2.0)
    assert st.surface_stress_ratio(h).tolist() == pytest.approx([0.3, 0.4])
    # box: the plane's own forces (lower half), not the platen's, which side-wall friction unloads
    assert st.box_stress_ratio(h.assign(normal_force=-5.0)).tolist() == pytest.approx([0.3, 0.4])
    assert st.box_stress_ratio(h.assign(surface_fz=-4.0)).tolist() == pytest.approx([0.15, 0.2])
    assert math.isnan(st.box_stress_ratio(h.assign(surface_fz=0.0)).iloc[0])
    # no compressive normal force on the surface: undefined, not infinite
    assert math.isnan(st.surface_stress_ratio(h.assign(window_fz=0.0)).iloc[0])
    # the ratio is the measuring window's (Case.window), not the whole surface's
    assert st.surface_stress_ratio(h.assign(surface_fx=9.0)).tolist() == pytest.approx([0.3, 0.4])


def test_peak_robust_to_noise():
    s = np.linspace(0, 3e-3, 3001)
    clean = 0.6 * (s / 1e-3) * np.exp(1 - s / 1e-3)          # peak 0.6 at 1 mm
    rng = np.random.default_rng(1)
    noisy = clean + 0.05 * rng.standard_normal(s.size)
    p = st.find_peak(s, noisy, window=0.35e-3)
    assert p.value == pytest.approx(0.6, abs=0.01)
    assert p.shear_disp == pytest.approx(1e-3, abs=0.1e-3)
    assert p.raw_max > p.value + 0.05                            # the raw maximum rides on the noise
    # unsorted rows give the same peak
    perm = rng.permutation(s.size)
    q = st.find_peak(s[perm], noisy[perm], window=0.35e-3)
    assert (q.value, q.shear_disp) == pytest.approx((p.value, p.shear_disp))
    assert noisy[perm][q.index] == pytest.approx(noisy[p.index])


def test_moving_average_exact_on_linear_and_skips_nan():
    x = np.linspace(0, 1, 101)
    y = 2 * x + 1
    m = st.moving_average(x, y, 0.2)
    assert m[20:-20] == pytest.approx(y[20:-20], abs=1e-12)
    y[50] = np.nan
    assert st.moving_average(x, y, 0.2)[50] == pytest.approx(2 * 0.5 + 1, abs=1e-12)


def test_peak_degenerate():
    p = st.find_peak([0, 1, 2], [np.nan] * 3, 0.5)
    assert math.isnan(p.value) and p.reason
    p = st.find_peak([], [], 0.5)
    assert math.isnan(p.value)


def test_residual_and_dilation():
    s = np.linspace(0, 1e-3, 11)
    r = np.r_[np.linspace(0, 0.6, 6), [0.5, 0.45, 0.4, 0.4, 0.4]]
    assert st.residual_ratio(s, r) == pytest.approx(0.4)
    h = history(s, r, platen_z=1e-2 + 0.5 * s)
    assert st.dilation(h, 0.5e-3) == pytest.approx(0.25e-3, rel=1e-9)


def test_load_balance_mask():
    h = history([0, 1, 2], [0.1, 0.2, 0.3])
    h["surface_fz"] = [-1.0, -1.2, -2.0]
    assert st.load_balanced(h).tolist() == [True, True, False]
    assert st.load_balanced(h, None).tolist() == [True, True, True]
    # the whole surface against the platen: how the window's part of it shares the load is free
    h["window_fz"] = [-0.1, -0.9, -1.9]
    assert st.load_balanced(h).tolist() == [True, True, False]


def test_efficiency_example():
    assert st.efficiency(math.tan(math.radians(25)), math.tan(math.radians(35))) == pytest.approx(0.66595, abs=1e-5)
    assert math.isnan(st.efficiency(0.5, 0.0))
    assert st.efficiency_from_rows({"peak_stress_ratio": 0.35}, {"peak_stress_ratio": 0.7}) == pytest.approx(0.5)


def test_inertial_number_example():
    gamma = 1e-3 / 10e-3                                        # 1 mm/s over a 10 mm band
    assert st.inertial_number(gamma, 1e-3, 100e3, 2650.0) == pytest.approx(1.63e-5, rel=2e-3)
    assert st.inertial_number(gamma, 1e-3, 100e3, 2650.0) < st.QUASI_STATIC_I
    for bad in ((gamma, 1e-3, 0.0, 2650.0), (gamma, -1e-3, 1e5, 2650.0), (np.nan, 1e-3, 1e5, 2650.0)):
        assert math.isnan(st.inertial_number(*bad))


def particles_linear(v_surface=-1e-3, T=10e-3, n_layers=40, snapshots=2, ds=0.1e-3, d=0.5e-3):
    """Grains on layers z = (k+½)·d with a linear profile: vx = v_surface·(1 − z/T) below T, 0 above;
    x displacement between snapshots −ds·(1 − z/T)₊ (the surface moves −x relative to the soil)."""
    rows = []
    z = (np.arange(n_layers) + 0.5) * d
    U = np.clip(1 - z / T, 0, None)
    for k in range(snapshots):
        for copy in range(3):
            rows.append(pd.DataFrame({
                "snapshot": k, "time": k * ds / 0.05, "shear_disp": k * ds, "id": np.arange(z.size) + 1000 * copy,
                "x": copy * 1e-3 - k * ds * U, "z": z, "vx": v_surface * U, "vz": 0.0, "radius": d / 2,
            }))
    return pd.concat(rows, ignore_index=True)


def test_shear_rate_from_profile():
    p = particles_linear()
    assert st.shear_rate_from_profile(p, method="max") == pytest.approx(1e-3 / 10e-3, rel=1e-9)
    # band average between the lowest and highest layers
    lo, hi = 0.25e-3, 19.75e-3
    expect = abs(-1e-3 * (1 - lo / 10e-3) - 0.0) / (hi - lo)
    assert st.shear_rate_from_profile(p, method="mean") == pytest.approx(expect, rel=1e-9)
    assert math.isnan(st.shear_rate_from_profile(p.iloc[:0]))


def test_shear_band_linear_profile():
    T = 7e-3
    z = np.linspace(0, 12e-3, 49)
    U = np.clip(1 - z / T, 0, None)
    assert st.shear_band_thickness(z, U, 0.0, 1e-3) == pytest.approx(0.9 * T / 1e-3, abs=1e-12)
    assert st.shear_band_thickness(z + 2e-3, U, 2e-3, 0.7e-3) == pytest.approx(0.9 * T / 0.7e-3, abs=1e-9)


def test_shear_band_from_particles():
    d = 0.5e-3
    p = particles_linear(T=10e-3, d=d)
    prof = st.displacement_profile(p, 0, 1, z_ref=0.0)
    band = st.shear_band_thickness(prof["z"], prof["U"], 0.0, d)
    assert band == pytest.approx(0.9 * 10e-3 / d, abs=1e-9)


def test_shear_band_across_a_periodic_boundary():
    """Grains that cross the cell's x boundary between the snapshots jump by one period; read with
    the period they count with their true displacement, and the band is the one without the jump."""
    d, L = 0.5e-3, 40e-3
    p = particles_linear(T=10e-3, d=d)
    late = p["snapshot"] == 1
    crossed = late & (p["id"] % 7 == 0)              # every 7th grain wrapped to the other side
    p.loc[crossed, "x"] += L
    wrapped = st.displacement_profile(p, 0, 1, z_ref=0.0)
    band = st.shear_band_thickness(wrapped["z"], wrapped["U"], 0.0, d)
    assert not band == pytest.approx(0.9 * 10e-3 / d, abs=1e-3)      # the jump corrupts the profile
    prof = st.displacement_profile(p, 0, 1, z_ref=0.0, period=L)
    band = st.shear_band_thickness(prof["z"], prof["U"], 0.0, d)
    assert band == pytest.approx(0.9 * 10e-3 / d, abs=1e-9)


def test_shear_band_degenerate():
    z = np.linspace(0, 1, 11)
    t, why = st.shear_band(z, np.full(11, 0.05), 0.0, 0.1)
    assert math.isnan(t) and "slips" in why
    t, why = st.shear_band(z, np.full(11, 0.9), 0.0, 0.1)
    assert math.isnan(t) and "thicker" in why
    assert math.isnan(st.shear_band_thickness([0.0], [1.0], 0.0, 0.1))


def test_missing_columns_named():
    with pytest.raises(MissingColumnError, match="window_fz"):
        st.surface_stress_ratio(pd.DataFrame({"window_fx": [1.0]}))
    with pytest.raises(MissingColumnError, match="vx"):
        st.velocity_profile(pd.DataFrame({"snapshot": [0], "z": [0.0], "radius": [1.0]}))


def test_peak_snapshot_on_a_plateau_is_a_sheared_state():
    """Flat sliding: the ratio rises to 0.2 within 0.05 mm and stays; noise puts the maximum at
    0.1 mm, nearest to the start-of-shear snapshot. The peak state must be a sheared snapshot."""
    s = np.linspace(0, 2e-3, 401)
    r = np.minimum(s / 5e-5, 1.0) * 0.2
    r[20] += 1e-3                                  # the maximum at 0.1 mm
    peak = st.find_peak(s, r, 0.0)
    assert peak.shear_disp == pytest.approx(1e-4)
    snaps = np.array([1.5e-5, 5e-4, 1e-3, 1.5e-3, 2e-3])
    assert st.peak_snapshot(snaps, s, r, peak) == 1
    # a sharp peak: the nearest snapshot even if the ratio there has dropped (no snapshot near it)
    r2 = 0.2 + 0.3 * np.exp(-((s - 7e-4) / 3e-5) ** 2)
    p2 = st.find_peak(s, r2, 0.0)
    assert st.peak_snapshot(snaps, s, r2, p2) == 1
    assert st.peak_snapshot(snaps, s, np.full_like(s, np.nan), st.find_peak(s, np.full_like(s, np.nan), 0.0)) is None
