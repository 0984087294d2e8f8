"""particles.studies.report: what write_study returns and logs, its errors and tables. The files and key
numbers of every study are checked on the course tour's output, which writes them all
(tests/library/test_tour.py): run once, not twice; here only the shortest study runs again."""

import pytest

from particles.studies.report import write_study, write_table


def test_write_study_returns_the_files_it_wrote_and_logs_them_first(tmp_path):
    """write_study returns the files it wrote, all non-empty in `out`, and its first log line names them."""
    lines = []
    files = write_study("bounce", tmp_path, log=lines.append)
    assert sorted(p.name for p in files) == ["bounce.csv", "bounce.png", "bounce.svg"]
    assert all(p.parent == tmp_path and p.stat().st_size > 0 for p in files)
    assert lines[0].startswith("study bounce (") and all(p.name in lines[0] for p in files)
    assert len(lines) > 1  # its summary follows


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
