"""Paths within a step against a surface: exact crossings of segments, the first entry, Hermite paths."""

import numpy as np
import pytest

from particles.collisions import Box, Plane, Sphere, first_crossing, hermite

g = 9.81


def test_crossing_of_segments_is_exact():
    """Segment against plane and sphere: the entry fraction matches the analytic intersection."""
    plane = Plane([0, 0, 0], [0, 0, 1])
    x0 = np.array([[0, 0, 3.0], [1, 1, 1.0], [0, 0, -1.0]])
    x1 = np.array([[0, 0, -1.0], [2, 1, 0.5], [0, 0, -2.0]])
    np.testing.assert_allclose(plane.crossing(x0, x1), [0.75, 1.0, 0.0], atol=1e-12)
    ball = Sphere([0, 0, 0], 1.0)
    s = ball.crossing([[-3.0, 0.5, 0.0]], [[3.0, 0.5, 0.0]])
    assert s[0] * 6.0 - 3.0 == pytest.approx(-np.sqrt(0.75), abs=1e-12)


def test_first_crossing_finds_the_first_of_two_entries():
    """A path that enters, leaves and re-enters a thin slab gets its first entry, not a later one."""
    slab = Box([0.2, -1.0], [0.3, 1.0])
    x0, x1 = np.array([[0.0, 0.0]]), np.array([[1.0, 0.0]])
    s, s_in = first_crossing(slab, lambda k, s: x0[k] + s[:, None] * (x1[k] - x0[k]), 1, samples=16)
    assert s[0] == pytest.approx(0.2, abs=1e-12) and s_in[0] >= s[0]


def test_hermite_reproduces_constant_acceleration():
    """The cubic Hermite path of a ballistic step is the exact parabola, positions and velocities."""
    x0, v0, a, h = np.array([[0.0, 2.0]]), np.array([[1.0, 3.0]]), np.array([0.0, -g]), 0.1
    x1, v1 = x0 + v0 * h + 0.5 * a * h**2, v0 + a * h
    s = np.array([0.37])
    x, v = hermite(x0, v0, x1, v1, h, s)
    tau = 0.37 * h
    np.testing.assert_allclose(x, x0 + v0 * tau + 0.5 * a * tau**2, atol=1e-15)
    np.testing.assert_allclose(v, v0 + a * tau, atol=1e-14)
