"""Stage 4 of the cloth pipeline: impact zones (Provot 1997, Bridson, Fedkiw and Anderson 2002).

Vertices of the collisions left after stage 3 are merged into zones (connected components of the graph of
collisions, :func:`scipy.sparse.csgraph.connected_components`); each zone moves rigidly with its linear and
angular momentum, or with its anchor (a pin or a body it touches), and the continuous test runs again on
the zones' vertices, until no collision is left. :class:`ImpactZoneStage` holds the methods
:class:`~particles.collisions.pipeline.ClothCollisions` takes from it.
"""

import numpy as np

from .proximity import dot

__all__ = ["ImpactZoneStage"]


class ImpactZoneStage:
    """The impact zones of :class:`~particles.collisions.pipeline.ClothCollisions` (a base class of it).

    They use its ``n``, ``m``, ``w``, ``bodies``, ``zone_iterations``, ``_detect`` and ``_body_violations``.
    """

    def _rigid(self, x0, vbar, labels, members, h):
        """The zones' rigid motions (linear and angular momentum kept), written into vbar of `members`."""
        zone_ids, z = np.unique(labels[members], return_inverse=True)  # zones numbered 0 .. Z - 1
        Z = len(zone_ids)
        m = self.m[members]
        r, u = x0[members], vbar[members]
        M = np.bincount(z, m, minlength=Z)
        xc = np.stack([np.bincount(z, m * r[:, a], minlength=Z) for a in range(3)], axis=1) / M[:, None]
        vc = np.stack([np.bincount(z, m * u[:, a], minlength=Z) for a in range(3)], axis=1) / M[:, None]
        R = r - xc[z]
        Lm = np.cross(R, u - vc[z]) * m[:, None]
        L = np.stack([np.bincount(z, Lm[:, a], minlength=Z) for a in range(3)], axis=1)
        RR = m[:, None, None] * (dot(R, R)[:, None, None] * np.eye(3) - R[:, :, None] * R[:, None, :])
        inertia = np.stack([np.bincount(z, RR[:, a, b], minlength=Z) for a in range(3) for b in range(3)],
                           axis=1).reshape(Z, 3, 3)
        omega = np.einsum("zab,zb->za", np.linalg.pinv(inertia, rcond=1e-10, hermitian=True), L)
        theta_v = h * omega[z]
        theta = np.sqrt(dot(theta_v, theta_v))
        k = np.divide(theta_v, theta[:, None], out=np.zeros_like(theta_v), where=theta[:, None] > 0)
        cos, sin = np.cos(theta)[:, None], np.sin(theta)[:, None]
        rotated = R * cos + np.cross(k, R) * sin + k * dot(k, R)[:, None] * (1.0 - cos)
        vbar[members] = (xc[z] + h * vc[z] + rotated - r) / h

    def _impact_zones(self, impacts, x0, vbar, t, h):
        """Merge, move rigidly, detect again, until no collision is left; returns counts."""
        import scipy.sparse.csgraph
        n = self.n
        pinned = self.w == 0
        rows, cols = [], []
        active = np.zeros(n, dtype=bool)
        anchor = np.full(n, -1)  # body held to, per vertex
        passes = 0
        converged = False
        owner = self._body_violations(x0, vbar, t, h)
        labels = np.arange(n)
        while passes < self.zone_iterations:  # a loop over zone passes
            if not len(impacts) and not (owner >= 0).any():
                converged = True
                break
            passes += 1
            V = impacts.vertices
            rows.append(V[:, [0, 0, 0]].ravel())
            cols.append(V[:, [1, 2, 3]].ravel())
            active[V.ravel()] = True
            hold = owner >= 0
            anchor[hold] = owner[hold]
            active |= hold
            r, c = np.concatenate(rows), np.concatenate(cols)
            graph = scipy.sparse.coo_matrix((np.ones(len(r)), (r, c)), shape=(n, n))
            _, labels = scipy.sparse.csgraph.connected_components(graph, directed=False)
            zone = np.zeros(labels.max() + 1, dtype=bool)
            zone[labels[active]] = True
            members = np.flatnonzero(zone[labels])
            # anchors of a zone: pins first (code -1), then bodies by their number; n_bodies: none
            B = len(self.bodies)
            code = np.where(pinned, -1, np.where(anchor >= 0, anchor, B))
            zone_code = np.full(labels.max() + 1, B)
            np.minimum.at(zone_code, labels[members], code[members])
            mc = zone_code[labels[members]]
            free_zone = members[mc == B]
            if len(free_zone):
                self._rigid(x0, vbar, labels, free_zone, h)
            held = members[mc == -1]
            vbar[held[~pinned[held]]] = 0.0  # pins do not move: their zone stays
            for b in range(B):  # a loop over the few bodies
                on = members[(mc == b) & ~pinned[members]]
                if len(on):
                    vbar[on] = np.asarray(self.bodies[b].velocity(x0[on], t + 0.5 * h), dtype=float)
            moved = np.zeros(n, dtype=bool)
            moved[members] = True
            impacts = self._detect(x0, vbar, h, moved)
            owner = self._body_violations(x0, vbar, t, h)
            owner[anchor >= 0] = -1
        if not converged:
            vbar[~pinned] = 0.0
        zones = len(np.unique(labels[active])) if active.any() else 0
        return zones, int(active.sum()), passes, int((anchor >= 0).sum()), converged
