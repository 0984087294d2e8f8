"""The response of a contact: the normal and friction impulses of a particle on a surface, and of cloth pieces.

A contact with unit normal ``n`` splits a velocity into ``v_n = (v . n) n`` and
``v_t = v - v_n``. The normal part of an approaching particle (``v . n < 0``)
is reflected and scaled by the coefficient of restitution ``eps``
(:func:`normal_change`); Coulomb friction takes at most ``mu`` times the normal
impulse from the tangential velocity, and never reverses it
(:func:`friction_change`). Two pieces of cloth closer than their thickness get
the impulse that brings their normal velocity to a target
(:func:`proximity_impulse`). These are the formulas of one contact: the NumPy
code (:func:`respond`; :class:`~particles.collisions.Collider`;
:class:`~particles.collisions.ClothCollisions`) applies them to arrays of
contacts, and the compiled kernels of :mod:`particles.collisions` inline them,
contact by contact.

References
----------
.. [1] A. Witkin and D. Baraff, "Physically Based Modeling: Principles and
   Practice", SIGGRAPH 1997 course notes, "Particle System Dynamics", section 5
   (collisions and contact).
.. [2] R. Bridson, R. Fedkiw and J. Anderson, "Robust treatment of collisions,
   contact and friction for cloth animation", ACM SIGGRAPH 2002 (Coulomb
   friction as a velocity impulse bounded by the normal impulse; proximity impulses).
"""

import numpy as np

from .._checks import as_float_array, nonnegative_number, restitution_coefficient
from .._vectors import rowdot

__all__ = ["normal_change", "friction_change", "proximity_impulse", "respond", "response", "UNIT_TOL"]

UNIT_TOL = 1e-9
"""Largest accepted ``| |n| - 1 |`` for the unit normals given to :func:`respond`."""


def normal_change(vn, restitution):
    """The normal velocity change of a contact: ``-(1 + eps) min(v . n, 0)`` (0 for a separating particle).

    Parameters
    ----------
    vn : float or ndarray
        ``v . n``, in m/s (negative: approaching).
    restitution : float
        ``eps`` in [0, 1].
    """
    return -(1.0 + restitution) * np.minimum(vn, 0.0)


def friction_change(friction, normal, speed_t):
    """Coulomb's friction: the tangential change ``min(mu normal, |v_t|)``, at most ``mu`` times the normal one.

    Parameters
    ----------
    friction : float
        ``mu`` >= 0.
    normal : float or ndarray
        The normal change (a velocity, or an impulse).
    speed_t : float or ndarray
        The tangential speed (in the units of `normal`): the change stops it, never reverses it.
    """
    return np.minimum(friction * normal, speed_t)


def proximity_impulse(target, vN, S, c):
    """The normal impulse that brings a contact's relative normal velocity `vN` to `target`: ``(target - vN) / S / c``.

    Parameters
    ----------
    target, vN : float or ndarray
        Target and current normal velocity of the pair, in m/s.
    S : float or ndarray
        ``sum_j W_j^2 w_j``: the inverse of the pair's effective mass, in 1/kg.
    c : float or ndarray
        The divisor of a contact that shares vertices with others (Jacobi's averaging), >= 1.
    """
    return (target - vN) / S / c


def respond(v, n, restitution=1.0, friction=0.0):
    """Velocities after a collision with a surface of unit normal `n`.

    ``v_n = (v . n) n``, ``v_t = v - v_n``; approaching particles (``v . n < 0``)
    get ``v_t - eps v_n``, with ``v_t`` reduced by Coulomb friction: the
    tangential impulse is at most ``mu`` times the normal one, so
    ``|v_t|`` shrinks by ``mu (1 + eps) |v . n|`` and stops at zero (it
    never reverses). Separating particles keep their velocity.

    Parameters
    ----------
    v : array_like, shape (k, d)
        Velocities at the contact, in m/s.
    n : array_like, shape (k, d)
        Unit normals pointing out of the solid (``|n| = 1`` within
        :data:`UNIT_TOL`; a longer or shorter ``n`` would scale the response,
        so it is rejected rather than silently normalized).
    restitution : float
        ``eps`` in [0, 1].
    friction : float
        Coulomb coefficient ``mu`` >= 0.

    Returns
    -------
    v_new : ndarray, shape (k, d)
    dv_n : ndarray, shape (k, d)
        Normal change of velocity ``-(1 + eps) v_n`` (impulse per unit mass).
    dv_t : ndarray, shape (k, d)
        Tangential change of velocity due to friction.

    Examples
    --------
    >>> v_new, dv_n, dv_t = respond([[3.0, -4.0]], [[0.0, 1.0]], restitution=0.5)
    >>> v_new.tolist(), dv_n.tolist()
    ([[3.0, 2.0]], [[0.0, 6.0]])
    """
    v = as_float_array(v, "v", ndim=2)
    n = as_float_array(n, "n", shape=v.shape)
    length = np.sqrt(rowdot(n, n))
    wrong = np.abs(length - 1.0) > UNIT_TOL
    if wrong.any():
        k = int(np.argmax(wrong))
        raise ValueError(f"n must be unit normals (|n| = 1 within {UNIT_TOL:g}), got |n| = {length[k]:.6g} "
                         f"in row {k}; divide n by its length first")
    return response(v, n, restitution_coefficient(restitution), nonnegative_number(friction, "friction"))


def response(v, n, eps, mu):
    """:func:`respond` without the argument checks: ``v_new, dv_n, dv_t``, shapes (k, d)."""
    vn = rowdot(v, n)
    v_t = v - vn[:, None] * n
    dv_n = normal_change(vn, eps)[:, None] * n
    dv_t = np.zeros_like(v)
    if mu > 0:
        speed_t = np.sqrt(rowdot(v_t, v_t))
        slow = friction_change(mu, normal_change(vn, eps), speed_t)
        scale = np.divide(slow, speed_t, out=np.zeros_like(slow), where=speed_t > 0)
        dv_t = -scale[:, None] * v_t
    return v + dv_n + dv_t, dv_n, dv_t
