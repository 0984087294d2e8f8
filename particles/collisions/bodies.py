"""Stage 1 of the cloth pipeline, and the bodies' part of stage 4: the cloth against moving bodies.

Each body is a :class:`~particles.collisions.moving.MovingBody` or a plain
:class:`~particles.collisions.surfaces.Surface` (seen as a body at rest). Free vertices that end closer
than the cloth's thickness to a body are moved out along its normal, with Coulomb friction relative to
the body's velocity; samples along the edges (:data:`EDGE_SAMPLES`) move both ends of their edge out, so
that a thin body does not slip between two vertices. :class:`BodyStage` holds the methods
:class:`~particles.collisions.pipeline.ClothCollisions` takes from it.
"""

import numpy as np

from .candidate_cache import compiled_stages
from .response import friction_change
from .proximity import dot

__all__ = ["EDGE_SAMPLES", "StaticBody", "BodyStage"]

EDGE_SAMPLES = (0.25, 0.5, 0.75)
"""Where edges are tested against bodies, as fractions of their length."""


class StaticBody:
    """A plain Surface seen as a body that does not move."""

    def __init__(self, surface):
        self.surface = surface

    def at(self, t):
        return self.surface

    def velocity(self, x, t):
        return np.zeros_like(np.asarray(x, dtype=float))


class BodyStage:
    """The body stages of :class:`~particles.collisions.pipeline.ClothCollisions` (a base class of it).

    They use its ``mesh``, ``n``, ``w`` (inverse masses), ``thickness``, ``friction``, ``bodies``, ``backend``
    and ``_scatter``. Compiled (:func:`particles.collisions.compiled_stages.cloth_body_vertices`) when every body is a
    primitive at rest; an edge sample that comes too close is then treated by the NumPy pass.
    """

    def _bodies(self, x0, vbar, t, h, edges=True, subset=None):
        """Move free vertices (of `subset`; and edge samples) out of every body's thickness at t + h; returns counts."""
        nv = ne = 0
        free = self.w > 0
        if subset is not None:
            free = free & subset
        E = self.mesh.edges
        fast, table = self._compiled_bodies()
        for b, body in enumerate(self.bodies):  # a loop over the few bodies
            surface = body.at(t + h)
            if table is not None:  # at rest and primitive: compiled, NumPy's arithmetic vertex by vertex
                one = (table[0][b:b + 1], table[1][b:b + 1])
                nv += fast.cloth_body_vertices(x0, vbar, free, h, self.thickness, self.friction, one)
                if edges and len(E) and fast.cloth_low_edge_samples(x0, vbar, h, E, self.w, EDGE_SAMPLES,
                                                                    0.5 * self.thickness, (one[0][0], one[1][0])):
                    ne += self._edges_out(body, surface, x0, vbar, t, h)
                continue
            xe = x0 + h * vbar
            idx = np.flatnonzero(free)
            H = surface._H(xe[idx])
            near = H < self.thickness
            idx = idx[near]
            if len(idx):
                p = xe[idx].copy()
                for _ in range(3):  # a loop over projection passes (exact at once for signed distances)
                    Hp = surface._H(p)
                    low = Hp < self.thickness * (1.0 - 1e-9)
                    if not low.any():
                        break
                    p[low] += (self.thickness - Hp[low])[:, None] * surface.normal(p[low])
                self._respond_body(body, vbar, idx, p, p - xe[idx], surface.normal(p), t + h, h)
                nv += len(idx)
            if edges and len(E):
                ne += self._edges_out(body, surface, x0, vbar, t, h)
        return nv, ne

    def _compiled_bodies(self):
        """The compiled kernels and the bodies' table when they run compiled (all primitives at rest), else None's."""
        fast = compiled_stages(self.backend, self.n)
        if fast is None or not all(type(b) is StaticBody for b in self.bodies):
            return None, None
        return fast, fast.surface_rows([b.surface for b in self.bodies])

    def _respond_body(self, body, vbar, idx, p, dx, n, t1, h):
        """``vbar`` of vertices `idx` moved by `dx` (along `n`) to `p`, then Coulomb friction relative to the body."""
        dv = dx / h
        vbar[idx] += dv
        if self.friction > 0:
            dn = np.sqrt(dot(dv, dv))
            u = vbar[idx] - np.asarray(body.velocity(p, t1), dtype=float)
            ut = u - dot(u, n)[:, None] * n
            speed = np.sqrt(dot(ut, ut))
            slow = friction_change(self.friction, dn, speed)
            vbar[idx] -= np.divide(slow, speed, out=np.zeros_like(speed), where=speed > 0)[:, None] * ut

    def _edges_out(self, body, surface, x0, vbar, t, h):
        """Edge samples closer than thickness / 2 to the body move both ends out (inverse-mass weights)."""
        E = self.mesh.edges
        target = 0.5 * self.thickness
        total = 0
        for _ in range(3):  # a loop over Jacobi passes
            xe = x0 + h * vbar
            s = np.repeat(np.array(EDGE_SAMPLES)[None, :], len(E), axis=0).ravel()
            e = np.repeat(np.arange(len(E)), len(EDGE_SAMPLES))
            a, b = E[e, 0], E[e, 1]
            pts = (1.0 - s)[:, None] * xe[a] + s[:, None] * xe[b]
            H = surface._H(pts)
            low = H < target * (1.0 - 1e-9)
            wa, wb = (1.0 - s) * self.w[a], s * self.w[b]
            low &= (wa + wb) > 0
            if not low.any():
                break
            total += int(low.sum())
            a, b, s, e, H, pts = a[low], b[low], s[low], e[low], H[low], pts[low]
            n = surface.normal(pts)
            lam = (target - H) / ((1.0 - s) ** 2 * self.w[a] + s ** 2 * self.w[b])
            cnt = np.bincount(np.concatenate([a, b]), minlength=self.n)
            c = np.maximum(cnt[a], cnt[b])
            lam = lam / c
            vertices = np.stack([a, b, a, b], axis=1)
            weights = np.stack([1.0 - s, s, 0.0 * s, 0.0 * s], axis=1)
            self._scatter(vbar, vertices, weights, (lam / h)[:, None] * n)
        return total

    def _body_violations(self, x0, vbar, t, h):
        """Body index (or -1) of free vertices that end below thickness / 2, or on an edge sample below 0."""
        owner = np.full(self.n, -1)
        free = self.w > 0
        E = self.mesh.edges
        xe = x0 + h * vbar
        for b in range(len(self.bodies) - 1, -1, -1):  # a loop over the few bodies (the first one wins)
            surface = self.bodies[b].at(t + h)
            bad = free & (surface._H(xe) < 0.5 * self.thickness) & (surface._H(x0) >= 0.5 * self.thickness)
            if len(E):
                s = np.array(EDGE_SAMPLES)
                pts = ((1.0 - s)[None, :, None] * xe[E[:, 0], None] + s[None, :, None] * xe[E[:, 1], None])
                below = (surface._H(pts.reshape(-1, 3)) < 0).reshape(len(E), -1).any(axis=1)
                ends = E[below].ravel()
                bad[ends[free[ends]]] = True
            owner[bad] = b
        return owner
