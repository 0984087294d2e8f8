"""Position-based dynamics: constraints instead of springs (PBD and XPBD).

Stiff springs need tiny explicit steps (lecture 7). Position-based dynamics
(Müller et al. 2007) turns each spring into a *constraint* ``C(x) = 0`` and
solves it on the positions, after an explicit prediction::

    for each substep of length hs = h / substeps:
        v  += hs a_ext(x, v, t)                 # forces that are not constraints (gravity, wind)
        x_n = x;  x += hs v                     # predict
        lambda = 0
        repeat `iterations` times:              # project the constraints
            for each constraint:  dlambda, dx from C(x) (below);  x += dx;  lambda += dlambda
        v = (x - x_n) / hs                      # velocities from positions

For a constraint with gradients ``grad_p C`` at its particles and inverse
masses ``w_p = 1 / m_p`` (0 for a pinned particle), the projection moves
each particle along its gradient, weighted by ``w_p``, by
``dx_p = w_p grad_p C dlambda``, which keeps the total momentum:

* **PBD** (Müller et al.): ``dlambda = -k C / sum_p w_p |grad_p C|^2`` with a
  stiffness ``k`` in [0, 1] (1: the constraint is solved exactly, as far as the
  linearization goes). Its effective stiffness depends on the iteration count
  and the time step: more iterations make it stiffer, without a physical unit.
* **XPBD** (Macklin, Müller and Chentanez 2016): a *compliance* ``alpha``
  (inverse stiffness, ``alpha = 1 / k`` in m/N for a spring), scaled by the
  step, ``alpha_tilde = alpha / hs^2``, and a Lagrange multiplier ``lambda``
  per constraint, set to zero at the start of each substep and accumulated
  over its iterations::

      dlambda = (-C - alpha_tilde lambda - gamma grad C . (x - x_n))
                / ((1 + gamma) sum_p w_p |grad_p C|^2 + alpha_tilde)

  with ``gamma = alpha kd / hs`` for a damping ``kd`` (kg/s) along the
  constraint. Converged, it solves one backward-Euler-like step of the energy
  ``C^2 / (2 alpha)``: a distance constraint of compliance ``1 / k`` *is* a
  spring of stiffness ``k``, whatever the iteration count and the time step,
  and ``alpha = 0`` is a rigid rod. The force of a constraint is
  ``lambda grad C / hs^2``.

**Iterations.** Gauss-Seidel (default) goes through the constraints one after
another, each seeing the corrections of the previous ones. Without a Python
loop over constraints, it sweeps through groups of constraints that share no
particle (a graph colouring, :func:`particles.constraints.colouring.color_constraints`): within a group the order
does not matter, and each group is one vectorized update. Jacobi computes
every ``dlambda`` from the same positions; a particle shared by ``c``
constraints would then receive ``c`` corrections each computed as if alone,
so each ``dlambda`` is divided by the largest number of constraints of its
set at its free particles (on a regular grid, an average of the
corrections). Positions still move by ``w grad C dlambda``, so momentum is
kept. Both converge, Jacobi more slowly, to positions where every
``C + alpha_tilde lambda = 0``; not to the same positions to the last digit,
since each correction follows the gradient where the iteration stands (on a
crumpled cloth the two differ by about 1e-4 of a spring length).

**Substeps.** Macklin et al. (2019) found that at equal cost, many substeps of
one iteration each beat few substeps with many iterations: each substep
starts from a better prediction and the error of a nonlinear Gauss-Seidel
sweep shrinks with ``hs^2``, so the constraints end closer to solved (less
stretch). The energy is another matter: converged, an XPBD substep is a
backward-Euler step of the constraints' energy, and backward Euler
multiplies the amplitude of a vibration of frequency ``omega`` by
``1 / sqrt(1 + (omega hs)^2)`` per step (lecture 7), so one large step
iterated to convergence loses as much energy as backward Euler at that step.
Unconverged iterations make the material softer, not more damped; substeps
lose less energy because each implicit step is smaller (lecture 8 measures
both).

**Constraints** (each a vectorized set, :mod:`particles.xpbd.constraint_sets`):
:class:`Distance` (strings, hair and cloth springs), :class:`IsometricBending`
(hair joints, cloth rows and columns; why this bending model, see there),
:class:`IsometricClamp` (a hair's clamped root) and :class:`Attachment` (a
particle held to a point, possibly softly). Hard pins are the system's
pinned particles (``w = 0``).

References
----------
.. [1] M. Müller, B. Heidelberger, M. Hennix and J. Ratcliff, "Position based
   dynamics", Journal of Visual Communication and Image Representation
   18(2), 2007, 109-118.
.. [2] M. Macklin, M. Müller and N. Chentanez, "XPBD: position-based
   simulation of compliant constrained dynamics", Motion in Games 2016.
.. [3] M. Macklin, K. Storey, M. Lu, P. Terdiman, N. Chentanez, S. Jeschke and
   M. Müller, "Small steps in physics simulation", Symposium on Computer
   Animation 2019.
.. [4] M. Bergou, M. Wardetzky, D. Harmon, D. Zorin and E. Grinspun, "A
   quadratic bending model for inextensible surfaces", Symposium on Geometry
   Processing 2006.
"""

import numpy as np

from .._checks import as_float_array, count, pinned_indices, positive_number
from ..backends import check_backend, compiled
from .constraint_sets import ConstraintSet, Distance
from .from_springs import constraints_from_system
from .stiffness import iteration_corrected

__all__ = ["XPBD", "PBD", "XPBD_WEIGHT"]

METHODS = ("gauss-seidel", "jacobi")

# XPBD and PBD ask "auto" (particles.backends) with this many times their particles: a step is its substeps'
# sweeps over the colour groups, a few dozen NumPy calls each. `python bench/bench_cloth_fold.py --xpbd-sizes` (the
# fold's sheet, 10 substeps, ms per step, NumPy / compiled, 2026-12-06): 8^2 1.92 / 0.33, 16^2 2.48 / 0.50,
# 24^2 3.46 / 0.77, 32^2 4.46 / 1.17, 48^2 8.28 / 2.32, 64^2 12.22 / 3.97. Compiled from 1024 particles: a 32^2
# sheet, not the lectures' curtains (10^2 and 12^2), which stay bit for bit the reference's
XPBD_WEIGHT = 4


class XPBD:
    """Extended position-based dynamics: a stepper that solves constraints on the positions.

    Parameters
    ----------
    constraints : sequence of Distance, IsometricBending, IsometricClamp, Attachment
        The constraint sets, swept in this order in each iteration; distance
        sets without colour groups of their own are coloured together and
        swept first.
    m : array_like, shape (n,)
        Particle masses, in kg (> 0).
    pinned : array_like of int or bool
        Particles that never move (inverse mass 0).
    substeps : int
        Substeps per time step (>= 1), each of length ``hs = h / substeps``.
    iterations : int
        Constraint iterations per substep (>= 1).
    method : {"gauss-seidel", "jacobi"}
        Sweep through the colour groups of each set, or all constraints at
        once with averaging (see the module notes).
    forces : sequence of Force, optional
        Forces that are not constraints (gravity, damping, wind). Given,
        the stepper evaluates them itself and ignores the ``f`` it is called
        with (use it on a system whose springs the constraints replace, see
        :meth:`from_system`); omitted, the external accelerations are
        ``f(X, t)[:, 1]``, for a system that holds no springs.
    collider : Collider, optional
        Collisions resolved at the end of every substep (projection and
        response, :meth:`particles.collisions.Collider.resolve`), as Macklin et
        al. (2019) treat contacts; or wrap the whole stepper with
        :meth:`~particles.collisions.Collider.stepper`.
    backend : {None, "auto", "numpy", "numba"}, optional
        The NumPy code of :meth:`~particles.xpbd.constraint_sets.Distance.project` and the other sets'
        ``project``, or the same projections compiled (:mod:`particles.xpbd.kernels`;
        None: the global choice, see :mod:`particles.backends`). Compiled, a
        Gauss-Seidel substep is one call
        (:class:`particles.xpbd.compiled_substep.CompiledSubstep`): the
        prediction, every set's colour groups (distance, bending, clamps,
        attachments; each group's rows in parallel) and the new velocities,
        with uniform gravity and damping folded in (other forces evaluated in
        NumPy first); the same bits as NumPy on any number of threads. Jacobi, and
        a set of a kind without a compiled form (a subclass with its own
        ``project``), keep the per-pass path: distance passes compiled one
        at a time, other sets in NumPy.

    Attributes
    ----------
    multipliers : list of ndarray
        Lagrange multipliers of each set (in the order given) at the end of
        the last substep, shape (s,) for distances, (d, s) for the others;
        the constraint force is ``lambda grad C / hs^2``.
    violation : list of float
        Largest ``|C|`` over all distance constraints after each step (m).

    Notes
    -----
    Called as ``solver(f, X, t, h)`` it is a stepper for
    :meth:`particles.ParticleSystem.run`: first order in ``h``, stable at
    any step (the constraints are solved implicitly, the other forces
    explicitly, as symplectic Euler), with a numerical damping that shrinks
    with ``hs``. Costs ``substeps x iterations`` sweeps per step.

    Examples
    --------
    A pendulum of 1 m as a rigid rod (compliance 0) keeps its length:

    >>> import numpy as np
    >>> from particles import ParticleSystem
    >>> from particles.forces import Gravity
    >>> ps = ParticleSystem([[0.0, 0.0], [1.0, 0.0]], m=1.0, forces=[Gravity([0, -9.81])], pinned=[0])
    >>> solver = XPBD([Distance([[0, 1]], 1.0)], ps.m, ps.pinned, substeps=10)
    >>> t, X = ps.run(1.0, 1 / 60, method=solver)
    >>> abs(float(np.linalg.norm(X[-1, 1, 0] - X[-1, 0, 0])) - 1.0) < 1e-12
    True
    """

    formulation = "xpbd"
    order = 1
    explicit = True
    second_order_layout = True

    def __init__(self, constraints, m, pinned=(), *, substeps=1, iterations=1, method="gauss-seidel",
                 forces=None, collider=None, backend=None):
        self._backend = check_backend(backend)
        if isinstance(constraints, ConstraintSet):
            constraints = [constraints]
        constraints = list(constraints)
        for c in constraints:
            if not isinstance(c, ConstraintSet):
                raise ValueError(f"constraints must be Distance, IsometricBending, IsometricClamp or Attachment "
                                 f"sets, got {type(c).__name__}")
        self.constraints = constraints
        m = as_float_array(m, "m", ndim=1)
        if np.any(m <= 0):
            raise ValueError("m must be positive: every mass must be > 0 kg")
        self.m = m.copy()
        n = len(m)
        for c in constraints:
            if c.highest >= n:
                raise ValueError(f"constraints refer to particle {c.highest}, but m holds only {n} particles")
        self.pinned = pinned_indices(pinned, n)
        self.w = 1.0 / self.m
        self.w[self.pinned] = 0.0
        self.substeps = count(substeps, "substeps", 1)
        self.iterations = count(iterations, "iterations", 1)
        if method not in METHODS:
            raise ValueError(f"method must be 'gauss-seidel' or 'jacobi', got {method!r}")
        self.method = method
        self.forces = None if forces is None else list(forces)
        if collider is not None and not callable(getattr(collider, "resolve", None)):
            raise ValueError(f"collider must be a particles.collisions.Collider, got {type(collider).__name__}")
        self.collider = collider
        # several distance sets without colours of their own are coloured together (fewer, fuller groups)
        merge = [k for k, c in enumerate(constraints) if isinstance(c, Distance) and c._groups is None]
        merge = merge if len(merge) > 1 else []
        sets = ([Distance.concatenate([constraints[k] for k in merge])] if merge else []) + \
            [c for k, c in enumerate(constraints) if k not in merge]
        self._sources = ([merge] if merge else []) + [[k] for k in range(len(constraints)) if k not in merge]
        self._orders = [None] * len(sets)
        if method == "gauss-seidel":  # rows sorted by colour: each group's data and multipliers are slices
            sets, self._orders = map(list, zip(*[s.by_colour(n) for s in sets])) if sets else ([], [])
        self._sets = sets
        self._batches = [s.batches(self.w, method) for s in self._sets]
        self._multipliers, self._last = [c.new_multipliers(0) for c in constraints], None
        self.violation = []
        self._fused = None  # the compiled substep of these batches, made at its first use
        self._passes = None  # the compiled distance projections, batch by batch, made at their first use

    @property
    def n(self):
        """Number of particles."""
        return len(self.m)

    @classmethod
    def from_system(cls, system, kinds=None, bending=True, **options):
        """A solver for a MassSpringSystem whose springs (and bending) become constraints.

        Parameters
        ----------
        system : MassSpringSystem
            Its spring sets (and :class:`~particles.forces.Bending` forces)
            become constraints of the same energy (:func:`constraints_from_system`);
            its other forces (gravity, damping, wind) act as external forces.
            Run it with ``system.run(T, h, method=solver)``.
        kinds : sequence of str, optional
            Spring kinds to convert (default: all).
        bending : bool
            Convert Bending forces too.
        **options
            ``substeps``, ``iterations``, ``method``, ``collider``, ``backend``.

        Returns
        -------
        XPBD or PBD
            With XPBD, compliance ``1 / k``; with PBD, every stiffness is 1
            (choose another with :meth:`set_stiffness`).
        """
        constraints, converted = constraints_from_system(system, kinds, bending)
        gone = set(map(id, converted))
        forces = [f for f in system.forces if id(f) not in gone]
        return cls(constraints, system.m, system.pinned, forces=forces, **options)

    def _accelerations(self, f, x, v, t):
        """External accelerations, shape (d, n): from the solver's forces, else from ``f``."""
        n, d = self.n, x.shape[0]
        if self.forces is not None:
            F = np.zeros((d, n)).T  # an (n, d) array in the library's Fortran layout
            for force in self.forces:  # a loop over the few force objects
                force.add_to(F, x.T, v.T, t, self.m)
            a = F.T / self.m
        else:
            X = np.empty((n, 2, d), order="F")
            X[:, 0], X[:, 1] = x.T, v.T
            a = np.array(np.asarray(f(X, t))[:, 1].T)
        a[:, self.pinned] = 0.0
        return a

    def __call__(self, f, X, t, h):
        X = np.asarray(X, dtype=float)
        if X.ndim != 3 or X.shape[0] != self.n or X.shape[1] != 2:
            raise ValueError(f"X must have shape ({self.n}, 2, d), got shape {X.shape}")
        hs = positive_number(h, "h", "seconds") / self.substeps
        x = np.ascontiguousarray(X[:, 0].T)  # coordinate-major (d, n): every operation runs over particles
        v = np.ascontiguousarray(X[:, 1].T)
        v[:, self.pinned] = 0.0
        fused = self._compiled(len(x))
        if fused is not None:  # the whole substep in one compiled call (particles.xpbd.compiled_substep)
            terms = None if self.forces is None else fused.force_terms(self.forces, len(x))
            d_lam, l_lam, lams = fused.multipliers()
        for s in range(self.substeps):  # a loop over substeps
            ts = t + s * hs
            if fused is not None:
                a = None if terms is not None else self._accelerations(f, x, v, ts)
                last = s == self.substeps - 1 and self.collider is None  # then the call measures the violation
                violation = fused.substep(x, v, a, terms if terms is not None else np.zeros((0, 4)), hs,
                                          self.iterations, (d_lam, l_lam), measure=last)
            else:
                v += hs * self._accelerations(f, x, v, ts)
                x_n = x.copy()
                x += hs * v
                lams = self._solve(x, x_n, hs)
                v = (x - x_n) / hs
            if self.collider is not None:
                xc, vc, _ = self.collider.resolve(x.T, v.T, self.m, self.pinned, ts + hs)
                x, v = np.ascontiguousarray(xc.T), np.ascontiguousarray(vc.T)
        self._keep_multipliers(lams)
        if fused is not None:
            self.violation.append(violation if self.collider is None else fused.violation(x))
        else:
            self.violation.append(max([float(np.max(np.abs(c.values(x.T)), initial=0.0))
                                       for c in self._sets if isinstance(c, Distance)], default=0.0))
        X_new = np.empty_like(X)
        X_new[:, 0], X_new[:, 1] = x.T, v.T
        return X_new

    def _compiled(self, d):
        """The compiled substep for positions in `d` dimensions, or None (NumPy or per-colour calls).

        It applies with the Gauss-Seidel method, the backend resolving to numba
        for this many particles, and every set of a compiled form (distance or
        linear, :attr:`~particles.xpbd.constraint_sets.ConstraintSet.compiled_form`); kept
        until the batches are rebuilt (:meth:`set_stiffness`).
        """
        if self.method != "gauss-seidel" or not compiled(self._backend, XPBD_WEIGHT * self.n):
            return None
        if self._fused is not None and self._fused[0] is self._batches and self._fused[1] == d:
            return self._fused[2]
        from .compiled_substep import CompiledSubstep  # noqa: PLC0415  (imports numba)

        fused = None
        if CompiledSubstep.applies(self._sets, self._batches, d):
            fused = CompiledSubstep(self._sets, self._batches, self.m, self.w, self.formulation, d)
        self._fused = (self._batches, d, fused)
        return fused

    def _solve(self, x, x_n, hs):
        """The constraint iterations of one substep, on x (d, n) in place; returns the multipliers."""
        lams = [s.new_multipliers(len(x)) for s in self._sets]
        passes = None
        if compiled(self._backend, XPBD_WEIGHT * self.n):  # distance sets projected compiled, batch by batch
            from .kernels import CompiledPasses  # noqa: PLC0415  (imports numba)
            if self._passes is None:
                self._passes = CompiledPasses()
            passes = self._passes
        for _ in range(self.iterations):  # a loop over iterations
            for s, batches, lam in zip(self._sets, self._batches, lams):  # a loop over the few sets
                compiled_set = passes is not None and isinstance(s, Distance)
                for b in batches:  # Gauss-Seidel: one colour at a time (Jacobi: one batch)
                    if compiled_set:
                        passes.project(b, x, x_n, lam, hs, self.formulation)
                    else:
                        s.project(b, x, x_n, lam, hs, self.formulation)
        return lams

    @property
    def multipliers(self):
        """Lagrange multipliers of each set at the end of the last substep (see the class notes).

        Put back in the order the sets and their rows were given when first
        read after a step (a scatter as long as the constraints, which a run
        that never reads them does not pay at every step).
        """
        if self._last is not None:
            self._multipliers, self._last = self._unsorted_multipliers(self._last), None
        return self._multipliers

    def _keep_multipliers(self, lams):
        """Keep the last substep's multipliers (per solver set, colour-sorted) for :attr:`multipliers`."""
        self._last = lams

    def _unsorted_multipliers(self, lams):
        """Multipliers per set, in the order the sets and their rows were given (distances split again)."""
        unsorted = []
        for lam, order in zip(lams, self._orders):  # a loop over the few sets: undo the colour sort
            if order is not None:
                back = np.empty_like(lam)
                back[..., order] = lam
                lam = back
            unsorted.append(lam)
        multipliers = [None] * len(self.constraints)
        for lam, sources in zip(unsorted, self._sources):  # a loop over the few sets: split merged ones
            ends = np.cumsum([len(self.constraints[k]) for k in sources])[:-1]
            for k, part in zip(sources, np.split(lam, ends, axis=-1)):
                multipliers[k] = part
        return multipliers

    def set_stiffness(self, stiffness):
        """Set every constraint's PBD stiffness (in [0, 1]) and rebuild the batches; returns self."""
        k = float(stiffness)
        if not 0.0 <= k <= 1.0:
            raise ValueError(f"stiffness must lie in [0, 1], got {stiffness!r}")
        for c in self.constraints + self._sets:  # a loop over the few sets
            c.stiffness[:] = k
        self._batches = [s.batches(self.w, self.method) for s in self._sets]
        return self


class PBD(XPBD):
    """Position-based dynamics (Müller et al. 2007): each set's ``stiffness`` in [0, 1], no multipliers.

    Parameters as :class:`XPBD`, and:

    corrected : bool
        Scale every stiffness ``k`` to ``1 - (1 - k)^(1/iterations)``
        (:func:`particles.xpbd.stiffness.iteration_corrected`, the paper's
        section 3.3), so that the iterations of a substep remove from one
        constraint what one iteration of ``k`` would. The constraint sets keep
        their ``k``; the solver projects with the corrected one.

    The constraint sets' ``compliance`` and ``damping`` are not used, and
    :attr:`multipliers` stay zero. Its effective stiffness depends on the
    iteration count (much less with ``corrected``) and on the time step
    (lecture 8 measures both).

    Examples
    --------
    The same string stiffness parameter, ten times the iterations: a string
    that stretches ten times less.

    >>> from particles.massspring import string
    >>> def mean_strain(iterations):
    ...     c = string(10, k=50.0, damping=0.05)
    ...     c.run(2.0, 1 / 60, method=PBD.from_system(c, iterations=iterations).set_stiffness(0.5))
    ...     return c.strain().mean()
    >>> round(float(mean_strain(1) / mean_strain(10)), 1)
    10.4
    """

    formulation = "pbd"

    def __init__(self, constraints, m, pinned=(), *, corrected=False, **options):
        super().__init__(constraints, m, pinned, **options)
        self.corrected = bool(corrected)
        self._correct_batches()

    def set_stiffness(self, stiffness):
        """Set every constraint's PBD stiffness (in [0, 1]) and rebuild the batches; returns self."""
        super().set_stiffness(stiffness)
        self._correct_batches()
        return self

    def _correct_batches(self):
        """With ``corrected``, project with ``1 - (1 - k)^(1/iterations)`` (the batches' copy of ``k``)."""
        if self.corrected:
            for batches in self._batches:  # a loop over the few sets
                for b in batches:  # and over their colour groups
                    b.k = iteration_corrected(b.k, self.iterations)
