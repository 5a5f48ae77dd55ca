"""Case identity travels: a campaign's finished cases read the same on a machine without engines."""

import json
import os

import pandas as pd
import pytest

from interphase.campaign.run import campaign_status


@pytest.mark.liggghts
def test_status_and_report_without_any_engine_on_path(quick_campaign, tmp_path, monkeypatch, capsys):
    from interphase.cli import main

    assert main(["status", str(quick_campaign), "--json"]) == 0
    before = json.loads(capsys.readouterr().out)
    assert before["counts"] == {"done": 6}
    # a login node / laptop: no liggghts, no yade on PATH (the Python tools stay reachable)
    empty = tmp_path / "bin"
    empty.mkdir()
    monkeypatch.setenv("PATH", str(empty))
    assert main(["status", str(quick_campaign), "--json"]) == 0
    after = json.loads(capsys.readouterr().out)
    assert after["counts"] == before["counts"]
    assert [c["case_id"] for c in after["cases"]] == [c["case_id"] for c in before["cases"]]
    out = tmp_path / "report"
    assert main(["report", str(quick_campaign), "--out", str(out), "--bootstrap", "9"]) == 0
    ens = pd.read_csv(out / "tables" / "ensembles.csv")
    assert len(ens) == 2 and ens["E"].notna().all()
    # the engine build that ran each case is kept as provenance
    folder = quick_campaign.parent / "runs" / before["cases"][0]["case_id"]
    prov = json.loads((folder / "case.json").read_text())["provenance"]
    assert prov["engine_version"].startswith("LIGGGHTS") and len(prov["recipe_id"]) == 16
    assert os.environ["PATH"] == str(empty)


@pytest.mark.liggghts
def test_status_table_fits_80_columns(quick_campaign, monkeypatch, capsys):
    from interphase.cli import main

    monkeypatch.setenv("COLUMNS", "80")
    assert main(["status", str(quick_campaign)]) == 0
    text = capsys.readouterr().out
    lines = text.splitlines()
    _, _, df = campaign_status(quick_campaign)
    rows = [ln for ln in lines if ln[:8] in {str(c)[:8] for c in df["case_id"]}]
    assert len(rows) == 6 and lines[0].startswith("quick: 6 done")
    assert str(quick_campaign.parent / "runs") in text                 # the folder it read, whole
    # every line fits, except one holding a path (never cut; a terminal folds it)
    assert all(len(ln.rstrip()) <= 80 for ln in lines if "/" not in ln)
    # labels keep the part that tells cases apart (issue 32: `-mu0.2-poly-s1` was cut off)
    for r in df.itertuples():
        assert any(ln.startswith(str(r.case_id)[:8]) and r.label.split("-", 2)[-1][-20:] in ln for ln in rows), r.label


@pytest.mark.liggghts
def test_report_reads_runs_written_elsewhere(quick_campaign, tmp_path, monkeypatch):
    # the campaign file as a colleague has it (no output line), the runs copied from the cluster
    from interphase.cli import main

    text = "\n".join(line for line in quick_campaign.read_text().splitlines() if not line.startswith("output ="))
    mine = tmp_path / "quick.toml"
    mine.write_text(text)
    runs = quick_campaign.parent / "runs"
    assert main(["report", str(mine), "--runs", str(runs), "--output", str(tmp_path / "rep"), "--bootstrap", "9"]) == 0
    assert len(pd.read_csv(tmp_path / "rep" / "tables" / "summaries.csv")) == 6
    monkeypatch.chdir(tmp_path)                          # ./runs/quick (the default) is not there
    assert main(["report", str(mine), "--out", str(tmp_path / "rep2")]) == 2


def test_the_report_uses_one_recipe_per_engine_and_counts_what_it_left_out(tmp_path):
    from interphase.campaign.plan import plan
    from interphase.campaign.schema import load_campaign
    from interphase.campaign.results import one_run_per_case, recipe_notes

    f = tmp_path / "c.toml"
    f.write_text('[campaign]\nname = "c"\nengines = ["liggghts"]\n[case]\ntest = "interface"\n'
                 'profile = {kind = "flat"}\nn_grains = 50\n[sweep]\nseed = [1, 2]\n[pairs]\nbox = false\n')
    c = load_campaign(f)
    a, b = plan(c, identity=lambda name: "new-recipe")
    old_a = next(iter(plan(c, identity=lambda name: "old-recipe")))
    rows = pd.DataFrame([
        dict(case_id=a.case_id, label=a.label, engine="liggghts", finished=1.0, recipe_id="new-recipe"),
        dict(case_id=old_a.case_id, label=a.label, engine="liggghts", finished=2.0, recipe_id="old-recipe"),
        dict(case_id="0ld0b", label=b.label, engine="liggghts", finished=3.0, recipe_id="old-recipe"),  # no new run yet
        dict(case_id="gone", label="a-label-no-longer-asked-for", engine="liggghts", finished=4.0, recipe_id="new-recipe"),
    ])
    out = one_run_per_case(rows, c, identity=lambda name: "new-recipe")
    assert list(out["case_id"]) == [a.case_id]                       # this recipe's runs only: never mixed
    assert out.attrs == {"recipes": {"liggghts": "new-recipe"}, "current": {"liggghts": True}, "other_recipe": 2,
                         "not_asked": 1}
    assert any("2 finished run(s) of another recipe left out" in n for n in recipe_notes(out.attrs))

    # nothing of this recipe yet: the recipe with most runs, said
    out = one_run_per_case(rows.iloc[1:], c, identity=lambda name: "newer-recipe")
    assert sorted(out["case_id"]) == sorted([old_a.case_id, "0ld0b"])
    assert out.attrs["recipes"] == {"liggghts": "old-recipe"} and out.attrs["current"] == {"liggghts": False}
    assert any("no finished run of this version's recipe; the report uses recipe old-recipe" in n
               for n in recipe_notes(out.attrs))


def test_a_run_takes_the_group_the_file_gives_its_case_now(tmp_path):
    """A file reorganised into groups (same cases, same ids) must not split a case's seeds between
    the group its first runs were planned under and the new one: the summaries take the file's."""
    from interphase.campaign.plan import plan
    from interphase.campaign.results import one_run_per_case
    from interphase.campaign.schema import load_campaign

    f = tmp_path / "c.toml"
    f.write_text('[campaign]\nname = "c"\nengines = ["liggghts"]\n[case]\ntest = "interface"\n'
                 'profile = {kind = "flat"}\nn_grains = 50\n[pairs]\nbox = false\n'
                 '[[group]]\nname = "now"\n[group.sweep]\nseed = [1, 2]\n')
    c = load_campaign(f)
    a, b = plan(c, identity=lambda name: "r")
    rows = pd.DataFrame([dict(case_id=a.case_id, label=a.label, engine="liggghts", finished=1.0, recipe_id="r",
                              group="c"),            # planned when the file had no groups
                         dict(case_id=b.case_id, label=b.label, engine="liggghts", finished=2.0, recipe_id="r",
                              group="now")])
    out = one_run_per_case(rows, c, identity=lambda name: "r")
    assert list(out["group"]) == ["now", "now"]
