"""Resting contact: balls that stay at rest on a surface and on each other (a stack), without chatter.

A ball lying on a floor is in contact at every step: gravity moves it a
little into the floor, and the collision fix must push it back. Treated as a
*collision*, with the restitution ``eps`` of every contact, the fix reflects
the inward speed ``g h`` that one step of gravity gave it: the ball leaves
the floor at ``eps g h``, falls back, and is bounced again, a hop at every
step or few steps that never dies out (*chatter*). In a stack the hops of
the lower balls kick the ones above. Witkin and Baraff [1]_ separate the two
cases by the speed of approach: a contact closing faster than a threshold
``rest_speed`` is a collision and bounces; a slower one is a *resting
contact*, whose normal velocity is only cancelled. Guendelman, Bridson and
Fedkiw [2]_ process the contacts of a stack that way, iterating over them
so that each ball's impulse reaches the balls above and below.

:class:`BallContacts` treats the particles as balls of radius ``r``, against
one surface (a floor) and against each other, after each step:

1. **contacts**: balls within ``2 r + margin`` of each other (the bucket
   grid of :mod:`particles.neighbors`) and within ``r + margin`` of the
   surface (its ``H`` a signed distance, as for
   :class:`~particles.collisions.Plane`), each with its normal ``u``, its gap
   ``g`` (negative when the balls overlap) and its normal relative velocity
   ``v_n`` (negative when closing) at the end of the step;
2. **velocities**: the impulses act within the step, as in symplectic Euler:
   a velocity change ``dv`` moves the ball by ``h dv``, so a contact ends the
   step closed, not overlapping, when ``v_n' >= v_n - g / h``. A ball resting
   on the floor has fallen by ``g h^2`` at ``v_n = -g h``: its bound is
   ``v_n' >= 0``, rest. A touching contact that closes faster than
   ``rest_speed`` is a collision and must also bounce, ``v_n' >= -eps v_n``.
   `iterations` sweeps of sequential impulses (projected Gauss-Seidel over
   groups of contacts that share no ball) meet these bounds with impulses
   that only push (their sum per contact stays >= 0);
3. **positions**: each ball moves by ``h`` times its velocity change.

With ``rest_speed = 0`` every touching contact that closes at all bounces:
the naive fix, whose chatter lecture 3 measures; with a threshold of a few
``g h``, a resting ball stays exactly where it is. A stack needs the
impulses to travel through it: Gauss-Seidel sweeps converge like those of a
chain, in about ``k^2`` sweeps for a stack of ``k`` balls; physics engines
start each step from the last step's impulses (warm starting) or sweep the
stack from the bottom up (Guendelman et al.'s shock propagation) to need
fewer. The impulses of the surface, divided by the step, are the contact
force that carries the stack: its weight.

References
----------
.. [1] A. Witkin and D. Baraff, "Particle System Dynamics", in *Physically
   Based Modeling: Principles and Practice*, SIGGRAPH 1997 course notes,
   section 5 (collisions and contact: a contact whose normal speed is below a
   small threshold is a resting contact).
.. [2] E. Guendelman, R. Bridson and R. Fedkiw, "Nonconvex rigid bodies with
   stacking", ACM Transactions on Graphics 22(3) (SIGGRAPH 2003), 871-878
   (restitution only for the collisions, iterated contact processing).
"""

from dataclasses import dataclass

import numpy as np

from .._checks import (as_float_array, count, mass_array, nonnegative_number, pinned_indices, positive_number,
                       restitution_coefficient)
from ..constraints.colouring import color_constraints
from ..forces.pairs import pair_differences
from ..integrators.solvers import after
from ..neighbors import CellGrid
from .surfaces import Surface

__all__ = ["BallContacts", "ContactImpulses"]



@dataclass
class ContactImpulses:
    """What one :meth:`BallContacts.resolve` did.

    Attributes
    ----------
    pairs : int
        Ball-ball contacts.
    surface : ndarray of float, shape (n,)
        Normal impulse of the surface on each ball, in N s (0 without contact).
    bounces : int
        Contacts that closed faster than ``rest_speed`` (treated as collisions).
    """

    pairs: int
    surface: np.ndarray
    bounces: int


class BallContacts:
    """Balls of radius `radius` against a surface and each other, with restitution and resting contact.

    Parameters
    ----------
    radius : float
        Radius ``r`` of every ball, in metres (> 0).
    m : float or array_like, shape (n,)
        Masses, in kg (> 0).
    surface : Surface, optional
        A solid whose ``H`` is a signed distance (a :class:`~particles.collisions.Plane`).
    restitution : float
        ``eps`` in [0, 1] of the collisions (of balls and surface alike).
    rest_speed : float
        Closing speed (m/s, >= 0) up to which a touching contact is resting:
        it is only closed, not reflected. 0: every closing contact bounces
        (the naive fix).
    iterations : int
        Sweeps over the contacts per step (>= 1).
    margin : float, optional
        Gap (m) within which a pair counts as a contact (default ``r / 2``):
        it then gets an impulse only if it would otherwise overlap at the end
        of the step (a ball pushed up by the one below pushes the one above).
    pinned : array_like of int or bool
        Balls that never move (infinite mass).

    Attributes
    ----------
    history : list of ContactImpulses
        One entry per step taken through :meth:`stepper`.

    Examples
    --------
    A ball of 1 kg resting on a floor, after a step of 10 ms under gravity: it
    sank by ``g h^2`` and moves down at ``g h``. A resting contact brings it
    back to where it was, at rest; the floor's impulse ``m g h`` is its weight
    times the step.

    >>> from particles.collisions import Plane
    >>> balls = BallContacts(0.05, 1.0, Plane([0.0, 0.0], [0.0, 1.0]), restitution=0.5, rest_speed=0.2)
    >>> x, v, done = balls.resolve([[0.0, 0.05 - 9.81e-4]], [[0.0, -0.0981]], h=0.01)
    >>> x.round(12).tolist(), v.round(12).tolist(), round(float(done.surface[0]), 12)
    ([[0.0, 0.05]], [[0.0, 0.0]], 0.0981)
    """

    def __init__(self, radius, m, surface=None, restitution=0.0, rest_speed=0.0, iterations=1, margin=None,
                 pinned=()):
        self.radius = positive_number(radius, "radius", "metres")
        self._m = as_float_array(m, "m", ndim=(0, 1))
        if surface is not None and not isinstance(surface, Surface):
            raise ValueError(f"surface must be a particles.collisions surface (a Plane), got {type(surface).__name__}")
        self.surface = surface
        self.restitution = restitution_coefficient(restitution)
        self.rest_speed = nonnegative_number(rest_speed, "rest_speed", "m/s")
        self.iterations = count(iterations, "iterations", 1)
        self.margin = 0.5 * self.radius if margin is None else nonnegative_number(margin, "margin", "metres")
        self._pinned = pinned
        self.history = []

    def _weights(self, n):
        """Inverse masses (0 for pinned balls), shape (n,)."""
        w = 1.0 / np.array(mass_array(self._m, n))
        w[pinned_indices(self._pinned, n)] = 0.0
        return w

    def contacts(self, x):
        """Ball-ball pairs within ``2 r + margin`` and balls within ``r + margin`` of the surface.

        Parameters
        ----------
        x : array_like, shape (n, d)
            Positions, in metres.

        Returns
        -------
        i, j : ndarray of int, shape (p,)
            Each pair once.
        k : ndarray of int, shape (q,)
            The balls near the surface.
        """
        x = as_float_array(x, "x", ndim=2)
        return self._contacts(x, self._weights(len(x)))

    def _contacts(self, x, w):
        reach = 2.0 * self.radius + self.margin
        i, j = CellGrid(x, reach).pairs() if len(x) > 1 else (np.zeros(0, int), np.zeros(0, int))
        movable = w[i] + w[j] > 0
        i, j = i[movable], j[movable]
        k = np.zeros(0, dtype=int)
        if self.surface is not None:
            k = np.flatnonzero((self.surface.H(x) < self.radius + self.margin) & (w > 0))
        return i, j, k

    def resolve(self, x, v, h):
        """The contact fix of one step of length `h`.

        Parameters
        ----------
        x, v : array_like, shape (n, d)
            Positions (m) and velocities (m/s) at the end of a step (not modified).
        h : float
            The step, in seconds.

        Returns
        -------
        x, v : ndarray, shape (n, d)
            Corrected copies: ``v`` meets every contact's bound, ``x`` moved by
            ``h`` times the velocity change.
        ContactImpulses
            The contacts and the surface's impulses.
        """
        x = np.array(as_float_array(x, "x", ndim=2), order="F")
        v = np.array(as_float_array(v, "v", shape=x.shape), order="F")
        return self._resolve(x, v, positive_number(h, "h", "seconds"))

    def _resolve(self, x, v, h):
        w = self._weights(len(x))
        i, j, k = self._contacts(x, w)
        d = pair_differences(x, i, j)                           # (dim, p), from j to i
        dist = np.sqrt(np.einsum("ap,ap->p", d, d))
        u = d / np.maximum(dist, 1e-300)
        nk = self.surface.normal(x[k]) if len(k) else np.zeros((0, x.shape[1]))
        gap_k = self.surface.H(x[k]) - self.radius if len(k) else np.zeros(0)
        bound_pairs, bounce_pairs = self._bounds(np.einsum("ap,ap->p", pair_differences(v, i, j), u),
                                                 dist - 2.0 * self.radius, h)
        bound_k, bounce_k = self._bounds(np.einsum("kd,kd->k", v[k], nk), gap_k, h)
        lam_pairs, lam_k = np.zeros(len(i)), np.zeros(len(k))  # the impulses of each contact, N s
        v_step = v.copy()
        groups = color_constraints(np.stack([i, j], axis=1), len(x)) if len(i) else []
        for _ in range(self.iterations):  # a loop over sweeps (projected Gauss-Seidel)
            vn = np.einsum("kd,kd->k", v[k], nk)              # the surface contacts: one ball each
            new = np.maximum(lam_k + (bound_k - vn) / np.maximum(w[k], 1e-300), 0.0)
            v[k] += (w[k] * (new - lam_k))[:, None] * nk
            lam_k = new
            for g in groups:  # one colour at a time: the pairs of a group share no ball
                a, b = i[g], j[g]
                vn = np.einsum("ap,ap->p", pair_differences(v, a, b), u[:, g])
                new = np.maximum(lam_pairs[g] + (bound_pairs[g] - vn) / (w[a] + w[b]), 0.0)
                change = new - lam_pairs[g]
                for c in range(x.shape[1]):  # per coordinate
                    v[a, c] += w[a] * change * u[c, g]
                    v[b, c] -= w[b] * change * u[c, g]
                lam_pairs[g] = new
        x += h * (v - v_step)                                   # the impulses act within the step
        surface = np.zeros(len(x))
        surface[k] = lam_k
        return x, v, ContactImpulses(int(np.sum(dist < 2.0 * self.radius)), surface,
                                     int(bounce_pairs.sum() + bounce_k.sum()))

    def _bounds(self, vn, gap, h):
        """Lower bounds of the contacts' normal velocities, and which contacts are collisions (bounce)."""
        bounce = (gap <= 0.0) & (-vn > self.rest_speed)
        bound = vn - gap / h                                    # ends the step closed, not overlapping
        return np.where(bounce, np.maximum(bound, -self.restitution * vn), bound), bounce

    def stepper(self, step):
        """Wrap a stepper so that every step ends with the contact fix (see :func:`particles.integrators.after`).

        Parameters
        ----------
        step : str, callable or solver
            A stepper ``step(f, X, t, h)`` or a name of :data:`particles.integrators.INTEGRATORS`;
            the fix is exact for a step that ends with ``x += h v`` (symplectic Euler).

        Returns
        -------
        callable
            A stepper; each step appends a :class:`ContactImpulses` to :attr:`history`.
        """

        def fix(X_old, X_new, t, h):
            x, v, done = self._resolve(np.array(X_new[:, 0], order="F"), np.array(X_new[:, 1], order="F"), h)
            self.history.append(done)
            X_new[:, 0], X_new[:, 1] = x, v
            return X_new

        return after(step, fix, "ball_contacts")
