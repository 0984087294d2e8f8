"""Strings and hair: chains of springs, hair with bending at its joints and a clamped root.

Each builder returns a :class:`particles.massspring.model.MassSpringSystem` with
gravity, damping and pins set up, under the naive or the physical scaling of
:mod:`particles.massspring`.
"""

import numpy as np

from .._checks import count, nonnegative_number, positive_number
from ..forces.spring_sets import Bending, Clamp, Springs
from .model import MassSpringSystem, check_scaling, common_forces, dual_weights

__all__ = ["string", "hair"]


def _chain(n, length, d, pin, span, direction):
    """Positions of a chain and the indices to pin."""
    n = count(n, "n", 2)
    length = positive_number(length, "length", "metres")
    if d not in (2, 3):
        raise ValueError(f"d must be 2 or 3, got {d!r}")
    s = np.linspace(0.0, 1.0, n)[:, None]
    if pin == "both":
        span = length if span is None else positive_number(span, "span", "metres")
        start, vector = np.zeros(d), np.eye(d)[0] * span
        start[0] = -span / 2
        pinned = [0, n - 1]
    else:
        u = np.asarray(direction, dtype=float)
        if u.shape != (d,) or not np.any(u):
            raise ValueError(f"direction must be a non-zero vector of {d} components, got {direction!r}")
        start, vector = np.zeros(d), u / np.linalg.norm(u) * length
        pinned = {"top": [0], "root": [0, 1], "none": []}.get(pin)
        if pinned is None:
            raise ValueError(f"pin must be 'top', 'root', 'both' or 'none', got {pin!r}")
    return start + s * vector, pinned


def _chain_parameters(n, length, scaling, mass, k, linear_density, stretch_modulus):
    """Masses (n,) and spring stiffness (n-1,) of a chain."""
    if check_scaling(scaling) == "naive":
        m = np.full(n, positive_number(mass, "mass", "kg"))
        k = np.full(n - 1, positive_number(k, "k", "N/m"))
    else:
        L0 = length / (n - 1)
        m = positive_number(linear_density, "linear_density", "kg/m") * L0 * dual_weights(n)
        k = np.full(n - 1, positive_number(stretch_modulus, "stretch_modulus", "N") / L0)
    return m, k


def string(n=20, length=1.0, *, pin="top", span=None, d=2, direction=None, scaling="naive",
           mass=0.01, k=50.0, kd=0.0, linear_density=0.2, stretch_modulus=20.0,
           gravity=9.81, damping=0.0):
    """A string: `n` particles in a chain of springs.

    Parameters
    ----------
    n : int
        Number of particles, >= 2.
    length : float
        Rest length of the whole string, in metres.
    pin : {"top", "both", "none"}
        ``"top"``: the first particle is fixed and the string hangs from it;
        ``"both"``: both ends fixed, `span` apart on a horizontal line.
    span : float, optional
        Distance between the two pins for ``pin="both"`` (default `length`:
        taut, so that any sag stretches it like a rubber band).
    d : {2, 3}
        Dimension; the last axis points up.
    direction : array_like, shape (d,), optional
        Initial direction of the string from the first particle (default:
        straight down).
    scaling : {"naive", "physical"}
        See the module docstring.
    mass, k : float
        ``"naive"``: mass of every particle (kg) and stiffness of every spring (N/m).
    linear_density, stretch_modulus : float
        ``"physical"``: mass per length (kg/m) and EA (N); then
        ``m = linear_density * L0`` (half at the ends) and ``k = EA / L0``.
    kd : float
        Damping along every spring, in kg/s, the same for every spring under
        both scalings (``"physical"`` rescales masses and stiffnesses only).
    gravity : float
        In m/s^2, pointing down the last axis.
    damping : float
        Viscous damping: kg/s per particle (naive) or 1/s per unit mass (physical).

    Returns
    -------
    MassSpringSystem
        With one spring set, kind ``"structural"``, and points ``"first"``, ``"last"``.

    Notes
    -----
    The springs keep the particles near their rest distance but do not
    preserve the string's length: hanging under its own weight, the string
    stretches like a rubber band, the more so the softer the springs.
    """
    if direction is None:
        direction = np.eye(d)[-1] * -1.0 if d in (2, 3) else None
    x, pinned = _chain(n, length, d, pin, span, direction)
    m, k = _chain_parameters(len(x), length, scaling, mass, k, linear_density, stretch_modulus)
    i = np.arange(len(x) - 1)
    springs = Springs(np.stack([i, i + 1], axis=1), rest_length=length / (len(x) - 1), k=k, kd=kd,
                      kind="structural")
    return MassSpringSystem(x, m=m, springs=[springs], forces=common_forces(d, gravity, damping, scaling),
                            pinned=pinned, points={"first": 0, "last": len(x) - 1})


def hair(n=20, length=0.3, *, pin="root", d=2, direction=None, scaling="naive", mass=0.001, k=200.0,
         kb=0.002, kd=0.0, linear_density=0.05, stretch_modulus=50.0, bending_modulus=2e-5,
         gravity=9.81, damping=0.0):
    """A hair: a chain of springs plus bending forces at the joints.

    The bending force at each joint is proportional to the angle between
    the two segments (see :class:`particles.forces.Bending`), so the hair
    tends to stay straight and droops under gravity like a cantilever.

    Parameters
    ----------
    n, length, d, scaling, mass, k, kd, linear_density, stretch_modulus, gravity, damping
        As for :func:`string`.
    pin : {"root", "pair", "top", "none"}
        ``"root"`` (default) clamps the hair at its first particle: that one
        is fixed, and a :class:`~particles.forces.Clamp` of stiffness
        ``2 kb`` holds the first segment along `direction` (the mirror-image
        ghost node of beam theory), so that a cantilever's tip deflection
        converges at second order in the spacing. ``"pair"`` fixes the first
        two particles instead: the first segment never turns, the clamp acts
        half a segment in, and the deflection is short by a first-order
        ``2 L0 / L`` (19% at 11 particles). ``"top"`` fixes only the first
        (a hinge).
    direction : array_like, shape (d,), optional
        Initial direction from the root (default: horizontal, along the first axis).
    kb : float
        ``"naive"``: bending stiffness of every joint, in N m / rad.
    bending_modulus : float
        ``"physical"``: EI, in N m^2; each joint gets ``kb = EI / L0``.

    Returns
    -------
    MassSpringSystem
        Spring set ``"structural"`` and a :class:`~particles.forces.Bending`
        force (with ``pin="root"`` also the :class:`~particles.forces.Clamp`)
        among :meth:`MassSpringSystem.other_forces`.
    """
    if pin not in ("root", "pair", "top", "none"):
        raise ValueError(f"pin must be 'root', 'pair', 'top' or 'none', got {pin!r}")
    if direction is None:
        direction = np.eye(d)[0] if d in (2, 3) else None
    x, pinned = _chain(n, length, d, {"root": "top", "pair": "root"}.get(pin, pin), None, direction)
    n = len(x)
    m, k = _chain_parameters(n, length, scaling, mass, k, linear_density, stretch_modulus)
    L0 = length / (n - 1)
    if scaling == "naive":
        kb = nonnegative_number(kb, "kb", "N m")
    else:
        kb = nonnegative_number(bending_modulus, "bending_modulus", "N m^2") / L0
    i = np.arange(n - 1)
    springs = Springs(np.stack([i, i + 1], axis=1), rest_length=L0, k=k, kd=kd, kind="structural")
    j = np.arange(n - 2)
    bending = [Bending(np.stack([j, j + 1, j + 2], axis=1), kb=kb)]
    if pin == "root":  # the clamp: the joint at the root with its mirror-image ghost, 2 kb (see Clamp)
        bending.append(Clamp([[0, 1]], direction=x[1] - x[0], kb=2.0 * kb))
    return MassSpringSystem(x, m=m, springs=[springs],
                            forces=bending + common_forces(d, gravity, damping, scaling),
                            pinned=pinned, points={"root": 0, "tip": n - 1})
