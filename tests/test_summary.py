"""summarise(case, results) → Summary: row keys, JSON round trip, box tests, degenerate input."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from interphase.analysis.summary import ROW_KEYS, Summary, summarise
from interphase.case import Case, case_from_dict
from interphase.surface.spec import ProfileSpec
from interphase.tables import CONTACT_COLUMNS, HISTORY_COLUMNS, PARTICLE_COLUMNS, MissingColumnError, Results

DATA = Path(__file__).parent / "data" / "liggghts_sawtooth45"


def real_case_and_results():
    raw = json.loads((DATA / "case.json").read_text())["case"]
    prof = raw.pop("profile")
    raw["profile"] = {"kind": prof["kind"], **prof.get("params", {})}
    return case_from_dict(raw), Results(pd.read_parquet(DATA / "contacts.parquet"),
                                        pd.read_parquet(DATA / "history.parquet"),
                                        pd.read_parquet(DATA / "particles.parquet"))


@pytest.fixture(scope="module")
def real():
    case, res = real_case_and_results()
    return case, res, summarise(case, res)


def _finite(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def test_row_has_every_key_and_nan_has_reason(real):
    _, _, s = real
    for key in ROW_KEYS:
        assert key in s.row, key
    for key, value in s.row.items():
        if isinstance(value, float) and math.isnan(value):
            assert key in s.reasons, key


def test_row_values_on_real_output(real):
    case, res, s = real
    r = s.row
    assert r["test"] == "interface"
    assert 0.2 < r["peak_stress_ratio"] < 1.0
    assert 0 < r["shear_disp_at_peak"] <= case.shear_distance
    snaps = res.contacts.groupby("snapshot")["shear_disp"].first()
    assert r["peak_snapshot"] == int(np.argmin(np.abs(snaps.to_numpy() - r["shear_disp_at_peak"])))
    assert r["n_contacts_surface"] > 0
    assert r["theta_r_surface_deg"] > 0            # the surface resists toward −x
    # the 45° saw-tooth with Rt = D50: docs/methods.md §3 table (filter 92: 39.35°, 90: 38.94°), Rn = 0.75
    assert r["theta_a_deg_92"] == pytest.approx(39.35, abs=0.05)
    assert r["theta_a_deg_90"] == pytest.approx(38.94, abs=0.05)
    assert r["rn"] == pytest.approx(0.75, abs=1e-3)
    assert r["mean_slope_deg"] == pytest.approx(45.0, abs=1e-6)
    assert r["region_z0"] == pytest.approx(1.5 * case.d50, rel=1e-9)
    for key in ("stress_ratio_region", "qp_region", "qp_sff", "a_region", "shear_band_d50", "inertial_number"):
        assert _finite(r[key]), key
    # the surface contacts of the window's grains at the peak snapshot sum to the engine's own
    # window force at that step (History row at the same step: snapshots fall on History rows)
    hist = res.history
    k = int(np.argmin(np.abs(hist["shear_disp"].to_numpy() - r["peak_snapshot_shear_disp"])))
    assert hist["shear_disp"].iloc[k] == pytest.approx(r["peak_snapshot_shear_disp"], abs=1e-9)
    engine = hist["window_fx"].iloc[k] / -hist["window_fz"].iloc[k]
    # (to 2 %: at e = 0.5 the dumped tangential forces include the damping term; exact at e = 1 in
    # tests/test_liggghts.py)
    assert r["stress_ratio_surface_contacts"] == pytest.approx(engine, rel=0.02)


def test_series_columns(real):
    _, res, s = real
    for col in ("shear_disp", "stress_ratio", "stress_ratio_smooth", "theta_r_surface_deg", "snapshot"):
        assert col in s.series.columns
    assert len(s.series) == len(res.history)
    assert s.series["theta_r_surface_deg"].notna().sum() == res.contacts["snapshot"].nunique()


def test_json_round_trip(real):
    _, _, s = real
    text = s.to_json()
    json.loads(text)                                 # strict JSON: no NaN tokens
    assert "NaN" not in text
    back = Summary.from_json(text)
    for k, v in s.row.items():
        if isinstance(v, float) and math.isnan(v):
            assert math.isnan(back.row[k])
        else:
            assert back.row[k] == v, k
    pd.testing.assert_frame_equal(back.series[["shear_disp", "stress_ratio"]], s.series[["shear_disp", "stress_ratio"]])


def test_mirrored_results_with_shear_sign(real):
    case, res, s = real
    from interphase.analysis.anisotropy import apply_shear_sign

    mirrored = Results(apply_shear_sign(res.contacts, -1), apply_shear_sign(res.history, -1),
                       apply_shear_sign(res.particles, -1))
    m = summarise(case, mirrored, shear_sign=-1)
    for key in ("peak_stress_ratio", "theta_r_surface_deg", "theta_n_surface_deg", "surface_force_angle_deg"):
        assert m.row[key] == pytest.approx(s.row[key], rel=1e-9, abs=1e-12), key


def synthetic_box():
    case = Case(test="box", profile=None, d50=0.7e-3)
    s = np.linspace(0, 3e-3, 61)
    ratio = 0.7 - 0.2 * ((s - 1.5e-3) / 1.5e-3) ** 2          # broad peak 0.7 at 1.5 mm
    hist = pd.DataFrame({"time": s / 0.05, "shear_disp": s, "surface_fx": ratio * 2.0, "surface_fz": -2.0,
                         "normal_force": 2.0, "platen_z": 0.01, "n_contacts": 50,
                         "window_fx": ratio * 2.0, "window_fz": -2.0})[list(HISTORY_COLUMNS)]
    rng = np.random.default_rng(0)
    frames = []
    for k, sd in enumerate(s[::10]):
        n = 40
        x1, z1 = rng.uniform(0, case.box_length, n), rng.uniform(0, 5e-3, n)
        th = rng.uniform(0, np.pi, n)
        nx, nz = np.cos(th), np.sin(th)
        fn = rng.uniform(0.1, 1, n)
        frames.append(pd.DataFrame({"snapshot": k, "time": sd / 0.05, "shear_disp": sd, "kind": "pp",
                                    "id1": np.arange(n), "id2": np.arange(n) + n, "cx": x1 + 0.35e-3 * nx,
                                    "cz": z1 + 0.35e-3 * nz, "nx": nx, "nz": nz, "fn": fn, "ft": 0.0,
                                    "fx": fn * nx, "fz": fn * nz, "x1": x1, "z1": z1, "x2": x1 + 0.7e-3 * nx,
                                    "z2": z1 + 0.7e-3 * nz, "overlap": 1e-6}))
    return case, Results(pd.concat(frames, ignore_index=True)[list(CONTACT_COLUMNS)], hist)


def test_box_test_summary():
    case, res = synthetic_box()
    s = summarise(case, res)
    assert s.row["test"] == "box"
    assert s.row["peak_stress_ratio"] == pytest.approx(0.7, abs=0.002)
    assert s.row["shear_disp_at_peak"] == pytest.approx(1.5e-3, abs=0.06e-3)
    assert math.isnan(s.row["theta_r_surface_deg"]) and "box test" in s.reasons["theta_r_surface_deg"]
    assert math.isnan(s.row["theta_a_deg_92"]) and "box test" in s.reasons["theta_a_deg_92"]
    assert s.row["n_contacts_surface"] == 0
    assert math.isnan(s.row["shear_band_d50"]) and "Particles" in s.reasons["shear_band_d50"]
    assert _finite(s.row["qp_region"])


def test_peak_at_the_end_of_the_shear_is_flagged():
    """A ratio still rising when the shear stops has no peak yet: the value stands as a lower bound,
    with a note; a broad peak mid-shear is not flagged."""
    case, res = synthetic_box()
    assert summarise(case, res).row["peak_at_end"] is False
    h = res.history.copy()
    h["surface_fx"] = h["window_fx"] = 2.0 * (0.3 + 100 * h["shear_disp"])    # 0.3 → 0.6, rising
    s = summarise(case, Results(res.contacts, h))
    assert s.row["peak_at_end"] is True and "still be rising" in s.reasons["peak_at_end"]
    assert s.row["peak_stress_ratio"] == pytest.approx(0.6, abs=0.02)


def test_empty_tables_give_nan_with_reasons():
    case = Case(profile=ProfileSpec.make("flat"), d50=0.7e-3)
    res = Results(pd.DataFrame({c: [] for c in CONTACT_COLUMNS}), pd.DataFrame({c: [] for c in HISTORY_COLUMNS}),
                  pd.DataFrame({c: [] for c in PARTICLE_COLUMNS}))
    s = summarise(case, res)
    for key in ("peak_stress_ratio", "theta_r_surface_deg", "stress_ratio_region", "shear_band_d50"):
        assert math.isnan(s.row[key]) and s.reasons[key], key
    # a flat surface is non-dilative: θa is NaN and says so
    assert math.isnan(s.row["theta_a_deg_92"]) and "non-dilative" in s.reasons["theta_a_deg_92"]
    json.loads(s.to_json())


def test_missing_column_refused(real):
    case, res, _ = real
    with pytest.raises(MissingColumnError, match="overlap"):
        summarise(case, Results(res.contacts.drop(columns="overlap"), res.history))
    with pytest.raises(MissingColumnError, match="platen_z"):
        summarise(case, Results(res.contacts, res.history.drop(columns="platen_z")))


def test_peak_snapshot_has_no_reason_when_found(real):
    _, _, summary = real
    assert math.isfinite(summary.row["peak_snapshot"])
    assert "peak_snapshot" not in summary.row["reasons"]


def test_mean_theta_r_over_loaded_snapshots(real):
    _, _, summary = real
    s = summary.series
    loaded = s.loc[s["load_balanced"] & s["theta_r_surface_deg"].notna(), "theta_r_surface_deg"]
    assert summary.row["theta_r_surface_mean_deg"] == pytest.approx(loaded.mean(), rel=1e-12)
    assert min(loaded) < summary.row["theta_r_surface_mean_deg"] < max(loaded)


def test_solid_fraction_of_a_square_lattice_is_pi_over_four():
    from interphase.analysis.summary_stages import solid_fraction
    from interphase.case import Case

    case = Case(test="box", d50=0.7e-3, box_length_d50=20, box_height_d50=10)
    s = case.d50 / 2                                   # pitch; grains of diameter s touch
    i, k = np.meshgrid(np.arange(40), np.arange(20))
    p = pd.DataFrame({"snapshot": 0, "x": (i.ravel() + 0.5) * s, "z": (k.ravel() + 0.5) * s, "radius": s / 2})
    assert solid_fraction(case, p, 0) == pytest.approx(np.pi / 4, rel=1e-12)
    # smaller grains: the top falls to 19.9 s, the rectangle to (4 s, 13.9 s) × (6 s, 34 s), 10 × 28 grains
    assert solid_fraction(case, p.assign(radius=0.4 * s), 0) == pytest.approx(280 * np.pi * 0.16 / (28 * 9.9), rel=1e-9)
    assert np.isnan(solid_fraction(case, p, 7))
