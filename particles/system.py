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

from ._checks import as_float_array, end_time, finite_real, pinned_indices, positive_number
from .integrators.loop import BLOWUP_FACTOR, integrate
from .integrators.solvers import as_stepper
from .population import Population

__all__ = ["ParticleSystem"]


class ParticleSystem(Population):
    """`n` point masses in `d` dimensions moved by a sum of forces.

    Parameters
    ----------
    x : array_like, shape (n, d)
        Initial positions, in metres; ``d`` is 2 or 3.
    v : array_like, shape (n, d), optional
        Initial velocities, in m/s (default zero).
    m : float or array_like, shape (n,)
        Masses, in kg, all > 0. A number gives every particle that mass.
    forces : sequence of Force, or one Force
        Force objects (see :mod:`particles.forces`); each adds its part into
        the total force array. A single force may be given without a list.
    pinned : array_like of int or bool, optional
        Indices (or a boolean mask of length n) of particles held in place:
        their net force is ignored and their derivative is zero. Their
        velocity must be zero.
    t : float
        Initial time, in seconds, finite.

    Attributes
    ----------
    X : ndarray, shape (n, 2, d)
        Current state: ``X[:, 0]`` positions, ``X[:, 1]`` velocities.
    t : float
        Current time, in seconds.
    m : ndarray, shape (n,)
    forces : list
    pinned : ndarray of int, shape (p,)
    attributes : dict of str to ndarray
        Per-particle data beyond the state (birth time, lifetime, colour...),
        each array of leading length ``n``; kept aligned with the particles by
        :meth:`add_particles` and :meth:`remove_particles`. Create one with
        :meth:`define_attribute`.

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
        self.forces = _force_list(forces)
        for force in self.forces:
            if not callable(getattr(force, "add_to", None)):
                raise ValueError(
                    f"forces must be Force objects with an add_to(F, x, v, t, m) method, "
                    f"got {type(force).__name__}"
                )
        self.pinned = pinned_indices(pinned, n)
        if np.any(v[self.pinned] != 0):
            raise ValueError("v of pinned particles must be zero: a pinned particle does not move")
        self.X = np.asfortranarray(np.stack([x, v], axis=1))
        self.t = finite_real(t, "t", "seconds")
        self.attributes = {}
        self._fill = {}
        self._changes = 0  # particles added or removed so far (a force reused by a run must be for the same ones)

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
        """Total kinetic energy ``sum(m v**2) / 2``, in joules.

        Parameters
        ----------
        X : ndarray, shape (n, 2, d), optional
            State: positions (m) and velocities (m/s); default the current one.

        Returns
        -------
        float
            Kinetic energy, in joules. Pinned particles have zero velocity and
            add nothing.
        """
        X = self.X if X is None else self._check_state(X)
        return 0.5 * float(np.sum(self.m * np.sum(X[:, 1] ** 2, axis=1)))

    def momentum(self, X=None):
        """Total linear momentum ``sum(m v)``.

        Parameters
        ----------
        X : ndarray, shape (n, 2, d), optional
            State: positions (m) and velocities (m/s); default the current one.

        Returns
        -------
        ndarray, shape (d,)
            Momentum, in kg m/s. Internal pair forces conserve it; gravity,
            damping and pins change it.
        """
        X = self.X if X is None else self._check_state(X)
        return self.m @ X[:, 1]

    def potential_energy(self, X=None, t=None):
        """Sum of the potential energies of the conservative forces, in joules.

        Forces without a ``potential_energy`` method (damping, wind) are skipped.

        Parameters
        ----------
        X : ndarray, shape (n, 2, d), optional
            State (only the positions ``X[:, 0]``, in metres, matter); default
            the current one.
        t : float, optional
            Time, in seconds, for time-dependent fields (default: the current one).

        Returns
        -------
        float
            Potential energy, in joules, relative to each force's own zero
            (e.g. ``y = 0`` for gravity, infinite separation for N-body gravity).
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

    def _rhs(self, step):
        """``f(X, t)`` for `step`: the derivative, with a force cache when the step can reuse forces.

        A stepper marked ``fsal`` (velocity Verlet, the Langevin and
        thermostat steppers) evaluates its last force at the positions the
        next step starts from. When no force depends on the velocities
        (each says so with ``uses_velocity = False``), that force is the
        next step's first one: :class:`_ReusedForces` returns it again.
        """
        if getattr(step, "fsal", False) and not any(getattr(f, "uses_velocity", True) for f in self.forces):
            return _ReusedForces(self)
        return self.derivative

    def stepper(self, method):
        """The stepper a run of this system takes its steps with, for `method`.

        Parameters
        ----------
        method : str, callable or solver
            A key of :data:`particles.integrators.INTEGRATORS`, a stepper
            ``step(f, X, t, h)`` (possibly wrapped by fixes) or a solver object
            with ``step(X, t, h)`` built for this system.

        Returns
        -------
        callable
            ``step(f, X, t, h)`` (:func:`particles.integrators.as_stepper`). A
            system may choose its own form of a method here, once per run
            (:meth:`particles.massspring.MassSpringSystem.stepper`: symplectic
            Euler as one compiled pass).

        Raises
        ------
        ValueError
            For an unknown name, or a solver built for another system.
        """
        step = as_stepper(method)
        solver = getattr(step, "solver", None)
        built_for = getattr(solver, "system", self)
        if built_for is not self:
            raise ValueError(
                f"method is a {type(solver).__name__} built for another system (it solves that system's "
                "springs, masses and pins); build one for this system")
        return step

    def step(self, h, method="rk4", blowup=BLOWUP_FACTOR, **options):
        """Advance the state by one step of `h` seconds: :meth:`run` to ``t + h``.

        Parameters
        ----------
        h : float
            Time step, in seconds, > 0.
        method : str, callable or solver
            A key of :data:`particles.integrators.INTEGRATORS`, a stepper
            ``step(f, X, t, h)`` or a solver object with ``step(X, t, h)``
            (see :meth:`run`).
        blowup : float or None
            Growth rule of the divergence guard, as in :meth:`run`.
        **options
            Passed to the stepper.

        Returns
        -------
        ndarray, shape (n, 2, d)
            A copy of the new state: positions (m) and velocities (m/s). The
            system's :attr:`X` and :attr:`t` (now ``t + h``) are updated.

        Raises
        ------
        SimulationDiverged
            As :meth:`run`; the system is then left as it was.
        """
        t1 = self.t + positive_number(h, "h", "seconds")
        self.run(t1, t1 - self.t, method=method, blowup=blowup, **options)  # one step, landing on t + h
        return self.state()

    def run(self, t_end, h, method="rk4", every=1, blowup=BLOWUP_FACTOR, between_steps=(), record=None,
            **options):
        """Simulate from the current time to `t_end` and record the states: the slide's loop.

        This is the library's one time loop. Collisions, constraints and
        solvers come in through `method` (a stepper, possibly wrapped, see
        :mod:`particles.integrators.solvers`); flocks, effects and anything else that
        acts between two steps come in through `between_steps`. The steps,
        `every` and the divergence guard are those of
        :func:`particles.integrators.integrate`.

        Parameters
        ----------
        t_end : float
            End time, in seconds, >= the current time :attr:`t`.
        h : float
            Time step, in seconds; the last step is shortened to land on `t_end`.
        method : str, callable or solver
            A key of :data:`particles.integrators.INTEGRATORS`, a stepper
            ``step(f, X, t, h)`` (called with ``f = derivative``), or a
            solver object with ``step(X, t, h)`` and ``order``
            (:class:`particles.implicit.BaraffWitkin`,
            :class:`particles.implicit.Prefactored`), built for this system;
            the run takes its steps with :meth:`stepper` of it.
        every : int
            Record every `every`-th step (first and last always recorded).
        blowup : float or None
            Growth rule of the divergence guard: the run stops when the largest
            entry of the state exceeds ``blowup * (1 + max|X|)`` of the start
            state, which catches an instability long before it overflows.
            Default :data:`particles.integrators.BLOWUP_FACTOR` (``1e12``):
            no particle motion worth animating grows that much. ``None``: stop
            only on inf or NaN.
        between_steps : callable or sequence of callables
            Hooks ``hook(system, t0)``, called in order after every step that
            passed the divergence guard, with this system at the step's end
            (``system.t``; ``t0`` is the step's start). A hook may read the
            state, add or remove particles (:meth:`add_particles`,
            :meth:`remove_particles`: births and deaths of an effect) or
            replace the state (:meth:`set_state`); the next step starts from
            the system as the hooks leave it. Never assign ``system.X``. (The
            compiled step's states stay in its C-ordered rows between steps,
            :mod:`particles.massspring.compiled_step`; the run ends in Fortran order.)
        record : callable, optional
            ``record(system) -> frame``, called at every recorded time
            instead of copying the state; the run then returns the frames in
            a list (needed when hooks change the number of particles).
        **options
            Passed to the stepper.

        Returns
        -------
        t : ndarray, shape (K,)
            Recorded times, in seconds, from the current time to `t_end`.
        X : ndarray, shape (K, n, 2, d), or list
            States at those times: positions (m) and velocities (m/s); with
            `record`, the list of its frames.

        Raises
        ------
        SimulationDiverged
            When the state becomes inf or NaN, or grows beyond the `blowup`
            rule; the message says which, at which step and time. Without
            hooks and `record`, the system is then left as it was before
            the call. With them it is updated after every step (the hooks
            see it, and births cannot be undone), and keeps the state at the
            start of the failing step.
        ValueError
            When ``t_end`` is not a finite number at least the current time,
            when a solver was built for another system, or when a hook changes
            the number of particles and `record` is not given.

        Notes
        -----
        With a stepper that ends where the next step starts (``fsal``:
        ``"verlet"``, :class:`particles.md.thermostats.Langevin`, a
        :class:`particles.md.thermostats.Berendsen` around Verlet) and forces
        that all depend on the positions only (``uses_velocity = False``:
        gravity, fields, N-body, Lennard-Jones), the force at the end of a
        step is reused at the start of the next one: a run of ``N`` steps
        evaluates the forces ``N + 1`` times instead of ``2 N``, with the
        same trajectory to the last bit. The reuse is checked on the values
        (the positions, the time if a force depends on it, and whether
        particles were added or removed), so it can never return a force for
        another state.

        Examples
        --------
        A hook that removes the particles that fall below the ground:

        >>> from particles.forces import Gravity
        >>> ps = ParticleSystem([[0.0, 1.0], [1.0, 3.0]], forces=[Gravity([0.0, -9.81])])
        >>> def below_ground(system, t0):
        ...     system.remove_particles(system.X[:, 0, 1] < 0.0)
        >>> t, n = ps.run(0.7, 0.01, between_steps=below_ground, record=lambda system: system.n)
        >>> n[0], n[-1]
        (2, 1)
        """
        t_end = end_time(t_end, self.t)
        step = self.stepper(method)
        hooks = _hook_list(between_steps)
        rhs = self._rhs(step)
        if not hooks and record is None:
            t, X = integrate(rhs, self.X, self.t, t_end, h, method=step, every=every, blowup=blowup, **options)
            self.X, self.t = np.array(X[-1], order="F"), float(t[-1])
            return t, X

        def after_step(X, t0, t1):
            # the hooks see the system at the step's end; the compiled step's C-ordered rows are kept as they
            # are between steps (its next step reads them in place), any other state in Fortran order
            self.X = X if X.flags.c_contiguous and X.dtype == np.float64 else np.asfortranarray(X)
            self.t = float(t1)
            for hook in hooks:  # a loop over the few hooks
                hook(self, t0)
            return self.X

        frame = None if record is None else (lambda X, t: record(self))
        t, X = integrate(rhs, self.X, self.t, t_end, h, method=step, every=every, blowup=blowup,
                         after_step=after_step, record=frame, **options)
        self.X = np.asfortranarray(self.X)  # the run's end state in Fortran order (see the class Notes)
        return t, X

    def set_state(self, X=None, t=None):
        """Replace the state and/or the time of the same particles (for hooks and solvers outside the loop).

        Parameters
        ----------
        X : array_like, shape (n, 2, d), optional
            The new positions (m) and velocities (m/s), finite, for the same
            ``n`` particles (add or remove particles with
            :meth:`add_particles` and :meth:`remove_particles`). Copied.
        t : float, optional
            The new time, in seconds.

        Raises
        ------
        ValueError
            For a state of another shape, a non-finite one, or pinned
            particles given a velocity.
        """
        if X is not None:
            X = as_float_array(X, "X", shape=self.X.shape)
            if np.any(X[self.pinned, 1] != 0):
                raise ValueError("v of pinned particles must be zero: a pinned particle does not move")
            self.X = np.array(X, order="F")
        if t is not None:
            self.t = finite_real(t, "t", "seconds")


class _ReusedForces:
    """The derivative of a system, remembering the accelerations of its last evaluation.

    Called with the positions (and, when a force depends on it, the time)
    of the last evaluation, it returns the same accelerations without
    computing the forces again. Valid because every force of the system
    depends on the positions (and time) only, never on the velocities.
    """

    def __init__(self, system):
        self.system = system
        self.uses_time = any(getattr(f, "uses_time", True) for f in system.forces)
        self.x = self.t = self.a = self.changes = None

    def __call__(self, X, t):
        x = X[:, 0]
        if (self.x is not None and (not self.uses_time or t == self.t) and self.changes == self.system._changes
                and np.array_equal(x, self.x)):
            dX = np.empty_like(X)
            dX[:, 0] = X[:, 1]
            dX[:, 1] = self.a
            if len(self.system.pinned):
                dX[self.system.pinned] = 0.0
            return dX
        dX = self.system.derivative(X, t)
        self.x, self.t, self.a = x.copy(order="K"), t, dX[:, 1].copy(order="K")
        self.changes = self.system._changes
        return dX


def _force_list(forces):
    """The forces as a list: one Force object alone is accepted too."""
    if callable(getattr(forces, "add_to", None)):
        return [forces]
    if isinstance(forces, (str, bytes)):
        raise ValueError(f"forces must be a list of Force objects, got the string {forces!r}")
    try:
        return list(forces)
    except TypeError:
        raise ValueError(
            f"forces must be a list of Force objects (or one Force), got {type(forces).__name__}"
        ) from None


def _hook_list(between_steps):
    """The `between_steps` of a run as a list of callables: one hook alone is accepted too."""
    hooks = [between_steps] if callable(between_steps) else list(between_steps or ())
    for hook in hooks:
        if not callable(hook):
            raise ValueError(f"between_steps must be a function hook(system, t0) or a list of them, "
                             f"got {type(hook).__name__}")
    return hooks
