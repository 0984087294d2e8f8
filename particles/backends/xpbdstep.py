"""The compiled XPBD substep: prediction, every colour group's projections and the new velocities in one call.

:class:`particles.xpbd.XPBD` (and PBD) with the numba backend and the
Gauss-Seidel method hands each substep to :meth:`CompiledSubstep.substep`:
one compiled call (:func:`particles.backends._pbd_kernels.substep`) that
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
(:meth:`particles.pbdconstraints._ConstraintSet._coefficients`), gathered again when
``hs`` changes. Uniform gravity is folded into the prediction; any other
external force is evaluated by the solver in NumPy and passed in as
accelerations.

Every projection does the NumPy code's operations in the same order, so a
substep gives the same bits as the NumPy solver's (tested to 1e-12), on any
number of threads: within a colour every particle is written by one row.
Importing this module imports numba; :mod:`particles.xpbd` imports it only
when :func:`particles.backends.kernels_for` resolves to numba.
"""

import numpy as np

from ._kernels import pick
from ._pbd_kernels import distance_violation
from ._pbd_kernels import substep as substep_kernel

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
    pinned : ndarray of int
        Pinned particles (inverse mass 0).
    formulation : {"xpbd", "pbd"}
    d : int
        Dimension, 2 or 3.

    Use :meth:`applies` first: it says whether every set has a compiled form.
    """

    def __init__(self, sets, batches, m, pinned, formulation, d):
        self.sets = sets
        self.batches = batches  # the solver's list: rebuilt batches (set_stiffness) mean a new layout
        self.formulation = formulation
        self.n, self.d = len(m), d
        self.m = np.ascontiguousarray(m, dtype=np.float64)
        self.free = np.ones(self.n, dtype=np.bool_)
        self.free[pinned] = False
        self.x_n = np.empty((d, self.n))
        self._hs = None
        forms = [s.compiled_form for s in sets]
        distance = [(s, bs) for s, bs, f in zip(sets, batches, forms) if f == "distance"]
        linear = [(s, bs) for s, bs, f in zip(sets, batches, forms) if f == "linear"]
        self._order = [(f, bs) for f, bs in zip(forms, batches)]
        # distance rows: every distance set's batches one after another
        dist_batches = [b for _, bs in distance for b in bs]
        self.dist = dict(batches=dist_batches, **self._distance_arrays(dist_batches))
        lin_batches = [b for _, bs in linear for b in bs]
        self.lin = dict(batches=lin_batches, **self._linear_arrays(lin_batches, d))
        # each set's rows in the flat arrays, for its multipliers
        self._spans = []
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

    @staticmethod
    def _distance_arrays(batches):
        cat = np.concatenate

        def joined(get, dtype=np.float64):
            parts = [np.asarray(get(b), dtype=dtype) for b in batches]
            return np.ascontiguousarray(cat(parts)) if parts else np.zeros(0, dtype=dtype)

        return dict(i=joined(lambda b: b.idx[:, 0], np.int64), j=joined(lambda b: b.idx[:, 1], np.int64),
                    L0=joined(lambda b: b.L0), wi=joined(lambda b: b.wi), wj=joined(lambda b: b.wj),
                    rows=sum(len(b.idx) for b in batches))

    @staticmethod
    def _linear_arrays(batches, d):
        r = sum(len(b.idx) for b in batches)
        idx, c, wc, offset = np.zeros((r, 3), np.int64), np.zeros((r, 3)), np.zeros((r, 3)), np.zeros((r, d))
        start = 0
        for b in batches:  # a loop over the colour groups of the linear sets
            k, stop = b.idx.shape[1], start + len(b.idx)
            idx[start:stop, :k], c[start:stop, :k], wc[start:stop, :k] = b.idx, b.c, b.wc
            offset[start:stop] = np.asarray(b.b, dtype=float).T if np.ndim(b.b) else b.b
            start = stop
        return dict(idx=idx, c=c, wc=wc, offset=offset, rows=r)

    def _segments(self):
        """One row (form, start, stop, width, damped) per colour group, in the order of the sweep."""
        out, start = [], {"distance": 0, "linear": 0}
        for form, bs in self._order:  # a loop over the few sets, then their colours
            for b in bs:
                r = len(b.idx)
                out.append((0 if form == "distance" else 1, start[form], start[form] + r, b.idx.shape[1],
                            int(bool(b.damped) and self.formulation == "xpbd")))
                start[form] += r
        return np.array(out, dtype=np.int64).reshape(-1, 5)

    def _coefficients(self, hs):
        """alpha~, 1 / denominator and gamma per row of each form for substeps of hs (gathered when hs changes)."""
        if self._hs == hs:
            return
        for part, form in ((self.dist, "distance"), (self.lin, "linear")):
            at, inv, gamma = [], [], []
            for s, bs in zip(self.sets, self.batches):  # a loop over the few sets, then their colours
                if s.compiled_form != form:
                    continue
                for b in bs:
                    s._coefficients(hs, b, self.formulation)
                    at.append(_rows(b.at, len(b.idx)))
                    inv.append(_rows(b.inv, len(b.idx)))
                    gamma.append(_rows(b.gamma, len(b.idx)))
            part["at"], part["inv"], part["gamma"] = (np.concatenate(a) if a else np.zeros(0) for a in (at, inv, gamma))
        self._hs = hs

    def multipliers(self):
        """Zero multipliers for a step: a flat distance array, a (d, r) linear one, and each set's view into them."""
        d_lam, l_lam = np.zeros(self.dist["rows"]), np.zeros((self.d, self.lin["rows"]))
        views = [d_lam[a:b] if f == "distance" else l_lam[:, a:b] for f, a, b in self._spans]
        return d_lam, l_lam, views

    def substep(self, x, v, a, G, hs, iterations, lams):
        """One substep on x, v (d, n) in place; `a` (d, n) given accelerations or None for gravity `G` (q, d) alone.

        `lams` from :meth:`multipliers`: set to zero, then accumulated (the views
        hold each set's multipliers afterwards).
        """
        self._coefficients(hs)
        dist, lin = self.dist, self.lin
        given = a is not None
        a = a if given else np.zeros((self.d, 1))
        kernel = pick(substep_kernel, dist["rows"] + lin["rows"])
        kernel(x, v, self.x_n, np.ascontiguousarray(a, dtype=np.float64), given, G, self.m, self.free, float(hs),
               int(iterations), self.formulation == "xpbd", self.segments,
               dist["i"], dist["j"], dist["L0"], dist["wi"], dist["wj"], dist["at"], dist["inv"], dist["gamma"],
               lams[0], lin["idx"], lin["c"], lin["wc"], lin["offset"], lin["at"], lin["inv"], lin["gamma"],
               lams[1])

    def violation(self, x):
        """The largest ``|C|`` over the distance constraints at x (d, n), in metres (0 without any)."""
        dist = self.dist
        out = dist.setdefault("violation", np.empty(dist["rows"]))
        pick(distance_violation, dist["rows"])(x, dist["i"], dist["j"], dist["L0"], out)
        return float(np.max(out, initial=0.0))
