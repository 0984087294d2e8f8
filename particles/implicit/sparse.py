"""What the implicit solvers of mass-spring systems share: their base class and sparse linear algebra.

:class:`SpringSolver` is the base of :class:`particles.implicit.BaraffWitkin`
and :class:`particles.implicit.Prefactored`: a solver object (see
:mod:`particles.integrators.solvers`) bound to a :class:`~particles.massspring.MassSpringSystem`,
first order. :func:`free_dofs` and :func:`factorize` are the sparse pieces both use;
:func:`projection_weight` is the local step of :class:`~particles.implicit.Prefactored` for one spring
(its NumPy step and its compiled one, :mod:`particles.implicit.kernels`, both use it).
"""

import numpy as np

from ..integrators.solvers import Solver

__all__ = ["SpringSolver", "free_dofs", "factorize", "projection_weight"]


def projection_weight(L, L0, k):
    """The local step of one spring, ``k d_s`` with ``d_s = L0 (x_i - x_j) / L``, per unit of ``x_i - x_j``: ``k L0 / L``.

    Each spring's energy ``k (L - L0)^2 / 2`` is the least of ``k |x_i - x_j - d|^2 / 2`` over vectors
    ``d`` of length ``L0``; the best ``d`` points along the spring (Liu et al. 2013). A spring of
    length 0 gives 0.
    """
    return k * L0 / np.maximum(L, 1e-300)


class SpringSolver(Solver):
    """A solver object for a mass-spring system: ``solver.step(X, t, h)``, first order.

    Parameters
    ----------
    system : MassSpringSystem
        The system whose springs, masses and pins the solver uses.
    """

    order = 1

    def __init__(self, system):
        if not hasattr(system, "springs"):
            raise ValueError("system must be a MassSpringSystem (with labelled spring sets)")
        super().__init__(system)


def free_dofs(system):
    """Flattened (particle-major) indices of the coordinates of the free particles, and the free particles.

    Parameters
    ----------
    system : ParticleSystem

    Returns
    -------
    dofs : ndarray of int, shape (f d,)
        ``i d + a`` for every free particle ``i`` and coordinate ``a``.
    free : ndarray of int, shape (f,)
        The particles that are not pinned.
    """
    d = system.d
    free = np.setdiff1d(np.arange(system.n), system.pinned)
    return (free[:, None] * d + np.arange(d)).ravel(), free


def factorize(A):
    """Sparse LU of a symmetric positive definite `A`: SuperLU in symmetric mode, minimum degree on ``A + A^T``.

    Parameters
    ----------
    A : sparse matrix, shape (k, k)
        Symmetric positive definite (``M - h D - h^2 K``, ``M + h^2 L`` on the free coordinates).

    Returns
    -------
    scipy.sparse.linalg.SuperLU
        Its ``solve(b)`` solves ``A x = b``.
    """
    import scipy.sparse.linalg
    return scipy.sparse.linalg.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                                    options={"SymmetricMode": True})
