"""Provot's constraint on chosen springs of a system, applied at the end of every step of a run.

:class:`ProvotConstraint` holds the constrained springs, the pins and the
options, and wraps a stepper so that every step ends with the projection of
:func:`particles.constraints.provot.provot_projection` (the NumPy reference)
or its compiled form (:mod:`particles.constraints.kernels`).
"""

import numpy as np

from .._checks import as_float_array, count, index_array, nonnegative_number
from ..backends import check_backend, compiled
from ..integrators.solvers import after
from .colouring import color_constraints
from .provot import ROUNDING, ProjectionResult, provot_projection

__all__ = ["ProvotConstraint"]


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
        (fewer passes, each dearer); see :func:`~particles.constraints.provot.provot_projection`.
    backend : {None, "auto", "numpy", "numba"}, optional
        Who projects in :meth:`stepper`: :func:`~particles.constraints.provot.provot_projection`,
        or the same passes compiled, in place on the step's end state
        (:mod:`particles.constraints.kernels`; None: the global choice, see
        :mod:`particles.backends`). :meth:`project` is always the NumPy reference.

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
        self.groups = color_constraints(self.indices, n) if method == "gauss-seidel" else None
        self.history = []
        self._compiled_projection = None  # the compiled projection's arrays, made at its first use

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
            compiled (:class:`particles.constraints.kernels.CompiledProjection`)
            and corrects the step's end state in place, in its own memory order.
        """

        def project(X_old, X_new, t, h):
            if compiled(self.backend, len(X_new)) and len(X_new) == len(self.free) and X_new.dtype == np.float64:
                if self._compiled_projection is None:
                    from .kernels import CompiledProjection  # noqa: PLC0415  (imports numba)
                    self._compiled_projection = CompiledProjection(self)
                worst, passes = self._compiled_projection.project(X_new, h)
                self.history.append(ProjectionResult(None, worst, passes, worst <= self.max_strain + self.tol + ROUNDING))
                return X_new
            result = self.project(X_new[:, 0])
            self.history.append(ProjectionResult(None, result.max_strain, result.iterations, result.converged))
            X_new[:, 1] += (result.x - X_new[:, 0]) / h
            X_new[:, 0] = result.x
            return X_new

        return after(step, project, "provot")
