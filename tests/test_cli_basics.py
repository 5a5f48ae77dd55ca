import re
import subprocess
import sys

import pytest


def test_help_lists_every_command_and_each_has_its_own_help(capsys):
    """--help lists exactly the commands the parser takes (argparse names them all when refusing an
    unknown one), and each command's own --help exits 0 with a usage line naming it."""
    from interphase.cli import main

    out = subprocess.run([sys.executable, "-m", "interphase.cli", "--help"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    listed = re.findall(r"^    (\S+)", out.stdout.split("positional arguments:")[1].split("options:")[0], re.M)
    bad = subprocess.run([sys.executable, "-m", "interphase.cli", "nosuch"], capture_output=True, text=True)
    assert bad.returncode == 2
    accepted = [c.strip(" '\"") for c in re.search(r"choose from (.*)\)", bad.stderr).group(1).split(",")]
    assert listed == accepted and {"theta-a", "profile", "run", "status", "report"} <= set(listed)
    for command in listed:
        with pytest.raises(SystemExit) as exc:
            main([command, "--help"])
        assert exc.value.code == 0
        assert capsys.readouterr().out.startswith(f"usage: campaign {command} ")


def test_status_messages_wrap_between_words_never_inside_a_path():
    from interphase.cli_text import _wrap

    path = "/tmp/" + "very-long-folder-name/" * 8 + "contacts.parquet"
    text = _wrap(f"abcd1234 corrupt: {path} does not verify; rerun with --rerun-failed", 40)
    lines = text.splitlines()
    assert len(lines) > 1 and all(len(ln) <= 40 for ln in lines if path not in ln)
    assert any(path in ln for ln in lines) and " ".join(ln.strip() for ln in lines).endswith("--rerun-failed")
