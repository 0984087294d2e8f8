"""Pair kernels: differences over index pairs, and Newton's third law for pair forces.

Every pair interaction of the library (springs, N-body gravity,
Lennard-Jones, boids, Provot's constraint, self-collision) gathers
``x_i - x_j`` over its index pairs with :func:`pair_differences` and, when it
is a force, scatters ``+f_ij`` to ``i`` and ``-f_ij`` to ``j`` with
:func:`scatter_pair_forces`, so that the total momentum is conserved to
round-off. Both work per coordinate on contiguous rows (see CONTRIBUTING.md,
"Speed without loops").
"""

import numpy as np

__all__ = ["pair_differences", "scatter_pair_forces"]


def pair_differences(x, i, j):
    """``x[i] - x[j]`` for each pair, as an array of shape (d, p).

    One row per axis: gathering from the contiguous columns of ``x`` is
    several times faster than fancy-indexing rows of an (n, d) array.

    Parameters
    ----------
    x : ndarray, shape (n, d)
        Positions, in metres.
    i, j : ndarray of int, shape (p,)
        The two particles of each pair, valid indices into `x` (not checked:
        this runs inside every force evaluation).

    Returns
    -------
    ndarray, shape (d, p)
        Column ``k`` is ``x[i[k]] - x[j[k]]``, in metres (the transpose of
        ``x[i] - x[j]``).

    Examples
    --------
    >>> import numpy as np
    >>> pair_differences(np.array([[0.0, 0.0], [1.0, 2.0]]), np.array([1]), np.array([0]))
    array([[1.],
           [2.]])
    """
    xt = np.ascontiguousarray(x.T)
    d = np.empty((xt.shape[0], len(i)))
    x_j = np.empty(len(i))
    for a, xa in enumerate(xt):  # a loop over the d coordinates
        np.take(xa, i, out=d[a], mode="clip")  # "clip": unbuffered, indices are valid
        np.take(xa, j, out=x_j, mode="clip")
        d[a] -= x_j
    return d


def scatter_pair_forces(F, i, j, f_ij):
    """Add ``f_ij`` to particles ``i`` and ``-f_ij`` to particles ``j``.

    Parameters
    ----------
    F : ndarray, shape (n, d)
        Force array, updated in place.
    i, j : ndarray of int, shape (p,)
        The two particles of each pair.
    f_ij : ndarray, shape (p, d)
        Force on ``i`` due to ``j``; ``j`` receives the opposite (Newton's
        third law), so the total momentum is conserved to round-off. The
        transpose of a (d, p) array is fastest (contiguous columns).

    Notes
    -----
    ``np.bincount`` sums the contributions of all pairs sharing a particle
    without a Python loop (``F[i] += f`` would drop repeated indices).
    """
    n = len(F)
    for a in range(F.shape[1]):  # a loop over the d coordinates
        F[:, a] += np.bincount(i, f_ij[:, a], minlength=n) - np.bincount(j, f_ij[:, a], minlength=n)
