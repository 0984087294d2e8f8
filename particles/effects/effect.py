"""Particle effects: a particle system whose particles are born, age and die.

:class:`ParticleEffect` is Reeves' *particle system*: emitters create
particles (:mod:`particles.effects.emitters`), forces move them, every particle
records its birth time and lifetime, its colour and transparency follow its
age (:class:`ColorRamp`), and it is removed when it is older than its
lifetime or, optionally, when it leaves given bounds. Effects form a tree:
a child effect's :class:`particles.effects.emitters.ParticleEmitter` can use the
particles of its parent as emitters (Reeves' hierarchical systems, the
Genesis effect; the sparks of a firework).

One step of the whole tree, from ``t`` to ``t + h``, is one step of the
root's :meth:`particles.ParticleSystem.run`, the library's one loop:

1. the root moves its particles with its stepper (one step of its ODE
   method, then collisions, if any: :attr:`ParticleEffect.stepper`);
2. then, in the run's ``between_steps`` hook (:meth:`ParticleEffect.between_steps`),
   every child moves its particles the same way (a one-step run of its own
   system), parents first every emitter adds the particles born during the
   step, each advanced by the part of the step it has lived, and every
   effect removes its dead particles.

Births and deaths are array operations (:meth:`particles.ParticleSystem.add_particles`,
:meth:`particles.ParticleSystem.remove_particles`); no Python loop runs
over particles. Colours come from :mod:`particles.effects.colours`, which does not
need Matplotlib.

References
----------
.. [1] W. T. Reeves, "Particle Systems - a Technique for Modeling a Class of
   Fuzzy Objects", ACM Transactions on Graphics 2(2), 91-108, 1983.
"""

from dataclasses import dataclass, field

import numpy as np

from .._checks import as_float_array, end_time, positive_number
from ..collisions.collider import Collider
from ..errors import SimulationDiverged
from ..integrators.solvers import as_stepper
from ..system import ParticleSystem
from .colours import ColorRamp
from .emitters import LIFE_TOL, Emitter, ParticleEmitter

__all__ = ["ColorRamp", "Snapshot", "ParticleEffect"]  # ColorRamp lives in particles.effects.colours


@dataclass
class Snapshot:
    """The particles of an effect tree at one time, ready to draw.

    Attributes
    ----------
    t : float
        Time, in seconds.
    x, v : ndarray, shape (n, d)
        Positions and velocities of all live particles of the tree.
    rgba : ndarray, shape (n, 4)
        Colours with transparency, from each effect's ramp and the particles' tints.
    size : ndarray, shape (n,)
        Marker areas, in points^2.
    age : ndarray, shape (n,)
        Ages, in seconds.
    counts : dict of str to int
        Live particles per effect, by effect name.
    """

    t: float
    x: np.ndarray
    v: np.ndarray
    rgba: np.ndarray
    size: np.ndarray
    age: np.ndarray
    counts: dict = field(default_factory=dict)

    def __len__(self):
        return len(self.x)


class ParticleEffect:
    """A particle system with emitters, lifetimes, colours by age, and child effects.

    Parameters
    ----------
    d : int
        Dimension of space, 2 or 3.
    emitters : sequence of Emitter or ParticleEmitter
        Where the particles come from (more can be added with :meth:`add_emitter`).
    forces : sequence of Force
        Forces on every particle (e.g. gravity, pointing up for smoke, and damping).
    collider : Collider, optional
        Collisions after each step (newborn particles are projected).
    bounds : (array_like, array_like), optional
        Box ``(lo, hi)``; particles leaving it are removed too.
    color : ColorRamp, optional
        Colour and transparency by age (default: white, fading out).
    size : float or (float, float)
        Marker area for drawing, in points^2; a pair ``(start, end)`` grows
        (or shrinks) it linearly over the relative age (smoke puffs spread).
    method : str
        ODE stepper (see :data:`particles.integrators.INTEGRATORS`).
    seed : int or numpy.random.Generator, optional
        Random numbers for all emitters of this effect.
    name : str
        Used in :attr:`Snapshot.counts`.
    t : float
        Start time, in seconds.

    Attributes
    ----------
    system : ParticleSystem
        The live particles; per-particle ``birth``, ``lifetime``, ``tint``
        and ``emitter`` are in ``system.attributes``.
    children : list of ParticleEffect
    steps : int
        Steps this effect has taken as the root of its tree.

    Examples
    --------
    >>> from particles.effects.emitters import Point, Cone
    >>> from particles.forces import Gravity
    >>> tap = Emitter(100.0, Point([0.0, 0.0]), Cone([0.0, 1.0], 3.0, 0.5, angle=0.2), lifetime=0.5)
    >>> fountain = ParticleEffect(2, [tap], forces=[Gravity([0.0, -9.81])], seed=0)
    >>> frames = fountain.run(2.0, h=0.01, every=50)
    >>> [len(s) for s in frames]     # the count settles at rate x lifetime
    [0, 50, 50, 50, 50]
    """

    def __init__(self, d, emitters=(), forces=(), collider=None, bounds=None, color=None, size=6.0,
                 method="symplectic_euler", seed=None, name="effect", t=0.0):
        if d not in (2, 3):
            raise ValueError(f"d must be 2 or 3, got {d!r}")
        self.system = ParticleSystem(np.zeros((0, d)), forces=forces, t=t)
        for key, fill, shape in (("birth", 0.0, ()), ("lifetime", np.inf, ()), ("tint", 1.0, (3,))):
            self.system.define_attribute(key, fill=fill, shape=shape)
        self.system.define_attribute("emitter", fill=-1, dtype=np.int64)
        if collider is not None and not isinstance(collider, Collider):
            raise ValueError(f"collider must be a particles.collisions.Collider, got {type(collider).__name__}")
        self.collider = collider
        self.bounds = None
        if bounds is not None:
            lo, hi = (as_float_array(b, "bounds", shape=(d,)) for b in bounds)
            if np.any(hi <= lo):
                raise ValueError(f"bounds must be (lo, hi) with lo < hi, got {lo.tolist()} and {hi.tolist()}")
            self.bounds = (lo, hi)
        self.color = ColorRamp() if color is None else color
        if not isinstance(self.color, ColorRamp):
            raise ValueError(f"color must be a ColorRamp, got {type(self.color).__name__}")
        sizes = np.atleast_1d(as_float_array(size, "size", ndim=(0, 1)))
        if sizes.shape not in ((1,), (2,)) or np.any(sizes <= 0):
            raise ValueError(f"size must be a positive number or a pair (start, end) in points^2, got {size!r}")
        self.size = sizes if len(sizes) == 2 else np.repeat(sizes, 2)
        self.method = method
        self._step = as_stepper(method)
        self.rng = np.random.default_rng(seed)
        self.name = str(name)
        self.steps = self._run_steps = 0
        self.emitters, self.children = [], []
        for emitter in emitters:
            self.add_emitter(emitter)

    @property
    def d(self):
        return self.system.d

    @property
    def n(self):
        """Number of live particles of this effect (not its children)."""
        return self.system.n

    @property
    def t(self):
        return self.system.t

    def add_emitter(self, emitter):
        """Add an Emitter or ParticleEmitter; returns it."""
        if not isinstance(emitter, (Emitter, ParticleEmitter)):
            raise ValueError(f"emitters must be Emitter or ParticleEmitter objects, got {type(emitter).__name__}")
        d = emitter.system.d if isinstance(emitter, ParticleEmitter) else emitter.d
        if d != self.d:
            raise ValueError(f"the emitter lives in another dimension ({d}D) than this {self.d}D effect")
        self.emitters.append(emitter)
        return emitter

    def add_child(self, effect):
        """Make `effect` step after this one (its emitters may use this effect's particles); returns it."""
        if not isinstance(effect, ParticleEffect) or effect is self:
            raise ValueError("effect must be another ParticleEffect")
        effect.system.set_state(t=self.t)
        self.children.append(effect)
        return effect

    def tree(self):
        """This effect and all its descendants, parents before children."""
        yield self
        for child in self.children:  # a loop over child effects
            yield from child.tree()

    def age(self):
        """Ages of the live particles, in seconds, shape (n,)."""
        return self.t - self.system.attributes["birth"]

    def relative_age(self):
        """Age over lifetime (or over the ramp's duration), clipped to [0, 1], shape (n,)."""
        return self.color.relative(self.age(), self.system.attributes["lifetime"])

    def colors(self):
        """RGBA of the live particles, shape (n, 4): the ramp at their age, times their tint."""
        rgba = self.color(self.relative_age())
        rgba[:, :3] *= self.system.attributes["tint"]
        return rgba

    def sizes(self):
        """Marker areas of the live particles, in points^2, shape (n,)."""
        return self.size[0] + (self.size[1] - self.size[0]) * self.relative_age()

    def stepper(self, f, X, t, h):
        """One step of this effect's particles: its ODE method, then its collisions (newborns excluded).

        A stepper of the library's form, for :meth:`particles.ParticleSystem.run`.

        Parameters
        ----------
        f : callable
            ``f(X, t)``: the derivative of :attr:`system`.
        X : ndarray, shape (n, 2, d)
            Positions (m) and velocities (m/s) of the live particles. Not modified.
        t, h : float
            Time and time step, in seconds.

        Returns
        -------
        ndarray, shape (n, 2, d)
        """
        if len(X) == 0:
            return X.copy(order="K")
        X_new = self._step(f, X, t, h)
        if self.collider is None or not np.isfinite(X_new).all():  # a blow-up: the run reports it
            return X_new
        X_new, _ = self.collider.collide(X, X_new, t, h, m=self.system.m)
        return X_new

    def between_steps(self, system, t0):
        """The hook of the root's run: move the children, emit (parents first), remove the dead.

        Parameters
        ----------
        system : ParticleSystem
            The root's system, at the end of the step (``system.t``).
        t0 : float
            The start of the step, in seconds.
        """
        t1 = system.t
        self.steps += 1
        self._run_steps += 1
        effects = list(self.tree())
        for effect in effects[1:]:  # a loop over the child effects: one step of each
            try:
                effect.system.run(t1, t1 - t0, method=effect.stepper)
            except SimulationDiverged as error:
                raised = SimulationDiverged(self._run_steps, t0, t1 - t0, error.method,
                                            f"(in the effect {effect.name!r})")
                raised.effect = effect.name
                raise raised from error
        for effect in effects:
            effect._emit(t0, t1)
        for effect in effects:
            effect._cull(t1)

    def _run(self, t_end, h, every, record):
        """The root's :meth:`particles.ParticleSystem.run` with the tree's stepper and hook."""
        self._run_steps = 0
        try:
            return self.system.run(t_end, h, method=self.stepper, every=every, between_steps=self.between_steps,
                                   record=record)
        except SimulationDiverged as error:
            if getattr(error, "effect", None) is None:
                error.args, error.effect = (f"{error} (in the effect {self.name!r})",), self.name
            raise

    def step(self, h):
        """Advance the whole tree by `h` seconds: move, emit (parents first), remove the dead.

        Parameters
        ----------
        h : float
            Time step, in seconds, > 0.

        Raises
        ------
        SimulationDiverged
            When the step makes the state of an effect blow up; it names the
            effect.
        """
        t1 = self.t + positive_number(h, "h", "seconds")
        self._run(t1, t1 - self.t, 1, lambda system: None)  # one step, landing on t + h

    def _emit(self, t0, t1):
        for k, emitter in enumerate(self.emitters):  # a loop over emitters
            births = emitter.emit(t0, t1, self.rng)
            if not len(births):
                continue
            x, v = self._advance_newborn(births, t1)
            self.system.add_particles(x, v, m=births.m, birth=births.t, lifetime=births.lifetime,
                                      tint=1.0 if births.tint is None else births.tint, emitter=k)

    def _advance_newborn(self, births, t1):
        """Move newborns over the part of the step they have lived, tau = t1 - t_birth.

        ``x + v tau + a tau^2 / 2`` with the acceleration ``a = F / m`` at
        birth (interactions with other particles are left to the next step).
        """
        tau = (t1 - births.t)[:, None]
        F = np.zeros_like(births.x)
        for force in self.system.forces:  # a loop over forces
            force.add_to(F, births.x, births.v, t1, births.m)
        a = F / births.m[:, None]
        x = births.x + births.v * tau + 0.5 * a * tau**2
        v = births.v + a * tau
        if self.collider is not None:
            x, v, _ = self.collider.resolve(x, v, births.m, t=t1)
        return x, v

    def _cull(self, t1):
        a = self.system.attributes
        dead = t1 - a["birth"] >= a["lifetime"] - LIFE_TOL  # a particle lives [birth, birth + lifetime)
        if self.bounds is not None:
            x = self.system.X[:, 0]
            dead |= np.any((x < self.bounds[0]) | (x > self.bounds[1]), axis=1)
        if dead.any():
            self.system.remove_particles(dead)

    def snapshot(self):
        """The live particles of the whole tree now, as a :class:`Snapshot`."""
        effects = list(self.tree())
        X = [e.system.X for e in effects]
        return Snapshot(
            t=self.t,
            x=np.concatenate([Xk[:, 0] for Xk in X]),
            v=np.concatenate([Xk[:, 1] for Xk in X]),
            rgba=np.concatenate([e.colors() for e in effects]),
            size=np.concatenate([e.sizes() for e in effects]),
            age=np.concatenate([e.age() for e in effects]),
            counts={e.name: e.n for e in effects},
        )

    def run(self, t_end, h, every=1):
        """Step the tree to `t_end` and record snapshots: the root's :meth:`particles.ParticleSystem.run`.

        Parameters
        ----------
        t_end : float
            End time, in seconds.
        h : float
            Time step, in seconds (the last one is shortened to land on `t_end`).
        every : int
            Record every `every`-th step (the first and last are always recorded).

        Returns
        -------
        list of Snapshot

        Raises
        ------
        SimulationDiverged
            When the state of an effect blows up: the message names the step
            of this run, its time and the effect; the tree keeps the state at
            the start of that step.
        """
        _, frames = self._run(end_time(t_end, self.t, "effect"), h, every, lambda system: self.snapshot())
        return frames
