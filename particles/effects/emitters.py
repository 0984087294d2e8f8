"""Emitters: where particles come from, how many, and with which initial state.

An emitter (a *generator* on the slides) creates particles at a rate, in
particles per second. At each step it creates::

    n = floor((t - t_last) * rate)

particles. The slide sets ``t_last = t`` whenever ``n > 0``; that throws away
the fraction ``(t - t_last) * rate - n`` each time, and the emitter runs slow
(with steps of 0.15 s at 10 particles/s it makes 1 per step: 6.7/s, not 10).
Here ``t_last`` is advanced by ``n / rate`` instead: it is always the birth
time of the last particle made, the fraction carries over, and after any
sequence of steps the total is ``floor(rate (t - start))`` exactly (see
:class:`Emitter`).

The ``n`` particles of one step are not all born at the end of the step:
particle ``k`` is born at ``t_last + k / rate``, where a moving emitter was at
that time, and the effect advances it by the part of the step it has lived.
So a fast emitter draws a continuous trail instead of clumps, one per step.

Initial positions come from a *shape* (:class:`Point`, :class:`Disk`,
:class:`SphereSurface`) and velocities from a :class:`Cone` of directions
with a mean speed and a spread. Random quantities follow Reeves: ``mean +
rand * spread`` with ``rand`` uniform in [-1, 1].

:class:`ParticleEmitter` turns the particles of another system into emitters:
trails behind moving particles, bursts when they die, or Reeves' hierarchical
systems, where every particle of a parent system is itself a particle system.

Emitters live in open space: a shape places particles where it is, even
outside a periodic box (:mod:`particles.md.periodic`). That is harmless for the
forces, which take the minimum image of every pair wherever the particles
are; fold the positions with :func:`particles.md.periodic.wrap` to draw them.
A newly added particle resets the neighbour lists of the system's forces
(:meth:`particles.ParticleSystem.add_particles`).

References
----------
.. [1] W. T. Reeves, "Particle Systems - a Technique for Modeling a Class of
   Fuzzy Objects", ACM Transactions on Graphics 2(2), 91-108, 1983
   (SIGGRAPH 1983).
"""

import itertools
from dataclasses import dataclass

import numpy as np

from .._checks import as_float_array, positive_number
from ..system import ParticleSystem
from .colours import hsv_to_rgb, to_rgb
from .distributions import Cone, Disk, Point, SphereSurface, lifetime_range, mean_and_spread, position_at, vary

__all__ = ["Point", "Disk", "SphereSurface", "Cone", "Births", "Emitter", "ParticleEmitter", "vary"]

# Counts are floor(phase + _COUNT_TOL): absorbs round-off in t (0.1 + 0.2 != 0.3).
_COUNT_TOL = 1e-9
# A particle is dead once its age is within LIFE_TOL seconds of its lifetime (round-off in t).
LIFE_TOL = 1e-9
_ids = itertools.count()


@dataclass
class Births:
    """Particles created during one step, before they are added to a system.

    Attributes
    ----------
    t : ndarray, shape (k,)
        Birth times, in seconds, within the step.
    x, v : ndarray, shape (k, d)
        Positions and velocities *at birth*.
    lifetime : ndarray, shape (k,)
        In seconds.
    m : ndarray, shape (k,)
        Masses, in kg.
    tint : ndarray, shape (k, 3) or None
        RGB colours multiplying the effect's colour ramp (None: white).
    """

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    lifetime: np.ndarray
    m: np.ndarray
    tint: np.ndarray = None

    def __len__(self):
        return len(self.t)


def _check_tint(tint):
    """None, "random", "parent" or a Matplotlib colour (checked now, not at the first emission)."""
    if tint is None or (isinstance(tint, str) and tint in ("random", "parent")):
        return tint
    try:
        to_rgb(tint)
    except (ValueError, TypeError):
        raise ValueError(f"tint must be a Matplotlib colour, 'random', 'parent' or None, got {tint!r}") from None
    return tint


def _step_times(t0, t1):
    """The two ends of a step, in seconds, checked: finite, ``t0 <= t1``."""
    t0 = float(as_float_array(t0, "t0", ndim=0))
    t1 = float(as_float_array(t1, "t1", ndim=0))
    if t1 < t0:
        raise ValueError(f"t1 must not be earlier than t0, got t0={t0!r}, t1={t1!r}")
    return t0, t1


class _Source:
    """What the two emitters share: initial velocities, lifetimes, masses, tints."""

    def __init__(self, velocity, lifetime, mass, tint, axis):
        if velocity is not None and not isinstance(velocity, Cone):
            raise ValueError(f"velocity must be a Cone or None, got {type(velocity).__name__}")
        self.velocity = velocity
        self.lifetime = lifetime_range(lifetime)
        self.mass = positive_number(mass, "mass", "kg")
        self.tint = _check_tint(tint)
        self.axis = axis

    def _tints(self, rng, n, parent=None):
        if self.tint is None:
            return None
        if isinstance(self.tint, str) and self.tint == "random":  # a bright random hue each
            return hsv_to_rgb(np.stack([rng.random(n), np.full(n, 0.7), np.ones(n)], axis=1))
        if isinstance(self.tint, str) and self.tint == "parent":
            return parent
        return np.broadcast_to(to_rgb(self.tint), (n, 3)).copy()

    def _births(self, rng, t_birth, x, axis, v_base, parent_tint=None):
        n, d = x.shape
        v = np.zeros((n, d)) if self.velocity is None else self.velocity.sample(rng, n, axis)
        if v_base is not None:
            v += v_base
        return Births(t_birth, x, v, vary(rng, *self.lifetime, n),
                      np.full(n, self.mass), self._tints(rng, n, parent_tint))


class Emitter(_Source):
    """A particle generator at a point, disk or sphere, possibly moving.

    Parameters
    ----------
    rate : float
        Mean rate of creation, in particles per second, >= 0.
    shape : Point, Disk or SphereSurface
        Where particles are born (its centre may be a function of time).
    velocity : Cone, optional
        Initial velocities (default: at rest).
    lifetime : float, (mean, spread) or None
        Lifetime in seconds, fixed or Reeves-random; None: forever.
    rate_spread : float
        Reeves' stochastic count: in each step the rate is
        ``rate + rand * rate_spread``, ``rand`` uniform in [-1, 1]; over a
        step of ``h`` this is Reeves' ``MeanParts + Rand() * VarParts`` with
        ``MeanParts = rate h`` and ``VarParts = rate_spread h``.
    mass : float
        Mass of each particle, in kg.
    inherit : float
        Fraction of the emitter's own velocity (for a moving centre) added to
        the particles' velocities.
    axis : None or "normal"
        ``"normal"``: each velocity cone points along the shape's normal at
        the particle (out of a sphere, along a disk's axis).
    start, stop : float
        The emitter works from `start` to `stop`, in seconds.
    tint : color, "random" or None
        Colour multiplying the effect's colour ramp (None: unchanged).
    carry : bool
        True: ``t_last`` advances by ``n / rate`` (exact counts). False: the
        slide's literal rule ``t_last = t`` when ``n > 0``, which loses the
        fractions and runs slow; kept for comparison in the lecture.

    Notes
    -----
    The counting state is the number ``N`` of particles made so far. With a
    fixed rate, the number due at time ``t`` is ``floor(rate (t - start))``,
    computed directly (no sum of step sizes that could drift): the step
    creates the difference ``n``, and ``t_last = start + N / rate`` is the
    birth time of the last particle, as on the slide but without losing
    the fraction. With ``rate_spread`` the phase ``rate * time`` is summed
    over steps instead (each step has its own rate). The births of one step
    are spread over it: particle ``N + k`` is born when the phase reaches
    ``N + k``.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> tap = Emitter(10.0, Point([0.0, 0.0]))
    >>> [len(tap.emit(t0, t1, rng)) for t0, t1 in [(0.0, 0.15), (0.15, 0.3), (0.3, 0.45)]]
    [1, 2, 1]
    >>> tap.count, tap.t_last
    (4, 0.4)
    """

    def __init__(self, rate, shape, velocity=None, lifetime=None, rate_spread=0.0, mass=1.0, inherit=0.0,
                 axis=None, start=0.0, stop=np.inf, tint=None, carry=True):
        if axis not in (None, "normal"):
            raise ValueError(f"axis must be None or 'normal', got {axis!r}")
        super().__init__(velocity, lifetime, mass, tint, axis)
        self.rate, self.rate_spread = mean_and_spread((rate, rate_spread), "rate", "particles/s")
        if not isinstance(shape, Point):
            raise ValueError(f"shape must be a Point, Disk or SphereSurface, got {type(shape).__name__}")
        self.shape, self.d = shape, shape.d
        if velocity is not None and len(velocity.direction) != self.d:
            raise ValueError(f"velocity has {len(velocity.direction)} components but shape lives in {self.d}D")
        self.inherit = float(as_float_array(inherit, "inherit", ndim=0))
        self.start = float(as_float_array(start, "start", ndim=0))
        self.stop = float(as_float_array(stop, "stop", ndim=0, finite=False))
        if not self.stop > self.start:
            raise ValueError(f"stop must be later than start, got start={start!r}, stop={stop!r}")
        self.carry = bool(carry)
        self.reset()

    def reset(self):
        """Forget what was emitted: counting restarts at `start`."""
        self.count, self.t_last, self.phase, self._seen = 0, self.start, 0.0, self.start

    def emit(self, t0, t1, rng):
        """The particles born in the step ``(t0, t1]``; positions and velocities at birth.

        Parameters
        ----------
        t0, t1 : float
            The step, in seconds, finite, ``t0 <= t1``.
        rng : numpy.random.Generator

        Returns
        -------
        Births
        """
        t0, t1 = _step_times(t0, t1)
        a, b = max(t0, self.start), min(t1, self.stop)
        if a > self._seen:  # time not covered by any step (a simulation starting after `start`)
            self.phase += self.rate * (min(a, self.stop) - self._seen)  # at the mean rate, nobody born
            skipped = self.rate * (min(a, self.stop) - self.start) if not self.rate_spread else self.phase
            self.count = max(self.count, int(np.floor(skipped + _COUNT_TOL)))
            self.t_last = self.start + self.count / self.rate if self.rate else self.start
        self._seen = max(self._seen, b)
        if b <= a or self.rate == 0:
            return self._births(rng, np.zeros(0), np.zeros((0, self.d)), None, None)
        if not self.carry:  # the slide's rule, for comparison
            n = int(np.floor((b - self.t_last) * self.rate + _COUNT_TOL))
            t_birth = self.t_last + np.arange(1, n + 1) / self.rate
            self.t_last = b if n > 0 else self.t_last
        else:
            rate = self.rate if not self.rate_spread else vary(rng, self.rate, self.rate_spread, 1)[0]
            phase0 = self.rate * (a - self.start) if not self.rate_spread else self.phase
            phase1 = self.rate * (b - self.start) if not self.rate_spread else self.phase + rate * (b - a)
            self.phase = phase1
            n = max(int(np.floor(phase1 + _COUNT_TOL)) - self.count, 0) if rate > 0 else 0
            k = self.count + np.arange(1, n + 1)  # particle k is born when the phase reaches k
            t_birth = np.clip(a + (k - phase0) / rate, a, b) if n else np.zeros(0)
            self.t_last = float(t_birth[-1]) if n else self.t_last
        self.count += n
        x = self.shape.sample(rng, t_birth)
        axis = self.shape.normal(x, t_birth) if self.axis == "normal" else None
        v_base = None
        if self.inherit and callable(self.shape.center) and n:  # the emitter's velocity, central differences
            delta, c = 1e-5, self.shape.center
            ahead, behind = position_at(c, t_birth + delta), position_at(c, t_birth - delta)
            v_base = self.inherit * (ahead - behind) / (2 * delta)
        return self._births(rng, t_birth, x, axis, v_base)


class ParticleEmitter(_Source):
    """Every particle of a source system emits: trails, bursts, Reeves' hierarchical systems.

    Parameters
    ----------
    source : ParticleEffect or ParticleSystem
        The parents. With a :class:`particles.effects.ParticleEffect`, each
        parent emits between its birth and its death; with a plain
        :class:`particles.ParticleSystem`, from the first step the emitter sees it.
    rate : float, optional
        Particles per second *per parent* (a trail, a secondary system).
    count : float or (mean, spread), optional
        With ``when="death"``: particles per parent, all at its death (a burst).
    when : {"alive", "death"}
    velocity : Cone, optional
        Velocities relative to the parent.
    axis : None, "velocity" or array_like, shape (d,)
        Cone axis per particle: the cone's own direction (None), the parent's
        direction of motion, or away from a point (the centre of a planet).
    inherit : float
        Fraction of the parent's velocity added.
    lifetime, mass, tint
        As for :class:`Emitter`; ``tint="parent"`` copies the parent's tint.

    Notes
    -----
    Counting is exact per parent: parent ``i`` has made
    ``floor(rate * (min(t, death_i) - birth_i))`` particles by time ``t``, its
    count ``N_i`` is stored with the parent (an attribute of the source
    system) and its births are spread over the step as for :class:`Emitter`.
    A child is born where its parent was then, ``x_p(t) - v_p(t) (t - t_b)``.
    """

    def __init__(self, source, rate=None, count=None, when="alive", velocity=None, axis=None, inherit=0.0,
                 lifetime=None, mass=1.0, tint=None):
        # a ParticleEffect is known by its system (this module does not import particles.effects)
        if not isinstance(source, ParticleSystem) and not isinstance(getattr(source, "system", None), ParticleSystem):
            raise ValueError(f"source must be a ParticleSystem or a ParticleEffect, got {type(source).__name__}")
        super().__init__(velocity, lifetime, mass, tint, axis)
        if when not in ("alive", "death"):
            raise ValueError(f"when must be 'alive' or 'death', got {when!r}")
        self.when = when
        if when == "alive":
            if rate is None:
                raise ValueError("rate (particles per second per parent) is needed when when='alive'")
            self.rate = positive_number(rate, "rate", "particles/s")
        else:
            if count is None:
                raise ValueError("count (particles per parent) is needed when when='death'")
            self.burst = mean_and_spread(count, "count", "particles")  # (mean, spread) per parent
        self.effect = None if isinstance(source, ParticleSystem) else source
        self.system = source.system if self.effect is not None else source
        if when == "death" and self.effect is None:
            raise ValueError("when='death' needs a source with lifetimes (a ParticleEffect)")
        if axis is not None and not (isinstance(axis, str) and axis == "velocity"):
            self.axis = as_float_array(axis, "axis", shape=(self.system.d,))
        self.inherit = float(as_float_array(inherit, "inherit", ndim=0))
        self._key = f"emitted_{next(_ids)}"
        self.system.define_attribute(self._key, fill=0, dtype=np.int64)
        if self.effect is None:
            self.system.define_attribute(self._key + "_since", fill=np.nan)

    def _windows(self, t0, t1):
        """Per parent, the part of ``(t0, t1]`` it is alive: (since, until), shape (n,) each."""
        if self.effect is not None:
            birth = self.system.attributes["birth"]
            return birth, birth + self.system.attributes["lifetime"]
        since = self.system.attributes[self._key + "_since"]
        since[np.isnan(since)] = t0  # parents seen for the first time start now
        return since, np.full(len(since), np.inf)

    def emit(self, t0, t1, rng):
        """The particles born in the step ``(t0, t1]`` from all parents.

        Parameters
        ----------
        t0, t1 : float
            The step, in seconds, finite, ``t0 <= t1``.
        rng : numpy.random.Generator

        Returns
        -------
        Births
            Positions and velocities at birth (see :class:`Emitter`).
        """
        t0, t1 = _step_times(t0, t1)
        d = self.system.d
        born, dies = self._windows(t0, t1)
        done = self.system.attributes[self._key]
        if self.when == "alive":
            due = np.floor(self.rate * (np.minimum(t1, dies) - born) + _COUNT_TOL)
            n = np.maximum(due.astype(np.int64) - done, 0) * (born <= t1)
        else:
            n = np.where((dies <= t1 + LIFE_TOL) & (done == 0), 1, 0)  # dies now: culled after this step
        parent = np.repeat(np.arange(len(n)), n)
        k = np.arange(len(parent)) - np.repeat(np.cumsum(n) - n, n)  # 0, 1, ... within each parent
        done += n
        if self.when == "alive":
            t_birth = born[parent] + (done[parent] - n[parent] + k + 1) / self.rate
        else:  # a burst: all at the death time, then a count per parent
            t_birth = dies[parent]
            sizes = np.maximum(np.round(vary(rng, *self.burst, len(parent))), 0).astype(np.int64)
            parent, t_birth = np.repeat(parent, sizes), np.repeat(t_birth, sizes)
        t_birth = np.clip(t_birth, t0, t1)
        x_p, v_p = self.system.X[parent, 0], self.system.X[parent, 1]
        x = x_p - v_p * (t1 - t_birth)[:, None]  # where the parent was at the birth time
        axis = None
        if isinstance(self.axis, str):
            axis = v_p + (np.linalg.norm(v_p, axis=1) == 0)[:, None] * np.eye(d)[-1]
        elif self.axis is not None:
            axis = x - self.axis
        v_base = self.inherit * v_p if self.inherit else None
        tint = self.system.attributes["tint"][parent] if "tint" in self.system.attributes else None
        return self._births(rng, t_birth, np.asarray(x, dtype=float), axis, v_base, tint)
