"""Provot's deformation constraint: springs may not stretch beyond a limit.

Real cloth hardly stretches (less than about 10%), but springs stiff enough to
keep it so would need tiny time steps. Provot (1995) keeps soft springs and,
after each time step, shortens every spring longer than ``(1 + s) L0`` back to
that length:

* both ends free: each end moves half of the excess, towards the other;
* one end pinned: only the free end moves, by the whole excess;
* both ends pinned: nothing moves.

Fixing one spring can stretch a neighbour, so the pass is repeated until all
springs hold (or an iteration cap is reached). Provot corrects the springs
one after another. Without a Python loop over springs we do the same in
groups of springs that share no particle (a graph colouring): within a group
the order does not matter, and sweeping through the groups is a
Gauss-Seidel iteration. A simpler alternative corrects all springs at once
(a Jacobi iteration), moving each particle by the average of its springs'
corrections; it converges more slowly. Velocities are corrected with the
positions, ``v += dx / h``, so that the velocity is still the displacement
over the step.

References
----------
.. [1] X. Provot, "Deformation constraints in a mass-spring model to describe
   rigid cloth behavior", Graphics Interface 1995, 147-154.
"""

from dataclasses import dataclass

import numpy as np

from .._checks import as_float_array, count, index_array, nonnegative_number
from .._vectors import unit
from ..backends import check_backend, kernels_for
from ..forces.pairs import pair_differences
from ..integrators.solvers import after

__all__ = ["ProvotConstraint", "ProjectionResult", "provot_projection", "color_springs"]

# A spring shortened to exactly (1 + s) L0 may come out a few ulps longer.
_ROUNDING = 1e-12


@dataclass(frozen=True)
class ProjectionResult:
    """What a projection did.

    Attributes
    ----------
    x : ndarray, shape (n, d)
        Corrected positions.
    max_strain : float
        Largest strain ``L / L0 - 1`` of any constrained spring afterwards.
    iterations : int
        Passes made (0 when nothing was too long).
    converged : bool
        Whether every spring ended within ``max_strain + tol``.
    """

    x: np.ndarray
    max_strain: float
    iterations: int
    converged: bool


def color_springs(indices, n, seed=0):
    """Split springs into groups that share no particle (a graph colouring).

    Within a group, springs can be corrected simultaneously with exactly the
    result of correcting them one after another; going through the groups in
    turn is then a Gauss-Seidel sweep, which converges much faster than
    correcting all springs at once. Luby's method, vectorized: in each round,
    every remaining spring whose random priority beats all remaining springs
    at both its ends joins the group; the round repeats until no spring can
    join, then the next group starts.

    Parameters
    ----------
    indices : array_like of int, shape (s, 2)
    n : int
        Number of particles.
    seed : int
        Seed of the priorities (the colouring is deterministic for a seed).

    Returns
    -------
    list of ndarray of int
        Spring numbers of each group; together they cover every spring once.
    """
    ij = index_array(indices, "indices", 2)
    i, j = ij[:, 0], ij[:, 1]
    priority = np.random.default_rng(seed).permutation(len(ij)).astype(float)
    remaining = np.ones(len(ij), dtype=bool)
    groups = []
    while remaining.any():  # a loop over colours (about twice the largest degree)
        group = np.zeros(len(ij), dtype=bool)
        taken = np.zeros(n, dtype=bool)  # particles already used by this colour
        while True:  # a few rounds of Luby's method per colour
            candidate = remaining & ~group & ~taken[i] & ~taken[j]
            if not candidate.any():
                break
            best = np.full(n, -1.0)
            np.maximum.at(best, i[candidate], priority[candidate])
            np.maximum.at(best, j[candidate], priority[candidate])
            wins = candidate & (best[i] == priority) & (best[j] == priority)
            group |= wins
            taken[i[wins]] = True
            taken[j[wins]] = True
        groups.append(np.flatnonzero(group))
        remaining &= ~group
    return groups


def provot_projection(x, indices, rest_length, free, max_strain=0.1, iterations=500, tol=0.005,
                      groups=None):
    """Shorten springs longer than ``(1 + max_strain) L0``, Jacobi-style.

    Parameters
    ----------
    x : array_like, shape (n, d)
        Positions after a time step. Not modified.
    indices : array_like of int, shape (s, 2)
    rest_length : array_like, shape (s,)
    free : array_like of bool, shape (n,)
        False for pinned particles, which never move.
    max_strain : float
        Allowed relative elongation ``s`` (0.1 = 10%).
    iterations : int
        Largest number of passes.
    tol : float
        Strain tolerance: passes stop when every spring is within
        ``max_strain + tol``.
    groups : list of ndarray of int, optional
        Spring groups sharing no particle (:func:`color_springs`). Given, each
        pass is a Gauss-Seidel sweep through the groups (Provot's sequential
        procedure, reordered); omitted, each pass is one Jacobi step with
        averaged corrections.

    Returns
    -------
    ProjectionResult
    """
    x = as_float_array(x, "x", ndim=2)
    ij = index_array(indices, "indices", 2)
    i, j = ij[:, 0], ij[:, 1]
    L0 = as_float_array(rest_length, "rest_length", shape=(len(ij),))
    free = np.asarray(free, dtype=bool)
    if free.shape != (len(x),):
        raise ValueError(f"free must be a boolean array of shape ({len(x)},), got {free.shape}")
    limit = 1.0 + nonnegative_number(max_strain, "max_strain")
    tol = nonnegative_number(tol, "tol")
    iterations = count(iterations, "iterations")
    # share of the excess each end takes: 1/2 each, all to the free end, or none
    wi, wj = free[i].astype(float), free[j].astype(float)
    total = wi + wj
    wi = np.divide(wi, total, out=np.zeros_like(wi), where=total > 0)
    wj = np.divide(wj, total, out=np.zeros_like(wj), where=total > 0)
    movable = total > 0
    n, dim = x.shape
    x = np.array(x, order="F")
    for passes in range(iterations + 1):
        strain = _strain(x, i, j, L0)
        worst = float(np.max(strain[movable], initial=0.0))
        if worst <= max_strain + tol + _ROUNDING or passes == iterations:
            break
        if groups is None:
            _correct(x, i, j, L0, wi, wj, movable, limit, free, average=True)
        else:
            for g in groups:  # Gauss-Seidel: one colour at a time
                _correct(x, i[g], j[g], L0[g], wi[g], wj[g], movable[g], limit, free, average=False)
    return ProjectionResult(x, worst, passes, worst <= max_strain + tol + _ROUNDING)


def _strain(x, i, j, L0):
    L, _ = unit(pair_differences(x, i, j))
    return L / L0 - 1.0


def _correct(x, i, j, L0, wi, wj, movable, limit, free, average):
    """One correction of the springs (i, j) that are too long, in place."""
    n = len(x)
    L, u = unit(pair_differences(x, i, j))
    too_long = movable & (L > limit * L0)
    if not too_long.any():
        return
    excess = np.where(too_long, L - limit * L0, 0.0)  # |x_i - x_j| must shrink by this much
    scale = 1.0
    if average:  # a particle pulled by several springs moves by their mean correction
        counts = (np.bincount(i[too_long], minlength=n) + np.bincount(j[too_long], minlength=n)) * free
        scale = 1.0 / np.maximum(counts, 1)
    for a in range(x.shape[1]):  # per coordinate
        c = excess * u[a]
        x[:, a] += scale * (np.bincount(j, wj * c, minlength=n) - np.bincount(i, wi * c, minlength=n))


class ProvotConstraint:
    """Provot's constraint on chosen springs of a system, applied after each step.

    Parameters
    ----------
    indices : array_like of int, shape (s, 2)
    rest_length : array_like, shape (s,)
    n : int
        Number of particles.
    pinned : array_like of int
        Particles that never move.
    max_strain : float
        Allowed relative elongation (default 0.1: 10%).
    iterations : int
        Cap on Jacobi passes per projection.
    tol : float
        Strain tolerance of the projection.
    method : {"jacobi", "gauss-seidel"}
        Correct all springs at once with averaging (default: simple and
        cheap per pass), or sweep through groups of independent springs
        (fewer passes, each dearer); see :func:`provot_projection`.
    backend : {None, "auto", "numpy", "numba"}, optional
        Who projects in :meth:`stepper`: :func:`provot_projection`, or the
        same passes compiled, in place on the step's end state (see
        :mod:`particles.backends`; None: the global choice). :meth:`project`
        is always the NumPy reference.

    Attributes
    ----------
    history : list of ProjectionResult
        One entry per step taken through :meth:`stepper` (without positions).

    Examples
    --------
    >>> from particles.massspring import cloth
    >>> from particles.integrators import symplectic_euler
    >>> c = cloth(10, 10, plane="horizontal", k_structural=20.0)
    >>> provot = ProvotConstraint.from_system(c)
    >>> t, X = c.run(0.5, 0.002, method=provot.stepper(symplectic_euler))
    >>> bool(c.max_strain(kind="structural") < 0.1 + provot.tol)
    True
    """

    def __init__(self, indices, rest_length, n, pinned=(), max_strain=0.1, iterations=500, tol=0.005,
                 method="jacobi", backend=None):
        self.backend = check_backend(backend)
        self.indices = index_array(indices, "indices", 2)
        self.rest_length = as_float_array(rest_length, "rest_length", shape=(len(self.indices),))
        n = count(n, "n", 1)
        if len(self.indices) and self.indices.max() >= n:
            raise ValueError(f"indices refer to particle {self.indices.max()} but n = {n}")
        pinned = np.asarray(pinned, dtype=int).ravel()
        if np.any((pinned < 0) | (pinned >= n)):
            raise ValueError(f"pinned must hold particle indices from 0 to {n - 1}, got {pinned.tolist()}")
        self.free = np.ones(n, dtype=bool)
        self.free[pinned] = False
        self.max_strain = nonnegative_number(max_strain, "max_strain")
        self.iterations = count(iterations, "iterations", 1)
        self.tol = nonnegative_number(tol, "tol")
        if method not in ("gauss-seidel", "jacobi"):
            raise ValueError(f"method must be 'gauss-seidel' or 'jacobi', got {method!r}")
        self.method = method
        self.groups = color_springs(self.indices, n) if method == "gauss-seidel" else None
        self.history = []

    @classmethod
    def from_system(cls, system, kinds=("structural", "shear"), **options):
        """Constrain the springs of the given kinds of a MassSpringSystem (Provot used structural and shear)."""
        chosen = [system.springs[k] for k in kinds if k in system.springs]
        if not chosen:
            raise ValueError(f"the system has no springs of kinds {kinds}; it has {list(system.springs)}")
        return cls(np.concatenate([s.indices for s in chosen]), np.concatenate([s.rest_length for s in chosen]),
                   system.n, system.pinned, **options)

    def project(self, x):
        """Apply the constraint to positions `x` (shape (n, d)); returns a :class:`ProjectionResult`."""
        return provot_projection(x, self.indices, self.rest_length, self.free, self.max_strain,
                                 self.iterations, self.tol, self.groups)

    def stepper(self, step):
        """Wrap a method so that every step ends with the projection.

        Parameters
        ----------
        step : str, callable or solver
            A stepper ``step(f, X, t, h)``, a name of
            :data:`particles.integrators.INTEGRATORS` or a solver object
            (see :mod:`particles.integrators.solvers`).

        Returns
        -------
        callable
            A stepper ``(f, X, t, h) -> X_new`` with the order and layout
            attributes of `step`; positions are projected and velocities
            corrected by the same displacement divided by ``h``. Each step
            appends a :class:`ProjectionResult` (without positions) to
            :attr:`history`. With the numba backend the projection is
            compiled (:func:`particles.backends.fixes.provot`) and corrects
            the step's end state in place, in its own memory order.
        """

        def project(X_old, X_new, t, h):
            fast = kernels_for(self.backend, len(X_new))
            if fast is not None and len(X_new) == len(self.free) and X_new.dtype == np.float64:
                worst, passes = fast.provot(self, X_new, h)
                self.history.append(ProjectionResult(None, worst, passes, worst <= self.max_strain + self.tol + _ROUNDING))
                return X_new
            result = self.project(X_new[:, 0])
            self.history.append(ProjectionResult(None, result.max_strain, result.iterations, result.converged))
            X_new[:, 1] += (result.x - X_new[:, 0]) / h
            X_new[:, 0] = result.x
            return X_new

        return after(step, project, "provot")
