"""Liu et al.'s prefactorized local/global solver of the implicit-Euler step, accelerated and warm-started.

See :mod:`particles.implicit` for both implicit solvers.

References
----------
.. [1] T. Liu, A. W. Bargteil, J. F. O'Brien and L. Kavan, "Fast simulation of
   mass-spring systems", ACM Transactions on Graphics 32(6), 2013.
.. [2] Y. Peng, B. Deng, J. Zhang, F. Geng, W. Qin and L. Liu, "Anderson
   acceleration for geometry optimization and physics simulation", ACM
   Transactions on Graphics 37(4), 2018.
.. [3] H. Wang, "A Chebyshev semi-iterative approach for accelerating
   projective and position-based dynamics", ACM Transactions on Graphics
   34(6), 2015.
"""

import numpy as np

from .._checks import count, positive_number
from ..backends import check_backend, compiled
from ..errors import ConvergenceError
from ..forces.pairs import pair_differences
from ..forces.springs import damped_spring_force
from .acceleration import Anderson, Chebyshev
from .sparse import SpringSolver, factorize, free_dofs, projection_weight

__all__ = ["Prefactored"]


class Prefactored(SpringSolver):
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
        not lower it is replaced by the plain local/global one. 0: no
        Anderson (Chebyshev's if `chebyshev`, else Liu et al.'s plain iteration).
    chebyshev : float
        With ``anderson=0``: Wang's (2015) Chebyshev semi-iterative
        acceleration for this estimate of the plain iteration's spectral
        radius, in [0, 1), with the same safeguard; 0: off. Fewer iterations
        than the plain ones (4x on the hanging stiff cloth at ``rho = 0.95``),
        more than Anderson's, and on a falling, folding cloth (non-convex
        ``Phi``) it stalls short of `tol` where Anderson converges.
    warm_start : bool
        Start each step's iteration from the last step's answer carried over,
        ``x = y + (x_n - y_{n-1})`` (kept if it lowers ``Phi``), instead of
        from ``y``. The correction ``x - y`` (what the springs hold against
        inertia and gravity) changes little from one frame to the next.
    iterations : int, optional
        A fixed number of plain local/global iterations per step, without
        the residual check (Liu et al.'s "about 10"); overrides `tol`,
        `max_iterations` and `anderson`.
    backend : {None, "auto", "numpy", "numba"}, optional
        The iteration's local step, global solves and residual in this NumPy
        code or compiled (:mod:`particles.implicit.compiled_factorization`; None: the
        global choice, see :mod:`particles.backends`). The compiled solves
        run over the same factorization; they agree with NumPy's to
        rounding, and a run to the solver's tolerance.

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
    Anderson's mixing. Compiled (`backend`), the local step also gives the
    residual (``g = M (x - y) / h^2 - F_springs(x)``, no product with the
    matrix) and the triangular solves run over the Cholesky factor of
    SuperLU's symmetric factorization, kept as plain arrays, all three
    coordinates in one pass.

    On the stiff 64 x 64 cloth of ``bench/bench_implicit.py`` at
    ``h = 1/60`` s the warm start cuts Anderson's iterations from about 17 to
    5.3 per step; the compiled global step solves with the Cholesky factor
    ``R`` of the symmetric factorization, one triangle read twice
    (:func:`particles.implicit.compiled_factorization.cholesky_factor`). A
    banded Cholesky after reverse Cuthill-McKee is no faster here: the band
    of that cloth (127 wide) holds 2.6 times the minimum-degree factor's
    entries.

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
    155 (32 x 32) iterations per step on average (from ``y``), where the plain
    iteration needs thousands. Much smaller tolerances are out of reach on
    a folded cloth, whose compressed springs make ``Phi`` non-convex.
    """

    def __init__(self, system, h, tol=0.1, max_iterations=1000, anderson=8, chebyshev=0.0, warm_start=True,
                 iterations=None, backend=None):
        super().__init__(system)
        self._backend = check_backend(backend)
        self._fast = None  # the compiled kernels of this factorization, when the step runs compiled
        if iterations is not None and (isinstance(iterations, bool) or not isinstance(iterations, (int, np.integer))
                                       or iterations < 1):
            raise ValueError(f"iterations must be a positive integer or None, got {iterations!r}")
        self.iterations = None if iterations is None else int(iterations)
        self.tol = positive_number(tol, "tol")
        self.max_iterations = count(max_iterations, "max_iterations", 1)
        self.anderson = count(anderson, "anderson", 0)
        self.chebyshev = float(chebyshev or 0.0)
        if not (np.isfinite(self.chebyshev) and 0.0 <= self.chebyshev < 1.0):
            raise ValueError(f"chebyshev must be a spectral radius estimate in [0, 1) (0: off), got {chebyshev!r}")
        if self.chebyshev and self.anderson:
            raise ValueError("choose one acceleration: chebyshev (a spectral radius) or anderson (a depth), "
                             f"got chebyshev={chebyshev!r} and anderson={anderson!r}")
        self.warm_start = bool(warm_start)
        self._offset = None  # the last step's x - y on the free particles, (d, f): the warm start
        self.counts = []
        self._i = np.concatenate([s.i for s in system.springs.values()])
        self._j = np.concatenate([s.j for s in system.springs.values()])
        self._k = np.concatenate([s.k for s in system.springs.values()])
        self._L0 = np.concatenate([s.rest_length for s in system.springs.values()])
        _, self._free = free_dofs(system)
        self._factor(positive_number(h, "h", "seconds"))

    def _factor(self, h):
        import scipy.sparse
        n, i, j, k = self.system.n, self._i, self._j, self._k
        L = scipy.sparse.coo_matrix(
            (np.concatenate([k, k, -k, -k]), (np.concatenate([i, j, i, j]), np.concatenate([i, j, j, i]))),
            shape=(n, n)).tocsr()
        Q = (scipy.sparse.diags(self.system.m) + h * h * L).tocsc()
        free, pinned = self._free, self.system.pinned
        self._Q_fp = Q[free][:, pinned]
        self._Q_ff = Q[free][:, free].tocsr()
        # a minimum-degree ordering of the symmetric matrix keeps the LU factors sparse
        self._lu = factorize(Q[free][:, free])
        self._kernels = None  # built from the factorization at the first compiled step
        self._offset = None  # an answer for another h is no warm start
        self.h = h

    def step(self, X, t, h):
        """One backward-Euler step from `X` at `t` to ``t + h``: local/global iterations on ``Phi``.

        Minimizes ``Phi(x) = (x - y)^T M (x - y) / (2 h^2) + sum_s k_s (|x_i - x_j| - L0_s)^2 / 2``
        with ``y = x + h v + h^2 M^-1 F_other`` by alternating the local step
        ``d_s = L0_s (x_i - x_j) / |x_i - x_j|`` and the global step
        ``(M + h^2 L) x = M y + h^2 J d`` (the factorized matrix), then sets
        ``v' = (x' - x) / h``. See the class Notes for the symbols.

        Parameters
        ----------
        X : ndarray, shape (n, 2, d)
            Positions (m) and velocities (m/s) of the system's particles. Not modified.
        t : float
            Time, in seconds.
        h : float
            Time step, in seconds, > 0; another `h` than the one the matrix
            was built for refactorizes it.

        Returns
        -------
        ndarray, shape (n, 2, d)
            The state at ``t + h``.

        Raises
        ------
        particles.ConvergenceError
            When the residual does not reach `tol` within `max_iterations`.
        """
        X = self._state(X)
        h = positive_number(h, "h", "seconds")
        if not np.isclose(h, self.h, rtol=1e-12, atol=0.0):
            self._factor(h)
        system, free = self.system, self._free
        self._fast = self._compiled() if compiled(self._backend, system.n) else None
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
        if self._fast is not None:
            self._fast.begin(yt[:, free], h * h)
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

    def _compiled(self):
        """The compiled local step, solves and residual of this factorization (particles.implicit.compiled_factorization)."""
        if self._kernels is None:
            from .compiled_factorization import FactoredKernels  # noqa: PLC0415  (imports numba)
            self._kernels = FactoredKernels(self._lu, self._Q_ff, self._i, self._j, self._k, self._L0,
                                            self.system.m, self._free, self.system.d)
        return self._kernels

    def _local(self, xt):
        """The springs' projections scattered, J d of shape (d, n_free), and their energy sum k (L - L0)^2 / 2."""
        if self._fast is not None:
            return self._fast.local(xt)
        d = pair_differences(xt.T, self._i, self._j)
        L = np.sqrt(np.einsum("as,as->s", d, d))
        d *= projection_weight(L, self._L0, self._k)
        n = self.system.n
        Jd = np.array([np.bincount(self._i, d[a], minlength=n) - np.bincount(self._j, d[a], minlength=n)
                       for a in range(len(d))])  # a loop over the d coordinates
        return Jd[:, self._free], 0.5 * float(np.sum(self._k * (L - self._L0) ** 2))

    def _spring_forces(self, xt):
        """Net spring force on every particle, shape (d, n): J d(x) - L x."""
        d = pair_differences(xt.T, self._i, self._j)
        L = np.sqrt(np.einsum("as,as->s", d, d))
        d *= damped_spring_force(L, self._L0, self._k, 0.0, 0.0) / np.maximum(L, 1e-300)
        n = self.system.n
        return np.array([np.bincount(self._i, d[a], minlength=n) - np.bincount(self._j, d[a], minlength=n)
                         for a in range(len(d))])  # a loop over the d coordinates

    def _global(self, b, Jd, h):
        """Free positions solving (M + h^2 L) x = M y + h^2 J d (pins on the right), shape (d, n_free)."""
        if self._fast is not None:
            return self._fast.solve(b, Jd, h * h)
        return self._lu.solve(np.ascontiguousarray((b + (h * h) * Jd).T)).T

    def _gradient_norm(self, Q, u, b, Jd, h2):
        """|g| with g = (Q u - b) / h^2 - J d, the gradient of Phi at the free positions u (a force, N)."""
        if self._fast is not None:
            return self._fast.gradient_norm(u, b, Jd, h2)
        g = (np.array([Q @ u[a] for a in range(len(u))]) - b) / h2 - Jd  # a loop over the d coordinates
        return float(np.linalg.norm(g))

    def _solve(self, xt, b, y_free, h, scale, t):
        """Accelerated local/global iterations until |g| <= tol f, from the warm start; returns the free positions."""
        free, h2 = self._free, h * h
        m = self.system.m[free]
        Q = self._Q_ff

        def objective(u, E):  # Phi at the free positions u, E the springs' energy there
            r = u - y_free
            return 0.5 * float(np.sum(m * r * r)) / h2 + E

        u = xt[:, free].copy()
        Jd, E = self._local(xt)
        phi = objective(u, E)
        if self.warm_start and self._offset is not None and self._offset.shape == u.shape:
            # the last step's answer x - y moved onto this step's y: kept where it lowers Phi
            xt[:, free] = y_free + self._offset
            Jd_w, E_w = self._local(xt)
            phi_w = objective(xt[:, free], E_w)
            if phi_w <= phi:
                u, Jd, phi = xt[:, free].copy(), Jd_w, phi_w
            else:
                xt[:, free] = u
        if self.anderson:
            mixing = Anderson(self.anderson, u.size)
        elif self.chebyshev:
            mixing = Chebyshev(self.chebyshev)
        else:
            mixing = None
        for iteration in range(self.max_iterations + 1):  # a loop over local/global iterations
            norm = self._gradient_norm(Q, u, b, Jd, h2)  # |g|, g the gradient of Phi at u
            if norm <= self.tol * scale:
                self.counts.append(iteration)
                self._offset = u - y_free
                return u
            if iteration == self.max_iterations:
                break
            image = self._global(b, Jd, h)
            candidate = image if mixing is None else mixing.propose(u, image)
            xt[:, free] = candidate
            Jd_c, E_c = self._local(xt)
            phi_c = objective(candidate, E_c)
            if candidate is not image and not phi_c <= phi:  # the safeguard: back to the plain iterate
                xt[:, free] = image
                Jd_c, E_c = self._local(xt)
                phi_c = objective(image, E_c)
                candidate = image
                mixing.restart(u)
            u, Jd, phi = candidate, Jd_c, phi_c
        self.counts.append(self.max_iterations)
        self._offset = None
        raise ConvergenceError(
            f"Prefactored: the residual did not reach tol = {self.tol:g} within max_iterations = "
            f"{self.max_iterations} local/global iterations at t = {t:.6g} s (h = {h:g} s, "
            f"|g| / f = {norm / max(scale, 1e-300):.3g}); raise max_iterations or tol, or "
            "take a smaller time step")
