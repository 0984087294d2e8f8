"""Continuous collision detection: when, within a step, a vertex hits a triangle or two edges meet.

A test at the end of a step misses a vertex that passes through a triangle
within the step. Following Provot [1]_ and Bridson, Fedkiw and Anderson [2]_,
every vertex moves on a straight line during the step,
``x(t) = x0 + t dx`` for ``t`` in [0, 1] (``dx = h vbar``, the step's average
velocity), and the test asks whether four points become coplanar while they
touch:

1. **Candidates.** The box swept by each vertex, edge and face over the step,
   inflated by a pad, is put in a bucket grid (:func:`particles.intersections.box_pairs`);
   only vertex-face and edge-edge pairs whose boxes overlap are tested.
   Pairs that share a vertex (a vertex of the face, two edges with a common
   end) touch by construction and are left out. A bucket grid rather than a
   bounding-volume hierarchy: the cloth's triangles all have about the same
   size, so a grid of that size costs O(n) to build every step, without a
   tree to refit.
2. **Coplanarity cubic.** Four points ``x_0 .. x_3`` (vertex and face, or
   the two edges) are coplanar when the volume
   ``f(t) = (x_1 - x_0) . ((x_2 - x_0) x (x_3 - x_0))`` vanishes. With
   ``p_i = x_i - x_0`` and ``q_i = dx_i - dx_0`` it is the cubic
   ``f(t) = a t^3 + b t^2 + c t + d`` with
   ``d = [p_1 p_2 p_3]``, ``c = [q_1 p_2 p_3] + [p_1 q_2 p_3] + [p_1 p_2 q_3]``,
   ``b = [q_1 q_2 p_3] + [q_1 p_2 q_3] + [p_1 q_2 q_3]``, ``a = [q_1 q_2 q_3]``
   (``[u v w] = u . (v x w)``).
3. **Roots, robustly.** A pair whose Bernstein coefficients on [0, 1] all
   have one sign (beyond a tolerance) has no root and is dropped. Otherwise
   [0, 1] is split at the roots of ``f'`` (a quadratic, in closed form),
   where ``f`` is monotone on every piece; a piece whose ends have opposite
   signs (or an end within the tolerance of zero) holds exactly one root,
   found by bisection to the last bits of ``t``. No polynomial solver and no
   loop over pairs: all pieces of all pairs bisect together.
4. **Touching.** At each root, in order, the closest points of the pair
   (:mod:`particles.proximity`) decide: a collision when they are closer than
   a tolerance ``eta``. The first such root is the time of impact; the
   normal there is the face's normal, or ``d_1 x d_2`` of the edges, oriented
   against the relative motion.

A pair that stays coplanar during the whole step (``f`` within the tolerance
of zero everywhere: a flat sheet moving in its plane) is tested at the end of
the step only; motion within a common plane is left to the proximity
repulsion of :mod:`particles.clothcollisions`, which keeps pairs a thickness
apart before that can happen.

References
----------
.. [1] X. Provot, "Collision and self-collision handling in cloth model
   dedicated to design garments", Graphics Interface 1997, 177-189
   (the coplanarity cubic, impact zones).
.. [2] R. Bridson, R. Fedkiw and J. Anderson, "Robust treatment of collisions,
   contact and friction for cloth animation", ACM Transactions on Graphics
   21(3) (SIGGRAPH 2002), 594-603, section 7.
"""

import numpy as np

from ._checks import as_float_array, nonnegative_number, positive_number
from ._sweep import (BISECTIONS, F_TOL, Impacts, candidate_pairs, cubic_coefficients, detect_pairs, first_contacts,
                     overlapping, unit_roots)
from .mesh import TriangleMesh

__all__ = ["cubic_roots", "coplanarity_cubic", "Impacts", "candidates", "overlapping", "first_contact", "detect",
           "BISECTIONS", "F_TOL"]


def coplanarity_cubic(x, dx):
    """Coefficients ``(a, b, c, d)`` of ``f(t) = [x_1 - x_0, x_2 - x_0, x_3 - x_0](t)``.

    Parameters
    ----------
    x, dx : array_like, shape (k, 4, 3)
        Positions of the four points at ``t = 0`` and their displacements over
        the step, in metres.

    Returns
    -------
    ndarray, shape (k, 4)
        ``a, b, c, d`` (m^3) with ``f(t) = a t^3 + b t^2 + c t + d``.

    Examples
    --------
    A vertex 1 m above a triangle, falling 2 m: coplanar half-way.

    >>> x = [[[0.2, 0.2, 1.0], [0.0, 0, 0], [1.0, 0, 0], [0.0, 1, 0]]]
    >>> dx = [[[0.0, 0.0, -2.0], [0.0, 0, 0], [0.0, 0, 0], [0.0, 0, 0]]]
    >>> coplanarity_cubic(x, dx).round(12).tolist()
    [[0.0, 0.0, 2.0, -1.0]]
    """
    x = as_float_array(x, "x", ndim=3)
    dx = as_float_array(dx, "dx", shape=x.shape)
    if x.shape[1:] != (4, 3):
        raise ValueError(f"x must have shape (k, 4, 3), got shape {x.shape}")
    return cubic_coefficients(x, dx)


def cubic_roots(coef, ftol=0.0):
    """Roots in [0, 1] of the cubics ``a t^3 + b t^2 + c t + d``, one row per cubic.

    Parameters
    ----------
    coef : array_like, shape (k, 4)
        ``a, b, c, d`` of each cubic (any of them may be zero).
    ftol : float or array_like, shape (k,)
        ``|f| <= ftol`` counts as zero: an end of a monotone piece within it
        is a root (a touching double root is then found too).

    Returns
    -------
    ndarray, shape (k, 3)
        The roots of each cubic in [0, 1], ascending, ``nan`` where there are
        fewer than three; one per monotone piece, so a root where two pieces
        meet may be listed twice. A cubic that is zero everywhere (within
        `ftol`) gives ``0`` (and the further pieces' ends).

    Examples
    --------
    >>> r = cubic_roots([[1.0, -1.5, 0.56, -0.06], [0.0, 0.0, 1.0, -2.0]])   # (t-.2)(t-.3)(t-1); t - 2
    >>> np.round(r, 12).tolist()
    [[0.2, 0.3, 1.0], [nan, nan, nan]]
    """
    coef = as_float_array(coef, "coef", ndim=2)
    if coef.shape[1] != 4:
        raise ValueError(f"coef must have shape (k, 4), got shape {coef.shape}")
    ftol = np.broadcast_to(as_float_array(ftol, "ftol", ndim=(0, 1)), (len(coef),))
    if np.any(ftol < 0):
        raise ValueError("ftol must be >= 0")
    return unit_roots(coef, ftol)


def candidates(mesh, x0, x1, pad=0.0, vertices=None):
    """Vertex-face and edge-edge pairs whose boxes, swept over the step and inflated by `pad`, overlap.

    Parameters
    ----------
    mesh : TriangleMesh
        The cloth's connectivity.
    x0, x1 : array_like, shape (n, 3)
        Positions at the start and the end of the step, in metres.
    pad : float
        Added on every side of every box, in metres (>= 0): pairs that may
        come closer than ``2 pad`` during the step are among the candidates.
    vertices : array_like of bool, shape (n,), optional
        Only pairs with at least one of these vertices (the ones whose motion
        changed since the last search).

    Returns
    -------
    vf : ndarray of int64, shape (p, 4)
        ``(vertex, a, b, c)``: vertices and faces that share no vertex.
    ee : ndarray of int64, shape (q, 4)
        ``(p_1, p_2, q_1, q_2)``: edge pairs that share no vertex, each once.
    """
    if not isinstance(mesh, TriangleMesh):
        raise ValueError(f"mesh must be a particles.mesh.TriangleMesh, got {type(mesh).__name__}")
    x0 = as_float_array(x0, "x0", shape=(mesh.n, 3))
    x1 = as_float_array(x1, "x1", shape=(mesh.n, 3))
    pad = nonnegative_number(pad, "pad", "metres")
    if vertices is not None:
        vertices = np.asarray(vertices)
        if vertices.shape != (mesh.n,) or vertices.dtype != bool:
            raise ValueError(f"vertices must be a boolean mask of shape ({mesh.n},), got {vertices.dtype} "
                             f"{vertices.shape}")
    return candidate_pairs(mesh, x0, x1, pad, vertices)


def first_contact(x, dx, edge, eta):
    """Time of first contact of vertex-face (or edge-edge) pairs moving linearly over a step.

    Parameters
    ----------
    x, dx : array_like, shape (k, 4, 3)
        Positions at the start of the step and displacements over it, in
        metres: ``(p, a, b, c)`` for a vertex and a face, ``(p_1, p_2, q_1, q_2)``
        for two edges.
    edge : bool
        Edge-edge pairs (else vertex-face).
    eta : float
        A root of the coplanarity cubic is a contact when the pair is closer
        than `eta` there, in metres (> 0).

    Returns
    -------
    Impacts
        One row per pair that touches during the step, with ``vertices`` the
        row numbers ``(r, r, r, r)`` of the pair in `x` (callers replace them
        with mesh vertices).

    Examples
    --------
    A vertex falling through a triangle, and one passing beside it:

    >>> x = [[[0.2, 0.2, 1.0], [0.0, 0, 0], [1.0, 0, 0], [0.0, 1, 0]],
    ...      [[2.0, 2.0, 1.0], [0.0, 0, 0], [1.0, 0, 0], [0.0, 1, 0]]]
    >>> dx = np.zeros((2, 4, 3)); dx[:, 0, 2] = -4.0
    >>> hits = first_contact(x, dx, edge=False, eta=1e-9)
    >>> hits.time.round(12).tolist(), hits.vertices[:, 0].tolist(), hits.normal.tolist()
    ([0.25], [0], [[0.0, 0.0, 1.0]])
    """
    x = as_float_array(x, "x", ndim=3)
    dx = as_float_array(dx, "dx", shape=x.shape)
    if x.shape[1:] != (4, 3):
        raise ValueError(f"x must have shape (k, 4, 3), got shape {x.shape}")
    return first_contacts(x, dx, bool(edge), positive_number(eta, "eta", "metres"))


def detect(mesh, x0, dx, eta, pad=None, vertices=None):
    """Every vertex-face and edge-edge contact of a mesh moving linearly by `dx` over a step.

    Parameters
    ----------
    mesh : TriangleMesh
    x0, dx : array_like, shape (n, 3)
        Positions at the start of the step and displacements, in metres.
    eta : float
        Contact tolerance, in metres (see :func:`first_contact`).
    pad : float, optional
        Box inflation (default `eta`).
    vertices : array_like of bool, shape (n,), optional
        Only pairs with one of these vertices.

    Returns
    -------
    Impacts
        With mesh vertex indices; vertex-face rows first.

    Examples
    --------
    Two triangles, one falling through the other within the step:

    >>> mesh = TriangleMesh([[0, 1, 2], [3, 4, 5]])
    >>> x0 = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 0.5], [1.2, 0.2, 0.5], [0.2, 1.2, 0.5]])
    >>> dx = np.zeros((6, 3)); dx[3:, 2] = -1.0
    >>> hits = detect(mesh, x0, dx, eta=1e-9)
    >>> hits.vertices.tolist(), hits.time.round(12).tolist()   # vertex 3 hits the face; edge 1-2 meets two edges
    ([[3, 0, 1, 2], [1, 2, 3, 4], [1, 2, 3, 5]], [0.5, 0.5, 0.5])
    """
    eta = positive_number(eta, "eta", "metres")
    pad = eta if pad is None else nonnegative_number(pad, "pad", "metres")
    if not isinstance(mesh, TriangleMesh):
        raise ValueError(f"mesh must be a particles.mesh.TriangleMesh, got {type(mesh).__name__}")
    x0 = np.ascontiguousarray(as_float_array(x0, "x0", shape=(mesh.n, 3)))
    dx = np.ascontiguousarray(as_float_array(dx, "dx", shape=(mesh.n, 3)))
    vf, ee = candidates(mesh, x0, x0 + dx, pad, vertices)
    return detect_pairs(x0, dx, vf, ee, eta)
