"""Cloth: a grid of particles with structural, shear and flexion springs (Provot's model).

:func:`cloth` builds the hanging curtain or the falling sheet of the lecture;
:func:`cloth_springs`, :func:`cloth_masses` and :func:`cloth_stiffness` are
its parts, under the naive or the physical scaling of :mod:`particles.massspring`.

References
----------
.. [1] X. Provot, "Deformation constraints in a mass-spring model to describe
   rigid cloth behavior", Graphics Interface 1995 (structural, shear and
   flexion springs).
"""

import numpy as np

from .._checks import count, nonnegative_number, positive_number
from ..forces.fields import Wind
from ..forces.spring_sets import Bending, Springs
from .model import MassSpringSystem, check_scaling, common_forces, dual_weights

__all__ = ["cloth", "cloth_springs", "cloth_masses", "cloth_stiffness"]


def cloth_springs(nx, ny):
    """Index pairs of a cloth grid's springs, by kind (particle (i, j) is j nx + i).

    Returns
    -------
    dict
        ``"structural"``: (i,j)-(i+1,j) and (i,j)-(i,j+1); ``"shear"``:
        (i,j)-(i+1,j+1) and (i+1,j)-(i,j+1); ``"flexion"``: (i,j)-(i+2,j) and
        (i,j)-(i,j+2). Each value is an int array of shape (s, 2).
    """
    idx = np.arange(nx * ny).reshape(ny, nx)  # idx[j, i]

    def pairs(a, b):
        return np.stack([a.ravel(), b.ravel()], axis=1)

    return {
        "structural": np.concatenate([pairs(idx[:, :-1], idx[:, 1:]), pairs(idx[:-1, :], idx[1:, :])]),
        "shear": np.concatenate([pairs(idx[:-1, :-1], idx[1:, 1:]), pairs(idx[:-1, 1:], idx[1:, :-1])]),
        "flexion": np.concatenate([pairs(idx[:, :-2], idx[:, 2:]), pairs(idx[:-2, :], idx[2:, :])]),
    }


def cloth_masses(nx, ny, width, height, areal_density):
    """Physical particle masses of a cloth grid: density x dual-cell area, shape (ny nx,).

    Interior particles stand for a whole cell ``dx dy``, edge particles for
    half of one, corners for a quarter; the masses add up to
    ``areal_density * width * height`` exactly.
    """
    dx, dy = width / (nx - 1), height / (ny - 1)
    return areal_density * dx * dy * np.outer(dual_weights(ny), dual_weights(nx)).ravel()


def cloth_stiffness(nx, ny, width, height, modulus):
    """Physical stiffness of each cloth spring, by kind: ``k = Y A / L0^2``.

    Parameters
    ----------
    nx, ny : int
    width, height : float
        In metres.
    modulus : dict
        ``{"structural": Y_s, "shear": Y_sh, "flexion": Y_f}`` in N/m.

    Returns
    -------
    dict
        Stiffness arrays (N/m) in the order of :func:`cloth_springs`.

    Notes
    -----
    ``A`` is the area each spring stands for. The springs along row j share
    the strip of the sheet that row stands for, ``width`` long and ``w_j dy``
    wide (``w_j = 1/2`` on the first and last rows): the ``nx - 1`` structural
    springs get ``A = dx w_j dy``, so ``k = Y_s w_j dy / dx``; the ``nx - 2``
    flexion springs (``L0 = 2 dx``) get ``A = width w_j dy / (nx - 2)``; columns
    likewise. The two diagonals of a cell share its area, ``A = dx dy / 2``.
    Under a uniform strain along the springs, each family then stores exactly
    the energy of the continuous sheet, at any resolution.
    """
    dx, dy = width / (nx - 1), height / (ny - 1)
    wx, wy = dual_weights(nx), dual_weights(ny)

    def along_rows(Y, g):  # springs (i, j)-(i+g, j): the nx-g of row j share its strip, width w_j dy
        A = width * wy[:, None] * dy / (nx - g)
        return (Y * A / (g * dx) ** 2 * np.ones((ny, nx - g))).ravel()

    def along_columns(Y, g):  # springs (i, j)-(i, j+g)
        A = height * wx[None, :] * dx / (ny - g)
        return (Y * A / (g * dy) ** 2 * np.ones((ny - g, nx))).ravel()

    diagonal = modulus["shear"] * (dx * dy / 2) / (dx**2 + dy**2)  # two diagonals share a cell
    return {
        "structural": np.concatenate([along_rows(modulus["structural"], 1),
                                      along_columns(modulus["structural"], 1)]),
        "shear": np.full(2 * (nx - 1) * (ny - 1), diagonal),
        "flexion": np.concatenate([along_rows(modulus["flexion"], 2), along_columns(modulus["flexion"], 2)]),
    }


def _cloth_positions(nx, ny, width, height, plane, origin):
    dx, dy = width / (nx - 1), height / (ny - 1)
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))  # i: column, j: row
    x = np.zeros((ny, nx, 3))
    x[..., 0] = i * dx
    if plane == "vertical":  # hanging curtain in the x-z plane, row 0 on top
        x[..., 2] = -j * dy
    elif plane == "horizontal":  # lying in the x-y plane
        x[..., 1] = j * dy
    else:
        raise ValueError(f"plane must be 'vertical' or 'horizontal', got {plane!r}")
    return x.reshape(-1, 3) + np.asarray(origin, dtype=float)


def _cloth_points(nx, ny):
    idx = np.arange(nx * ny).reshape(ny, nx)
    return {
        "top left": int(idx[0, 0]), "top right": int(idx[0, -1]),
        "bottom left": int(idx[-1, 0]), "bottom right": int(idx[-1, -1]),
        "top corners": [int(idx[0, 0]), int(idx[0, -1])],
        "corners": [int(idx[0, 0]), int(idx[0, -1]), int(idx[-1, 0]), int(idx[-1, -1])],
        "top edge": idx[0].tolist(),
        "center": int(idx[ny // 2, nx // 2]),
    }


def cloth(nx=16, ny=16, width=1.0, height=1.0, *, pins="top corners", plane="vertical",
          origin=(0.0, 0.0, 0.0), scaling="naive", reference=8,
          mass=None, k_structural=None, k_shear=None, k_flexion=None, kb=None, kd=0.0,
          areal_density=0.2, stretch_modulus=100.0, shear_modulus=None, flexion_modulus=None,
          bending_modulus=0.0, gravity=9.81, damping=0.0, wind=None):
    """A rectangular cloth: a grid of particles with structural, shear and flexion springs.

    Parameters
    ----------
    nx, ny : int
        Particles per row and per column (>= 3).
    width, height : float
        Size of the cloth, in metres.
    pins : str, sequence of str or int, or None
        Particles held fixed: indices, point names (``"top left"``,
        ``"top right"``, ``"bottom left"``, ``"bottom right"``,
        ``"top corners"``, ``"corners"``, ``"top edge"``, ``"center"``) or a
        mix. Row 0 is the "top" edge. Default: the two top corners (the
        hanging curtain).
    plane : {"vertical", "horizontal"}
        Initial plane: a curtain in the x-z plane hanging from row 0 (z up),
        or a sheet lying in the x-y plane (to fall, swing or drape).
    origin : array_like, shape (3,)
        Position of particle (0, 0).
    scaling : {"naive", "physical"}
        See the module docstring. ``"naive"`` uses `mass` and `k_*` for every
        particle and spring; their defaults are the physical values of an
        interior particle and spring at a `reference` x `reference` grid of
        the same material, so that both scalings agree at that resolution.
    reference : int
        Resolution at which the naive defaults are calibrated.
    mass, k_structural, k_shear, k_flexion, kb : float, optional
        Naive per-particle mass (kg), per-spring stiffnesses (N/m) and
        per-joint bending stiffness (N m).
    kd : float
        Damping along every spring, in kg/s, the same for every spring under
        both scalings (``"physical"`` rescales masses and stiffnesses only).
    areal_density : float
        kg/m^2.
    stretch_modulus, shear_modulus, flexion_modulus : float
        2D moduli in N/m of the structural, shear and flexion springs
        (defaults: shear = stretch / 4, flexion = stretch / 10).
    bending_modulus : float
        N m. If > 0, joints along rows and columns also resist bending with
        a torque proportional to their angle (:class:`~particles.forces.Bending`),
        ``kb = B w / L0``.
    gravity : float
        m/s^2, along -z.
    damping : float
        Viscous damping: kg/s per particle (naive) or 1/s per unit mass (physical).
    wind : array_like, shape (3,), optional
        Wind acceleration (m/s^2), applied per unit mass: a uniform field,
        gravity turned sideways, whatever the sheet's orientation or speed.
        For wind that presses on the surface along its normal with the
        relative velocity (Provot's), add a
        :class:`~particles.forces.SurfaceWind` to the system's forces.

    Returns
    -------
    MassSpringSystem
        Spring sets ``"structural"``, ``"shear"``, ``"flexion"``; ``grid_shape``
        ``(ny, nx)``; ``points`` with the names above.
    """
    nx, ny = count(nx, "nx", 3), count(ny, "ny", 3)
    width = positive_number(width, "width", "metres")
    height = positive_number(height, "height", "metres")
    scaling = check_scaling(scaling)
    moduli = {
        "structural": positive_number(stretch_modulus, "stretch_modulus", "N/m"),
        "shear": stretch_modulus / 4 if shear_modulus is None else positive_number(shear_modulus, "shear_modulus", "N/m"),
        "flexion": stretch_modulus / 10 if flexion_modulus is None else positive_number(flexion_modulus, "flexion_modulus", "N/m"),
    }
    density = positive_number(areal_density, "areal_density", "kg/m^2")
    B = nonnegative_number(bending_modulus, "bending_modulus", "N m")
    x = _cloth_positions(nx, ny, width, height, plane, origin)
    pairs = cloth_springs(nx, ny)
    if scaling == "physical":
        m = cloth_masses(nx, ny, width, height, density)
        ks = cloth_stiffness(nx, ny, width, height, moduli)
        dx, dy = width / (nx - 1), height / (ny - 1)
        kb_rows, kb_cols = B * dy / dx, B * dx / dy
    else:
        r = count(reference, "reference", 3)
        ref_m = cloth_masses(r, r, width, height, density).reshape(r, r)[1, 1]
        ref_k = {kind: k.max() for kind, k in cloth_stiffness(r, r, width, height, moduli).items()}
        rdx, rdy = width / (r - 1), height / (r - 1)
        given = {"structural": k_structural, "shear": k_shear, "flexion": k_flexion}
        m = np.full(nx * ny, ref_m if mass is None else positive_number(mass, "mass", "kg"))
        ks = {kind: np.full(len(pairs[kind]), ref_k[kind] if given[kind] is None
                            else positive_number(given[kind], f"k_{kind}", "N/m")) for kind in pairs}
        kb_rows = kb_cols = B * rdy / rdx if kb is None else nonnegative_number(kb, "kb", "N m")
    springs = [Springs(pairs[kind], x=x, k=ks[kind], kd=kd, kind=kind) for kind in pairs]
    forces = common_forces(3, gravity, damping, scaling)
    if wind is not None:
        forces.append(Wind(wind, per_mass=True))
    idx = np.arange(nx * ny).reshape(ny, nx)
    if kb_rows > 0 or kb_cols > 0:
        rows = np.stack([idx[:, :-2], idx[:, 1:-1], idx[:, 2:]], axis=-1).reshape(-1, 3)
        cols = np.stack([idx[:-2, :], idx[1:-1, :], idx[2:, :]], axis=-1).reshape(-1, 3)
        kb_all = np.concatenate([np.full(len(rows), kb_rows), np.full(len(cols), kb_cols)])
        forces.insert(0, Bending(np.concatenate([rows, cols]), kb=kb_all))
    points = _cloth_points(nx, ny)
    return MassSpringSystem(x, m=m, springs=springs, forces=forces, pinned=_resolve_pins(pins, points, nx * ny),
                            points=points, grid_shape=(ny, nx))


def _resolve_pins(pins, points, n):
    """Indices from names, indices or a mix."""
    if pins is None:
        return []
    if isinstance(pins, (str, int, np.integer)):
        pins = [pins]
    out = []
    for p in pins:  # a loop over the few pin names the user gave
        if isinstance(p, str):
            if p not in points:
                raise ValueError(f"unknown pin name {p!r}; expected one of {', '.join(map(repr, points))}")
            value = points[p]
            out.extend(value if isinstance(value, list) else [value])
        elif isinstance(p, (int, np.integer)) and not isinstance(p, bool) and 0 <= p < n:
            out.append(int(p))
        else:
            raise ValueError(f"pins must be particle indices in [0, {n}) or point names, got {p!r}")
    return sorted(set(out))
