"""N-body gravity (particles.forces.nbody): inverse square, momentum, potential, blocks, an orbit."""

import numpy as np

from particles import ParticleSystem
from particles.forces import NBodyGravity

from .helpers import numerical_gradient


def test_nbody_two_bodies_inverse_square():
    """|F| = G m1 m2 / r^2 along the line joining the bodies, equal and opposite."""
    x = np.array([[0.0, 0.0, 0.0], [3.0, 4.0, 0.0]])
    m = np.array([2.0, 5.0])
    F = NBodyGravity(G=1.5)(x, m=m)
    np.testing.assert_allclose(F[0], 1.5 * 2 * 5 / 25 * np.array([0.6, 0.8, 0.0]))
    np.testing.assert_allclose(F[1], -F[0])


def test_nbody_momentum_and_potential():
    """Total force zero to round-off; force is minus the gradient of the potential."""
    rng = np.random.default_rng(4)
    x = rng.normal(size=(60, 3))
    m = rng.uniform(0.5, 2.0, 60)
    nb = NBodyGravity(G=1.0, softening=0.05)
    F = nb(x, m=m)
    assert np.abs(F.sum(axis=0)).max() < 1e-12 * np.abs(F).max() * 60
    grad = numerical_gradient(lambda y: nb.potential_energy(y, m), x, eps=1e-6)
    np.testing.assert_allclose(F, -grad, rtol=1e-5, atol=1e-6)


def test_nbody_blocks_match_direct_sum():
    """The blocked computation equals a direct double sum (many blocks for large n)."""
    rng = np.random.default_rng(5)
    x = rng.normal(size=(1200, 2))
    m = rng.uniform(1, 2, 1200)
    F = NBodyGravity(softening=0.1)(x, m=m)
    k = 17
    r = x - x[k]
    r2 = np.sum(r**2, axis=1) + 0.01
    r2[k] = np.inf
    np.testing.assert_allclose(F[k], (m[k] * m / r2**1.5) @ r, rtol=1e-10)


def test_two_body_orbit_conserves_energy():
    """A circular two-body orbit with Verlet keeps its energy within 1e-4."""
    G, M = 1.0, 1.0
    x = np.array([[0.0, 0.0], [1.0, 0.0]])
    v = np.array([[0.0, 0.0], [0.0, 1.0]])
    ps = ParticleSystem(x, v=v, m=[M, 1e-6], forces=[NBodyGravity(G)])
    E0 = ps.kinetic_energy() + ps.potential_energy()
    ps.run(2 * np.pi, 0.005, method="verlet")
    assert abs(ps.kinetic_energy() + ps.potential_energy() - E0) < 1e-4 * abs(E0)
    np.testing.assert_allclose(ps.X[1, 0], [1.0, 0.0], atol=1e-2)  # back after one period
