"""Implicit integration of stiff mass-spring systems.

Stiff springs force explicit methods to tiny steps (``h < 2 / omega_max``).
Two implicit answers, both usable as steppers ``step(f, X, t, h)`` of a
:class:`~particles.massspring.MassSpringSystem` (``system.run(T, h,
method=solver)``):

* :class:`BaraffWitkin`: backward Euler linearized once per step, as in
  Baraff and Witkin (1998). With ``K = dF/dx`` and ``D = dF/dv`` (sparse),
  each step solves

      (M - h D - h^2 K) dv = h (F + h K v),    v += dv,    x += h v,

  by preconditioned conjugate gradients. Compressed springs drop the
  transverse part of ``K`` so that the matrix stays positive definite;
  pinned particles are filtered out of the system.

* :class:`Prefactored`: the local/global solver of Liu et al. (2013). Each
  spring's energy ``k (|x_i - x_j| - L0)^2 / 2`` is the smallest value of
  ``k |x_i - x_j - d|^2 / 2`` over vectors ``d`` of length ``L0``. Alternately
  fixing ``d`` (local step: ``d = L0 (x_i - x_j) / |x_i - x_j|``) and ``x``
  (global step: a linear system whose matrix ``M + h^2 L`` never changes)
  minimizes the implicit-Euler objective. The matrix is factorized once;
  each step costs a few back-substitutions.

Both are first order and dissipate energy (numerical damping grows with
``h``), and both are stable at time steps far above the explicit limit.

References
----------
.. [1] D. Baraff and A. Witkin, "Large steps in cloth simulation", SIGGRAPH 1998.
.. [2] T. Liu, A. W. Bargteil, J. F. O'Brien and L. Kavan, "Fast simulation of
   mass-spring systems", ACM Transactions on Graphics 32(6), 2013.
.. [3] K.-J. Choi and H.-S. Ko, "Stable but responsive cloth", SIGGRAPH 2002.
"""

import numpy as np
import scipy.sparse
import scipy.sparse.linalg

from ._checks import count, positive_number
from .errors import ConvergenceError
from .forces import Damping, pair_differences
from .springs import _unit

__all__ = ["BaraffWitkin", "Prefactored", "relax"]


def _free_dofs(system):
    """Flattened (particle-major) indices of the coordinates of free particles."""
    d = system.d
    free = np.setdiff1d(np.arange(system.n), system.pinned)
    return (free[:, None] * d + np.arange(d)).ravel(), free


class _ImplicitStepper:
    """Common parts: a stepper object bound to a mass-spring system."""

    order = 1
    explicit = False
    second_order_layout = True

    def __init__(self, system):
        if not hasattr(system, "springs"):
            raise ValueError("system must be a MassSpringSystem (with labelled spring sets)")
        self.system = system

    def _state(self, X):
        X = np.asarray(X, dtype=float)
        if X.shape != self.system.X.shape:
            raise ValueError(f"X must have the shape of the system's state {self.system.X.shape}, got {X.shape}")
        return X


class BaraffWitkin(_ImplicitStepper):
    """Linearized backward Euler with sparse Jacobians and conjugate gradients.

    Parameters
    ----------
    system : MassSpringSystem
        The system whose springs, masses, damping and pins define the step.
    tol : float
        Relative residual at which conjugate gradients stop.
    maxiter : int
        Iteration cap of conjugate gradients per step.
    linear_solver : {"cg", "direct"}
        Conjugate gradients (the paper's choice) or a sparse direct solve
        (SuperLU), often faster for a few thousand particles.
    newton_iterations : int
        1 (the paper): one linearized solve per step. More iterations solve
        the nonlinear backward-Euler equations more exactly, which matters
        for large rotations at large steps.

    Attributes
    ----------
    iterations : list of int
        Conjugate-gradient iterations of every linear solve so far.
    converged : bool
        Whether the last solve reached `tol` within `maxiter` (when it does
        not, the step raises :class:`~particles.ConvergenceError`).

    Raises
    ------
    particles.ConvergenceError
        From a step whose conjugate gradients do not reach `tol` within
        `maxiter` iterations: the step is not taken, rather than taken with
        an unconverged velocity change.

    Notes
    -----
    Called as ``solver(f, X, t, h)``, a stepper: `f` is not evaluated, the
    solver uses its system's forces and their Jacobians. The Jacobian of
    :class:`~particles.forces.Damping` is included; other non-spring forces
    (gravity, wind, bending) are treated explicitly. A Jacobi
    (diagonal) preconditioner is used, as in the paper.

    With one linearized solve per step (the paper's choice) the energy is
    not guaranteed to fall at every step: under gravity an occasional step
    may gain a little. ``newton_iterations=2`` solves the backward-Euler
    equations closely enough that no step gains energy (tested).

    Examples
    --------
    >>> from particles.massspring import cloth
    >>> c = cloth(8, 8, k_structural=5e3)
    >>> solver = BaraffWitkin(c)
    >>> t, X = c.run(1.0, 1 / 30, method=solver)
    >>> bool(np.isfinite(X).all()), len(solver.iterations)
    (True, 30)
    """

    def __init__(self, system, tol=1e-6, maxiter=500, linear_solver="cg", newton_iterations=1):
        super().__init__(system)
        self.newton_iterations = count(newton_iterations, "newton_iterations", 1)
        if linear_solver not in ("cg", "direct"):
            raise ValueError(f"linear_solver must be 'cg' or 'direct', got {linear_solver!r}")
        self.linear_solver = linear_solver
        self.tol = positive_number(tol, "tol")
        self.maxiter = count(maxiter, "maxiter", 1)
        self.iterations = []
        self.converged = True
        self._dofs, _ = _free_dofs(system)
        n, d = system.n, system.d
        self._mass = np.repeat(system.m, d)  # diagonal of M, particle-major
        damping = np.zeros(n)  # -dF/dv of the Damping forces, per particle
        for force in system.other_forces():  # a loop over the few non-spring forces
            if isinstance(force, Damping):
                damping += force.d if force.rate is None else force.rate * system.m
        self._damping = np.repeat(damping, d)

    def __call__(self, f, X, t, h):
        X = self._state(X)
        h = positive_number(h, "h", "seconds")
        system = self.system
        x, v = X[:, 0], X[:, 1]
        # Baraff and Witkin's step: linearize F about the current state
        F = system.total_force(X, t).ravel()
        Kx, Kv = self._jacobians(X)
        dv = self._solve(Kx, Kv, h, h * (F + h * (Kx @ v.ravel())))
        X_new = np.empty_like(X)
        X_new[:, 1] = v + dv.reshape(v.shape)
        X_new[:, 0] = x + h * X_new[:, 1]
        # optional further Newton iterations on M (v' - v) = h F(x + h v', v')
        for _ in range(self.newton_iterations - 1):
            G = self._mass * (X_new[:, 1] - v).ravel() - h * system.total_force(X_new, t + h).ravel()
            Kx, Kv = self._jacobians(X_new)
            dv = self._solve(Kx, Kv, h, -G)
            X_new[:, 1] += dv.reshape(v.shape)
            X_new[:, 0] = x + h * X_new[:, 1]
        return X_new

    def _jacobians(self, X):
        Kx, Kv = self.system.spring_jacobians(X, clamp=True)
        return Kx, Kv - scipy.sparse.diags(self._damping)

    def _solve(self, Kx, Kv, h, b):
        """Solve (M - h Kv - h^2 Kx) dv = b on the free coordinates (pinned: dv = 0)."""
        dofs = self._dofs
        A = (scipy.sparse.diags(self._mass) - h * Kv - h * h * Kx).tocsr()[dofs][:, dofs]
        if self.linear_solver == "direct":
            dv_free = scipy.sparse.linalg.spsolve(A.tocsc(), b[dofs])
            self.iterations.append(0)
        else:
            ticks = [0]

            def tick(_):
                ticks[0] += 1

            preconditioner = scipy.sparse.diags(1.0 / A.diagonal())
            dv_free, info = scipy.sparse.linalg.cg(A, b[dofs], rtol=self.tol, atol=0.0, maxiter=self.maxiter,
                                                   M=preconditioner, callback=tick)
            self.iterations.append(ticks[0])
            self.converged = info == 0
            if not self.converged:
                raise ConvergenceError(
                    f"conjugate gradients did not reach the relative residual tol = {self.tol:g} within "
                    f"maxiter = {self.maxiter} iterations (h = {h:g} s); raise maxiter, loosen tol, use "
                    "linear_solver='direct', or take a smaller time step")
        dv = np.zeros(len(b))
        dv[dofs] = dv_free
        return dv


class Prefactored(_ImplicitStepper):
    """Liu et al.'s local/global solver, with the system matrix factorized once.

    Parameters
    ----------
    system : MassSpringSystem
    h : float
        The time step the matrix ``M + h^2 L`` is built for, in seconds; the
        stepper refactorizes if called with another `h`.
    iterations : int
        Local/global iterations per step (about 10 is typical: more gets
        closer to the exact backward-Euler step).

    Notes
    -----
    ``L = sum_s k_s (e_i - e_j)(e_i - e_j)^T`` is the stiffness-weighted graph
    Laplacian of the springs (n x n, the same for each coordinate). The
    global step solves ``(M + h^2 L) x = M y + h^2 J d`` with
    ``y = x_n + h v_n + h^2 M^-1 F_other`` (``F_other``: gravity, damping, wind,
    bending, evaluated at the start of the step) and ``J d`` the springs'
    projected directions, scattered. Pinned particles are moved to the right-hand
    side. Spring damping ``kd`` is not used (the method's own numerical
    damping dominates); use :class:`~particles.forces.Damping`.
    """

    def __init__(self, system, h, iterations=10):
        super().__init__(system)
        if isinstance(iterations, bool) or not isinstance(iterations, (int, np.integer)) or iterations < 1:
            raise ValueError(f"iterations must be a positive integer, got {iterations!r}")
        self.iterations = int(iterations)
        self._i = np.concatenate([s.i for s in system.springs.values()])
        self._j = np.concatenate([s.j for s in system.springs.values()])
        self._k = np.concatenate([s.k for s in system.springs.values()])
        self._L0 = np.concatenate([s.rest_length for s in system.springs.values()])
        _, self._free = _free_dofs(system)
        self._factor(positive_number(h, "h", "seconds"))

    def _factor(self, h):
        n, i, j, k = self.system.n, self._i, self._j, self._k
        L = scipy.sparse.coo_matrix(
            (np.concatenate([k, k, -k, -k]), (np.concatenate([i, j, i, j]), np.concatenate([i, j, j, i]))),
            shape=(n, n)).tocsr()
        Q = (scipy.sparse.diags(self.system.m) + h * h * L).tocsc()
        free, pinned = self._free, self.system.pinned
        self._Q_fp = Q[free][:, pinned]
        # a minimum-degree ordering of the symmetric matrix keeps the LU factors sparse
        self._lu = scipy.sparse.linalg.splu(Q[free][:, free].tocsc(), permc_spec="MMD_AT_PLUS_A")
        self.h = h

    def __call__(self, f, X, t, h):
        X = self._state(X)
        h = positive_number(h, "h", "seconds")
        if not np.isclose(h, self.h, rtol=1e-12, atol=0.0):
            self._factor(h)
        system = self.system
        x, v = X[:, 0], X[:, 1]
        F = np.zeros_like(x)
        for force in system.other_forces():  # a loop over the few non-spring forces
            force.add_to(F, x, v, t, system.m)
        m = system.m
        # coordinate-major (d, n) arrays: every operation below runs over particles
        yt = np.ascontiguousarray((x + h * v + (h * h) * F / m[:, None]).T)
        xt = yt.copy()
        xt[:, system.pinned] = x[system.pinned].T
        My = yt * m
        fixed = (self._Q_fp @ x[system.pinned]).T  # pinned particles' pull on the free ones
        free, n = self._free, system.n
        kL0 = self._k * self._L0
        for _ in range(self.iterations):  # local/global iterations
            # local: the closest vector of length L0 to each spring, times k
            d = pair_differences(xt.T, self._i, self._j)
            d *= kL0 / np.maximum(np.sqrt(np.einsum("as,as->s", d, d)), 1e-300)
            # global: (M + h^2 L) x = M y + h^2 J d, with J d scattered per coordinate
            rhs = My.copy()
            for a in range(len(xt)):  # a loop over the d coordinates
                rhs[a] += (h * h) * (np.bincount(self._i, d[a], minlength=n) - np.bincount(self._j, d[a], minlength=n))
            xt[:, free] = self._lu.solve(np.ascontiguousarray((rhs[:, free] - fixed).T)).T
        X_new = np.empty_like(X)
        X_new[:, 0] = xt.T
        X_new[:, 1] = (X_new[:, 0] - x) / h
        return X_new


def relax(system, h=0.05, tol=1e-8, max_steps=2000, method="auto"):
    """Static equilibrium of a mass-spring system: positions where the net force vanishes.

    Parameters
    ----------
    system : MassSpringSystem
        Relaxed in place: its state becomes the equilibrium, at rest.
    h : float
        Pseudo time step of the ``"implicit"`` method (larger is closer to
        plain Newton), and the first of the growing pseudo time steps of the
        ``"newton"`` method's continuation.
    tol : float
        Relative force tolerance: stop when the largest net force on a free
        particle is below ``tol`` times the force scale, the larger of the
        largest net force at the start and the largest force any one force
        object applies (so that a system already at equilibrium returns at
        once); ``"newton"``: at most ``max(tol, 1e-6)`` times it, the floor
        set by its finite-difference Jacobian.
    max_steps : int
        Largest number of pseudo time steps.
    method : {"auto", "implicit", "newton"}
        ``"implicit"`` repeats backward-Euler steps (:class:`BaraffWitkin`)
        from rest, i.e. Newton's method on ``F(x) = 0`` regularized by
        ``M / h^2``; it handles large cloths but treats forces other than
        springs and damping explicitly. ``"newton"`` calls
        ``scipy.optimize.root`` (Powell's hybrid method, finite-difference
        Jacobian) on all forces, for small systems such as a hair with
        bending. ``"auto"`` picks ``"newton"`` when the system has forces
        beyond springs, gravity, damping and wind, else ``"implicit"``.

    Returns
    -------
    int
        Steps (``"implicit"``) or force evaluations (``"newton"``) used.

    Raises
    ------
    particles.ConvergenceError
        When no equilibrium is found.
    """
    import scipy.optimize

    from .errors import ConvergenceError
    from .forces import Gravity, Wind

    if method == "auto":
        simple = all(isinstance(f, (Gravity, Damping, Wind)) for f in system.other_forces())
        method = "implicit" if simple else "newton"
    if method not in ("implicit", "newton"):
        raise ValueError(f"method must be 'auto', 'implicit' or 'newton', got {method!r}")
    free = np.setdiff1d(np.arange(system.n), system.pinned)
    X = system.X.copy(order="K")
    X[:, 1] = 0.0
    # the force scale: the larger of the net force at the start and the largest force any one force
    # applies (at an equilibrium the net force is ~0 but gravity and the springs are not)
    scale = max(np.max(np.abs(system.total_force(X, system.t)[free]), initial=0.0), 1e-300)
    for force in system.forces:  # a loop over the few force objects
        F_one = np.zeros_like(X[:, 0])
        force.add_to(F_one, X[:, 0], X[:, 1], system.t, system.m)
        scale = max(scale, np.max(np.abs(F_one[free]), initial=0.0))
    if method == "newton":
        mass = np.repeat(system.m[free], system.d)

        def net_force(y):
            X[free, 0] = y.reshape(-1, system.d)
            return system.total_force(X, system.t)[free].ravel() / scale

        # continuation: backward-Euler-like steps from rest with growing pseudo
        # time steps guide Newton to the equilibrium nearest the start, then a
        # plain solve of F(x) = 0. A pseudo step whose solve fails is not
        # taken: it is retried at half the length (large rotations of stiff
        # springs defeat Newton when the step is too long).
        y, evaluations = X[free, 0].ravel().copy(), 0
        tau, longest = h, h * 2.0**11
        for _ in range(max_steps):  # a loop over pseudo time steps
            start = y.copy()
            sol = scipy.optimize.root(lambda z: net_force(z) - mass * (z - start) / (tau * tau * scale),
                                      start, method="hybr", tol=1e-12)
            evaluations += sol.nfev
            if sol.success:
                y = sol.x
                if tau == np.inf:
                    break
                tau = np.inf if tau >= longest else 2.0 * tau
            elif tau == np.inf:
                tau = longest  # not close enough for a plain solve: more pseudo steps first
            elif tau > 1e-6 * h:
                tau /= 2.0
            else:
                break
        # finite-difference Jacobians limit the attainable residual to about 1e-8
        if not sol.success or np.max(np.abs(net_force(y))) > max(tol, 1e-6):
            raise ConvergenceError(f"relax: Newton found no static equilibrium ({sol.message})")
        X[free, 0] = y.reshape(-1, system.d)
        system.X = X
        return int(evaluations)
    solver = BaraffWitkin(system, linear_solver="direct")
    residual = np.inf
    for step in range(max_steps + 1):
        X[:, 1] = 0.0
        residual = np.max(np.abs(system.total_force(X, system.t)[free]), initial=0.0)
        if residual <= tol * scale:
            system.X = X
            return step
        X = solver(None, X, system.t, h)
        if not np.all(np.isfinite(X)):
            break
    raise ConvergenceError(f"relax: no static equilibrium within {max_steps} steps "
                           f"(largest net force {residual:.3g} N)")
