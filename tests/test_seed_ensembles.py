"""The report per physical case (docs/methods.md §7, "Seeds in the report"): seed means with their
intervals, the seed bootstrap of the fits, the figures' points and error bars — on synthetic seed
ensembles and on the real quick campaign (conftest.quick_campaign, no new engine run)."""

import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402
from hypothesis import given, settings, strategies as st  # noqa: E402
from matplotlib.collections import LineCollection, PathCollection  # noqa: E402

from interphase.analysis.correlations import (SPECS, fit_bilinear, fit_plateau, fit_study, prepare_points,  # noqa: E402
                                              seed_ensemble)
from interphase.analysis.ensemble import t_interval  # noqa: E402
from interphase.report import figures as F  # noqa: E402
from interphase.report.tables import results_tables  # noqa: E402

TAN_PHI = (0.50, 0.55, 0.60, 0.55)    # the box seeds


def seeded_summaries(k: int = 12, seeds: int = 3, scatter_deg: float = 2.0, scatter_e: float = 0.03,
                     seed: int = 0, exact_means: bool = False) -> pd.DataFrame:
    """k physical cases (θa 0–50°) × `seeds` runs plus `seeds` box tests paired by seed. θr and tan δ
    vary by seed; with exact_means the seed deviations sum to zero, so each case's mean lies on
    E = 0.2 + 0.8·min(θr, 30)/30 with θr = 5 + 0.7·θa."""
    rng = np.random.default_rng(seed)
    ta = np.linspace(0.0, 50.0, k)
    rows = []
    for i in range(k):
        tr0 = 5 + 0.7 * ta[i]
        dev_t = rng.normal(0, scatter_deg, seeds)
        dev_e = rng.normal(0, scatter_e, seeds)
        if exact_means:
            dev_t, dev_e = dev_t - dev_t.mean(), dev_e - dev_e.mean()
        for s in range(seeds):
            tr = tr0 + dev_t[s]
            e = 0.2 + 0.8 * min(tr0, 30) / 30 + dev_e[s]
            rows.append(dict(case_id=f"c{i:03d}s{s + 1}", group="g1", label=f"iface-rt{i}-mu0.2-s{s + 1}",
                             role="interface", test="interface", pair_id=f"box{s + 1}", friction_ps=0.2,
                             gradation="poly", profile_kind="sawtooth", sr=0.0, theta_a_deg_92=ta[i],
                             theta_a_deg_90=ta[i], theta_r_surface_deg=tr, theta_n_surface_deg=tr - 2,
                             peak_stress_ratio=e * np.mean(TAN_PHI[:seeds]), rnc=ta[i] / 80, seed=s + 1))
    box = [dict(case_id=f"box{s + 1}", group="box", label=f"box-s{s + 1}", role="box", test="box",
                peak_stress_ratio=TAN_PHI[s], seed=s + 1) for s in range(seeds)]
    return pd.DataFrame(rows + box)


def test_one_point_per_physical_case_with_t_intervals():
    summ = seeded_summaries(k=9, seeds=3)
    runs = prepare_points(summ)
    ens = seed_ensemble(runs)
    p = ens.points
    assert len(runs) == 27 and len(p) == 9
    assert (p["seeds"] == 3).all() and (p["box_seeds"] == 3).all()
    for _, row in p.iterrows():
        g = runs[runs["physical_case"] == row["physical_case"]]
        assert row["theta_r_surface_deg"] == pytest.approx(g["theta_r_surface_deg"].mean())
        lo, hi = t_interval(g["theta_r_surface_deg"].to_numpy())
        assert (row["theta_r_surface_deg_lo"], row["theta_r_surface_deg_hi"]) == pytest.approx((lo, hi))
        # E = mean tan δ over mean tan φ of its box seeds, not the mean of the runs' ratios
        assert row["efficiency"] == pytest.approx(g["peak_stress_ratio"].mean() / np.mean(TAN_PHI[:3]))
        assert row["efficiency_lo"] <= row["efficiency"] <= row["efficiency_hi"]
        # θa does not vary by seed: zero-width interval
        assert row["theta_a_deg_92_lo"] == pytest.approx(row["theta_a_deg_92"])
    assert ens.points["tan_phi"].iloc[0] == pytest.approx(np.mean(TAN_PHI[:3]))


def test_ensembles_table_values_replace_the_computed_ones():
    summ = seeded_summaries(k=3, seeds=3)
    runs = prepare_points(summ)
    cases = sorted(runs["physical_case"].unique())
    table = pd.DataFrame({"group": "g1", "case": cases, "E": [0.7, 0.8, 0.9], "E_lo": [0.6, 0.7, 0.8],
                          "E_hi": [0.75, 0.95, 1.1], "tan_delta": [0.3, 0.4, 0.5], "tan_delta_lo": 0.2,
                          "tan_delta_hi": 0.6, "tan_phi": 0.55, "tan_phi_lo": 0.5, "tan_phi_hi": 0.6})
    p = seed_ensemble(runs, ensembles=table).points.set_index("physical_case").loc[cases]
    assert list(p["efficiency"]) == [0.7, 0.8, 0.9] and list(p["efficiency_hi"]) == [0.75, 0.95, 1.1]
    assert list(p["peak_stress_ratio"]) == [0.3, 0.4, 0.5] and (p["tan_phi_lo"] == 0.5).all()


def test_seed_states_set_tan_delta_and_the_box_values():
    summ = seeded_summaries(k=2, seeds=2)
    runs = prepare_points(summ)
    states = {cid: 0.4 + 0.01 * i for i, cid in enumerate(runs["case_id"])} | {"box1": 0.5, "box2": 0.7}
    p = seed_ensemble(runs, states).points
    assert p["peak_stress_ratio"].tolist() == pytest.approx([0.405, 0.425])
    assert p["tan_phi"].tolist() == pytest.approx([0.6, 0.6])
    assert p["efficiency"].tolist() == pytest.approx([0.405 / 0.6, 0.425 / 0.6])


def test_box_tests_on_further_seeds_join_every_case_of_their_soil():
    # 3 interface seeds paired with box seeds 1-3, and [pairs] seeds 4-6 of the same soil (no
    # interface case pairs with them), plus a box test of another soil that must stay out
    from interphase.analysis.ensemble_table import box_pools

    summ = seeded_summaries(k=3, seeds=3)
    soil = dict(group="box", role="box", test="box", gradation="poly", normal_stress=1e5)
    summ = summ.assign(gradation="poly", normal_stress=1e5)
    extra = [dict(soil, case_id=f"box{s}", label=f"box-s{s}", peak_stress_ratio=v, seed=s)
             for s, v in ((4, 0.50), (5, 0.65), (6, 0.52))]
    other = [dict(soil, case_id="boxhi", label="box-s1", normal_stress=2e5, peak_stress_ratio=0.9, seed=1)]
    summ = pd.concat([summ, pd.DataFrame(extra + other)], ignore_index=True)
    pools = box_pools(summ)
    assert pools["box1"] == ("box1", "box2", "box3", "box4", "box5", "box6") and pools["boxhi"] == ("boxhi",)
    runs = prepare_points(summ)
    states = dict(zip(summ["case_id"], summ["peak_stress_ratio"]))
    p = seed_ensemble(runs, states, box_pools=pools).points
    tan_phi = [*TAN_PHI[:3], 0.50, 0.65, 0.52]
    assert (p["box_seeds"] == 6).all() and p["tan_phi"].tolist() == pytest.approx([np.mean(tan_phi)] * 3)
    three = seed_ensemble(runs, states).points              # the pair_ids alone
    assert (three["box_seeds"] == 3).all()
    assert (p["efficiency_hi"] - p["efficiency_lo"] < three["efficiency_hi"] - three["efficiency_lo"]).all()


def test_large_seed_scatter_widens_the_fit_interval_beyond_the_residual_bootstrap():
    # each case's seed mean lies exactly on the plateau (residual bootstrap: no spread) but its seeds
    # scatter by 4° and 0.08 in E: the seed bootstrap must show that
    ens = seed_ensemble(prepare_points(seeded_summaries(k=14, seeds=4, scatter_deg=4.0, scatter_e=0.08,
                                                        exact_means=True, seed=5)))
    fits = {(f.spec.key, f.slice): f.fit for f in fit_study(ens.points, [SPECS["fig6_10a"]], n_boot=150,
                                                            ensemble=ens)}
    f = fits[("fig6_10a", "all")]
    assert f.bootstrap == "seed" and f.n_boot == 150
    seed_w = f.c_interval_bootstrap[1] - f.c_interval_bootstrap[0]
    res_lo, res_hi = f.extra["c_interval_residual"]
    assert seed_w > 2.0 and seed_w > 5 * (res_hi - res_lo)
    assert f.to_dict()["bootstrap"] == "seed" and f.to_dict()["c_lo_resid"] == res_lo
    lo, hi = f.coef_interval[1]
    assert hi - lo > 0
    # the band of the seed refits is wider than the residual one's at the breakpoint
    r = fit_plateau(ens.points["theta_r_surface_deg"], ens.points["efficiency"], n_boot=150)
    sb, rb = f.predict_interval(f.c), r.predict_interval(r.c)
    assert sb[1] - sb[0] > rb[1] - rb[0]


@settings(max_examples=15, deadline=None, derandomize=True)
@given(st.integers(8, 14), st.integers(2, 4), st.floats(0.2, 6.0), st.integers(0, 10_000),
       st.sampled_from(["fig6_10a", "fig6_8", "fig6_3b"]))
def test_seed_bootstrap_interval_contains_the_estimate(k, seeds, scatter, seed, key):
    ens = seed_ensemble(prepare_points(seeded_summaries(k=k, seeds=seeds, scatter_deg=scatter, seed=seed)))
    fr = next(f for f in fit_study(ens.points, [SPECS[key]], n_boot=60, seed=seed, ensemble=ens) if f.slice == "all")
    f = fr.fit
    assert f is not None and f.bootstrap == "seed" and f.n == k
    lo, hi = f.c_interval_bootstrap
    assert math.isfinite(lo) and lo <= f.c <= hi
    for (blo, bhi) in f.coef_interval:
        assert blo <= bhi
    band = f.predict_band(np.linspace(*f.x_range, 7))
    assert np.all(band[0] <= band[1])


def test_one_seed_per_case_falls_back_to_the_residual_bootstrap():
    ens = seed_ensemble(prepare_points(seeded_summaries(k=12, seeds=1)))
    assert ens.points["theta_r_surface_deg_lo"].isna().all() and ens.points["efficiency_lo"].isna().all()
    f = next(r.fit for r in fit_study(ens.points, [SPECS["fig6_10a"]], n_boot=40, ensemble=ens))
    assert f.bootstrap == "residual" and "c_interval_residual" not in f.extra


def test_replicates_must_match_the_points():
    x = np.arange(10.0)
    with pytest.raises(ValueError, match="shape"):
        fit_bilinear(x, np.minimum(x, 5), "plateau", replicates=np.zeros((3, 2, 9)))
    # identical replicates: a zero-width interval at the fit itself
    reps = np.broadcast_to(np.stack([x, np.minimum(x, 5.0)]), (5, 2, 10))
    f = fit_bilinear(x, np.minimum(x, 5.0), "plateau", replicates=reps)
    assert f.bootstrap == "seed" and f.c_interval_bootstrap == pytest.approx((f.c, f.c))


def _panel(points, key, fits=()):
    fig, ax = plt.subplots()
    colour, marker = F._styles(points)
    F.correlation_panel(ax, points, key, list(fits), colour, marker)
    pts = np.concatenate([c.get_offsets() for c in ax.collections if isinstance(c, PathCollection)] or [np.zeros((0, 2))])
    segs = [s for c in ax.collections if isinstance(c, LineCollection) for s in c.get_segments()]
    plt.close(fig)
    return pts, segs


def test_panel_plots_one_point_per_case_with_x_bars_only_where_x_varies_by_seed():
    ens = seed_ensemble(prepare_points(seeded_summaries(k=10, seeds=3)))
    pts, segs = _panel(ens.points, "fig6_8")                 # θa (no seed scatter) vs θr
    assert len(pts) == 10
    vertical = [s for s in segs if np.isclose(s[0, 0], s[1, 0])]
    assert len(vertical) == len(segs) == 10                  # y bars only, one per case
    p = ens.points.set_index("theta_a_deg_92")
    for s in vertical:
        row = p.loc[s[0, 0]]
        assert sorted(s[:, 1]) == pytest.approx([row["theta_r_surface_deg_lo"], row["theta_r_surface_deg_hi"]])
    pts, segs = _panel(ens.points, "fig6_10a")               # θr vs E: both vary by seed
    assert len(pts) == 10 and len(segs) == 20


# ---- the real quick campaign (2 surfaces × 2 seeds, 2 box seeds; tests/conftest.py) ----------------
@pytest.fixture(scope="module")
def quick_ensemble(quick_campaign):
    from interphase.campaign.results import open_campaign
    from interphase.report.build import ensemble_points

    _, store, summ = open_campaign(quick_campaign)
    try:
        ens, table = ensemble_points(summ, store)
    finally:
        store.close()
    return ens, table, summ


@pytest.mark.liggghts
def test_real_points_are_the_physical_cases_with_the_ensembles_table_values(quick_ensemble):
    ens, table, summ = quick_ensemble
    tab = table.add_prefix("t_")
    p = ens.points.merge(tab, left_on=["group", "physical_case"], right_on=["t_group", "t_case"])
    assert len(table) >= 2 and len(ens.points) == len(table) == len(p)
    assert (p["seeds"] == 2).all() and (p["box_seeds"] == 2).all() and (p["t_seeds"] == 2).all()
    for mine, theirs in (("efficiency", "E"), ("peak_stress_ratio", "tan_delta"), ("tan_phi", "tan_phi"),
                         ("theta_r_surface_deg", "theta_r")):
        for a in ("", "_lo", "_hi"):
            other = "t_theta_r_deg" if theirs == "theta_r" and not a else f"t_{theirs}{a}"
            np.testing.assert_allclose(p[mine + a], p[other], rtol=1e-12)
    # E recomputed here from the seeds' peak states agrees with the table's (same curves, same formula)
    again = seed_ensemble(ens.runs.drop(columns=["case_index", "tan_delta_seed"]),
                          {**ens.runs.set_index("case_id")["tan_delta_seed"].to_dict(),
                           **_box_states(ens)}).points
    np.testing.assert_allclose(again["efficiency"], ens.points["efficiency"], rtol=1e-12)
    for end in ("_lo", "_hi"):                               # and so does its interval (ratio_interval)
        np.testing.assert_allclose(again["efficiency" + end], ens.points["efficiency" + end], rtol=1e-9)


def _box_states(ens):
    """{box case_id: value} back out of a SeedEnsemble built with states."""
    ids = sorted({str(b) for b in ens.runs["pair_id"].dropna()})
    return dict(zip(ids, ens.box_values[0][:len(ids)]))


@pytest.mark.liggghts
def test_real_e_error_bars_are_the_ensembles_table_intervals(quick_ensemble):
    ens, table, _ = quick_ensemble
    pts, segs = _panel(ens.points, "fig6_10a")
    assert len(pts) == len(table) >= 2                      # one point per physical case
    # two seeds each: no interval in the table (fewer than 3), so no bar in x or y either
    assert table["E_lo"].isna().all() and table["theta_r_lo"].isna().all()
    assert not segs


@pytest.mark.liggghts
def test_real_results_table_is_per_physical_case(quick_ensemble):
    ens, table, _ = quick_ensemble
    (t,) = results_tables(ens.points)
    assert len(t.df) == len(table) and (t.df["seeds"] == 2).all()
    assert (t.df["E 95%"] == "").all() and (t.df["tan δ 95%"] == "").all()    # 2 seeds: no interval, said so
    assert any("none with fewer than 3 seeds" in n for n in t.notes)
    assert f"{len(table)} physical cases, {2 * len(table)} runs" in t.title


def test_seed_bootstrap_gives_the_mean_its_full_variance():
    """Resampling 3 seeds with replacement makes the mean vary by s²·(2/3)/3; the replicates restore
    s²/3 (adjusted bootstrap), so fit bands are not a fifth too narrow."""
    from interphase.analysis.correlations import _draw_means

    rng = np.random.default_rng(1)
    mat = np.array([[1.0, 2.0, 4.0], [0.5, 0.5, np.nan]])
    n = np.array([3, 2])
    draws = _draw_means(mat, n, rng, 40000)
    s2 = np.var(mat[0], ddof=1)
    assert np.var(draws[:, 0]) == pytest.approx(s2 / 3, rel=0.03)
    assert np.mean(draws[:, 0]) == pytest.approx(mat[0].mean(), abs=0.01)
    assert np.all(draws[:, 1] == 0.5)                   # no scatter, nothing to inflate
