"""Explorations: values set from code re-run and redraw; the widget and the static player agree.

The lectures' four explorations are checked on what they are there to show: the blow-up above
``h_max`` (lecture 7), the damping's decay rate (lecture 2), Provot's strain against the passes
allowed (lecture 7) and the restitution law (lecture 3), with the numbers their prose states.
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import nbformat
import numpy as np
import pytest

from particles import explore
from particles.explore import STATIC, Exploration, figures

ROOT = Path(__file__).resolve().parents[3]


def toy(calls=None):
    """An exploration of y = a x whose runs are counted; its figure is a line of slope a."""
    calls = [] if calls is None else calls

    def run(a):
        calls.append(a)
        x = np.linspace(0.0, 1.0, 5)
        return {"a": a, "x": x, "y": a * x}

    def draw(data):
        fig, ax = plt.subplots(figsize=(2, 2))
        ax.plot(data["x"], data["y"])
        ax.set_title(f"a = {data['a']}")
        return fig

    return Exploration(run, draw, ("a", [1.0, 2.0, 3.0]), value=2.0, unit="m"), calls


def test_setting_the_value_reruns_once_and_redraws():
    """exp.value = v runs v (once, then from the cache) and the data, figure and image follow it."""
    exp, calls = toy()
    assert exp.value == 2.0 and calls == []
    open_figures = plt.get_fignums()
    first = exp.image
    assert calls == [2.0] and exp.figure.axes[0].get_title() == "a = 2.0"
    exp.value = 3.0
    assert calls == [2.0, 3.0] and exp.data["a"] == 3.0
    assert np.allclose(exp.figure.axes[0].lines[0].get_ydata(), 3.0 * np.linspace(0, 1, 5))
    assert exp.image != first and exp.image.startswith(b"\x89PNG")
    exp.value = 2.0
    assert calls == [2.0, 3.0] and exp.image == first  # cached: no new run
    assert plt.get_fignums() == open_figures  # none left open for the inline backend to show twice


def test_bad_values_and_arguments_are_refused():
    """Unknown values, empty or repeated value lists and draws that return no figure raise ValueError."""
    exp, _ = toy()
    with pytest.raises(ValueError, match=r"a must be one of \[1.0, 2.0, 3.0\], got 4"):
        exp.value = 4
    with pytest.raises(ValueError, match="all different"):
        Exploration(lambda v: v, lambda d: None, ("a", [1, 1]))
    with pytest.raises(ValueError, match="pair"):
        Exploration(lambda v: v, lambda d: None, 3)
    with pytest.raises(ValueError, match="Figure"):
        Exploration(lambda v: v, lambda d: None, ("a", [1])).image


def test_static_player_holds_one_image_per_value_and_a_slider():
    """The player embeds every value's PNG once, in order, with one range input over their indices."""
    exp, calls = toy()
    html = exp._repr_html_()
    assert calls == [1.0, 2.0, 3.0]
    assert html.count('class="explore-frame"') == 3 and html.count('type="range"') == 1
    assert 'min="0" max="2"' in html and 'value="1"' in html  # the current value is shown first
    assert re.findall(r'data-label="([^"]*)"', html) == ["a = 1 m", "a = 2 m", "a = 3 m"]
    sources = re.findall(r'src="data:image/png;base64,([^"]+)"', html)
    assert len(set(sources)) == 3
    assert "http" not in html.replace("http://www.w3.org", "")  # nothing to fetch


def test_the_widget_reruns_when_its_slider_moves():
    """Moving the ipywidgets slider sets the value, re-runs and replaces the image; and back."""
    pytest.importorskip("ipywidgets")
    exp, calls = toy()
    slider, picture = exp.widget.children
    assert slider.value == 2.0 and [label for label, _ in slider.options] == ["1 m", "2 m", "3 m"]
    before = picture.value
    slider.value = 1.0
    assert exp.value == 1.0 and calls == [2.0, 1.0] and picture.value != before
    exp.value = 2.0  # from code: the slider follows
    assert slider.value == 2.0 and picture.value == before


class _Kernel:
    kernel = object()


def _displayed(monkeypatch, exp, kernel=True, static=False, widgets=True):
    import IPython
    import IPython.display

    shown = []
    monkeypatch.setattr(IPython, "get_ipython", lambda: _Kernel() if kernel else None)
    monkeypatch.setattr(IPython.display, "display", lambda obj, raw=False: shown.append(obj))
    if static:
        monkeypatch.setenv(STATIC, "static")
    else:
        monkeypatch.delenv(STATIC, raising=False)
    if not widgets:
        monkeypatch.setitem(sys.modules, "ipywidgets", None)  # import fails
    exp._ipython_display_()
    return shown


def test_display_chooses_the_widget_in_a_kernel_and_the_player_otherwise(monkeypatch):
    """A kernel with ipywidgets gets the widget; the site's build (STATIC) gets the player without a
    note; a kernel without ipywidgets gets the player with a note; a terminal gets text."""
    pytest.importorskip("ipywidgets")
    import ipywidgets

    shown = _displayed(monkeypatch, toy()[0])
    assert len(shown) == 1 and isinstance(shown[0], ipywidgets.VBox)
    shown = _displayed(monkeypatch, toy()[0], static=True)
    assert "explore-frame" in shown[0]["text/html"] and "ipywidgets" not in shown[0]["text/html"]
    shown = _displayed(monkeypatch, toy()[0], widgets=False)
    assert "explore-frame" in shown[0]["text/html"] and "particles[notebook]" in shown[0]["text/html"]
    with pytest.raises(ImportError, match=r"pip install 'particles\[notebook\]'"):
        toy()[0].widget
    exp, calls = toy()
    assert list(_displayed(monkeypatch, exp, kernel=False)[0]) == ["text/plain"] and calls == []


def test_the_library_does_not_import_ipywidgets():
    """Importing the library and building an exploration's player loads no widget package."""
    code = ("import sys, particles, particles.explore, particles.render; "
            "e = particles.explore.Exploration(particles.explore.bouncing_ball, particles.explore.figures.plot_bounces, "
            "('eps', [0.8])); e.player(); print('ipywidgets' in sys.modules)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                            env={**os.environ, "MPLBACKEND": "Agg"})
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "False"


def test_slider_player_checks_its_arguments():
    """The player needs one label per image and an initial index in range."""
    with pytest.raises(ValueError, match="same length"):
        figures.slider_player([b"png"], ["a", "b"])
    with pytest.raises(ValueError, match="initial"):
        figures.slider_player([b"png"], ["a"], initial=1)


# --- the lectures' explorations -------------------------------------------------------------


def test_time_step_blow_up_flag_flips_above_h_max():
    """The stiff curtain runs at 0.98 h_max with the strain of 0.5 h_max and diverges at 1.02 h_max."""
    exp = Exploration(explore.curtain_time_step, figures.plot_time_step, ("h / h_max", [0.5, 0.98, 1.02, 1.1]))
    verdicts = {}
    for factor in exp.values:
        exp.value = factor
        verdicts[factor] = exp.data["diverged"]
        assert ("blew up" in exp.figure.axes[1].get_title()) == exp.data["diverged"]
    assert verdicts == {0.5: False, 0.98: False, 1.02: True, 1.1: True}
    stable, blown = exp.result(0.98), exp.result(1.02)
    assert abs(stable["t"][-1] - 0.3) < stable["h"] and np.isclose(stable["strain"].max(), 0.0046, atol=5e-5)
    assert np.isclose(stable["strain"].max(), exp.result(0.5)["strain"].max(), rtol=1e-3)
    assert 0.03 < blown["t_diverged"] < 0.045 and blown["t_diverged"] < exp.result(1.02)["T"]
    assert exp.result(1.1)["t_diverged"] < blown["t_diverged"]  # larger step, sooner


def test_damping_decay_rate_grows_to_critical_then_falls():
    """The measured decay rate is d/2m below d_c and (d - sqrt(d^2 - 4km))/2m above: it grows, then
    falls like k/d (glue); d = 0.1 and d = 20 kg/s relax equally slowly, and neither settles in 60 s."""
    values = [0.1, 0.3, 1.0, 2.0, 5.0, 20.0]
    exp = Exploration(explore.damped_spring, figures.plot_damped_spring, ("d", values), unit="kg/s")
    rates = []
    for d in values:
        exp.value = d
        data = exp.data
        rates.append(data["rate"])
        assert f"d = {d:g} kg/s" in exp.figure.axes[0].get_title()
        assert np.allclose(exp.figure.axes[0].lines[0].get_ydata(), data["x"])
        tolerance = 0.03 if data["regime"] == "critical" else 2e-3
        assert data["rate"] == pytest.approx(data["predicted_rate"], rel=tolerance)
    assert np.all(np.diff(rates[:4]) > 0) and np.all(np.diff(rates[3:]) < 0)
    assert exp.result(20.0)["rate"] == pytest.approx(5e-2, rel=3e-3) == exp.result(0.1)["rate"]
    assert exp.result(0.1)["settling_time"] is None and exp.result(20.0)["settling_time"] is None
    assert exp.result(1.0)["settling_time"] < exp.result(0.3)["settling_time"]


def test_provot_strain_falls_with_the_passes_allowed():
    """Capping the projection's passes per step leaves more strain: 41%, 19% and 12% with 1, 10, 50."""
    exp = Exploration(explore.provot_passes, figures.plot_provot_passes, ("passes", [1, 10, 50]))
    largest = {}
    for passes in exp.values:
        exp.value = passes
        largest[passes] = exp.data["strain"].max()
        assert exp.data["mean_passes"] <= passes
        assert f"at most {passes} pass{'es' if passes > 1 else ''} per step" in exp.figure.axes[1].get_title()
    assert largest[1] > largest[10] > largest[50] > 0.1
    assert [round(100 * largest[p]) for p in (1, 10, 50)] == [41, 19, 12]


def test_bounce_height_ratio_is_eps_squared():
    """Each arc of the backtracked ball reaches eps^2 of the one before, for every eps of the slider."""
    exp = Exploration(explore.bouncing_ball, figures.plot_bounces, ("eps", [0.3, 0.5, 0.8, 1.0]))
    for e in exp.values:
        exp.value = e
        H = exp.data["heights"]
        assert len(H) >= 3 and H[0] == pytest.approx(1.0)
        assert np.allclose(H[1:] / H[:-1], e * e, rtol=1e-6, atol=0)
        assert f"eps^2 = {e * e:.6f}" in exp.figure.axes[1].get_title()
    assert exp.result(0.3)["heights"][2] < 0.01 and len(exp.result(1.0)["heights"]) == 6


def test_cloth_drop_wraps_the_ball_and_reaches_the_floor_without_crossing():
    """A 10^2 sheet dropped on the ball: no crossing pair after any step, the stretch within 10%, the bodies
    stage holds it off the ball and the floor, and the figure says so; a softer sheet sags lower."""
    exp = Exploration(lambda Y: explore.cloth_drop(Y, n=10, T=0.6), figures.plot_cloth_drop,
                      ("Y", [50.0, 1000.0]))
    for Y in exp.values:
        exp.value = Y
        data = exp.data
        assert data["crossings"].max() == 0 and len(data["crossings"]) == 24
        assert data["strain"].max() <= 0.1 + 1e-12 and len(data["strain"]) == 24
        assert data["stages"]["vertices moved out of a body"].max() > 0
        assert 0.25 / 9 / 2 <= data["lowest"] < data["radius"]         # down the ball, off the floor
        assert data["x"].shape == (4, 100, 3) and np.all(data["x"][-1, :, 2] >= data["lowest"])
        assert "at most 0 crossing pairs" in exp.figure.axes[-1].get_title()
    assert exp.result(50.0)["lowest"] <= exp.result(1000.0)["lowest"]


def test_widget_of_a_lecture_exploration_switches_runs():
    """Through the widget: moving the slider of the restitution exploration gives that run's data."""
    pytest.importorskip("ipywidgets")
    exp = Exploration(explore.bouncing_ball, figures.plot_bounces, ("eps", [0.5, 0.8]), value=0.8)
    exp.widget.children[0].value = 0.5
    assert exp.value == 0.5 and exp.data["heights"][1] == pytest.approx(0.25, rel=1e-9)


LECTURE_EXPLORATIONS = {
    "02_forces": ["damped_spring"],
    "03_collisions": ["bouncing_ball"],
    "07_stiffness_provot_implicit": ["curtain_time_step", "provot_passes"],
    "09_cloth_collisions": ["cloth_drop"],
}


@pytest.mark.parametrize("lecture", sorted(LECTURE_EXPLORATIONS))
def test_lectures_hold_their_explorations(lecture):
    """Each lecture builds its explorations in a code cell after an 'Explore:' header of its own."""
    nb = nbformat.read(ROOT / "lectures" / f"{lecture}.ipynb", as_version=4)
    runs = [m.group(1) for c in nb.cells if c.cell_type == "code"
            for m in re.finditer(r"Exploration\(run=(\w+)", c.source)]
    assert runs == LECTURE_EXPLORATIONS[lecture]
    headers = [c for c in nb.cells if c.cell_type == "markdown" and c.source.startswith("### Explore:")]
    assert len(headers) == len(runs)
