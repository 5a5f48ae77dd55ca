"""Issue 40 item 6 and the smaller items: the API and the CLI speak one language (one keyword per
meaning; the README's option table is the parser's, checked both ways); -o on run and crosscheck;
render refuses a non-empty folder; the ensembles carry the physical inputs; the sequential dry run
says one count per meaning and a time estimate; docs/architecture.md names every module."""

from __future__ import annotations

import inspect
import re
from pathlib import Path

import pandas as pd
import pytest

import interphase as ip
from interphase.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[1]


def _subparsers():
    parser = build_parser()
    (sub,) = [a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction"]
    return sub.choices


def _option_groups(p) -> list[set]:
    """Each option of a (sub)parser as the set of its spellings; a command with kinds (`profile
    sawtooth|…|plot`) has its kinds' options."""
    out = []
    for a in p._actions:
        if a.__class__.__name__ == "_SubParsersAction":
            for q in a.choices.values():
                out += [g for g in _option_groups(q) if g not in out]
        elif a.option_strings and "-h" not in a.option_strings:
            out.append(set(a.option_strings))
    return out


def _readme_rows() -> dict[str, str]:
    """{command: the first cell of its row} of the README's command table."""
    text = (ROOT / "docs" / "cli.md").read_text().split("## Commands", 1)[1].split("\n## ", 1)[0]
    rows = {}
    for line in text.splitlines():
        m = re.match(r"^\| `campaign ([a-z-]+)(.*?)` \|", line)
        if m:
            rows.setdefault(m.group(1), "")
            rows[m.group(1)] += " " + line.split(" | ")[0]
    return rows


def test_the_readme_option_table_is_the_parsers():
    """README promised `-o` on run and crosscheck (only --output worked); the table and --help
    must list the same options, command by command."""
    rows = _readme_rows()
    parsers = _subparsers()
    assert set(rows) == set(parsers), set(rows) ^ set(parsers)
    for name, p in parsers.items():
        cell = rows[name]
        written = set(re.findall(r"(?<![\w-])(--?[a-z][a-z0-9-]*)", cell))
        groups = _option_groups(p)
        for g in groups:
            assert g & written, f"campaign {name}: {sorted(g)} is in --help but not in the README row"
        known = set().union(*groups) if groups else set()
        assert written <= known, f"campaign {name}: {sorted(written - known)} in the README but not in --help"


def test_one_keyword_per_meaning_across_the_api():
    """`runs=` is the runs folder (--runs) and `output=` what a command writes (-o) everywhere;
    the calibration's card was `card=`."""
    for fn in (ip.run, ip.status, ip.summaries, ip.ensembles, ip.element, ip.calibrate, ip.validate):
        params = inspect.signature(fn).parameters
        assert "output" not in params or fn in (ip.calibrate, ip.validate), fn
        assert fn is ip.element or not {"card", "card_path"} & set(params), fn     # element's card is its input
    for fn in (ip.run, ip.element, ip.calibrate, ip.validate):
        assert "runs" in inspect.signature(fn).parameters, fn


def test_element_with_a_bad_stress_leaves_no_file(tmp_path):
    """ip.element(card, -5) wrote the generated campaign file before the engine refused it."""
    card = tmp_path / "card.toml"
    card.write_text((ROOT / "tests" / "data" / "soils" / "tiny_card.toml").read_text())
    for bad in (-5, 0, float("nan")):
        with pytest.raises(ip.InputError, match="--normal-stress"):
            ip.element(card, bad)
    with pytest.raises(ip.InputError, match="seeds"):
        ip.element(card, 100e3, seeds=0)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["card.toml"]


def test_run_and_crosscheck_take_o(tmp_path):
    for cmd in ("run", "crosscheck"):
        args = build_parser().parse_args([cmd, "c.toml", "-o", str(tmp_path)])
        assert args.runs == str(tmp_path)


def test_render_refuses_a_non_empty_folder(tmp_path, capsys):
    case = tmp_path / "case.toml"
    case.write_text('[case]\ntest = "box"\ndevice = "periodic"\nbox_length_d50 = 12.0\nbox_height_d50 = 8.0\n'
                    'shear_velocity = 0.02\n')
    busy = tmp_path / "busy"
    busy.mkdir()
    (busy / "notes.txt").write_text("mine")
    assert main(["render", str(case), "-o", str(busy)]) == 2
    err = capsys.readouterr().err
    assert "not empty" in err and "busy-2" in err and sorted(p.name for p in busy.iterdir()) == ["notes.txt"]
    assert main(["render", str(case), "-o", str(tmp_path / "new")]) == 0


def test_ensembles_carry_the_physical_inputs():
    """`ensembles` carried only the label: no Rt, Sw, μ, gradation or device columns."""
    from interphase.campaign.results import with_inputs

    rows = pd.DataFrame({"physical_id": ["a", "a", "b"], "label": ["x-s1", "x-s2", "y-s1"], "test": "interface",
                         "device": "periodic", "rt": [1.0, 1.0, 2.0], "sw": 2.0, "sr": 0.0,
                         "friction_ps": [0.2, 0.2, 0.5], "gradation": "poly", "normal_stress": 1e5, "d50": 7e-4})
    table = pd.DataFrame({"group": ["g", "g"], "case": ["x", "y"], "physical_id": ["a", "b"], "tan_delta": [0.3, 0.4]})
    out = with_inputs(table, rows)
    assert list(out.columns[:3]) == ["group", "case", "test"]
    assert out.set_index("case").loc["y", ["rt", "sw", "sr", "friction_ps", "gradation", "device"]].tolist() == \
        [2.0, 2.0, 0.0, 0.5, "poly", "periodic"]
    assert out["tan_delta"].tolist() == [0.3, 0.4]


def test_sequential_dry_run_says_what_each_count_is_and_how_long(tmp_path, capsys):
    assert main(["run", str(ROOT / "studies" / "sequential_seeds" / "group1_sequential.toml"), "--dry-run",
                 "--runs", str(tmp_path / "r")]) == 0
    out = capsys.readouterr().out
    assert "at most (sequential seeds: up to 24 per physical case)" in out
    assert "this round 101 cases" in out and "estimated time:" in out and "slot-hour" in out


def test_architecture_names_every_module():
    text = (ROOT / "docs" / "architecture.md").read_text()
    src = ROOT / "src" / "interphase"
    missing = [str(p.relative_to(src)) for p in sorted(src.rglob("*.py"))
               if p.name != "__init__.py" and str(p.relative_to(src)) not in text and p.name not in text]
    assert not missing, missing
