"""Vector helpers shared by the library's modules (private to the package).

:func:`unit`, for the two layouts the library uses: columns of a
``(dim, s)`` array (pair differences from :func:`particles.forces.pairs.pair_differences`,
one column per spring or pair) and rows of an ``(n, dim)`` array (gradients
of implicit surfaces, one row per particle); and :func:`rowdot`, the dot
product of rows summed in coordinate order.

The laws of one item written for the NumPy code and the compiled kernels
alike (the closest points of two pieces of cloth, the coplanarity cubic)
take their 3-vectors as tuples ``(x, y, z)``, each component a number (in a
kernel) or an array over the items (in NumPy), and use :func:`vdot`,
:func:`vsub`, :func:`vadd`, :func:`vcross`, :func:`vscale` and
:func:`select`: ``np.where`` on arrays, a plain branch on numbers in a
kernel (:mod:`particles.backends.compile` registers it with numba).
"""

import numpy as np

__all__ = ["unit", "rowdot", "select", "vdot", "vsub", "vadd", "vcross", "vscale", "vselect"]


def unit(d, axis=0):
    """Lengths and unit vectors of the vectors stored along `axis` of `d`; ``u = 0`` where ``L = 0``.

    Parameters
    ----------
    d : ndarray, shape (dim, s) for ``axis=0`` or (n, dim) for ``axis=1``
        The vectors: columns (``axis=0``) or rows (``axis=1``).
    axis : {0, 1}
        The axis along which the components of one vector lie.

    Returns
    -------
    L : ndarray, shape (s,) or (n,)
        Lengths ``|d_k|``.
    u : ndarray, shape of `d`
        ``d_k / |d_k|``, zero for vectors of length zero.

    Examples
    --------
    >>> L, u = unit(np.array([[3.0, 0.0], [4.0, 0.0]]))     # two columns: (3, 4) and (0, 0)
    >>> L.tolist(), u.tolist()
    ([5.0, 0.0], [[0.6, 0.0], [0.8, 0.0]])
    """
    if axis == 0:
        L = np.sqrt(np.einsum("as,as->s", d, d))
        return L, np.divide(d, L, out=np.zeros_like(d), where=L != 0)
    if axis == 1:
        L = np.sqrt(rowdot(d, d))
        return L, np.divide(d, L[:, None], out=np.zeros_like(d), where=L[:, None] != 0)
    raise ValueError(f"axis must be 0 (columns) or 1 (rows), got {axis!r}")


def rowdot(a, b):
    """``a_k . b_k`` for each row k, summed in coordinate order: ``(a_0 b_0 + a_1 b_1) + a_2 b_2``.

    ``np.einsum("ij,ij->i", a, b)`` sums the three products of C-ordered rows
    in another order than those of Fortran-ordered ones (and a one-row array
    is both), so its last bit depends on the layout, and in the collisions
    on which particles share an array; this sum does not (the compiled
    collider of :mod:`particles.backends` sums the same way).

    Parameters
    ----------
    a : ndarray, shape (n, dim)
    b : ndarray, shape (n, dim) or (dim,)

    Returns
    -------
    ndarray, shape (n,)

    Examples
    --------
    >>> rowdot(np.array([[1.0, 2.0, 3.0]]), np.array([1.0, 0.0, 1.0])).tolist()
    [4.0]
    """
    out = a[:, 0] * b[..., 0]
    for k in range(1, a.shape[1]):  # a loop over the dim coordinates
        out += a[:, k] * b[..., k]
    return out


def select(condition, a, b):
    """`a` where `condition` holds, else `b`: ``np.where`` on arrays; in a compiled kernel, a branch on numbers."""
    return np.where(condition, a, b)


def any_of(condition):
    """Whether `condition` holds anywhere: ``np.any`` on arrays; in a compiled kernel, the one bool itself."""
    return bool(np.any(condition))


def vdot(a, b):
    """``a . b`` of 3-tuples, summed in coordinate order (as :func:`rowdot`)."""
    return (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]


def vsub(a, b):
    """``a - b`` of 3-tuples."""
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def vadd(a, b):
    """``a + b`` of 3-tuples."""
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def vcross(a, b):
    """``a x b`` of 3-tuples."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def vscale(s, a):
    """``s a`` of a number (or array) and a 3-tuple."""
    return (s * a[0], s * a[1], s * a[2])


def vselect(condition, a, b):
    """The 3-tuple `a` where `condition` holds, else `b` (:func:`select`, component by component)."""
    return (select(condition, a[0], b[0]), select(condition, a[1], b[1]), select(condition, a[2], b[2]))
