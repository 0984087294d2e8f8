"""Rigid constraints the classical way: Lagrange multipliers (Witkin's constrained dynamics).

A rigid rod of length ``L`` between particles ``i`` and ``j`` is the
constraint ``C = (|x_i - x_j|^2 - L^2) / 2 = 0``. Keeping it means keeping
``C`` and its rate ``dC/dt = J v`` at zero, hence ``d^2C/dt^2 = 0``: with the
constraint Jacobian ``J = dC/dx`` (one row per rod: ``d^T`` at ``i``,
``-d^T`` at ``j``, ``d = x_i - x_j``), the inverse masses ``W = M^-1`` and the
applied forces ``F``, the constraint force ``J^T lambda`` must satisfy

    J W J^T lambda = -dJ/dt v - J W F - ks C - kd dC/dt,

with ``dJ/dt v = |v_i - v_j|^2`` per rod. The feedback terms ``ks C + kd dC/dt``
(Baumgarte stabilization) pull back the drift that integration errors
cause; alternatively, :meth:`RigidRods.stepper` projects the positions and
velocities back onto the constraint after every step. The multipliers solve
one linear system of the size of the number of rods per force evaluation,
so this is for small systems (a pendulum, a chain); for large ones see
:mod:`particles.xpbd`.

:class:`RigidRods` is a force of a :class:`particles.ParticleSystem`: it
reads the sum of the forces listed before it, so it must come **last**.

References
----------
.. [1] A. Witkin, "Constrained dynamics", in A. Witkin and D. Baraff,
   "Physically Based Modeling: Principles and Practice", SIGGRAPH 1997 course
   notes (and "Particle System Dynamics", same notes).
.. [2] J. Baumgarte, "Stabilization of constraints and integrals of motion in
   dynamical systems", Computer Methods in Applied Mechanics and Engineering
   1(1), 1972, 1-16.
"""

import numpy as np

from .._checks import as_float_array, count, index_array, nonnegative_number, per_item, positive_number
from ..errors import ConvergenceError
from ..forces import Force, Gravity
from ..integrators.solvers import after
from ..system import ParticleSystem

__all__ = ["RigidRods", "pendulum", "chain", "pendulum_period", "crossing_period"]

DENSE_LIMIT = 200
"""Up to this many rods the multipliers are solved with a dense matrix (faster for small systems)."""


class RigidRods(Force):
    """Rigid distance constraints held by Lagrange multipliers, a force to put last in a system's list.

    Parameters
    ----------
    indices : array_like of int, shape (s, 2)
        The two particles of each rod.
    length : float or array_like, shape (s,), optional
        Rod lengths ``L`` in metres (default: the distances in `x`).
    pinned : array_like of int
        The system's pinned particles (they do not move: inverse mass 0).
    x : array_like, shape (n, d), optional
        Positions that give the lengths.
    ks, kd : float
        Baumgarte feedback, in 1/s^2 and 1/s (>= 0; 0: none).

    Attributes
    ----------
    lam : ndarray, shape (s,)
        The multipliers of the last evaluation; the force on ``i`` is
        ``lam d`` (N), ``lam`` in N/m.

    Notes
    -----
    The constraint force does no work on the exact motion (it is
    perpendicular to every velocity the rods allow), so the energy of a
    pendulum is conserved up to the integrator's error and the drift.

    Examples
    --------
    A bob at rest hanging below its pivot: the rod carries its weight.

    >>> import numpy as np
    >>> rods = RigidRods([[0, 1]], 1.0, pinned=[0])
    >>> F = np.array([[0.0, 0.0], [0.0, -9.81]])
    >>> rods.add_to(F, np.array([[0.0, 0.0], [0.0, -1.0]]), np.zeros((2, 2)), 0.0, np.ones(2))
    >>> F.round(12).tolist()
    [[0.0, -9.81], [0.0, 0.0]]
    """

    uses_velocity = True
    uses_time = False

    def __init__(self, indices, length=None, pinned=(), x=None, ks=0.0, kd=0.0):
        ij = index_array(indices, "indices", 2)
        if np.any(ij[:, 0] == ij[:, 1]):
            raise ValueError("indices must join two different particles in every rod")
        self.i, self.j = ij[:, 0].copy(), ij[:, 1].copy()
        if length is None:
            if x is None:
                raise ValueError("give length, or positions x from which to take the rod lengths")
            x = as_float_array(x, "x", ndim=2)
            if ij.max(initial=-1) >= len(x):
                raise ValueError(f"indices refer to particle {ij.max()} but x has only {len(x)} particles")
            length = np.linalg.norm(x[self.i] - x[self.j], axis=1)
        self.length = per_item(length, "length", len(ij), positive=True)
        self.pinned = np.unique(np.asarray(pinned, dtype=np.int64).ravel())
        both = np.isin(self.i, self.pinned) & np.isin(self.j, self.pinned)
        if np.any(both):
            raise ValueError(f"rod {int(np.argmax(both))} joins two pinned particles: it can hold nothing")
        self.ks = nonnegative_number(ks, "ks", "1/s^2")
        self.kd = nonnegative_number(kd, "kd", "1/s")
        self.lam = np.zeros(len(ij))

    def __len__(self):
        return len(self.i)

    def values(self, x):
        """Length errors ``|x_i - x_j| - L`` of every rod, shape (s,), in metres."""
        x = np.asarray(x, dtype=float)
        return np.linalg.norm(x[self.i] - x[self.j], axis=1) - self.length

    def _inverse_masses(self, m, n):
        w = 1.0 / np.broadcast_to(np.asarray(m, dtype=float), (n,))
        w = w.copy()
        w[self.pinned[self.pinned < n]] = 0.0
        return w

    def _solve(self, d, w, rhs):
        """Solve (J W J^T) mu = rhs for rods of directions d (s, dim), inverse masses w."""
        import scipy.sparse.linalg
        i, j, s = self.i, self.j, len(self.i)
        # (J W J^T)_kl = sum over shared particles p of w_p (+-d_k).(+-d_l)
        if s <= DENSE_LIMIT:
            n = len(w)
            J = np.zeros((s, n, d.shape[1]))
            J[np.arange(s), i] = d
            J[np.arange(s), j] = -d
            A = np.einsum("kpa,p,lpa->kl", J, w, J)
            try:
                return np.linalg.solve(A, rhs)
            except np.linalg.LinAlgError:  # redundant rods (a closed loop): the least-squares multipliers
                return np.linalg.lstsq(A, rhs, rcond=None)[0]
        J = self._jacobian(d, len(w))
        A = (J @ scipy.sparse.diags(np.repeat(w, d.shape[1])) @ J.T).tocsc()
        return scipy.sparse.linalg.spsolve(A, rhs)

    def _jacobian(self, d, n):
        """J as a sparse (s, n dim) matrix, particle-major columns."""
        import scipy.sparse
        s, dim = d.shape
        rows = np.repeat(np.arange(s), 2 * dim)
        cols = np.concatenate([self.i[:, None] * dim + np.arange(dim), self.j[:, None] * dim + np.arange(dim)],
                              axis=1).ravel()
        vals = np.concatenate([d, -d], axis=1).ravel()
        return scipy.sparse.csr_matrix((vals, (rows, cols)), shape=(s, n * dim))

    def add_to(self, F, x, v, t, m):
        n = len(x)
        w = self._inverse_masses(m, n)
        d = x[self.i] - x[self.j]                      # (s, dim)
        dv = v[self.i] - v[self.j]
        C = 0.5 * (np.einsum("sa,sa->s", d, d) - self.length**2)
        C_dot = np.einsum("sa,sa->s", d, dv)
        a = F * w[:, None]                             # W F
        JWF = np.einsum("sa,sa->s", d, a[self.i] - a[self.j])
        rhs = -np.einsum("sa,sa->s", dv, dv) - JWF - self.ks * C - self.kd * C_dot
        self.lam = self._solve(d, w, rhs)
        f = self.lam[:, None] * d                      # J^T lambda: +lam d on i, -lam d on j
        for a_ in range(x.shape[1]):  # a loop over the d coordinates
            F[:, a_] += np.bincount(self.i, f[:, a_], minlength=n) - np.bincount(self.j, f[:, a_], minlength=n)

    def project(self, x, v, m, tol=1e-13, max_iterations=20):
        """Positions and velocities moved back onto the rods, with the least mass-weighted change.

        Newton iterations ``x += W J^T mu`` with ``(J W J^T) mu = -C`` until every
        ``|C| <= tol L^2``, then ``v += W J^T nu`` with ``(J W J^T) nu = -J v``.

        Parameters
        ----------
        x, v : array_like, shape (n, d)
            Positions (m) and velocities (m/s). Not modified.
        m : float or array_like, shape (n,)
            Masses, in kg.
        tol : float
            Relative tolerance on ``C``.
        max_iterations : int
            Largest number of Newton iterations.

        Returns
        -------
        x, v : ndarray, shape (n, d)

        Raises
        ------
        particles.ConvergenceError
            When the positions cannot be projected within `max_iterations`.
        """
        x = np.array(as_float_array(x, "x", ndim=2))
        v = np.array(as_float_array(v, "v", shape=x.shape))
        n = len(x)
        w = self._inverse_masses(m, n)
        for _ in range(count(max_iterations, "max_iterations", 1)):  # a loop over Newton iterations
            d = x[self.i] - x[self.j]
            C = 0.5 * (np.einsum("sa,sa->s", d, d) - self.length**2)
            if np.all(np.abs(C) <= tol * self.length**2):
                break
            self._move(x, d, w, self._solve(d, w, -C))
        else:
            raise ConvergenceError(f"RigidRods.project: the rods still differ from their lengths by up to "
                                   f"{np.abs(self.values(x)).max():.3g} m after {max_iterations} iterations")
        d = x[self.i] - x[self.j]
        self._move(v, d, w, self._solve(d, w, -np.einsum("sa,sa->s", d, v[self.i] - v[self.j])))
        return x, v

    def _move(self, y, d, w, mu):
        """y += W J^T mu, in place."""
        f = mu[:, None] * d
        n = len(y)
        for a in range(y.shape[1]):  # a loop over the d coordinates
            y[:, a] += w * (np.bincount(self.i, f[:, a], minlength=n) - np.bincount(self.j, f[:, a], minlength=n))

    def stepper(self, step, m):
        """Wrap a stepper so that every step ends with :meth:`project`.

        Parameters
        ----------
        step : callable or str
            A stepper ``step(f, X, t, h)`` or a name of :data:`particles.integrators.INTEGRATORS`.
        m : float or array_like, shape (n,)
            Masses, in kg.

        Returns
        -------
        callable
            A stepper with the order and layout attributes of `step`
            (:func:`particles.integrators.solvers.after`).
        """

        def fix(X_old, X_new, t, h):
            x, v = self.project(X_new[:, 0], X_new[:, 1], m)
            X_new[:, 0], X_new[:, 1] = x, v
            return X_new

        return after(step, fix, "projected")


def pendulum(theta0, length=1.0, m=1.0, g=9.81, ks=0.0, kd=0.0):
    """A simple pendulum in 2D: a pinned pivot at the origin, a bob on a rigid rod, at rest at `theta0`.

    Parameters
    ----------
    theta0 : float
        Initial angle from the downward vertical, in radians (|theta0| < pi).
    length : float
        Rod length, in metres.
    m : float
        Mass of the bob, in kg.
    g : float
        Gravity, in m/s^2.
    ks, kd : float
        Baumgarte feedback (see :class:`RigidRods`).

    Returns
    -------
    ParticleSystem
        Two particles (0: the pivot, pinned; 1: the bob), forces
        ``[Gravity, RigidRods]``.
    """
    return chain(1, length, theta0=theta0, m=m, g=g, ks=ks, kd=kd)


def chain(n, length=1.0, *, theta0=np.pi / 2, m=1.0, g=9.81, ks=0.0, kd=0.0):
    """A chain of `n` rigid links hanging from a pinned pivot, straight at `theta0` and at rest.

    Parameters
    ----------
    n : int
        Number of links (and bobs), >= 1.
    length : float
        Length of the whole chain, in metres (each link ``length / n``).
    theta0 : float
        Initial angle from the downward vertical, in radians (default:
        horizontal).
    m : float
        Mass of each bob, in kg (the pivot's does not matter).
    g : float
        Gravity, in m/s^2, along -y.
    ks, kd : float
        Baumgarte feedback (see :class:`RigidRods`).

    Returns
    -------
    ParticleSystem
        ``n + 1`` particles in 2D, particle 0 the pinned pivot at the origin.
    """
    n = count(n, "n", 1)
    length = positive_number(length, "length", "metres")
    theta0 = float(theta0)
    if not abs(theta0) < np.pi:
        raise ValueError(f"theta0 must lie in (-pi, pi) radians, got {theta0!r}")
    m = positive_number(m, "m", "kg")
    g = nonnegative_number(g, "g", "m/s^2")
    s = np.linspace(0.0, length, n + 1)[:, None]
    x = s * np.array([np.sin(theta0), -np.cos(theta0)])
    k = np.arange(n)
    rods = RigidRods(np.stack([k, k + 1], axis=1), length / n, pinned=[0], ks=ks, kd=kd)
    return ParticleSystem(x, m=m, forces=[Gravity([0.0, -g]), rods], pinned=[0])


def pendulum_period(theta0, length=1.0, g=9.81):
    """Exact period of a simple pendulum of amplitude `theta0`: ``T = 4 sqrt(L / g) K(sin^2(theta0 / 2))``.

    ``K(m)`` is the complete elliptic integral of the first kind with parameter
    ``m = k^2`` (:func:`scipy.special.ellipk`); for small amplitudes
    ``T -> 2 pi sqrt(L / g)``.

    Parameters
    ----------
    theta0 : float
        Amplitude, in radians, ``0 <= |theta0| < pi``.
    length : float
        In metres.
    g : float
        In m/s^2.

    Returns
    -------
    float
        The period, in seconds.

    Examples
    --------
    >>> round(float(pendulum_period(1e-6) / (2 * np.pi / np.sqrt(9.81))), 9)
    1.0
    >>> round(pendulum_period(np.radians(120.0)) / pendulum_period(1e-6), 4)
    1.3729
    """
    import scipy.special
    theta0 = float(theta0)
    if not abs(theta0) < np.pi:
        raise ValueError(f"theta0 must lie in (-pi, pi) radians, got {theta0!r}")
    length = positive_number(length, "length", "metres")
    g = positive_number(g, "g", "m/s^2")
    return float(4.0 * np.sqrt(length / g) * scipy.special.ellipk(np.sin(theta0 / 2.0) ** 2))


def crossing_period(t, y):
    """Period of an oscillation from the times where `y` crosses zero (linear interpolation).

    Parameters
    ----------
    t : array_like, shape (K,)
        Increasing times, in seconds.
    y : array_like, shape (K,)
        An oscillating quantity (e.g. the bob's horizontal position).

    Returns
    -------
    float
        Twice the mean time between successive zero crossings, in seconds.

    Raises
    ------
    ValueError
        When `y` crosses zero fewer than twice.
    """
    t = as_float_array(t, "t", ndim=1)
    y = as_float_array(y, "y", shape=t.shape)
    k = np.flatnonzero(np.signbit(y[:-1]) != np.signbit(y[1:]))
    if len(k) < 2:
        raise ValueError(f"y must cross zero at least twice to give a period, it crosses {len(k)} times")
    tc = t[k] - y[k] * (t[k + 1] - t[k]) / (y[k + 1] - y[k])
    return float(2.0 * (tc[-1] - tc[0]) / (len(tc) - 1))
