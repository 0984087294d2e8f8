"""Baraff and Witkin's implicit step, iterated by Newton's method to backward Euler.

With ``K = dF/dx`` and ``D = dF/dv`` (sparse) and ``A = M - h D - h^2 K``,
:class:`BaraffWitkin` solves ``A dv = h (F + h K v)``, ``v += dv``,
``x += h v``, then Newton iterations ``A dv = -G`` on the residual of the
backward-Euler equations (see :mod:`particles.implicit` for both solvers).

References
----------
.. [1] D. Baraff and A. Witkin, "Large steps in cloth simulation", SIGGRAPH 1998.
.. [2] K.-J. Choi and H.-S. Ko, "Stable but responsive cloth", SIGGRAPH 2002.
"""

import numpy as np

from .._checks import count, positive_number
from ..errors import ConvergenceError
from ..forces.fields import Damping
from .sparse import SpringSolver, factorize, free_dofs

__all__ = ["BaraffWitkin"]


class BaraffWitkin(SpringSolver):
    """Backward Euler by Newton's method on sparse Jacobians, Baraff and Witkin's step first.

    Parameters
    ----------
    system : MassSpringSystem
        The system whose springs, masses, damping and pins define the step.
    tol : float
        Relative residual ``|A dv - b| <= tol |b|`` at which conjugate
        gradients stop (``"cg"`` and ``"auto"``).
    maxiter : int
        Iteration cap of conjugate gradients per linear solve.
    linear_solver : {"auto", "cg", "direct"}
        How ``A dv = b`` is solved. ``"cg"``: conjugate gradients with a
        block-Jacobi preconditioner (the inverse of each particle's d x d
        diagonal block of ``A``), warm-started from the previous step's
        ``dv``; a solve that does not reach `tol` within `maxiter` raises
        :class:`~particles.ConvergenceError`. ``"direct"``: a sparse
        factorization (SuperLU in symmetric mode, minimum-degree ordering).
        ``"auto"`` (default): the same conjugate gradients, each solve capped
        at :attr:`AUTO_CG_ITERATIONS` (or `maxiter` if smaller); once a solve
        reaches the cap, it and all later ones are factorized.
    newton_iterations : int
        Linear solves per step: 1 is the paper's single linearized step, 2
        (default) adds one Newton iteration.
    energy_check : bool
        After the `newton_iterations`, keep iterating while the step gains
        energy (see Notes), up to `max_newton_iterations` in all.
    max_newton_iterations : int
        Largest number of linear solves per step with `energy_check` (at
        least `newton_iterations`).

    Attributes
    ----------
    iterations : list of int
        Conjugate-gradient iterations of every linear solve so far (0 for a
        direct solve).
    newton : list of int
        Linear solves (Newton iterations) of every step so far.
    direct_solves : int
        Linear solves done by the sparse factorization.
    converged : bool
        Whether the last linear solve reached `tol` (a direct solve always does).

    Raises
    ------
    particles.ConvergenceError
        From a step whose conjugate gradients (``linear_solver="cg"``) do not
        reach `tol` within `maxiter` iterations, or that still gains energy
        after `max_newton_iterations`: the step is not taken, rather than
        taken with an unconverged velocity.

    Notes
    -----
    A step is ``solver.step(X, t, h)`` (:meth:`step`): the solver uses its
    system's forces and their Jacobians ``K = dF/dx`` and ``D = dF/dv``,
    compressed springs clamped (Choi and Ko) so that ``A = M - h D - h^2 K``
    is symmetric positive definite. The Jacobian of
    :class:`~particles.forces.Damping` is included in ``D``; other
    non-spring forces (gravity, wind, bending) enter the right-hand sides
    but not ``A``.

    The first solve is Baraff and Witkin's step, ``F`` linearized about the
    current state::

        A dv = h (F + h K v),    v' = v + dv,    x' = x + h v'.

    Each further one is a Newton iteration on the backward-Euler equations
    ``G(v') = M (v' - v) - h F(x + h v', v') = 0``, with ``F, K, D`` at
    ``(x', v')``: ``A dv = -G``, ``v' += dv``.

    The energy check: a solved backward-Euler step cannot gain energy when
    the potentials are convex (stretched springs, gravity): with ``E`` the
    kinetic plus potential energy and ``W = h F_n(x', v') . v'`` the work of
    the forces that have no potential (damping, wind) over the step,
    ``E(x', v') <= E(x, v) + W``. A step that breaks this by more than
    ``1e-9`` of the energies involved (and round-off) is not solved yet,
    and gets another iteration.

    Cost: each solve is one evaluation of the forces, the assembly of
    ``K`` and ``D``, and one conjugate-gradient solve or factorization of
    ``A``; the energy check adds an evaluation of the energies per step.

    Why not one solve: it does not solve the backward-Euler equations, and
    for stiff cloth at animation steps the error is large. A cloth of
    stretch modulus 5000 N/m (physical scaling) falling from flat at
    ``h = 1/30`` s gains 11% (16 x 16) and 54% (32 x 32) of ``M g H`` in
    energy with one solve per step, and stretches 5.8% and 21%; with two,
    no step gains energy and the largest strain is 1.7% and 3.4%, as with
    six (lecture 7 tabulates the damping and cost). Why block-Jacobi and
    the fallback: under physical scaling ``h^2 k / m`` grows like the
    number of particles, and with it the condition number of ``A``; on that
    cloth Jacobi-preconditioned conjugate gradients need 450 (16 x 16) to
    2200 (64 x 64) iterations, block-Jacobi two to three times fewer, and
    one factorization costs as much as 90 (16 x 16) to 450 (64 x 64)
    block-Jacobi iterations.

    Examples
    --------
    >>> from particles.massspring import cloth
    >>> c = cloth(8, 8, k_structural=5e3)
    >>> solver = BaraffWitkin(c)
    >>> t, X = c.run(1.0, 1 / 30, method=solver)
    >>> bool(np.isfinite(X).all()), len(solver.newton), min(solver.newton)
    (True, 30, 2)
    """

    AUTO_CG_ITERATIONS = 100
    """``"auto"``: conjugate-gradient iterations after which a solve counts as stalled (about
    the cost of factorizing a 16 x 16 cloth's ``A``; a larger cloth's costs more)."""

    def __init__(self, system, tol=1e-6, maxiter=500, linear_solver="auto", newton_iterations=2,
                 energy_check=True, max_newton_iterations=10):
        super().__init__(system)
        self.newton_iterations = count(newton_iterations, "newton_iterations", 1)
        self.max_newton_iterations = count(max_newton_iterations, "max_newton_iterations", 1)
        self.energy_check = bool(energy_check)
        if linear_solver not in ("auto", "cg", "direct"):
            raise ValueError(f"linear_solver must be 'auto', 'cg' or 'direct', got {linear_solver!r}")
        self.linear_solver = linear_solver
        self.tol = positive_number(tol, "tol")
        self.maxiter = count(maxiter, "maxiter", 1)
        self.iterations, self.newton, self.direct_solves = [], [], 0
        self.converged = True
        self._stalled = False  # "auto": conjugate gradients stalled once, factorize from now on
        self._dofs, _ = free_dofs(system)
        self._guess = None  # the last step's first dv on the free coordinates: a warm start
        n, d = system.n, system.d
        self._mass = np.repeat(system.m, d)  # diagonal of M, particle-major
        damping = np.zeros(n)  # -dF/dv of the Damping forces, per particle
        for force in system.other_forces():  # a loop over the few non-spring forces
            if isinstance(force, Damping):
                damping += force.d if force.rate is None else force.rate * system.m
        self._damping = np.repeat(damping, d)

    def step(self, X, t, h):
        """One backward-Euler step of the system from `X` at `t` to ``t + h``, by Newton's method.

        With ``A = M - h D - h^2 K`` (``M`` the masses, ``K = dF/dx`` and
        ``D = dF/dv`` of the springs and :class:`~particles.forces.Damping`,
        on the free coordinates: pinned particles keep ``dv = 0``), the first
        solve is Baraff and Witkin's linearized step and each further one a
        Newton iteration on ``G(v') = M (v' - v) - h F(x + h v', v') = 0``::

            A dv = h (F + h K v)        then    A dv = -G,    v' = v + dv,    x' = x + h v'.

        Parameters
        ----------
        X : ndarray, shape (n, 2, d)
            Positions (m) and velocities (m/s) of the system's particles. Not modified.
        t : float
            Time, in seconds.
        h : float
            Time step, in seconds, > 0.

        Returns
        -------
        ndarray, shape (n, 2, d)
            The state at ``t + h``.

        Raises
        ------
        particles.ConvergenceError
            As described for the class.
        """
        X = self._state(X)
        h = positive_number(h, "h", "seconds")
        system, dofs = self.system, self._dofs
        x, v0 = X[:, 0], X[:, 1].ravel()
        # Baraff and Witkin's step: linearize F about the current state
        F = system.total_force(X, t).ravel()
        K, D = self._jacobians(X)
        dv = self._solve(K, D, h, h * (F + h * (K @ v0)), self._guess)  # A dv = h (F + h K v)
        self._guess = dv[dofs]
        V = v0 + dv  # v', flattened
        E0, solves = None, 1
        while True:  # a loop over Newton iterations
            X_new = self._end_state(x, V, h)
            if solves >= self.newton_iterations:
                if not self.energy_check:
                    break
                if E0 is None:
                    E0 = (system.kinetic_energy(X), system.potential_energy(X, t))
                gain = self._energy_gain(X, X_new, E0, t + h, h)
                if gain <= 0.0 or not np.isfinite(gain):  # solved, or blown up (the run reports that)
                    break
                if solves >= max(self.max_newton_iterations, self.newton_iterations):
                    self.newton.append(solves)
                    raise ConvergenceError(
                        f"the backward-Euler step from t = {t:.6g} s (h = {h:g} s) still gains {gain:.3g} J after "
                        f"max_newton_iterations = {self.max_newton_iterations} Newton iterations; raise "
                        "max_newton_iterations or take a smaller time step")
            # Newton on G(v') = M (v' - v) - h F(x + h v', v') = 0
            G = self._mass * (V - v0) - h * system.total_force(X_new, t + h).ravel()
            K, D = self._jacobians(X_new)
            V = V + self._solve(K, D, h, -G, None)  # A dv = -G
            solves += 1
        self.newton.append(solves)
        return X_new

    def _end_state(self, x, V, h):
        """The state (x + h v', v') for the flattened end velocity V, in the system's memory order."""
        X_new = np.empty((self.system.n, 2, self.system.d), order="F")
        X_new[:, 1] = V.reshape(-1, self.system.d)
        X_new[:, 0] = x + h * X_new[:, 1]
        return X_new

    def _energy_gain(self, X, X_new, E0, t, h):
        """E(x', v') - E(x, v) - W, less a round-off allowance (> 0: the step gains energy), in joules."""
        system = self.system
        K1, U1 = system.kinetic_energy(X_new), system.potential_energy(X_new, t)
        F = np.zeros_like(X_new[:, 0])
        for force in system.forces:  # a loop over the few force objects: the work of those without a potential
            if not hasattr(force, "potential_energy"):
                force.add_to(F, X_new[:, 0], X_new[:, 1], t, system.m)
        W = h * float(np.sum(F * X_new[:, 1]))
        # 1e-9 of the energies involved, and the energy of every spring stretched by round-off
        springs = sum(float(s.k.sum()) for s in system.springs.values())  # a loop over spring sets
        roundoff = (64 * np.finfo(float).eps * np.max(np.abs(X_new[:, 0]), initial=0.0)) ** 2 * springs
        allowance = 1e-9 * (E0[0] + abs(E0[1]) + K1 + abs(U1) + abs(W)) + roundoff
        return K1 + U1 - E0[0] - E0[1] - W - allowance

    def _jacobians(self, X):
        """K = dF/dx (springs, clamped) and D = dF/dv (springs and Damping), sparse, at X."""
        import scipy.sparse
        K, D = self.system.spring_jacobians(X, clamp=True)
        return K, D - scipy.sparse.diags(self._damping)

    def _solve(self, K, D, h, b, guess):
        """Solve A dv = b, A = M - h D - h^2 K, on the free coordinates (pinned: dv = 0)."""
        import scipy.sparse
        dofs = self._dofs
        M = scipy.sparse.diags(self._mass)
        A = (M - h * D - h * h * K).tocsr()[dofs][:, dofs]
        if self.linear_solver == "direct" or self._stalled:
            dv_free = self._direct(A, b[dofs])
        else:
            cap = min(self.maxiter, self.AUTO_CG_ITERATIONS) if self.linear_solver == "auto" else self.maxiter
            dv_free, ticks, self.converged = _block_cg(A, b[dofs], guess, self.tol, cap, self.system.d)
            self.iterations.append(ticks)
            if not self.converged and self.linear_solver == "auto":
                self._stalled = True
                dv_free = self._direct(A, b[dofs], record=False)  # the stalled iterations stay recorded
            elif not self.converged:
                raise ConvergenceError(
                    f"conjugate gradients did not reach the relative residual tol = {self.tol:g} within "
                    f"maxiter = {self.maxiter} iterations (h = {h:g} s); raise maxiter, loosen tol, use "
                    "linear_solver='direct' or 'auto', or take a smaller time step")
        dv = np.zeros(len(b))
        dv[dofs] = dv_free
        return dv

    def _direct(self, A, b, record=True):
        if record:
            self.iterations.append(0)
        self.direct_solves += 1
        self.converged = True
        return factorize(A).solve(b)


def _block_jacobi(A, d):
    """The inverses of the d x d diagonal blocks of A (one per particle), as a block-diagonal matrix."""
    import scipy.sparse
    C = A.tocoo()
    same = C.row // d == C.col // d
    blocks = np.zeros((A.shape[0] // d, d, d))
    blocks[C.row[same] // d, C.row[same] % d, C.col[same] % d] = C.data[same]  # CSR entries are unique
    nb = len(blocks)
    return scipy.sparse.bsr_matrix((np.linalg.inv(blocks), np.arange(nb), np.arange(nb + 1)), shape=A.shape)


def _block_cg(A, b, guess, tol, maxiter, d):
    """Block-Jacobi preconditioned conjugate gradients; returns (x, iterations, converged)."""
    import scipy.sparse.linalg
    ticks = [0]

    def tick(_):
        ticks[0] += 1

    x0 = guess if guess is not None and guess.shape == b.shape else None
    x, info = scipy.sparse.linalg.cg(A, b, x0=x0, rtol=tol, atol=0.0, maxiter=maxiter,
                                     M=_block_jacobi(A, d), callback=tick)
    return x, ticks[0], info == 0
