"""analysis.difference (the agree / differ / undecided decision) and `campaign compare` on real runs."""

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from interphase.analysis.difference import difference, verdict
from interphase.campaign.compare import compare, seed_values

ROOT = Path(__file__).resolve().parents[1]

samples = st.lists(st.floats(-5, 5, allow_nan=False), min_size=2, max_size=8)


@settings(max_examples=200, deadline=None)
@given(samples, samples, st.floats(0.01, 3))
def test_difference_interval_holds_the_change_and_the_verdict_follows_it(a, b, tol):
    d = difference(a, b, tol)
    assert d.change == pytest.approx(np.mean(b) - np.mean(a), abs=1e-12)
    assert d.change_lo <= d.change + 1e-12 and d.change <= d.change_hi + 1e-12
    assert d.verdict == verdict(d.change_lo, d.change_hi, tol)
    if d.verdict == "agree":
        assert -tol <= d.change_lo and d.change_hi <= tol
    if d.verdict == "differ":
        assert abs(d.change) > tol


def test_difference_decides_clear_cases_and_counts_the_seeds_an_unclear_one_needs():
    rng = np.random.default_rng(3)
    ref = 0.40 + 0.01 * rng.standard_normal(5)
    assert difference(ref, ref + 0.002 * rng.standard_normal(5), 0.03).verdict == "agree"
    assert difference(ref, ref + 0.2, 0.03).verdict == "differ"
    # scatter 0.05 on 3 seeds cannot tell a 0.01 change from 0.03: undecided, and the seeds it
    # would take shrink the half-width below the margin at that scatter
    wide = difference([0.35, 0.40, 0.45], [0.36, 0.41, 0.46], 0.03)
    assert wide.verdict == "undecided" and wide.seeds_needed is not None and wide.seeds_needed > 3
    n = wide.seeds_needed
    from scipy import stats
    half = stats.t.ppf(0.975, 2 * n - 2) * math.sqrt(2 * 0.05 ** 2 / n)
    assert half < abs(abs(wide.change) - 0.03)
    # paired: a constant per-seed shift has no scatter, whatever the seeds' spread
    p = difference([0.35, 0.40, 0.45], [0.37, 0.42, 0.47], 0.03, paired=True)
    assert p.change == pytest.approx(0.02) and p.change_hi - p.change_lo == pytest.approx(0, abs=1e-12)
    assert p.verdict == "agree"
    one = difference([0.4], [0.5], 0.03)
    assert one.verdict == "undecided" and math.isnan(one.change_lo)


def test_compare_shifted_ensemble_differs_on_its_metric_only():
    rows = []
    for seed in (1, 2, 3, 4):
        rows.append(dict(case="box-x", case_id=f"b{seed}", seed=seed, test="box", pair_id=None, peak=0.40 + 0.005 * seed,
                         critical=0.36, theta_r_deg=np.nan, surface_contacts_per_d50=np.nan))
        rows.append(dict(case="iface-x", case_id=f"i{seed}", seed=seed, test="interface", pair_id=f"b{seed}",
                         peak=0.39 + 0.004 * seed, critical=0.37, theta_r_deg=30 + seed * 0.1, surface_contacts_per_d50=1.5 + 0.01 * seed))
    ref = pd.DataFrame(rows)
    ref["E"] = ref["peak"] / 0.41
    ref["E_cs"] = ref["critical"] / 0.36
    var = ref.assign(peak=np.where(ref["test"].eq("interface"), ref["peak"] + 0.15, ref["peak"]))
    t = compare(ref, var).set_index(["case", "metric"])["verdict"]
    assert t["iface-x", "tan_delta"] == "differ"
    assert t["iface-x", "theta_r_deg"] == "agree" and t["box-x", "tan_phi"] == "agree"


def test_surface_contacts_are_per_area_in_3d_so_a_deeper_cell_reads_the_same_density():
    """The committed 3D cell study (studies/kfs_3d_cell/results/summaries.csv): a surface in a
    cell 10 D50 deep carries about twice the contacts it carries in one 5 D50 deep; per D50² of
    surface (length × depth) the two agree within 10 % (the compare's tolerance), per D50 of length
    alone they would not. A quasi-2D row keeps its length."""
    from interphase.analysis.ensemble import physical_case
    from interphase.campaign.compare import surface_extent_d50

    summ = pd.read_csv(ROOT / "studies" / "kfs_3d_cell" / "results" / "summaries.csv")
    iface = summ[summ["test"].eq("interface") & summ["box_length_d50"].eq(20.0)]
    extent = surface_extent_d50(iface, 0.00014)
    length = (iface["region_x1"] - iface["region_x0"]) / 0.00014
    assert np.allclose(extent, length * iface["box_depth_d50"])
    keys = [iface["label"].map(physical_case), iface["box_depth_d50"]]
    per_area = (iface["n_contacts_surface"] / extent).groupby(keys).mean().unstack()[[5.0, 10.0]].dropna()
    per_length = (iface["n_contacts_surface"] / length).groupby(keys).mean().unstack()[[5.0, 10.0]].dropna()
    assert len(per_area) >= 1
    assert ((per_area[10.0] / per_area[5.0] - 1).abs() < 0.10).all()
    assert (per_length[10.0] / per_length[5.0] > 1.7).all()
    flat = iface.head(1).assign(device="periodic")
    assert surface_extent_d50(flat, 0.00014).iloc[0] == pytest.approx(length.iloc[0])


@pytest.mark.liggghts
def test_compare_of_a_campaign_with_itself_finds_no_change(quick_campaign):
    from interphase.campaign.results import open_campaign

    _, store, summ = open_campaign(quick_campaign)
    try:
        v = seed_values(summ, store)
    finally:
        store.close()
    iface, box = v[v["test"].eq("interface")], v[v["test"].eq("box")].set_index("case_id")
    assert len(iface) == 4 and len(box) == 2
    # each seed's E is its interface value over its own box test's
    assert np.allclose(iface["E"], iface["peak"].to_numpy() / box.loc[iface["pair_id"].astype(str), "peak"].to_numpy())
    t = compare(v, v)
    assert set(t["case"]) == set(v["case"]) and (t["change"] == 0).all()
    assert not t["verdict"].eq("differ").any()


@pytest.mark.liggghts
def test_campaign_compare_cli_prints_and_writes_the_table(quick_campaign, tmp_path, capsys):
    from interphase.cli import main

    out = tmp_path / "cmp.csv"
    assert main(["compare", str(quick_campaign), str(quick_campaign), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "tan_delta" in text and "change +0" in text
    t = pd.read_csv(out)
    assert {"case", "metric", "change_lo", "change_hi", "verdict"} <= set(t.columns) and len(t) >= 8


@pytest.mark.liggghts
def test_campaign_compare_by_a_field_compares_one_campaigns_cells_without_pooling_them(quick_campaign, tmp_path,
                                                                                       capsys):
    """--by splits one campaign's runs into cells by a field's value (here the seed: every physical
    case has one run in each cell) and reads each cell's ensembles, E from its own soil tests."""
    from interphase.campaign.results import open_campaign
    from interphase.cli import main

    out = tmp_path / "cells.csv"
    assert main(["compare", str(quick_campaign), "--by", "seed=1", "--out", str(out)]) == 0
    assert "reference cell: seed=1" in capsys.readouterr().out
    t = pd.read_csv(out)
    assert set(t["variant"]) == {"seed=2"} and (t["n_ref"] == 1).all() and (t["n_value"] == 1).all()
    _, store, summ = open_campaign(quick_campaign)
    try:
        one, two = (seed_values(summ[summ["seed"].eq(s)], store) for s in (1, 2))
    finally:
        store.close()
    e = t[t["metric"].eq("E")].set_index("case")
    assert len(e) == 2
    for case, row in e.iterrows():
        assert row["ref"] == pytest.approx(float(one.loc[one["case"].eq(case), "E"].iloc[0]))
        assert row["change"] == pytest.approx(float(two.loc[two["case"].eq(case), "E"].iloc[0]) - row["ref"])
    for args, says in ((["--by", "seed=7"], "seed=1; seed=2"), (["--by", "box_depth=3"], "no such field"),
                       ([str(quick_campaign), "--by", "seed=1"], "not both nor neither"), ([], "not both nor neither")):
        assert main(["compare", str(quick_campaign), *args]) == 2
        assert says in capsys.readouterr().err
