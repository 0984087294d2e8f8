"""Sets of springs, bending joints and clamps as force objects: index arrays, parameters, the backend.

:class:`Springs` holds many springs as index arrays (one spring per row) and
evaluates them all at once with :func:`particles.forces.springs.spring_forces`
(or its compiled form); it also assembles the sparse force Jacobians ``dF/dx``
and ``dF/dv`` that implicit integration needs. :class:`Bending` resists the
angle between consecutive segments of a chain (hair); :class:`Clamp` the angle
between a chain's first segment and a fixed direction (a clamped root). Their
formulas are in :mod:`particles.forces.springs`.
"""

import numpy as np

from .._checks import as_float_array, index_array, indices_fit, per_item
from .._vectors import unit
from ..backends import check_backend, compiled
from .force import Force
from .pairs import pair_differences
from .springs import bending_forces, clamp_forces, spring_forces, spring_jacobians

__all__ = ["Springs", "Bending", "Clamp"]


class Springs(Force):
    """A set of linear springs with damping along each spring.

    Parameters
    ----------
    indices : array_like of int, shape (s, 2)
        The two particles ``(i, j)`` of each spring.
    rest_length : float or array_like, shape (s,), optional
        ``L0`` in metres. Default: the current distances in `x`.
    k : float or array_like, shape (s,)
        Stiffness, in N/m, > 0.
    kd : float or array_like, shape (s,)
        Damping along the spring, in kg/s (N s/m), >= 0.
    x : array_like, shape (n, d), optional
        Positions that define the rest lengths when `rest_length` is omitted.
    kind : str, optional
        A label ("structural", "shear", ...), used by builders and plots.
    backend : {None, "auto", "numpy", "numba"}, optional
        Who evaluates the forces: :func:`~particles.forces.springs.spring_forces`,
        or the same formula compiled (:mod:`particles.forces.kernels`; None: the
        global choice, see :mod:`particles.backends`).

    Attributes
    ----------
    i, j : ndarray of int, shape (s,)
    rest_length, k, kd : ndarray, shape (s,)

    Examples
    --------
    >>> import numpy as np
    >>> s = Springs([[0, 1]], rest_length=1.0, k=10.0)
    >>> s(np.array([[0.0, 0.0], [1.5, 0.0]]))     # stretched by 0.5 m: 5 N pulls them together
    array([[ 5.,  0.],
           [-5.,  0.]])
    """

    _compiled_role = "springs"  # the compiled step of particles.massspring computes these itself

    def __init__(self, indices, rest_length=None, k=1.0, kd=0.0, x=None, kind=None, backend=None):
        self._backend = check_backend(backend)
        ij = index_array(indices, "indices", 2)
        if np.any(ij[:, 0] == ij[:, 1]):
            raise ValueError("indices must join two different particles in every spring")
        self.i, self.j = ij[:, 0].copy(), ij[:, 1].copy()
        s = len(ij)
        if rest_length is None:
            if x is None:
                raise ValueError("give rest_length, or positions x from which to take the rest lengths")
            x = as_float_array(x, "x", ndim=2)
            if s and ij.max() >= len(x):
                raise ValueError(f"indices refer to particle {ij.max()} but x has only {len(x)} particles")
            rest_length, _ = unit(pair_differences(x, self.i, self.j))
        self.rest_length = per_item(rest_length, "rest_length", s)
        if np.any(self.rest_length < 0):
            raise ValueError("rest_length must be >= 0 (in metres); 0 is a zero-length spring")
        self.k = per_item(k, "k", s, positive=True)
        self.kd = per_item(kd, "kd", s)
        self.kind = kind
        self._highest = int(ij.max()) if s else -1
        self._compiled_pass = None  # the compiled pass's incidence list and buffers, made at its first use

    def __len__(self):
        return len(self.i)

    @property
    def indices(self):
        """The spring index pairs, shape (s, 2)."""
        return np.stack([self.i, self.j], axis=1)

    def lengths(self, x):
        """Current lengths ``|x_i - x_j|``, shape (s,), in metres."""
        L, _ = unit(pair_differences(np.asarray(x, dtype=float), self.i, self.j))
        return L

    def strain(self, x):
        """Relative elongation ``(L - L0) / L0`` of every spring, shape (s,)."""
        return self.lengths(x) / self.rest_length - 1.0

    def add_to(self, F, x, v, t, m):
        indices_fit(self._highest, len(x), "indices")
        if compiled(self._backend, len(x)):
            from .kernels import SpringPass  # noqa: PLC0415  (imports numba)
            if self._compiled_pass is None:
                self._compiled_pass = SpringPass()
            return self._compiled_pass.add_to(F, x, v, self.i, self.j, self.rest_length, self.k, self.kd)
        spring_forces(F, x, v, self.i, self.j, self.rest_length, self.k, self.kd)

    def potential_energy(self, x, m=None, t=0.0):
        """Elastic energy ``sum k (L - L0)^2 / 2``, in joules."""
        return 0.5 * float(np.sum(self.k * (self.lengths(x) - self.rest_length) ** 2))

    def jacobians(self, x, v=None, n=None, clamp=False, damping_position_terms=None):
        """Sparse Jacobians ``dF/dx`` and ``dF/dv`` of these springs' forces.

        Parameters
        ----------
        x, v : ndarray, shape (n, d)
            Positions and velocities (`v` only matters for the damping part
            of ``dF/dx``).
        n : int, optional
            Number of particles (default ``len(x)``).
        clamp : bool
            Drop the transverse term of compressed springs (``L < L0``), whose
            sign would make ``-dF/dx`` indefinite (Choi and Ko 2002). Use it
            for implicit integration; the result is then symmetric negative
            semi-definite.
        damping_position_terms : bool, optional
            Include how the damping force changes with positions (a
            non-symmetric term). Default: included when ``clamp`` is False
            (the exact Jacobian), left out when it is True.

        Returns
        -------
        Kx, Kv : scipy.sparse.csr_matrix, shape (n d, n d)
            Entry ``[i d + a, j d + b]`` is ``dF_{i,a} / dx_{j,b}`` (resp. ``v``),
            for the particle-major flattening ``x.ravel()``
            (:func:`particles.forces.springs.spring_jacobians`).
        """
        x = np.asarray(x, dtype=float)
        n = len(x) if n is None else n
        indices_fit(self._highest, min(n, len(x)), "indices")
        return spring_jacobians(x, v, self.i, self.j, self.rest_length, self.k, self.kd, n, clamp=clamp,
                                damping_position_terms=damping_position_terms)


class Bending(Force):
    """Resistance to bending at the joints of a chain: torque proportional to the angle.

    For each triple ``(i, j, l)`` of consecutive particles, ``theta`` is the
    angle between the segments ``e1 = x_j - x_i`` and ``e2 = x_l - x_j`` (0
    when straight). The energy ``kb (theta - theta0)^2 / 2`` gives forces
    ``F = -kb (theta - theta0) dtheta/dx``, proportional to the angle and
    summing to zero (no net force, no net torque)
    (:func:`particles.forces.springs.bending_forces`).

    Parameters
    ----------
    triples : array_like of int, shape (b, 3)
    kb : float or array_like, shape (b,)
        Bending stiffness per joint, in N m / rad (joules), >= 0.
    rest_angle : float or array_like, shape (b,), optional
        ``theta0`` in radians (default: 0, straight).
    x : array_like, shape (n, d), optional
        Take the rest angles from these positions instead.
    backend : {None, "auto", "numpy", "numba"}, optional
        The NumPy pass or the same formula compiled (see :mod:`particles.backends`).

    Notes
    -----
    With ``c = cos(theta)``, ``dtheta/dx = -dc/dx / sin(theta)`` and
    ``dc/de1 = (e2_hat - c e1_hat) / |e1|``, ``dc/de2 = (e1_hat - c e2_hat) / |e2|``.
    For a straight rest shape, ``theta / sin(theta) -> 1`` as the chain
    straightens, so the force is computed without dividing by zero
    (:func:`particles.forces.springs.joint_factor`).
    """

    uses_velocity = False
    uses_time = False
    _compiled_role = "bending"  # the compiled step of particles.massspring computes these itself

    def __init__(self, triples, kb=1.0, rest_angle=None, x=None, backend=None):
        self._backend = check_backend(backend)
        ijl = index_array(triples, "triples", 3)
        self.i, self.j, self.l = (ijl[:, c].copy() for c in range(3))
        b = len(ijl)
        self._highest = int(ijl.max()) if b else -1
        self.kb = per_item(kb, "kb", b)
        if rest_angle is None and x is not None:
            rest_angle = self.angles(as_float_array(x, "x", ndim=2))
        self.rest_angle = per_item(0.0 if rest_angle is None else rest_angle, "rest_angle", b)
        self._compiled_pass = None  # the compiled pass's incidence list and buffers, made at its first use

    def angles(self, x):
        """Angle at each joint, in radians, shape (b,)."""
        x = np.asarray(x, dtype=float)
        _, u1 = unit(x.T[:, self.j] - x.T[:, self.i])
        _, u2 = unit(x.T[:, self.l] - x.T[:, self.j])
        return np.arccos(np.clip(np.einsum("as,as->s", u1, u2), -1.0, 1.0))

    def add_to(self, F, x, v, t, m):
        indices_fit(self._highest, len(x), "triples")
        if compiled(self._backend, len(x)):
            from .kernels import BendingPass  # noqa: PLC0415  (imports numba)
            if self._compiled_pass is None:
                self._compiled_pass = BendingPass()
            return self._compiled_pass.add_to(F, x, self.i, self.j, self.l, self.kb, self.rest_angle)
        bending_forces(F, x, self.i, self.j, self.l, self.kb, self.rest_angle)

    def potential_energy(self, x, m=None, t=0.0):
        """``sum kb (theta - theta0)^2 / 2``, in joules."""
        return 0.5 * float(np.sum(self.kb * (self.angles(x) - self.rest_angle) ** 2))


class Clamp(Force):
    """A clamped end: a torque proportional to the angle between a segment and a fixed direction.

    For each pair ``(i, j)`` (``i`` the clamped end, usually pinned, ``j`` its
    neighbour), ``theta`` is the angle between the unit vector ``u0`` and
    ``e = x_j - x_i``. The energy ``kb theta^2 / 2`` gives the force
    ``F_j = -F_i = kb (theta / sin theta) (u0 - cos(theta) e_hat) / |e|``:
    the joint of :class:`Bending` whose first segment is held along ``u0``
    (:func:`particles.forces.springs.clamp_forces`).

    Parameters
    ----------
    pairs : array_like of int, shape (c, 2)
        ``(i, j)`` per clamp.
    direction : array_like, shape (d,) or (c, d)
        The clamped direction(s) ``u0``, normalized here.
    kb : float or array_like, shape (c,)
        Stiffness, in N m / rad (joules), >= 0.

    Notes
    -----
    A beam clamped at ``x_0`` has ``w(0) = 0`` and ``w'(0) = 0``. Pinning
    ``x_0`` and ``x_1`` instead holds the whole first segment straight: the
    beam is then clamped half a segment in, an error of first order in the
    spacing. The mirror-image ghost node ``x_-1`` (reflection of ``x_1``)
    makes the root a joint of angle ``2 theta`` that stands for half a
    segment, i.e. a :class:`Bending` joint of stiffness ``kb`` turned by
    ``2 theta`` with half the weight: energy ``(kb / 2) (2 theta)^2 / 2``, a
    clamp of stiffness ``2 kb`` (see :func:`particles.massspring.hair`).

    Examples
    --------
    >>> import numpy as np
    >>> clamp = Clamp([[0, 1]], direction=[1.0, 0.0], kb=2.0)
    >>> x = np.array([[0.0, 0.0], [0.1, 0.0]])
    >>> clamp(x).tolist()   # straight along u0: no force
    [[0.0, 0.0], [0.0, 0.0]]
    """

    uses_velocity = False
    uses_time = False
    _compiled_role = "clamp"  # the compiled step of particles.massspring has a kernel for it

    def __init__(self, pairs, direction, kb=1.0):
        ij = index_array(pairs, "pairs", 2)
        self.i, self.j = ij[:, 0].copy(), ij[:, 1].copy()
        c = len(ij)
        self._highest = int(ij.max()) if c else -1
        u = as_float_array(direction, "direction", ndim=(1, 2))
        u = np.broadcast_to(u, (c, u.shape[-1])).copy() if u.ndim == 1 else u
        if u.shape[0] != c:
            raise ValueError(f"direction must have shape (d,) or ({c}, d), got shape {u.shape}")
        norm = np.linalg.norm(u, axis=1)
        if np.any(norm == 0):
            raise ValueError("direction must be non-zero vectors")
        self.direction = u / norm[:, None]
        self.kb = per_item(kb, "kb", c)

    def angles(self, x):
        """Angle between each clamped segment and its direction, in radians, shape (c,)."""
        x = np.asarray(x, dtype=float)
        _, u = unit(x.T[:, self.j] - x.T[:, self.i])
        return np.arccos(np.clip(np.einsum("as,sa->s", u, self.direction), -1.0, 1.0))

    def add_to(self, F, x, v, t, m):
        indices_fit(self._highest, len(x), "pairs")
        clamp_forces(F, x, self.i, self.j, self.direction, self.kb)

    def potential_energy(self, x, m=None, t=0.0):
        """``sum kb theta^2 / 2``, in joules."""
        return 0.5 * float(np.sum(self.kb * self.angles(x) ** 2))
