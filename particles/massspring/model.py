"""The mass-spring model: a particle system with labelled spring sets, and the rules its builders share.

:class:`MassSpringSystem` is a :class:`particles.ParticleSystem` whose spring
sets (:class:`particles.forces.Springs`) are labelled by kind
(``"structural"``, ``"shear"``, ...), with the quantities the lecture
measures on them: strains, the springs' Jacobians for implicit solvers, the
highest frequency and the largest stable step of symplectic Euler; its runs
take symplectic Euler's steps in one compiled pass where its springs run
compiled (:meth:`MassSpringSystem.stepper`, :class:`SymplecticEulerStep`). The
builders of :mod:`particles.massspring.strands` (strings, hair) and
:mod:`particles.massspring.cloth` make them, with the discretization rules below
(:func:`dual_weights`, :func:`common_forces`; see :mod:`particles.massspring`
for the naive and physical scalings).
"""

import numpy as np

from .._checks import nonnegative_number
from ..backends import compiled
from ..forces.fields import Damping, Gravity
from ..integrators import rewrap, symplectic_euler
from ..integrators.common import check_arguments
from ..system import ParticleSystem

__all__ = ["MassSpringSystem", "SymplecticEulerStep", "SCALINGS", "SYMPLECTIC_LIMIT", "check_scaling",
           "dual_weights", "common_forces", "gravity_vector"]

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
        self._compiled_step = None  # the compiled step's layout of this system, made at its first use

    def stepper(self, method):
        """The stepper a run takes its steps with (:meth:`particles.ParticleSystem.stepper`), symplectic Euler
        as :class:`SymplecticEulerStep`: this system's step in one compiled pass where its springs run compiled.

        Chosen once per run, where the system runs: symplectic Euler alone or inside fixes
        (:func:`particles.integrators.after`: Provot's constraint, a collider) becomes the system's own
        step; every other method is left as it is.
        """
        return rewrap(super().stepper(method), lambda step: SymplecticEulerStep(self) if step is symplectic_euler
                      else step)

    def compiled_step(self):
        """This system's :class:`~particles.massspring.compiled_step.CompiledStep` when it applies, else None.

        It applies when the system has one to three :class:`~particles.forces.Springs` sets
        (``compiled_role == "springs"``), in 2D or 3D, all resolving to numba for the system's size
        (:func:`particles.backends.compiled`), and the step covers its forces
        (:meth:`~particles.massspring.compiled_step.CompiledStep.parts`). Nothing imports numba otherwise.
        """
        springs = [f for f in self.forces if getattr(f, "compiled_role", None) == "springs"]
        if not springs or not all(compiled(f._backend, self.n) for f in springs):
            return None
        if self._compiled_step is None:
            from .compiled_step import CompiledStep  # noqa: PLC0415  (imports numba)
            self._compiled_step = CompiledStep(self)
        return self._compiled_step if self._compiled_step.parts(self.n) is not None else None

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

        See :meth:`particles.forces.Springs.jacobians`; `clamp` keeps
        ``-dF/dx`` positive semi-definite for implicit integration.
        """
        import scipy.sparse
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


class SymplecticEulerStep:
    """Symplectic Euler for one mass-spring system: its compiled step where it applies, else the NumPy stepper.

    A stepper ``step(f, X, t, h)`` (``order`` 1, second-order layout) that
    :meth:`MassSpringSystem.stepper` puts in place of
    :func:`~particles.integrators.symplectic_euler`: it takes the step with
    the system's :meth:`~MassSpringSystem.compiled_step` (the same state as
    the NumPy step, to rounding) when that applies, and with
    ``symplectic_euler(f, X, t, h)`` otherwise. Its :meth:`steps` lets
    :func:`particles.integrators.integrate` take the steps up to the next
    recorded state in one compiled call.
    """

    order = 1
    explicit = True
    second_order_layout = True
    fsal = False

    def __init__(self, system):
        self.system = system
        self.__name__ = "symplectic_euler"  # error messages name the method

    def __call__(self, f, X, t, h):
        step = self.system.compiled_step()
        if step is not None:
            X_checked, h_checked = check_arguments(X, t, h)
            X_new = step.symplectic_euler(X_checked, t, h_checked)
            if X_new is not None:
                return X_new
        return symplectic_euler(f, X, t, h)

    def steps(self, f, X, times, limit):
        """The steps from ``times[0]`` to ``times[-1]`` in one compiled call, guarded; None when it does not apply.

        Each step is the one :meth:`__call__` takes, to the bit, and the divergence guard
        (``max|X| <= limit``, finite) runs after each step inside the call
        (:meth:`~particles.massspring.compiled_step.CompiledStep.symplectic_euler_steps`).

        Returns
        -------
        (ndarray, int, float) or None
            The last state that passed the guard, the number of steps that passed, and the size
            ``max|X|`` of the last state computed.
        """
        step = self.system.compiled_step()
        if step is None:
            return None
        X, _ = check_arguments(X, times[0], times[1] - times[0])
        return step.symplectic_euler_steps(X, times, limit)


def check_scaling(scaling):
    """`scaling` checked: ``"naive"`` or ``"physical"`` (see :mod:`particles.massspring`)."""
    if scaling not in SCALINGS:
        raise ValueError(f"scaling must be 'naive' or 'physical', got {scaling!r}")
    return scaling


def dual_weights(n):
    """Share of a segment or cell that each of `n` grid points stands for: its dual cell, 1/2 at the ends.

    Parameters
    ----------
    n : int
        Points along a string or along one side of a cloth grid.

    Returns
    -------
    ndarray, shape (n,)
        ``[1/2, 1, ..., 1, 1/2]``: a particle's mass is ``density x spacing x`` its weight (the
        outer product of two of them for a cloth).
    """
    w = np.ones(n)
    w[[0, -1]] = 0.5
    return w


def gravity_vector(g, d):
    """Gravity of magnitude `g` (m/s^2, >= 0) down the last of `d` axes, shape (d,)."""
    g = nonnegative_number(g, "gravity", "m/s^2")
    vec = np.zeros(d)
    vec[-1] = -g  # the last axis points up
    return vec


def common_forces(d, gravity, damping, scaling):
    """The forces every builder adds: gravity down the last axis and damping (per unit mass when physical).

    Parameters
    ----------
    d : int
        Dimension of space.
    gravity : float
        In m/s^2 (0: none).
    damping : float
        kg/s per particle (``"naive"``) or 1/s per unit mass (``"physical"``); 0: none.
    scaling : {"naive", "physical"}

    Returns
    -------
    list of Force
    """
    forces = []
    if gravity:
        forces.append(Gravity(gravity_vector(gravity, d)))
    if damping:
        # physical: the same relaxation time for every particle (damping per unit mass)
        forces.append(Damping(rate=damping) if scaling == "physical" else Damping(damping))
    return forces
