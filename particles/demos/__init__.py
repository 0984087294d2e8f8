"""The demos of ``particles demo NAME``: each a function that returns data, drawn separately.

Every demo is a function ``demo(seconds, fps, seed) -> DemoData`` that
simulates and returns the positions of every frame, with colours, sizes and
scenery (:class:`DemoData`); :func:`animate_demo` draws it and
:func:`write_demo` saves a GIF (or an HTML player). Nothing needs a window.
The three arguments are the same for every demo:

seconds : float
    Simulated time, in seconds.
fps : float
    Frames recorded per simulated second. A demo's time step is its own:
    `fps` only says how often a frame is recorded, so a preview shows the
    same physics as the full animation (the cloth demos shorten their step so
    that a whole number of steps fits in a frame).
seed : int
    Seed of the demo's random numbers (the deterministic demos ignore it).

One module per family of demos, all listed in :data:`DEMOS`:

=================  ========================  ==================================================================
``fountain``       :mod:`.effects`           3D: a nozzle, gravity, water splashing on the ground (collisions)
``fireworks``      :mod:`.effects`           2D: rockets whose trails and bursts are child systems (hierarchical)
``smoke``          :mod:`.effects`           2D: a moving chimney, gravity pointing up, wind, puffs fading and growing
``bouncing``       :mod:`.collisions`        2D: balls in a box with obstacles, restitution and backtracking
``flock``          :mod:`.flocks`            2D: Reynolds' boids coloured by heading
``genesis``        :mod:`.effects`           3D: Reeves' Genesis effect, a ring of secondary systems over a planet
``cloth``          :mod:`.massspring`        3D: a curtain pinned at two corners, swinging in the wind (Provot)
``drape``          :mod:`.massspring`        3D: a cloth falling onto a sphere and the floor
=================  ========================  ==================================================================

Adding a demo: write its function in the module of its family (or a new
one), returning a :class:`DemoData`, and add its :class:`Demo` entry to
:data:`DEMOS` below; ``particles demo NAME`` and the tour (which writes a
short preview of each demo, at 5 frames per second) pick it up. A notebook
or a test can add one at run time with :func:`register`.

Modules: :mod:`particles.demos.effects` (fountain, fireworks, smoke, genesis), :mod:`particles.demos.collisions`
(bouncing balls), :mod:`particles.demos.flocks`, :mod:`particles.demos.massspring` (cloth, drape), and
:mod:`particles.demos.data` (:class:`DemoData`, what every demo returns).
"""

from pathlib import Path

from .collisions import bouncing
from .data import Demo, DemoData
from .effects import fireworks, fountain, genesis, smoke
from .flocks import flock
from .massspring import draped_cloth, hanging_cloth

__all__ = ["DemoData", "Demo", "DEMOS", "register", "run_demo", "animate_demo", "write_demo", "fountain",
           "fireworks", "smoke", "bouncing", "flock", "genesis", "hanging_cloth", "draped_cloth"]

DEMOS = {demo.name: demo for demo in [
    Demo("fountain", "3D: water from a nozzle, splashing on the ground (collisions, lifetimes)", fountain,
         {"seconds": 2.4}),
    Demo("fireworks", "2D: rockets with trails and bursts, systems of systems (Reeves' hierarchy)", fireworks,
         {"seconds": 3.6}),
    Demo("smoke", "2D: a moving chimney, gravity pointing up, wind gusts; puffs grow and fade", smoke,
         {"seconds": 3.0}),
    Demo("bouncing", "2D: balls in a box with a ramp and an obstacle (restitution 0.95, backtracking)", bouncing,
         {"seconds": 2.4}),
    Demo("flock", "2D: Reynolds' boids from random headings to one flock; the camera follows it", flock),
    Demo("genesis", "3D: Reeves' Genesis effect, an expanding ring of secondary systems over a planet", genesis,
         {"seconds": 2.4}),
    Demo("cloth", "3D: a curtain pinned at two corners, falling and swinging in a gusty wind (Provot's constraint)",
         hanging_cloth, {"seconds": 2.0}),
    Demo("drape", "3D: a cloth falling onto a sphere and the floor (collisions with friction)", draped_cloth,
         {"seconds": 2.0}),
]}
"""Demo name -> :class:`Demo` (its description, function and preview), in the order of the lessons."""


def register(name, description, preview=None):
    """Decorator adding a demo function ``fn(seconds, fps, seed) -> DemoData`` to :data:`DEMOS` at run time.

    The library's own demos are listed in :data:`DEMOS` directly; this is
    for a demo written in a notebook or a test.

    Parameters
    ----------
    name, description : str
        Its name on the command line and what it shows.
    preview : dict, optional
        Options of the short version the tour writes (default: the demo's
        own length at 5 frames per second).

    Returns
    -------
    callable
        The decorator, which returns the function unchanged.
    """
    def add(function):
        DEMOS[name] = Demo(name, description, function, dict(preview or {}))
        return function
    return add


def run_demo(name, seconds=None, fps=None, seed=0):
    """Compute the data of the demo `name`, drawing nothing.

    Parameters
    ----------
    name : str
        A key of :data:`DEMOS` (``"fountain"``, ``"flock"``, ...).
    seconds : float, optional
        Simulated time, in seconds (None: the demo's default).
    fps : float, optional
        Frames recorded per simulated second (None: the demo's default).
    seed : int
        Seed of the demo's random numbers.

    Returns
    -------
    DemoData
        Positions per frame, shape (n_k, d) in metres, with colours, sizes
        and scenery; :func:`animate_demo` draws it.
    """
    if name not in DEMOS:
        raise ValueError(f"unknown demo {name!r}; expected one of {', '.join(map(repr, DEMOS))}")
    options = {k: v for k, v in (("seconds", seconds), ("fps", fps)) if v is not None}
    return DEMOS[name].function(seed=seed, **options)


def animate_demo(data, figsize=(4, 4)):
    """A Matplotlib animation of a :class:`DemoData` (see :func:`particles.render.animate`)."""
    from .. import render

    return render.animate(data.positions, times=data.times, velocities=data.velocities, blur=data.blur,
                          limits=data.limits, title=data.title, figsize=figsize, interval=round(1000 / data.fps),
                          colors=data.colors, sizes=data.sizes, springs=data.springs, lines=data.lines,
                          background=data.background, axis=data.axis, view=data.view)


def write_demo(name, out="out", seconds=None, fps=None, seed=0, html=False, dpi=72):
    """Compute the demo `name`, write ``out/NAME.gif`` (and ``NAME.html`` with `html`).

    Returns
    -------
    data : DemoData
    paths : list of pathlib.Path
    """
    from .. import render

    data = run_demo(name, seconds, fps, seed)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    anim = animate_demo(data)
    paths = [render.save_gif(anim, out / f"{name}.gif", fps=data.fps, dpi=dpi)]
    if html:
        path = out / f"{name}.html"
        path.write_text(render.to_html(anim))
        paths.append(path)
    return data, paths
