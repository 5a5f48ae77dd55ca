"""Average stress (docs/methods.md §6): the lattice example at arbitrary offsets, clipping, readings,
the model q/p, the sampling rectangle and degenerate input."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from interphase.analysis.stress import average_stress, clip_fraction, sampling_rectangle, stress_readings, trace_top
from interphase.case import Case
from interphase.surface.spec import ProfileSpec
from interphase.tables import MissingColumnError

D = 0.5   # lattice spacing: a power of two keeps node coordinates exact


def lattice(Fx, Fz, T, n=40):
    """Square lattice of spacing D over [−5D, (n−5)D]²: horizontal contacts carry (Fx, T), vertical
    ones (T, Fz), force on body 2, branch from node to node."""
    i, j = np.meshgrid(np.arange(-5, n - 5), np.arange(-5, n - 5), indexing="ij")
    x, z = (i * D).ravel(), (j * D).ravel()
    h = pd.DataFrame(dict(snapshot=0, kind="pp", x1=x, z1=z, x2=x + D, z2=z, fx=Fx, fz=T))
    v = pd.DataFrame(dict(snapshot=0, kind="pp", x1=x, z1=z, x2=x, z2=z + D, fx=T, fz=Fz))
    return pd.concat([h, v], ignore_index=True)


@settings(max_examples=60, deadline=None)
# offsets keep the edges off the lattice lines: an edge within rounding of a line of contacts is a
# tie between the half-open bounds (oz = 2.2e-16 dropped one row); the aligned case is tested below
@given(ox=st.floats(1e-6, 1 - 1e-6), oz=st.floats(1e-6, 1 - 1e-6), nx=st.integers(1, 12), nz=st.integers(1, 12),
       Fx=st.floats(-5, 5), Fz=st.floats(0.1, 5), T=st.floats(-3, 3))
def test_lattice_any_offset(ox, oz, nx, nz, Fx, Fz, T):
    rect = (ox * D + 2 * D, ox * D + (2 + nx) * D, oz * D + 1 * D, oz * D + (1 + nz) * D)
    s = average_stress(lattice(Fx, Fz, T), rect).iloc[0]
    assert s["sxx"] * D == pytest.approx(Fx, abs=1e-9)
    assert s["szz"] * D == pytest.approx(Fz, abs=1e-9)
    assert s["sxz"] * D == pytest.approx(T, abs=1e-9)


@pytest.mark.parametrize("off", [0.0, 0.25, 0.37])
def test_lattice_aligned_and_offset(off):
    rect = (off, off + 6 * D, 2 * off, 2 * off + 9 * D)
    s = average_stress(lattice(3.0, 5.0, 0.7), rect).iloc[0]
    assert [s["sxx"] * D, s["szz"] * D, s["sxz"] * D] == pytest.approx([3.0, 5.0, 0.7], abs=1e-12)


def test_clip_fraction_cases():
    rect = (0.0, 1.0, 0.0, 1.0)
    x0 = np.array([0.2, -1.0, 0.5, 2.0, 0.5, -0.5, 0.5])
    z0 = np.array([0.2, 0.5, 0.5, 2.0, -1.0, -0.5, 0.5])
    lx = np.array([0.1, 3.0, 1.0, 1.0, 0.0, 2.0, 0.0])
    lz = np.array([0.1, 0.0, 0.0, 1.0, 4.0, 2.0, 0.0])
    expect = [1.0, 1 / 3, 0.5, 0.0, 0.25, 0.5, 1.0]
    assert clip_fraction(x0, z0, lx, lz, rect) == pytest.approx(expect, abs=1e-15)
    # reversing every segment keeps the inside share
    assert clip_fraction(x0 + lx, z0 + lz, -lx, -lz, rect) == pytest.approx(expect, abs=1e-15)


def test_readings_sign_and_principal():
    # force chains leaning up-left (ψ = 30°): compression along m = (−sin30, cos30)
    m = np.array([-math.sin(math.radians(30)), math.cos(math.radians(30))])
    sig = 2.0 * np.outer(m, m) + 0.5 * np.eye(2)
    r = stress_readings(sig[0, 0], sig[1, 1], sig[0, 1])
    assert float(r["principal_deg"]) == pytest.approx(30.0, abs=1e-10)
    assert float(r["stress_ratio"]) > 0             # −σxz/σzz: the resisting shear is positive
    assert float(r["qp"]) == pytest.approx(1.0 / 1.5, abs=1e-12)   # q = 1, p = 1.5


def test_model_stress_q_over_p():
    """Contacts of equal branch length with the model's weights folded into their forces: the stress
    tensor's q/p equals the stress–force–fabric value 0.548539 (exact for the model forms)."""
    th = np.arange(72) * np.pi / 36
    w = 1 + 0.4 * np.cos(2 * (th - math.radians(100)))
    fn = 1.7 * (1 + 0.6 * np.cos(2 * (th - math.radians(110))))
    ft = -1.7 * 0.25 * np.sin(2 * (th - math.radians(95)))
    nx, nz = np.cos(th), np.sin(th)
    fx, fz = w * (fn * nx - ft * nz), w * (fn * nz + ft * nx)
    c = pd.DataFrame(dict(snapshot=0, kind="pp", x1=-0.5 * nx, z1=-0.5 * nz, x2=0.5 * nx, z2=0.5 * nz, fx=fx, fz=fz))
    s = average_stress(c, (-1, 1, -1, 1)).iloc[0]
    assert s["qp"] == pytest.approx(0.548539, abs=5e-7)


def test_rotation_of_whole_assembly_rotates_principal_direction():
    rng = np.random.default_rng(2)
    n = 200
    x1, z1 = rng.uniform(-1, 1, (2, n))
    l = rng.normal(size=(2, n)) * 0.05
    f = rng.normal(size=(2, n)) + np.array([[0.3], [1.0]])
    c = pd.DataFrame(dict(snapshot=0, kind="pp", x1=x1, z1=z1, x2=x1 + l[0], z2=z1 + l[1], fx=f[0], fz=f[1]))
    beta = 0.4
    cb, sb = math.cos(beta), math.sin(beta)
    rot = lambda x, z: (cb * x - sb * z, sb * x + cb * z)  # noqa: E731
    r = c.copy()
    r["x1"], r["z1"] = rot(c["x1"], c["z1"])
    r["x2"], r["z2"] = rot(c["x2"], c["z2"])
    r["fx"], r["fz"] = rot(c["fx"], c["fz"])
    big = (-10, 10, -10, 10)
    a, b = average_stress(c, big).iloc[0], average_stress(r, big).iloc[0]
    d = (b["principal_deg"] - a["principal_deg"] - math.degrees(beta) + 90) % 180 - 90
    assert abs(d) < 1e-9
    assert b["qp"] == pytest.approx(a["qp"], rel=1e-12)


def test_degenerate_input():
    empty = pd.DataFrame(dict(snapshot=[], kind=[], x1=[], z1=[], x2=[], z2=[], fx=[], fz=[]))
    assert average_stress(empty, (0, 1, 0, 1)).empty
    c = lattice(1.0, 1.0, 0.0, n=8)
    out = average_stress(c, (100, 101, 100, 101)).iloc[0]
    assert math.isnan(out["sxx"]) and "no branch" in out["reason"]
    out = average_stress(c, (0, 0, 0, 1)).iloc[0]
    assert math.isnan(out["qp"]) and "no area" in out["reason"]
    zero = c.assign(fx=0.0, fz=0.0)
    out = average_stress(zero, (0, 1, 0, 1)).iloc[0]
    assert math.isnan(out["qp"]) and "p ≤ 0" in out["reason"]
    nanrow = c.copy()
    nanrow.loc[0, "fx"] = np.nan
    out = average_stress(nanrow, (-2.5, -1.5, -2.5, -1.5)).iloc[0]
    assert out["n_dropped"] == 1 and np.isfinite(out["sxx"])
    with pytest.raises(MissingColumnError, match="x2"):
        average_stress(c.drop(columns="x2"), (0, 1, 0, 1))


def test_long_branches_dropped():
    c = lattice(1.0, 2.0, 0.0, n=10)
    wrap = pd.DataFrame(dict(snapshot=[0], kind=["pp"], x1=[0.1], z1=[0.3], x2=[50.1], z2=[0.3], fx=[9.0], fz=[0.0]))
    both = pd.concat([c, wrap], ignore_index=True)
    rect = (0.0, 2 * D, 0.0, 2 * D)
    assert average_stress(both, rect, max_branch=2 * D).iloc[0]["sxx"] * D == pytest.approx(1.0, abs=1e-12)
    assert average_stress(both, rect).iloc[0]["sxx"] * D != pytest.approx(1.0, abs=1e-3)


def test_sampling_rectangle_from_case():
    case = Case(profile=ProfileSpec.make("sawtooth", rt=1, sw=2, sr=0), d50=0.7e-3)
    z0 = trace_top(case)
    assert z0 == pytest.approx(0.7e-3 + 0.35e-3, rel=1e-12)    # peak height Rt = D50, plus D50/2
    rect = sampling_rectangle(case, z0)
    # the measuring window: 3 D50 off each side wall (Case.window)
    assert rect == pytest.approx((2.1e-3, case.box_length - 2.1e-3, z0, z0 + 14e-3), rel=1e-12)
    low = sampling_rectangle(case, z0, soil_top=z0 + 5e-3)
    assert low[3] == pytest.approx(z0 + 5e-3)
