"""θa of areal scans (surface/areal.py) against an independent implementation of the rule.

The rule (docs/methods.md, "Areal scans"): every grid line along the shear axis is split at missing
points into valid runs; runs shorter than 5·D50 are dropped; each run is levelled by its own
least-squares line; the centroid traces' normals of all runs are pooled and θa is their principal
direction over the normals beyond the filter. `reference` below does the same with a different
code path: a Python loop over lines and runs of the raw array, np.split / np.polyfit / np.interp,
and the dilation as a brute-force max over sliding windows.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numpy.lib.stride_tricks import sliding_window_view

from interphase.surface.areal import dilate_blocks, theta_a_lines, theta_a_scan
from interphase.surface.normals import theta_a_filters
from interphase.surface.profiles import Profile
from interphase.surface.readers import read_scan
from interphase.surface.trace import dilate_half_disk

DATA = Path(__file__).parent / "data" / "profiles"


def reference(x: np.ndarray, H: np.ndarray, d50: float, dx: float, sign: int = 1, filt_deg: float = 92.0):
    """(pooled ψa [deg], per-run ψa list, runs used, runs dropped) for lines H (n_lines, n) along x."""
    h = x[1] - x[0]
    total = 0j
    per_run, used, dropped = [], 0, 0
    R = d50 / 2
    K = int(math.floor(R / dx))
    hk = np.sqrt(np.maximum(R * R - (np.arange(-K, K + 1) * dx) ** 2, 0))
    for row in H:
        idx = np.flatnonzero(np.isfinite(row))
        if idx.size == 0:
            continue
        for g in np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1):
            if (g.size - 1) * h < 5 * d50 * (1 - 1e-9):
                dropped += 1
                continue
            used += 1
            xs = x[g] - x[g[0]]
            zs = row[g]
            b, a = np.polyfit(xs, zs, 1)
            zs = zs - (a + b * xs)
            if sign < 0:
                xs, zs = xs[-1] - xs[::-1], zs[::-1]
            n = int(round(xs[-1] / dx))
            xf = np.arange(n + 1) * dx
            zf = np.interp(xf, xs, zs)
            c = (sliding_window_view(zf, 2 * K + 1) + hk).max(axis=1)
            dcz = np.diff(c)
            th = np.arctan2(dx, -dcz)
            w = np.hypot(dx, dcz)
            keep = th > math.radians(filt_deg)
            s = np.sum(w[keep] * np.exp(2j * th[keep]))
            total += s
            if keep.any():
                per_run.append(math.degrees(np.mod(np.angle(s) / 2, np.pi)) - 90)
    psi = math.degrees(np.mod(np.angle(total) / 2, np.pi)) - 90 if total != 0 else math.nan
    return psi, per_run, used, dropped


FRT1 = Path(__file__).parents[1] / "campaigns" / "profiles" / "frt-1.frt"


@pytest.fixture(scope="module")
def frt2():
    return read_scan(DATA / "frt-2.frt")


@pytest.fixture(scope="module")
def frt1():
    return read_scan(FRT1)


@pytest.mark.parametrize("sign", [1, -1])
@pytest.mark.parametrize("name,every,d50,dx,min_dilative", [
    ("frt1", 5, 0.2e-3, 2e-6, 10),     # 500 × 500 over 12 mm, 31 % missing: every 5th line along x
    ("frt2", 1, 0.2e-3, 2e-6, 2),      # 150 × 300 over 30 × 60 mm, 27 % missing: all 300 lines along x
])
def test_real_scan_with_missing_points_matches_the_independent_rule(request, name, every, d50, dx, min_dilative,
                                                                    sign):
    scan = request.getfixturevalue(name)
    s, Z = scan.lines("x")
    Z = Z[::every]
    assert np.isnan(Z).mean() > 0.2
    res = theta_a_lines(s, Z, d50, (92,), dx=dx)["+" if sign > 0 else "-"][92]
    psi, per_run, used, dropped = reference(s, Z, d50, dx, sign)
    assert res.step == pytest.approx(dx)
    assert (res.n_runs, res.n_dropped) == (used, dropped)
    assert res.n_runs_dilative == len(per_run) >= min_dilative
    assert res.dilative and abs(res.theta_a_deg - psi) < 0.3
    lo, hi = np.percentile(per_run, [5, 95])
    assert res.spread_deg[0] == pytest.approx(lo, abs=0.3) and res.spread_deg[1] == pytest.approx(hi, abs=0.3)


def test_four_directions_come_from_two_axes_and_their_mirrors(frt2):
    d50 = 0.2e-3
    res = theta_a_scan(frt2, d50, (92,))
    assert set(res) == {"+x", "-x", "+y", "-y"}
    # −y is +y of the scan flipped along y; +y read on the transposed scan is +x
    s, Z = frt2.lines("y")
    flipped = theta_a_lines(s, Z[:, ::-1], d50, (92,))["+"][92]
    assert flipped.theta_a_deg == pytest.approx(res["-y"][92].theta_a_deg, abs=1e-6)
    assert res["+y"][92].n_lines == 150 and res["+x"][92].n_lines == 300


def test_identical_lines_pool_to_the_single_line_value():
    """A scan whose lines are one saw-tooth-and-noise profile: pooled θa, Rn, Rnc, slope are that line's."""
    d50 = 0.7e-3
    rng = np.random.default_rng(3)
    x = np.arange(400) * 25e-6
    z = 0.15e-3 * np.abs(((x / 1.4e-3) % 1) - 0.5) + rng.normal(0, 2e-6, x.size)
    z = z - np.polyval(np.polyfit(x, z, 1), x)
    dx = 25e-6 / 10
    one = theta_a_filters(Profile(x, z), d50, dx=dx)
    pooled = theta_a_lines(x, np.tile(z, (7, 1)), d50, dx=dx)["+"]
    for f in (92, 90):
        assert pooled[f].theta_a_deg == pytest.approx(one[f].theta_a_deg, abs=1e-6)
        assert pooled[f].spread_deg[0] == pytest.approx(one[f].theta_a_deg, abs=1e-6)
    assert pooled[92].rnc == pytest.approx(one[92].rnc, rel=0.02)
    assert pooled[92].rn == pytest.approx(one[92].rn, rel=0.02)
    assert pooled[92].mean_slope_deg == pytest.approx(one[92].mean_slope_deg, rel=1e-6)


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10_000), holes=st.floats(0.0, 0.02), n_lines=st.integers(1, 6))
def test_random_scans_with_holes_match_the_reference(seed, holes, n_lines):
    rng = np.random.default_rng(seed)
    d50, h, m = 0.5e-3, 50e-6, 8
    n = 200
    x = np.arange(n) * h
    H = np.cumsum(rng.normal(0, 8e-6, (n_lines, n)), axis=1) + 3e-5 * np.sin(x / 7e-4 + rng.uniform(0, 6))
    H[rng.random(H.shape) < holes] = np.nan
    try:
        res = theta_a_lines(x, H, d50, (92,), dx=h / m)
    except Exception as exc:       # no run long enough: the reference must agree there is none
        assert reference(x, H, d50, h / m)[2] == 0, exc
        return
    for sign, key in ((1, "+"), (-1, "-")):
        psi, per_run, used, dropped = reference(x, H, d50, h / m, sign)
        r = res[key][92]
        assert (r.n_runs, r.n_dropped, r.n_runs_dilative) == (used, dropped, len(per_run))
        if math.isnan(psi):
            assert not r.dilative
        else:
            assert abs(r.theta_a_deg - psi) < 0.3


@pytest.mark.parametrize("n,R", [(5000, 20.3), (70000, 116.6), (1000, 3.0)])
def test_blocked_dilation_equals_the_trace_modules(n, R):
    z = np.random.default_rng(n).normal(size=n) * 5
    np.testing.assert_array_equal(dilate_blocks(z, R), dilate_half_disk(z, R, False))


def test_predict_reads_an_areal_scan_along_the_axis_it_is_sheared(capsys):
    """`campaign predict SCAN --axis x|y` on a real instrument scan (frt-1.frt, FRT MicroProf): θa is
    the one `campaign theta-a` reads for that direction (every grid line pooled), flat spacing is
    judged line by line and said so, δ comes with its interval; --axis on a line profile is refused,
    and --simulate (the quasi-2D DEM shears one line) says how to give one line of the scan."""
    import json

    from interphase.cli import main

    for axis in ("x", "y"):
        assert main(["theta-a", str(FRT1), "--d50", "0.7", "--axis", axis, "--json"]) == 0
        theta = json.loads(capsys.readouterr().out)["theta_a_deg"]
        assert main(["predict", str(FRT1), "--d50", "0.7", "--friction", "0.2", "--axis", axis, "--json",
                     "--fit", "study"]) == 0
        d = json.loads(capsys.readouterr().out)
        assert d["theta_a_deg_92"] == pytest.approx(theta, rel=1e-12) and math.isfinite(theta)
        assert f"lines along {axis}" in d["flat_spacing_reason"] and not d["flat_spaced"]
        assert d["delta_deg_lo"] < d["delta_deg"] < d["delta_deg_hi"]
    line = Path(__file__).parent / "data" / "dektak-1.csv"
    assert main(["predict", str(line), "--d50", "0.7", "--friction", "0.2", "--units", "um", "--axis", "y",
                 "--fit", "study"]) == 2
    assert "--axis" in capsys.readouterr().err
    card = Path(__file__).parents[1] / "soils" / "karlsruhe-fine-sand-2d.toml"
    assert main(["predict", str(FRT1), "--friction", "0.2", "--soil", str(card), "--simulate"]) == 2
    err = capsys.readouterr().err                     # the quasi-2D DEM shears one line: say how to give one
    assert "one line" in err and 'line = "1/3"' in err and "without --simulate" in err
