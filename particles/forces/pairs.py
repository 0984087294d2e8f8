"""Pair interactions: differences over index pairs, and the per-pair laws of N-body gravity and Lennard-Jones.

:func:`pair_differences` gathers ``x_i - x_j`` over index pairs, per
coordinate on contiguous rows (see CONTRIBUTING.md, "Speed without loops").
:func:`gravitational_pull` and :func:`lennard_jones_virial` are the laws of one
pair: the NumPy passes of :class:`~particles.forces.NBodyGravity` and
:class:`~particles.forces.LennardJones` apply them to whole arrays of pairs,
and their compiled kernels (:mod:`particles.forces.kernels`) inline them, pair
by pair.
"""

import numpy as np

__all__ = ["pair_differences", "gravitational_pull", "integer_power", "lennard_jones_virial"]


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


def gravitational_pull(G, m_i, m_j, r2, eps2):
    """``G m_i m_j / (r^2 + eps^2)^(3/2)``: the force of j on i is this times ``x_j - x_i`` (N/m).

    Parameters
    ----------
    G : float
        Gravitational constant in the model's units.
    m_i, m_j : float or ndarray
        Masses, in kg.
    r2 : float or ndarray
        ``|x_j - x_i|^2``, in m^2 (``inf`` for a particle and itself: no pull).
    eps2 : float
        Plummer softening squared, in m^2.
    """
    s = r2 + eps2
    return G * m_i * m_j / (s * np.sqrt(s))


def integer_power(u, e):
    """``u ** e``, by repeated products when `e` is an integer from 1 to 16 (several times faster than a power)."""
    if e == np.floor(e) and 1 <= e <= 16:
        result = u
        for _ in range(int(e) - 1):  # a loop over the exponent, not the pairs
            result = result * u
        return result
    return u ** e


def lennard_jones_virial(u, k1, k2, p, q):
    """The pair virial ``r f(r) = k1 / r^(m-1) - k2 / r^(n-1)`` from ``u = 1 / r^2``: ``u^q (k1 u^(p-q) - k2)``.

    With ``p = (m - 1) / 2`` and ``q = (n - 1) / 2`` (12-6: ``u^3 (k1 u^3 - k2)``). The force of j on
    i is ``u r f(r) (x_i - x_j)``; ``u = 0`` (a pair beyond the cutoff) gives 0.

    Parameters
    ----------
    u : float or ndarray
        ``1 / r^2``, in 1/m^2.
    k1, k2 : float
        Strengths of the repulsive and attractive terms.
    p, q : float
        Half the exponents of ``r f(r)``, ``(m - 1) / 2`` and ``(n - 1) / 2``.
    """
    u_q = integer_power(u, q)
    u_pq = u_q if p - q == q else integer_power(u, p - q)
    return (k1 * u_pq - k2) * u_q
