"""Mass-spring models: strings, hair and cloth, ready to simulate.

Each builder returns a :class:`MassSpringSystem`, a particle system whose
spring sets are labelled by kind, with gravity, damping and pins set up.

Discretization and physical parameters
--------------------------------------
A builder's ``scaling`` says how masses and stiffnesses follow the grid:

* ``"naive"``: every particle has the same mass and every spring of a kind
  the same stiffness, whatever the resolution. This is what the lecture
  warns about: refining the grid adds mass and changes the stiffness of the
  body, so a finer cloth does not behave like a coarser one.
* ``"physical"``: masses and stiffnesses are derived from material
  parameters so that the *body* stays the same under refinement:

  - mass = density x the length (string) or area (cloth) a particle stands
    for (its dual cell: half a segment or cell at the boundary);
  - stiffness by matching elastic energies. A spring of rest length ``L0``
    stretched by a strain ``e`` stores ``k (e L0)^2 / 2``; the piece of
    material it stands for stores ``Y e^2 / 2`` per unit length (string,
    ``Y`` = EA in N) or per unit area (cloth, ``Y`` in N/m). Equal energies
    give ``k = Y / L0`` for a string and ``k = Y A / L0^2`` for a cloth spring
    standing for an area ``A``. On a square grid ``k = Y`` whatever the
    spacing: a 2D spring network keeps its stiffness under refinement while
    its particles get lighter;
  - bending stiffness per joint ``kb = B w / L0`` from a bending modulus ``B``
    (EI in N m^2 for hair; N m for cloth, over a strip of width ``w``), since
    a joint turning by ``theta`` over a segment ``L0`` is a curvature
    ``theta / L0``.

References
----------
.. [1] X. Provot, "Deformation constraints in a mass-spring model to describe
   rigid cloth behavior", Graphics Interface 1995 (structural, shear and
   flexion springs).
"""

import numpy as np
import scipy.sparse

from ._checks import nonnegative_number, positive_number
from .forces import Damping, Gravity, Wind
from .springs import Bending, Clamp, Springs
from .system import ParticleSystem

__all__ = ["MassSpringSystem", "string", "hair", "cloth", "cloth_masses", "cloth_stiffness"]

SYMPLECTIC_LIMIT = 2.0  # symplectic Euler and Verlet are stable for omega h <= 2

SCALINGS = ("naive", "physical")


class MassSpringSystem(ParticleSystem):
    """A :class:`~particles.ParticleSystem` with labelled spring sets.

    Parameters
    ----------
    x, v, m, pinned, t
        As for :class:`~particles.ParticleSystem`.
    springs : sequence of Springs
        Spring sets, each with a distinct ``kind`` label.
    forces : sequence of Force
        Other forces (gravity, damping, wind, bending).
    points : dict, optional
        Named particle indices or index lists, e.g. ``{"top left": 0}``.
    grid_shape : (int, int), optional
        ``(ny, nx)`` for a cloth: particle ``(i, j)`` (column i, row j) is
        ``j * nx + i``.

    Attributes
    ----------
    springs : dict
        Spring set by kind.
    points : dict
    grid_shape : tuple or None
    """

    def __init__(self, x, v=None, m=1.0, springs=(), forces=(), pinned=(), t=0.0, points=None,
                 grid_shape=None):
        kinds = [s.kind for s in springs]
        if len(set(kinds)) != len(kinds):
            raise ValueError(f"spring sets need distinct kinds, got {kinds}")
        self.springs = {s.kind: s for s in springs}
        super().__init__(x, v=v, m=m, forces=list(springs) + list(forces), pinned=pinned, t=t)
        self.points = dict(points or {})
        self.grid_shape = grid_shape

    def spring_indices(self):
        """All springs' index pairs, shape (s, 2), kinds concatenated in order."""
        return np.concatenate([s.indices for s in self.springs.values()]) if self.springs \
            else np.zeros((0, 2), dtype=np.int64)

    def rest_lengths(self):
        """All springs' rest lengths, shape (s,), in the order of :meth:`spring_indices`."""
        return np.concatenate([s.rest_length for s in self.springs.values()]) if self.springs \
            else np.zeros(0)

    def strain(self, X=None, kind=None):
        """Relative elongation ``(L - L0) / L0`` of the springs (of one `kind`, or all)."""
        X = self.X if X is None else self._check_state(X)
        chosen = self.springs.values() if kind is None else [self.springs[kind]]
        return np.concatenate([s.strain(X[:, 0]) for s in chosen])

    def max_strain(self, X=None, kind=None):
        """Largest relative elongation of any spring (0 when none is stretched)."""
        return float(max(0.0, np.max(self.strain(X, kind), initial=0.0)))

    def spring_jacobians(self, X=None, clamp=True):
        """Sum of all spring sets' ``dF/dx`` and ``dF/dv`` (sparse, (n d)^2).

        See :meth:`particles.springs.Springs.jacobians`; `clamp` keeps
        ``-dF/dx`` positive semi-definite for implicit integration.
        """
        X = self.X if X is None else self._check_state(X)
        n, d = X.shape[0], X.shape[2]
        Kx = scipy.sparse.csr_matrix((n * d, n * d))
        Kv = scipy.sparse.csr_matrix((n * d, n * d))
        for s in self.springs.values():  # a loop over the few spring kinds
            kx, kv = s.jacobians(X[:, 0], X[:, 1], clamp=clamp)
            Kx, Kv = Kx + kx, Kv + kv
        return Kx, Kv

    def highest_frequency(self, X=None):
        """Largest angular frequency ``omega_max`` (rad/s) of small oscillations about `X`.

        The square root of the largest eigenvalue of ``-M^-1 K`` (springs only,
        compressed springs clamped), computed for the free particles with
        ``scipy.sparse.linalg.eigsh`` from a fixed start vector (the same
        result at every call). Symplectic Euler and Verlet need
        ``h <= 2 / omega_max``: see :meth:`max_stable_step`.
        """
        import scipy.sparse.linalg

        X = self.X if X is None else self._check_state(X)
        Kx, _ = self.spring_jacobians(X, clamp=True)
        d = self.d
        free = np.setdiff1d(np.arange(self.n), self.pinned)
        dofs = (free[:, None] * d + np.arange(d)).ravel()
        s = 1.0 / np.sqrt(np.repeat(self.m[free], d))
        A = -(scipy.sparse.diags(s) @ Kx.tocsr()[dofs][:, dofs] @ scipy.sparse.diags(s))  # same spectrum as -M^-1 K
        if A.shape[0] < 3:
            lam = np.linalg.eigvalsh(A.toarray()).max(initial=0.0)
        else:
            # a fixed start vector: ARPACK's default is random, and h_max would change in its last digits
            v0 = np.random.default_rng(0).uniform(0.5, 1.5, A.shape[0])
            lam = scipy.sparse.linalg.eigsh(A, k=1, which="LA", return_eigenvectors=False, tol=1e-6, v0=v0)[0]
        return float(np.sqrt(max(lam, 0.0)))

    def max_stable_step(self, X=None):
        """Largest time step of symplectic Euler (and Verlet) for this system, ``2 / omega_max``, in seconds."""
        omega = self.highest_frequency(X)
        return np.inf if omega == 0 else SYMPLECTIC_LIMIT / omega

    def other_forces(self):
        """The forces that are not spring sets (gravity, damping, wind, bending)."""
        springs = set(map(id, self.springs.values()))
        return [f for f in self.forces if id(f) not in springs]


def _check_scaling(scaling):
    if scaling not in SCALINGS:
        raise ValueError(f"scaling must be 'naive' or 'physical', got {scaling!r}")
    return scaling


def _count(value, name, least):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
        raise ValueError(f"{name} must be an integer >= {least}, got {value!r}")
    return int(value)


def _dual_weights(n):
    """Share of a segment or cell that each of n grid points stands for: 1/2 at the ends."""
    w = np.ones(n)
    w[[0, -1]] = 0.5
    return w


def _gravity_vector(g, d):
    g = nonnegative_number(g, "gravity", "m/s^2")
    vec = np.zeros(d)
    vec[-1] = -g  # the last axis points up
    return vec


def _common_forces(d, gravity, damping, scaling):
    forces = []
    if gravity:
        forces.append(Gravity(_gravity_vector(gravity, d)))
    if damping:
        # physical: the same relaxation time for every particle (damping per unit mass)
        forces.append(Damping(rate=damping) if scaling == "physical" else Damping(damping))
    return forces


# -- strings and hair ----------------------------------------------------------


def _chain(n, length, d, pin, span, direction):
    """Positions of a chain and the indices to pin."""
    n = _count(n, "n", 2)
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
    if _check_scaling(scaling) == "naive":
        m = np.full(n, positive_number(mass, "mass", "kg"))
        k = np.full(n - 1, positive_number(k, "k", "N/m"))
    else:
        L0 = length / (n - 1)
        m = positive_number(linear_density, "linear_density", "kg/m") * L0 * _dual_weights(n)
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
    return MassSpringSystem(x, m=m, springs=[springs], forces=_common_forces(d, gravity, damping, scaling),
                            pinned=pinned, points={"first": 0, "last": len(x) - 1})


def hair(n=20, length=0.3, *, pin="root", d=2, direction=None, scaling="naive", mass=0.001, k=200.0,
         kb=0.002, kd=0.0, linear_density=0.05, stretch_modulus=50.0, bending_modulus=2e-5,
         gravity=9.81, damping=0.0):
    """A hair: a chain of springs plus bending forces at the joints.

    The bending force at each joint is proportional to the angle between
    the two segments (see :class:`particles.springs.Bending`), so the hair
    tends to stay straight and droops under gravity like a cantilever.

    Parameters
    ----------
    n, length, d, scaling, mass, k, kd, linear_density, stretch_modulus, gravity, damping
        As for :func:`string`.
    pin : {"root", "pair", "top", "none"}
        ``"root"`` (default) clamps the hair at its first particle: that one
        is fixed, and a :class:`~particles.springs.Clamp` of stiffness
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
        Spring set ``"structural"`` and a :class:`~particles.springs.Bending`
        force (with ``pin="root"`` also the :class:`~particles.springs.Clamp`)
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
                            forces=bending + _common_forces(d, gravity, damping, scaling),
                            pinned=pinned, points={"root": 0, "tip": n - 1})


# -- cloth ---------------------------------------------------------------------


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
    return areal_density * dx * dy * np.outer(_dual_weights(ny), _dual_weights(nx)).ravel()


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
    wx, wy = _dual_weights(nx), _dual_weights(ny)

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
        a torque proportional to their angle (:class:`~particles.springs.Bending`),
        ``kb = B w / L0``.
    gravity : float
        m/s^2, along -z.
    damping : float
        Viscous damping: kg/s per particle (naive) or 1/s per unit mass (physical).
    wind : array_like, shape (3,), optional
        Wind acceleration (m/s^2), applied per unit mass.

    Returns
    -------
    MassSpringSystem
        Spring sets ``"structural"``, ``"shear"``, ``"flexion"``; ``grid_shape``
        ``(ny, nx)``; ``points`` with the names above.
    """
    nx, ny = _count(nx, "nx", 3), _count(ny, "ny", 3)
    width = positive_number(width, "width", "metres")
    height = positive_number(height, "height", "metres")
    scaling = _check_scaling(scaling)
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
        r = _count(reference, "reference", 3)
        ref_m = cloth_masses(r, r, width, height, density).reshape(r, r)[1, 1]
        ref_k = {kind: k.max() for kind, k in cloth_stiffness(r, r, width, height, moduli).items()}
        rdx, rdy = width / (r - 1), height / (r - 1)
        given = {"structural": k_structural, "shear": k_shear, "flexion": k_flexion}
        m = np.full(nx * ny, ref_m if mass is None else positive_number(mass, "mass", "kg"))
        ks = {kind: np.full(len(pairs[kind]), ref_k[kind] if given[kind] is None
                            else positive_number(given[kind], f"k_{kind}", "N/m")) for kind in pairs}
        kb_rows = kb_cols = B * rdy / rdx if kb is None else nonnegative_number(kb, "kb", "N m")
    springs = [Springs(pairs[kind], x=x, k=ks[kind], kd=kd, kind=kind) for kind in pairs]
    forces = _common_forces(3, gravity, damping, scaling)
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
