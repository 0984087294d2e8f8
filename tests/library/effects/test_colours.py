"""Colours without Matplotlib: Matplotlib's values to the last bit, and effects that run where it is missing."""

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from particles.effects import TAB10, ColorRamp, hsv_to_rgb, palette, to_rgb
from particles.effects.colours import BASIC

COLOURS = [*BASIC, "#f2fbff", "#5aa9e6", "#1D4E89", "#fff", "#ff000080", "0.25", "0.85", "1", (0.2, 0.4, 0.6),
           [1.0, 0.5, 0.0, 0.3], "tab:blue", "xkcd:sky blue"]


@pytest.mark.parametrize("color", COLOURS, ids=str)
def test_colours_are_read_as_matplotlib_reads_them(color):
    """to_rgb gives Matplotlib's RGB exactly, for the names it reads itself and those it asks Matplotlib about."""
    from matplotlib.colors import to_rgb as reference

    assert to_rgb(color) == reference(color)


@pytest.mark.parametrize("bad", ["nocolour", "#12345", "#ggg", "1.5", (1.0, 2.0), (0.1, 0.2), None])
def test_what_is_not_a_colour_is_refused(bad):
    """A string or sequence that is no colour raises ValueError (or TypeError for None) naming it."""
    with pytest.raises((ValueError, TypeError)):
        to_rgb(bad)


def test_hsv_and_palette_are_matplotlibs():
    """hsv_to_rgb and the tab10 palette equal Matplotlib's, bit for bit."""
    from matplotlib import colormaps
    from matplotlib.colors import hsv_to_rgb as reference

    hsv = np.random.default_rng(0).random((500, 3))
    hsv[::7, 1] = 0.0  # grey: saturation 0
    hsv[::11, 0] = 1.0  # the last hue wraps to the first sector
    np.testing.assert_array_equal(hsv_to_rgb(hsv), reference(hsv))
    np.testing.assert_array_equal(palette(23), colormaps["tab10"](np.arange(23) % 10)[:, :3])
    assert len(TAB10) == 10


def test_color_ramp_interpolates_colours_and_alphas():
    """A ramp from white to red fading out: the middle is pink and half transparent."""
    ramp = ColorRamp(["white", "#ff0000"], alphas=[1.0, 0.0])
    np.testing.assert_allclose(ramp(np.array([0.5])), [[1.0, 0.5, 0.5, 0.5]])
    with pytest.raises(ValueError, match="colors must be a list of Matplotlib colours"):
        ColorRamp(["nocolour"])


def test_an_effect_runs_where_matplotlib_cannot_be_imported():
    """With Matplotlib made unimportable, a fountain with tints and a colour ramp is built and run."""
    code = textwrap.dedent("""
        import sys
        class NoMatplotlib:
            def find_spec(self, name, path=None, target=None):
                if name.split(".")[0] in ("matplotlib", "mpl_toolkits"):
                    raise ImportError(f"{name} is blocked for this test")
        sys.meta_path.insert(0, NoMatplotlib())
        import numpy as np
        import particles
        from particles.effects import ColorRamp, Cone, Emitter, ParticleEffect, ParticleEmitter, Point
        from particles.forces import Gravity
        tap = Emitter(50.0, Point([0.0, 0.0]), Cone([0.0, 1.0], 3.0, angle=0.3), lifetime=0.5, tint="random")
        fountain = ParticleEffect(2, [tap], forces=[Gravity([0.0, -9.81])], seed=0,
                                  color=ColorRamp(["#5aa9e6", "0.5", "white"]))
        spray = fountain.add_child(ParticleEffect(2, seed=1))
        spray.add_emitter(ParticleEmitter(fountain, rate=10.0, lifetime=0.2, tint="orange"))
        frames = fountain.run(1.0, h=0.01, every=50)
        assert len(frames[-1]) > 0 and frames[-1].rgba.shape[1] == 4
        try:
            ColorRamp(["tab:blue"])
        except ValueError as error:
            print("refused:", error)
        assert not any(m.startswith("matplotlib") for m in sys.modules)
        print("ran", len(frames), "frames")
    """)
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert "ran 3 frames" in result.stdout and "refused: colors must be a list" in result.stdout
