"""`campaign run-case` outside a campaign: the runner's folder rules, engine-free."""

from __future__ import annotations

import pytest

from interphase.campaign import store as st
from interphase.campaign.checks import load_case_file
from interphase.campaign.runner import run_single
from interphase.case import Case
from interphase.cli import main
from interphase.errors import InputError
from interphase.surface.spec import ProfileSpec

CASE = Case(profile=ProfileSpec("flat"), box_length_d50=16, box_height_d50=8)


def test_a_users_folder_is_never_cleared(tmp_path):
    (tmp_path / "thesis.tex").write_text("months of work")
    with pytest.raises(InputError, match="not a case folder"):
        run_single(CASE, "liggghts", tmp_path)
    assert (tmp_path / "thesis.tex").read_text() == "months of work"


def test_the_cli_refuses_it_with_exit_2(tmp_path, capsys):
    toml = tmp_path / "c.toml"
    toml.write_text('[case]\ntest = "interface"\nprofile = {kind = "flat"}\n')
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("keep")
    assert main(["run-case", str(toml), "-o", str(out)]) == 2
    assert "not a case folder" in capsys.readouterr().err and (out / "notes.txt").exists()


def test_a_finished_case_folder_is_not_run_again(tmp_path):
    row = {"test": "interface", "peak_stress_ratio": 0.42}
    st.write_json_atomic(tmp_path / st.CASE_JSON, {"case_id": "x", "engine": "liggghts", "inputs": CASE.canonical()})
    st.write_json_atomic(tmp_path / st.SUMMARY_JSON, {"row": row})
    st.mark_done(tmp_path)
    res = run_single(CASE, "liggghts", tmp_path)
    assert res["status"] == "done" and res["skipped"] and res["summary"] == row


@pytest.mark.parametrize("status", ["done", "failed"])
def test_a_folder_of_another_case_is_refused_and_left_alone(tmp_path, capsys, status):
    """Issue 32: `run-case -o` into another case's folder printed `skipped True` and that case's
    results (finished), or would clear its files (unfinished): refused, exit 2, naming the folder."""
    folder = tmp_path / "other"
    folder.mkdir()
    other = CASE.replace(seed=7)
    st.write_json_atomic(folder / st.CASE_JSON, {"case_id": "x", "engine": "liggghts", "label": other.label(),
                                                 "inputs": other.canonical()})
    if status == "done":
        st.write_json_atomic(folder / st.SUMMARY_JSON, {"row": {"peak_stress_ratio": 0.4}})
        st.mark_done(folder)
    else:
        st.write_json_atomic(folder / st.FAILURE_JSON, {"status": "failed", "cause": "lost_atoms"})
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    toml = tmp_path / "c.toml"
    toml.write_text('[case]\ntest = "interface"\nprofile = {kind = "flat"}\nbox_length_d50 = 16\n'
                    'box_height_d50 = 8\n')
    assert main(["run-case", str(toml), "-o", str(folder)]) == 2
    err = capsys.readouterr().err
    assert str(folder) in err and other.label() in err and "other inputs" in err and "new or empty folder" in err
    assert "Traceback" not in err
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before
    # the same case under another engine is another case too
    with pytest.raises(InputError, match="engine liggghts, not yade"):
        run_single(other, "yade", folder)


def test_case_file_errors_name_the_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[case\n")
    with pytest.raises(InputError, match="TOML syntax error") as exc:
        load_case_file(bad)
    assert str(bad) in str(exc.value)
    bad.write_text("[other]\nx = 1\n")
    with pytest.raises(InputError, match=r"no \[case\] table"):
        load_case_file(bad)
    with pytest.raises(InputError, match="file not found"):
        load_case_file(tmp_path / "missing.toml")
    good = tmp_path / "good.toml"
    good.write_text('[case]\ntest = "box"\nd50 = 0.0007\n')
    assert load_case_file(good).test == "box"
