"""When does a path cross a surface? Ray-object intersection for particle paths.

Collision detection after a step only says *that* a particle ended inside a
solid. To respond at the right place ("back up" on the slide) we need *when*
it entered: the first root of ``H(x(s)) = 0`` along the path of the step,
``s`` in [0, 1]. The path between the two end states of a step is the cubic
Hermite interpolant (:func:`hermite`), and :func:`first_crossing` finds its
first entry into the solid for all particles at once.

References
----------
.. [1] J. C. Hart, "Sphere tracing: a geometric method for the antialiased ray
   tracing of implicit surfaces", The Visual Computer 12(10), 527-545, 1996.
.. [2] M. Dowell and P. Jarratt, "A modified regula falsi method for computing
   the root of an equation", BIT 11, 168-174, 1971 (the Illinois method).
"""

import numpy as np

__all__ = ["hermite", "hermite_coefficients", "cubic_path", "path_speed", "first_crossing"]

# A crossing is accepted once the outside end of its bracket has H below _CROSSING_TOL
# and the inside end H above -_INSIDE_TOL (metres, for signed distances).
_CROSSING_TOL = 1e-12
_INSIDE_TOL = 1e-9


def _steps(h, k):
    """Step lengths as an array of shape (k,)."""
    return np.broadcast_to(np.asarray(h, dtype=float), (k,))


def hermite(x0, v0, x1, v1, h, s):
    """Position and velocity at fraction `s` of a step, from the step's end states.

    The cubic Hermite interpolant matches ``x`` and ``dx/dt = v`` at both ends
    of the step; it reproduces any path with constant acceleration exactly
    (a parabola is a cubic) and is fourth-order accurate for smooth paths::

        x(s) = (2s^3 - 3s^2 + 1) x0 + (s^3 - 2s^2 + s) h v0 + (3s^2 - 2s^3) x1 + (s^3 - s^2) h v1
        v(s) = dx/ds / h

    Parameters
    ----------
    x0, v0, x1, v1 : ndarray, shape (k, d)
        Positions and velocities at the start and the end of the step.
    h : float or ndarray, shape (k,)
        Step length, in seconds.
    s : ndarray, shape (k,)
        Fractions of the step in [0, 1].

    Returns
    -------
    x, v : ndarray, shape (k, d)
    """
    s = np.asarray(s, dtype=float)
    k, d = np.shape(x0)
    h = _steps(h, k)
    s2, s3 = s * s, s * s * s
    b0, b1, b2, b3 = 2 * s3 - 3 * s2 + 1, (s3 - 2 * s2 + s) * h, 3 * s2 - 2 * s3, (s3 - s2) * h
    db0, db1, db3 = (6 * s2 - 6 * s) / h, 3 * s2 - 4 * s + 1, 3 * s2 - 2 * s
    x, v = np.empty((k, d), order="F"), np.empty((k, d), order="F")
    for a in range(d):  # a loop over the d coordinates (faster than broadcasting over rows)
        x[:, a] = b0 * x0[:, a] + b1 * v0[:, a] + b2 * x1[:, a] + b3 * v1[:, a]
        v[:, a] = db0 * (x0[:, a] - x1[:, a]) + db1 * v0[:, a] + db3 * v1[:, a]
    return x, v


def hermite_coefficients(x0, v0, x1, v1, h):
    """Coefficients of the Hermite path as a cubic in s: ``x(s) = c0 + s (c1 + s (c2 + s c3))``.

    ``c0 = x0``, ``c1 = h v0``, ``c2 = 3 (x1 - x0) - h (2 v0 + v1)``,
    ``c3 = 2 (x0 - x1) + h (v0 + v1)``; evaluating in this (Horner) form, see
    :func:`cubic_path`, is cheaper than the four basis polynomials when a
    path is sampled many times.

    Returns
    -------
    ndarray, shape (4, d, k)
        Coordinate-major, so that each coordinate is one contiguous row.
    """
    k, d = np.shape(x0)
    h = _steps(h, k)
    c = np.empty((4, d, k))
    for a in range(d):  # a loop over the d coordinates
        chord = x1[:, a] - x0[:, a]
        c[0, a], c[1, a] = x0[:, a], h * v0[:, a]
        c[2, a] = 3 * chord - h * (2 * v0[:, a] + v1[:, a])
        c[3, a] = -2 * chord + h * (v0[:, a] + v1[:, a])
    return c


def cubic_path(c, idx, s):
    """Positions ``c0 + s (c1 + s (c2 + s c3))`` of paths `idx` at parameters `s`, shape (len(idx), d)."""
    x = np.empty((c.shape[1], len(idx)))
    for a in range(len(x)):  # a loop over the d coordinates
        c0, c1, c2, c3 = (np.take(c[j, a], idx) for j in range(4))
        x[a] = c0 + s * (c1 + s * (c2 + s * c3))
    return x.T


def path_speed(x0, v0, x1, v1, h):
    """A bound ``D >= |dx/ds|`` on the Hermite path of a step, shape (k,).

    With the chord ``c = x1 - x0``, ``dx/ds = c + b0(s) (h v0 - c) + b1(s) (h v1 - c)``
    where ``|b0|, |b1| <= 1`` on [0, 1]; so ``D = |c| + |h v0 - c| + |h v1 - c|``,
    which is ``|c|`` for a straight path at constant speed.
    """
    k, d = np.shape(x0)
    h = _steps(h, k)
    sums = np.zeros((3, k))
    for a in range(d):  # a loop over the d coordinates
        chord = x1[:, a] - x0[:, a]
        sums[0] += chord * chord
        sums[1] += (h * v0[:, a] - chord) ** 2
        sums[2] += (h * v1[:, a] - chord) ** 2
    return np.sqrt(sums).sum(axis=0)


def first_crossing(surface, path, n, samples=8, speed=None, iterations=60):
    """First parameter ``s`` in [0, 1] at which paths enter a solid, found without loops over particles.

    Each path ``s -> path(idx, s)`` is walked from ``s = 0`` in steps of at
    most ``1/K``; the first point inside the solid brackets the entry, which
    is then refined by the Illinois variant of regula falsi. With a bound
    ``speed >= |dx/ds|`` and a Lipschitz surface (``|grad H| <= L``), a point
    with ``H > 0`` proves that the path stays outside for the next
    ``H / (L speed)``, and the walk skips ahead that far (sphere tracing [1]_),
    so that paths far from the surface cost one or two evaluations.

    Parameters
    ----------
    surface : Surface
    path : callable
        ``path(idx, s)`` returns positions, shape (len(idx), d), of paths
        ``idx`` (int array) at parameters ``s`` (shape (len(idx),)).
    n : int
        Number of paths.
    samples : int
        ``K``: the walk takes at most ``K`` steps, so a path that enters and
        leaves a solid thinner than about ``speed / K`` can be missed.
    speed : ndarray, shape (n,), optional
        A bound on ``|dx/ds|`` along each path (enables the skipping).
    iterations : int
        Largest number of regula falsi iterations (usually fewer than 10
        are needed).

    Returns
    -------
    s : ndarray, shape (n,)
        1 for paths that stay outside, 0 for paths that start inside.
        Otherwise the outside end of the final bracket: ``0 <= H <= 1e-12``
        there (or the bracket is narrower than ``1e-13``).
    s_in : ndarray, shape (n,)
        The inside end of the final bracket (1 for paths that stay
        outside), with ``-1e-9 <= H < 0``: the gradient there tells which
        face was crossed, even at an edge or a corner where the gradient on
        the surface is ambiguous.
    """
    lo, H_lo = np.zeros(n), surface._H(path(np.arange(n), np.zeros(n)))
    start_inside = H_lo < 0
    hi, H_hi = np.ones(n), np.zeros(n)
    found = np.zeros(n, dtype=bool)
    skip = speed is not None and surface.lipschitz is not None
    for _ in range(samples):  # a loop over the steps of the walk along the paths
        todo = np.flatnonzero(~found & ~start_inside & (lo < 1.0))
        if not len(todo):
            break
        ahead = np.full(len(todo), 1.0 / samples)
        if skip:
            reach = np.divide(H_lo[todo], surface.lipschitz * speed[todo],
                              out=np.full(len(todo), np.inf), where=speed[todo] > 0)
            ahead = np.maximum(ahead, reach)
        sk = np.minimum(lo[todo] + ahead, 1.0)
        Hk = surface._H(path(todo, sk))
        entered = Hk < 0
        hit, miss = todo[entered], todo[~entered]
        found[hit], hi[hit], H_hi[hit] = True, sk[entered], Hk[entered]
        lo[miss], H_lo[miss] = sk[~entered], Hk[~entered]
    idx = np.flatnonzero(found)
    lo, H_lo, hi, H_hi = lo[idx], H_lo[idx], hi[idx], H_hi[idx]
    side = np.zeros(len(idx))  # Illinois: halve the value kept twice in a row
    for _ in range(iterations):  # a loop over root-finding iterations
        # Done when the outside end is on the surface and the inside end just below it
        # (the inside end tells which face was crossed).
        active = (hi - lo > 1e-13) & ((H_lo > _CROSSING_TOL) | (H_hi < -_INSIDE_TOL))
        if not active.any():
            break
        a = np.flatnonzero(active)
        # Regula falsi aims at H = 0; once the outside end is there, at a point just inside.
        level = np.where(H_lo[a] > _CROSSING_TOL, 0.0, -0.1 * _INSIDE_TOL)
        sm = lo[a] + (level - H_lo[a]) * (hi[a] - lo[a]) / (H_hi[a] - H_lo[a])
        sm = np.clip(sm, lo[a], hi[a])
        Hm = surface._H(path(idx[a], sm))
        inside = Hm < 0
        ai, ao = a[inside], a[~inside]
        hi[ai], H_hi[ai] = sm[inside], Hm[inside]  # new inside end: lo is kept
        H_lo[ai] *= np.where(side[ai] == -1, 0.5, 1.0)
        side[ai] = -1
        lo[ao], H_lo[ao] = sm[~inside], Hm[~inside]  # new outside end: hi is kept
        H_hi[ao] *= np.where(side[ao] == 1, 0.5, 1.0)
        side[ao] = 1
    s = np.where(start_inside, 0.0, 1.0)
    s_in = s.copy()
    s[idx], s_in[idx] = lo, hi
    return s, s_in
