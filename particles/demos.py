"""The effect demos of ``particles demo NAME``: each a function that returns data.

Every demo simulates and returns a :class:`DemoData` (positions per frame,
colours, sizes, scenery); :func:`animate_demo` draws it and :func:`write_demo`
saves a GIF (or an HTML player). Nothing needs a window.

=================  ==========================================================
``fountain``       3D: a nozzle, gravity, water splashing on the ground (collisions)
``fireworks``      2D: rockets whose trails and bursts are child systems (hierarchical)
``smoke``          2D: a moving chimney, gravity pointing up, wind, puffs fading and growing
``bouncing``       2D: balls in a box with obstacles, restitution and backtracking
``flock``          2D: Reynolds' boids coloured by heading
``genesis``        3D: Reeves' Genesis effect, a ring of secondary systems over a planet
=================  ==========================================================

Adding a demo is one decorated function, e.g. the hanging cloth of the
mass-spring models::

    @register("cloth", "a curtain pinned at two corners, swinging in the wind", preview=dict(seconds=2.0))
    def cloth(seconds=4.0, fps=10, seed=0):
        ...                                   # build and run the model, record every 1 / fps seconds
        return DemoData("cloth", "hanging cloth", times, positions, springs=index_pairs, fps=fps)

after which ``particles demo cloth`` and the tour (which writes a short
preview of each demo, at 5 frames per second) pick it up. A demo's time step
is its own: `fps` only says how often a frame is recorded, so a preview shows
the same physics as the full animation.
"""

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import forces
from .collisions import Box, Collider, Plane, Sphere
from .effects import ColorRamp, ParticleEffect
from .emitters import Cone, Disk, Emitter, ParticleEmitter, Point, SphereSurface
from .flocking import Boids, Flock, polarization
from ._checks import positive_number
from .system import ParticleSystem

__all__ = ["DemoData", "DEMOS", "register", "run_demo", "animate_demo", "write_demo"]


@dataclass
class DemoData:
    """What a demo computed: enough to draw every frame, and nothing drawn yet.

    Attributes
    ----------
    name, title : str
    times : ndarray, shape (K,)
        Frame times, in seconds.
    positions : list of ndarray, each shape (n_k, d)
    velocities : list of ndarray, optional
        For motion blur (``x, x + v blur``).
    colors : list of ndarray, each shape (n_k, 4), optional
    sizes : list of ndarray, each shape (n_k,), optional
    springs : ndarray of int, shape (p, 2), optional
        Index pairs drawn as lines (mass-spring models).
    lines : list of ndarray, each shape (k, d)
        Static scenery (walls, ground, obstacles).
    limits : list of (lo, hi), optional
    blur : float, optional
        Motion-blur exposure, in seconds.
    background : color, optional
    axis : bool
        Whether to draw the axes (slow: ticks and labels cost more than the particles).
    view : (elevation, azimuth), optional
        3D camera, in degrees.
    fps : float
        Frames per second of the animation (real time): one frame per
        ``1 / fps`` simulated seconds.
    info : dict
        Measured figures printed by the tour (counts, polarization...).
    """

    name: str
    title: str
    times: np.ndarray
    positions: list
    velocities: list = None
    colors: list = None
    sizes: list = None
    springs: np.ndarray = None
    lines: list = field(default_factory=list)
    limits: list = None
    blur: float = None
    background: str = None
    axis: bool = False
    view: tuple = None
    fps: float = 20
    info: dict = field(default_factory=dict)

    def __len__(self):
        return len(self.times)


@dataclass
class Demo:
    name: str
    description: str
    function: object
    preview: dict = field(default_factory=dict)  # options of the short version written by the tour


DEMOS = {}
"""Demo name -> :class:`Demo` (its description and function), in registration order."""


def register(name, description, preview=None):
    """Decorator adding a demo function ``fn(seconds, fps, seed) -> DemoData`` to :data:`DEMOS`.

    `preview` holds the options of the short version the tour writes
    (default: the demo's own length at 5 frames per second).
    """
    def add(function):
        DEMOS[name] = Demo(name, description, function, {"fps": 5, **(preview or {})})
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


def _circle(center, radius, k=64, axes=(0, 1), d=2):
    """A closed polyline around a circle, shape (k + 1, d)."""
    angle = np.linspace(0.0, 2 * np.pi, k + 1)
    line = np.zeros((k + 1, d)) + np.asarray(center, dtype=float)
    line[:, axes[0]] += radius * np.cos(angle)
    line[:, axes[1]] += radius * np.sin(angle)
    return line


def _every(fps, h):
    """Steps of length `h` between frames at `fps` frames per second (at least 1)."""
    return max(1, int(round(1.0 / (positive_number(fps, "fps", "frames per second") * h))))


def _from_effect(effect, name, title, seconds, fps, h, **options):
    """Run an effect tree with steps of `h` seconds and package a snapshot per frame."""
    every = _every(fps, h)
    frames = effect.run(seconds, h=h, every=every)
    fps = 1.0 / (every * h)
    largest = max(sum(s.counts.values()) for s in frames)
    return DemoData(name, title, np.array([s.t for s in frames]), [s.x for s in frames],
                    velocities=[s.v for s in frames], colors=[s.rgba for s in frames],
                    sizes=[s.size for s in frames], fps=fps,
                    info={"most particles": largest, **options.pop("info", {})}, **options)


@register("fountain", "3D: water from a nozzle, splashing on the ground (collisions, lifetimes)",
          preview=dict(seconds=2.4))
def fountain(seconds=4.0, fps=10, seed=0):
    """Water from a nozzle under gravity, splashing on the ground: collisions and lifetimes, in 3D.

    A disk nozzle of radius 4 cm emits 250 drops/s upwards in a cone
    (4.4 m/s, half-angle 0.3 rad), each living 2.4 +- 0.4 s; gravity, light
    damping and the ground ``z = 0`` (restitution 0.3, friction 0.6, with
    backtracking) act on them; drops leaving the box ``[-3, 3]^2 x [-1, 3]``
    m are removed. Steps of 1/40 s.

    Parameters
    ----------
    seconds : float
        Simulated time, in seconds (default 4.0).
    fps : float
        Frames recorded per simulated second (default 10); the time step
        is the demo's own, so `fps` does not change the physics.
    seed : int
        Seed of the emitter's random numbers.

    Returns
    -------
    DemoData
        Per frame, positions and velocities of shape (n_k, 3) (m, m/s; the
        number of drops changes), RGBA colours (n_k, 4) by age and marker
        areas (n_k,); ``info["most particles"]``: the largest count.
    """
    nozzle = Emitter(250.0, Disk([0.0, 0.0, 0.05], 0.04), Cone([0, 0, 1], 4.4, 0.3, angle=0.3),
                     lifetime=(2.4, 0.4))
    ground = Collider(Plane([0, 0, 0], [0, 0, 1]), restitution=0.3, friction=0.6)
    water = ParticleEffect(3, [nozzle], forces=[forces.Gravity([0, 0, -9.81]), forces.Damping(0.05)],
                           collider=ground, color=ColorRamp(["#f2fbff", "#5aa9e6", "#1d4e89"], [0.9, 0.8, 0.0]),
                           size=5.0, seed=seed, name="water", bounds=([-3, -3, -1], [3, 3, 3]))
    return _from_effect(water, "fountain", "fountain", seconds, fps, 1 / 40, blur=0.03,
                        limits=[(-1.6, 1.6), (-1.6, 1.6), (0.0, 1.6)], view=(18, -60),
                        lines=[_circle([0, 0, 0], 1.5, axes=(0, 1), d=3)])


@register("fireworks", "2D: rockets with trails and bursts, systems of systems (Reeves' hierarchy)",
          preview=dict(seconds=3.6))
def fireworks(seconds=5.0, fps=15, seed=0):
    """Rockets with trails and bursts, systems of systems (Reeves' hierarchy), in 2D.

    A launcher fires about 1.6 rockets/s (12 m/s, random tints); each
    rocket is the emitter of a child effect of trails (90 particles/s) and,
    when it dies after about 1.1 s, of a burst of 140 +- 40 sparks, some of
    which crackle when they die in turn. Steps of 1/30 s; the launcher stops
    1.8 s before the end so that the last bursts are seen.

    Parameters
    ----------
    seconds : float
        Simulated time, in seconds (default 5.0).
    fps : float
        Frames recorded per simulated second (default 15); the time step
        is the demo's own, so `fps` does not change the physics.
    seed : int
        Seed of the launcher; the child effects use seed + 1, + 2 and + 3.

    Returns
    -------
    DemoData
        Per frame, positions and velocities of shape (n_k, 2) (m, m/s) of
        all rockets, trails, sparks and crackle together, RGBA colours
        (n_k, 4) and marker areas (n_k,), on a black background;
        ``info["most particles"]``: the largest count.
    """
    g = forces.Gravity([0.0, -9.81])
    launcher = Emitter(1.6, Point([0.0, 0.0]), Cone([0, 1], 12.0, 1.5, angle=0.3), lifetime=(1.1, 0.2),
                       rate_spread=0.8, start=-0.55, stop=max(seconds - 1.8, 0.5), tint="random")  # first at 0.1 s
    rockets = ParticleEffect(2, [launcher], forces=[g], color=ColorRamp(["white"], [1.0]), size=8.0,
                             seed=seed, name="rockets")
    trails = rockets.add_child(ParticleEffect(2, forces=[g, forces.Damping(2.0)], size=3.0, seed=seed + 1,
                                              color=ColorRamp(["#fff3c4", "#ff9f1c"], [0.8, 0.0]), name="trails"))
    trails.add_emitter(ParticleEmitter(rockets, rate=90.0, velocity=Cone([0, 1], 0.5, 0.3, angle=np.pi),
                                       lifetime=(0.35, 0.1)))
    sparks = rockets.add_child(ParticleEffect(2, forces=[g, forces.Damping(0.7)], size=6.0, seed=seed + 2,
                                              color=ColorRamp(["white"], [1.0, 0.9, 0.0]), name="sparks"))
    sparks.add_emitter(ParticleEmitter(rockets, count=(140, 40), when="death", inherit=0.4, tint="parent",
                                       velocity=Cone([0, 1], 3.5, 1.0, angle=np.pi), lifetime=(1.6, 0.5)))
    crackle = sparks.add_child(ParticleEffect(2, forces=[g], size=4.0, seed=seed + 3, name="crackle",
                                              color=ColorRamp(["white", "#ffe08a"], [1.0, 0.0])))
    crackle.add_emitter(ParticleEmitter(sparks, count=(0.6, 0.6), when="death", inherit=1.0,
                                        velocity=Cone([0, 1], 0.8, angle=np.pi), lifetime=(0.25, 0.1)))
    return _from_effect(rockets, "fireworks", "fireworks", seconds, fps, 1 / 30, blur=0.04, background="black",
                        axis=False, limits=[(-7.0, 7.0), (0.0, 12.0)])


@register("smoke", "2D: a moving chimney, gravity pointing up, wind gusts; puffs grow and fade",
          preview=dict(seconds=3.0))
def smoke(seconds=4.0, fps=15, seed=0):
    """Smoke from a moving chimney: gravity pointing up, damping, wind gusts, in 2D.

    A disk of radius 0.12 m swinging as ``0.8 sin(0.9 t)`` m emits 120
    puffs/s, which inherit half its velocity, rise under an upward "gravity"
    of 0.35 m/s^2, are slowed by damping and blown by gusty wind; they grow
    from 25 to 300 points^2 and fade out over their 3.5 +- 1 s. Steps of 1/30 s.

    Parameters
    ----------
    seconds : float
        Simulated time, in seconds (default 4.0).
    fps : float
        Frames recorded per simulated second (default 15); the time step
        is the demo's own, so `fps` does not change the physics.
    seed : int
        Seed of the emitter's random numbers.

    Returns
    -------
    DemoData
        Per frame, positions and velocities of shape (n_k, 2) (m, m/s),
        RGBA colours (n_k, 4) fading with age and marker areas (n_k,) growing
        with it; ``info["most particles"]``: the largest count.
    """
    chimney = Disk(lambda t: np.stack([0.8 * np.sin(0.9 * t), np.zeros_like(t)], axis=-1), 0.12)
    source = Emitter(120.0, chimney, Cone([0, 1], 0.5, 0.3, angle=0.6), lifetime=(3.5, 1.0), inherit=0.5)
    puffs = ParticleEffect(
        2, [source], size=(25.0, 300.0), seed=seed, name="smoke",
        forces=[forces.Gravity([0.0, 0.35]), forces.Damping(0.6),
                forces.Wind([0.25, 0.0], gust=0.8, period=2.5, wavelength=3.0)],
        color=ColorRamp(["0.25", "0.55", "0.85"], [0.5, 0.3, 0.0]))
    return _from_effect(puffs, "smoke", "smoke (gravity up, fading)", seconds, fps, 1 / 30,
                        limits=[(-2.5, 3.5), (-0.2, 5.0)], lines=[np.array([[-2.5, -0.05], [3.5, -0.05]])])


@register("bouncing", "2D: balls in a box with a ramp and an obstacle (restitution 0.95, backtracking)",
          preview=dict(seconds=2.4))
def bouncing(seconds=4.0, fps=15, seed=0):
    """Balls in a box with a ramp and a round obstacle: restitution 0.95, friction, backtracking, in 2D.

    Up to 24 balls start at random in the upper part of the 4 m x 3 m box
    (those that would start inside the obstacle or below the ramp are left out) with random
    velocities; gravity, velocity Verlet with steps of 1/90 s and
    :class:`particles.collisions.Collider` with ``method="backtrack"``.

    Parameters
    ----------
    seconds : float
        Simulated time, in seconds (default 4.0).
    fps : float
        Frames recorded per simulated second (default 15); the time step
        is the demo's own, so `fps` does not change the physics.
    seed : int
        Seed of the initial positions and velocities.

    Returns
    -------
    DemoData
        Per frame, positions and velocities of shape (n, 2) (m, m/s; the
        same n balls throughout), one colour per ball (n, 4) and areas (n,);
        ``info``: the number of contacts and the fraction of the energy kept.
    """
    rng = np.random.default_rng(seed)
    n = 24
    x = np.column_stack([rng.uniform(0.3, 3.7, n), rng.uniform(1.8, 2.8, n)])
    ball, ramp = Sphere([2.2, 0.9], 0.45), Plane([0.0, 0.8], [1.0, 2.0])
    scene = Box([0.0, 0.0], [4.0, 3.0], container=True) | ball | ramp
    x = x[scene.H(x) > 0]
    system = ParticleSystem(x, v=rng.normal(0.0, 1.5, x.shape), forces=[forces.Gravity([0.0, -9.81])])
    E0 = system.kinetic_energy() + system.potential_energy()
    collider = Collider(scene, restitution=0.95, friction=0.02, method="backtrack")
    h = 1 / 90
    every = _every(fps, h)
    t, X, contacts = collider.run(system, seconds, h=h, method="verlet", every=every)
    E1 = system.kinetic_energy() + system.potential_energy()
    color = np.array([(*c, 1.0) for c in _palette(len(x))])
    walls = np.array([[0, 0], [4, 0], [4, 3], [0, 3], [0, 0]], dtype=float)
    return DemoData("bouncing", "bouncing balls", t, list(X[:, :, 0]), velocities=list(X[:, :, 1]),
                    colors=[color] * len(t), sizes=[np.full(len(x), 60.0)] * len(t), blur=0.03, fps=1 / (every * h),
                    lines=[walls, _circle(ball.center, ball.radius), np.array([[0.0, 0.8], [1.6, 0.0]])],
                    limits=[(-0.1, 4.1), (-0.1, 3.1)],
                    info={"contacts": len(contacts), "energy kept": f"{E1 / E0:.2f}"})


def _palette(n):
    from matplotlib import colormaps

    return colormaps["tab10"](np.arange(n) % 10)[:, :3]


@register("flock", "2D: Reynolds' boids from random headings to one flock; the camera follows it")
def flock(seconds=8.0, fps=10, seed=0):
    """200 boids from random headings to one flock (Reynolds' rules), in 2D; the camera follows it.

    The rules and limits of tests/test_flocking.py: radius 3 m, separation
    0.1, alignment 2, cohesion 0.5, steering at most 3 m/s^2, speeds within
    [0.5, 2] m/s; steps of 1/50 s. Each boid is coloured by its heading.

    Parameters
    ----------
    seconds : float
        Simulated time, in seconds (default 8.0).
    fps : float
        Frames recorded per simulated second (default 10); the time step
        is the demo's own, so `fps` does not change the physics.
    seed : int
        Seed of the initial positions (uniform in a 10 m square) and headings.

    Returns
    -------
    DemoData
        Per frame, positions relative to the flock's centre and velocities,
        shape (200, 2) (m, m/s), colours (200, 4) by heading and areas
        (200,); ``info["polarization"]``: its first and last values.
    """
    from matplotlib.colors import hsv_to_rgb

    rng = np.random.default_rng(seed)
    n = 200
    x = rng.uniform(0.0, 10.0, (n, 2))
    angle = rng.uniform(0.0, 2 * np.pi, n)
    v = np.column_stack([np.cos(angle), np.sin(angle)])
    rules = Boids(3.0, separation=0.1, alignment=2.0, cohesion=0.5, max_force=3.0)  # as in the tests
    birds = Flock(x, v, rules, min_speed=0.5, max_speed=2.0)
    h = 1 / 50
    every = _every(fps, h)
    t, X = birds.run(seconds, h=h, every=every)
    heading = np.arctan2(X[:, :, 1, 1], X[:, :, 1, 0]) / (2 * np.pi) % 1.0
    colors = [np.column_stack([hsv_to_rgb(np.column_stack([hk, np.full(n, 0.75), np.full(n, 0.9)])),
                               np.ones(n)]) for hk in heading]
    p = [polarization(Xk[:, 1]) for Xk in X]
    centred = [Xk[:, 0] - Xk[:, 0].mean(axis=0) for Xk in X]  # a camera that follows the flock
    return DemoData("flock", "flock (camera follows)", t, centred, velocities=list(X[:, :, 1]), colors=colors,
                    sizes=[np.full(n, 12.0)] * len(t), blur=0.4, fps=1 / (every * h), limits=[(-8.0, 8.0), (-8.0, 8.0)],
                    info={"polarization": f"{p[0]:.2f} -> {p[-1]:.2f}"})


@register("genesis", "3D: Reeves' Genesis effect, an expanding ring of secondary systems over a planet",
          preview=dict(seconds=2.4))
def genesis(seconds=3.6, fps=15, seed=0):
    """Reeves' Genesis effect: an expanding ring of secondary particle systems over a planet, in 3D.

    A ring on the unit sphere, its polar angle growing as ``0.6 t`` rad,
    emits 120 short-lived particles/s; each is itself the emitter of a
    child "fire" effect (18 particles/s, shot outwards from the planet's
    centre, pulled back by an attractor and slowed by damping). Steps of 1/30 s.

    Parameters
    ----------
    seconds : float
        Simulated time, in seconds (default 3.6).
    fps : float
        Frames recorded per simulated second (default 15); the time step
        is the demo's own, so `fps` does not change the physics.
    seed : int
        Seed of the ring emitter; the fire uses seed + 1.

    Returns
    -------
    DemoData
        Per frame, positions and velocities of shape (n_k, 3) (m, m/s) of
        both generations, RGBA colours (n_k, 4) and areas (n_k,), on a black
        background; ``info["most particles"]``: the largest count.
    """
    planet = np.zeros(3)
    ring = SphereSurface(planet, 1.0, polar=lambda t: (0.6 * t, 0.6 * t + 0.12))
    systems = ParticleEffect(3, [Emitter(120.0, ring, lifetime=(0.7, 0.2))], size=2.0, seed=seed,
                             color=ColorRamp(["#ffd27a"], [0.6, 0.0]), name="systems")
    fire = systems.add_child(ParticleEffect(
        3, size=(6.0, 2.0), seed=seed + 1, name="fire",
        forces=[forces.Attractor(planet, strength=1.2, softening=0.2), forces.Damping(0.3)],
        color=ColorRamp(["#fff6b0", "#ffb000", "#d62400", "#400000"], [1.0, 0.9, 0.6, 0.0])))
    fire.add_emitter(ParticleEmitter(systems, rate=18.0, velocity=Cone([0, 0, 1], 0.9, 0.35, angle=0.35),
                                     axis=planet, lifetime=(0.9, 0.3)))
    lines = [_circle([0, 0, z], np.sqrt(1 - z * z), axes=(0, 1), d=3) for z in (-0.6, -0.3, 0.0, 0.3, 0.6)]
    lines += [_circle(planet, 1.0, axes=(0, 2), d=3), _circle(planet, 1.0, axes=(1, 2), d=3)]
    return _from_effect(systems, "genesis", "Genesis effect", seconds, fps, 1 / 30, background="black", axis=False,
                        limits=[(-1.6, 1.6)] * 3, view=(20, -50), lines=lines)


def animate_demo(data, figsize=(4, 4)):
    """A Matplotlib animation of a :class:`DemoData` (see :func:`particles.render.animate`)."""
    from . import render

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
    from . import render

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


from . import clothdemos  # noqa: E402,F401  (registers the mass-spring demos "cloth" and "drape")
