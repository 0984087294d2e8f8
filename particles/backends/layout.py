"""The layouts the compiled kernels share: per-particle incidence lists in compressed rows, C-ordered states.

A kernel that sums, for each particle, the terms of the items (springs,
joints, constraints) that touch it writes each particle's sum from one
thread, in a fixed order, through these lists: the same bits on any number
of threads, without atomic additions. They are built once per set of items,
in NumPy.
"""

import contextlib

import numpy as np

__all__ = ["incidence", "c_ordered", "kept_array"]


def incidence(rows, n, width, by_item):
    """Compressed rows of the entries ``rows`` (shape (width s,)): entry ``e`` is item ``e % s`` in role ``e // s``.

    Parameters
    ----------
    rows : array_like of int, shape (width s,)
        The particle of each entry: the first particles of the ``s`` items, then the second ones, ...
    n : int
        Number of particles.
    width : int
        Particles per item (2 for springs, 3 for bending joints).
    by_item : bool
        Each particle's entries in increasing item (the order of a sorted sparse matrix's row, or of a
        loop over the items that adds each one's terms), else by role, then item (the order of one
        ``np.bincount`` per role).

    Returns
    -------
    ptr : ndarray of int64, shape (n + 1,)
    col : ndarray of int64, shape (width s,)
        The entries of particle ``p`` are ``col[ptr[p]:ptr[p + 1]]``.

    Examples
    --------
    >>> ptr, col = incidence([0, 1, 1, 2], 3, 2, True)     # springs (0, 1) and (1, 2)
    >>> ptr.tolist(), col.tolist()
    ([0, 1, 3, 4], [0, 2, 1, 3])
    """
    rows = np.asarray(rows, dtype=np.int64)
    s = len(rows) // width
    entries = np.arange(len(rows), dtype=np.int64)
    if by_item:  # k = item width + role lists entry role s + item
        entries = (entries % width) * s + entries // width
    col = entries[np.argsort(rows[entries], kind="stable")]
    ptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=n), out=ptr[1:])
    return ptr, col


@contextlib.contextmanager
def c_ordered(X):
    """X itself when it is C-ordered, else a C-ordered copy that is written back into X at the end.

    A kernel that walks a state ``X`` of shape (n, 2, d) row by row reads it
    in place; a view (a slice, a transpose) is copied in and out once.
    """
    if X.flags.c_contiguous:
        yield X
        return
    rows = np.ascontiguousarray(X)
    try:
        yield rows
    finally:
        X[...] = rows


def kept_array(store, name, shape, dtype=np.float64):
    """The array ``store[name]`` of this shape and dtype, made anew (uninitialised) when either changed.

    ``store`` is a dict an object keeps for its kernels' work arrays, so that
    a step allocates nothing once the sizes are known.
    """
    a = store.get(name)
    if a is None or a.shape != shape or a.dtype != dtype:
        a = store[name] = np.empty(shape, dtype=dtype)
    return a
