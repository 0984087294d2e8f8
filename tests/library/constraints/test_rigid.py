"""Rigid rods by Lagrange multipliers (particles.constraints.rigid): the pendulum's exact period, drift, invariants."""

import numpy as np
import pytest

from particles import ParticleSystem
from particles.constraints import RigidRods, chain, crossing_period, pendulum, pendulum_period

G = 9.81


def test_pendulum_period_matches_the_elliptic_integral_at_120_degrees():
    """The Lagrange-multiplier pendulum released at 120 degrees has the period 4 sqrt(L/g) K(sin^2(60 deg)) to 1e-4."""
    theta0, L = np.radians(120.0), 0.7
    T = pendulum_period(theta0, L, G)
    p = pendulum(theta0, L, m=0.3, g=G)
    t, X = p.run(2.2 * T, 0.005, method="rk4")
    measured = crossing_period(t, X[:, 1, 0, 0])
    assert abs(measured / T - 1.0) < 1e-4
    assert abs(T / (2 * np.pi * np.sqrt(L / G)) - 1.3729) < 1e-4  # 37% longer than the small-angle period


def test_small_amplitude_period_is_two_pi_sqrt_l_over_g():
    """At 1 degree the measured period is the textbook 2 pi sqrt(L/g) to 1e-4."""
    p = pendulum(np.radians(1.0))
    t, X = p.run(5.0, 0.005, method="rk4")
    assert abs(crossing_period(t, X[:, 1, 0, 0]) / (2 * np.pi / np.sqrt(G)) - 1.0) < 1e-4


def test_rod_tension_at_the_bottom():
    """Passing the bottom, the rod pulls with m g (3 - 2 cos theta0), the weight plus the centripetal force."""
    theta0, m = np.radians(90.0), 0.5
    p = pendulum(theta0, 1.0, m=m)
    T = pendulum_period(theta0)
    p.run(T / 4, T / 4 / 2000, method="rk4")  # a quarter period: at the bottom
    rods = p.forces[-1]
    F = np.zeros((2, 2))
    p.forces[0].add_to(F, p.X[:, 0], p.X[:, 1], p.t, p.m)
    rods.add_to(F, p.X[:, 0], p.X[:, 1], p.t, p.m)
    tension = -rods.lam[0] * np.linalg.norm(p.X[1, 0] - p.X[0, 0])
    assert abs(tension / (m * G * (3 - 2 * np.cos(theta0))) - 1.0) < 1e-6


def test_drift_without_and_with_stabilization():
    """A swinging chain drifts off its rod lengths; Baumgarte feedback bounds the drift, projection removes it."""
    def drift(**options):
        c = chain(4, 1.0, theta0=np.radians(80.0), **{k: v for k, v in options.items() if k in ("ks", "kd")})
        method = c.forces[-1].stepper("rk4", c.m) if options.get("project") else "rk4"
        t, X = c.run(3.0, 0.01, method=method)
        return max(np.abs(c.forces[-1].values(Xk[:, 0])).max() for Xk in X)

    free, baumgarte, projected = drift(), drift(ks=400.0, kd=40.0), drift(project=True)
    assert free > 1e-7
    assert baumgarte < free / 10
    assert projected < 1e-12


def test_energy_of_the_chain_is_conserved():
    """RK4 on the multiplier chain keeps the total energy to 1e-6 of m g L over 3 s (the rods do no work)."""
    c = chain(3, 1.0, theta0=np.radians(70.0), m=0.2)
    t, X = c.run(3.0, 0.002, method="rk4")
    E = np.array([c.kinetic_energy(Xk) + c.potential_energy(Xk) for Xk in X])
    assert np.abs(E - E[0]).max() < 1e-6 * 3 * 0.2 * G


def test_internal_rods_conserve_momentum():
    """Free particles linked by rods, without gravity: the constraint forces sum to zero, momentum stays."""
    rng = np.random.default_rng(4)
    x = np.cumsum(rng.normal(size=(5, 3)), axis=0)
    v = rng.normal(size=(5, 3))
    k = np.arange(4)
    rods = RigidRods(np.stack([k, k + 1], axis=1), x=x)
    v = rods.project(x, v, 1.0)[1]  # velocities the rods allow
    m = rng.uniform(0.5, 2.0, 5)
    ps = ParticleSystem(x, v=v, m=m, forces=[rods])
    P0 = ps.momentum()
    t, X = ps.run(1.0, 0.002, method="rk4")
    assert np.allclose(ps.momentum(), P0, rtol=0, atol=1e-12)
    assert np.abs(rods.values(X[-1, :, 0])).max() < 1e-6


def test_projection_leaves_inputs_and_valid_states_alone():
    """project moves a valid state by nothing and never modifies the arrays it is given."""
    c = chain(3, theta0=0.4)
    x, v = c.X[:, 0].copy(), np.zeros((4, 2))
    v[1:] = [[1.0, 0.3], [2.0, 0.6], [3.0, 0.9]]  # along the straight chain: not allowed, removed
    x_new, v_new = c.forces[-1].project(x, v, c.m)
    assert np.array_equal(x, c.X[:, 0]) and np.abs(x_new - x).max() < 1e-15
    assert v[1, 0] == 1.0 and np.abs(c.forces[-1].values(x_new)).max() < 1e-14
    d = x_new[1:] - x_new[:-1]
    assert np.abs(np.einsum("sa,sa->s", d, v_new[1:] - v_new[:-1])).max() < 1e-12


@pytest.mark.parametrize("make, name", [
    (lambda: pendulum(np.pi), "theta0"),
    (lambda: pendulum_period(4.0), "theta0"),
    (lambda: pendulum(1.0, length=-1.0), "length"),
    (lambda: chain(0), "n"),
    (lambda: chain(2, m=0.0), "m"),
    (lambda: RigidRods([[0, 1]], 1.0, pinned=[0, 1]), "pinned"),
    (lambda: RigidRods([[0, 0]], 1.0), "indices"),
    (lambda: RigidRods([[0, 1]], 0.0), "length"),
    (lambda: RigidRods([[0, 1]]), "length"),
    (lambda: RigidRods([[0, 1]], 1.0, ks=-1.0), "ks"),
    (lambda: crossing_period([0.0, 1.0, 2.0], [1.0, 2.0, 3.0]), "y"),
])
def test_bad_input_names_the_argument(make, name):
    """Bad arguments raise ValueError naming the argument."""
    with pytest.raises(ValueError, match=name):
        make()
