"""The demo registry (particles.demos): every demo's data, headless GIFs of one image per frame, the CLI."""

import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from particles.cli import main
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
