"""Implicit integration of stiff mass-spring systems.

Stiff springs force explicit methods to tiny steps (``h < 2 / omega_max``).
Two implicit answers, both usable as steppers ``step(f, X, t, h)`` of a
:class:`~particles.massspring.MassSpringSystem` (``system.run(T, h,
method=solver)``):

* :class:`BaraffWitkin`: backward Euler, starting with the step of Baraff
  and Witkin (1998) linearized once. With ``K = dF/dx`` and ``D = dF/dv``
  (sparse) and ``A = M - h D - h^2 K``, it solves

      A dv = h (F + h K v),    v += dv,    x += h v,

  then (by default) one Newton iteration ``A dv = -G`` on the residual
  ``G = M (v' - v) - h F(x', v')`` of the backward-Euler equations, and more
  while the step would gain energy; each solve by block-Jacobi
  preconditioned conjugate gradients or a sparse factorization. Compressed
  springs drop the transverse part of ``K`` so that ``A`` stays positive
  definite; pinned particles are filtered out of the system.

* :class:`Prefactored`: the local/global solver of Liu et al. (2013). Each
  spring's energy ``k (|x_i - x_j| - L0)^2 / 2`` is the smallest value of
  ``k |x_i - x_j - d|^2 / 2`` over vectors ``d`` of length ``L0``. Alternately
  fixing ``d`` (local step: ``d = L0 (x_i - x_j) / |x_i - x_j|``) and ``x``
  (global step: a linear system whose matrix ``M + h^2 L`` never changes)
  minimizes the implicit-Euler objective. The matrix is factorized once;
  each iteration costs a few back-substitutions, and a step iterates (with
  Anderson acceleration) until the objective's gradient is small.

Both are first order and dissipate energy (numerical damping grows with
``h``), and both are stable at time steps far above the explicit limit.

References
----------
.. [1] D. Baraff and A. Witkin, "Large steps in cloth simulation", SIGGRAPH 1998.
.. [2] T. Liu, A. W. Bargteil, J. F. O'Brien and L. Kavan, "Fast simulation of
   mass-spring systems", ACM Transactions on Graphics 32(6), 2013.
.. [3] K.-J. Choi and H.-S. Ko, "Stable but responsive cloth", SIGGRAPH 2002.
.. [4] Y. Peng, B. Deng, J. Zhang, F. Geng, W. Qin and L. Liu, "Anderson
   acceleration for geometry optimization and physics simulation", ACM
   Transactions on Graphics 37(4), 2018.
"""

import numpy as np
import scipy.sparse
import scipy.sparse.linalg

from ._checks import count, positive_number
from .errors import ConvergenceError
from .forces import Damping, pair_differences

__all__ = ["BaraffWitkin", "Prefactored"]  # relax, from particles.statics, is importable from here too


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
    Called as ``solver(f, X, t, h)``, a stepper: `f` is not evaluated, the
    solver uses its system's forces and their Jacobians ``K = dF/dx`` and
    ``D = dF/dv``, compressed springs clamped (Choi and Ko) so that
    ``A = M - h D - h^2 K`` is symmetric positive definite. The Jacobian of
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
        self._dofs, _ = _free_dofs(system)
        self._guess = None  # the last step's first dv on the free coordinates: a warm start
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
        K, D = self.system.spring_jacobians(X, clamp=True)
        return K, D - scipy.sparse.diags(self._damping)

    def _solve(self, K, D, h, b, guess):
        """Solve A dv = b, A = M - h D - h^2 K, on the free coordinates (pinned: dv = 0)."""
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
        return _factorize(A).solve(b)


def _least_squares(A, b):
    """argmin |A c - b| for a tall A of a few columns, by its normal equations (Anderson's small problem)."""
    AtA = A.T @ A
    try:
        return np.linalg.solve(AtA + 1e-14 * np.trace(AtA) * np.eye(len(AtA)), A.T @ b)
    except np.linalg.LinAlgError:  # exactly dependent columns
        return np.linalg.lstsq(A, b, rcond=None)[0]


def _factorize(A):
    """Sparse LU of a symmetric positive definite A: symmetric mode, minimum degree on A + A^T."""
    return scipy.sparse.linalg.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                                    options={"SymmetricMode": True})


def _block_jacobi(A, d):
    """The inverses of the d x d diagonal blocks of A (one per particle), as a block-diagonal matrix."""
    C = A.tocoo()
    same = C.row // d == C.col // d
    blocks = np.zeros((A.shape[0] // d, d, d))
    blocks[C.row[same] // d, C.row[same] % d, C.col[same] % d] = C.data[same]  # CSR entries are unique
    nb = len(blocks)
    return scipy.sparse.bsr_matrix((np.linalg.inv(blocks), np.arange(nb), np.arange(nb + 1)), shape=A.shape)


def _block_cg(A, b, guess, tol, maxiter, d):
    """Block-Jacobi preconditioned conjugate gradients; returns (x, iterations, converged)."""
    ticks = [0]

    def tick(_):
        ticks[0] += 1

    x0 = guess if guess is not None and guess.shape == b.shape else None
    x, info = scipy.sparse.linalg.cg(A, b, x0=x0, rtol=tol, atol=0.0, maxiter=maxiter,
                                     M=_block_jacobi(A, d), callback=tick)
    return x, ticks[0], info == 0


class Prefactored(_ImplicitStepper):
    """Liu et al.'s local/global solver, the system matrix factorized once, iterated to a residual.

    Parameters
    ----------
    system : MassSpringSystem
    h : float
        The time step the matrix ``M + h^2 L`` is built for, in seconds; the
        stepper refactorizes if called with another `h`.
    tol : float
        Stop when the backward-Euler residual ``g`` (a force, see Notes) has
        ``|g| <= tol f``: 2-norms over the free particles, ``f`` the larger
        of the springs' net force and the other forces' net force at the
        start of the step.
    max_iterations : int
        Largest number of local/global iterations per step; a step that does
        not reach `tol` within them raises :class:`~particles.ConvergenceError`.
    anderson : int
        Anderson acceleration over this many previous iterates (Peng et al.
        2018), safeguarded by the objective: an accelerated iterate that does
        not lower it is replaced by the plain local/global one. 0: Liu et
        al.'s plain iteration.
    iterations : int, optional
        A fixed number of plain local/global iterations per step, without
        the residual check (Liu et al.'s "about 10"); overrides `tol`,
        `max_iterations` and `anderson`.

    Attributes
    ----------
    counts : list of int
        Local/global iterations of every step so far.

    Raises
    ------
    particles.ConvergenceError
        From a step whose residual does not reach `tol` within `max_iterations`.

    Notes
    -----
    ``L = sum_s k_s (e_i - e_j)(e_i - e_j)^T`` is the stiffness-weighted graph
    Laplacian of the springs (n x n, the same for each coordinate). A
    backward-Euler step minimizes

        Phi(x) = (x - y)^T M (x - y) / (2 h^2) + sum_s k_s (|x_i - x_j| - L0_s)^2 / 2,

    with ``y = x_n + h v_n + h^2 M^-1 F_other`` (``F_other``: gravity, damping,
    wind, bending, evaluated at the start of the step). The local step sets
    each spring's ``d_s = L0_s (x_i - x_j) / |x_i - x_j|``; the global step
    solves ``(M + h^2 L) x = M y + h^2 J d`` (``J d``: the ``k_s d_s``
    scattered, +i, -j), pinned particles moved to the right-hand side. The
    residual is the gradient of ``Phi``, a force:
    ``g = (M + h^2 L) x / h^2 - M y / h^2 - J d(x)``. Spring damping ``kd`` is
    not used; use :class:`~particles.forces.Damping`.

    Cost: one factorization of ``M + h^2 L`` per `h`; per iteration one
    local step over the springs, two triangular solves per coordinate, a
    sparse product for the residual and the small least-squares problem of
    Anderson's mixing.

    Why a residual and acceleration: the plain iteration converges
    linearly, at a rate set by how far ``M + h^2 L`` (every spring as stiff
    across as along) is from the true Hessian (a cloth is nearly free
    across). On the 5000 N/m cloth of :class:`BaraffWitkin`'s notes at
    ``h = 1/30`` s the rate is 0.99 and worse: 10 iterations leave a
    residual of about half the force scale, and the unsolved steps hold the
    cloth back like a strong extra damping (after 0.5 s of falling its
    centre has dropped 0.17 m where backward Euler's has dropped 0.54 m),
    and keep a hanging cloth at rest at 1.9% strain where its equilibrium
    has 0.72%. With ``tol = 0.1`` the fall, the strain and the energy are
    backward Euler's; Anderson acceleration gets there in 90 (16 x 16) and
    155 (32 x 32) iterations per step on average, where the plain
    iteration needs thousands. Much smaller tolerances are out of reach on
    a folded cloth, whose compressed springs make ``Phi`` non-convex.
    """

    def __init__(self, system, h, tol=0.1, max_iterations=1000, anderson=8, iterations=None):
        super().__init__(system)
        if iterations is not None and (isinstance(iterations, bool) or not isinstance(iterations, (int, np.integer))
                                       or iterations < 1):
            raise ValueError(f"iterations must be a positive integer or None, got {iterations!r}")
        self.iterations = None if iterations is None else int(iterations)
        self.tol = positive_number(tol, "tol")
        self.max_iterations = count(max_iterations, "max_iterations", 1)
        self.anderson = count(anderson, "anderson", 0)
        self.counts = []
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
        self._Q_ff = Q[free][:, free].tocsr()
        # a minimum-degree ordering of the symmetric matrix keeps the LU factors sparse
        self._lu = _factorize(Q[free][:, free])
        self.h = h

    def __call__(self, f, X, t, h):
        X = self._state(X)
        h = positive_number(h, "h", "seconds")
        if not np.isclose(h, self.h, rtol=1e-12, atol=0.0):
            self._factor(h)
        system, free = self.system, self._free
        x, v, m = X[:, 0], X[:, 1], system.m
        F = np.zeros_like(x)
        for force in system.other_forces():  # a loop over the few non-spring forces
            force.add_to(F, x, v, t, m)
        # coordinate-major (d, n) arrays: every operation below runs over particles
        yt = np.ascontiguousarray((x + h * v + (h * h) * F / m[:, None]).T)
        fixed = (self._Q_fp @ x[system.pinned]).T  # pinned particles' pull on the free ones
        b = (yt * m)[:, free] - fixed  # M y on the free particles, pins moved over
        scale = max(float(np.linalg.norm(F[free])), float(np.linalg.norm(self._spring_forces(x.T)[:, free])))
        # never below the round-off of the spring forces (a system at rest without gravity has f = 0)
        scale = max(scale, 16 * np.finfo(float).eps * float(self._k.max(initial=0.0))
                    * float(np.max(np.abs(x), initial=0.0)) * np.sqrt(x[free].size) / self.tol)
        xt = yt.copy()
        xt[:, system.pinned] = x[system.pinned].T
        if self.iterations is not None:
            for _ in range(self.iterations):  # a loop over local/global iterations
                xt[:, free] = self._global(b, self._local(xt)[0], h)
            self.counts.append(self.iterations)
        else:
            xt[:, free] = self._solve(xt, b, yt[:, free], h, scale, t)
        X_new = np.empty_like(X)
        X_new[:, 0] = xt.T
        X_new[:, 1] = (X_new[:, 0] - x) / h
        return X_new

    def _local(self, xt):
        """The springs' projections scattered, J d of shape (d, n_free), and their energy sum k (L - L0)^2 / 2."""
        d = pair_differences(xt.T, self._i, self._j)
        L = np.sqrt(np.einsum("as,as->s", d, d))
        d *= self._k * self._L0 / np.maximum(L, 1e-300)
        n = self.system.n
        Jd = np.array([np.bincount(self._i, d[a], minlength=n) - np.bincount(self._j, d[a], minlength=n)
                       for a in range(len(d))])  # a loop over the d coordinates
        return Jd[:, self._free], 0.5 * float(np.sum(self._k * (L - self._L0) ** 2))

    def _spring_forces(self, xt):
        """Net spring force on every particle, shape (d, n): J d(x) - L x."""
        d = pair_differences(xt.T, self._i, self._j)
        L = np.sqrt(np.einsum("as,as->s", d, d))
        d *= self._k * (self._L0 / np.maximum(L, 1e-300) - 1.0)
        n = self.system.n
        return np.array([np.bincount(self._i, d[a], minlength=n) - np.bincount(self._j, d[a], minlength=n)
                         for a in range(len(d))])  # a loop over the d coordinates

    def _global(self, b, Jd, h):
        """Free positions solving (M + h^2 L) x = M y + h^2 J d (pins on the right), shape (d, n_free)."""
        return self._lu.solve(np.ascontiguousarray((b + (h * h) * Jd).T)).T

    def _solve(self, xt, b, y_free, h, scale, t):
        """Anderson-accelerated local/global iterations until |g| <= tol f; returns the free positions."""
        free, h2 = self._free, h * h
        m = self.system.m[free]
        Q = self._Q_ff

        def objective(u, E):  # Phi at the free positions u, E the springs' energy there
            r = u - y_free
            return 0.5 * float(np.sum(m * r * r)) / h2 + E

        u = xt[:, free].copy()
        Jd, E = self._local(xt)
        phi = objective(u, E)
        history_u, history_f = [], []  # Anderson: recent images G(u) and differences G(u) - u
        for iteration in range(self.max_iterations + 1):  # a loop over local/global iterations
            g = (np.array([Q @ u[a] for a in range(len(u))]) - b) / h2 - Jd  # the gradient of Phi at u
            if np.linalg.norm(g) <= self.tol * scale:
                self.counts.append(iteration)
                return u
            if iteration == self.max_iterations:
                break
            image = self._global(b, Jd, h)
            history_u.append(image.ravel())
            history_f.append((image - u).ravel())
            candidate = image
            if self.anderson and len(history_f) > 1:
                del history_u[:-self.anderson - 1], history_f[:-self.anderson - 1]
                dF = np.diff(np.array(history_f), axis=0).T
                dG = np.diff(np.array(history_u), axis=0).T
                gamma = _least_squares(dF, history_f[-1])
                candidate = (history_u[-1] - dG @ gamma).reshape(u.shape)
            xt[:, free] = candidate
            Jd_c, E_c = self._local(xt)
            phi_c = objective(candidate, E_c)
            if candidate is not image and not phi_c <= phi:  # the safeguard: back to the plain iterate
                xt[:, free] = image
                Jd_c, E_c = self._local(xt)
                phi_c = objective(image, E_c)
                candidate = image
                del history_u[:-1], history_f[:-1]
            u, Jd, phi = candidate, Jd_c, phi_c
        self.counts.append(self.max_iterations)
        raise ConvergenceError(
            f"Prefactored: the residual did not reach tol = {self.tol:g} within max_iterations = "
            f"{self.max_iterations} local/global iterations at t = {t:.6g} s (h = {h:g} s, "
            f"|g| / f = {np.linalg.norm(g) / max(scale, 1e-300):.3g}); raise max_iterations or tol, or "
            "take a smaller time step")


def __getattr__(name):
    """``relax`` lives in :mod:`particles.statics`; importing it from here still works."""
    if name == "relax":
        from .statics import relax

        return relax
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
