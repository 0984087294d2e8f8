"""The effect demos: particle effects with emitters, lifetimes, colour ramps and child systems.

``fountain``, ``fireworks``, ``smoke`` and ``genesis`` each build a
:class:`particles.effects.ParticleEffect` tree and record it with
:func:`record_effect`.
"""

import numpy as np

from ..collisions.collider import Collider
from ..collisions.surfaces import Plane
from ..effects.colours import ColorRamp
from ..effects.distributions import Cone, Disk, Point, SphereSurface
from ..effects.effect import ParticleEffect
from ..effects.emitters import Emitter, ParticleEmitter
from ..forces.fields import Attractor, Damping, Gravity, Wind
from .data import DemoData, circle, steps_per_frame

__all__ = ["fountain", "fireworks", "smoke", "genesis", "record_effect"]


def record_effect(effect, name, title, seconds, fps, h, **options):
    """Run an effect tree with steps of `h` seconds and package a snapshot per frame.

    Parameters
    ----------
    effect : ParticleEffect
        The root of the tree.
    name, title : str
        Of the :class:`DemoData`.
    seconds, fps : float
        Simulated time (s) and frames per simulated second.
    h : float
        Time step, in seconds.
    **options
        Other fields of :class:`DemoData`; ``info`` entries are added to
        ``"most particles"``.

    Returns
    -------
    DemoData
    """
    every = steps_per_frame(fps, h)
    frames = effect.run(seconds, h=h, every=every)
    fps = 1.0 / (every * h)
    largest = max(sum(s.counts.values()) for s in frames)
    return DemoData(name, title, np.array([s.t for s in frames]), [s.x for s in frames],
                    velocities=[s.v for s in frames], colors=[s.rgba for s in frames],
                    sizes=[s.size for s in frames], fps=fps,
                    info={"most particles": largest, **options.pop("info", {})}, **options)


def fountain(seconds=4.0, fps=10, seed=0):
    """Water from a nozzle under gravity, splashing on the ground: collisions and lifetimes, in 3D.

    A disk nozzle of radius 4 cm emits 250 drops/s upwards in a cone
    (4.4 m/s, half-angle 0.3 rad), each living 2.4 +- 0.4 s; gravity, light
    damping and the ground ``z = 0`` (restitution 0.3, friction 0.6, with
    backtracking) act on them; drops leaving the box ``[-3, 3]^2 x [-1, 3]``
    m are removed. Steps of 1/40 s.

    Parameters
    ----------
    seconds, fps, seed
        As for every demo (see :mod:`particles.demos`); defaults 4.0 s and
        10 frames/s. `seed`: seed of the emitter's random numbers.

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
    water = ParticleEffect(3, [nozzle], forces=[Gravity([0, 0, -9.81]), Damping(0.05)],
                           collider=ground, color=ColorRamp(["#f2fbff", "#5aa9e6", "#1d4e89"], [0.9, 0.8, 0.0]),
                           size=5.0, seed=seed, name="water", bounds=([-3, -3, -1], [3, 3, 3]))
    return record_effect(water, "fountain", "fountain", seconds, fps, 1 / 40, blur=0.03,
                        limits=[(-1.6, 1.6), (-1.6, 1.6), (0.0, 1.6)], view=(18, -60),
                        lines=[circle([0, 0, 0], 1.5, axes=(0, 1), d=3)])


def fireworks(seconds=5.0, fps=15, seed=0):
    """Rockets with trails and bursts, systems of systems (Reeves' hierarchy), in 2D.

    A launcher fires about 1.6 rockets/s (12 m/s, random tints); each
    rocket is the emitter of a child effect of trails (90 particles/s) and,
    when it dies after about 1.1 s, of a burst of 140 +- 40 sparks, some of
    which crackle when they die in turn. Steps of 1/30 s; the launcher stops
    1.8 s before the end so that the last bursts are seen.

    Parameters
    ----------
    seconds, fps, seed
        As for every demo (see :mod:`particles.demos`); defaults 5.0 s and
        15 frames/s. `seed`: seed of the launcher; the child effects use seed + 1, + 2 and + 3.

    Returns
    -------
    DemoData
        Per frame, positions and velocities of shape (n_k, 2) (m, m/s) of
        all rockets, trails, sparks and crackle together, RGBA colours
        (n_k, 4) and marker areas (n_k,), on a black background;
        ``info["most particles"]``: the largest count.
    """
    g = Gravity([0.0, -9.81])
    launcher = Emitter(1.6, Point([0.0, 0.0]), Cone([0, 1], 12.0, 1.5, angle=0.3), lifetime=(1.1, 0.2),
                       rate_spread=0.8, start=-0.55, stop=max(seconds - 1.8, 0.5), tint="random")  # first at 0.1 s
    rockets = ParticleEffect(2, [launcher], forces=[g], color=ColorRamp(["white"], [1.0]), size=8.0,
                             seed=seed, name="rockets")
    trails = rockets.add_child(ParticleEffect(2, forces=[g, Damping(2.0)], size=3.0, seed=seed + 1,
                                              color=ColorRamp(["#fff3c4", "#ff9f1c"], [0.8, 0.0]), name="trails"))
    trails.add_emitter(ParticleEmitter(rockets, rate=90.0, velocity=Cone([0, 1], 0.5, 0.3, angle=np.pi),
                                       lifetime=(0.35, 0.1)))
    sparks = rockets.add_child(ParticleEffect(2, forces=[g, Damping(0.7)], size=6.0, seed=seed + 2,
                                              color=ColorRamp(["white"], [1.0, 0.9, 0.0]), name="sparks"))
    sparks.add_emitter(ParticleEmitter(rockets, count=(140, 40), when="death", inherit=0.4, tint="parent",
                                       velocity=Cone([0, 1], 3.5, 1.0, angle=np.pi), lifetime=(1.6, 0.5)))
    crackle = sparks.add_child(ParticleEffect(2, forces=[g], size=4.0, seed=seed + 3, name="crackle",
                                              color=ColorRamp(["white", "#ffe08a"], [1.0, 0.0])))
    crackle.add_emitter(ParticleEmitter(sparks, count=(0.6, 0.6), when="death", inherit=1.0,
                                        velocity=Cone([0, 1], 0.8, angle=np.pi), lifetime=(0.25, 0.1)))
    return record_effect(rockets, "fireworks", "fireworks", seconds, fps, 1 / 30, blur=0.04, background="black",
                        axis=False, limits=[(-7.0, 7.0), (0.0, 12.0)])


def smoke(seconds=4.0, fps=15, seed=0):
    """Smoke from a moving chimney: gravity pointing up, damping, wind gusts, in 2D.

    A disk of radius 0.12 m swinging as ``0.8 sin(0.9 t)`` m emits 120
    puffs/s, which inherit half its velocity, rise under an upward "gravity"
    of 0.35 m/s^2, are slowed by damping and blown by gusty wind; they grow
    from 25 to 300 points^2 and fade out over their 3.5 +- 1 s. Steps of 1/30 s.

    Parameters
    ----------
    seconds, fps, seed
        As for every demo (see :mod:`particles.demos`); defaults 4.0 s and
        15 frames/s. `seed`: seed of the emitter's random numbers.

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
        forces=[Gravity([0.0, 0.35]), Damping(0.6),
                Wind([0.25, 0.0], gust=0.8, period=2.5, wavelength=3.0)],
        color=ColorRamp(["0.25", "0.55", "0.85"], [0.5, 0.3, 0.0]))
    return record_effect(puffs, "smoke", "smoke (gravity up, fading)", seconds, fps, 1 / 30,
                        limits=[(-2.5, 3.5), (-0.2, 5.0)], lines=[np.array([[-2.5, -0.05], [3.5, -0.05]])])


def genesis(seconds=3.6, fps=15, seed=0):
    """Reeves' Genesis effect: an expanding ring of secondary particle systems over a planet, in 3D.

    A ring on the unit sphere, its polar angle growing as ``0.6 t`` rad,
    emits 120 short-lived particles/s; each is itself the emitter of a
    child "fire" effect (18 particles/s, shot outwards from the planet's
    centre, pulled back by an attractor and slowed by damping). Steps of 1/30 s.

    Parameters
    ----------
    seconds, fps, seed
        As for every demo (see :mod:`particles.demos`); defaults 3.6 s and
        15 frames/s. `seed`: seed of the ring emitter; the fire uses seed + 1.

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
        forces=[Attractor(planet, strength=1.2, softening=0.2), Damping(0.3)],
        color=ColorRamp(["#fff6b0", "#ffb000", "#d62400", "#400000"], [1.0, 0.9, 0.6, 0.0])))
    fire.add_emitter(ParticleEmitter(systems, rate=18.0, velocity=Cone([0, 0, 1], 0.9, 0.35, angle=0.35),
                                     axis=planet, lifetime=(0.9, 0.3)))
    lines = [circle([0, 0, z], np.sqrt(1 - z * z), axes=(0, 1), d=3) for z in (-0.6, -0.3, 0.0, 0.3, 0.6)]
    lines += [circle(planet, 1.0, axes=(0, 2), d=3), circle(planet, 1.0, axes=(1, 2), d=3)]
    return record_effect(systems, "genesis", "Genesis effect", seconds, fps, 1 / 30, background="black", axis=False,
                        limits=[(-1.6, 1.6)] * 3, view=(20, -50), lines=lines)
