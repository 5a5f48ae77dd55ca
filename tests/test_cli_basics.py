import subprocess
import sys


def test_help_lists_commands():
    out = subprocess.run([sys.executable, "-m", "interphase.cli", "--help"], capture_output=True, text=True)
    assert out.returncode == 0
    assert "campaign" in out.stdout


def test_status_messages_wrap_between_words_never_inside_a_path():
    from interphase.cli import _wrap

    path = "/tmp/" + "very-long-folder-name/" * 8 + "contacts.parquet"
    text = _wrap(f"abcd1234 corrupt: {path} does not verify; rerun with --rerun-failed", 40)
    lines = text.splitlines()
    assert len(lines) > 1 and all(len(ln) <= 40 for ln in lines if path not in ln)
    assert any(path in ln for ln in lines) and " ".join(ln.strip() for ln in lines).endswith("--rerun-failed")
