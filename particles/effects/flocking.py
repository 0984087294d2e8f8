"""Flocks: Reynolds' boids, particles that steer by three local rules.

Each boid ("bird-oid") sees only its neighbours: the other boids within a
radius ``R`` (and, optionally, within a view angle around its heading). From
them it computes three steering accelerations:

* separation, away from close neighbours: ``sum_j (x_i - x_j) / |x_i - x_j|^2``
  over neighbours closer than ``R_s``;
* alignment, towards their mean velocity: ``mean_j v_j - v_i``;
* cohesion, towards their centre: ``mean_j x_j - x_i``.

The weighted sum is limited to a largest steering acceleration, and the speed
to a range, as for a real animal. Neighbours are found with the bucket grid
of :mod:`particles.neighbors` in O(n), never by testing all pairs.

Measured behaviour (tests/library/effects/test_flocking.py): from random headings the
*polarization* ``|mean_i v_i / |v_i||`` (0 for random headings, 1 when all
fly the same way) rises above 0.9 with alignment on, and the flock keeps a
bounded size with cohesion on.

References
----------
.. [1] C. W. Reynolds, "Flocks, herds and schools: a distributed behavioral
   model", Computer Graphics 21(4), 25-34, 1987 (SIGGRAPH 1987).
.. [2] C. W. Reynolds, "Steering behaviors for autonomous characters", Game
   Developers Conference, 1999 (steering and speed limits).
.. [3] T. Vicsek, A. Czirok, E. Ben-Jacob, I. Cohen and O. Shochet, "Novel type
   of phase transition in a system of self-driven particles", Physical Review
   Letters 75(6), 1226-1229, 1995 (the polarization order parameter).
"""

import numpy as np

from .._checks import as_float_array, end_time, nonnegative_number, positive_number
from ..errors import SimulationDiverged
from ..forces.force import Force
from ..forces.pairs import pair_differences
from ..md.periodic import box_option, minimum_image
from ..neighbors import cell_pairs
from ..system import ParticleSystem

__all__ = ["Boids", "Containment", "Flock", "polarization", "spread"]


def polarization(v):
    """``|mean_i v_i / |v_i||``: 1 when all move the same way, about ``1/sqrt(n)`` for random headings.

    Parameters
    ----------
    v : array_like, shape (n, d)
        Velocities (boids at rest are left out).

    Examples
    --------
    >>> polarization([[1.0, 0.0], [2.0, 0.0], [-1.0, 0.0], [0.0, 3.0]])
    0.3535533905932738
    """
    v = as_float_array(v, "v", ndim=2)
    speed = np.linalg.norm(v, axis=1)
    moving = speed > 0
    if not moving.any():
        return 0.0
    return float(np.linalg.norm(np.mean(v[moving] / speed[moving, None], axis=0)))


def spread(x):
    """Radius of gyration ``sqrt(mean_i |x_i - mean x|^2)``, in metres: the size of a flock."""
    x = as_float_array(x, "x", ndim=2)
    return float(np.sqrt(np.mean(np.sum((x - x.mean(axis=0)) ** 2, axis=1))))


class Boids(Force):
    """Reynolds' three rules as a force, ``F = m a``, for use in any particle system.

    Parameters
    ----------
    radius : float
        Neighbourhood radius ``R``, in metres.
    separation, alignment, cohesion : float
        Weights, >= 0, in m^2/s^2, 1/s and 1/s^2 (0 switches a rule off): the separation
        acceleration ``separation / r`` (m/s^2) needs m^2/s^2 for a distance ``r`` in metres.
    separation_radius : float, optional
        ``R_s``: only neighbours closer than this push away (default ``R / 2``).
    view_angle : float, optional
        Half-angle of the field of view around the heading, in radians (pi:
        all around, the default). Neighbours behind it are not seen.
    max_force : float
        Largest steering acceleration, in m/s^2 (default: unlimited).
    box : array_like, shape (d,) or float, optional
        Side lengths of a periodic world, in metres, each at least
        ``2 radius`` (see :mod:`particles.md.periodic`): boids see each other
        through the walls, by the minimum image. Wrap the positions for
        drawing with :func:`particles.md.periodic.wrap`. Default: open space.

    Notes
    -----
    Seeing is not symmetric with a view angle (``i`` may see ``j`` while
    ``j`` does not see ``i``), so each unordered pair from the bucket grid is
    used in both directions and filtered per observer.
    """

    def __init__(self, radius, separation=1.0, alignment=1.0, cohesion=1.0, separation_radius=None,
                 view_angle=np.pi, max_force=np.inf, box=None):
        self.radius = positive_number(radius, "radius", "metres")
        self.separation = nonnegative_number(separation, "separation")
        self.alignment = nonnegative_number(alignment, "alignment")
        self.cohesion = nonnegative_number(cohesion, "cohesion")
        self.separation_radius = (0.5 * self.radius if separation_radius is None
                                  else positive_number(separation_radius, "separation_radius", "metres"))
        self.view_angle = nonnegative_number(view_angle, "view_angle", "radians")
        if self.view_angle > np.pi:
            raise ValueError(f"view_angle must lie in [0, pi] radians, got {view_angle!r}")
        self.max_force = float(max_force) if max_force == np.inf else positive_number(max_force, "max_force", "m/s^2")
        self.box = box_option(box, self.radius, reach="radius")

    def neighbours(self, x, v):
        """Directed pairs ``(i, j)``: boid ``i`` sees boid ``j``; and ``x_j - x_i`` as shape (d, p)."""
        i, j = cell_pairs(x, self.radius, box=self.box)
        obs, nb = np.concatenate([i, j]), np.concatenate([j, i])
        r = pair_differences(x, nb, obs)  # (d, p): x_j - x_i
        if self.box is not None:
            r = minimum_image(r, self.box, axis=0)
        if self.view_angle < np.pi:
            vt = np.ascontiguousarray(v.T)
            dot = np.zeros(len(obs))
            v2 = np.zeros(len(obs))
            for a in range(len(vt)):  # a loop over the d coordinates
                va = vt[a][obs]
                dot += va * r[a]
                v2 += va * va
            r2 = np.einsum("ap,ap->p", r, r)
            seen = dot >= np.cos(self.view_angle) * np.sqrt(v2 * r2)  # angle(v_i, x_j - x_i) <= view
            obs, nb, r = obs[seen], nb[seen], r[:, seen]
        return obs, nb, r

    def accelerations(self, x, v):
        """Steering accelerations ``a_i`` of all boids.

        Parameters
        ----------
        x, v : array_like, shape (n, d)
            Positions (m) and velocities (m/s), finite, of the same shape.

        Returns
        -------
        ndarray, shape (n, d)
            Accelerations, in m/s^2 (at most `max_force` in length).
        """
        x = as_float_array(x, "x", ndim=2)
        v = as_float_array(v, "v", shape=x.shape)
        n, d = x.shape
        a = np.zeros((n, d), order="F")
        if n < 2:
            return a
        obs, nb, r = self.neighbours(x, v)
        count = np.bincount(obs, minlength=n)
        seen = count > 0
        inv_count = np.divide(1.0, count, out=np.zeros(n), where=seen)
        r2 = np.einsum("ap,ap->p", r, r)
        push = np.where(r2 < self.separation_radius**2, 1.0 / np.maximum(r2, 1e-12), 0.0)
        for k in range(d):  # a loop over the d coordinates
            if self.cohesion:  # mean_j x_j - x_i = mean_j (x_j - x_i)
                a[:, k] += self.cohesion * np.bincount(obs, r[k], minlength=n) * inv_count
            if self.alignment:
                mean_v = np.bincount(obs, v[nb, k], minlength=n) * inv_count
                a[:, k] += self.alignment * np.where(seen, mean_v - v[:, k], 0.0)
            if self.separation:
                a[:, k] -= self.separation * np.bincount(obs, r[k] * push, minlength=n)
        if np.isfinite(self.max_force):
            norm = np.sqrt(np.einsum("ij,ij->i", a, a))
            too_big = norm > self.max_force
            a[too_big] *= (self.max_force / norm[too_big])[:, None]
        return a

    def add_to(self, F, x, v, t, m):
        """Add the steering forces ``m a`` to `F`, in place.

        Parameters
        ----------
        F : ndarray, shape (n, d)
            Force accumulator, in newtons.
        x, v : ndarray, shape (n, d)
            Positions (m) and velocities (m/s).
        t : float
            Time, in seconds (unused: the rules do not depend on it).
        m : float or ndarray, shape (n,)
            Masses, in kg.
        """
        a = self.accelerations(x, v)
        for k in range(F.shape[1]):  # a loop over the d coordinates
            F[:, k] += m * a[:, k]


class Containment(Force):
    """Steer back into a box: an acceleration growing linearly over a margin inside each wall.

    ``a_k = strength (lo_k + margin - x_k) / margin`` below ``lo_k + margin``,
    and the mirror image near ``hi_k``; zero well inside. Reynolds'
    "containment" keeps a flock on screen without hard walls.

    Parameters
    ----------
    lo, hi : array_like, shape (d,)
        The box, in metres.
    margin : float
        Width of the boundary layer, in metres.
    strength : float
        Acceleration at the wall, in m/s^2.
    """

    uses_velocity = False
    uses_time = False

    def __init__(self, lo, hi, margin=1.0, strength=2.0):
        self.lo = as_float_array(lo, "lo", ndim=1)
        self.hi = as_float_array(hi, "hi", shape=self.lo.shape)
        if np.any(self.hi <= self.lo):
            raise ValueError(f"hi must exceed lo along every axis, got lo={self.lo.tolist()}, hi={self.hi.tolist()}")
        self.margin = positive_number(margin, "margin", "metres")
        self.strength = positive_number(strength, "strength", "m/s^2")

    def add_to(self, F, x, v, t, m):
        for k in range(F.shape[1]):  # a loop over the d coordinates
            below = np.maximum(self.lo[k] + self.margin - x[:, k], 0.0)
            above = np.maximum(x[:, k] - (self.hi[k] - self.margin), 0.0)
            F[:, k] += m * self.strength * (below - above) / self.margin


class Flock:
    """A flock of boids: steering forces, then speed limits, one symplectic Euler step at a time.

    Each step (:meth:`stepper`): ``v <- v + h F / m``, then the speed is
    clamped to ``[min_speed, max_speed]`` (the direction is kept), then
    ``x <- x + h v``. The flock runs in :meth:`particles.ParticleSystem.run`,
    the library's one loop, with that stepper; :meth:`run` and :meth:`step`
    are thin wrappers of it.

    Parameters
    ----------
    x, v : array_like, shape (n, d)
        Initial positions (m) and velocities (m/s).
    rules : Boids
        The steering rules.
    min_speed, max_speed : float
        Speed limits, in m/s (boids at rest stay at rest).
    forces : sequence of Force
        Other forces, e.g. :class:`Containment` or wind.
    m : float or array_like, shape (n,)
        Masses, in kg.

    Attributes
    ----------
    system : ParticleSystem
        State and forces (``rules`` first).
    steps : int
        Steps taken since the flock was made.

    Examples
    --------
    The same flock, by its wrapper or by the system's loop with its stepper:

    >>> rng = np.random.default_rng(0)
    >>> x, v = rng.uniform(0, 5, (30, 2)), rng.normal(size=(30, 2))
    >>> a, b = (Flock(x, v, Boids(2.0), max_speed=1.0) for _ in range(2))
    >>> t, X = a.run(1.0, 0.05)
    >>> t, Y = b.system.run(1.0, 0.05, method=b.stepper)
    >>> bool(np.array_equal(X, Y))
    True
    """

    def __init__(self, x, v, rules, min_speed=0.0, max_speed=np.inf, forces=(), m=1.0):
        if not isinstance(rules, Boids):
            raise ValueError(f"rules must be a Boids object, got {type(rules).__name__}")
        self.rules = rules
        self.min_speed = nonnegative_number(min_speed, "min_speed", "m/s")
        self.max_speed = np.inf if max_speed == np.inf else positive_number(max_speed, "max_speed", "m/s")
        if self.max_speed < self.min_speed:
            raise ValueError(f"max_speed must be >= min_speed, got {max_speed!r} < {min_speed!r}")
        v = as_float_array(v, "v", ndim=2).copy()
        self._limit(v)
        self.system = ParticleSystem(x, v=v, m=m, forces=[rules, *forces])
        self.steps = 0

    @property
    def t(self):
        return self.system.t

    def _limit(self, v):
        """Clamp speeds into [min_speed, max_speed], in place."""
        speed = np.sqrt(np.einsum("ij,ij->i", v, v))
        target = np.clip(speed, self.min_speed, self.max_speed)
        scale = np.divide(target, speed, out=np.ones_like(speed), where=speed > 0)
        for k in range(v.shape[1]):  # a loop over the d coordinates
            v[:, k] *= scale

    def stepper(self, f, X, t, h):
        """One step of the flock: symplectic Euler with the speed clamped between the kick and the drift.

        ``v' = clamp(v + h a)``, ``x' = x + h v'`` with ``a = f(X, t)[:, 1]``.
        A stepper of the library's form (first order, the second-order
        layout), for :meth:`particles.ParticleSystem.run`.

        Parameters
        ----------
        f : callable
            ``f(X, t)`` of the second-order form ``(v, a)``: the system's derivative.
        X : ndarray, shape (n, 2, d)
            Positions (m) and velocities (m/s). Not modified.
        t, h : float
            Time and time step, in seconds.

        Returns
        -------
        ndarray, shape (n, 2, d)
        """
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # a blow-up is reported by the run
            X_new = np.empty_like(X)
            X_new[:, 1] = X[:, 1] + h * f(X, t)[:, 1]
            self._limit(X_new[:, 1])
            X_new[:, 0] = X[:, 0] + h * X_new[:, 1]
        return X_new

    stepper.order, stepper.explicit, stepper.second_order_layout = 1, True, True

    def _count_step(self, system, t0):
        self.steps += 1

    def _run(self, t_end, h, every):
        """:meth:`particles.ParticleSystem.run` with the flock's stepper, naming the cause of a blow-up."""
        try:
            return self.system.run(t_end, h, method=self.stepper, every=every, between_steps=self._count_step)
        except SimulationDiverged as error:
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                F = self.system.total_force(self.system.X, self.system.t)  # at the start of the failing step
            error.args = (f"{error} {self._blow_up_cause(F)}",)
            raise

    def step(self, h):
        """Advance by `h` seconds.

        Parameters
        ----------
        h : float
            Time step, in seconds, > 0.

        Returns
        -------
        ndarray, shape (n, 2, d)
            A copy of the new state: positions (m) and velocities (m/s).

        Raises
        ------
        SimulationDiverged
            When the new state is not finite (a steering force overflowed);
            the flock is then left as it was before the step.
        """
        t1 = self.t + positive_number(h, "h", "seconds")
        self._run(t1, t1 - self.t, 1)  # one step, landing on t + h
        return self.system.state()

    def _blow_up_cause(self, F):
        """The likely cause of a non-finite step, for the message of SimulationDiverged."""
        with np.errstate(invalid="ignore", over="ignore"):
            largest = np.max(np.abs(F), initial=0.0)
        reached = f"reached {largest:.3g} N" if np.isfinite(largest) else "overflowed"
        return (f"(In the flock: the steering forces {reached}. The likely cause is a rule weight too large "
                f"for boids this close: separation = {self.rules.separation:g} pushes with separation / "
                "distance, without bound when two boids nearly coincide; lower the weights, or set max_force.)")

    def run(self, t_end, h, every=1):
        """Simulate to `t_end`; returns times (K,) and states (K, n, 2, d) as :meth:`ParticleSystem.run`.

        Raises :class:`particles.SimulationDiverged` as :meth:`step` does
        (the flock then keeps the last finite state).
        """
        return self._run(end_time(t_end, self.t, "flock"), h, every)
