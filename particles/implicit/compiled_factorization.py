"""The prefactorized solver's iteration, compiled: the local step, the global step's solves and the residual.

:class:`particles.implicit.Prefactored` with the numba backend calls these in
place of its NumPy methods; the Anderson-accelerated iteration around them is
the same code. What does not change between iterations (the spring arrays,
the Cholesky factor from SuperLU's symmetric factorization as plain arrays
(:func:`cholesky_factor`), the matrix ``M + h^2 L`` in CSR) is built once per factorization, in :class:`FactoredKernels`. Importing this module
imports numba; :class:`~particles.implicit.Prefactored` imports it when its
backend resolves to numba (:func:`particles.backends.compiled`).

References
----------
.. [1] T. Liu, A. W. Bargteil, J. F. O'Brien and L. Kavan, "Fast simulation of
   mass-spring systems", ACM Transactions on Graphics 32(6), 2013.
"""

import numpy as np
import scipy.sparse

from .kernels import global_step, gradient_norm, local_step

__all__ = ["FactoredKernels", "cholesky_factor"]


def cholesky_factor(lu):
    """The Cholesky factor ``R`` (upper) of an SPD ``Q`` from SuperLU's symmetric factorization, in CSR parts.

    With symmetric mode and diagonal pivots, ``P Q P^T = L U`` with ``U = D L^T`` (``D`` U's diagonal), so
    ``P Q P^T = R^T R`` with ``R = D^(-1/2) U``: one triangle instead of two.

    Parameters
    ----------
    lu : scipy.sparse.linalg.SuperLU
        From :func:`particles.implicit.sparse.factorize` (``perm_r == perm_c``).

    Returns
    -------
    perm : ndarray of int64, shape (f,)
        The permutation ``P`` (SuperLU's ``perm_c``).
    Rp, Rj : ndarray of int32
        R's strictly upper part: row pointers and column indices.
    Rx : ndarray, shape (nnz,)
        Its values.
    Rd : ndarray, shape (f,)
        R's diagonal, ``sqrt(D)``.

    Raises
    ------
    ValueError
        If the factorization pivoted off the diagonal or ``D`` is not positive (not an SPD matrix's).
    """
    if not np.array_equal(lu.perm_r, lu.perm_c):
        raise ValueError("lu must be a symmetric factorization (perm_r == perm_c), as factorize() makes")
    U = scipy.sparse.csr_matrix(lu.U)
    D = U.diagonal()
    if not np.all(D > 0):
        raise ValueError("lu must factorize a symmetric positive definite matrix (U's diagonal > 0)")
    R = scipy.sparse.csr_matrix(scipy.sparse.diags(1.0 / np.sqrt(D)) @ scipy.sparse.triu(U, 1))
    R.sort_indices()
    return (lu.perm_c.astype(np.int64), R.indptr.astype(np.int32), R.indices.astype(np.int32),
            np.ascontiguousarray(R.data), np.sqrt(D))


class FactoredKernels:
    """The compiled local step, global step and residual of one factorization of ``Q = M + h^2 L``.

    Parameters
    ----------
    lu : scipy.sparse.linalg.SuperLU
        The factorization of ``Q`` on the free particles, ``Pr Q Pc = L U``
        (L with a unit diagonal).
    Q : sparse matrix, shape (f, f)
        ``Q`` itself on the free particles (for a residual not computed by the local step).
    i, j : ndarray of int, shape (s,)
        The springs' particles.
    k, L0 : ndarray, shape (s,)
        Stiffnesses (N/m) and rest lengths (m).
    m : ndarray, shape (n,)
        Masses, in kg.
    free : ndarray of int, shape (f,)
        The free particles.
    d : int
        Coordinates, 2 or 3.

    Notes
    -----
    The methods return what :class:`particles.implicit.Prefactored`'s
    ``_local``, ``_global`` and ``_gradient_norm`` return, with NumPy's bits
    for ``J d`` and to rounding (about 1e-15 relative) for the rest: the
    triangular solves run over the Cholesky factor ``R`` (:func:`cholesky_factor`), and the local step
    also computes the norm of the gradient of Phi at its positions, as
    ``M (x - y) / h^2 - F_springs(x)`` (equal to ``(Q x - b) / h^2 - J d``),
    which :meth:`gradient_norm` returns for the ``J d`` it made.
    """

    def __init__(self, lu, Q, i, j, k, L0, m, free, d):
        self.perm, self.Rp, self.Rj, self.Rx, self.Rd = cholesky_factor(lu)
        Q = scipy.sparse.csr_matrix(Q)
        self.Qp, self.Qj, self.Qx = Q.indptr.astype(np.int64), Q.indices.astype(np.int64), Q.data.astype(float)
        self.i, self.j = i.astype(np.int64), j.astype(np.int64)
        self.k, self.L0 = np.ascontiguousarray(k, dtype=float), np.ascontiguousarray(L0, dtype=float)
        self.free = free.astype(np.int64)
        self.m = np.ascontiguousarray(m[free], dtype=float)
        n = len(m)
        self._rows = [np.empty((n, d)) for _ in range(4)]  # scratch of the local step
        self._y = np.empty((len(free), 3))  # scratch of the solves (three columns in 2D too)
        self._inertial, self._h2 = np.zeros((d, len(free))), 1.0
        self._last = (None, np.zeros(1))  # the last J d made, and |g| where it was made

    def begin(self, y, h2):
        """Set the step's inertial positions `y` (d, f) of the free particles and ``h2 = h^2`` (s^2)."""
        self._inertial, self._h2 = np.ascontiguousarray(y, dtype=float), float(h2)

    def local(self, xt):
        """``(J d, E)``: the projections scattered on the free particles (d, f), and the springs' energy (J)."""
        Jd = np.empty((xt.shape[0], len(self.free)))
        norm = np.zeros(1)
        E = local_step(np.ascontiguousarray(xt), self.i, self.j, self.k, self.L0, self.free, self.m,
                       self._inertial, self._h2, *self._rows, Jd, norm)
        self._last = (Jd, norm)
        return Jd, E

    def solve(self, b, Jd, h2):
        """The free positions (d, f) solving ``Q x = b + h2 J d``."""
        out = np.empty_like(b)
        global_step(np.ascontiguousarray(b), np.ascontiguousarray(Jd), h2, self.perm, self.Rp, self.Rj, self.Rx,
                    self.Rd, self._y, out)
        return out

    def gradient_norm(self, u, b, Jd, h2):
        """``|g|``, ``g = (Q u - b) / h2 - J d`` the gradient of Phi at the free positions `u` (d, f), in N.

        From the local step that made `Jd` (at `u`, this step's `y` and `h2`), else by a product with ``Q``.
        """
        made, norm = self._last
        if Jd is made and h2 == self._h2:
            return float(norm[0])
        return gradient_norm(self.Qp, self.Qj, self.Qx, np.ascontiguousarray(u), np.ascontiguousarray(b),
                             np.ascontiguousarray(Jd), h2)
