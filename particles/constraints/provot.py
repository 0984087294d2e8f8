"""Provot's deformation constraint: springs may not stretch beyond a limit.

Real cloth hardly stretches (less than about 10%), but springs stiff enough to
keep it so would need tiny time steps. Provot (1995) keeps soft springs and,
after each time step, shortens every spring longer than ``(1 + s) L0`` back to
that length (:func:`provot_excess`, the formula of one spring):

* both ends free: each end moves half of the excess, towards the other;
* one end pinned: only the free end moves, by the whole excess;
* both ends pinned: nothing moves.

Fixing one spring can stretch a neighbour, so the pass (:func:`provot_pass`)
is repeated until all springs hold, or an iteration cap is reached
(:func:`provot_projection`). Provot corrects the springs one after another.
Without a Python loop over springs we do the same in groups of springs that
share no particle (a graph colouring, :func:`particles.constraints.colouring.color_constraints`):
within a group the order does not matter, and sweeping through the groups is
a Gauss-Seidel iteration. A simpler alternative corrects all springs at once
(a Jacobi iteration), moving each particle by the average of its springs'
corrections; it converges more slowly.

This module is the reference: the formula and the NumPy passes. The
constraint applied after every step of a run is
:class:`particles.constraints.provot_constraint.ProvotConstraint`, which runs
these passes or their compiled form (:mod:`particles.constraints.kernels`).

References
----------
.. [1] X. Provot, "Deformation constraints in a mass-spring model to describe
   rigid cloth behavior", Graphics Interface 1995, 147-154.
"""

from dataclasses import dataclass

import numpy as np

from .._checks import as_float_array, count, index_array, nonnegative_number

__all__ = ["provot_excess", "provot_pass", "provot_projection", "end_shares", "spring_lengths", "ProjectionResult",
           "ROUNDING"]

ROUNDING = 1e-12
"""A spring shortened to exactly ``(1 + s) L0`` may come out a few ulps longer: the strain tolerance's margin."""


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


def provot_excess(L, L0, max_strain):
    """How much a spring must shorten: ``max(L - (1 + s) L0, 0)``, in metres (0 when it holds).

    Parameters
    ----------
    L, L0 : float or ndarray
        Length and rest length, in metres.
    max_strain : float or ndarray
        ``s``: the stretch allowed, as a fraction of ``L0``.

    Examples
    --------
    >>> float(provot_excess(1.5, 1.0, 0.25))     # 50% long, 25% allowed: shorten by 0.25 m
    0.25
    >>> float(provot_excess(1.1, 1.0, 0.25))     # within the limit
    0.0
    """
    return np.maximum(L - (1.0 + max_strain) * L0, 0.0)


def end_shares(free_i, free_j):
    """The share of a spring's excess each end takes: ``(1/2, 1/2)``, ``(1, 0)`` or ``(0, 1)``, ``(0, 0)``.

    Parameters
    ----------
    free_i, free_j : ndarray of bool, shape (s,)
        Whether each end may move.
    """
    wi, wj = free_i.astype(float), free_j.astype(float)
    total = wi + wj
    return (np.divide(wi, total, out=np.zeros_like(wi), where=total > 0),
            np.divide(wj, total, out=np.zeros_like(wj), where=total > 0))


def spring_lengths(x, i, j):
    """``x_i - x_j`` coordinate by coordinate (a list of d arrays of shape (s,)) and the springs' lengths."""
    d = [x[i, a] - x[j, a] for a in range(x.shape[1])]  # the columns of x: contiguous in the system's order
    return d, np.sqrt(sum(da * da for da in d))


def provot_pass(x, i, j, L0, wi, wj, max_strain, average):
    """One pass of Provot's correction over the springs ``(i, j)``, in place on `x` (shape (n, d)).

    Every spring longer than ``(1 + s) L0`` is shortened by :func:`provot_excess` along
    ``u = (x_i - x_j) / L``: ``x_i -= w_i excess u``, ``x_j += w_j excess u``, with the ends'
    shares `wi`, `wj` (:func:`end_shares`). With `average` (Jacobi: the springs may share
    particles), each particle moves by the mean of its too long springs' corrections; without it
    the springs must share no particle (one colour group of Gauss-Seidel).
    """
    n, dim = x.shape
    d, L = spring_lengths(x, i, j)
    excess = provot_excess(L, L0, max_strain) * ((wi + wj) > 0)  # both ends pinned: nothing moves
    too_long = excess > 0
    if not too_long.any():
        return
    scale = 1.0
    if average:  # a particle pulled by several springs moves by their mean correction
        scale = 1.0 / np.maximum(np.bincount(i[too_long], minlength=n) + np.bincount(j[too_long], minlength=n), 1)
    L = np.maximum(L, 1e-300)  # a spring of length 0 is never too long; no 0 / 0 either
    for a in range(dim):  # a loop over the d coordinates: c = excess u
        c = excess * (d[a] / L)
        x[:, a] += scale * (np.bincount(j, wj * c, minlength=n) - np.bincount(i, wi * c, minlength=n))


def provot_projection(x, indices, rest_length, free, max_strain=0.1, iterations=500, tol=0.005,
                      groups=None):
    """Shorten springs longer than ``(1 + max_strain) L0`` by repeated passes (:func:`provot_pass`).

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
        Spring groups sharing no particle (:func:`~particles.constraints.colouring.color_constraints`).
        Given, each pass is a Gauss-Seidel sweep through the groups (Provot's sequential
        procedure, reordered); omitted, each pass is one Jacobi step with averaged corrections.

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
    max_strain = nonnegative_number(max_strain, "max_strain")
    tol = nonnegative_number(tol, "tol")
    iterations = count(iterations, "iterations")
    wi, wj = end_shares(free[i], free[j])
    movable = (wi + wj) > 0
    x = np.array(x, order="F")
    for passes in range(iterations + 1):
        strain = spring_lengths(x, i, j)[1] / L0 - 1.0
        worst = float(np.max(strain[movable], initial=0.0))
        if worst <= max_strain + tol + ROUNDING or passes == iterations:
            break
        for g in [slice(None)] if groups is None else groups:  # Gauss-Seidel: one colour at a time
            provot_pass(x, i[g], j[g], L0[g], wi[g], wj[g], max_strain, average=groups is None)
    return ProjectionResult(x, worst, passes, worst <= max_strain + tol + ROUNDING)
