"""Resting contact of balls (particles.collisions.resting): chatter of the naive fix, rest, stacks, collisions."""

import numpy as np
import pytest

from particles import ParticleSystem
from particles.collisions import BallContacts, Plane
from particles.forces import Gravity

G, H, R = 9.81, 0.01, 0.05
FLOOR = Plane([0.0, 0.0], [0.0, 1.0])


def stack(k, rest_speed, iterations, T=1.0, restitution=0.5):
    """k balls of 1 kg stacked on the floor at rest, run for T; returns times, states and the contact fix."""
    x0 = np.column_stack([np.zeros(k), R + 2 * R * np.arange(k)])
    ps = ParticleSystem(x0, m=1.0, forces=[Gravity([0.0, -G])])
    balls = BallContacts(R, ps.m, FLOOR, restitution=restitution, rest_speed=rest_speed, iterations=iterations)
    t, X = ps.run(T, H, method=balls.stepper("symplectic_euler"))
    return t, X, balls


def test_a_resting_ball_stays_put_and_the_floor_carries_its_weight():
    """With a resting threshold the ball never moves (to round-off) and the floor's impulse per step is m g h;
    with naive restitution it chatters: off the floor on most steps, the floor's force swinging around m g."""
    t, X, balls = stack(1, rest_speed=2 * G * H, iterations=1)
    assert np.abs(X[:, 0, 0, 1] - R).max() == 0.0 and np.abs(X[:, 0, 1]).max() < 1e-14
    np.testing.assert_allclose([c.surface[0] / H for c in balls.history], G, rtol=1e-12)
    assert all(c.bounces == 0 for c in balls.history)
    t, X, balls = stack(1, rest_speed=0.0, iterations=1)
    force = np.array([c.surface[0] for c in balls.history]) / H
    assert np.mean(force == 0) > 0.5 and force.max() > 2 * G
    assert np.abs(X[:, 0, 1, 1]).max() > 0.5 * G * H


def test_a_stack_comes_to_rest_with_enough_sweeps():
    """Four balls on each other: with the threshold and 16 sweeps they end at rest, the floor carrying 4 m g;
    the naive fix keeps them hopping (some step without floor contact, speeds of order g h)."""
    t, X, balls = stack(4, rest_speed=2 * G * H, iterations=16)
    late = t > 0.5
    assert np.abs(X[late, :, 1]).max() < 1e-12
    np.testing.assert_allclose([c.surface.sum() / H for c in balls.history[-20:]], 4 * G, rtol=1e-9)
    gaps = np.diff(X[-1, :, 0, 1]) - 2 * R
    assert np.abs(gaps).max() < 1e-3 * R
    t, X, balls = stack(4, rest_speed=0.0, iterations=16)
    assert np.abs(X[t > 0.5, :, 1]).max() > 0.5 * G * H
    assert any(c.surface.sum() == 0 for c in balls.history[-50:])


def test_a_collision_bounces_with_the_restitution_and_keeps_the_momentum():
    """Two balls closing at 2 m/s leave each other at eps times that, momentum kept; a ball that hits the
    floor fast leaves it at eps times its speed at the end of the step."""
    balls = BallContacts(R, [1.0, 3.0], restitution=0.6, rest_speed=0.1)
    x = np.array([[0.0, 0.0], [2 * R - 0.01, 0.0]])
    v = np.array([[1.0, 0.0], [-1.0, 0.0]])
    x1, v1, done = balls.resolve(x, v, h=0.01)
    assert done.pairs == 1 and done.bounces == 1
    np.testing.assert_allclose(v1[1, 0] - v1[0, 0], 0.6 * 2.0)
    np.testing.assert_allclose([1.0, 3.0] @ v1[:, 0], [1.0, 3.0] @ v[:, 0])
    floor = BallContacts(R, 1.0, FLOOR, restitution=0.5, rest_speed=0.1)
    _, v2, done = floor.resolve([[0.0, R - 0.02]], [[0.3, -4.0]], h=0.01)
    np.testing.assert_allclose(v2, [[0.3, 2.0]])
    assert done.surface[0] == pytest.approx(6.0)


def test_only_what_would_overlap_at_the_end_of_the_step_is_pushed():
    """A pair that ends the step 1 cm apart needs nothing, however fast it closes; one that ends 1 cm into each
    other, closing slowly (a resting contact), leaves the step separating at 1 cm / h minus its closing speed,
    so that moving by h times the change ends it exactly touching."""
    balls = BallContacts(R, 1.0, rest_speed=0.1)
    apart = np.array([[0.0, 0.0], [2 * R + 0.01, 0.0]])
    v = np.array([[1.0, 0.0], [-1.0, 0.0]])
    np.testing.assert_array_equal(balls.resolve(apart, v, h=0.01)[1], v)
    into = np.array([[0.0, 0.0], [2 * R - 0.01, 0.0]])
    x1, v1, done = balls.resolve(into, [[0.025, 0.0], [-0.025, 0.0]], h=0.01)
    assert done.bounces == 0
    assert v1[1, 0] - v1[0, 0] == pytest.approx(0.01 / 0.01 - 0.05)
    assert x1[1, 0] - x1[0, 0] == pytest.approx(2 * R)


def test_bad_input_is_refused_by_name():
    """A non-positive radius, a surface that is not one, a restitution outside [0, 1], a negative threshold,
    zero sweeps and a bad step are refused with messages that name them."""
    with pytest.raises(ValueError, match="radius"):
        BallContacts(0.0, 1.0)
    with pytest.raises(ValueError, match="surface must be"):
        BallContacts(R, 1.0, surface="floor")
    with pytest.raises(ValueError, match="restitution"):
        BallContacts(R, 1.0, restitution=1.5)
    with pytest.raises(ValueError, match="rest_speed"):
        BallContacts(R, 1.0, rest_speed=-1.0)
    with pytest.raises(ValueError, match="iterations"):
        BallContacts(R, 1.0, iterations=0)
    with pytest.raises(ValueError, match="h must be"):
        BallContacts(R, 1.0).resolve([[0.0, 0.0]], [[0.0, 0.0]], h=0.0)
