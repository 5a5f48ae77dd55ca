"""Issue 32 item 1, for real (LIGGGHTS, one tiny run): a finished case folder's checksums are
unchanged after every command is pointed at it. `campaign render CASE.toml -o runs/quick/<id>`
used to overwrite its in.deck, recipe.json, grains and STL files while status still said done;
`run-case -o` into another case's folder printed `skipped True` and that case's results."""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

import pytest

from tests.campaign_files import TINY_CASE, write_toml
from tests.conftest import need_binary

from interphase.cli import main

pytestmark = pytest.mark.liggghts

#: the tiny real case in a periodic cell
CASE = {"test": "interface", "device": "periodic", **TINY_CASE, "shear_velocity": 0.01}


def _sums(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def test_a_finished_folder_survives_every_command(tmp_path, capsys):
    need_binary("liggghts")
    camp = write_toml(tmp_path / "c.toml", campaign={"name": "c"}, case=CASE, pairs={"box": False})
    same = write_toml(tmp_path / "same.toml", case=CASE)
    other = write_toml(tmp_path / "other.toml", case=CASE | {"seed": 2})
    assert main(["run", str(camp), "--plain"]) == 0
    runs = tmp_path / "runs" / "c"
    (folder,) = [p for p in runs.iterdir() if (p / "DONE").exists()]
    before = _sums(folder)
    assert {"in.deck", "DONE", "summary.json", "contacts.parquet"} <= set(before)
    capsys.readouterr()

    refused = [["render", str(same), "-o", str(folder)], ["render", str(other), "-o", str(folder)],
               ["render", str(same), "-o", str(runs)], ["run-case", str(other), "-o", str(folder)],
               ["run-case", str(same), "-o", str(folder), "--engine", "yade"]]
    for cmd in refused:
        assert main(cmd) == 2, cmd
        err = capsys.readouterr().err
        assert "Traceback" not in err and str(folder if cmd[-1] != str(runs) else runs) in err, (cmd, err)
        assert "new" in err, err                           # the way out
    # the same case: read back, not rerun
    assert main(["run-case", str(same), "-o", str(folder), "--json"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["skipped"] is True and "nothing was rerun" in captured.err
    others = [["run", str(camp), "--plain"], ["run", str(camp), "--plain", "--rerun-failed"],
              ["run", str(camp), "--dry-run", "--render"], ["status", str(camp)], ["status", str(camp), "--json"],
              ["report", str(camp), "--output", str(tmp_path / "rep"), "--bootstrap", "0"],
              ["compare", str(camp), str(camp)], ["crosscheck", str(camp), "--no-run"]]
    for cmd in others:
        rc = main(cmd)
        captured = capsys.readouterr()
        assert rc in (0, 1, 2) and "Traceback" not in captured.err, (cmd, captured.err)
    assert _sums(folder) == before
    assert main(["status", str(camp), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["counts"] == {"done": 1}
