"""One XPBD solve of distance constraints, as the paper writes it: the multiplier's step and one pass.

A distance constraint ``C = |x_i - x_j| - L0`` has the gradients ``u`` at ``i`` and ``-u`` at ``j``
(``u = (x_i - x_j) / |x_i - x_j|``), so ``W = w_i + w_j`` for the inverse masses ``w``. XPBD
(Macklin, Müller and Chentanez 2016) moves its multiplier by

    dlambda = (-C - alpha_tilde lambda - gamma dC) / ((1 + gamma) W + alpha_tilde)

(:func:`multiplier_step`; ``alpha_tilde = alpha / h^2`` the compliance of the (sub)step, ``gamma``
the damping, ``dC`` the constraint's change over the step), then the particles by
``x_i += w_i dlambda u``, ``x_j -= w_j dlambda u``: :func:`distance_pass` does this for every
constraint, colour group after colour group (Gauss-Seidel) or all at once with averaging (Jacobi).

This is the reference. The solvers (:class:`particles.xpbd.XPBD`, :class:`particles.xpbd.PBD`)
project their constraint sets (:mod:`particles.xpbd.constraint_sets`) with the same
:func:`multiplier_step`, in NumPy or compiled (:mod:`particles.xpbd.kernels`, which inlines it).

References
----------
.. [1] M. Macklin, M. Müller and N. Chentanez, "XPBD: position-based
   simulation of compliant constrained dynamics", MIG 2016 (eq. 18 and 26).
"""

import numpy as np

from .._checks import as_float_array, index_array, per_item
from ..constraints.colouring import check_groups

__all__ = ["distance_constraint", "multiplier_step", "distance_pass"]


def distance_constraint(L, L0):
    """The distance constraint's value ``C = |x_i - x_j| - L0`` from the length ``L``, in metres."""
    return L - L0


def multiplier_step(C, lam, alpha_tilde, gamma, dC, inv):
    """XPBD's multiplier step ``(-C - alpha_tilde lambda - gamma dC) / ((1 + gamma) W + alpha_tilde)``.

    Parameters
    ----------
    C : float or ndarray
        The constraint's value.
    lam : float or ndarray
        Its multiplier accumulated so far in the (sub)step.
    alpha_tilde, gamma : float or ndarray
        ``alpha / h^2`` and the damping ``alpha kd / h`` (0 without damping; PBD: both 0).
    dC : float or ndarray
        ``grad C . (x - x_n)``, the constraint's change over the step (read only with damping).
    inv : float or ndarray
        ``1 / ((1 + gamma) W + alpha_tilde)``, computed once per step (PBD: ``k / W``); 0 for a
        constraint whose particles are all pinned.

    Returns
    -------
    float or ndarray
        ``dlambda``.
    """
    return (-C - alpha_tilde * lam - gamma * dC) * inv


def distance_pass(x, w, indices, rest_length, alpha_tilde, lam, groups=None):
    """One XPBD pass over distance constraints: Gauss-Seidel over colour groups, or Jacobi.

    For each constraint ``C = |x_i - x_j| - L0`` with ``u = (x_i - x_j) / |x_i - x_j|``::

        dlambda = (-C - alpha_tilde lambda) / (w_i + w_j + alpha_tilde)
        x_i += w_i dlambda u,    x_j -= w_j dlambda u,    lambda += dlambda

    Parameters
    ----------
    x : array_like, shape (n, d)
        Positions, in metres. Not modified.
    w : array_like, shape (n,)
        Inverse masses ``1 / m`` in 1/kg, 0 for pinned particles.
    indices : array_like of int, shape (s, 2)
    rest_length : array_like, shape (s,)
        ``L0`` in metres.
    alpha_tilde : float or array_like, shape (s,)
        ``alpha / h^2`` of the substep, in kg^-1 (0: rigid).
    lam : array_like, shape (s,)
        Multipliers accumulated so far in this substep. Not modified.
    groups : list of array_like of int, or ndarray of int, shape (s,), optional
        Colour groups, or a colour per constraint (swept in increasing
        order): a Gauss-Seidel pass. Omitted: one Jacobi pass, each
        ``dlambda`` divided by the largest number of constraints at a free
        particle of its constraint (on a regular grid, the average of the
        corrections).

    Returns
    -------
    x_new : ndarray, shape (n, d)
    lam_new : ndarray, shape (s,)

    Examples
    --------
    A rod of rest length 1 m stretched to 1.5 m, its first end pinned, rigid:

    >>> x, lam = distance_pass([[0.0, 0.0], [1.5, 0.0]], [0.0, 1.0], [[0, 1]], [1.0], 0.0, [0.0])
    >>> x.tolist(), lam.tolist()
    ([[0.0, 0.0], [1.0, 0.0]], [-0.5])
    """
    x, w, ij, L0, at, lam = _checked(x, w, indices, rest_length, alpha_tilde, lam)
    i, j = ij[:, 0], ij[:, 1]
    W = w[i] + w[j]
    inv = np.divide(1.0, W + at, out=np.zeros(len(ij)), where=W + at > 0)
    if groups is None:  # Jacobi: each constraint divided by the largest count at its free particles
        count = np.bincount(i, minlength=len(x)) + np.bincount(j, minlength=len(x))
        inv /= np.maximum(np.maximum(count[i] * (w[i] > 0), count[j] * (w[j] > 0)), 1)
    for g in [np.arange(len(ij))] if groups is None else check_groups(groups, ij):  # one colour at a time
        d = x[i[g]] - x[j[g]]
        L = np.linalg.norm(d, axis=1)
        dlam = multiplier_step(distance_constraint(L, L0[g]), lam[g], at[g], 0.0, 0.0, inv[g])
        lam[g] += dlam
        u = d / np.maximum(L, 1e-150)[:, None]
        np.add.at(x, i[g], (w[i[g]] * dlam)[:, None] * u)  # a colour group: no particle twice
        np.add.at(x, j[g], -(w[j[g]] * dlam)[:, None] * u)
    return x, lam


def _checked(x, w, indices, rest_length, alpha_tilde, lam):
    """distance_pass's arguments, checked, as float arrays it may modify (copies)."""
    x = np.array(as_float_array(x, "x", ndim=2))
    w = as_float_array(w, "w", shape=(len(x),))
    if np.any(w < 0):
        raise ValueError("w must hold inverse masses >= 0 (0 for pinned particles)")
    ij = index_array(indices, "indices", 2)
    if np.any(ij[:, 0] == ij[:, 1]):
        raise ValueError("indices must join two different particles in every constraint")
    if len(ij) and ij.max() >= len(x):
        raise ValueError(f"indices refer to particle {ij.max()} but x has only {len(x)} particles")
    L0 = per_item(rest_length, "rest_length", len(ij))
    at = per_item(alpha_tilde, "alpha_tilde", len(ij))
    lam = np.array(as_float_array(lam, "lam", shape=(len(ij),)))
    return x, w, ij, L0, at, lam
