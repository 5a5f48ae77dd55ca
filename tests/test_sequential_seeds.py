"""Sequential seeds ([seeds]): the schema (bad tables exit 2 naming file, line and field), the round
logic on tables without an engine, and a tiny real campaign where only the wide case gets a seed."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from tests.campaign_files import TINY_CASE, toml_text
from tests.conftest import need_binary

from interphase.campaign.plan import plan
from interphase.campaign.schema import SeedRule, load_campaign
from interphase.campaign.sequential import cap_notes, interface_key, replay, wanted_ids
from interphase.cli import main

#: two physical cases (μs 0.05 and 0.5) of the tiny periodic case, sheared at 0.02 m/s
BASE_TABLES = dict(campaign={"name": "seq", "engines": ["liggghts"], "output": "out"},
                   execution={"jobs": 2},
                   case={"device": "periodic", **TINY_CASE, "shear_velocity": 0.02},
                   sweep={"friction_ps": [0.05, 0.5]})
BASE = toml_text(**BASE_TABLES)
SEEDS = '\n[seeds]\nstart = 3\nmax = {max}\ntarget = {{quantity = "E", halfwidth = {h}}}\n'

# (what replaces the [seeds] table's text, line the message points at, what it must name)
BAD = {
    "unknown key": ("[seeds]\nstart = 3\nmax = 4\nstep = 1\nstpe = 2\ntarget = {quantity = \"E\", halfwidth = 0.05}",
                    26, "seeds.stpe"),
    "start > max": ("[seeds]\nstart = 5\nmax = 4\ntarget = {quantity = \"E\", halfwidth = 0.05}", 23, "seeds.start"),
    "halfwidth 0": ("[seeds]\nstart = 3\nmax = 4\ntarget = {quantity = \"E\", halfwidth = 0}", 25,
                    "seeds.target.halfwidth"),
    "negative halfwidth": ("[seeds]\nstart = 3\nmax = 4\ntarget = {quantity = \"E\", halfwidth = -0.1}", 25,
                           "seeds.target.halfwidth"),
    "unknown quantity": ("[seeds]\nstart = 3\nmax = 4\ntarget = {quantity = \"E_peak\", halfwidth = 0.05}", 25,
                         "seeds.target.quantity"),
    "start of two seeds": ("[seeds]\nstart = 2\nmax = 4\ntarget = {quantity = \"E\", halfwidth = 0.05}", 23,
                          "seeds.start"),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_a_bad_seeds_table_exits_2_naming_file_line_and_field(name, tmp_path, capsys):
    table, line, field = BAD[name]
    f = tmp_path / "bad.toml"
    f.write_text(BASE + "\n" + table + "\n")
    assert main(["run", str(f), "--dry-run"]) == 2
    err = capsys.readouterr().err
    assert f"{f}:{line}: {field}" in err, err


def test_seeds_and_a_seed_sweep_is_an_error_naming_both(tmp_path, capsys):
    f = tmp_path / "both.toml"
    f.write_text(toml_text(**(BASE_TABLES | {"sweep": {"friction_ps": [0.05, 0.5], "seed": [1, 2, 3]}}))
                 + SEEDS.format(max=4, h=0.05))
    assert main(["run", str(f), "--dry-run"]) == 2
    err = capsys.readouterr().err
    assert f"{f}:21: sweep.seed" in err and "[seeds] (line 23)" in err, err


def test_seeds_plan_every_seed_to_the_cap_and_run_start_first(tmp_path):
    f = tmp_path / "ok.toml"
    f.write_text(BASE + SEEDS.format(max=5, h=0.05))
    c = load_campaign(f)
    assert c.seeds == SeedRule(3, 5, 1, "E", 0.05)
    planned = plan(c, identity=lambda name: "0123456789abcdef")
    assert sorted({p.case.seed for p in planned}) == [1, 2, 3, 4, 5]
    keys = {interface_key(p) for p in planned if p.role == "interface"}
    assert len(keys) == 2 and {k[2] for k in keys} == {p.physical_id for p in planned if p.role == "interface"}
    rounds = replay(c.seeds, {k: set() for k in keys}, lambda k: {})
    want = wanted_ids(c.seeds, planned, rounds)
    ran = sorted((p.role, p.case.seed) for p in planned if p.case_id in want)
    assert ran == [("box", 1), ("box", 2), ("box", 3)] + [("interface", 1)] * 2 + [("interface", 2)] * 2 \
        + [("interface", 3)] * 2


def _t_eval(values: dict):
    """evaluate() for replay: each case's mean of its seeds 1..k with a 95 % t interval."""
    def evaluate(k):
        out = {}
        for key, n in k.items():
            v = np.asarray(values[key][:n])
            half = stats.t.ppf(0.975, n - 1) * v.std(ddof=1) / math.sqrt(n)
            out[key] = (v.mean(), v.mean() - half, v.mean() + half)
        return out
    return evaluate


def _named(evaluate):
    """The evaluator on keys (engine, group, case) from one on case names."""
    return lambda k: {("e", "g", c): v for c, v in evaluate({key[2]: n for key, n in k.items()}).items()}


def _replay(rule, done, evaluate):
    """sequential.replay on case names: {case: CaseRound}."""
    return {key[2]: r for key, r in replay(rule, {("e", "g", c): s for c, s in done.items()}, evaluate).items()}


def test_rounds_add_seeds_only_where_the_interval_is_wide():
    rule = SeedRule(start=3, max=6, step=1, quantity="tan_delta", halfwidth=0.05)
    values = {"narrow": [0.50, 0.51, 0.49, 0.50, 0.5, 0.5], "wide": [0.44, 0.56, 0.5, 0.5, 0.5, 0.5],
              "noisy": [0.1, 0.9, 0.2, 0.8, 0.3, 0.7]}
    evaluate = _named(_t_eval(values))
    replay = _replay
    # nothing ran: every case asks for seeds 1..start
    r = replay(rule, {k: set() for k in values}, evaluate)
    assert {k: v.wanted for k, v in r.items()} == {"narrow": 3, "wide": 3, "noisy": 3}
    assert all(v.state == "waiting" for v in r.values())
    # the first round finished: the wide cases get a 4th seed, the narrow one too, its confirming round
    r = replay(rule, {k: {1, 2, 3} for k in values}, evaluate)
    assert {k: (v.wanted, v.state) for k, v in r.items()} == {"narrow": (4, "confirming"), "wide": (4, "adding"),
                                                              "noisy": (4, "adding")}
    assert r["narrow"].halfwidth <= 0.05 < r["wide"].halfwidth
    # every seed finished: the rounds replay to the same stops; the narrow case stops after its
    # confirming round, the wide one reaches the target at the cap, 6 seeds (± 0.040; ± 0.053 at
    # 5), the noisy one stops at the cap
    r = replay(rule, {k: set(range(1, 7)) for k in values}, evaluate)
    assert {k: (v.wanted, v.n, v.state) for k, v in r.items()} == {
        "narrow": (4, 4, "reached"), "wide": (6, 6, "reached"), "noisy": (6, 6, "capped")}
    # a case waiting on a run is not judged and does not hold the others back
    r = replay(rule, {"narrow": {1, 2, 3}, "wide": {1, 2, 3, 5}, "noisy": set(range(1, 7))}, evaluate)
    assert (r["wide"].wanted, r["wide"].state, r["wide"].finished) == (4, "adding", 4)
    assert r["noisy"].state == "capped" and r["narrow"].state == "confirming"
    # step 2: seeds come two at a time, never beyond the cap
    r = replay(SeedRule(3, 6, 2, "tan_delta", 0.05), {k: set(range(1, 6)) for k in values}, evaluate)
    assert (r["wide"].n, r["wide"].wanted, r["wide"].state) == (5, 6, "adding")      # judged at 3 and 5
    assert (r["noisy"].n, r["noisy"].wanted) == (5, 6)
    assert (r["narrow"].n, r["narrow"].wanted, r["narrow"].state) == (5, 5, "reached")   # 3, then 5 to confirm


def test_a_confirming_round_that_reads_wide_goes_on_adding_seeds():
    """Within the target at 3 seeds (± 0.025), the 4th seed an outlier (± 0.081 at 4): the case does
    not stop on the wide reading but adds seeds until two rounds in a row read within (± 0.043 at
    the cap, 6); a case that stops before the cap always reports an interval within the target."""
    rule = SeedRule(start=3, max=6, step=1, quantity="tan_delta", halfwidth=0.05)
    evaluate = _named(_t_eval({"relapse": [0.50, 0.51, 0.49, 0.60, 0.50, 0.50]}))
    states = [(r.wanted, r.state, round(r.halfwidth, 3))
              for r in (_replay(rule, {"relapse": set(range(1, n + 1))}, evaluate)["relapse"] for n in (3, 4, 5, 6))]
    assert states == [(4, "confirming", 0.025), (5, "adding", 0.081), (6, "adding", 0.056), (6, "reached", 0.043)]


def test_cap_notes_name_only_the_cases_that_stopped_at_the_cap():
    import pandas as pd

    rule = SeedRule(3, 6, 1, "E", 0.05)
    table = pd.DataFrame({"seeds": [6, 6, 4], "E": [1.0, 1.0, 1.0], "E_lo": [0.8, 0.97, 0.7], "E_hi": [1.2, 1.03, 1.3]})
    notes = cap_notes(table, rule)
    assert notes[0].startswith("hit the seed cap (6) at ± 0.2 in E") and notes[1] == "" and notes[2] == ""


def _status(f: Path) -> dict:
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["status", str(f), "--json"]) == 0
    return json.loads(buf.getvalue())


@pytest.mark.liggghts
def test_a_tiny_sequential_campaign_adds_seeds_only_to_the_case_still_wide(tmp_path):
    """Two physical cases with E as the target. Seeds 1–3, then 4 (the cap at 3, then at 4, with an
    unreachable target) give each case its E interval at 3 and at 4 seeds. Then the target is set
    between the two 4-seed readings, above both 3-seed ones, and the cap raised to 5: the rounds
    replay from the finished runs; both cases read within at 3 and run a confirming seed 4; the one
    that reads within again stops there, the one whose 4th seed widened it goes on to seed 5 (with
    its soil test); nothing finished is rerun, and a rerun runs nothing."""
    need_binary("liggghts")
    f = tmp_path / "seq.toml"
    halves = {}
    for cap in (3, 4):
        f.write_text(BASE + SEEDS.format(max=cap, h=1e-9))
        assert main(["run", str(f), "--plain"]) == 0
        status = {r["case"]: r for r in _status(f)["seeds"]}
        assert {(r["finished"], r["wanted"], r["n"], r["state"]) for r in status.values()} == {
            (cap, cap, cap, "capped")}
        for case, r in status.items():
            halves.setdefault(case, []).append(r["halfwidth"])
    narrow, wide = sorted(halves, key=lambda c: halves[c][1])
    target = (halves[narrow][1] + halves[wide][1]) / 2
    assert max(halves[narrow][0], halves[wide][0]) <= target, f"a 3-seed reading is wider than the target: {halves}"
    out = tmp_path / "out"
    done_before = {p.name: (p / "DONE").stat().st_mtime_ns for p in out.iterdir() if (p / "DONE").exists()}
    assert len(done_before) == 12                  # 2 cases × 4 seeds + the 4 soil tests

    f.write_text(BASE + SEEDS.format(max=5, h=target))
    assert main(["run", str(f), "--plain"]) == 0
    status = _status(f)
    seeds = {r["case"]: r for r in status["seeds"]}
    assert (seeds[narrow]["finished"], seeds[narrow]["wanted"], seeds[narrow]["state"]) == (4, 4, "reached")
    assert (seeds[wide]["finished"], seeds[wide]["wanted"], seeds[wide]["n"]) == (5, 5, 5)
    assert seeds[wide]["state"] in ("reached", "capped")
    labels = [r["label"] for r in status["cases"]]
    box = "box-periodic-box-mu0.9-mono"
    assert sorted(lb for lb in labels if lb.endswith("-s4")) == sorted([f"{wide}-s4", f"{narrow}-s4", f"{box}-s4"])
    assert sorted(lb for lb in labels if lb.endswith("-s5")) == sorted([f"{wide}-s5", f"{box}-s5"])
    after = {p.name: (p / "DONE").stat().st_mtime_ns for p in out.iterdir() if (p / "DONE").exists()}
    assert len(after) == 14 and all(after[k] == v for k, v in done_before.items())  # nothing finished reran
    assert main(["run", str(f), "--plain"]) == 0                    # the rounds replay: nothing to run
    assert {p.name: (p / "DONE").stat().st_mtime_ns for p in out.iterdir() if (p / "DONE").exists()} == after
