"""The course tour (particles.tour, what ``make demo`` runs): every file it writes and every number it prints.

The tour writes each study of ``particles study`` (particles.studies.report) with its summary, so the
studies' files and key numbers are checked here, on one run of the tour (about 30 s), not again.
"""

import contextlib
import csv
import inspect
import io
import re

import pytest
from PIL import Image

from particles.cli import main
from particles.demos import DEMOS
from particles.tour import force_field_scene, lennard_jones_costs


@pytest.fixture(scope="module")
def tour(tmp_path_factory):
    """``particles tour`` run once: ``(out folder, printed lines)``."""
    out = tmp_path_factory.mktemp("tour")
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        status = main(["tour", "--out", str(out)])
    assert status == 0
    return out, printed.getvalue().splitlines()


def test_tour_writes_files_and_prints_table(tour):
    """`particles tour` writes every figure, table and animation, and prints the measured orders."""
    out, lines = tour
    text = "\n".join(lines)
    for name in ("order.png", "order.svg", "order.csv", "force_field.gif", "lennard_jones_costs.csv",
                 "stability.png", "provot.svg", "discretization.csv"):
        assert (out / name).stat().st_size > 0, name
    assert "rk4                expected 4  observed 4.0" in text
    with Image.open(out / "force_field.gif") as gif:
        assert gif.n_frames == len(force_field_scene()[0])
    rows = list(csv.DictReader(open(out / "order.csv")))
    assert {r["method"] for r in rows} >= {"euler", "rk4", "verlet", "implicit_euler"}
    assert (out / "bounce.png").stat().st_size > 0
    assert "backtrack  1.00       20" in text
    for name, demo in DEMOS.items():  # the effects: one preview GIF per demo
        seconds = demo.preview.get("seconds", inspect.signature(demo.function).parameters["seconds"].default)
        with Image.open(out / f"{name}.gif") as gif:
            assert gif.n_frames == round(seconds * demo.preview["fps"]) + 1, name


# study -> (files written, checks of the summary: (pattern capturing a number, lower bound, upper bound))
STUDY_OUTPUTS = {
    "order": (["order.csv", "order.png", "order.svg"],
              [(r"^rk4 .*observed (\d+\.\d+)", 3.9, 4.1), (r"^verlet .*observed (\d+\.\d+)", 1.9, 2.1)]),
    "stability": (["stability.csv", "stability.png", "stability.svg", "stability_cost.csv"],
                  [(r"^verlet .*omega h_max = (\d+\.\d+)", 1.98, 2.0), (r"^rk4 .*omega h_max = (\d+\.\d+)", 2.80, 2.83),
                   (r"^symplectic_euler .*slope of h_max vs k: ([-+]\d+\.\d+)", -0.51, -0.49)]),
    "provot": (["provot.csv", "provot.png", "provot.svg"],
               [(r"soft springs (\d+)%", 30, 100), (r"with the constraint (\d+\.\d+)%", 9.0, 11.0)]),
    "discretization": (["discretization.csv", "discretization.png", "discretization.svg"],
                       [(r"^physical +sag \(mm\) \[(\d+\.\d+)", 8.0, 9.0), (r"^physical .*h_max ~ dx\^(\d+\.\d+)", 0.9, 1.1),
                        (r"^naive .*h_max ~ dx\^(-?\d+\.\d+)", -0.1, 0.1)]),
    "bounce": (["bounce.csv", "bounce.png", "bounce.svg"],
               [(r"^backtrack +1\.00 +(\d+) ", 20, 20), (r"^project +0\.80 +(\d+) ", 6, 6)]),
}


def _summary(lines, name):
    """The study's lines of the tour's output: its "study NAME (...)" line and its indented summary below."""
    start = [k for k, line in enumerate(lines) if line.strip().startswith(f"study {name} (")]
    assert len(start) == 1, f"one line 'study {name} (' expected in the tour's output"
    k, indent = start[0], len(lines[start[0]]) - len(lines[start[0]].lstrip())
    block = [lines[k].strip()]
    for line in lines[k + 1:]:  # a loop over the lines below, while they are indented deeper
        if not line.strip() or len(line) - len(line.lstrip()) <= indent:
            break
        block.append(line.strip())
    return block


def _key_number(lines, pattern):
    """The number captured by `pattern` in the one summary line it matches."""
    found = [m for m in (re.search(pattern, line) for line in lines) if m]
    assert len(found) == 1, f"{pattern!r} should match one line of {lines}"
    return float(found[0].group(1))


@pytest.mark.parametrize("name", sorted(STUDY_OUTPUTS))
def test_each_study_writes_its_files_and_prints_its_key_numbers(tour, name):
    """Each study writes a non-empty PNG, SVG and CSV table(s), names them, and prints its key numbers."""
    out, lines = tour
    expected, checks = STUDY_OUTPUTS[name]
    summary = _summary(lines, name)
    files = [out / f for f in expected]
    assert all(p.stat().st_size > 0 for p in files)
    for p in files:
        head = p.read_bytes()[:400]
        if p.suffix == ".png":
            assert head.startswith(b"\x89PNG\r\n\x1a\n")
        elif p.suffix == ".svg":
            assert b"<svg" in head
        else:
            with open(p, newline="") as fh:
                rows = list(csv.reader(fh))
            assert len(rows) >= 3 and all(len(r) == len(rows[0]) for r in rows)
    named = re.findall(r"[\w.]+\.(?:png|svg|csv)", summary[0])
    assert sorted(named) == expected, summary[0]
    for pattern, low, high in checks:
        assert low <= _key_number(summary[1:], pattern) <= high, (pattern, summary)


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
