"""The files of ``particles study`` (particles.studies.report): figures, tables and key numbers."""

import csv
import re

import pytest

from particles.studies.report import write_study, write_table


def _key_number(lines, pattern):
    """The number captured by `pattern` in the one summary line it matches."""
    found = [m for m in (re.search(pattern, line.strip()) for line in lines) if m]
    assert len(found) == 1, f"{pattern!r} should match one line of {lines}"
    return float(found[0].group(1))


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
                       [(r"^physical +sag \(mm\) \[(\d+\.\d+)", 8.0, 9.0), (r"^physical .*h_max ~ dx\^(\d+\.\d+)", 0.9, 1.1), (r"^naive .*h_max ~ dx\^(-?\d+\.\d+)", -0.1, 0.1)]),
}


@pytest.mark.parametrize("name", sorted(STUDY_OUTPUTS))
def test_write_study_files_and_summary(name, tmp_path):
    """Each study writes a non-empty PNG, SVG and CSV table(s) and prints its key numbers."""
    lines = []
    files = write_study(name, tmp_path, log=lines.append)
    expected, checks = STUDY_OUTPUTS[name]
    assert sorted(p.name for p in files) == expected
    assert all(p.parent == tmp_path and p.stat().st_size > 0 for p in files)
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
    assert lines[0].startswith(f"study {name} (") and all(p.name in lines[0] for p in files)
    for pattern, low, high in checks:
        assert low <= _key_number(lines[1:], pattern) <= high, (pattern, lines)


def test_write_study_and_write_table_errors(tmp_path):
    """Unknown study names, a non-callable log and empty tables are ValueErrors naming the problem."""
    with pytest.raises(ValueError, match="unknown study 'speed'; expected one of 'order'"):
        write_study("speed", tmp_path)
    with pytest.raises(ValueError, match="name must be a study's name"):
        write_study(["order"], tmp_path)
    with pytest.raises(ValueError, match="log must be callable"):
        write_study("order", tmp_path, log="stdout")
    with pytest.raises(ValueError, match="rows must be a non-empty list of dicts"):
        write_table(tmp_path, "empty", [])
    assert write_table(str(tmp_path), "t", [{"a": 1, "b": 2}]).read_text().splitlines() == ["a,b", "1,2"]
