"""Graph colouring of constraints: groups of rows that share no particle, for Gauss-Seidel sweeps.

A Gauss-Seidel sweep corrects the constraints of one group at a time; constraints of a group touch
different particles, so their corrections are written at once, without a scatter, with exactly the
result of correcting them one after another. :func:`color_constraints` colours any of them (springs of
Provot's pass, distances and bending of XPBD, contacts of the cloth pipeline) by vectorized Luby rounds;
:func:`check_groups` checks groups given by a user.

References
----------
.. [1] M. Luby, "A simple parallel algorithm for the maximal independent set problem", SIAM Journal on
   Computing 15(4), 1986.
"""

import numpy as np

from .._checks import index_array

__all__ = ["color_constraints", "check_groups"]


def color_constraints(indices, n, seed=0):
    """Split constraints into groups that share no particle (a graph colouring).

    Parameters
    ----------
    indices : array_like of int, shape (s, k)
        The ``k`` particles of each constraint (``k = 2`` for distances,
        ``3`` for bending, ``1`` for attachments, ``4`` for cloth contacts).
    n : int
        Number of particles.
    seed : int
        Seed of the random priorities (the colouring is deterministic for a seed).

    Returns
    -------
    list of ndarray of int
        Row numbers of each group; together they cover every row once.

    Notes
    -----
    Luby's method, vectorized: in each round, every remaining constraint
    whose random priority beats all remaining ones at each of its particles
    joins the group; the rounds repeat until none can join, then the next
    group (colour) starts. Within a group the order does not matter; going
    through the groups in turn is a Gauss-Seidel sweep, which converges much
    faster than correcting all constraints at once.

    Examples
    --------
    >>> [g.tolist() for g in color_constraints([[0, 1], [1, 2], [2, 3]], 4)]
    [[0, 2], [1]]
    """
    a = np.asarray(indices)
    width = a.shape[1] if a.ndim == 2 else 0
    a = index_array(a, "indices", width)
    if len(a) and a.max() >= n:
        raise ValueError(f"indices refer to particle {a.max()} but n = {n}")
    priority = np.random.default_rng(seed).permutation(len(a)).astype(float)
    remaining = np.ones(len(a), dtype=bool)
    groups = []
    while remaining.any():  # a loop over colours
        group = np.zeros(len(a), dtype=bool)
        taken = np.zeros(n, dtype=bool)
        while True:  # Luby's rounds within a colour
            candidate = remaining & ~group & ~taken[a].any(axis=1)
            if not candidate.any():
                break
            best = np.full(n, -1.0)
            for c in range(width):  # a loop over the k particles of a constraint
                np.maximum.at(best, a[candidate, c], priority[candidate])
            wins = candidate & (best[a] == priority[:, None]).all(axis=1)
            group |= wins
            taken[a[wins].ravel()] = True
        groups.append(np.flatnonzero(group))
        remaining &= ~group
    return groups


def check_groups(groups, idx):
    """Colour groups given as a list of row arrays or an int colour per row, checked."""
    s = len(idx)
    if isinstance(groups, np.ndarray) and groups.ndim == 1 and groups.dtype.kind in "iu":
        if groups.shape != (s,) or (s and groups.min() < 0):
            raise ValueError(f"groups given as colours must be {s} integers >= 0, got shape {groups.shape}")
        rows = [np.flatnonzero(groups == c) for c in range(int(groups.max(initial=-1)) + 1)]
        rows = [g for g in rows if len(g)]
    else:
        rows = [np.asarray(g, dtype=np.int64).ravel() for g in groups]
    every = np.sort(np.concatenate(rows)) if rows else np.zeros(0, dtype=np.int64)
    if not np.array_equal(every, np.arange(s)):
        raise ValueError(f"groups must cover every one of the {s} constraints exactly once")
    for g in rows:  # a loop over the colours given: each must be independent
        used = idx[g].ravel()
        if len(np.unique(used)) != len(used):
            raise ValueError("groups must hold constraints that share no particle within each group")
    return rows
