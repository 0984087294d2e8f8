"""The command line: its commands, help and errors (the tour itself: tests/library/test_tour.py)."""

import subprocess
import sys

from particles.cli import main


def test_console_script_help():
    """`python -m particles --help` lists the commands."""
    result = subprocess.run([sys.executable, "-m", "particles", "--help"], capture_output=True, text=True)
    assert result.returncode == 0 and "tour" in result.stdout and "demo" in result.stdout


def test_unknown_command_fails_cleanly():
    """An unknown command exits with status 2 and says the choice is invalid."""
    result = subprocess.run([sys.executable, "-m", "particles", "fly"], capture_output=True, text=True)
    assert result.returncode == 2 and "invalid choice" in result.stderr


def test_site_with_a_missing_lectures_folder_fails_cleanly(tmp_path, capsys):
    """`particles site` names the missing folder, exits 2, and creates no output folder."""
    assert main(["site", "--lectures", str(tmp_path / "nowhere"), "--out", str(tmp_path / "site")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert not (tmp_path / "site").exists()
