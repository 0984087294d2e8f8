"""Cloth against bodies at rest, compiled (numba): ``BodyStage._bodies``' vertex pass and its edge samples' test.

Imported by :mod:`particles.collisions.compiled_stages` and :mod:`particles.collisions.impulse_kernels`. The bodies are
primitives (:mod:`particles.collisions.collider_kernels`' kinds and rows) that do not move; each vertex is
one loop iteration with the arithmetic of :mod:`particles.collisions.bodies` in its order, so the
results are NumPy's and have the same bits on any number of threads.
"""

import math

from ..backends.compile import inline, jit, prange
from .collider_kernels import surface_H, surface_normal
from .response import friction_change

inline(friction_change)


def out_of_bodies(p, x0, vbar, h, thickness, friction, kinds, rows):
    """Vertex `p` moved out of each body's `thickness` at the end of the step, as ``BodyStage._bodies`` does it.

    The bodies are at rest (their velocity is zero): the change of ``vbar`` is the displacement over `h`,
    then friction takes at most ``friction`` times that change from the tangential velocity. Returns how
    many bodies the vertex ended closer than `thickness` to.
    """
    near = 0
    for b in range(len(kinds)):  # the few bodies, in their order
        kind, P = kinds[b], rows[b]
        e0, e1, e2 = x0[p, 0] + h * vbar[p, 0], x0[p, 1] + h * vbar[p, 1], x0[p, 2] + h * vbar[p, 2]
        if not surface_H(kind, P, 3, e0, e1, e2) < thickness:
            continue
        near += 1
        q0, q1, q2 = e0, e1, e2
        for _ in range(3):  # projection passes (exact at once for signed distances)
            Hq = surface_H(kind, P, 3, q0, q1, q2)
            if not Hq < thickness * (1.0 - 1e-9):
                break
            n0, n1, n2 = surface_normal(kind, P, 3, q0, q1, q2)
            q0, q1, q2 = q0 + (thickness - Hq) * n0, q1 + (thickness - Hq) * n1, q2 + (thickness - Hq) * n2
        d0, d1, d2 = (q0 - e0) / h, (q1 - e1) / h, (q2 - e2) / h
        vbar[p, 0] += d0
        vbar[p, 1] += d1
        vbar[p, 2] += d2
        if friction > 0:
            n0, n1, n2 = surface_normal(kind, P, 3, q0, q1, q2)
            dn = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            u0, u1, u2 = vbar[p, 0], vbar[p, 1], vbar[p, 2]
            un = u0 * n0 + u1 * n1 + u2 * n2
            t0, t1, t2 = u0 - un * n0, u1 - un * n1, u2 - un * n2
            speed = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
            slow = friction_change(friction, dn, speed)
            f = slow / speed if speed > 0 else 0.0
            vbar[p, 0] -= f * t0
            vbar[p, 1] -= f * t1
            vbar[p, 2] -= f * t2
    return near


@jit(parallel=True)
def body_vertices(x0, vbar, free, h, thickness, friction, kinds, rows):
    """The vertex pass of ``BodyStage._bodies`` on the `free` vertices, in place; returns how many were near."""
    near = 0
    for p in prange(len(vbar)):
        if free[p]:
            near += out_of_bodies(p, x0, vbar, h, thickness, friction, kinds, rows)
    return near


@jit(parallel=True)
def low_edge_samples(x0, vbar, h, E, w, samples, target, kind, P):
    """How many edge samples end closer than ``target (1 - 1e-9)`` to the body and can move (``BodyStage._edges_out``).

    A sample ``s`` of edge ``(a, b)`` is the point ``(1 - s) xe_a + s xe_b`` with ``xe = x0 + h vbar``;
    one with ``(1 - s) w_a + s w_b = 0`` (pinned ends) is not counted.
    """
    low = 0
    for e in prange(len(E)):
        a, b = E[e, 0], E[e, 1]
        for s in samples:
            p0 = (1.0 - s) * (x0[a, 0] + h * vbar[a, 0]) + s * (x0[b, 0] + h * vbar[b, 0])
            p1 = (1.0 - s) * (x0[a, 1] + h * vbar[a, 1]) + s * (x0[b, 1] + h * vbar[b, 1])
            p2 = (1.0 - s) * (x0[a, 2] + h * vbar[a, 2]) + s * (x0[b, 2] + h * vbar[b, 2])
            if surface_H(kind, P, 3, p0, p1, p2) < target * (1.0 - 1e-9) and (1.0 - s) * w[a] + s * w[b] > 0:
                low += 1
    return low


for _helper in (out_of_bodies,):  # compiled into the kernels that call them
    inline(_helper, into="never")
