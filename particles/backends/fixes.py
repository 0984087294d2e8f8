"""The fixes at the end of a step, compiled: Provot's projection and a collider's response (numba).

:meth:`particles.constraints.ProvotConstraint.stepper` and
:meth:`particles.collisions.Collider.stepper` call these (through
:func:`particles.backends.kernels_for`) when their backend resolves to numba:
they correct the end state of a step in place, with the results of the NumPy
fixes to rounding. The kernels read C-ordered states (the compiled step's
rows); a NumPy step's Fortran-ordered state is corrected in a C-ordered copy
that is written back (:func:`_rows`), so that each kernel is compiled once,
not once per memory order. What does not change
between steps (the incidence list of the constrained springs, the buffers) is
kept on the fix's object, in ``_compiled``. Importing this module imports
numba.
"""

import contextlib

import numpy as np

from ..collisions.surfaces import Box, Cylinder, Plane, Sphere
from ._collider_kernels import BOX, CYLINDER, PLANE, SPHERE, collider_candidates, collider_resolve
from ._kernels import incidence, pick
from ._provot_kernels import largest, provot_average, provot_end, provot_group, provot_start, provot_strains

__all__ = ["provot", "surface_row", "surface_rows", "collide"]

STRAIN_BLOCKS = 64  # blocks of springs whose largest strains are taken in parallel (a maximum: any order)


def _store(owner):
    """The object's dictionary of compiled-backend data (created on first use)."""
    store = owner.__dict__.get("_compiled")
    if store is None:
        store = owner.__dict__["_compiled"] = {}
    return store


def _buffer(store, name, shape, dtype=np.float64):
    """A kept array of this shape (made anew when the shape changes)."""
    a = store.get(name)
    if a is None or a.shape != shape or a.dtype != dtype:
        a = store[name] = np.empty(shape, dtype=dtype)
    return a


@contextlib.contextmanager
def _rows(X):
    """X (n, 2, d) itself when it is C-ordered, else a C-ordered copy that is written back into X at the end."""
    if X.flags.c_contiguous:
        yield X
        return
    rows = np.ascontiguousarray(X)
    try:
        yield rows
    finally:
        X[...] = rows


def _springs(constraint, n):
    """The constrained springs as the kernels read them: ends, rest lengths, shares, the incidence list."""
    store = _store(constraint)
    key = (n, id(constraint.indices), id(constraint.rest_length), id(constraint.free))
    if store.get("key") != key:
        i, j = (np.ascontiguousarray(constraint.indices[:, c], dtype=np.int64) for c in range(2))
        free = constraint.free
        wi, wj = free[i].astype(float), free[j].astype(float)
        total = wi + wj
        wi = np.divide(wi, total, out=np.zeros_like(wi), where=total > 0)
        wj = np.divide(wj, total, out=np.zeros_like(wj), where=total > 0)
        groups = constraint.groups
        store.update(key=key, i=i, j=j, L0=np.ascontiguousarray(constraint.rest_length, dtype=float), wi=wi, wj=wj,
                     movable=total > 0, free=np.ascontiguousarray(free),
                     incidence=incidence(np.concatenate([i, j]), n, 2, True),
                     groups=None if groups is None else [np.ascontiguousarray(g, dtype=np.int64) for g in groups])
    return store


def provot(constraint, X, h):
    """Provot's projection of the end state X (n, 2, d) in place, velocities corrected; returns (worst, passes).

    The passes of :func:`particles.constraints.provot_projection` (Jacobi
    with averaging, or Gauss-Seidel over the colour groups), each pass a
    compiled strain pass and a compiled correction; a step whose springs
    all hold costs one strain pass.
    """
    with _rows(X) as X_c:
        return _provot(constraint, X_c, h)


def _provot(constraint, X, h):
    """:func:`provot` on a C-ordered X."""
    n, _, d = X.shape
    store = _springs(constraint, n)
    i, j, L0, wi, wj, movable = (store[k] for k in ("i", "j", "L0", "wi", "wj", "movable"))
    s = len(i)
    limit = 1.0 + constraint.max_strain
    stop = constraint.max_strain + constraint.tol + 1e-12  # particles.constraints.provot._ROUNDING
    x0 = _buffer(store, "x0", (n, d))
    bworst = _buffer(store, "worst", (max(1, min(STRAIN_BLOCKS, s // 1024)),))
    jacobi = store["groups"] is None
    c = _buffer(store, "c", (s, d) if jacobi else (0, d))
    too = _buffer(store, "too", (s,) if jacobi else (0,), np.bool_)
    strains = pick(provot_strains, s)
    worst = 0.0
    for passes in range(constraint.iterations + 1):  # a loop over the passes of the projection
        strains(X, i, j, L0, movable, limit, bworst, c, too)
        worst = largest(bworst)
        if worst <= stop or passes == constraint.iterations:
            break
        if passes == 0:  # the positions before the first correction (no pass: nothing moves)
            pick(provot_start, n)(X, x0)
        if jacobi:
            pick(provot_average, s)(X, c, too, wi, wj, store["free"], *store["incidence"])
        else:
            for g in store["groups"]:  # Gauss-Seidel: one colour at a time
                pick(provot_group, len(g))(X, g, i, j, L0, wi, wj, movable, limit)
    if passes:
        pick(provot_end, n)(X, x0, float(h))
    return float(worst), passes


def surface_row(surface):
    """The kind and the numbers of a primitive surface as the collider's kernels read them; None for others.

    Plane: ``n, -n . p``; Sphere: ``c, r, sign``; Box: ``c, half, lo, hi,
    sign``; Cylinder: ``p, a, R, sign, across`` (3 components each, the third
    0 in 2D). Unions, intersections and complements are left to NumPy.
    """
    def padded(v):
        return list(v) + [0.0] * (3 - len(v))

    kind = type(surface)
    if kind is Plane:
        return PLANE, np.array(padded(surface.n) + [-float(surface.n @ surface.point)])
    if kind is Sphere:
        return SPHERE, np.array(padded(surface.center) + [surface.radius, surface.sign])
    if kind is Box:
        return BOX, np.array(padded(surface.center) + padded(surface.half) + padded(surface.lo) + padded(surface.hi)
                             + [surface.sign])
    if kind is Cylinder:  # across: the fixed unit normal on the axis, as Cylinder makes it
        helper = np.eye(3)[np.argmin(np.abs(surface.axis))]
        across = np.cross(surface.axis, helper) / np.linalg.norm(np.cross(surface.axis, helper))
        return CYLINDER, np.array(list(surface.point) + list(surface.axis) + [surface.radius, surface.sign]
                                  + list(across))
    return None


def surface_rows(surfaces):
    """The surfaces as :func:`surface_row` gives them, in one table: ``kinds`` (b,) and ``rows`` (b, 13); or None.

    None when one of them is not a primitive. Rows are padded with zeros to the longest (a box's 13).
    """
    table = [surface_row(s) for s in surfaces]
    if any(r is None for r in table):
        return None
    rows = np.zeros((len(table), 13))
    for b, (_, P) in enumerate(table):  # a loop over the few surfaces
        rows[b, :len(P)] = P
    return np.array([kind for kind, _ in table], dtype=np.int64), rows


def collide(collider, X_old, X, t, h, m, free):
    """The collider's fix of the end state X (n, 2, d) in place; returns the contacts' columns, or None.

    None (nothing done) when the surface is not a primitive. Otherwise
    ``(index, time, point, normal, impulse, friction)`` in the order of
    :meth:`particles.collisions.Collider.collide`: the contacts of each
    bounce, then those of the projection.
    """
    row = surface_row(collider.surface)
    if row is None:
        return None
    kind, P = row
    n, _, d = X.shape
    store = _store(collider)
    flag = _buffer(store, "flag", (n,), np.bool_)
    backtrack = collider.method == "backtrack"
    lipschitz = 0.0 if collider.surface.lipschitz is None else float(collider.surface.lipschitz)
    X_old = np.ascontiguousarray(X_old)
    with _rows(X) as X_c:
        pick(collider_candidates, n)(kind, P, X_old, X_c, free, float(h), backtrack, lipschitz, flag)
        todo = np.flatnonzero(flag)
        slots = collider.max_bounces + 1
        rec = _buffer(store, "rec", (max(len(todo), 16), slots, 1 + 4 * d))
        has = _buffer(store, "has", rec.shape[:2], np.bool_)
        pick(collider_resolve, len(todo))(kind, P, X_old, X_c, todo, m, float(t), float(h), backtrack,
                                          collider.restitution, collider.friction, collider.max_bounces,
                                          collider.samples, lipschitz, rec, has)
    rows = [np.flatnonzero(has[:len(todo), r]) for r in range(slots)]  # a loop over the rounds
    k = np.concatenate(rows)
    r = np.concatenate([np.full(len(q), c) for c, q in enumerate(rows)])
    data = rec[k, r]
    return (todo[k], data[:, 0], *(np.ascontiguousarray(data[:, 1 + a * d:1 + (a + 1) * d]) for a in range(4)))
