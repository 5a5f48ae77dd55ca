"""Finished folders are verified when read (issue: "a stale or broken result is visible, never silently
used"). Every fault is injected for real into a COPY of the session's real quick campaign (LIGGGHTS):
a truncated Parquet table, an edited case.json, a deleted or broken index, a DONE removed behind the
index's back, a folder the index does not know, a folder of the older id scheme."""

from __future__ import annotations

import json
import shutil
import sqlite3

import pyarrow.parquet as pq
import pytest

from interphase.campaign.run import campaign_status
from interphase.campaign.store import CampaignStore, folder_status
from interphase.cli import main

pytestmark = pytest.mark.liggghts      # every test copies the session's real LIGGGHTS quick campaign


@pytest.fixture()
def runs(quick_campaign, tmp_path):
    """(campaign file, a private copy of its runs) — other tests read the original."""
    out = tmp_path / "runs"
    shutil.copytree(quick_campaign.parent / "runs", out, ignore=shutil.ignore_patterns(".campaign.lock", ".dry-run"))
    return quick_campaign, out


def _status(toml, out):
    _, _, df = campaign_status(toml, output=out)
    return df.set_index("case_id")


def _done_interface(toml, out):
    df = _status(toml, out)
    assert (df["status"] == "done").all(), df[["status", "cause", "message"]]
    return df[df["role"] == "interface"].index[0]


def _dry(toml, out, capsys, *extra):
    assert main(["run", str(toml), "--output", str(out), "--dry-run", *extra]) == 0
    return capsys.readouterr().out


def test_truncated_table_is_corrupt_unused_and_rerun(runs, capsys):
    toml, out = runs
    cid = _done_interface(toml, out)
    path = out / cid / "contacts.parquet"
    size = path.stat().st_size
    with open(path, "r+b") as fh:
        fh.truncate(size // 2)
    df = _status(toml, out)
    row = df.loc[cid]
    assert row["status"] == "corrupt" and row["cause"] == "bad_parquet"
    assert str(path) in row["message"] and "--rerun-failed" in row["message"]
    assert (df.drop(index=cid)["status"] == "done").all()
    # the CLI: counted and listed as corrupt, the message (path, fix) in --json
    assert main(["status", str(toml), "--runs", str(out)]) == 0
    text = capsys.readouterr().out
    line, why = [ln for ln in text.splitlines() if ln.startswith(cid[:8])]   # its table row, then its message
    assert "1 corrupt" in text and "corrupt" in line
    # the message wraps between words only: the whole path stays on one line, however long
    assert why.startswith(f"{cid[:8]} corrupt:") and any(str(path) in ln for ln in text.splitlines())
    assert "--rerun-failed" in text
    assert main(["status", str(toml), "--runs", str(out), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    (case,) = [c for c in data["cases"] if c["case_id"] == cid]
    assert case["status"] == "corrupt" and "contacts.parquet" in case["message"]
    # the report does not use it
    from interphase.campaign.results import open_campaign

    _, store, summ = open_campaign(toml, output=out)
    store.close()
    assert cid not in set(summ["case_id"]) and len(summ) == len(df) - 1
    # run keeps it (not counted as done) unless --rerun-failed
    kept = [ln for ln in _dry(toml, out, capsys).splitlines() if cid in ln]
    assert kept and kept[0].split()[:2] == ["skip", "(corrupt)"]
    text = _dry(toml, out, capsys, "--rerun-failed")
    rerun = [ln for ln in text.splitlines() if cid in ln]
    assert rerun and rerun[0].split()[:2] == ["rerun", "(corrupt)"]
    assert sum(ln.split()[:2] == ["skip", "(done)"] for ln in text.splitlines()) == len(df) - 1
    assert f"{len(df)} cases: 1 rerun (corrupt), {len(df) - 1} skip (done)" in text       # the tallies
    # for real: only that case runs; its folder is cleaned first, its history kept
    starts = (out / cid / "attempts.jsonl").read_text().count('"event": "start"')
    assert main(["run", str(toml), "--output", str(out), "--plain"]) == 1       # kept: not all done
    assert "0 to run" in capsys.readouterr().out
    assert main(["run", str(toml), "--output", str(out), "--rerun-failed", "--plain"]) == 0
    text = capsys.readouterr().out
    assert "1 to run" in text and f"rerun corrupt {cid}" in text
    lines = [json.loads(x) for x in (out / cid / "attempts.jsonl").read_text().splitlines()]
    assert [x["event"] for x in lines].count("start") == starts + 1
    assert any(x["event"] == "discarded" and x["cause"] == "bad_parquet" for x in lines)
    pq.read_metadata(out / cid / "contacts.parquet")
    assert (_status(toml, out)["status"] == "done").all()


def test_edited_case_json_is_an_id_mismatch(runs, capsys):
    toml, out = runs
    cid = _done_interface(toml, out)
    cj = out / cid / "case.json"
    meta = json.loads(cj.read_text())
    meta["inputs"]["seed"] += 10
    cj.write_text(json.dumps(meta))
    row = _status(toml, out).loc[cid]
    assert row["status"] == "corrupt" and row["cause"] == "id_mismatch"
    assert str(cj) in row["message"] and f"not to the folder's name {cid}" in row["message"]
    kept = [ln for ln in _dry(toml, out, capsys).splitlines() if cid in ln]
    assert kept[0].split()[:2] == ["skip", "(corrupt)"]
    # restored: done again (the verdict follows the file, not a stale cache)
    meta["inputs"]["seed"] -= 10
    cj.write_text(json.dumps(meta))
    assert _status(toml, out).loc[cid, "status"] == "done"


def test_deleted_or_broken_index_is_rebuilt_with_the_same_statuses(runs):
    toml, out = runs
    cid = _done_interface(toml, out)
    with open(out / cid / "history.parquet", "r+b") as fh:     # one corrupt case among the done ones
        fh.truncate(100)
    before = _status(toml, out)[["status", "cause"]]
    assert before.loc[cid, "status"] == "corrupt"
    (out / "index.sqlite").unlink()
    after = _status(toml, out)[["status", "cause"]]
    assert after.equals(before)
    (out / "index.sqlite").write_bytes(b"this is not a database" * 100)
    for ext in ("-wal", "-shm"):
        (out / f"index.sqlite{ext}").unlink(missing_ok=True)
    again = _status(toml, out)[["status", "cause"]]
    assert again.equals(before)
    assert list(out.glob("index.sqlite.broken-*"))


def test_done_removed_behind_the_index_is_corrected(runs):
    toml, out = runs
    cid = _done_interface(toml, out)
    (out / cid / "DONE").unlink()
    con = sqlite3.connect(out / "index.sqlite")
    assert con.execute("SELECT status FROM cases WHERE case_id = ?", (cid,)).fetchone() == ("done",)
    con.close()
    df = _status(toml, out)
    assert df.loc[cid, "status"] == "incomplete" and folder_status(out / cid) == "incomplete"
    con = sqlite3.connect(out / "index.sqlite")
    assert con.execute("SELECT status FROM cases WHERE case_id = ?", (cid,)).fetchone() == ("incomplete",)
    con.close()
    with CampaignStore(out) as store:
        assert cid not in set(store.summaries()["case_id"])


def test_a_queued_rerun_reads_queued_while_its_run_holds_the_lock(runs, capsys):
    """A case a live `campaign run` has queued again, whose folder still holds its last attempt's
    failure (a stop's "interrupted"): `status` and a dry run read it as queued while that run holds
    the campaign's lock (here the lock itself, taken by this process: the run it stands for cannot
    be reached mid-flight), and as the folder says once the lock is free."""
    toml, out = runs
    cid = _done_interface(toml, out)
    (out / cid / "DONE").unlink()
    (out / cid / "failure.json").write_text(json.dumps({"status": "interrupted", "cause": "interrupted",
                                                         "message": "stopped during setup: SIGINT"}))
    assert folder_status(out / cid) == "interrupted"
    with CampaignStore(out) as store, store.lock():
        store.set_status(cid, "queued")
        assert _status(toml, out).loc[cid, "status"] == "queued"
        text = _dry(toml, out, capsys)
        assert "a `campaign run` is running" in text and f"queued        {cid}" in text, text
    assert _status(toml, out).loc[cid, "status"] == "interrupted"
    text = _dry(toml, out, capsys)
    assert "a `campaign run` is running" not in text and f"run           {cid}" in text, text


def test_unknown_folder_is_indexed_and_an_older_scheme_is_unverifiable(runs):
    """A folder the index does not know (here: a copy carrying an id of the older scheme — engine
    version + template hash, no recipe id) is indexed when the campaign is read; it cannot be hashed,
    so it stays done, marked unverifiable, never corrupt. A copy that keeps its recipe id under a
    foreign name is an id mismatch."""
    toml, out = runs
    cid = _done_interface(toml, out)
    old = out / "0ld5cheme0001"
    shutil.copytree(out / cid, old)
    meta = json.loads((old / "case.json").read_text())
    prov = meta["provenance"]
    prov.pop("recipe_id")
    meta.pop("recipe_id", None)
    prov["template_hash"] = "0123456789abcdef"
    meta["case_id"] = old.name
    (old / "case.json").write_text(json.dumps(meta))
    renamed = out / "c0ffee000002"
    shutil.copytree(out / cid, renamed)
    with CampaignStore(out) as store:
        df = store.status().set_index("case_id")
        summ = store.summaries()
    assert df.loc[old.name, "status"] == "done" and df.loc[old.name, "cause"] == "unverifiable"
    assert "older scheme" in df.loc[old.name, "message"]
    assert df.loc[renamed.name, "status"] == "corrupt" and df.loc[renamed.name, "cause"] == "id_mismatch"
    assert df.loc[cid, "status"] == "done" and not isinstance(df.loc[cid, "cause"], str)
    assert old.name in set(summ["case_id"]) and renamed.name not in set(summ["case_id"])
