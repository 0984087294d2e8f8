"""The command line: the tour writes its figures, animation and tables."""

import csv
import inspect
import subprocess
import sys

from PIL import Image

from particles.cli import main
from particles.demos import DEMOS
from particles.tour import force_field_scene, lennard_jones_costs


def test_tour_writes_files_and_prints_table(tmp_path, capsys):
    """`particles tour` writes every figure, table and animation, and prints the measured orders."""
    assert main(["tour", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    for name in ("order.png", "order.svg", "order.csv", "force_field.gif", "lennard_jones_costs.csv",
                 "stability.png", "provot.svg", "discretization.csv"):
        assert (tmp_path / name).stat().st_size > 0, name
    assert "rk4                expected 4  observed 4.0" in out
    with Image.open(tmp_path / "force_field.gif") as gif:
        assert gif.n_frames == len(force_field_scene()[0])
    rows = list(csv.DictReader(open(tmp_path / "order.csv")))
    assert {r["method"] for r in rows} >= {"euler", "rk4", "verlet", "implicit_euler"}
    assert (tmp_path / "bounce.png").stat().st_size > 0
    assert "backtrack  1.00       20" in out
    for name, demo in DEMOS.items():  # the effects: one preview GIF per demo
        seconds = demo.preview.get("seconds", inspect.signature(demo.function).parameters["seconds"].default)
        with Image.open(tmp_path / f"{name}.gif") as gif:
            assert gif.n_frames == round(seconds * demo.preview["fps"]) + 1, name


def test_force_field_scene_stays_bounded():
    """The tour's swirl keeps its particles on screen (damping balances the fields)."""
    t, X = force_field_scene(n=50)
    assert X.shape == (len(t), 50, 2, 2)
    assert abs(X[:, :, 0]).max() < 2.5


def test_lennard_jones_costs_rows():
    """The Lennard-Jones cost table has one row per size, with pairs and both searches' times."""
    rows = lennard_jones_costs(sizes=(100, 200))
    assert [r["n"] for r in rows] == [100, 200]
    assert all(r["pairs"] > 0 and r["all_s"] > 0 and r["cells_s"] > 0 for r in rows)


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
