"""The README's example and the docstring examples run and say what they claim."""

import doctest
import importlib
import pkgutil
import re
from pathlib import Path

import pytest

import particles

ROOT = Path(__file__).resolve().parents[2]
MODULES = sorted(
    name for _, name, _ in pkgutil.walk_packages(particles.__path__, "particles.")
    if not name.endswith("__main__")
)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    """Every >>> example in the library's docstrings runs and prints what it shows."""
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0


def test_readme_api_example_runs(capsys):
    """The ten-line example of the README works as printed."""
    text = (ROOT / "README.md").read_text()
    block = re.search(r"## The library in ten lines\s+```python\n(.*?)```", text, re.S).group(1)
    assert len(block.strip().splitlines()) <= 10
    exec(compile(block, "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert out.startswith("(21, 500, 2, 2)")


def test_readme_quick_start_is_the_two_commands():
    """The README's quick start is `make demo` and `make test`, and CI runs `make test`."""
    text = (ROOT / "README.md").read_text()
    quick = re.search(r"## Quick start(.*?)##", text, re.S).group(1)
    commands = re.findall(r"^make \w+", quick, re.M)
    assert commands == ["make demo", "make test"]
    assert "make test" in (ROOT / ".ci" / "run").read_text()
