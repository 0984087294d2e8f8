"""Periodic boundaries: a box of side lengths ``L``, wrapping and the minimum image.

A liquid simulated in open space has a surface, and with a few hundred
particles most of them sit near it. Periodic boundaries remove the surface:
the box of side lengths ``L = (L_1, ..., L_d)`` is repeated in every
direction, a particle leaving through one face comes back through the
opposite one, and particle ``i`` interacts with the nearest copy of ``j``,
the **minimum image**

    ``r_ij = x_i - x_j - L round((x_i - x_j) / L)``   (per axis).

The minimum image is the only copy closer than the cutoff ``r_c`` as long
as ``L >= 2 r_c`` along every axis (two copies of ``j`` are ``L`` apart, so
they cannot both lie within ``r_c`` of ``i``): the bucket grid and the
Verlet list of :mod:`particles.neighbors` refuse smaller boxes.

Positions need not lie in the box: the library computes every difference
with the minimum image, so a trajectory can stay *unwrapped* (which is what
a diffusion measurement wants) and :func:`wrap` folds positions into the box
when a picture or a histogram needs them there. Nothing the user passed is
changed: :func:`wrap` returns a new array.

References
----------
.. [1] M. P. Allen and D. J. Tildesley, *Computer Simulation of Liquids*,
   2nd ed., Oxford University Press, 2017, section 1.6.2 (periodic boundary
   conditions and the minimum image convention).
"""

import numpy as np

from .._checks import as_float_array

__all__ = ["check_box", "box_option", "wrap", "minimum_image", "volume"]


def check_box(box, d, cutoff=None, name="box", reach="cutoff"):
    """The box as a float array of shape (d,), checked.

    Parameters
    ----------
    box : array_like, shape (d,) or scalar
        Side lengths ``L``, in metres, finite and > 0; a number gives a cube.
    d : int
        Dimension of space.
    cutoff : float, optional
        Interaction range: then every side must be at least ``2 cutoff``, so
        that the minimum image is the only copy within the cutoff.
    name : str
        Name of the argument, for the error messages.
    reach : str
        What `cutoff` is, for the error messages (``"(cutoff + skin)"`` for a
        Verlet list).

    Returns
    -------
    ndarray, shape (d,)
        The side lengths, in metres.

    Raises
    ------
    ValueError
        When a side is not a positive finite number, the shape is not (d,),
        or a side is shorter than ``2 cutoff``.

    Examples
    --------
    >>> check_box(10.0, 3).tolist()
    [10.0, 10.0, 10.0]
    """
    given = as_float_array(box, name, ndim=(0, 1), finite=False)
    L = np.full(d, float(given)) if given.ndim == 0 else given
    if L.shape != (d,):
        raise ValueError(f"{name} must have {d} side lengths (one per axis), got shape {L.shape}")
    if not np.all(np.isfinite(L) & (L > 0)):
        raise ValueError(f"{name} must hold positive finite side lengths (in metres), got {given.tolist()}")
    if cutoff is not None and np.any(L < 2 * cutoff):
        raise ValueError(
            f"{name} must be at least 2 x {reach} = {2 * cutoff:g} m along every axis so that the minimum "
            f"image is the only copy within the cutoff, got {given.tolist()}; use more particles, a shorter "
            "cutoff or a smaller skin"
        )
    return L.copy()


def box_option(box, cutoff=None, name="box", reach="cutoff"):
    """A `box` argument checked before the dimension is known: None, a number, or shape (d,).

    Parameters
    ----------
    box : None, float or array_like, shape (d,)
        Side lengths, in metres (a number: a cube in any dimension).
    cutoff : float, optional
        Every side must be at least ``2 cutoff``.
    name, reach : str
        For the error messages, as in :func:`check_box`.

    Returns
    -------
    None, float or ndarray of shape (d,)
        The box as given, checked.
    """
    if box is None:
        return None
    L = check_box(box, max(np.size(box), 1), cutoff, name, reach)
    return float(L[0]) if np.ndim(box) == 0 else L


def wrap(x, box):
    """Positions folded into the box ``[0, L)`` along every axis.

    Parameters
    ----------
    x : array_like, shape (n, d)
        Positions, in metres (anywhere).
    box : array_like, shape (d,) or scalar
        Side lengths ``L``, in metres.

    Returns
    -------
    ndarray, shape (n, d)
        A new array ``x - L floor(x / L)``; `x` is not modified. A value a
        hair below 0 may round to exactly ``L``.

    Examples
    --------
    >>> wrap([[-0.5, 10.5]], 10.0).tolist()
    [[9.5, 0.5]]
    """
    x = as_float_array(x, "x", ndim=2)
    L = check_box(box, x.shape[1])
    out = np.empty_like(x)
    for a in range(x.shape[1]):  # a loop over the d coordinates
        np.floor_divide(x[:, a], L[a], out=out[:, a])
        out[:, a] *= -L[a]
        out[:, a] += x[:, a]
    return out


def minimum_image(r, box, axis=-1):
    """Differences mapped to their nearest periodic copy, ``r - L round(r / L)``.

    Parameters
    ----------
    r : array_like
        Differences ``x_i - x_j``, in metres, with the d components along
        `axis`: shape (p, d) with ``axis=-1``, or (d, p) with ``axis=0`` (the
        layout of :func:`particles.forces.pair_differences`).
    box : array_like, shape (d,) or scalar
        Side lengths ``L``, in metres.
    axis : int
        The axis of `r` that holds the components.

    Returns
    -------
    ndarray, shape of `r`
        A new array, every component in ``[-L/2, L/2]``.

    Examples
    --------
    >>> minimum_image([[4.0, -6.0]], 10.0).tolist()
    [[4.0, 4.0]]
    """
    r = np.array(as_float_array(r, "r"), copy=True)
    if r.ndim == 0:
        raise ValueError("r must have at least 1 dimension (the d components)")
    comps = np.moveaxis(r, axis, 0)  # a view: writing into it writes into r
    L = check_box(box, comps.shape[0])
    for a in range(len(L)):  # a loop over the d coordinates
        comps[a] -= L[a] * np.rint(comps[a] / L[a])
    return r


def volume(box):
    """Volume (3D) or area (2D) of the box, ``prod(L)``, in m^d.

    Parameters
    ----------
    box : array_like, shape (d,)
        Side lengths, in metres.

    Returns
    -------
    float
    """
    L = as_float_array(box, "box", ndim=1)
    return float(np.prod(check_box(L, len(L))))
