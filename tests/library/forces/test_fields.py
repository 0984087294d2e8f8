"""The forces on each particle alone (particles.forces.fields): formulas, potentials, argument checks."""

import numpy as np
import pytest

from particles.forces import Attractor, Damping, Field, Gravity, Vortex, Wind

from .helpers import numerical_gradient


def test_gravity_is_mass_proportional_and_can_point_up():
    """Gravity is m g for each particle, and an upward g lifts (smoke)."""
    x = np.zeros((3, 2))
    m = np.array([1.0, 2.0, 0.5])
    np.testing.assert_allclose(Gravity([0, -9.81])(x, m=m), np.outer(m, [0, -9.81]))
    assert np.all(Gravity([0, 0.3])(x, m=m)[:, 1] > 0)  # smoke rises


def test_gravity_dimension_mismatch_is_reported():
    """A 3D g on 2D particles is refused, naming both dimensions."""
    with pytest.raises(ValueError, match="g has 3 components but the particles live in 2 dimensions"):
        Gravity([0, 0, -9.81])(np.zeros((1, 2)))


def test_damping_opposes_velocity():
    """Damping is -d v, and a negative d is refused by name."""
    v = np.array([[1.0, -2.0], [0.0, 3.0]])
    np.testing.assert_allclose(Damping(0.4)(np.zeros((2, 2)), v), -0.4 * v)
    with pytest.raises(ValueError, match="d must be a finite number >= 0"):
        Damping(-1.0)


def test_wind_constant_and_gusting():
    """Calm wind is uniform; gusts vary with time and along the wind."""
    x = np.array([[0.0, 0.0], [0.25, 0.0]])
    calm = Wind([2.0, 0.0])
    np.testing.assert_allclose(calm(x, t=3.0), [[2.0, 0.0]] * 2)
    gusty = Wind([2.0, 0.0], gust=0.5, period=1.0, wavelength=1.0)
    F0, F1 = gusty(x, t=0.0), gusty(x, t=0.25)
    np.testing.assert_allclose(F0[:, 1], 0.0)
    np.testing.assert_allclose(F0[:, 0], 2.0 * (1 + 0.5 * np.sin(-2 * np.pi * x[:, 0])))
    assert not np.allclose(F0, F1)
    assert F1[1, 0] == pytest.approx(2.0)  # gust front: phase 0 at x = 0.25, t = 0.25


def test_attractor_formula_repulser_and_potential():
    """The softened attractor's force follows its formula, a negative strength repels, and F = -grad U."""
    x = np.array([[1.0, 0.0], [0.0, -2.0], [3.0, 4.0]])
    a = Attractor([0.0, 0.0], strength=2.0, softening=0.5)
    F = a(x)
    r = -x
    r2 = np.sum(r**2, axis=1) + 0.25
    np.testing.assert_allclose(F, 2.0 * r / (r2**1.5)[:, None])
    np.testing.assert_allclose(Attractor([0, 0], -2.0, softening=0.5)(x), -F)  # negative repels
    grad = numerical_gradient(lambda y: a.potential_energy(y, None), x)
    np.testing.assert_allclose(F, -grad, rtol=1e-6, atol=1e-9)


def test_attractor_moving_center():
    """A centre given as a function of time moves with t."""
    a = Attractor(lambda t: [t, 0.0], strength=1.0)
    x = np.array([[1.0, 0.0]])
    assert a(x, t=0.0)[0, 0] < 0 < a(x, t=2.0)[0, 0]


def test_vortex_2d_is_tangential_counterclockwise():
    """A 2D vortex pushes tangentially, counterclockwise, with the core-softened magnitude."""
    rng = np.random.default_rng(1)
    x = rng.normal(size=(50, 2))
    F = Vortex([0.0, 0.0], strength=1.5, core=0.2)(x)
    np.testing.assert_allclose(np.sum(F * x, axis=1), 0.0, atol=1e-12)  # no radial part
    assert np.all(x[:, 0] * F[:, 1] - x[:, 1] * F[:, 0] > 0)  # positive torque about z
    r = np.linalg.norm(x, axis=1)
    np.testing.assert_allclose(np.linalg.norm(F, axis=1), 1.5 * r / (r**2 + 0.04))


def test_vortex_3d_about_axis():
    """In 3D the swirl is perpendicular to the axis and to the radius."""
    rng = np.random.default_rng(2)
    axis = np.array([1.0, 1.0, 0.0])
    x = rng.normal(size=(40, 3))
    c = np.array([0.5, 0.0, 1.0])
    F = Vortex(c, strength=2.0, axis=axis)(x)
    np.testing.assert_allclose(F @ axis, 0.0, atol=1e-12)
    np.testing.assert_allclose(np.sum(F * (x - c), axis=1), 0.0, atol=1e-12)
    with pytest.raises(ValueError, match="axis must be a non-zero vector"):
        Vortex(c, 1.0, axis=[0, 0, 0])


def test_field_calls_user_function_and_checks_shape():
    """A Field calls the user's fn(x, t), and a wrong shape or a non-function is refused by name."""
    fn = Field(lambda x, t: np.sin(t) * x)
    x = np.array([[1.0, 2.0]])
    np.testing.assert_allclose(fn(x, t=0.5), np.sin(0.5) * x)
    with pytest.raises(ValueError, match=r"fn\(x, t\) must return shape \(1, 2\), got \(2,\)"):
        Field(lambda x, t: np.zeros(2))(x)
    with pytest.raises(ValueError, match="fn must be a function"):
        Field(3.0)


def test_force_call_checks_masses():
    """force(x, m=...) refuses masses <= 0 and masses of the wrong length, naming m."""
    x = np.zeros((2, 2))
    for m in (-1.0, 0.0, [1.0, -2.0]):
        with pytest.raises(ValueError, match="m must be positive"):
            Gravity([0, -9.81])(x, m=m)
    with pytest.raises(ValueError, match=r"m must be a number or have shape \(2,\), got shape \(3,\)"):
        Gravity([0, -9.81])(x, m=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="t must be a finite real number"):
        Gravity([0, -9.81])(x, t=np.nan)
    np.testing.assert_allclose(Gravity([0, -9.81])(x, m=[1.0, 2.0]), [[0, -9.81], [0, -19.62]])
