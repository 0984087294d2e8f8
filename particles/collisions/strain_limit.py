"""The strain limit of the cloth pipeline: stretch springs held within Provot's limit, consistent with contact.

Cloth hardly stretches (Provot: about 10%), and the collision treatment of a step can stretch it where
the dynamics did not: a vertex held by the floor's friction while its neighbours move on, a proximity
impulse pushing two layers apart, an inelastic impulse at an impact. Bridson, Marino and Fedkiw [1]_
limit the strain inside the collision treatment, on the step's average velocity ``vbar``, before the
collisions that guarantee no crossing; Provot [2]_ shortens each spring longer than ``(1 + s) L0``.
:class:`StrainLimitStage` does both, alternately with the body stage:

1. the end positions ``x1 = x0 + h vbar`` go through Provot's Gauss-Seidel projection of the stretch
   springs (:func:`particles.constraints.provot.provot_projection`, or its compiled passes), and
   ``vbar`` takes the displacement over ``h``;
2. the vertices and edges that this moved into a body are moved out again (the body stage);
3. repeat while a spring is longer than the limit after the bodies (alternating projections onto
   two sets whose intersection holds the answer: the floor and the springs' balls are convex).

:class:`~particles.collisions.pipeline.ClothCollisions` then runs its continuous test and impact zones,
so the step never ends crossed; if they stretched a spring past the limit (an impulse at an impact, a
zone moved rigidly with a free neighbour), the pipeline limits again and repeats the continuous test
from ``x0``, up to ``strain_rounds`` times. Crossings are never traded for strain: the last stage of
every step is the continuous test.

References
----------
.. [1] R. Bridson, S. Marino and R. Fedkiw, "Simulation of clothing with folds and wrinkles",
   Symposium on Computer Animation 2003, 28-36.
.. [2] X. Provot, "Deformation constraints in a mass-spring model to describe rigid cloth
   behavior", Graphics Interface 1995, 147-154.
"""

import numpy as np

from ..backends import compiled
from .candidate_cache import CLOTH_COLLISION_WEIGHT
from ..constraints.provot import ROUNDING, spring_lengths
from ..constraints.provot_constraint import ProvotConstraint

__all__ = ["StrainLimitStage", "strain_limit_from_system", "MARGIN"]

MARGIN = 0.2
"""A spring past ``(1 + s) L0`` is shortened to ``(1 + (1 - MARGIN) s) L0``; the projection stops once every
spring is within ``(1 + s) L0``. Gauss-Seidel crawls in its tail (each sweep carries a correction one spring
further): on the 64^2 fold of ``bench/bench_cloth_fold.py`` a limit without margin took 7332 sweeps in its
first second, with a margin of 0.1, 0.2, 0.3 of the limit 599, 601 and 517 (and less time per step than the
treatment without any limit)."""


def strain_limit_from_system(system, kinds=("structural",), max_strain=0.1, iterations=200, backend=None):
    """Provot's constraint on a cloth's stretch springs, for ``ClothCollisions(strain_limit=...)``.

    Parameters
    ----------
    system : MassSpringSystem
        The cloth (its spring sets of the given kinds, its pins).
    kinds : sequence of str
        Spring kinds to limit (default: the structural, stretch, springs).
    max_strain : float
        ``s``: the largest relative elongation, default 0.1 (Provot's 10%).
    iterations : int
        Largest number of Gauss-Seidel sweeps per projection.
    backend : {None, "auto", "numpy", "numba"}

    Returns
    -------
    ProvotConstraint
        Gauss-Seidel over colour groups, shortening springs to ``(1 + (1 - MARGIN) s) L0`` with the
        tolerance ``MARGIN s``: a projection ends with every spring within ``(1 + s) L0`` unless it ran
        out of sweeps.
    """
    margin = MARGIN * max_strain
    return ProvotConstraint.from_system(system, kinds=kinds, max_strain=max_strain - margin, iterations=iterations,
                                        tol=margin, method="gauss-seidel", backend=backend)


class StrainLimitStage:
    """The strain limit of :class:`~particles.collisions.pipeline.ClothCollisions` (a base class of it).

    It uses its ``n``, ``strain_limit`` (a :class:`~particles.constraints.ProvotConstraint` or None),
    ``strain_rounds``, ``bodies`` and ``_bodies``.
    """

    def _strain(self, x0, vbar, h):
        """The largest strain of the limited springs at ``x0 + h vbar`` (0 without a limit)."""
        if self.strain_limit is None:
            return 0.0
        c = self.strain_limit
        i, j = c.indices[:, 0], c.indices[:, 1]
        strain = spring_lengths(x0 + h * vbar, i, j)[1] / c.rest_length - 1.0
        movable = c.free[i] | c.free[j]
        return float(np.max(strain[movable], initial=0.0))

    def _holds(self, strain):
        """Whether a largest strain is within the limit (and its rounding)."""
        return strain <= self.strain_limit.max_strain + self.strain_limit.tol + ROUNDING

    def _project_strain(self, x0, vbar, h):
        """Provot's projection of ``x0 + h vbar``, ``vbar`` corrected in place; returns (largest strain, sweeps).

        Compiled (:class:`particles.constraints.kernels.CompiledProjection`) where the constraint's backend
        resolves to numba for the mesh's vertices weighted as the other stages weigh them
        (:data:`particles.collisions.candidate_cache.CLOTH_COLLISION_WEIGHT`): a step's projection makes
        dozens of sweeps.
        """
        c = self.strain_limit
        X = np.empty((self.n, 2, 3))
        X[:, 0] = x0 + h * vbar
        X[:, 1] = vbar
        if compiled(c.backend, CLOTH_COLLISION_WEIGHT * self.n):  # "auto" as for the other stages
            if c._compiled_projection is None:
                from ..constraints.kernels import CompiledProjection  # noqa: PLC0415  (imports numba)
                c._compiled_projection = CompiledProjection(c)
            worst, sweeps = c._compiled_projection.project(X, h)
        else:
            result = c.project(X[:, 0])
            worst, sweeps = result.max_strain, result.iterations
            X[:, 0] = result.x
        vbar[:] = (X[:, 0] - x0) / h
        return float(worst), int(sweeps)

    def _limit_strain(self, x0, vbar, t, h):
        """Alternate Provot's projection and the body stage until both hold; returns the sweeps made.

        At most ``strain_rounds`` alternations, each with the whole body stage (vertices and edge
        samples); the last word is the bodies' (a vertex never ends in a body), and the caller checks
        the strain again after its continuous test. The edge samples belong in every alternation: over a
        box's corner, a limit whose alternations moved the vertices alone, the samples once after them,
        ended its steps with springs at up to 13.8% (24^2) and 18.1% (40^2), the samples' push having the
        last word; with them in each, within 10%.
        """
        sweeps = 0
        for _ in range(self.strain_rounds):  # a loop over alternations of the two projections
            strain = self._strain(x0, vbar, h)
            if self._holds(strain):
                break
            sweeps += self._project_strain(x0, vbar, h)[1]
            if not self.bodies:
                break
            self._bodies(x0, vbar, t, h)
        return sweeps
