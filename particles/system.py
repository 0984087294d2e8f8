"""A particle system: masses, forces, pins, and the state that changes.

The slide's animation loop is the whole architecture::

    X = X0
    while t < t_end:
        F  = sum of force(X, t) over all forces      # ComputeForces
        dX = (v, F / m)                              # AssembleDerivative
        X, t = stepper(f, X, t, h)                   # ODESolverStep
        draw(X)

:class:`ParticleSystem` keeps what does not change (masses, forces, pinned
indices) apart from the state ``X`` of shape ``(n, 2, d)`` that does.

References
----------
.. [1] A. Witkin, "Particle System Dynamics", in *Physically Based Modeling:
   Principles and Practice*, SIGGRAPH 1997 course notes.
"""

import numpy as np

from ._checks import as_float_array, method_name, positive_number
from .integrators import INTEGRATORS, integrate

__all__ = ["ParticleSystem"]


class ParticleSystem:
    """`n` point masses in `d` dimensions moved by a sum of forces.

    Parameters
    ----------
    x : array_like, shape (n, d)
        Initial positions, in metres; ``d`` is 2 or 3.
    v : array_like, shape (n, d), optional
        Initial velocities, in m/s (default zero).
    m : float or array_like, shape (n,)
        Masses, in kg, all > 0. A number gives every particle that mass.
    forces : sequence of Force
        Force objects (see :mod:`particles.forces`); each adds its part into
        the total force array.
    pinned : array_like of int or bool, optional
        Indices (or a boolean mask of length n) of particles held in place:
        their net force is ignored and their derivative is zero. Their
        velocity must be zero.
    t : float
        Initial time, in seconds.

    Attributes
    ----------
    X : ndarray, shape (n, 2, d)
        Current state: ``X[:, 0]`` positions, ``X[:, 1]`` velocities.
    t : float
        Current time, in seconds.
    m : ndarray, shape (n,)
    forces : list
    pinned : ndarray of int, shape (p,)

    Notes
    -----
    The state is stored in Fortran (column-major) memory order: all
    x-coordinates, then all y-coordinates, ... NumPy runs its inner loops
    along the last axis in memory; with only 2 or 3 numbers per particle in
    that axis, C order would make every operation on ``x`` or ``v`` run a tiny
    loop per particle and be 5-30 times slower. Indexing and shapes are the
    same in either order; :meth:`state` returns an ordinary C-ordered copy.

    Examples
    --------
    >>> from particles.forces import Gravity
    >>> ps = ParticleSystem([[0.0, 10.0]], v=[[1.0, 0.0]], forces=[Gravity([0, -9.81])])
    >>> t, X = ps.run(1.0, h=0.01, method="rk4")
    >>> X[-1, 0, 0].round(6).tolist()             # x(1) = x0 + vx t, y(1) = 10 - g/2
    [1.0, 5.095]
    """

    def __init__(self, x, v=None, m=1.0, forces=(), pinned=(), t=0.0):
        x = as_float_array(x, "x", ndim=2)
        n, d = x.shape
        if d not in (2, 3):
            raise ValueError(f"x must have shape (n, 2) or (n, 3), got shape {x.shape}")
        v = np.zeros_like(x) if v is None else as_float_array(v, "v", shape=(n, d))
        m = as_float_array(m, "m", ndim=(0, 1))
        m = np.broadcast_to(m, (n,)).copy() if m.ndim == 0 else m
        if m.shape != (n,):
            raise ValueError(f"m must be a number or have shape ({n},), got shape {m.shape}")
        if np.any(m <= 0):
            raise ValueError("m must be positive: every mass must be > 0 kg")
        self.m = m
        self.forces = list(forces)
        for force in self.forces:
            if not callable(getattr(force, "add_to", None)):
                raise ValueError(
                    f"forces must be Force objects with an add_to(F, x, v, t, m) method, "
                    f"got {type(force).__name__}"
                )
        self.pinned = _pinned_indices(pinned, n)
        if np.any(v[self.pinned] != 0):
            raise ValueError("v of pinned particles must be zero: a pinned particle does not move")
        self.X = np.asfortranarray(np.stack([x, v], axis=1))
        self.t = float(t)

    @property
    def n(self):
        """Number of particles."""
        return self.X.shape[0]

    @property
    def d(self):
        """Dimension of space (2 or 3)."""
        return self.X.shape[2]

    def state(self):
        """A copy of the current state ``X``, shape (n, 2, d)."""
        return np.ascontiguousarray(self.X)

    def _check_state(self, X):
        X = np.asarray(X, dtype=float)
        if X.shape != self.X.shape:
            raise ValueError(f"X must have shape {self.X.shape}, got shape {X.shape}")
        return X

    def total_force(self, X, t):
        """Sum of all forces on every particle, pins included (ComputeForces).

        Parameters
        ----------
        X : ndarray, shape (n, 2, d)
        t : float

        Returns
        -------
        F : ndarray, shape (n, d), in newtons.
        """
        X = self._check_state(X)
        x, v = X[:, 0], X[:, 1]
        F = np.zeros_like(x)  # same memory order as the state (see Notes of the class)
        for force in self.forces:
            force.add_to(F, x, v, t, self.m)
        return F

    def derivative(self, X, t):
        """Right-hand side ``f(X, t) = (v, F / m)``, zero for pinned particles.

        Parameters
        ----------
        X : ndarray, shape (n, 2, d)
        t : float

        Returns
        -------
        dX : ndarray, shape (n, 2, d)
        """
        F = self.total_force(X, t)
        dX = np.empty_like(X)
        dX[:, 0] = X[:, 1]
        np.divide(F, self.m[:, None], out=dX[:, 1])
        if len(self.pinned):
            dX[self.pinned] = 0.0
        return dX

    def reaction_forces(self, X=None, t=None):
        """Force each pin exerts on its particle, by inverse dynamics.

        A pinned particle does not accelerate, so the pin's force balances the
        sum of all other forces on it: ``R = -sum(F)``.

        Parameters
        ----------
        X : ndarray, shape (n, 2, d), optional
            State (default: the current one).
        t : float, optional
            Time (default: the current one).

        Returns
        -------
        R : ndarray, shape (p, d)
            One row per pinned particle, in the order of :attr:`pinned`.
        """
        X = self.X if X is None else X
        t = self.t if t is None else t
        return -self.total_force(X, t)[self.pinned]

    def kinetic_energy(self, X=None):
        """Total kinetic energy ``sum(m v**2) / 2``, in joules."""
        X = self.X if X is None else self._check_state(X)
        return 0.5 * float(np.sum(self.m * np.sum(X[:, 1] ** 2, axis=1)))

    def momentum(self, X=None):
        """Total linear momentum ``sum(m v)``, shape (d,), in kg m/s."""
        X = self.X if X is None else self._check_state(X)
        return self.m @ X[:, 1]

    def potential_energy(self, X=None, t=None):
        """Sum of the potential energies of the conservative forces, in joules.

        Forces without a ``potential_energy`` method (damping, wind) are skipped.
        """
        X = self.X if X is None else self._check_state(X)
        t = self.t if t is None else t
        return float(
            sum(
                force.potential_energy(X[:, 0], self.m, t)
                for force in self.forces
                if hasattr(force, "potential_energy")
            )
        )

    def step(self, h, method="rk4", **options):
        """Advance the state by one step of `h` seconds; returns the new state."""
        step = method_name(method, INTEGRATORS)
        h = positive_number(h, "h", "seconds")
        _, X = integrate(self.derivative, self.X, self.t, self.t + h, h, method=step, **options)
        self.X, self.t = np.array(X[-1], order="F"), self.t + h
        return self.state()

    def run(self, t_end, h, method="rk4", every=1, **options):
        """Simulate from the current time to `t_end` and record the states.

        Parameters
        ----------
        t_end : float
            End time, in seconds, >= the current time :attr:`t`.
        h : float
            Time step, in seconds; the last step is shortened to land on `t_end`.
        method : str or callable
            A key of :data:`particles.integrators.INTEGRATORS` or a stepper.
        every : int
            Record every `every`-th step (first and last always recorded).
        **options
            Passed to the stepper.

        Returns
        -------
        t : ndarray, shape (K,)
        X : ndarray, shape (K, n, 2, d)

        Raises
        ------
        SimulationDiverged
            When the state becomes non-finite; the system is then left as it
            was before the call.
        """
        t, X = integrate(
            self.derivative, self.X, self.t, t_end, h, method=method, every=every, **options
        )
        self.X, self.t = np.array(X[-1], order="F"), float(t[-1])
        return t, X


def _pinned_indices(pinned, n):
    """Sorted unique indices from indices or a boolean mask, checked against n."""
    p = np.asarray(pinned)
    if p.dtype == bool:
        if p.shape != (n,):
            raise ValueError(f"pinned as a boolean mask must have shape ({n},), got {p.shape}")
        return np.flatnonzero(p)
    if p.size == 0:
        return np.zeros(0, dtype=int)
    if p.ndim != 1 or not np.issubdtype(p.dtype, np.integer):
        raise ValueError(f"pinned must be a list of particle indices or a boolean mask, got {pinned!r}")
    if np.any((p < -n) | (p >= n)):
        raise ValueError(f"pinned indices must lie in [0, {n}), got {p.tolist()}")
    p = np.unique(p % n)
    return p
