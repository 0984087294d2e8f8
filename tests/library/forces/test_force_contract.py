"""The contract every force of the library keeps, checked for every subclass of Force in the package.

The forces are found by importing every module of ``particles`` (the grader
and the console command excepted) and walking the subclasses of
:class:`particles.forces.Force`; each must have a case below, so that a new
force cannot be forgotten. A case builds the force for given positions in 2D
or 3D and says whether it acts between particles (then it conserves the total
momentum).
"""

import importlib
import pkgutil
from dataclasses import dataclass

import numpy as np
import pytest

import particles
from particles.constraints import RigidRods
from particles.effects import Boids, Containment
from particles.forces import (Attractor, Bending, Clamp, Damping, Field, Force, Gravity, LennardJones, NBodyGravity,
                              Springs, SurfaceWind, Vortex, Wind)

N = 12  # particles of every test configuration


def _all_force_classes():
    """Every subclass of Force defined in the package (every module imported first)."""
    for info in pkgutil.walk_packages(particles.__path__, "particles."):
        if not info.name.startswith(("particles.course", "particles.cli", "particles.__main__")):
            importlib.import_module(info.name)
    found, todo = set(), [Force]
    while todo:  # a walk over the class tree
        for sub in todo.pop().__subclasses__():
            if sub not in found and sub.__module__.startswith("particles."):
                found.add(sub)
                todo.append(sub)
    return found


def _chain(n=N):
    return np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)


def _lennard_jones(x, **options):
    """A 12-6 force whose cutoff lies in the widest gap between the pair distances (its potential is smooth there)."""
    r = np.sort(np.linalg.norm(x[:, None] - x[None, :], axis=-1)[np.triu_indices(len(x), 1)])
    r = r[(r > 0.9) & (r < 2.5)]
    k = int(np.argmax(np.diff(r)))
    return LennardJones.from_epsilon_sigma(epsilon=0.5, sigma=0.6, cutoff=0.5 * (r[k] + r[k + 1]), **options)


@dataclass
class Case:
    """How to build one force for positions `x` (shape (n, d)), and whether it acts between particles."""

    cls: type
    make: object
    internal: bool = False
    dims: tuple = (2, 3)
    label: str = ""
    constraint: bool = False  # adds what cancels the forces already in F (put last), so F0 is zero for it


CASES = [
    Case(Gravity, lambda x: Gravity(np.r_[np.zeros(x.shape[1] - 1), -9.81])),
    Case(Damping, lambda x: Damping(0.7), label="d"),
    Case(Damping, lambda x: Damping(rate=0.3), label="rate"),
    Case(Wind, lambda x: Wind(np.linspace(0.5, 1.0, x.shape[1]), gust=0.5, period=1.3, wavelength=2.0,
                              per_mass=True)),
    Case(Attractor, lambda x: Attractor(np.full(x.shape[1], 0.4), strength=2.0, softening=0.3)),
    Case(Attractor, lambda x: Attractor(lambda t: np.full(x.shape[1], 0.1 * t), strength=-1.0), label="moving"),
    Case(Vortex, lambda x: Vortex(np.full(x.shape[1], 0.3), 1.5, core=0.2), label="default axis"),
    Case(Vortex, lambda x: Vortex(np.zeros(3), 1.5, axis=[1.0, 1.0, 0.0], core=0.2), dims=(3,), label="axis"),
    Case(Field, lambda x: Field(lambda y, t: -y * (1.0 + t))),
    Case(NBodyGravity, lambda x: NBodyGravity(G=1.0, softening=0.1), internal=True),
    Case(LennardJones, lambda x: _lennard_jones(x), internal=True, label="cells"),
    Case(LennardJones, lambda x: _lennard_jones(x, neighbors="all"), internal=True, label="all pairs"),
    Case(LennardJones, lambda x: _lennard_jones(x, box=8.0), internal=True, label="periodic"),
    Case(Springs, lambda x: Springs(np.concatenate([_chain(), [[0, 5], [3, 9]]]), rest_length=0.8, k=30.0,
                                    kd=0.4), internal=True),
    Case(Bending, lambda x: Bending(np.stack([np.arange(N - 2), np.arange(1, N - 1), np.arange(2, N)], axis=1),
                                    kb=0.7, rest_angle=0.3), internal=True),
    Case(Clamp, lambda x: Clamp([[0, 1], [4, 5]], direction=np.eye(x.shape[1])[0], kb=2.0)),
    Case(Boids, lambda x: Boids(2.0, separation=0.3, alignment=1.0, cohesion=0.5, view_angle=2.5, max_force=4.0)),
    Case(Containment, lambda x: Containment(np.full(x.shape[1], 0.5), np.full(x.shape[1], 2.5), margin=0.6)),
    Case(RigidRods, lambda x: RigidRods(_chain(6), x=x), internal=True, constraint=True),
    Case(SurfaceWind, lambda x: SurfaceWind([[0, 1, 2], [3, 4, 5], [6, 7, 8], [9, 10, 11], [0, 5, 10]],
                                            velocity=[1.0, -0.5, 2.0], coefficient=0.8), dims=(3,)),
    Case(SurfaceWind, lambda x: SurfaceWind([[0, 1, 2], [2, 3, 4]], velocity=lambda t: [0.0, 0.0, 1.0 + t],
                                            coefficient=1.2), dims=(3,), label="gusts"),
]


def _params():
    return [pytest.param(case, d, id=f"{case.cls.__name__}{'-' + case.label if case.label else ''}-{d}d")
            for case in CASES for d in case.dims]


def _state(d, seed=0):
    """Positions on a jittered grid (no two particles closer than 0.7 m), velocities, masses, a time."""
    rng = np.random.default_rng(seed)
    grid = np.stack(np.meshgrid(*[np.arange(4.0)] * d, indexing="ij"), -1).reshape(-1, d)
    x = grid[rng.permutation(len(grid))[:N]] + rng.uniform(-0.1, 0.1, (N, d))
    return x, rng.normal(size=(N, d)), rng.uniform(0.5, 2.0, N), 0.3


def test_every_force_of_the_package_has_a_case():
    """Each Force subclass found by walking the package is checked below (a new force cannot be forgotten)."""
    assert _all_force_classes() == {case.cls for case in CASES}


@pytest.mark.parametrize("case, d", _params())
def test_inputs_are_not_modified(case, d):
    """The force, its add_to and its potential energy leave positions, velocities and masses alone."""
    x, v, m, t = _state(d)
    force = case.make(x)
    copies = [a.copy() for a in (x, v, m)]
    for a in (x, v, m):
        a.setflags(write=False)
    force(x, v, t, m)
    force.add_to(np.zeros((N, d)), x, v, t, m)
    if hasattr(force, "potential_energy"):
        force.potential_energy(x, m, t)
    for a, b in zip((x, v, m), copies):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("case, d", _params())
def test_add_to_adds_in_place_with_the_right_shape_and_dtype(case, d):
    """add_to adds exactly the force alone into F, which keeps its shape (n, d), dtype and memory order."""
    x, v, m, t = _state(d)
    alone = case.make(x)(x, v, t, m)
    assert alone.shape == (N, d) and alone.dtype == np.float64 and np.all(np.isfinite(alone))
    for order in ("C", "F"):
        F0 = np.asarray(np.random.default_rng(1).normal(size=(N, d)) * (not case.constraint), order=order)
        F = F0.copy(order="K")
        assert case.make(x).add_to(F, x, v, t, m) is None
        assert F.shape == (N, d) and F.dtype == np.float64 and F.flags.f_contiguous == F0.flags.f_contiguous
        np.testing.assert_allclose(F - F0, alone, rtol=1e-12, atol=1e-12 * (1 + np.abs(alone).max()))


@pytest.mark.parametrize("case, d", [p for p in _params() if p.values[0].internal])
def test_forces_between_particles_conserve_momentum(case, d):
    """A force between particles sums to zero over all of them: the total momentum does not change."""
    x, v, m, t = _state(d)
    F = case.make(x)(x, v, t, m)
    np.testing.assert_allclose(F.sum(axis=0), 0.0, atol=1e-12 * np.abs(F).sum())


@pytest.mark.parametrize("case, d", [p for p in _params() if hasattr(p.values[0].cls, "potential_energy")])
def test_force_is_minus_the_gradient_of_its_potential_energy(case, d):
    """Where a potential energy is defined, F = -dU/dx by central differences (at rest, so damping is zero)."""
    x, _, m, t = _state(d)
    force = case.make(x)
    v = np.zeros_like(x)
    F = force(x, v, t, m)
    step = 1e-6
    grad = np.zeros_like(x)
    for i in range(N):  # a loop over particles and coordinates: the finite-difference reference
        for a in range(d):
            up, down = x.copy(), x.copy()
            up[i, a] += step
            down[i, a] -= step
            grad[i, a] = (force.potential_energy(up, m, t) - force.potential_energy(down, m, t)) / (2 * step)
    assert isinstance(force.potential_energy(x, m, t), float)
    np.testing.assert_allclose(F, -grad, rtol=1e-5, atol=1e-6 * (1 + np.abs(F).max()))


@pytest.mark.parametrize("case, d", _params())
def test_declared_independence_of_velocity_and_time_holds(case, d):
    """A force with uses_velocity = False ignores v, one with uses_time = False ignores t (runs rely on it)."""
    x, v, m, t = _state(d)
    force = case.make(x)
    F = force(x, v, t, m)
    if not force.uses_velocity:
        np.testing.assert_array_equal(case.make(x)(x, 3.0 * v + 1.0, t, m), F)
    if not force.uses_time:
        np.testing.assert_array_equal(case.make(x)(x, v, t + 1.7, m), F)


def test_forces_do_not_modify_inputs():
    """x and v are read, never written."""
    rng = np.random.default_rng(0)
    x, v = rng.normal(size=(30, 3)), rng.normal(size=(30, 3))
    x.setflags(write=False)
    v.setflags(write=False)
    for force in [Gravity([0, 0, -1]), Damping(1.0), Wind([1, 0, 0], gust=0.3), Attractor([0, 0, 0], 1.0),
                  Vortex([0, 0, 0], 1.0), NBodyGravity(softening=0.1), LennardJones.from_epsilon_sigma()]:
        force(x, v, 0.5)


def test_position_only_forces_say_so():
    """Forces that ignore velocity and time declare it (the run may reuse them); damping does not."""
    lj = LennardJones.from_epsilon_sigma()
    assert not lj.uses_velocity and not lj.uses_time
    assert not Gravity([0, -1]).uses_velocity and not NBodyGravity().uses_time
    assert Damping(1.0).uses_velocity and not Damping(1.0).uses_time
    assert Wind([1, 0], gust=0.5).uses_time and not Wind([1, 0]).uses_time
    assert Attractor(lambda t: [t, 0.0], 1.0).uses_time and not Attractor([0, 0], 1.0).uses_time
    assert not Field(lambda x, t: x).uses_velocity and Field(lambda x, t: x).uses_time
