"""Explorations: one parameter of a simulation on a slider, re-run and redrawn.

An :class:`Exploration` joins a simulation, ``run(value) -> data`` (a function
returning data), a drawing, ``draw(data) -> Figure`` (Matplotlib, e.g. the
``plot_*`` functions of :mod:`particles.render`), and a parameter with a few
values. Each value is run and drawn once, when first asked for, and kept.

How it shows in a notebook:

* in a live Jupyter kernel with ipywidgets (``pip install 'particles[notebook]'``)
  it is a slider widget (:attr:`Exploration.widget`) that re-runs and redraws;
* elsewhere it is a static player (:meth:`Exploration.player`): the figure of
  every value pre-rendered as an image, and a range input that switches between
  them, plain HTML and JavaScript (no kernel, no network). It is what a kernel
  without ipywidgets shows, with a note, and what the course site shows:
  ``particles site`` executes the lectures with ``PARTICLES_EXPLORATIONS=static``
  in the kernel's environment (:data:`STATIC`), so their outputs hold the player.

The library itself needs no widget package: ipywidgets is imported only when a
widget is built.

The module also holds the simulations of the lectures' explorations (data only;
their figures are drawn by :mod:`particles.render`): :func:`damped_spring`
(lecture 2), :func:`bouncing_ball` (lecture 3), :func:`curtain_time_step` and
:func:`provot_passes` (lecture 7).

Examples
--------
>>> from particles.explore import Exploration, bouncing_ball, plot_bounces
>>> ball = Exploration(bouncing_ball, plot_bounces, ("eps", [0.5, 0.8]), value=0.8)
>>> ball.value = 0.5                      # re-runs (once) and redraws
>>> H = ball.data["heights"]
>>> bool(abs(H[1] / H[0] - 0.25) < 1e-6)
True
>>> ball.player().count('class="explore-frame"')
2
"""

import os

import numpy as np

from .._checks import count, nonnegative_number, positive_number
from ..collisions.collider import Collider
from ..collisions.surfaces import Plane
from ..constraints import ProvotConstraint
from ..errors import SimulationDiverged
from ..forces.fields import Damping, Field, Gravity
from ..integrators.steppers import symplectic_euler
from ..massspring.cloth import cloth
from ..studies.provot import curtain
from ..system import ParticleSystem
from .figures import figure_png, slider_player

__all__ = ["Exploration", "STATIC", "damped_spring", "bouncing_ball", "curtain_time_step",
           "provot_passes"]

STATIC = "PARTICLES_EXPLORATIONS"
"""Environment variable: ``static`` makes every exploration show its static player (the site's build)."""

NO_WIDGETS = ("ipywidgets is not installed, so this is the pre-computed player; "
              "pip install 'particles[notebook]' for a live slider that re-runs the simulation")

G = 9.81  # m/s^2


class Exploration:
    """A simulation re-run and redrawn for each value of one parameter.

    Parameters
    ----------
    run : callable
        ``run(value) -> data``: the simulation for one value of the parameter,
        returning data (e.g. a dict of arrays). Called once per value.
    draw : callable
        ``draw(data) -> matplotlib.figure.Figure``: the picture of one run.
    parameter : (str, sequence)
        The parameter's name and its values (at least one, all different), in
        slider order.
    value : optional
        The value shown first (default: the first value).
    unit : str
        Unit of the values, shown after them (``"kg/s"``).
    fmt : str
        Format of a value on the slider (``"{:g}"``).
    dpi : float
        Resolution of the images, in dots per inch.

    Attributes
    ----------
    values : tuple
        The parameter's values.

    Notes
    -----
    ``exp.value = v`` runs (once) and draws `v`, and moves the widget's slider
    when there is one; moving the slider does the same. :attr:`data`,
    :attr:`figure` and :attr:`image` are those of the current value.
    """

    def __init__(self, run, draw, parameter, value=None, unit="", fmt="{:g}", dpi=72):
        if not callable(run) or not callable(draw):
            raise ValueError("run and draw must be callables: run(value) -> data, draw(data) -> Figure")
        try:
            name, values = parameter
            values = tuple(values)
        except (TypeError, ValueError):
            raise ValueError(f"parameter must be a pair (name, values), got {parameter!r}") from None
        if not values or any(a == b for k, a in enumerate(values) for b in values[k + 1:]):
            raise ValueError(f"the values of {name!r} must be at least one and all different, got {values}")
        self.run, self.draw = run, draw
        self.name, self.values, self.unit, self.fmt = str(name), values, str(unit), fmt
        self.dpi = positive_number(dpi, "dpi", "dots per inch")
        self._data, self._figures, self._images = {}, {}, {}
        self._index = 0 if value is None else self._position(value)
        self._widget = None

    def __repr__(self):
        shown = ", ".join(self.format(v) for v in self.values)
        return f"Exploration of {self.name} over [{shown}], showing {self.name} = {self.format(self.value)}"

    def format(self, value):
        """A value as the slider shows it, with its unit: ``"0.3 kg/s"``."""
        return self.fmt.format(value) + (f" {self.unit}" if self.unit else "")

    def _position(self, value):
        for k, v in enumerate(self.values):  # a loop over the few values of the slider
            if v == value:
                return k
        raise ValueError(f"{self.name} must be one of {list(self.values)}, got {value!r}")

    @property
    def value(self):
        """The current value; setting it runs (once) and redraws."""
        return self.values[self._index]

    @value.setter
    def value(self, value):
        self._index = self._position(value)
        image = self.image  # run and draw now, so that a bad value fails here
        if self._widget is not None:
            slider, picture = self._widget.children
            slider.value = self.value
            picture.value = image

    def result(self, value):
        """The data of one value (``run(value)``, computed once)."""
        k = self._position(value)
        if k not in self._data:
            self._data[k] = self.run(self.values[k])
        return self._data[k]

    def _drawn(self, k):
        if k not in self._images:
            fig = self.draw(self.result(self.values[k]))
            if not hasattr(fig, "savefig"):
                raise ValueError(f"draw must return a matplotlib Figure, got {type(fig).__name__}")
            self._images[k] = figure_png(fig, self.dpi)
            self._figures[k] = fig
        return self._figures[k], self._images[k]

    @property
    def data(self):
        """The data of the current value."""
        return self.result(self.value)

    @property
    def figure(self):
        """The figure of the current value (closed in pyplot; inspect its axes and artists)."""
        return self._drawn(self._index)[0]

    @property
    def image(self):
        """The PNG bytes of the current value's figure."""
        return self._drawn(self._index)[1]

    def images(self):
        """The PNG bytes of every value's figure, in slider order (runs them all)."""
        return [self._drawn(k)[1] for k in range(len(self.values))]

    def player(self, note=None):
        """The static player: every value's image and a slider (HTML, no kernel, no network)."""
        labels = [f"{self.name} = {self.format(v)}" for v in self.values]
        return slider_player(self.images(), labels, self.name, self._index, note)

    def _repr_html_(self):
        return self.player()

    @property
    def widget(self):
        """The ipywidgets slider and image (built once; needs ipywidgets)."""
        if self._widget is None:
            try:
                import ipywidgets as widgets
            except ImportError as error:
                raise ImportError(NO_WIDGETS) from error
            slider = widgets.SelectionSlider(
                options=[(self.format(v), v) for v in self.values], value=self.value,
                description=self.name, continuous_update=False, layout=widgets.Layout(width="30em"))
            picture = widgets.Image(value=self.image, format="png")
            slider.observe(lambda change: setattr(self, "value", change["new"]), names="value")
            self._widget = widgets.VBox([slider, picture])
        return self._widget

    def _ipython_display_(self):
        from IPython import get_ipython
        from IPython.display import display

        if getattr(get_ipython(), "kernel", None) is None:  # a terminal: text only
            display({"text/plain": repr(self)}, raw=True)
        elif os.environ.get(STATIC) == "static":
            display({"text/html": self.player(), "text/plain": repr(self)}, raw=True)
        else:
            try:
                widget = self.widget
            except ImportError:
                display({"text/html": self.player(note=NO_WIDGETS),
                         "text/plain": f"{self!r}\n({NO_WIDGETS})"}, raw=True)
            else:
                display(widget)


def _settling_time(t, x, tol=0.01):
    """First time after which |x| stays within `tol`, or None when it never does."""
    outside = np.flatnonzero(np.abs(x) > tol)
    if len(outside) == 0:
        return float(t[0])
    return None if outside[-1] + 1 == len(t) else float(t[outside[-1] + 1])


def damped_spring(d, k=1.0, m=1.0, T=60.0, h=0.05):
    """A particle on a spring with damping d, released from 1 m: from ringing to glue.

    ``m x'' = -k x - d x'``: its slowest mode decays at the rate ``d / 2m`` below
    critical damping ``d_c = 2 sqrt(k m)``, and at ``(d - sqrt(d^2 - 4km)) / 2m``
    (about ``k / d``: glue) above it.

    Parameters
    ----------
    d : float
        Damping coefficient, in kg/s (>= 0).
    k : float
        Spring stiffness, in N/m.
    m : float
        Mass, in kg.
    T : float
        Simulated time, in seconds (RK4 with the step `h`).
    h : float
        Time step, in seconds.

    Returns
    -------
    dict
        ``"t"``, ``"x"``: times (s) and positions (m), shape (K,); ``"rate"``: the
        measured decay rate of the amplitude, in 1/s (half the slope of ``log E``
        over the second half of the run, ``E`` the mechanical energy);
        ``"predicted_rate"``; ``"settling_time"`` (s; None when it does not settle
        within 1 cm by `T`); ``"regime"``: ``"rings"``, ``"critical"`` or ``"glue"``;
        ``"d"``, ``"d_c"``, ``"k"``, ``"m"``.
    """
    d = nonnegative_number(d, "d", "kg/s")
    k, m = positive_number(k, "k", "N/m"), positive_number(m, "m", "kg")
    spring = ParticleSystem([[1.0, 0.0]], m=m, forces=[Field(lambda x, t: -k * x), Damping(d)])
    t, X = spring.run(positive_number(T, "T", "s"), positive_number(h, "h", "s"), method="rk4")
    x, v = X[:, 0, 0, 0], X[:, 0, 1, 0]
    E = 0.5 * m * v**2 + 0.5 * k * x**2
    late = (t >= t[-1] / 2) & (E > 0)
    rate = -0.5 * np.polyfit(t[late], np.log(E[late]), 1)[0]
    d_c = 2 * np.sqrt(k * m)
    predicted = d / (2 * m) if d < d_c else (d - np.sqrt(d * d - d_c * d_c)) / (2 * m)
    regime = "rings" if d < 0.9 * d_c else "glue" if d > 1.1 * d_c else "critical"
    return {"t": t, "x": x, "rate": float(rate), "predicted_rate": float(predicted),
            "settling_time": _settling_time(t, x), "regime": regime, "d": d, "d_c": d_c, "k": k, "m": m}


def bouncing_ball(restitution, bounces=5, lowest=0.005, height=1.0, h=0.005):
    """A ball dropped on the floor with restitution eps: its height, and the top of each arc.

    Backtracking and velocity Verlet (exact under gravity), so that each arc
    reaches ``eps^2`` of the previous one, ``H_k = eps^(2k) H0``.

    Parameters
    ----------
    restitution : float
        ``eps`` in (0, 1].
    bounces : int
        Largest number of bounces simulated.
    lowest : float
        Arcs lower than this (m) are not simulated: the run stops at the bounce
        before the first one (short arcs, resting contact).
    height : float
        Drop height ``H0``, in metres.
    h : float
        Time step, in seconds.

    Returns
    -------
    dict
        ``"t"``, ``"y"``: times (s) and heights (m) of the ball; ``"heights"``: the
        top of each arc, ``y + v_y^2 / 2g`` between two contacts (exact on a
        ballistic arc), the drop first, shape (arcs,); ``"restitution"``;
        ``"t_max"``: the time of the last bounce of the strongest ball (eps = 1),
        a common axis.
    """
    e = positive_number(restitution, "restitution")
    if e > 1:
        raise ValueError(f"restitution must be in (0, 1], got {e}")
    H0 = positive_number(height, "height", "m")
    arcs = count(bounces, "bounces", 1)
    if e < 1:  # arc k reaches eps^2k H0: stop before the first one lower than `lowest`
        arcs = min(arcs, max(1, int(np.log(positive_number(lowest, "lowest", "m") / H0) / np.log(e * e))))
    fall = np.sqrt(2 * H0 / G)  # time of the drop; arc k lasts 2 eps^k of it
    T = fall * (1 + 2 * sum(e**j for j in range(1, arcs + 1)) - 0.5 * e**arcs)  # in the last descent
    ball = ParticleSystem([[0.0, H0]], forces=[Gravity([0.0, -G])])
    floor = Collider(Plane([0.0, 0.0], [0.0, 1.0]), restitution=e)
    t, X, contacts = floor.run(ball, T, positive_number(h, "h", "s"), method="verlet")
    y, vy = X[:, 0, 0, 1], X[:, 0, 1, 1]
    top = y + vy**2 / (2 * G)  # exact on a ballistic arc, and on part of one
    edges = np.concatenate([[-np.inf], contacts.time, [np.inf]])
    on_arc = [(t > a) & (t < b) for a, b in zip(edges[:-1], edges[1:])]
    heights = [top[arc].mean() for arc in on_arc if arc.any()]
    return {"t": t, "y": y, "heights": np.array(heights[:arcs + 1]), "restitution": e,
            "t_max": fall * (1 + 2 * bounces)}


def _recording(step, record):
    """A stepper doing `step`, then ``record(X_new, t + h)``; it keeps `step`'s attributes."""

    def recorded(f, X, t, h, **options):
        X_new = step(f, X, t, h, **options)
        record(X_new, t + h)
        return X_new

    for attr in ("order", "explicit", "second_order_layout", "fsal"):
        setattr(recorded, attr, getattr(step, attr, None))
    recorded.__name__ = getattr(step, "__name__", "step")
    return recorded


def curtain_time_step(factor, k=1e4, n=12, T=0.3):
    """The stiff curtain of lecture 7 stepped at `factor` times its largest stable step.

    A 1 m curtain of n x n particles held by its top corners, structural springs
    `k` (shear ``k/4``, flexion ``k/10``), symplectic Euler with
    ``h = factor h_max``, ``h_max = 2 / omega_max`` (:meth:`max_stable_step`).

    Parameters
    ----------
    factor : float
        ``h / h_max`` (> 0).
    k : float
        Structural stiffness, in N/m.
    n : int
        Particles per side.
    T : float
        Simulated time, in seconds.

    Returns
    -------
    dict
        ``"t"``, ``"strain"``: the time (s) and the largest spring strain after each
        step, until the end or the blow-up; ``"diverged"`` (bool) and
        ``"t_diverged"`` (s, or None); ``"x"``: the positions (m) at ``"t_shown"``,
        the last step with every strain below 50%; ``"h"``, ``"h_max"`` (s),
        ``"grid_shape"``, ``"T"``.
    """
    factor = positive_number(factor, "factor")
    c = cloth(count(n, "n", 3), n, k_structural=positive_number(k, "k", "N/m"), k_shear=k / 4,
              k_flexion=k / 10)
    h_max = c.max_stable_step()
    h = factor * h_max
    times, strain, shown = [0.0], [c.max_strain()], [0.0, c.X[:, 0].copy()]

    def record(X, t):
        times.append(t)
        strain.append(c.max_strain(X) if np.isfinite(X).all() else np.inf)
        if strain[-1] < 0.5:
            shown[:] = [t, X[:, 0].copy()]

    try:
        c.run(h * round(T / h), h, method=_recording(symplectic_euler, record), every=10**9)
        t_diverged = None
    except SimulationDiverged as error:
        t_diverged = error.t + error.h
    return {"t": np.array(times), "strain": np.array(strain), "diverged": t_diverged is not None,
            "t_diverged": t_diverged, "t_shown": shown[0], "x": shown[1], "h": h, "h_max": h_max,
            "grid_shape": c.grid_shape, "T": T}


def provot_passes(passes, n=12, k=30.0, steps=200, h=0.005, max_strain=0.1):
    """The slide's curtain with Provot's constraint capped at `passes` projection passes per step.

    The curtain of :func:`particles.studies.provot.curtain` (soft springs `k`,
    held by two corners, falling from the horizontal), symplectic Euler, and
    :class:`particles.constraints.ProvotConstraint` on the structural and shear
    springs with at most `passes` Jacobi passes per step.

    Parameters
    ----------
    passes : int
        Largest number of projection passes per step (>= 1).
    n, k, steps, h, max_strain
        Particles per side, structural stiffness (N/m), steps, time step (s), and
        the strain limit (0.1: 10%).

    Returns
    -------
    dict
        ``"t"``, ``"strain"``: recorded times (s) and the largest structural strain
        then; ``"x"``: the positions (m) when it is largest, at ``"t_shown"``; ``"passes"``, ``"mean_passes"`` (passes
        used per step), ``"max_strain"``, ``"grid_shape"``.
    """
    c = curtain(n, k)
    provot = ProvotConstraint.from_system(c, max_strain=max_strain, iterations=count(passes, "passes", 1))
    t, X = c.run(count(steps, "steps", 1) * h, h, method=provot.stepper(symplectic_euler), every=2)
    strain = np.array([c.max_strain(Xk, "structural") for Xk in X])
    worst = int(np.argmax(strain))
    return {"t": t, "strain": strain, "x": X[worst, :, 0], "t_shown": float(t[worst]), "passes": passes,
            "mean_passes": float(np.mean([r.iterations for r in provot.history])),
            "max_strain": max_strain, "grid_shape": c.grid_shape}
