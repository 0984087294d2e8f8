"""Implicit surfaces ``H(x) = 0``: the solids particles collide with.

A solid is described by one function ``H``: ``H(x) < 0`` inside the solid,
``H(x) = 0`` on its surface, ``H(x) > 0`` in free space. Detecting a
collision is then one evaluation per particle: a particle is inside when
``H`` is negative. The gradient ``grad H`` points out of the solid, so the
unit normal is ``n = grad H / |grad H|``.

The primitives (:class:`Plane`, :class:`Sphere`, :class:`Box`, :class:`Cylinder`) use the
*signed distance*: ``|H(x)|`` is the distance to the surface and
``|grad H| = 1``. They combine like sets:

* ``a | b``, :class:`Union`: ``H = min(H_a, H_b)`` (inside either solid);
* ``a & b``, :class:`Intersection`: ``H = max(H_a, H_b)`` (inside both);
* ``~a``, :class:`Complement`: ``H = -H_a`` (solid and free space swapped,
  e.g. a container).

Every method is vectorized over particles: ``x`` has shape (n, d) (or (d,)
for a single point) and ``d`` is 2 or 3 (a 2D "sphere" is a circle).

References
----------
.. [1] A. Witkin, "Physically Based Modeling: Particle System Dynamics",
   SIGGRAPH 1997 course notes, section "Collisions".
.. [2] J. C. Hart, "Sphere tracing: a geometric method for the antialiased ray
   tracing of implicit surfaces", The Visual Computer 12(10), 527-545, 1996
   (signed distances, their unions and intersections).
"""

import numpy as np

from .._checks import as_float_array, positive_number
from .._vectors import rowdot, unit

__all__ = ["Surface", "Plane", "Sphere", "Box", "Cylinder", "Union", "Intersection", "Complement", "plane_height",
           "round_height", "box_height"]

# A point p counts as on a combined surface when |H(p)| <= _ON_SURFACE * (1 + |p|).
_ON_SURFACE = 1e-9


def plane_height(x0, x1, x2, n0, n1, n2, offset):
    """A plane's ``H = n . x + offset`` (``offset = -n . p``), summed in coordinate order (0 for a 2D point's third).

    The signed distances of the primitives are laws of one point, in its coordinates: the NumPy surfaces
    apply them to columns of points, the compiled collider (:mod:`particles.collisions.collider_kernels`)
    to one point.
    """
    return ((offset + n0 * x0) + n1 * x1) + n2 * x2


def round_height(r0, r1, r2, radius, sign):
    """A sphere's or a cylinder's ``H = sign (|r| - R)``, from the offset ``r`` from its centre or its axis."""
    return sign * (np.sqrt((r0 * r0 + r1 * r1) + r2 * r2) - radius)


def box_height(q0, q1, q2, sign):
    """A box's ``H = sign (|max(q, 0)| + min(max_a q_a, 0))`` from ``q_a = |x_a - c_a| - half_a`` (``-inf`` unused)."""
    m0, m1, m2 = np.maximum(q0, 0.0), np.maximum(q1, 0.0), np.maximum(q2, 0.0)
    return sign * (np.sqrt((m0 * m0 + m1 * m1) + m2 * m2) + np.minimum(np.maximum(np.maximum(q0, q1), q2), 0.0))


def _columns(x):
    """The three coordinates of points `x` (n, d), the third 0 in 2D."""
    return x[:, 0], x[:, 1], x[:, 2] if x.shape[1] == 3 else 0.0


class Surface:
    """Base class of implicit surfaces; subclasses implement ``_H``, ``_gradient``, ``_closest``.

    Attributes
    ----------
    d : int
        Dimension of space (2 or 3).
    lipschitz : float or None
        A bound on ``|grad H|``: 1 for signed distances and their unions,
        intersections and complements. Collision detection uses it to skip
        particles that are too far away to touch the surface within a step;
        a subclass whose ``H`` is not so bounded sets it to None.
    """

    d = None
    lipschitz = 1.0

    def _points(self, x):
        x = as_float_array(x, "x", ndim=(1, 2))
        single = x.ndim == 1
        x2 = x[None, :] if single else x
        if x2.shape[1] != self.d:
            raise ValueError(
                f"x must have shape (n, {self.d}) for this {self.d}D {type(self).__name__}, "
                f"got shape {x.shape}"
            )
        return x2, single

    def H(self, x):
        """The implicit function: negative inside, zero on the surface, positive outside.

        Parameters
        ----------
        x : array_like, shape (n, d) or (d,)
            Points, in metres.

        Returns
        -------
        ndarray, shape (n,) or ()
            For the primitives, the signed distance to the surface, in metres.
        """
        x, single = self._points(x)
        H = self._H(x)
        return H[0] if single else H

    def inside(self, x):
        """``H(x) < 0``: which points are inside the solid; bool, shape (n,) or ()."""
        return self.H(x) < 0

    def gradient(self, x):
        """``grad H``, shape (n, d) or (d,): points out of the solid (unit length for primitives).

        Where ``H`` has a kink (the centre of a sphere, the medial planes of a
        box, where two parts of a union meet) one of the one-sided gradients
        is returned.
        """
        x, single = self._points(x)
        g = self._gradient(x)
        return g[0] if single else g

    def normal(self, x):
        """Unit outward normal ``grad H / |grad H|``, shape (n, d) or (d,)."""
        x, single = self._points(x)
        _, n = unit(self._gradient(x), axis=1)  # rows of zeros stay zero
        return n[0] if single else n

    def closest_point(self, x):
        """The point of the surface ``H = 0`` closest to each point, shape (n, d) or (d,).

        Exact for the primitives. For combinations see :class:`Union`.
        """
        x, single = self._points(x)
        p = self._closest(x)
        return p[0] if single else p

    def crossing(self, x0, x1):
        """Where the segments ``x0 -> x1`` first enter the solid (ray-object intersection).

        Parameters
        ----------
        x0, x1 : array_like, shape (n, d)
            Start (outside, ``H >= 0``) and end points of each segment.

        Returns
        -------
        s : ndarray, shape (n,)
            Fraction of the segment, in [0, 1], at which ``H`` first becomes
            zero: the entry point is ``x0 + s (x1 - x0)``. ``s = 1`` for
            segments that never enter the solid, 0 for ones that start inside.
        """
        x0, _ = self._points(x0)
        x1, _ = self._points(x1)
        if x0.shape != x1.shape:
            raise ValueError(f"x0 and x1 must have the same shape, got {x0.shape} and {x1.shape}")
        from .surface_crossing import first_crossing

        chord = np.sqrt(rowdot(x1 - x0, x1 - x0))  # |dx/ds| on a segment
        return first_crossing(self, lambda idx, s: x0[idx] + s[:, None] * (x1[idx] - x0[idx]),
                              len(x0), speed=chord)[0]

    def __or__(self, other):
        return Union(self, other)

    def __and__(self, other):
        return Intersection(self, other)

    def __invert__(self):
        return Complement(self)


class Plane(Surface):
    """A half-space: the solid lies on the side opposite to `normal`.

    ``H(x) = n . (x - p)`` with ``n`` the unit normal.

    Parameters
    ----------
    point : array_like, shape (d,)
        A point ``p`` of the plane (a line in 2D), in metres.
    normal : array_like, shape (d,)
        Direction pointing out of the solid, into free space (need not be unit).

    Examples
    --------
    >>> floor = Plane([0.0, 0.0], [0.0, 1.0])
    >>> floor.H([[0.0, 2.0], [1.0, -0.5]]).tolist()
    [2.0, -0.5]
    """

    def __init__(self, point, normal):
        self.point = as_float_array(point, "point", ndim=1)
        normal = as_float_array(normal, "normal", shape=self.point.shape)
        if self.point.size not in (2, 3):
            raise ValueError(f"point must have 2 or 3 components, got {self.point.size}")
        if not np.any(normal):
            raise ValueError("normal must be a non-zero vector")
        self.n = normal / np.linalg.norm(normal)
        self.d = self.point.size

    def _H(self, x):
        n = list(self.n) + [0.0] * (3 - self.d)
        return plane_height(*_columns(x), *n, -float(self.n @ self.point))

    def _gradient(self, x):
        return np.broadcast_to(self.n, x.shape).copy(order="F")

    def _closest(self, x):
        H = self._H(x)
        p = np.empty_like(x)
        for a in range(self.d):  # a loop over the d coordinates
            p[:, a] = x[:, a] - H * self.n[a]
        return p

    def __repr__(self):
        return f"Plane(point={self.point.tolist()}, normal={self.n.tolist()})"


class Sphere(Surface):
    """A ball (a disk in 2D), solid or hollow.

    Solid: ``H(x) = |x - c| - r``. Container (``container=True``), particles
    move inside it and the solid is everything outside: ``H(x) = r - |x - c|``.

    Parameters
    ----------
    center : array_like, shape (d,)
        ``c``, in metres.
    radius : float
        ``r``, in metres, > 0.
    container : bool
        Whether the particles live inside the sphere.

    Examples
    --------
    >>> ball = Sphere([0.0, 0.0, 0.0], 1.0)
    >>> ball.H([[0.0, 0.0, 3.0], [0.5, 0.0, 0.0]]).tolist()
    [2.0, -0.5]
    >>> ball.closest_point([0.0, 0.0, 3.0]).tolist()
    [0.0, 0.0, 1.0]
    """

    def __init__(self, center, radius, container=False):
        self.center = as_float_array(center, "center", ndim=1)
        if self.center.size not in (2, 3):
            raise ValueError(f"center must have 2 or 3 components, got {self.center.size}")
        self.radius = positive_number(radius, "radius", "metres")
        self.container = bool(container)
        self.sign = -1.0 if self.container else 1.0
        self.d = self.center.size

    def _offsets(self, x):
        """``x - c`` and ``|x - c|``."""
        r = np.empty_like(x)
        for a in range(self.d):  # a loop over the d coordinates
            r[:, a] = x[:, a] - self.center[a]
        return r, np.sqrt(rowdot(r, r))

    def _directions(self, x):
        """Unit vectors from the centre; the centre itself gets the first axis."""
        r, dist = self._offsets(x)
        at_centre = dist == 0
        r[at_centre, 0], dist[at_centre] = 1.0, 1.0
        for a in range(self.d):  # a loop over the d coordinates
            r[:, a] /= dist
        return r

    def _H(self, x):
        r, _ = self._offsets(x)
        return round_height(*_columns(r), self.radius, self.sign)

    def _gradient(self, x):
        g = self._directions(x)
        g *= self.sign
        return g

    def _closest(self, x):
        u = self._directions(x)
        for a in range(self.d):  # a loop over the d coordinates
            u[:, a] = self.center[a] + self.radius * u[:, a]
        return u

    def __repr__(self):
        return f"Sphere(center={self.center.tolist()}, radius={self.radius}, container={self.container})"


class Box(Surface):
    """An axis-aligned box, solid or hollow, with its exact signed distance.

    With ``q_a = |x_a - c_a| - half_a`` (``c`` the centre, ``half`` the
    half-widths): ``H = |max(q, 0)| + min(max_a q_a, 0)``, the distance to
    the box outside and minus the distance to the nearest face inside.

    Parameters
    ----------
    lo, hi : array_like, shape (d,)
        Opposite corners, in metres, ``lo < hi`` along every axis.
    container : bool
        Whether the particles live inside the box (its walls keep them in).

    Examples
    --------
    >>> box = Box([0.0, 0.0], [2.0, 1.0])
    >>> box.H([[1.0, 0.5], [3.0, 0.5], [5.0, 5.0]]).tolist()
    [-0.5, 1.0, 5.0]
    """

    def __init__(self, lo, hi, container=False):
        self.lo = as_float_array(lo, "lo", ndim=1)
        self.hi = as_float_array(hi, "hi", shape=self.lo.shape)
        if self.lo.size not in (2, 3):
            raise ValueError(f"lo must have 2 or 3 components, got {self.lo.size}")
        if np.any(self.hi <= self.lo):
            raise ValueError(f"hi must exceed lo along every axis, got lo={self.lo.tolist()}, hi={self.hi.tolist()}")
        self.center, self.half = (self.lo + self.hi) / 2, (self.hi - self.lo) / 2
        self.container = bool(container)
        self.sign = -1.0 if self.container else 1.0
        self.d = self.lo.size

    def _q(self, x):
        """``q_a = |x_a - c_a| - half_a`` and the signs of ``x_a - c_a``, shape (n, d)."""
        q, side = np.empty_like(x), np.empty_like(x)
        for a in range(self.d):  # a loop over the d coordinates
            r = x[:, a] - self.center[a]
            side[:, a] = np.where(r < 0, -1.0, 1.0)
            q[:, a] = np.abs(r) - self.half[a]
        return q, side

    def _H(self, x):
        q, _ = self._q(x)
        return box_height(q[:, 0], q[:, 1], q[:, 2] if self.d == 3 else -np.inf, self.sign)

    def _gradient(self, x):
        q, side = self._q(x)
        g = np.maximum(q, 0.0) * side
        outside = np.sqrt(rowdot(g, g))
        out = outside > 0
        g[out] /= outside[out, None]
        inner = np.flatnonzero(~out)  # inside: the normal of the nearest face
        k = np.argmax(q[inner], axis=1)
        g[inner] = 0.0
        g[inner, k] = side[inner, k]
        g *= self.sign
        return g

    def _closest(self, x):
        q, side = self._q(x)
        p = np.empty_like(x)
        for a in range(self.d):  # a loop over the d coordinates
            p[:, a] = np.clip(x[:, a], self.lo[a], self.hi[a])
        inner = np.flatnonzero(q.max(axis=1) <= 0)  # inside: move to the nearest face
        k = np.argmax(q[inner], axis=1)
        p[inner, k] = self.center[k] + side[inner, k] * self.half[k]
        return p

    def __repr__(self):
        return f"Box(lo={self.lo.tolist()}, hi={self.hi.tolist()}, container={self.container})"


class Cylinder(Surface):
    """An infinite circular cylinder in 3D (a bar, a rod, a roller), solid or hollow.

    With ``a`` the unit axis direction and ``p`` a point of the axis, the
    offset from the axis is ``r = (x - p) - ((x - p) . a) a`` and
    ``H(x) = |r| - R`` (solid) or ``R - |r|`` (``container=True``). It has no
    caps: the bar is longer than anything that meets it. The gradient is
    ``r / |r|``, perpendicular to the axis; on the axis itself it is a fixed
    unit vector perpendicular to ``a``.

    Parameters
    ----------
    point : array_like, shape (3,)
        A point ``p`` of the axis, in metres.
    axis : array_like, shape (3,)
        Direction of the axis (need not be unit, non-zero).
    radius : float
        ``R``, in metres, > 0.
    container : bool
        Whether the particles live inside the cylinder (a pipe).

    Examples
    --------
    >>> bar = Cylinder([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.5)
    >>> bar.H([[7.0, 0.0, 2.0], [-3.0, 0.3, 0.0]]).tolist()
    [1.5, -0.2]
    >>> bar.closest_point([7.0, 0.0, 2.0]).tolist()
    [7.0, 0.0, 0.5]
    """

    d = 3

    def __init__(self, point, axis, radius, container=False):
        self.point = as_float_array(point, "point", shape=(3,))
        axis = as_float_array(axis, "axis", shape=(3,))
        if not np.any(axis):
            raise ValueError("axis must be a non-zero vector")
        self.axis = axis / np.linalg.norm(axis)
        self.radius = positive_number(radius, "radius", "metres")
        self.container = bool(container)
        self.sign = -1.0 if self.container else 1.0
        helper = np.eye(3)[np.argmin(np.abs(self.axis))]  # the coordinate axis least parallel to a
        self._across = np.cross(self.axis, helper) / np.linalg.norm(np.cross(self.axis, helper))

    def _offsets(self, x):
        """Offsets ``r`` from the axis, shape (n, 3), and their lengths."""
        y = x - self.point
        r = y - np.outer(rowdot(y, self.axis), self.axis)
        return r, np.sqrt(rowdot(r, r))

    def _directions(self, x):
        """Unit offsets from the axis; points on the axis get a fixed perpendicular.

        A point on the axis can have an offset of rounding size along the
        axis itself; the axial part is removed again after normalizing, and
        what is left is trusted only if it is more than half a unit vector.
        """
        r, dist = self._offsets(x)
        u = r / np.maximum(dist, 1e-300)[:, None]
        u -= np.outer(rowdot(u, self.axis), self.axis)
        size = np.sqrt(rowdot(u, u))
        on_axis = size < 0.5
        u[on_axis], size[on_axis] = self._across, 1.0
        return u / size[:, None]

    def _H(self, x):
        r, _ = self._offsets(x)
        return round_height(*_columns(r), self.radius, self.sign)

    def _gradient(self, x):
        return self.sign * self._directions(x)

    def _closest(self, x):
        y = x - self.point
        foot = self.point + np.outer(rowdot(y, self.axis), self.axis)  # the nearest point of the axis
        return foot + self.radius * self._directions(x)

    def __repr__(self):
        return (f"Cylinder(point={self.point.tolist()}, axis={self.axis.tolist()}, radius={self.radius}, "
                f"container={self.container})")


class _Combination(Surface):
    """Union or intersection of surfaces: ``H`` is the min or max of the parts' ``H``."""

    pick = None  # np.argmin or np.argmax

    def __init__(self, *parts):
        flat = []
        for part in parts:
            if not isinstance(part, Surface):
                raise ValueError(f"parts must be Surface objects, got {type(part).__name__}")
            flat.extend(part.parts if type(part) is type(self) else [part])
        if len(flat) < 2:
            raise ValueError(f"{type(self).__name__} needs at least 2 parts, got {len(flat)}")
        dims = {part.d for part in flat}
        if len(dims) != 1:
            raise ValueError(f"parts must all live in the same dimension, got dimensions {sorted(dims)}")
        self.parts, self.d = flat, dims.pop()
        bounds = [part.lipschitz for part in flat]
        self.lipschitz = None if None in bounds else max(bounds)

    def _stack(self, x):
        return np.stack([part._H(x) for part in self.parts])  # (parts, n)

    def _H(self, x):
        Hs = self._stack(x)
        return Hs[type(self).pick(Hs, axis=0), np.arange(len(x))]

    def _gradient(self, x):
        active = type(self).pick(self._stack(x), axis=0)
        g = np.empty_like(x)
        for k, part in enumerate(self.parts):  # a loop over the parts
            mine = active == k
            g[mine] = part._gradient(x[mine])
        return g

    def _closest(self, x):
        best, best_d2 = np.empty_like(x), np.full(len(x), np.inf)
        for part in self.parts:  # a loop over the parts
            p = part._closest(x)
            on = np.abs(self._H(p)) <= _ON_SURFACE * (1.0 + np.abs(p).max(axis=1))
            d2 = np.where(on, np.sum((p - x) ** 2, axis=1), np.inf)
            better = d2 < best_d2
            best[better], best_d2[better] = p[better], d2[better]
        lost = np.flatnonzero(~np.isfinite(best_d2))
        if len(lost):
            best[lost] = self._newton_projection(x[lost])
        return best

    def _newton_projection(self, x, iterations=50):
        """Walk along the gradient onto ``H = 0``: ``p <- p - H grad H / |grad H|^2``."""
        p = x.copy()
        for _ in range(iterations):  # a loop over Newton iterations
            H = self._H(p)
            off = np.abs(H) > 1e-13 * (1.0 + np.abs(p).max(axis=1))
            if not off.any():
                break
            g = self._gradient(p[off])
            p[off] -= (H[off] / np.maximum(np.sum(g * g, axis=1), 1e-300))[:, None] * g
        return p

    def __repr__(self):
        return f"{type(self).__name__}({', '.join(repr(p) for p in self.parts)})"


class Union(_Combination):
    """Inside any of the parts: ``H = min_k H_k`` (also written ``a | b``).

    The gradient is that of the part with the smallest ``H``. The closest
    point is the nearest of the parts' closest points that lies on the
    combined surface; this is exact outside the union, and inside it except
    near creases, where the nearest point is on the curve where two parts
    meet. When no part's closest point lies on the combined surface, a
    surface point is found by Newton steps along the gradient.

    Examples
    --------
    >>> snowman = Sphere([0.0, 0.0], 1.0) | Sphere([0.0, 1.5], 0.7)
    >>> snowman.inside([[0.0, 2.0], [0.0, 3.0]]).tolist()
    [True, False]
    """

    pick = staticmethod(np.argmin)


class Intersection(_Combination):
    """Inside all of the parts: ``H = max_k H_k`` (also written ``a & b``).

    Gradient and closest point as for :class:`Union`, with the largest ``H``.
    """

    pick = staticmethod(np.argmax)


class Complement(Surface):
    """Solid and free space swapped: ``H = -H_part`` (also written ``~a``).

    ``~Sphere(c, r)`` is the same as ``Sphere(c, r, container=True)``.
    """

    def __init__(self, part):
        if not isinstance(part, Surface):
            raise ValueError(f"part must be a Surface, got {type(part).__name__}")
        self.part, self.d, self.lipschitz = part, part.d, part.lipschitz

    def _H(self, x):
        return -self.part._H(x)

    def _gradient(self, x):
        return -self.part._gradient(x)

    def _closest(self, x):
        return self.part._closest(x)

    def __repr__(self):
        return f"Complement({self.part!r})"
