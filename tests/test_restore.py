"""`campaign run --restore`: a campaign goes on on another machine from its committed summaries
table, without rerunning what finished, and runs only the rest (real LIGGGHTS for the rest)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tests.conftest import need_binary

from interphase.analysis.ensemble import physical_case
from interphase.campaign.store import CampaignStore
from interphase.cli import main
from interphase.campaign.results import open_campaign, write_curves, write_summaries
from interphase.analysis.ensemble_table import ensemble_table

pytestmark = pytest.mark.liggghts


def _elsewhere(quick_campaign: Path, tmp_path: Path) -> Path:
    """The same campaign file on a fresh machine: its own, empty output folder."""
    text = "\n".join(line for line in quick_campaign.read_text().splitlines() if not line.startswith("output ="))
    toml = tmp_path / "quick.toml"
    toml.write_text(text.replace('name = "quick"', f'name = "quick"\noutput = "{tmp_path / "runs"}"', 1))
    return toml


def _starts(folder: Path) -> int:
    return sum('"event": "start"' in line for line in (folder / "attempts.jsonl").read_text().splitlines())


def test_restored_campaign_reruns_nothing_and_reports_the_same_numbers(quick_campaign, tmp_path, capsys):
    need_binary("liggghts")
    _, store, original = open_campaign(quick_campaign)
    store.close()
    record = write_summaries(original, tmp_path / "summaries.csv")
    with CampaignStore(quick_campaign.parent / "runs") as st:
        assert write_curves(original, st, tmp_path / "curves.parquet") is not None
        before = ensemble_table(original, st).set_index("case")
    # one interface run did not make it into the record: it, and only it, runs here
    table = pd.read_csv(record, dtype={"case_id": str})
    lost = table[table["test"] == "interface"].iloc[0]
    table[table["case_id"] != lost["case_id"]].to_csv(record, index=False)
    # a row whose curve the curves table lacks is run again, not restored without it
    curves = pd.read_parquet(tmp_path / "curves.parquet")
    no_curve = table[table["test"] == "box"].iloc[0]
    curves[curves["case_id"].astype(str) != no_curve["case_id"]].to_parquet(tmp_path / "curves.parquet")
    # a row of another campaign (another recipe / inputs) is counted, never used
    foreign = table.iloc[[0]].assign(case_id="0123456789ab")
    pd.concat([pd.read_csv(record, dtype={"case_id": str}), foreign]).to_csv(record, index=False)

    toml = _elsewhere(quick_campaign, tmp_path)
    assert main(["run", str(toml), "--restore", str(record), "--plain"]) == 0
    out = capsys.readouterr().out
    assert f"restored {len(original) - 2} finished run(s)" in out and f"({len(original) - 2} with their curve" in out
    assert "1 row(s) without a curve in curves.parquet are run again" in out and "1 row(s) are no case of this plan" in out
    assert "4 finished" in out and "2 to run" in out
    runs = tmp_path / "runs"
    for cid in (lost["case_id"], no_curve["case_id"]):
        assert _starts(runs / cid) == 1 and (runs / cid / "contacts.parquet").exists()
    for cid in table["case_id"]:
        if cid not in (lost["case_id"], no_curve["case_id"]):
            assert _starts(runs / cid) == 0 and not (runs / cid / "contacts.parquet").exists()
            prov = json.loads((runs / cid / "case.json").read_text())["provenance"]
            assert prov["restored_from"] == str(record.resolve())

    # a second run finds everything finished (restored folders verify: not corrupt, not stale)
    assert main(["run", str(toml), "--restore", str(record), "--plain"]) == 0
    out = capsys.readouterr().out
    assert "restored 0 finished run(s)" in out and "5 already here" in out and "0 to run" in out
    with CampaignStore(runs) as st:
        assert set(st.status()["status"]) == {"done"}

    _, store, again = open_campaign(toml)
    store.close()
    a = original.set_index("case_id").sort_index()
    b = again.set_index("case_id").sort_index()
    assert list(a.index) == list(b.index)
    restored = ~b.index.isin([lost["case_id"], no_curve["case_id"]])
    for col in ("peak_stress_ratio", "theta_r_surface_deg", "theta_a_deg_92", "solid_fraction", "n_contacts_surface"):
        x, y = a.loc[restored, col].astype(float), b.loc[restored, col].astype(float)
        np.testing.assert_allclose(y, x, rtol=1e-5, err_msg=col)     # the CSV keeps 6 significant digits
    assert (b["label"] == a["label"]).all() and (b["pair_id"].fillna("") == a["pair_id"].fillna("")).all()
    # the seed ensembles (tan δ, tan φ, E with intervals) come back from the resampled curves: the
    # cases the lost run is not part of agree with the original's far inside their intervals
    with CampaignStore(runs) as st:
        after = ensemble_table(again, st).set_index("case")
    # (the rerun box test is one of every case's soil tests: compare where the rerun reproduced it)
    lost_case = physical_case(lost["label"])
    same = [c for c in before.index if c != lost_case]
    assert same and list(after.index) == list(before.index)
    for q in ("tan_delta", "tan_phi", "E", "E_cs"):
        # 2 seeds a case here: no interval (analysis.ensemble.MIN_SEEDS), before or after
        assert before.loc[same, f"{q}_lo"].isna().all() and after.loc[same, f"{q}_lo"].isna().all()
        rel = ((after.loc[same, q] - before.loc[same, q]) / before.loc[same, q]).abs().astype(float)
        assert (rel <= 0.01).all(), (q, rel.max())
    # the report runs on the restored campaign
    assert main(["report", str(toml), "--out", str(tmp_path / "rep"), "--bootstrap", "9"]) == 0
    rep = pd.read_csv(tmp_path / "rep" / "tables" / "summaries.csv", dtype={"case_id": str})
    assert len(rep) == len(original)


def test_restore_from_a_file_that_is_no_summaries_table_names_it(quick_campaign, tmp_path, capsys):
    toml = _elsewhere(quick_campaign, tmp_path)
    bad = tmp_path / "notes.csv"
    bad.write_text("what,value\nx,1\n")
    assert main(["run", str(toml), "--restore", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "notes.csv" in err and "'case_id'" in err and "--restore" in err
    assert main(["run", str(toml), "--restore", str(tmp_path / "missing.csv")]) == 2
    assert "missing.csv" in capsys.readouterr().err
    # nothing ran, nothing was restored
    assert not any((tmp_path / "runs").glob("*/DONE"))


def test_dry_run_lists_what_would_be_restored(quick_campaign, tmp_path, capsys):
    _, store, original = open_campaign(quick_campaign)
    store.close()
    record = write_summaries(original, tmp_path / "summaries.csv")
    toml = _elsewhere(quick_campaign, tmp_path)
    assert main(["run", str(toml), "--restore", str(record), "--dry-run"]) == 0
    out = capsys.readouterr().out
    assert out.count("  restore  ") == len(original)
    # with a curves table, a row without its curve would run
    with CampaignStore(quick_campaign.parent / "runs") as st:
        curves = pd.read_parquet(write_curves(original, st, tmp_path / "curves.parquet"))
    first = str(curves["case_id"].iloc[0])
    curves[curves["case_id"].astype(str) != first].to_parquet(tmp_path / "curves.parquet")
    assert main(["run", str(toml), "--restore", str(record), "--dry-run"]) == 0
    out = capsys.readouterr().out
    assert out.count("  restore  ") == len(original) - 1 and f"  run           {first}" in out
    assert not any((tmp_path / "runs").glob("*/DONE"))
