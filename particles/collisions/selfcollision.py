"""Cloth self-collision: particles of a cloth keep a minimum distance from each other.

A cloth that folds, or two sheets that fall onto each other, must not pass
through itself. This module treats the cloth as particles of diameter
``thickness`` (the position-based particle approach of Müller et al. [2]_,
with the proximity idea of Bridson, Fedkiw and Anderson [1]_: act on pairs
that come closer than a thickness, before they cross):

1. **Who may collide.** Particles that are close in the *rest* state (closer
   than ``rest_distance``, or joined by a spring) belong to the same piece of
   cloth and never repel: otherwise the cloth would push itself apart. This
   list is computed once, from the rest positions, and stored as sorted pair
   keys ``i n + j`` (``i < j``).
2. **Detection.** After a time step, the pairs closer than ``thickness`` are
   found with the bucket grid of :mod:`particles.neighbors` (cells of side
   ``thickness``, O(n)), and the excluded pairs are dropped.
3. **Positions.** Each close pair is pushed apart along its line, to exactly
   ``thickness``, with inverse-mass weights: particle ``i`` moves by
   ``w_i (thickness - r) n`` and ``j`` by ``-w_j (thickness - r) n`` with
   ``w_i = m_i^-1 / (m_i^-1 + m_j^-1)``, which keeps the centre of mass (and a
   pinned particle, of infinite mass, stays). Pairs are corrected in groups
   that share no particle (:func:`particles.constraints.colouring.color_constraints`), a
   Gauss-Seidel sweep; pushing one pair apart can bring another together, so
   search and sweep are repeated up to ``iterations`` times, until no pair is
   closer than ``thickness (1 - tol)``.
4. **Velocities.** The push itself adds no velocity (as
   :class:`particles.collisions.Collider` with ``method="project"``). Each
   pair found in step 2 or 3 whose particles still approach each other
   (``(v_i - v_j) . n < 0``) gets an impulse along ``n`` that sets their
   relative normal velocity to ``-eps`` times its value (``restitution = 0``,
   the default: perfectly inelastic, the pair then slides together), and
   Coulomb friction reduces their relative tangential velocity by at most
   ``friction`` times the normal change, never reversing it. The impulses
   are equal and opposite, so momentum is conserved (pinned particles excepted).

**Composition.** :meth:`SelfCollision.stepper` wraps a stepper like
:meth:`particles.constraints.ProvotConstraint.stepper` and
:meth:`particles.collisions.Collider.stepper`; put Provot's projection
innermost and the collisions with bodies outermost, so that no particle ends
a step inside a body. The body's fix then runs after the push and may undo
part of it (a particle of a lower layer pushed into the floor is moved back
up): with two sheets resting on a floor, the closest pair measured 0.989
``thickness`` in ``tests/library/collisions/test_selfcollision.py``.

Limits: only particle-particle proximity is tested, at the end of a step.
A particle can slip between two others of a sheet when ``thickness`` is less
than about ``dx / sqrt(2)`` on a square grid of spacing ``dx`` (the hole at
the centre of a cell), or when it moves more than about ``thickness`` in one
step; Bridson et al. [1]_ add point-triangle and edge-edge tests and a
continuous (swept) collision check for both.

References
----------
.. [1] R. Bridson, R. Fedkiw and J. Anderson, "Robust treatment of collisions,
   contact and friction for cloth animation", ACM Transactions on Graphics
   21(3) (SIGGRAPH 2002), 594-603 (proximity repulsion within a thickness,
   inelastic normal impulses, Coulomb friction).
.. [2] M. Müller, B. Heidelberger, M. Hennix and J. Ratcliff, "Position based
   dynamics", Journal of Visual Communication and Image Representation 18(2),
   2007, 109-118 (projection of positions with inverse-mass weights); see also
   M. Macklin, M. Müller, N. Chentanez and T.-Y. Kim, "Unified particle
   physics for real-time applications", ACM SIGGRAPH 2014 (particles closer
   than a rest distance do not collide).
"""

from dataclasses import dataclass

import numpy as np

from .._checks import (as_float_array, count, index_array, mass_array, nonnegative_number, pinned_indices,
                       positive_number, restitution_coefficient)
from .._vectors import unit
from ..constraints.colouring import color_constraints
from ..forces.pairs import pair_differences
from ..integrators.solvers import after
from ..neighbors import CellGrid, all_pairs

__all__ = ["SelfCollision", "SelfCollisionResult"]


@dataclass(frozen=True)
class SelfCollisionResult:
    """What one self-collision fix did.

    Attributes
    ----------
    x, v : ndarray, shape (n, d) or None
        Corrected positions (m) and velocities (m/s); None in
        :attr:`SelfCollision.history`.
    pairs : int
        Non-neighbour pairs closer than ``thickness`` before the fix.
    min_distance : float
        Smallest distance of a non-neighbour pair after the fix, in metres,
        among the pairs closer than ``thickness``; ``inf`` when none is (a
        pair pushed to exactly ``thickness`` may come out a few ulps closer
        and be listed).
    iterations : int
        Search-and-push passes made (0 when nothing was too close).
    converged : bool
        Whether every non-neighbour pair ended at least ``thickness (1 - tol)`` apart.
    """

    x: np.ndarray
    v: np.ndarray
    pairs: int
    min_distance: float
    iterations: int
    converged: bool


class SelfCollision:
    """Particle-particle self-collision of a cloth, applied after each step.

    Parameters
    ----------
    thickness : float
        Smallest allowed distance between two particles that are not rest
        neighbours, in metres (> 0). On a square grid of spacing ``dx``, use at
        least ``0.75 dx`` so that a particle cannot pass through the centre of
        a cell of the other layer.
    x_rest : array_like, shape (n, d)
        Rest positions, in metres (a flat cloth before it moves).
    m : float or array_like, shape (n,)
        Masses, in kg, > 0 (for the inverse-mass weights).
    pinned : array_like of int or bool
        Particles that never move (infinite mass).
    exclude : array_like of int, shape (s, 2), optional
        Pairs that never collide besides the rest neighbours, e.g. the
        springs of the cloth.
    rest_distance : float, optional
        Pairs closer than this in `x_rest` never collide, in metres, >=
        `thickness` (default ``2 thickness``).
    iterations : int
        Largest number of search-and-push passes per step (>= 1).
    tol : float
        Relative tolerance: passes stop when every pair is at least
        ``thickness (1 - tol)`` apart, in [0, 1).
    restitution : float
        Coefficient of restitution of the pairs' normal velocity, in [0, 1].
    friction : float
        Coulomb friction coefficient between the layers, >= 0.

    Attributes
    ----------
    excluded : ndarray of int, shape (e,)
        Sorted keys ``i n + j`` (``i < j``) of the pairs that never collide.
    history : list of SelfCollisionResult
        One entry per step taken through :meth:`stepper` (without x and v).

    Examples
    --------
    Two particles 1 cm apart, 3 cm apart at rest, with a thickness of 2 cm:

    >>> sc = SelfCollision(0.02, [[0.0, 0.0, 0.0], [0.03, 0.0, 0.0]], rest_distance=0.025)
    >>> res = sc.resolve([[0.0, 0.0, 0.0], [0.01, 0.0, 0.0]], [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    >>> res.x[:, 0].round(12).tolist(), res.v[:, 0].tolist(), res.pairs
    ([-0.005, 0.015], [0.0, 0.0], 1)
    """

    def __init__(self, thickness, x_rest, m=1.0, pinned=(), exclude=None, rest_distance=None,
                 iterations=20, tol=1e-3, restitution=0.0, friction=0.0):
        self.thickness = positive_number(thickness, "thickness", "metres")
        self.x_rest = np.array(as_float_array(x_rest, "x_rest", ndim=2))
        n = self.n = len(self.x_rest)
        self.m = np.array(mass_array(m, n))
        self.inverse_mass = 1.0 / self.m
        self.inverse_mass[pinned_indices(pinned, n)] = 0.0
        if rest_distance is None:
            rest_distance = 2.0 * self.thickness
        self.rest_distance = positive_number(rest_distance, "rest_distance", "metres")
        if self.rest_distance < self.thickness:
            raise ValueError(f"rest_distance must be >= thickness = {self.thickness:g} (else particles "
                             f"close at rest push each other apart), got {rest_distance!r}")
        self.iterations = count(iterations, "iterations", 1)
        self.tol = nonnegative_number(tol, "tol")
        if self.tol >= 1:
            raise ValueError(f"tol must lie in [0, 1) (a fraction of the thickness), got {tol!r}")
        self.restitution = restitution_coefficient(restitution)
        self.friction = nonnegative_number(friction, "friction")
        i, j = CellGrid(self.x_rest, self.rest_distance).pairs()
        keys = [self._keys(i, j)]
        if exclude is not None:
            ij = index_array(exclude, "exclude", 2)
            if len(ij) and (ij.max() >= n or ij.min() < 0):
                raise ValueError(f"exclude must hold particle indices from 0 to {n - 1}, got {ij.max()}")
            keys.append(self._keys(ij[:, 0], ij[:, 1]))
        self.excluded = np.unique(np.concatenate(keys))
        self.history = []

    @classmethod
    def from_system(cls, system, thickness, **options):
        """Self-collision of a :class:`~particles.massspring.MassSpringSystem` at its current state.

        The current positions are the rest positions, every spring's pair is
        excluded, and masses and pins come from the system.
        """
        return cls(thickness, system.X[:, 0], m=system.m, pinned=system.pinned,
                   exclude=system.spring_indices(), **options)

    def _keys(self, i, j):
        """One integer per unordered pair, ``min n + max``."""
        return np.minimum(i, j).astype(np.int64) * self.n + np.maximum(i, j)

    def is_neighbour(self, i, j):
        """Whether each pair ``(i[k], j[k])`` is excluded: close at rest, or listed in `exclude`.

        Parameters
        ----------
        i, j : array_like of int, shape (p,)
            Particle indices, in [0, n).

        Returns
        -------
        ndarray of bool, shape (p,)
            True for the pairs that never collide.
        """
        i, j = np.asarray(i), np.asarray(j)
        if i.shape != j.shape or i.ndim != 1 or (i.size and not np.issubdtype(i.dtype, np.integer)) \
                or (j.size and not np.issubdtype(j.dtype, np.integer)):
            raise ValueError(f"i and j must be integer arrays of the same shape (p,), got shapes {i.shape} and {j.shape}")
        if i.size and (min(i.min(), j.min()) < 0 or max(i.max(), j.max()) >= self.n):
            raise ValueError(f"i and j must hold particle indices from 0 to {self.n - 1}")
        return self._is_excluded(self._keys(i, j))

    def _is_excluded(self, keys):
        pos = np.minimum(np.searchsorted(self.excluded, keys), max(len(self.excluded) - 1, 0))
        return self.excluded[pos] == keys if len(self.excluded) else np.zeros(len(keys), dtype=bool)

    def _check_x(self, x, name="x"):
        return as_float_array(x, name, shape=(self.n, self.x_rest.shape[1]))

    def close_pairs(self, x, search="grid"):
        """Non-neighbour pairs closer than ``thickness``.

        Parameters
        ----------
        x : array_like, shape (n, d)
            Positions, in metres.
        search : {"grid", "all"}
            The bucket grid (cells of side ``thickness``, O(n)) or the test
            of all n (n - 1) / 2 pairs (O(n^2), the reference).

        Returns
        -------
        i, j : ndarray of int, shape (p,)
            Each pair once, ``i < j``, sorted by key ``i n + j``.
        """
        x = self._check_x(x)
        if search not in ("grid", "all"):
            raise ValueError(f"search must be 'grid' or 'all', got {search!r}")
        return self._close_pairs(x, search)

    def _close_pairs(self, x, search="grid"):
        if search == "grid":
            i, j = CellGrid(x, self.thickness, cells_per_cutoff=1).pairs()
        else:
            i, j = all_pairs(x, self.thickness)
        keys = np.unique(self._keys(i, j))
        keys = keys[~self._is_excluded(keys)]
        i, j = np.divmod(keys, self.n)
        movable = self.inverse_mass[i] + self.inverse_mass[j] > 0
        return i[movable], j[movable]

    def resolve(self, x, v):
        """Push close non-neighbour pairs apart and stop their approach.

        Parameters
        ----------
        x, v : array_like, shape (n, d)
            Positions (m) and velocities (m/s) after a step (not modified).

        Returns
        -------
        SelfCollisionResult
            With corrected copies of `x` and `v`.
        """
        x = np.array(self._check_x(x), order="F")
        v = np.array(self._check_x(v, "v"), order="F")
        return self._resolve(x, v)

    def _resolve(self, x, v):
        """:meth:`resolve` on checked copies, corrected in place."""
        t, n = self.thickness, self.n
        found = []
        passes, converged = 0, True
        i, j = self._close_pairs(x)
        first = len(i)
        while len(i):  # a loop over search-and-push passes
            found.append(self._keys(i, j))
            r, _ = unit(pair_differences(x, i, j))
            converged = bool(r.min() >= t * (1.0 - self.tol))
            if converged or passes == self.iterations:
                break
            for g in color_constraints(np.stack([i, j], axis=1), n):  # Gauss-Seidel: one colour at a time
                self._push(x, i[g], j[g])
            passes += 1
            i, j = self._close_pairs(x)
        converged = converged or not len(i)
        min_distance = float(unit(pair_differences(x, i, j))[0].min()) if len(i) else np.inf
        if found:
            i, j = np.divmod(np.unique(np.concatenate(found)), n)
            for g in color_constraints(np.stack([i, j], axis=1), n):  # one colour at a time
                self._stop(x, v, i[g], j[g])
        return SelfCollisionResult(x, v, first, min_distance, passes, converged)

    def _directions(self, x, i, j):
        """Distances and unit vectors from j to i; the rest-state direction where they coincide."""
        r, u = unit(pair_differences(x, i, j))
        same = r == 0
        if same.any():
            u[:, same] = unit(pair_differences(self.x_rest, i[same], j[same]))[1]
        return r, u

    def _weights(self, i, j):
        wi, wj = self.inverse_mass[i], self.inverse_mass[j]
        total = wi + wj  # > 0: pairs of two pinned particles were dropped
        return wi / total, wj / total

    def _push(self, x, i, j):
        """Move the pairs (i, j), which share no particle, to ``thickness`` apart, in place."""
        r, u = self._directions(x, i, j)
        overlap = np.maximum(self.thickness - r, 0.0)
        wi, wj = self._weights(i, j)
        for a in range(x.shape[1]):  # per coordinate; i and j hold no repeated particle
            x[i, a] += wi * overlap * u[a]
            x[j, a] -= wj * overlap * u[a]

    def _stop(self, x, v, i, j):
        """Inelastic normal impulse and Coulomb friction on approaching pairs, in place."""
        _, u = self._directions(x, i, j)
        dv = pair_differences(v, i, j)  # relative velocity v_i - v_j, shape (d, p)
        vn = np.einsum("ap,ap->p", dv, u)
        approach = np.minimum(vn, 0.0)
        change_n = -(1.0 + self.restitution) * approach  # >= 0: added to the relative normal velocity
        change = change_n * u
        if self.friction > 0:
            vt = dv - vn * u
            speed = np.sqrt(np.einsum("ap,ap->p", vt, vt))
            slow = np.minimum(self.friction * change_n, speed)
            change -= np.divide(slow, speed, out=np.zeros_like(speed), where=speed > 0) * vt
        wi, wj = self._weights(i, j)
        for a in range(v.shape[1]):  # per coordinate; i and j hold no repeated particle
            v[i, a] += wi * change[a]
            v[j, a] -= wj * change[a]

    def stepper(self, step):
        """Wrap a stepper so that every step ends with the self-collision fix.

        Composes with the other wrappers: Provot's constraint first, then the
        self-collision, then collisions with bodies last, so that no
        particle ends a step inside a body::

            provot = ProvotConstraint.from_system(sheet)
            selfc = SelfCollision.from_system(sheet, thickness=0.8 * dx)
            step = collider.stepper(selfc.stepper(provot.stepper(symplectic_euler)),
                                    m=sheet.m, pinned=sheet.pinned)

        Parameters
        ----------
        step : str, callable or solver
            A stepper ``step(f, X, t, h)``, a name of
            :data:`particles.integrators.INTEGRATORS` or a solver object
            (see :mod:`particles.integrators.solvers`).

        Returns
        -------
        callable
            A stepper with the order and layout attributes of `step`; each
            step appends a :class:`SelfCollisionResult` (without x and v) to
            :attr:`history`.
        """

        def push(X_old, X_new, t, h):
            x = np.array(X_new[:, 0], order="F")
            v = np.array(X_new[:, 1], order="F")
            res = self._resolve(x, v)
            self.history.append(SelfCollisionResult(None, None, res.pairs, res.min_distance,
                                                    res.iterations, res.converged))
            X_new[:, 0], X_new[:, 1] = res.x, res.v
            return X_new

        return after(step, push, "self_collision")
