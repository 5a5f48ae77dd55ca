"""Issue 32 items 2, 4 and 6, engine-free: the runs folder follows the campaign file, every command
says which folder it read, a missing one is an error; campaigns of any size are counted first and
planned lazily; one meaning per option, --json where a command reads or runs."""

from __future__ import annotations

import json

import pytest

from interphase.campaign import schema
from interphase.campaign.plan import iter_plan, plan
from interphase.campaign.schema import load_campaign
from interphase.cli import build_parser, main
from tests.campaign_files import SAWTOOTH, write_toml

#: a periodic case of 6 mm shear, planned only (never run)
CASE = {"test": "interface", "device": "periodic", "profile": SAWTOOTH, "shear_velocity": 0.02,
        "shear_modulus": 50e6, "shear_distance": 0.006, "box_height_d50": 25}


def _write(folder, sweep=None):
    folder.mkdir(parents=True, exist_ok=True)
    return write_toml(folder / "c.toml", campaign={"name": "c"}, case=CASE, sweep=sweep or {"seed": [1, 2]})


def test_status_from_another_folder_reads_the_files_runs_folder(tmp_path, monkeypatch, capsys):
    f = _write(tmp_path / "project" / "campaigns")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    runs = tmp_path / "project" / "campaigns" / "runs" / "c"
    # no runs yet: said, exit 2 (it used to print "c: 4 pending", rc 0, from ./runs/c)
    assert main(["status", str(f)]) == 2
    err = capsys.readouterr().err
    assert f"the runs folder {runs} does not exist" in err and "--runs" in err
    runs.mkdir(parents=True)
    assert main(["status", str(f)]) == 0
    out = " ".join(capsys.readouterr().out.split())        # where a line wraps is the terminal's business
    assert "c: 4 pending" in out and f"runs folder {runs} (the default runs/c beside c.toml" in out
    assert main(["status", str(f), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["runs"] == str(runs) and "default" in data["runs_from"]
    assert not (elsewhere / "runs").exists()
    # stated in the file: relative to the file; on the command line: as given
    f.write_text(f.read_text().replace('name = "c"', 'name = "c"\noutput = "../out"'))
    c = load_campaign(f)
    assert c.output == tmp_path / "project" / "out" and "[campaign] output of" in c.output_from
    assert load_campaign(f, output=tmp_path / "x").output == tmp_path / "x"


def test_a_huge_sweep_is_counted_first_and_needs_yes(tmp_path, capsys, monkeypatch):
    """A million cases are counted, not planned: the eager planner is never called and the lazy
    one is read only as far as the sample (it took 90 s to print anything when they were planned)."""
    import interphase.campaign.plan as plan_module
    import interphase.campaign.run as run_module

    rt = [float(f"{0.01 * i:.2f}") for i in range(1, 101)]
    mu = [float(f"{0.005 * i:.3f}") for i in range(1, 101)]
    f = _write(tmp_path, {"profile.rt": rt, "friction_ps": mu, "seed": list(range(1, 101))})
    pulled = []

    def counted(*a, **kw):
        for p in iter_plan(*a, **kw):
            pulled.append(p)
            yield p

    def eager(*a, **kw):
        raise AssertionError("a million cases planned eagerly")

    monkeypatch.setattr(plan_module, "iter_plan", counted)
    monkeypatch.setattr(run_module, "plan", eager)
    assert main(["run", str(f), "--dry-run"]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert "1000000 case(s) in the sweeps × 1 engine(s) = 1000000" in lines[0]
    assert sum(ln.startswith("  run ") for ln in lines) == 10 and "`--dry-run --yes`" in out
    assert not (tmp_path / "runs").exists()              # no deck, no folder
    assert len(pulled) <= run_module.SAMPLE + 1, len(pulled)
    for extra in ([], ["--dry-run", "--render"], ["--dry-run", "--list"]):
        assert main(["run", str(f), *extra]) == 2
        err = capsys.readouterr().err
        assert "1000000 cases is more than 10000" in err and "--yes" in err
    # checked at load all the same: one bad value among 100 is refused
    f.write_text(f.read_text().replace("seed = [1,", "seed = [-1,"))
    assert main(["run", str(f), "--dry-run"]) == 2
    assert "sweep.seed" in capsys.readouterr().err


def test_lazy_planning_gives_the_eager_plans_ids(tmp_path, monkeypatch):
    f = _write(tmp_path, {"profile.rt": [0.5, 1, 2], "friction_ps": [0.2, 0.5], "seed": [1, 2, 3]})
    eager = load_campaign(f)
    monkeypatch.setattr(schema, "EAGER_MAX", 5)
    lazy = load_campaign(f)
    assert lazy.lazy and not eager.lazy and lazy.size == eager.size == 18 and lazy.cases == ()
    a = {p.case_id: (p.pair_id, p.label) for p in plan(eager)}
    b = {p.case_id: (p.pair_id, p.label) for p in iter_plan(lazy)}
    assert a == b and len(a) == 18 + 3


def test_one_meaning_per_option():
    sub = next(a for a in build_parser()._actions if a.dest == "command").choices
    opts = {name: {s for a in p._actions for s in a.option_strings} for name, p in sub.items()}
    for name in ("run", "status", "crosscheck", "report"):
        assert "--runs" in opts[name], name                 # the campaign's runs folder
    for name in ("render", "run-case", "report", "compare"):
        assert "--output" in opts[name], name              # what the command writes
    for name in ("run", "status", "crosscheck", "report", "compare", "predict", "theta-a", "render", "run-case"):
        assert "--json" in opts[name], name


def test_run_json(tmp_path, capsys):
    f = _write(tmp_path)
    assert main(["run", str(f), "--dry-run", "--json"]) == 0
    captured = capsys.readouterr()
    data = json.loads(captured.out)
    assert data["planned"] == 4 and data["runs"] == str(tmp_path / "runs" / "c") and data["counts"] == {"pending": 4}
    assert "dry run" in captured.err                   # the progress, on stderr
