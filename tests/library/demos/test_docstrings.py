"""Docstrings of the demos and the effects' public API: numpydoc sections, the common arguments once."""

import pytest


def _documented(function):
    """The parameter names listed in the numpydoc Parameters section of `function`, and its section titles."""
    import inspect
    import re

    doc = inspect.getdoc(function) or ""
    sections = set(re.findall(r"^(\w[\w ]*)\n-{3,}$", doc, flags=re.M))
    listed = set()
    block = re.search(r"^Parameters\n-{3,}\n(.*?)(?=^\w[\w ]*\n-{3,}$|\Z)", doc, flags=re.M | re.S)
    for line in (block.group(1).splitlines() if block else []):
        if line and not line[0].isspace():
            listed.update(name.strip() for name in line.split(":")[0].split(","))
    return listed, sections


def _public_api_of_the_effects():
    from particles import demos, render
    from particles.collisions import Contacts
    from particles.effects import Boids, Disk, Point, SphereSurface

    functions = [demo.function for demo in demos.DEMOS.values()]
    functions += [demos.run_demo, demos.register, demos.effects.record_effect, demos.data.circle,
                  demos.data.steps_per_frame, Contacts.empty, Contacts.concatenate, render.save_gif, render.to_html,
                  render.animate_snapshots, Boids.add_to]
    functions += [getattr(shape, method) for shape in (Point, Disk, SphereSurface) for method in ("sample", "normal")]
    return functions


@pytest.mark.parametrize("function", _public_api_of_the_effects(), ids=lambda f: f.__qualname__)
def test_public_functions_have_numpydoc_sections(function):
    """Each public function lists every argument under Parameters and, unless it works in place, has Returns."""
    import inspect

    listed, sections = _documented(function)
    star = {inspect.Parameter.VAR_POSITIONAL: "*", inspect.Parameter.VAR_KEYWORD: "**"}
    wanted = {star.get(p.kind, "") + name for name, p in inspect.signature(function).parameters.items()
              if name not in ("self", "cls")}
    assert "Parameters" in sections and wanted <= listed, f"not documented: {sorted(wanted - listed)}"
    assert "Returns" in sections or function.__name__ == "add_to"


def test_the_common_arguments_are_described_once():
    """The paragraph on seconds, fps and seed is written in the package docstring only, not in every demo."""
    from pathlib import Path

    import particles.demos as package

    texts = [p.read_text() for p in Path(package.__file__).parent.glob("*.py")]
    assert sum(t.count("does not change the physics") for t in texts) == 0
    assert sum(t.count("only says how often a frame is recorded") for t in texts) == 1
