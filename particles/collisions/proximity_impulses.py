"""Stage 2 of the cloth pipeline: proximity impulses between pieces of the cloth closer than its thickness.

Vertex-face and edge-edge pairs closer than ``thickness`` at the start of the step, or that would end
closer along their normal, get normal impulses with Coulomb friction, iterated (Jacobi with averaging, or
Gauss-Seidel over vertex-disjoint colour groups), each iteration followed by the bodies' vertex pass
(:class:`~particles.collisions.bodies.BodyStage`). With the numba backend the Jacobi iterations run in
:func:`particles.collisions.compiled_stages.cloth_impulses`. :class:`ProximityStage` holds the methods
:class:`~particles.collisions.pipeline.ClothCollisions` takes from it.
"""

import numpy as np

from ..constraints.colouring import color_constraints
from .candidate_cache import compiled_stages
from .response import friction_change, proximity_impulse
from .proximity import PARALLEL, approaching_within, dot, edge_edge_kernel, vertex_face_kernel

__all__ = ["ProximityStage"]


class ProximityStage:
    """The proximity stage of :class:`~particles.collisions.pipeline.ClothCollisions` (a base class of it).

    It uses its ``n``, ``w``, ``thickness``, ``friction``, ``repulsion``, ``rest_distance``, ``x_rest``,
    ``iterations``, ``relaxation``, ``method``, ``tol``, ``backend``, ``bodies``, ``candidates``, ``_bodies``,
    ``_compiled_bodies``, ``_scatter``, ``_relative`` and ``_effective``.
    """

    def _rest_far(self, vertices, edge):
        """Pairs farther apart than rest_distance in the rest shape (the others never repel)."""
        if self.x_rest is None or not len(vertices):
            return np.ones(len(vertices), dtype=bool)
        p = self.x_rest[vertices]
        close = (edge_edge_kernel if edge else vertex_face_kernel)(p[:, 0], p[:, 1], p[:, 2], p[:, 3])
        return close.distance >= self.rest_distance

    def _proximity_contacts(self, x0, vbar, h):
        """Pairs within thickness at x0 or ending within it: vertices, weights, normals, distances."""
        vf, ee = self.candidates.pairs(x0, h * vbar, self.thickness)
        fast = compiled_stages(self.backend, self.n)
        parts = []
        for idx, edge in ((vf, False), (ee, True)):  # the two kinds of pairs
            if not len(idx):
                continue
            if fast is not None:  # the same tests pair by pair, compiled
                parts.append(fast.cloth_proximity(x0, vbar, self.w, self.x_rest, idx, edge, h, self.thickness,
                                                  self.rest_distance, PARALLEL))
                continue
            p = x0[idx]
            close = (edge_edge_kernel if edge else vertex_face_kernel)(p[:, 0], p[:, 1], p[:, 2], p[:, 3])
            vN = dot(close.normal, self._relative(vbar, idx, close.weights))
            keep = approaching_within(close.distance, vN, h, self.thickness)
            keep &= self._effective(idx, close.weights) > 0
            if edge:  # edges whose closest points are ends: that contact is a vertex's, found with the faces
                s_, u_ = close.weights[:, 1], -close.weights[:, 3]
                keep &= (s_ > 1e-9) & (s_ < 1 - 1e-9) & (u_ > 1e-9) & (u_ < 1 - 1e-9)
            rows = np.flatnonzero(keep)
            rows = rows[self._rest_far(idx[rows], edge)]
            parts.append((idx[rows], close.weights[rows], close.normal[rows], close.distance[rows]))
        if not parts:
            return None
        return tuple(np.concatenate([p[k] for p in parts]) for k in range(4))

    def _proximity(self, contacts, x0, vbar, t, h):
        """Iterations of proximity impulses with friction, each followed by the bodies' vertex pass.

        Gauss-Seidel: one vertex-disjoint colour group of contacts at a time,
        each seeing the impulses of the groups before it; Jacobi: all at once,
        each impulse divided by the largest load (``sum |w_j|`` of the active
        contacts) at its free vertices (from the second iteration on, by that
        load over ``relaxation``, and never by less than 1). Returns how many pairs got
        an impulse.
        """
        if contacts is None or not len(contacts[0]):
            return 0
        V, W, N, D = contacts
        S = self._effective(V, W)
        inside = D < self.thickness
        target = np.where(inside, self.repulsion * (self.thickness - D), self.thickness - D) / h
        groups = color_constraints(V, self.n) if self.method == "gauss-seidel" else None
        fast = compiled_stages(self.backend, self.n) if groups is None else None
        if fast is not None:
            return self._compiled_proximity(fast, V, W, N, S, target, x0, vbar, t, h)
        touched = np.zeros(len(V), dtype=bool)
        free = self.w[V] > 0
        for it in range(self.iterations):  # a loop over iterations
            if groups is None:
                k = self._active(vbar, V, W, N, target, h)
                if len(k):
                    share = np.where(free[k], np.abs(W[k]), 0.0)  # each free vertex's part in each contact
                    load = np.bincount(V[k].ravel(), share.ravel(), minlength=self.n)
                    relaxed = self.relaxation if it > 0 else 1.0  # the first iteration plain averaging
                    c = np.maximum(np.max(np.where(share > 0, load[V[k]], 0.0), axis=1) / relaxed, 1.0)
                    self._impulses(vbar, V[k], W[k], N[k], S[k], target[k], c, disjoint=False)
            else:
                k = []
                for g in groups:  # Gauss-Seidel: one colour at a time
                    kg = g[self._active(vbar, V[g], W[g], N[g], target[g], h)]
                    if len(kg):
                        self._impulses(vbar, V[kg], W[kg], N[kg], S[kg], target[kg], 1.0, disjoint=True)
                        k.append(kg)
                k = np.concatenate(k) if k else []
            if not len(k):
                break
            touched[k] = True
            if self.bodies:
                moved = np.zeros(self.n, dtype=bool)
                moved[V[k].ravel()] = True
                self._bodies(x0, vbar, t, h, edges=False, subset=moved)
        return int(touched.sum())

    def _compiled_proximity(self, fast, V, W, N, S, target, x0, vbar, t, h):
        """:meth:`_proximity`'s Jacobi iterations compiled: in one call when the bodies are primitives at rest."""
        rows = self._compiled_bodies()[1]
        args = (vbar, x0, V, W, N, S, target, self.w, h, self.tol * self.thickness, self.friction)
        if rows is not None or not self.bodies:
            _, touched, _ = fast.cloth_impulses(*args, self.iterations, self.thickness, rows, self.relaxation)
            return int(touched.sum())
        touched = np.zeros(len(V), dtype=bool)
        for it in range(self.iterations):  # one compiled iteration, then the NumPy bodies' pass
            done, hit, active = fast.cloth_impulses(*args, 1, self.thickness, None, self.relaxation, it)
            if not done:
                break
            touched |= hit
            moved = np.zeros(self.n, dtype=bool)
            moved[V[active].ravel()] = True
            self._bodies(x0, vbar, t, h, edges=False, subset=moved)
        return int(touched.sum())

    def _active(self, vbar, V, W, N, target, h):
        """Rows of the contacts whose relative normal velocity is below their target."""
        vN = dot(N, self._relative(vbar, V, W))
        dvN = target - vN
        return np.flatnonzero(dvN * h > self.tol * self.thickness)

    def _impulses(self, vbar, V, W, N, S, target, c, disjoint):
        """Normal impulses to the target normal velocity, divided by `c`, with Coulomb friction."""
        rel = self._relative(vbar, V, W)
        vN = dot(N, rel)
        I = proximity_impulse(target, vN, S, c)  # normal impulse, N s
        impulse = I[:, None] * N
        if self.friction > 0:
            vt = rel - vN[:, None] * N
            speed = np.sqrt(dot(vt, vt))
            J = friction_change(self.friction, I, speed / S / c)
            impulse -= np.divide(J, speed, out=np.zeros_like(speed), where=speed > 0)[:, None] * vt
        if disjoint:  # no vertex twice: a plain indexed add
            vbar[V] += (W * self.w[V])[:, :, None] * impulse[:, None, :]
        else:
            self._scatter(vbar, V, W, impulse)
