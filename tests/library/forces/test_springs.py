"""The formulas of springs, bending and clamps (particles.forces.springs) and their NumPy passes."""

from fractions import Fraction

import numpy as np
import pytest

from particles.forces.springs import (STRAIGHT_RANGE, bending_forces, bent_ratio, damped_spring_force, joint_factor,
                                      spring_forces, straight_ratio)


def test_damped_spring_force_is_the_slides_formula():
    """k (L0 - L) - kd dL: pulls when stretched, pushes when compressed, damps along the spring."""
    assert damped_spring_force(1.5, 1.0, 10.0, 0.0, 0.0) == -5.0
    assert damped_spring_force(0.5, 1.0, 10.0, 0.0, 0.0) == 5.0
    assert damped_spring_force(1.0, 1.0, 10.0, 2.0, 0.25) == -0.5
    L = np.array([0.5, 1.0, 2.0])
    np.testing.assert_array_equal(damped_spring_force(L, 1.0, 3.0, 0.5, L), 3.0 * (1.0 - L) - 0.5 * L)


def loop(x, v, ij, L0, k, kd):
    """The slide's loop over springs, one spring at a time (the reference of the pass)."""
    F = np.zeros_like(x)
    for (i, j), L0s, ks, kds in zip(ij, L0, k, kd):
        d = x[i] - x[j]
        L = np.linalg.norm(d)
        u = d / L
        f = ks * (L0s - L) - kds * np.dot(v[i] - v[j], u)
        F[i] += f * u
        F[j] -= f * u
    return F


@pytest.mark.parametrize("d", [2, 3])
def test_the_pass_is_the_loop_over_springs_and_accumulates_repeated_particles(d):
    """spring_forces equals the per-spring loop; a particle in several springs gets all of them (F[i] += f drops
    repeats), and the total force is zero (Newton's third law)."""
    rng = np.random.default_rng(d)
    x, v = rng.normal(size=(5, d)), rng.normal(size=(5, d))
    ij = np.array([[0, 1], [0, 2], [0, 3], [1, 2], [3, 4], [4, 0]])
    L0, k, kd = rng.uniform(0.5, 1.5, 6), rng.uniform(1, 5, 6), rng.uniform(0, 1, 6)
    F = np.zeros((5, d))
    spring_forces(F, x, v, ij[:, 0], ij[:, 1], L0, k, kd)
    np.testing.assert_allclose(F, loop(x, v, ij, L0, k, kd), rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(F.sum(axis=0), 0.0, atol=1e-13)


def test_joint_factor_is_the_angle_over_its_sine_with_its_limit_at_straight():
    """kb (theta - theta0) / sin(theta): kb theta / sin theta off straight, kb at a straight joint (the limit)."""
    theta = np.array([0.3, 1.0, 2.5])
    np.testing.assert_allclose(joint_factor(np.cos(theta), 0.1, 2.0), 2.0 * (theta - 0.1) / np.sin(theta),
                               rtol=1e-12)
    assert joint_factor(1.0, 0.0, 2.0) == 2.0
    assert joint_factor(np.cos(1e-3), 0.0, 2.0) == pytest.approx(2.0 * 1e-3 / np.sin(1e-3), rel=1e-9)


def _ratio_exactly(c):
    """theta / sin(theta) at cos(theta) = c (a double), from its series in 1 - c summed in rationals to 1e-30."""
    x, a, total, n = 1 - Fraction(c), Fraction(1), Fraction(0), 0
    while a * x**n > Fraction(1, 10**30):  # a loop over the series' terms
        total += a * x**n
        a, n = a * (n + 1) / (2 * n + 3), n + 1
    return float(total)


def test_a_nearly_straight_joint_takes_its_series_to_the_last_bits():
    """Straight at rest and bent by less than 29 degrees: theta / sin(theta) to 2 ulp of the exact value, where
    acos(c) / sqrt(1 - c^2) loses up to 1e-11 (two small numbers divided); at 29 degrees both forms agree."""
    theta = np.array([1e-7, 1e-6, 1e-5, 1e-3, 0.01, 0.1, 0.3, 0.5])
    c = np.cos(theta)
    exact = np.array([_ratio_exactly(float(ci)) for ci in c])
    np.testing.assert_allclose(joint_factor(c, 0.0, 1.0), exact, rtol=4.5e-16, atol=0)
    assert np.max(np.abs(bent_ratio(c, 0.0) / exact - 1)) > 1e-12  # what the series spares
    edge = np.nextafter(1.0 - STRAIGHT_RANGE, 2.0)  # the last cosine of the series' range, and the first after it
    for ci in (edge, np.nextafter(edge, 0.0)):
        assert float(joint_factor(ci, 0.0, 1.0)) == pytest.approx(_ratio_exactly(ci), rel=1e-15)
    assert float(straight_ratio(0.0)) == 1.0


def test_a_bent_joint_swings_its_ends_towards_straight_with_no_net_force():
    """A right angle at (1, 0): the ends move across their segments to straighten it, forces summing to zero."""
    x = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    F = np.zeros_like(x)
    bending_forces(F, x, np.array([0]), np.array([1]), np.array([2]), np.array([1.0]), np.array([0.0]))
    np.testing.assert_allclose(F.sum(axis=0), 0.0, atol=1e-15)
    assert F[0, 1] < 0 and F[0, 0] == 0 and F[2, 0] > 0 and F[2, 1] == 0  # each end across its segment
    np.testing.assert_allclose(np.abs(F[[0, 2]]).max(), np.pi / 2)  # kb theta / |e| with theta = 90 degrees
