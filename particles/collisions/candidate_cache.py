"""The cloth pipeline's candidate pairs kept from step to step, and the pipeline's compiled stages.

:class:`CandidateCache` keeps the pairs of the broad phase (:mod:`particles.collisions.candidates`) from
step to step, as a Verlet list keeps neighbours: a search with boxes padded by a margin serves the steps
until a vertex leaves its box. With the compiled backend each call searches its own boxes instead.
:func:`compiled_stages` loads the compiled stages (:mod:`particles.collisions.compiled_stages`) when the
pipeline's backend resolves to numba; :data:`CLOTH_COLLISION_WEIGHT` weighs its vertices for ``"auto"``.
"""

import numpy as np

from ..backends import check_backend, compiled
from .candidates import boxes_overlap, candidates_in_boxes, candidates_touching, element_boxes, merge_keys, pair_rows

__all__ = ["CLOTH_COLLISION_WEIGHT", "compiled_stages", "CandidateCache"]

# the cloth collision pipeline asks "auto" (particles.backends) with this many times its vertices: each vertex
# carries dozens of force passes' work (its candidate pairs' closest points, up to 50 Jacobi iterations, the
# continuous test), and NumPy's calls cost the same whatever the sheet. Measured with
# bench/bench_cloth_fold.py --compare (median ms per step, NumPy / compiled): 8^2 6.3 / 1.3, 16^2 18.6 / 2.8,
# 32^2 about 60 / 8: compiled from 64 vertices
CLOTH_COLLISION_WEIGHT = 64


def compiled_stages(backend, n):
    """The cloth pipeline's compiled stages (:mod:`particles.collisions.compiled_stages`) when `backend` resolves to
    numba for a mesh of `n` vertices (weighted by :data:`CLOTH_COLLISION_WEIGHT`), else None."""
    if not compiled(backend, CLOTH_COLLISION_WEIGHT * n):
        return None
    import particles.collisions.compiled_stages as stages  # noqa: PLC0415  (imports numba)
    return stages


class CandidateCache:
    """Candidate pairs of a mesh kept from step to step, searched again only when a vertex left its box.

    The pairs are searched with the boxes of each vertex's motion, padded by ``thickness / 2 + SKIN
    thickness``, and searched again only when a vertex left its box by more than ``SKIN thickness - eta``.
    Contacts depend on relative motion only, so boxes are compared in a frame that follows the median
    displacement (a falling sheet's boxes do not grow with its fall). When only a few vertices left their
    boxes (at most ``max(FEW, n / 16)``), their boxes grow and they alone are searched again, against
    every box. With the compiled backend each call searches its own boxes instead (the same pairs), and a
    call without a mask whose padded boxes lie within those of the last such call filters that call's
    pairs (in a step, the continuous test's first search within the proximity search's boxes; ``memo``
    of :func:`particles.collisions.compiled_stages.cloth_candidate_rows`).

    Parameters
    ----------
    mesh : TriangleMesh
        The cloth's faces and edges.
    thickness : float
        The cloth's thickness, in metres.
    eta : float
        The narrow phase's tolerance, in metres.
    backend : {None, "auto", "numpy", "numba"}
        Who searches and filters the pairs (:mod:`particles.backends`): NumPy, or the compiled grid of
        :func:`particles.collisions.compiled_stages.cloth_candidates` (the same pairs).

    Attributes
    ----------
    searches : int
        Full searches made so far (the other steps reused or grew the cached pairs).
    """

    SKIN = 0.5
    FEW = 64  # up to this many vertices out of their boxes: a search around them only

    def __init__(self, mesh, thickness, eta, backend=None):
        self.mesh, self.thickness, self.eta = mesh, thickness, eta
        self.backend = check_backend(backend)
        self.x0 = self.lo = self.hi = None  # start of the search, the vertices' boxes (in its frame)
        self.vf = self.ee = None  # sorted keys iv m + jf and ie e + je of the cached pairs
        self.searches = 0
        self.memo = {}  # the compiled backend's last search without a mask (see cloth_candidate_rows)

    def frame(self, x0, dx):
        """Start and end of each vertex's motion in the frame of the cache (a common translation removed)."""
        offset = np.median(x0 - self.x0, axis=0) if self.x0 is not None else np.zeros(3)
        return x0 - offset, x0 + dx - np.median(dx, axis=0) - offset

    def update(self, x0, dx, search=True):
        """Make the cached candidates cover the motion x0 -> x0 + dx; returns its start and end in their frame.

        Without `search`, only the frame and the boxes are kept up to date (the compiled :meth:`pairs`
        searches the step's own boxes, which gives the same pairs), and the cached pairs are dropped.
        """
        mesh = self.mesh
        pad = (0.5 + self.SKIN) * self.thickness
        if search and self.vf is None:  # no pairs cached (the compiled backend ran): search anew
            self.x0 = None
        if self.x0 is not None and self.x0.shape == x0.shape:
            a, b = self.frame(x0, dx)
            lo, hi = self.lo, self.hi
            out = np.maximum(np.maximum(lo - a, a - hi), np.maximum(lo - b, b - hi)).max(axis=1)
            far = out > self.SKIN * self.thickness - self.eta
            if not far.any():
                return a, b
            if far.sum() <= max(self.FEW, mesh.n // 16):  # grow those vertices' boxes, test them against every box
                lo[far] = np.minimum(lo[far], np.minimum(a[far], b[far]))
                hi[far] = np.maximum(hi[far], np.maximum(a[far], b[far]))
                if not search:
                    return a, b
                iv, jf, ie, je = candidates_touching(mesh, lo, hi, pad, far)
                self.vf = merge_keys(self.vf, iv * mesh.m + jf)
                self.ee = merge_keys(self.ee, ie * len(mesh.edges) + je)
                return a, b
        self.x0 = None
        a, b = self.frame(x0, dx)
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        self.x0, self.lo, self.hi = x0.copy(), lo, hi
        self.searches += 1
        if not search:
            self.vf = self.ee = None
            return a, b
        iv, jf, ie, je = candidates_in_boxes(mesh, lo, hi, pad)
        self.vf, self.ee = iv * mesh.m + jf, ie * len(mesh.edges) + je
        return a, b

    def pairs(self, x0, dx, pad, moved=None):
        """Cached candidate rows whose boxes, swept over x0 -> x0 + dx, overlap when padded by `pad` / 2 each.

        With a mask `moved` (shape (n,)), only the pairs that hold one of those vertices. Returns the
        vertex-face rows ``(vertex, a, b, c)`` and the edge-edge rows ``(p_1, p_2, q_1, q_2)``, in the order of
        their keys; with the compiled backend, with the key as a fifth column, in an order fixed by the
        boxes (the compiled stages sort the pairs they keep by it: ``ordered=False`` of
        :func:`particles.collisions.compiled_stages.cloth_candidate_rows`).
        """
        mesh = self.mesh
        fast = compiled_stages(self.backend, mesh.n)
        a, b = self.update(x0, dx, search=fast is None)
        if fast is not None:  # compiled: a search with the step's own boxes finds the pairs the cache would give
            return fast.cloth_candidate_rows(mesh, np.minimum(a, b), np.maximum(a, b), 0.5 * pad, moved, self.memo,
                                             ordered=False)
        iv, jf = np.divmod(self.vf, max(mesh.m, 1))
        ie, je = np.divmod(self.ee, max(len(mesh.edges), 1))
        if moved is not None:
            F, E = mesh.faces, mesh.edges
            keep = moved[iv] | moved[F[jf]].any(axis=1)
            iv, jf = iv[keep], jf[keep]
            keep = moved[E[ie]].any(axis=1) | moved[E[je]].any(axis=1)
            ie, je = ie[keep], je[keep]
        vb, fb, eb = element_boxes(mesh, a, b, 0.5 * pad)
        keep = boxes_overlap(vb, fb, iv, jf)
        iv, jf = iv[keep], jf[keep]
        keep = boxes_overlap(eb, eb, ie, je)
        return pair_rows(mesh, iv, jf, ie[keep], je[keep])
