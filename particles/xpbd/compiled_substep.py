"""The compiled XPBD substep: prediction, every colour group's projections and the new velocities in one call.

:class:`particles.xpbd.XPBD` (and PBD) with the numba backend and the
Gauss-Seidel method hands each substep to :meth:`CompiledSubstep.substep`:
one compiled call (:func:`particles.xpbd.kernels.substep`) that
predicts, sweeps ``iterations`` times through the colour groups of every
constraint set in the solver's order (the rows of a group in parallel: they
share no particle) and makes the velocities ``(x - x_n) / hs``. A Python loop
runs over the substeps only.

What the call reads is laid out once and kept: the distance sets' rows one
after another (each set already sorted by colour, so a group is a range of
rows), the linear sets' (isometric bending, clamps, attachments) likewise,
and a table of segments ``(form, start, stop, width, damped)``, one per
colour group in sweep order. The coefficients ``alpha / hs^2``, ``1 /
((1 + gamma) W + alpha / hs^2)`` and ``gamma`` are the batches' own
(:meth:`particles.xpbd.constraint_sets.Batch.coefficients`), gathered again when
``hs`` changes. Uniform gravity and damping are folded into the prediction
(:meth:`CompiledSubstep.force_terms`); any other external force is
evaluated by the solver in NumPy and passed in as accelerations.

Every projection does the NumPy code's operations in the same order, so a
substep gives the same bits as the NumPy solver's (tested to 1e-12), on any
number of threads: within a colour every particle is written by one row.
Importing this module imports numba; :class:`particles.xpbd.XPBD` imports it
only when its backend resolves to numba (:func:`particles.backends.compiled`).
"""

import numpy as np

from ..backends.compile import pick
from .kernels import distance_violation
from .kernels import substep as substep_kernel

__all__ = ["CompiledSubstep"]


def _rows(a, r):
    """A per-row coefficient (a scalar or shape (r,)) as a contiguous float64 array of shape (r,)."""
    return np.ascontiguousarray(np.broadcast_to(np.asarray(a, dtype=np.float64), (r,)))


class CompiledSubstep:
    """A Gauss-Seidel XPBD (or PBD) solver's substep as one compiled call.

    Parameters
    ----------
    sets : list of constraint sets
        The solver's sets, each sorted by colour (``by_colour``), swept in this order.
    batches : list of list
        Each set's colour groups as the solver built them (``set.batches(w, "gauss-seidel")``).
    m : ndarray, shape (n,)
        Masses, in kg.
    w : ndarray, shape (n,)
        Inverse masses, 0 at pinned particles (those the prediction leaves at rest).
    formulation : {"xpbd", "pbd"}
    d : int
        Dimension, 2 or 3.

    Use :meth:`applies` first: it says whether every set has a compiled form.
    """

    def __init__(self, sets, batches, m, w, formulation, d):
        self.sets = sets
        self.batches = batches  # the solver's list: rebuilt batches (set_stiffness) mean a new layout
        self.formulation = formulation
        self.n, self.d = len(m), d
        self.m = np.ascontiguousarray(m, dtype=np.float64)
        self.free = np.ascontiguousarray(w > 0)
        self.P = np.zeros((self.n, 8))  # per particle: x (3), x_n (3), w, unused: one cache line
        self.P[:, 6] = w
        self._hs = None
        forms = [s.compiled_form for s in sets]
        self._forms = forms
        dist_batches = [b for bs, f in zip(batches, forms) if f == "distance" for b in bs]
        lin_batches = [b for bs, f in zip(batches, forms) if f == "linear" for b in bs]
        r = sum(len(b.idx) for b in dist_batches)
        self.ij = np.zeros((r, 2), dtype=np.int32)  # distance rows: every distance set's groups one after another
        self.dco = np.zeros((r, 4))  # L0, alpha~, 1 / denominator, gamma
        start = 0
        for b in dist_batches:  # a loop over the colour groups of the distance sets
            stop = start + len(b.idx)
            self.ij[start:stop], self.dco[start:stop, 0] = b.idx, b.L0
            start = stop
        r = sum(len(b.idx) for b in lin_batches)
        self.idx, self.c, self.wc = np.zeros((r, 3), np.int32), np.zeros((r, 3)), np.zeros((r, 3))
        self.offset, self.lco = np.zeros((r, d)), np.zeros((r, 3))  # lco: alpha~, 1 / denominator, gamma
        start = 0
        for b in lin_batches:  # a loop over the colour groups of the linear sets
            k, stop = b.idx.shape[1], start + len(b.idx)
            self.idx[start:stop, :k], self.c[start:stop, :k], self.wc[start:stop, :k] = b.idx, b.c, b.wc
            self.offset[start:stop] = np.asarray(b.b, dtype=float).T if np.ndim(b.b) else b.b
            start = stop
        self.violations = np.empty(len(self.ij))
        self._spans = []  # each set's rows in the flat arrays, for its multipliers
        start = {"distance": 0, "linear": 0}
        for s, f in zip(sets, forms):  # a loop over the few sets
            self._spans.append((f, start[f], start[f] + len(s)))
            start[f] += len(s)
        self.segments = self._segments()

    @staticmethod
    def applies(sets, batches, d):
        """Whether the compiled substep can run these sets: each distance or linear, rows in colour order, 2D/3D."""
        if d not in (2, 3):
            return False
        for s, bs in zip(sets, batches):  # a loop over the few sets
            form = s.compiled_form
            if form is None or (form == "linear" and s.idx.shape[1] > 3):
                return False
            rows = [np.arange(len(s))[b.rows] for b in bs]
            if not np.array_equal(np.concatenate(rows) if rows else np.zeros(0, int), np.arange(len(s))):
                return False  # a group is not a range of the sorted rows
            if form == "linear" and any(np.ndim(b.b) and np.shape(b.b)[0] != d for b in bs):
                return False
        return True

    def _segments(self):
        """One row (form, start, stop, width, damped) per colour group, in the order of the sweep."""
        out, start = [], {"distance": 0, "linear": 0}
        for form, bs in zip(self._forms, self.batches):  # a loop over the few sets, then their colours
            for b in bs:
                r = len(b.idx)
                out.append((0 if form == "distance" else 1, start[form], start[form] + r, b.idx.shape[1],
                            int(bool(b.damped) and self.formulation == "xpbd")))
                start[form] += r
        return np.array(out, dtype=np.int64).reshape(-1, 5)

    def _coefficients(self, hs):
        """alpha~, 1 / denominator and gamma of every row for substeps of hs (the batches' own; again when hs changes)."""
        if self._hs == hs:
            return
        rows = {"distance": [], "linear": []}
        for s, bs, form in zip(self.sets, self.batches, self._forms):  # a loop over the few sets, then their colours
            for b in bs:
                b.coefficients(hs, self.formulation)
                rows[form].append(np.stack([_rows(a, len(b.idx)) for a in (b.at, b.inv, b.gamma)], axis=1))
        if rows["distance"]:
            self.dco[:, 1:] = np.concatenate(rows["distance"])
        if rows["linear"]:
            self.lco[:] = np.concatenate(rows["linear"])
        self._hs = hs

    def multipliers(self):
        """Zero multipliers for a step: a flat distance array, a (d, r) linear one, and each set's view into them."""
        d_lam, l_lam = np.zeros(len(self.ij)), np.zeros((self.d, len(self.idx)))
        views = [d_lam[a:b] if f == "distance" else l_lam[:, a:b] for f, a, b in self._spans]
        return d_lam, l_lam, views

    @staticmethod
    def force_terms(forces, d):
        """The forces as rows the prediction evaluates itself, shape (q, 4); None if one of them it cannot.

        By :attr:`~particles.forces.force.Force.compiled_role`, in the forces' order:
        uniform gravity ``(0, g)`` and damping, ``(1, d, 0, 0)`` for ``-d v``
        or ``(2, rate, 0, 0)`` for ``-rate m v``. Any other force (wind, a
        force of the user's) is evaluated by the solver in NumPy instead.
        """
        terms = []
        for force in forces:  # a loop over the few force objects
            role = getattr(force, "compiled_role", None)
            if role == "gravity" and np.shape(force.g) == (d,):
                terms.append([0.0, *np.asarray(force.g, dtype=float), *[0.0] * (3 - d)])
            elif role == "damping":
                rate = getattr(force, "rate", None)
                terms.append([1.0, float(force.d), 0.0, 0.0] if rate is None else [2.0, float(rate), 0.0, 0.0])
            else:
                return None
        return np.array(terms, dtype=np.float64).reshape(-1, 4)

    def substep(self, x, v, a, terms, hs, iterations, lams, measure=False):
        """One substep on x, v (d, n) in place; returns the largest ``|C|`` of the distances after it if `measure`.

        `a` (d, n): the accelerations, or None for the forces of `terms`
        (:meth:`force_terms`). `lams` from :meth:`multipliers`: set to zero,
        then accumulated (the views hold each set's multipliers afterwards).
        """
        self._coefficients(hs)
        given = a is not None
        a = np.ascontiguousarray(a, dtype=np.float64) if given else np.zeros((self.d, 1))
        # each colour group is a parallel loop of its own, and starting the threads costs 2 to 7 microseconds
        # (bench/bench_threads.py): threads only when the groups are long (pick's threshold on the mean group)
        kernel = pick(substep_kernel, (len(self.ij) + len(self.idx)) // max(1, len(self.segments)))
        kernel(x, v, a, given, terms, self.m, self.free, float(hs), int(iterations), self.formulation == "xpbd",
               self.segments, self.P, self.ij, self.dco, lams[0], self.idx, self.c, self.wc, self.offset, self.lco,
               lams[1])
        return self.violation(x) if measure else None

    def violation(self, x):
        """The largest ``|C|`` over the distance constraints at x (d, n), in metres (0 without any)."""
        pick(distance_violation, len(self.ij))(x, self.ij, self.dco, self.violations)
        return float(np.max(self.violations, initial=0.0))
