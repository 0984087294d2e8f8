"""The effect demos: data that makes physical sense, and headless GIFs with one image per frame."""

import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from particles.cli import main
from particles.collisions import Box, Plane, Sphere
from particles.demos import DEMOS, DemoData, register, run_demo, write_demo

SHORT = dict(seconds=1.0, fps=5)  # 6 frames: enough to check the machinery quickly


@pytest.mark.parametrize("name", list(DEMOS))
def test_demo_writes_a_gif_with_one_image_per_frame(name, tmp_path, capsys):
    """`particles demo NAME` writes NAME.gif, non-empty, with seconds x fps + 1 frames."""
    assert main(["demo", name, "--out", str(tmp_path), "--seconds", "1", "--fps", "5"]) == 0
    path = tmp_path / f"{name}.gif"
    assert path.stat().st_size > 1000
    with Image.open(path) as gif:
        assert gif.n_frames == 6
    assert f"{name}: 6 frames" in capsys.readouterr().out


@pytest.mark.parametrize("name", list(DEMOS))
def test_demo_data_is_consistent(name):
    """Every frame has positions, velocities, colours and sizes for the same particles, all finite."""
    data = run_demo(name, **SHORT)
    assert isinstance(data, DemoData) and len(data) == 6
    np.testing.assert_allclose(data.times, np.linspace(0.0, 1.0, 6))
    assert sum(len(x) for x in data.positions) > 0
    for k, x in enumerate(data.positions):
        assert np.all(np.isfinite(x)) and x.shape[1] == len(data.limits)
        assert data.velocities[k].shape == x.shape
        assert data.colors[k].shape == (len(x), 4) and data.sizes[k].shape == (len(x),)
        assert np.all((data.colors[k] >= 0) & (data.colors[k] <= 1))


def test_fountain_water_stays_above_the_ground():
    """The fountain's collider keeps every drop on or above the ground plane."""
    data = run_demo("fountain", seconds=2.0, fps=5)
    ground = Plane([0, 0, 0], [0, 0, 1])
    assert min(ground.H(x).min(initial=0.0) for x in data.positions) >= -1e-12
    assert max(len(x) for x in data.positions) > 300


def test_bouncing_balls_stay_in_the_box_and_out_of_the_obstacles():
    """No ball is ever inside a wall, the ramp or the round obstacle."""
    data = run_demo("bouncing", seconds=2.0, fps=10)
    scene = Box([0.0, 0.0], [4.0, 3.0], container=True) | Sphere([2.2, 0.9], 0.45) | Plane([0.0, 0.8], [1.0, 2.0])
    assert min(scene.H(x).min() for x in data.positions) >= -1e-12
    assert data.info["contacts"] > 0


def test_fireworks_sparks_come_from_rockets():
    """Hierarchy: bursts appear only after the first rocket has died, and outnumber the rockets."""
    data = run_demo("fireworks", seconds=2.5, fps=10)
    counts = [len(x) for x in data.positions]
    assert counts[0] == 0 and max(counts) > 100  # 140 +- 40 sparks per rocket


def test_smoke_rises_and_fades():
    """Gravity points up: the smoke's centre rises; old puffs are more transparent than young ones."""
    data = run_demo("smoke", seconds=2.0, fps=5)
    heights = [x[:, 1].mean() for x in data.positions if len(x)]
    assert heights[-1] > heights[1] > 0
    x, rgba = data.positions[-1], data.colors[-1]
    high = x[:, 1] > np.median(x[:, 1])
    assert rgba[high, 3].mean() < rgba[~high, 3].mean()


def test_flock_aligns():
    """The flock demo measures its own polarization, which rises."""
    data = run_demo("flock")
    before, after = (float(p) for p in data.info["polarization"].split(" -> "))
    assert before < 0.2 and after > 0.9


def test_a_new_demo_is_one_registered_function(tmp_path):
    """Registering a function adds a demo to the CLI; springs are drawn (the cloth demo's hook)."""
    @register("test-chain", "a swinging chain, drawn with its springs")
    def chain(seconds=1.0, fps=4, seed=0):
        t = np.linspace(0.0, seconds, int(seconds * fps) + 1)
        x = [np.column_stack([np.sin(0.3 * np.sin(tk)) * np.arange(5), -np.arange(5.0)]) for tk in t]
        return DemoData("test-chain", "chain", t, x, springs=np.column_stack([np.arange(4), np.arange(1, 5)]),
                        limits=[(-2, 2), (-5, 1)])

    try:
        data, paths = write_demo("test-chain", tmp_path)
        with Image.open(paths[0]) as gif:
            assert gif.n_frames == 5
        assert main(["demo", "test-chain", "--out", str(tmp_path)]) == 0
    finally:
        del DEMOS["test-chain"]


def test_demo_runs_headless_from_the_command_line(tmp_path):
    """Without a display (no DISPLAY, no backend set) the console command still writes the GIF."""
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "MPLBACKEND", "WAYLAND_DISPLAY")}
    result = subprocess.run([sys.executable, "-m", "particles", "demo", "genesis", "--seconds", "0.4", "--fps", "5",
                             "--out", str(tmp_path)], capture_output=True, text=True, env=env)
    assert result.returncode == 0, result.stderr
    with Image.open(tmp_path / "genesis.gif") as gif:
        assert gif.n_frames == 3


def test_unknown_demo_is_rejected():
    """An unknown name lists the demos."""
    with pytest.raises(ValueError, match="unknown demo 'rain'; expected one of 'fountain'"):
        run_demo("rain")


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


def test_the_registry_lists_every_demo_of_every_family_module():
    """DEMOS is written out in particles/demos/__init__.py: every demo function of the family modules is in it."""
    import importlib
    import inspect
    import pkgutil

    import particles.demos as package

    listed = {demo.function for demo in DEMOS.values()}
    for info in pkgutil.iter_modules(package.__path__):
        module = importlib.import_module(f"particles.demos.{info.name}")
        for name in getattr(module, "__all__", []):
            function = getattr(module, name)
            if inspect.isfunction(function) and list(inspect.signature(function).parameters) == ["seconds", "fps",
                                                                                                  "seed"]:
                assert function in listed, f"particles.demos.{info.name}.{name} is not in DEMOS"
    assert list(DEMOS)[:8] == ["fountain", "fireworks", "smoke", "bouncing", "flock", "genesis", "cloth", "drape"]


def test_the_common_arguments_are_described_once():
    """The paragraph on seconds, fps and seed is written in the package docstring only, not in every demo."""
    from pathlib import Path

    import particles.demos as package

    texts = [p.read_text() for p in Path(package.__file__).parent.glob("*.py")]
    assert sum(t.count("does not change the physics") for t in texts) == 0
    assert sum(t.count("only says how often a frame is recorded") for t in texts) == 1
