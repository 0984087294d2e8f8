"""Constraint sets of position-based dynamics: distance, isometric bending, attachment.

Each set holds many constraints as index arrays (one constraint per row).
The solvers of :mod:`particles.xpbd` split a set into *batches*
(:class:`Batch`): the rows of one colour group (Gauss-Seidel: they share no
particle, so corrections are written directly) or all rows with a scale per
row (Jacobi: corrections scattered with ``np.bincount``). Positions are
coordinate-major, shape ``(d, n)``, and batches gather and scatter through
flat indices into them, so that every operation runs along the particles.

With inverse masses ``w`` and the gradient ``grad_p C`` of a constraint at
its particles, a projection computes

* PBD:  ``dlambda = -k C / W``;
* XPBD: ``dlambda = (-C - alpha_tilde lambda - gamma grad C . (x - x_n)) / ((1 + gamma) W + alpha_tilde)``,
  ``alpha_tilde = alpha / hs^2``, ``gamma = alpha kd / hs``, and ``lambda += dlambda``,

(both :func:`particles.xpbd.distance.multiplier_step`, PBD with ``alpha_tilde = gamma = 0`` and
``1 / W`` scaled by ``k``) with ``W = sum_p w_p |grad_p C|^2``, and moves
``x_p += w_p grad_p C dlambda``. A constraint whose particles are all pinned
(``W = 0``) is skipped. The reference of one distance pass, with positions
``(n, d)``, is :func:`particles.xpbd.distance.distance_pass`.

**Why isometric bending.** A joint angle ``C = theta - theta0`` (the hair
bending of Müller et al. 2007) or a cloth dihedral angle has no gradient at
the straight rest shape (``theta = |angle|`` is a cone there: ``dtheta/dx`` is
``dc/dx / sin(theta)`` with ``sin(theta) -> 0``), so a projection at rest
divides zero by zero and a nearly straight hair chatters. Bergou et al.
(2006) observed that for inextensible curves and surfaces the bending energy
is *quadratic* in the positions. For three consecutive particles of a hair,
or of a cloth row or column, with rest lengths ``L1 = |x_j - x_i|`` and
``L2 = |x_l - x_j|``,

    C = (x_l - x_j) / L2 - (x_j - x_i) / L1        (a vector, zero when straight)

is the difference of the unit tangents while the lengths hold, so
``|C| = 2 sin(theta / 2) ~ theta``: the energy ``kb |C|^2 / 2`` is the
package's :class:`~particles.forces.Bending` energy ``kb theta^2 / 2`` for
small angles. It is *linear* in the positions: constant gradients
``(1/L1, -(1/L1 + 1/L2), 1/L2)`` per coordinate, one projection solves it
exactly, and nothing is singular at rest. It uses the same triples as the
spring model's bending, so lecture 8 compares like with like. Its limit: the
rest shape must be straight (flat cloth, straight hair).

References
----------
.. [1] M. Müller, B. Heidelberger, M. Hennix and J. Ratcliff, "Position based
   dynamics", J. Vis. Commun. Image R. 18(2), 2007 (distance and bending
   constraints, stiffness, graph colouring of the Gauss-Seidel sweep).
.. [2] M. Macklin, M. Müller and N. Chentanez, "XPBD: position-based
   simulation of compliant constrained dynamics", MIG 2016 (compliance,
   multipliers, damping, eq. 26).
.. [3] M. Bergou, M. Wardetzky, D. Harmon, D. Zorin and E. Grinspun, "A
   quadratic bending model for inextensible surfaces", SGP 2006.
"""

import copy

import numpy as np

from .._checks import as_float_array, index_array, per_item
from ..constraints.colouring import check_groups, color_constraints
from .distance import distance_constraint, multiplier_step

__all__ = ["Distance", "IsometricBending", "IsometricClamp", "Attachment", "ConstraintSet", "Batch"]

_TINY = 1e-150  # guards 1 / L for a constraint of zero length (its direction, 0, makes the product 0)


class Batch:
    """Rows of one set projected together, with everything that does not change between projections.

    Parameters
    ----------
    rows : slice or ndarray of int
        The set's rows (a colour group, or all of them).
    idx : ndarray of int, shape (r, k)
        Their particles.
    w : ndarray, shape (n,)
        Inverse masses of all the particles.
    scale : ndarray, shape (r,), optional
        Jacobi: each row's ``dlambda`` factor; None: a colour group.
    alpha, kd, k : ndarray, shape (r,)
        Compliances, dampings and PBD stiffnesses of the rows.
    W : ndarray, shape (r,)
        ``sum_p w_p |grad_p C|^2`` of each row.
    **geometry
        What the set's projection reads beside (distances: ``L0``; linear sets: ``c``, ``b``, and then
        ``wc = w c`` is kept too).

    Attributes
    ----------
    damped : bool
        Whether a row has both a compliance and a damping (then XPBD reads ``x_n``).
    at, gamma, inv : ndarray or float
        ``alpha / hs^2``, ``alpha kd / hs`` and ``1 / ((1 + gamma) W + alpha_tilde)`` (PBD: 0, 0 and
        ``k / W``) for substeps of :attr:`hs` (:meth:`coefficients`).
    """

    def __init__(self, rows, idx, w, scale, alpha, kd, k, W, **geometry):
        self.rows = rows
        self.idx = idx
        self.w = w[idx]                                   # (r, k) inverse masses
        self.wi, self.wj = self.w[:, 0].copy(), self.w[:, -1].copy()
        self.flat = None if scale is not None else [np.arange(0)] * idx.shape[1]
        self.scale = scale
        self.n = len(w)
        self.alpha, self.kd, self.k, self.W = alpha, kd, k, W
        self.damped = bool(np.any(alpha * kd))
        for name, value in geometry.items():  # a loop over the few arrays of the set's geometry
            setattr(self, name, value)
        if "c" in geometry:  # a linear set: each particle's step is w c dlambda
            self.wc = self.w * self.c
        self.hs = self.formulation = None
        self.at = self.gamma = self.inv = None

    def coefficients(self, hs, formulation):
        """Set :attr:`at`, :attr:`gamma` and :attr:`inv` for substeps of `hs` seconds (kept until hs changes)."""
        if (self.hs, self.formulation) != (hs, formulation):
            if formulation == "pbd":
                self.at, self.gamma = 0.0, 0.0
                self.inv = np.divide(self.k, self.W, out=np.zeros_like(self.W), where=self.W > 0)
            else:
                self.at = self.alpha / (hs * hs)
                self.gamma = self.alpha * self.kd / hs
                denom = (1.0 + self.gamma) * self.W + self.at
                self.inv = np.divide(1.0, denom, out=np.zeros_like(denom), where=denom > 0)
            self.hs, self.formulation = hs, formulation
        return self

    def flats(self, d):
        """Flat indices into a (d, n) array of each particle column, shape (d r,) each."""
        if self.flat is None or len(self.flat[0]) != d * len(self.idx):
            self.flat = [(np.arange(d)[:, None] * self.n + self.idx[:, k]).ravel() for k in range(self.idx.shape[1])]
        return self.flat


class ConstraintSet:
    """Common parts: index arrays, parameters per row, colour groups, batches."""

    _per_row = ("idx", "compliance", "stiffness", "damping")
    _compiled_form = None

    @property
    def compiled_form(self):
        """How the compiled XPBD substep (:mod:`particles.xpbd.compiled_substep`) projects this set, or None.

        ``"distance"`` or ``"linear"`` (a vector constraint linear in the
        positions), declared by a class in ``_compiled_form``; the form holds
        only while ``project`` is that class's own, so that a subclass with
        another projection is projected by its own ``project`` (then the
        solver takes the NumPy sweep for the whole substep).
        """
        for cls in type(self).__mro__:  # a loop over the few classes of the set's lineage
            if "_compiled_form" in cls.__dict__:
                form = cls._compiled_form
                return form if form is not None and type(self).project is cls.project else None
        return None

    def _setup(self, idx, compliance, stiffness, damping, kind, groups):
        self.idx = idx
        s = len(idx)
        self.compliance = per_item(compliance, "compliance", s)
        self.stiffness = per_item(stiffness, "stiffness", s)
        if np.any(self.stiffness > 1):
            raise ValueError("stiffness must lie in [0, 1] (PBD: 1 solves the constraint fully)")
        self.damping = per_item(damping, "damping", s)
        self.kind = kind
        self.highest = int(idx.max()) if s else -1
        self._groups = None if groups is None else check_groups(groups, idx)

    def __len__(self):
        return len(self.idx)

    def groups(self, n):
        """Colour groups of the rows (computed once): lists of row numbers that share no particle."""
        if self._groups is None:
            self._groups = color_constraints(self.idx, n)
        return self._groups

    def by_colour(self, n):
        """A copy whose rows are sorted by colour group, each group a slice; and the order (s,) used.

        Row ``k`` of the copy is row ``order[k]`` of this set. Solvers sweep the
        copy: a group's parameters and multipliers are then views, not gathers.
        Within a group the rows go by their lowest particle (the order does not
        change the result, the rows share no particle): a compiled sweep then
        walks through the particles once per group instead of jumping about.
        """
        groups = [np.asarray(g) for g in self.groups(n)]
        groups = [g[np.argsort(self.idx[g].min(axis=1), kind="stable")] for g in groups]  # a loop over colours
        order = np.concatenate(groups) if groups else np.zeros(0, dtype=np.int64)
        new = copy.copy(self)
        for name in self._per_row:  # a loop over the per-row arrays of the set
            setattr(new, name, getattr(self, name)[order])
        ends = np.cumsum([0] + [len(g) for g in groups])
        new._groups = [slice(int(a), int(b)) for a, b in zip(ends[:-1], ends[1:])]
        return new, order

    def jacobi_scale(self, w):
        """1 / (largest number of this set's constraints at a free particle of each row), shape (s,)."""
        n = len(w)
        counts = np.zeros(n)
        for c in range(self.idx.shape[1]):  # a loop over the k particles of a constraint
            counts += np.bincount(self.idx[:, c], minlength=n)
        worst = np.max(np.where(w[self.idx] > 0, counts[self.idx], 0.0), axis=1, initial=0.0)
        return 1.0 / np.maximum(worst, 1.0)

    def batches(self, w, method):
        """The batches of a sweep: one per colour group (``"gauss-seidel"``) or one of all rows (``"jacobi"``)."""
        n = len(w)
        if method == "jacobi":
            return [self._batch(slice(None), w, n, self.jacobi_scale(w))]
        return [self._batch(g, w, n) for g in self.groups(n)]

    def _batch(self, rows, w, n, scale=None):
        """The batch of `rows` (see :class:`Batch`), with the set's geometry (:meth:`_geometry`)."""
        idx = self.idx[rows]
        return Batch(rows, idx, w, scale, self.compliance[rows], self.damping[rows], self.stiffness[rows],
                     self._W(w[idx], rows), **self._geometry(rows))

    @staticmethod
    def _dlambda(C, lam, b, formulation, rel=None):
        """Multiplier increments of batch b from its constraint values C (and their change `rel`, damped XPBD)."""
        if formulation == "pbd":
            dl = multiplier_step(C, 0.0, 0.0, 0.0, 0.0, b.inv)
        else:
            dl = multiplier_step(C, lam, b.at, b.gamma if rel is not None else 0.0, 0.0 if rel is None else rel,
                                 b.inv)
        if b.scale is not None:
            dl *= b.scale
        return dl


class Distance(ConstraintSet):
    """Distance constraints ``C = |x_i - x_j| - L0``: the springs of strings, hair and cloth.

    Parameters
    ----------
    indices : array_like of int, shape (s, 2)
        The two particles of each constraint.
    rest_length : float or array_like, shape (s,), optional
        ``L0`` in metres (default: the distances in `x`).
    compliance : float or array_like, shape (s,)
        XPBD's ``alpha`` in m/N, >= 0 (``1 / k`` for a spring ``k``; 0: rigid).
    stiffness : float or array_like, shape (s,)
        PBD's ``k`` in [0, 1].
    damping : float or array_like, shape (s,)
        XPBD damping along the constraint, in kg/s (a spring's ``kd``);
        acts only with a compliance > 0.
    x : array_like, shape (n, d), optional
        Positions that give the rest lengths.
    kind : str, optional
        A label.
    groups : list of array_like of int, or ndarray of int, shape (s,), optional
        Colour groups (rows sharing no particle, swept in order) or a colour
        per row (swept in increasing order); default :func:`color_constraints`.

    Notes
    -----
    Gradients ``grad_i C = u = (x_i - x_j) / |x_i - x_j|``, ``grad_j C = -u``, so
    ``W = w_i + w_j``. A constraint of zero current length is left alone.

    Examples
    --------
    >>> c = Distance([[0, 1], [1, 2]], x=[[0.0, 0.0], [1.0, 0.0], [1.0, 2.0]], compliance=1e-3)
    >>> c.rest_length.tolist(), c.values([[0.0, 0.0], [1.5, 0.0], [1.5, 2.0]]).tolist()
    ([1.0, 2.0], [0.5, 0.0])
    """

    def __init__(self, indices, rest_length=None, compliance=0.0, stiffness=1.0, damping=0.0, x=None,
                 kind=None, groups=None):
        ij = index_array(indices, "indices", 2)
        if np.any(ij[:, 0] == ij[:, 1]):
            raise ValueError("indices must join two different particles in every constraint")
        if rest_length is None:
            if x is None:
                raise ValueError("give rest_length, or positions x from which to take the rest lengths")
            x = as_float_array(x, "x", ndim=2)
            if len(ij) and ij.max() >= len(x):
                raise ValueError(f"indices refer to particle {ij.max()} but x has only {len(x)} particles")
            rest_length = np.linalg.norm(x[ij[:, 0]] - x[ij[:, 1]], axis=1)
        self.rest_length = per_item(rest_length, "rest_length", len(ij))
        self._setup(ij, compliance, stiffness, damping, kind, groups)
        self.i, self.j = ij[:, 0].copy(), ij[:, 1].copy()

    @classmethod
    def concatenate(cls, sets):
        """One set holding the rows of several, in order (coloured together by a solver)."""
        sets = list(sets)
        joined = cls(np.concatenate([s.idx for s in sets]), np.concatenate([s.rest_length for s in sets]),
                     compliance=np.concatenate([s.compliance for s in sets]),
                     stiffness=np.concatenate([s.stiffness for s in sets]),
                     damping=np.concatenate([s.damping for s in sets]), kind="+".join(str(s.kind) for s in sets))
        return joined

    def new_multipliers(self, d):
        """Zero multipliers, shape (s,)."""
        return np.zeros(len(self))

    def values(self, x):
        """``C = |x_i - x_j| - L0`` of every constraint, shape (s,), in metres (x of shape (n, d))."""
        x = np.asarray(x, dtype=float)
        return distance_constraint(np.linalg.norm(x[self.i] - x[self.j], axis=1), self.rest_length)

    _per_row = ConstraintSet._per_row + ("rest_length", "i", "j")
    _compiled_form = "distance"

    @staticmethod
    def _W(w, rows):
        return w[:, 0] + w[:, 1]

    def _geometry(self, rows):
        return {"L0": self.rest_length[rows]}

    def project(self, b, x, x_n, lam, hs, formulation):
        """Project batch `b` on positions `x` (d, n) in place; `lam` (s,) of the set, updated (XPBD).

        ``x_n`` holds the positions at the start of the substep (for damping).
        """
        b.coefficients(hs, formulation)
        d = len(x)
        xf = x.reshape(-1)
        if b.scale is None:
            fi, fj = b.flats(d)
            xi, xj = xf[fi].reshape(d, -1), xf[fj].reshape(d, -1)
        else:
            xi, xj = x[:, b.idx[:, 0]], x[:, b.idx[:, 1]]
        dv = xi - xj
        L = np.sqrt((dv * dv).sum(axis=0))
        if formulation == "xpbd" and not b.damped and b.scale is None:  # the common case, in fewest operations
            dl = multiplier_step(distance_constraint(L, b.L0), lam[b.rows], b.at, 0.0, 0.0, b.inv)
        else:
            rel = None
            if b.damped and formulation == "xpbd":
                rel = (dv * (dv - (x_n[:, b.idx[:, 0]] - x_n[:, b.idx[:, 1]]))).sum(axis=0) / np.maximum(L, _TINY)
            dl = self._dlambda(L - b.L0, lam[b.rows], b, formulation, rel)
        if formulation == "xpbd":
            lam[b.rows] += dl
        dv *= dl / np.maximum(L, _TINY)  # u dlambda
        if b.scale is None:  # a colour group: no particle twice
            xf[fi] = (xi + b.wi * dv).ravel()
            xf[fj] = (xj - b.wj * dv).ravel()
        else:
            n = x.shape[1]
            for a in range(d):  # a loop over the d coordinates
                x[a] += np.bincount(b.idx[:, 0], b.wi * dv[a], minlength=n) - np.bincount(b.idx[:, 1], b.wj * dv[a],
                                                                                          minlength=n)


class _Linear(ConstraintSet):
    """Vector constraints linear in the positions: ``C = sum_k c_k x_{idx_k} - b`` (one row per constraint).

    Each coordinate is an independent scalar constraint with the constant
    gradient ``c_k`` at particle ``idx_k``, so ``W = sum_k w_k c_k^2``, and one
    projection solves it exactly. Multipliers have shape (d, s).
    """

    _per_row = ConstraintSet._per_row + ("coefficients", "offset")
    _compiled_form = "linear"

    def new_multipliers(self, d):
        """Zero multipliers, shape (d, s)."""
        return np.zeros((d, len(self)))

    def values(self, x):
        """The vector ``C`` of every constraint, shape (s, d), for positions `x` of shape (n, d)."""
        x = np.asarray(x, dtype=float)
        return np.einsum("sk,skd->sd", self.coefficients, x[self.idx]) - self.offset

    def _W(self, w, rows):
        c = self.coefficients[rows]
        return np.einsum("rk,rk->r", w, c * c)

    def _geometry(self, rows):
        c = self.coefficients[rows]
        return {"c": c, "b": np.ascontiguousarray(self.offset[rows].T)}  # b: (d, r)

    def project(self, b, x, x_n, lam, hs, formulation):
        """As :meth:`Distance.project`; `lam` has shape (d, s)."""
        b.coefficients(hs, formulation)
        d, width = len(x), b.idx.shape[1]
        if b.scale is None:
            xf = x.reshape(-1)
            flats = b.flats(d)
            xs = [xf[f].reshape(d, -1) for f in flats]
        else:
            xs = [x[:, b.idx[:, k]] for k in range(width)]
        C = sum(b.c[:, k] * xs[k] for k in range(width)) - b.b
        rel = None
        if b.damped and formulation == "xpbd":
            rel = C + b.b - sum(b.c[:, k] * x_n[:, b.idx[:, k]] for k in range(width))  # C(x) - C(x_n)
        dl = self._dlambda(C, lam[:, b.rows], b, formulation, rel)
        if formulation == "xpbd":
            lam[:, b.rows] += dl
        for k in range(width):  # a loop over the particles of a constraint
            if b.scale is None:
                xf[flats[k]] = (xs[k] + b.wc[:, k] * dl).ravel()
            else:
                step = b.wc[:, k] * dl
                for a in range(d):  # a loop over the d coordinates
                    x[a] += np.bincount(b.idx[:, k], step[a], minlength=x.shape[1])


class IsometricBending(_Linear):
    """Isometric bending at the joints of chains: ``C = (x_l - x_j) / L2 - (x_j - x_i) / L1`` (a vector).

    Parameters
    ----------
    triples : array_like of int, shape (b, 3)
        Consecutive particles ``(i, j, l)`` of a hair or of a cloth row or column.
    rest_lengths : array_like, shape (b, 2), optional
        ``(L1, L2)`` in metres; default from `x`.
    compliance : float or array_like, shape (b,)
        XPBD's ``alpha`` in 1/(N m), >= 0: ``1 / kb`` for the joint stiffness
        ``kb`` (N m / rad) of :class:`particles.forces.Bending`.
    stiffness, kind, groups
        As for :class:`Distance`.
    damping : float or array_like, shape (b,)
        XPBD damping, in N m s (per unit of ``C`` and of its rate).
    x : array_like, shape (n, d), optional
        Straight rest positions that give the rest lengths.

    Notes
    -----
    See the module notes for why this model: linear in the positions, each
    coordinate an independent scalar constraint with the constant gradient
    ``(1/L1, -(1/L1 + 1/L2), 1/L2)``; ``|C| = 2 sin(theta/2)`` while the
    segments keep their rest lengths. Multipliers have shape (d, b).

    Examples
    --------
    A right angle at the middle joint: ``|C| = 2 sin(45 deg) = sqrt(2)``.

    >>> bend = IsometricBending([[0, 1, 2]], x=[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    >>> bend.values([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]).tolist()
    [[-1.0, 1.0]]
    """

    def __init__(self, triples, rest_lengths=None, compliance=0.0, stiffness=1.0, damping=0.0, x=None,
                 kind=None, groups=None):
        ijl = index_array(triples, "triples", 3)
        if rest_lengths is None:
            if x is None:
                raise ValueError("give rest_lengths, or positions x from which to take them")
            x = as_float_array(x, "x", ndim=2)
            if len(ijl) and ijl.max() >= len(x):
                raise ValueError(f"triples refer to particle {ijl.max()} but x has only {len(x)} particles")
            rest_lengths = np.stack([np.linalg.norm(x[ijl[:, 1]] - x[ijl[:, 0]], axis=1),
                                     np.linalg.norm(x[ijl[:, 2]] - x[ijl[:, 1]], axis=1)], axis=1)
        L = as_float_array(rest_lengths, "rest_lengths", shape=(len(ijl), 2))
        if np.any(L <= 0):
            raise ValueError("rest_lengths must be > 0 (in metres)")
        self.coefficients = np.stack([1.0 / L[:, 0], -(1.0 / L[:, 0] + 1.0 / L[:, 1]), 1.0 / L[:, 1]], axis=1)
        d = x.shape[1] if x is not None else 3
        self.offset = np.zeros((len(ijl), d))
        self._setup(ijl, compliance, stiffness, damping, kind, groups)

    def values(self, x):
        """The vector ``C`` of every joint, shape (b, d) (dimensionless; ``|C| ~ theta``)."""
        x = np.asarray(x, dtype=float)
        return np.einsum("bk,bkd->bd", self.coefficients, x[self.idx])

    def _geometry(self, rows):
        return {"c": self.coefficients[rows], "b": 0.0}  # straight rest shapes: no offset, in any dimension


class IsometricClamp(_Linear):
    """A clamped end: ``C = (x_j - x_i) / L0 - u0`` (a vector), the first segment held along ``u0``.

    The isometric counterpart of :class:`particles.forces.Clamp`: while the
    segment keeps its length ``L0``, ``|C| = 2 sin(theta / 2) ~ theta`` for the
    angle ``theta`` between ``x_j - x_i`` and ``u0``, and ``C`` is linear in the
    positions.

    Parameters
    ----------
    pairs : array_like of int, shape (c, 2)
        ``(i, j)``: the clamped end (usually pinned) and its neighbour.
    direction : array_like, shape (d,) or (c, d)
        The clamped direction(s) ``u0`` (normalized here).
    rest_length : float or array_like, shape (c,)
        ``L0`` in metres.
    compliance : float or array_like, shape (c,)
        ``1 / kb`` for the clamp stiffness ``kb`` (N m / rad).
    stiffness, damping, kind, groups
        As for :class:`IsometricBending`.

    Examples
    --------
    >>> clamp = IsometricClamp([[0, 1]], [1.0, 0.0], 0.5)
    >>> clamp.values([[0.0, 0.0], [0.0, 0.5]]).tolist()   # turned by 90 degrees: |C| = sqrt(2)
    [[-1.0, 1.0]]
    """

    def __init__(self, pairs, direction, rest_length, compliance=0.0, stiffness=1.0, damping=0.0, kind=None,
                 groups=None):
        ij = index_array(pairs, "pairs", 2)
        u = as_float_array(direction, "direction", ndim=(1, 2))
        u = np.broadcast_to(u, (len(ij), u.shape[-1])).copy() if u.ndim == 1 else u
        if u.shape[0] != len(ij) or np.any(np.linalg.norm(u, axis=1) == 0):
            raise ValueError(f"direction must be non-zero, of shape (d,) or ({len(ij)}, d), got shape {u.shape}")
        L0 = per_item(rest_length, "rest_length", len(ij), positive=True)
        self.coefficients = np.stack([-1.0 / L0, 1.0 / L0], axis=1)
        self.offset = u / np.linalg.norm(u, axis=1)[:, None]
        self._setup(ij, compliance, stiffness, damping, kind, groups)


class Attachment(_Linear):
    """Particles held to points: ``C = x_i - p`` (a vector), rigidly or through a compliance.

    Parameters
    ----------
    indices : array_like of int, shape (p,)
        The attached particles.
    targets : array_like, shape (p, d)
        The points, in metres.
    compliance : float or array_like, shape (p,)
        XPBD's ``alpha`` in m/N (0: held exactly, as far as the iterations go).
    stiffness, damping, kind, groups
        As for :class:`Distance`.

    Examples
    --------
    >>> Attachment([2], [[0.0, 1.0]]).values([[0, 0], [0, 0], [0.5, 1.0]]).tolist()
    [[0.5, 0.0]]
    """

    def __init__(self, indices, targets, compliance=0.0, stiffness=1.0, damping=0.0, kind=None, groups=None):
        idx = np.asarray(indices)
        idx = index_array(idx.reshape(-1, 1) if idx.size else idx, "indices", 1)
        self.targets = as_float_array(targets, "targets", ndim=2)
        if len(self.targets) != len(idx):
            raise ValueError(f"targets must have one row per attached particle ({len(idx)}), got "
                             f"{len(self.targets)}")
        self.coefficients = np.ones((len(idx), 1))
        self.offset = self.targets
        self._setup(idx, compliance, stiffness, damping, kind, groups)
