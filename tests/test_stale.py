"""A stale result is visible, never silently mixed (issue 17, item 2). On a copy of the session's real
quick campaign (LIGGGHTS), cut to one seed of one surface (an interface case and its box test):

- a recipe change (an engine's RECIPE_VERSIONS number bumped, as a template change must; here the
  LIGGGHTS engine value with the next number, passed to status, run and report as an argument, and
  carried by every task to the campaign's workers) makes every finished case stale: `status` says so per case, `run` keeps them and says so (exit 1), `report`
  uses one recipe and says which, `run --rerun-stale` reruns exactly those under the new recipe (new
  folders; the old ones stay), after which `report` uses the new recipe only and counts the old runs
  it left out;
- another engine build on this machine (the one part faked: a second LIGGGHTS build cannot be
  installed here; the engine value's profile states it) flags the finished cases, and `--rerun-stale` runs them again in their folders,
  the old folders kept under .superseded/."""

from __future__ import annotations

import dataclasses
import io
import json
import shutil

import pandas as pd
import pytest

from interphase.campaign import run as run_mod
from interphase.campaign.results import open_campaign, recipe_notes
from interphase.campaign.run import campaign_status, run_campaign
from interphase.cli import status_text
from interphase.engines.base import engine_spec
from interphase.recipe import RECIPE_VERSIONS
from interphase.report.build import build_report

pytestmark = pytest.mark.liggghts      # every test copies the session's real LIGGGHTS quick campaign


@pytest.fixture()
def one_seed(quick_campaign, tmp_path):
    out = tmp_path / "runs"
    shutil.copytree(quick_campaign.parent / "runs", out, ignore=shutil.ignore_patterns(".campaign.lock", ".dry-run"))
    text = quick_campaign.read_text().split("[sweep]")[0] + "[sweep]\nprofile.rt = [0.5]\nfriction_ps = [0.2]\nseed = [1]\n"
    toml = tmp_path / "one.toml"
    toml.write_text("\n".join(line for line in text.splitlines() if not line.startswith("output =")))
    return toml, out


def _status(toml, out, engines=None):
    _, _, df = campaign_status(toml, output=out, engines=engines)
    return df.set_index("case_id")


#: this version's LIGGGHTS recipe made a new one, as when its RECIPE_VERSIONS number is bumped: the
#: engine value with the next number, which the plan hashes and every task carries to its worker
BUMPED = (engine_spec("liggghts", recipe_version=RECIPE_VERSIONS["liggghts"] + 1),)


def test_a_recipe_change_flags_keeps_and_reruns_exactly_the_stale_cases(one_seed, tmp_path):
    toml, out = one_seed
    before = _status(toml, out)
    assert (before["status"] == "done").all() and len(before) == 2
    old_recipe = set(before["recipe_id"])
    folders = {p.name for p in out.iterdir() if p.is_dir()}

    campaign, _, df = campaign_status(toml, output=out, engines=BUMPED)
    assert "2 stale (recipe)" in "\n".join(status_text(campaign, df))      # `campaign status`'s lines
    df = df.set_index("case_id")
    assert not set(df.index) & set(before.index)                       # new ids
    assert (df["status"] == "stale").all() and (df["cause"] == "recipe").all()
    assert all(f"folder {cid}" in m for cid, m in zip(before.index, df["message"])), df["message"].tolist()

    # the report would use the earlier recipe (no run of this one) and say so: the runs and notes
    # build_report takes (open_campaign's one_run_per_case, recipe_notes); the whole report is
    # built after the rerun below
    _, store, summ = open_campaign(toml, out, engines=BUMPED)
    store.close()
    assert set(summ["case_id"]) == set(before.index) and summ.attrs["recipes"]["liggghts"] in old_recipe
    notes = recipe_notes(summ.attrs)
    assert any("no finished run of this version's recipe" in w and next(iter(old_recipe)) in w for w in notes)

    # a plain run keeps them and says so
    said = io.StringIO()
    assert run_campaign(toml, output=out, engines=BUMPED, stream=said, live=False).exit_code == 1
    assert "2 stale (kept; --rerun-stale reruns them)" in said.getvalue() and "0 to run" in said.getvalue()
    assert {p.name for p in out.iterdir() if p.is_dir()} == folders

    # --rerun-stale runs exactly those, under the new recipe, in new folders
    rep = run_campaign(toml, output=out, engines=BUMPED, rerun_stale=True, live=False)
    assert rep.ran == 2 and rep.exit_code == 0
    after = _status(toml, out, BUMPED)
    assert (after["status"] == "done").all() and set(after.index) == set(df.index)
    assert not set(after["recipe_id"]) & old_recipe
    assert folders <= {p.name for p in out.iterdir() if p.is_dir()}          # old folders stay
    for cid in after.index:        # the workers ran the engine value they were given
        assert json.loads((out / cid / "case.json").read_text())["provenance"]["recipe_id"] == after.loc[cid, "recipe_id"]

    # the report now uses the new recipe only and counts what it left out
    res = build_report(toml, out=tmp_path / "rep1", n_boot=9, output=out, engines=BUMPED)
    summ = pd.read_csv(tmp_path / "rep1" / "tables" / "summaries.csv")
    assert set(summ["case_id"]) == set(after.index)
    assert any("2 finished run(s) of another recipe left out" in w for w in res.warnings), res.warnings
    # this version's own recipe still reads its own runs, untouched
    assert (_status(toml, out)["status"] == "done").all()


def test_another_engine_build_flags_the_cases_and_reruns_them_in_place(one_seed):
    toml, out = one_seed
    before = _status(toml, out)
    built = before["engine_version"].iloc[0]
    assert isinstance(built, str) and built.startswith("LIGGGHTS")
    lig = engine_spec("liggghts")
    other = (dataclasses.replace(lig, profile=dataclasses.replace(lig.profile, version="LIGGGHTS-PUBLIC 9.9")),)
    df = _status(toml, out, other)
    assert (df["status"] == "stale").all() and (df["cause"] == "engine build").all()
    assert all(built in m and "9.9" in m for m in df["message"])

    said = io.StringIO()
    assert run_campaign(toml, output=out, engines=other, stream=said, live=False).exit_code == 0   # kept, exit 0
    assert "2 stale (kept" in said.getvalue()

    rep = run_campaign(toml, output=out, engines=other, rerun_stale=True, live=False)
    assert rep.ran == 2 and rep.exit_code == 0
    superseded = sorted((out / ".superseded").iterdir())
    assert sorted(p.name.rsplit("-", 1)[0] for p in superseded) == sorted(before.index)
    for p in superseded:       # the old result, whole
        assert (p / "DONE").exists() and json.loads((p / "case.json").read_text())["case_id"] in before.index
    after = _status(toml, out, other)      # rerun by the build the engine value states
    assert (after["status"] == "done").all() and set(after.index) == set(before.index)
    assert (after["engine_version"] == "LIGGGHTS-PUBLIC 9.9").all()
    assert (_status(toml, out)["status"] == "stale").all()       # this machine's real build: stale again


def test_a_machine_without_the_engine_flags_no_build(one_seed, monkeypatch, tmp_path):
    toml, out = one_seed
    empty = tmp_path / "empty-bin"
    empty.mkdir()
    monkeypatch.setenv("PATH", str(empty))
    assert run_mod.engine_builds([engine_spec("liggghts"), engine_spec("yade")]) == {"liggghts": None, "yade": None}
    assert (_status(toml, out)["status"] == "done").all()
