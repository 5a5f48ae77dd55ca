"""Further checks of the surface toolkit: the closed form away from the table, exactness of the
half-disk dilation, the mirror with the shear direction flipped on an asymmetric surface, repeated x
in measured files, why the Dektak trace is non-dilative at D50 = 0.7 mm, Gaussian filtering through
a ProfileSpec, the STL text LIGGGHTS reads, and more bad input (exit 2, one located message)."""

import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from interphase.cli import main
from interphase.surface.mesh import write_stl
from interphase.surface.normals import principal_direction, segment_normals, theta_a
from interphase.surface.builder import file_spec, from_spec
from interphase.surface.filters import prepare_measured
from interphase.surface.profiles import Profile, random_profile, sawtooth
from interphase.surface.readers import read_profile
from interphase.surface.roughness import rn
from interphase.surface.spec import ProfileSpec
from interphase.surface.trace import centroid_trace, dilate_half_disk

D50 = 0.7e-3


def closed_form_psi(alpha_deg, h, eps_deg, r=0.5):
    """docs/methods.md §3 closed form for a symmetric saw-tooth (h, r in D50 units), degrees."""
    a, e = math.radians(alpha_deg), math.radians(eps_deg)
    lf = h / math.sin(a) - r * math.tan(a)
    return math.degrees(a / 2 + 0.5 * math.atan2(lf * math.sin(a) + r * math.sin(a - e) * math.sin(e),
                                                 lf * math.cos(a) + r * math.sin(a - e) * math.cos(e)))


@pytest.mark.parametrize("alpha,h", [(20, 1.0), (35, 0.75), (50, 1.5), (55, 3.0)])
def test_code_matches_closed_form_away_from_the_table(alpha, h):
    p = sawtooth(h, 2 * h / math.tan(math.radians(alpha)), 0.0, d50=D50, periods=2)
    assert theta_a(p, D50, 90).theta_a_deg == pytest.approx(closed_form_psi(alpha, h, 0.0), abs=0.05)
    assert theta_a(p, D50, 92).theta_a_deg == pytest.approx(closed_form_psi(alpha, h, 2.0), abs=0.05)


def spaced_closed_form_psi(alpha_deg, h, sr, eps_deg, r=0.5):
    """Group 2 (flat spacing sr ≥ 2r·tan(α/2), D50 units), derived like docs/methods.md §3: the feet are
    concave corners, so the trace has cusps there; each face run shortens to Lf' = h/sinα − r·tan(α/2)
    and the flat run is Lflat = sr − 2r·tan(α/2) at ψ = 0, kept only by the ≥ 90° filter:
    ψa = ½·arg(e^{iα}[Lf'·e^{iα} + r·sin(α−ε)·e^{iε}] + [ε = 0]·Lflat)."""
    a, e = math.radians(alpha_deg), math.radians(eps_deg)
    t = math.tan(a / 2)
    lf, lflat = h / math.sin(a) - r * t, sr - 2 * r * t
    s = complex(math.cos(a), math.sin(a)) * (lf * complex(math.cos(a), math.sin(a))
                                             + r * math.sin(a - e) * complex(math.cos(e), math.sin(e)))
    if eps_deg == 0:
        s += lflat
    return math.degrees(math.atan2(s.imag, s.real)) / 2


@pytest.mark.parametrize("alpha,h,sr", [(45, 1, 1), (45, 1, 5), (30, 1, 3), (60, 1, 2)])
def test_flat_spaced_sawtooth_matches_its_closed_form(alpha, h, sr):
    p = sawtooth(h, 2 * h / math.tan(math.radians(alpha)), sr, d50=D50, periods=2)
    psi90, psi92 = theta_a(p, D50, 90).theta_a_deg, theta_a(p, D50, 92).theta_a_deg
    assert psi90 == pytest.approx(spaced_closed_form_psi(alpha, h, sr, 0.0), abs=0.05)
    assert psi92 == pytest.approx(spaced_closed_form_psi(alpha, h, sr, 2.0), abs=0.05)
    assert psi90 < psi92 - 5   # the flats pull the ≥ 90° reading toward vertical


# ---- the fast dilation is the naive max over shifts, exactly ---------------------------------
def naive_dilation(z, R, periodic):
    K = int(math.floor(R))
    n = z.size
    u = np.arange(-K, K + 1)
    disk = np.sqrt(np.maximum(R * R - u * u, 0.0))
    if periodic:
        return (z[(np.arange(n)[:, None] + u[None, :]) % n] + disk).max(axis=1)
    centres = np.arange(K, n - K)
    return (z[centres[:, None] + u[None, :]] + disk).max(axis=1)


@settings(max_examples=40, deadline=None)
@given(n=st.integers(5, 500), R=st.floats(0.5, 120.0), periodic=st.booleans(), seed=st.integers(0, 2**31),
       kind=st.sampled_from(["walk", "spikes", "steps"]))
def test_dilation_equals_naive_max(n, R, periodic, seed, kind):
    rng = np.random.default_rng(seed)
    if kind == "walk":
        z = np.cumsum(rng.normal(size=n)) * rng.uniform(0.01, 50)
    elif kind == "spikes":        # isolated tall points: the maximiser jumps between them
        z = np.where(rng.random(n) < 0.05, rng.uniform(0, 3 * R, n), 0.0)
    else:                         # plateaus: ties between many shifts
        z = np.repeat(rng.integers(0, 5, n // 7 + 1).astype(float), 7)[:n]
    if not periodic and n <= 2 * int(R):
        return                    # an open profile shorter than one grain is refused (tested below)
    np.testing.assert_allclose(dilate_half_disk(z, R, periodic), naive_dilation(z, R, periodic), rtol=0, atol=1e-9)


def test_open_profile_shorter_than_a_grain_is_refused():
    from interphase.errors import InputError

    with pytest.raises(InputError, match="shorter than one grain"):
        centroid_trace(Profile(np.linspace(0, 0.5 * D50, 50), np.zeros(50)), D50)


# ---- mirror with the shear direction flipped --------------------------------------------------
def asymmetric(steep=0.4, gentle=2.0, h=1.0, periods=3):
    """Periodic saw-tooth rising steeply toward +x over `steep`, falling over `gentle` (D50 units)."""
    x = (np.arange(periods)[:, None] * (steep + gentle) + np.array([0.0, steep])).ravel()
    x = np.append(x, periods * (steep + gentle)) * D50
    z = np.append(np.tile([0.0, h], periods), 0.0) * D50
    return Profile(x, z, periodic=True, name="asym")


def test_mirror_reads_the_other_faces():
    p = asymmetric()
    forward = theta_a(p, D50, 92).theta_a_deg         # soil moves +x: resists on the steep faces
    backward = theta_a(p.mirrored(), D50, 92).theta_a_deg   # surface sheared the other way
    assert forward > backward + 10    # the steep side resists forward, the gentle side backward
    # backward = the trace of p read on its other side (θ < 88°) and mirrored (θ → π − θ)
    th, w = segment_normals(centroid_trace(p, D50))
    other = th < math.radians(88.0)
    psi_other = math.degrees(principal_direction(math.pi - th[other], w[other])) - 90.0
    assert backward == pytest.approx(psi_other, abs=1e-6)


@settings(max_examples=8, deadline=None)
@given(st.integers(0, 10_000), st.floats(0.2, 5.0))
def test_open_profile_scaling_x_z_d50_together(seed, scale):
    p = random_profile(2, 1, 2, d50=D50, length=25 * D50, seed=seed)
    a, b = theta_a(p, D50, 92), theta_a(p.scaled(scale), D50 * scale, 92)
    assert b.theta_a_deg == pytest.approx(a.theta_a_deg, abs=1e-6)
    assert b.rnc == pytest.approx(a.rnc, abs=1e-9) and b.rn == pytest.approx(a.rn, abs=1e-9)


@settings(max_examples=200, deadline=None)
@given(n=st.integers(1, 400), w=st.integers(1, 400), seed=st.integers(0, 2**31), ties=st.booleans())
def test_running_max_and_min_equal_scipys_filters(n, w, seed, ties):
    """roughness.running (O(N) blocks, no scipy import in an engine run's summary) gives scipy.ndimage's
    maximum/minimum_filter1d over every full window, exactly, with or without tied values."""
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    from interphase.surface.roughness import running

    w = min(w, n)
    z = np.random.default_rng(seed).normal(size=n)
    z = z.round(0) if ties else z
    full = slice(0, n - w + 1)
    assert np.array_equal(running(z, w, np.maximum), maximum_filter1d(z, w, origin=-(w // 2))[full])
    assert np.array_equal(running(z, w, np.minimum), minimum_filter1d(z, w, origin=-(w // 2))[full])


def test_rn_ignores_a_linear_trend_on_open_profiles():
    p = random_profile(2, 1, 2, d50=D50, length=30 * D50, seed=3)
    tilted = Profile(p.x, p.z + 0.2 * p.x + 1e-3, periodic=False)
    assert rn(tilted, D50) == pytest.approx(rn(p, D50), abs=1e-3)
    assert rn(p, D50) > 0.3   # and is not trivially zero


# ---- measured files ----------------------------------------------------------------------------
def test_repeated_x_are_merged_to_their_mean(tmp_path):
    f = tmp_path / "rounded.csv"
    f.write_text("0.0,0.0\n0.1,1.0\n0.1,3.0\n0.2,0.0\n0.3,1.0\n")
    p = read_profile(f, units="um")
    np.testing.assert_allclose(p.x, [0, 0.1e-6, 0.2e-6, 0.3e-6], rtol=1e-12)
    np.testing.assert_allclose(p.z, [0, 2e-6, 0, 1e-6], rtol=1e-12)


def test_decreasing_x_is_still_refused(tmp_path, capsys):
    f = tmp_path / "back.txt"
    f.write_text("0 0\n1 1\n1 2\n0.5 3\n2 4\n")
    assert main(["theta-a", str(f), "--d50", "0.7"]) == 2
    err = capsys.readouterr().err
    assert "line 4" in err and "decreases" in err and str(f) in err


def test_dektak_is_non_dilative_because_its_relief_is_sub_micron(dektak_csv):
    p = prepare_measured(read_profile(dektak_csv))
    relief = p.z.max() - p.z.min()
    assert relief < 1e-6                       # < 1 µm of relief under a 700 µm grain
    res = theta_a(p, D50, 92)
    assert not res.dilative and res.max_tilt_deg < 2.0 and res.kept_fraction == 0.0
    # a disk of radius r over a bump of height h tilts its trace by at most ~sqrt(2h/r)
    assert math.radians(res.max_tilt_deg) < math.sqrt(2 * relief / (D50 / 2))
    # the same surface does dilate grains small enough to feel it
    tilts = [theta_a(p, d, 92).max_tilt_deg for d in (0.7e-3, 0.1e-3, 0.01e-3)]
    assert tilts[0] < tilts[1] < tilts[2]
    small = theta_a(p, 0.1e-3, 92)
    assert small.dilative and 0 < small.theta_a_deg < 10


def test_spec_cutoff_filters_the_measured_profile(dektak_csv):
    raw = from_spec(file_spec(dektak_csv, units="um"), D50, 1e-3)
    filt = from_spec(file_spec(dektak_csv, units="um", cutoff=80e-6), D50, 1e-3)
    assert raw.x[0] == 0 and filt.x[0] == 0 and filt.length >= 1e-3
    # λc = 80 µm removes the waviness: less height spread, and the filtered line has no trend
    assert 0 < np.std(filt.z) < 0.9 * np.std(raw.z)


# ---- STL text as LIGGGHTS reads it ------------------------------------------------------------
def test_stl_text_has_upward_facet_normals(tmp_path):
    p = from_spec(ProfileSpec.make("random", au=1, ar=1, rtmax=2, seed=5), D50, 10 * D50)
    text = write_stl(p, tmp_path / "r.stl", 0.0, D50).read_text()
    assert text.startswith("solid") and text.rstrip().endswith("endsolid")
    normals = np.array(re.findall(r"facet normal (\S+) (\S+) (\S+)", text), dtype=float)
    assert normals.shape == (2 * (p.x.size - 1), 3)
    assert np.all(normals[:, 2] > 0) and np.allclose(np.linalg.norm(normals, axis=1), 1)
    assert text.count("outer loop") == normals.shape[0] and text.count("vertex") == 3 * normals.shape[0]


# ---- CLI ---------------------------------------------------------------------------------------
def test_profile_random_file_roundtrip(tmp_path, capsys):
    out = tmp_path / "rand.txt"
    assert main(["profile", "random", "--au", "2", "--ar", "1", "--rtmax", "2", "--seed", "9",
                 "--length", "12", "-o", str(out)]) == 0
    assert out.read_text().startswith("# x_mm z_mm")
    back = read_profile(out, units="mm")
    ref = random_profile(2, 1, 2, d50=D50, length=12e-3, seed=9)
    np.testing.assert_allclose(back.x, ref.x, rtol=1e-8, atol=1e-15)
    np.testing.assert_allclose(back.z, ref.z, rtol=1e-8, atol=1e-15)


def test_theta_a_text_output_names_both_readings(tmp_path, capsys):
    out = tmp_path / "saw.txt"
    assert main(["profile", "sawtooth", "--rt", "1", "--sw", "2", "--length", "10", "-o", str(out)]) == 0
    capsys.readouterr()
    assert main(["theta-a", str(out), "--d50", "0.7", "--filter", "90"]) == 0
    text = capsys.readouterr().out
    psi, ccw = map(float, re.search(r"([\d.]+)° from vertical\s+\(([\d.]+)° ccw", text).groups())
    assert ccw == pytest.approx(psi + 90, abs=0.011)
    assert "Rn, Rnc" in text and "mean asperity slope" in text and "trace points" in text


@pytest.mark.parametrize("argv,needle", [
    (["profile", "spaced", "--rt", "1", "--sw", "2", "--sr", "1", "-o", "{tmp}/no/such/dir/p.txt"], "-o"),
    (["profile", "plot", "{ok}", "-o", "{tmp}/no/such/dir/p.png"], "-o"),
    (["profile", "sawtooth", "--rt", "-1", "--sw", "2", "-o", "{tmp}/p.txt"], "rt > 0"),
    (["profile", "random", "--au", "0", "--ar", "1", "--rtmax", "2", "--seed", "1", "-o", "{tmp}/p.txt"], "au"),
    (["profile", "sawtooth", "--rt", "1", "--sw", "2", "--length", "-3", "-o", "{tmp}/p.txt"], "--length"),
    (["theta-a", "{tmp}/missing.csv", "--d50", "0.7"], "file not found"),
    (["theta-a", "{ok}", "--d50", "0.7", "--cutoff", "-1"], "--cutoff"),
    (["theta-a", "{ok}", "--d50", "nan"], "--d50"),
    (["theta-a", "{hdr}", "--d50", "0.7"], "line 1"),
    (["theta-a", "{inf}", "--d50", "0.7"], "line 2"),
    (["theta-a", "{short}", "--d50", "0.7"], "short.txt: the profile is 0.3 mm long"),
])
def test_more_bad_input_exit_2(tmp_path, capsys, argv, needle):
    ok = tmp_path / "ok.txt"
    ok.write_text("\n".join(f"{i * 0.1} {math.sin(i)}" for i in range(100)))
    (tmp_path / "hdr.txt").write_text("x,z\n")
    (tmp_path / "inf.txt").write_text("0,0\n1,inf\n2,0\n3,1\n")
    (tmp_path / "short.txt").write_text("0 0\n0.1 0.05\n0.2 0\n0.3 0.05\n")
    subst = dict(tmp=tmp_path, ok=ok, hdr=tmp_path / "hdr.txt", inf=tmp_path / "inf.txt",
                 short=tmp_path / "short.txt")
    assert main([a.format(**subst) for a in argv]) == 2
    err = capsys.readouterr().err
    assert needle in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
