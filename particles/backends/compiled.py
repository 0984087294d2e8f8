"""The numba backend: the force modules' hooks call these, which prepare plain arrays and run the kernels.

What does not change between evaluations (a spring set's incidence list, a
Verlet list sorted by particle, a batch's coefficients) is built once and kept on
the object, in a private attribute ``_compiled``. Importing this module
imports numba; :func:`particles.backends.kernels_for` does so only when a
pass resolves to numba.
"""

import numpy as np

from ._kernels import add_windows, bending_forces, gather_pairs, gather_roles
from ._kernels import incidence, parallel, pick, rank_blocks, spring_forces, spring_scatter, take_rows
from ._kernels import lennard_jones as lennard_jones_pairs
from ._kernels import nbody as nbody_sums
from ._pbd_kernels import distance_group, distance_jacobi

__all__ = ["springs", "bending", "lennard_jones", "nbody", "distance_project"]


def _store(owner):
    """The object's dictionary of compiled-backend data (created on first use)."""
    store = owner.__dict__.get("_compiled")
    if store is None:
        store = owner.__dict__["_compiled"] = {}
    return store


def _incidence(owner, columns, n, by_item):
    """Compressed-row incidence of the index arrays `columns` (roles) over `n` particles, kept on `owner`."""
    store = _store(owner)
    key = (n, tuple(id(c) for c in columns), len(columns[0]))
    if store.get("incidence_key") != key:
        rows = np.concatenate(columns).astype(np.int64)
        store["incidence"] = incidence(rows, n, len(columns), by_item)
        store["incidence_key"] = key
    return store["incidence"]


def _float_rows(a):
    """`a` as the (n, d) float64 array the kernels read (no copy when it already is one)."""
    return np.asarray(a, dtype=np.float64)


# the two-pass parallel spring pass writes and reads every spring's force once more than the one-thread
# scatter: it pays from about this many threads (on two it was slower, bench/bench_backends.py)
SPRING_THREADS = 4


def springs(force, F, x, v):
    """:meth:`particles.springs.Springs.add_to`, compiled.

    One pass on one thread (each spring's force added to both particles),
    or, on SPRING_THREADS threads or more, forces per spring in parallel and
    then each particle's sum gathered through the incidence list: the same
    bits either way (each particle's sum runs in increasing spring order).
    """
    s = len(force.i)
    x = _float_rows(x)
    v = x if v is None or not np.any(force.kd) else _float_rows(v)  # v is read only for damped springs
    if not parallel(s, SPRING_THREADS):
        S = np.zeros_like(F)
        spring_scatter(S, x, v, force.i, force.j, force.rest_length, force.k, force.kd)
        F += S
        return
    ptr, col = _incidence(force, (force.i, force.j), len(F), True)
    store = _store(force)
    f = store.get("f")
    if f is None or f.shape != (s, x.shape[1]):
        f = store["f"] = np.empty((s, x.shape[1]))
    pick(spring_forces, s)(x, v, force.i, force.j, force.rest_length, force.k, force.kd, f)
    pick(gather_pairs, s)(F, f, ptr, col, s)


def bending(force, F, x):
    """:meth:`particles.springs.Bending.add_to`, compiled: forces per joint, gathered per particle and role."""
    b = len(force.i)
    x = _float_rows(x)
    ptr, col = _incidence(force, (force.i, force.j, force.l), len(F), False)
    store = _store(force)
    g = store.get("g")
    if g is None or g.shape != (3, b, x.shape[1]):
        g = store["g"] = np.empty((3, b, x.shape[1]))
    pick(bending_forces, b)(x, force.i, force.j, force.l, force.kb, force.rest_angle, g)
    pick(gather_roles, b)(F, g, ptr, col, b)


def lennard_jones(force, F, x, perm, i, j, box):
    """:meth:`particles.lennardjones.LennardJones.add_to` on its Verlet list, compiled; returns the virial.

    The list sorted by first rank (again only when it is rebuilt) and cut
    into a fixed number of blocks of ranks (set by the particle count, not
    the threads); blocks run in parallel, each summing its pairs' forces,
    both ends, into its own window of ranks; the windows are then added in
    block order. Each pair is computed once, and the result has the same
    bits for any number of threads.
    """
    n, d = x.shape
    store = _store(force)
    if store.get("pairs") is not i or store.get("n") != n:
        blocks = int(min(64, max(1, n // 4096)))  # blocks of about 4k ranks: windows about twice as wide
        ptr, nbr, start, lo, hi = rank_blocks(i.astype(np.int64), j.astype(np.int64), n, blocks)
        offset = np.concatenate([[0], np.cumsum((hi - lo) * d)]).astype(np.int64)
        store.update(pairs=i, n=n, lists=(ptr, nbr, start), windows=(lo, hi, offset), sums=np.empty(offset[-1]),
                     virials=np.empty(blocks))
    (ptr, nbr, start), (lo, hi, offset) = store["lists"], store["windows"]
    xs = np.empty((n, d))
    take_rows(_float_rows(x), perm, xs)
    periodic = box is not None
    L = np.asarray(box, dtype=float) if periodic else np.ones(d)
    p, q = (force.m_exp - 1) / 2, (force.n_exp - 1) / 2
    pick(lennard_jones_pairs, len(i))(xs, ptr, nbr, start, lo, offset, force.k1, force.k2, p, q, force.cutoff**2, L,
                                      periodic, store["sums"], store["virials"])
    add_windows(F, perm, lo, hi, offset, store["sums"])
    return float(sum(store["virials"].tolist()))  # block after block


def nbody(force, F, x, m):
    """:meth:`particles.nbody.NBodyGravity.add_to`, compiled: one thread per particle over all others."""
    m = np.ascontiguousarray(m, dtype=np.float64)
    pick(nbody_sums, len(x) ** 2)(F, _float_rows(x), m, force.G, force.softening**2)


def _batch_arrays(constraints, b, hs, formulation):
    """The per-row arrays of a batch for substeps of `hs` (kept on the batch until `hs` changes)."""
    constraints._coefficients(hs, b, formulation)
    store = _store(b)
    key = (hs, formulation)
    if store.get("key") != key:
        r = len(b.idx)
        rows = b.rows if not isinstance(b.rows, slice) else np.arange(len(constraints))[b.rows]
        store["rows"] = np.ascontiguousarray(rows, dtype=np.int64)
        store["ij"] = np.ascontiguousarray(b.idx[:, 0]), np.ascontiguousarray(b.idx[:, 1])
        store["coefficients"] = tuple(np.ascontiguousarray(np.broadcast_to(np.asarray(c, dtype=float), (r,)))
                                      for c in (b.at, b.inv, b.gamma))
        store["scale"] = None if b.scale is None else np.ascontiguousarray(b.scale, dtype=float)
        store["key"] = key
    return store


def distance_project(constraints, b, x, x_n, lam, hs, formulation):
    """:meth:`particles.pbdconstraints.Distance.project` of batch `b`, compiled, on x (d, n) in place."""
    store = _batch_arrays(constraints, b, hs, formulation)
    i, j = store["ij"]
    at, inv, gamma = store["coefficients"]
    xpbd, damped = formulation == "xpbd", bool(b.damped and formulation == "xpbd")
    if store["scale"] is None:  # a colour group: no particle twice, corrections written directly
        group = pick(distance_group, len(i))
        group(x, x_n, lam, store["rows"], i, j, b.L0, b.wi, b.wj, at, inv, gamma, xpbd, damped)
        return
    buffers = store.get("buffers")
    if buffers is None or buffers[0].shape != x.shape:
        buffers = store["buffers"] = np.empty(x.shape), np.empty(x.shape)
    distance_jacobi(x, x_n, lam, i, j, b.L0, b.wi, b.wj, at, inv, gamma, store["scale"], xpbd, damped, *buffers)
