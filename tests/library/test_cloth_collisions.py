"""Cloth against implicit surfaces: nothing left inside, friction, stability at the cloth's time step."""

import numpy as np
import pytest

from particles.collisions import Collider, Plane, Sphere
from particles.constraints import ProvotConstraint
from particles.implicit import Prefactored
from particles.integrators import symplectic_euler
from particles.massspring import cloth


def sheet(n=12, z=0.3, **options):
    return cloth(n, n, width=0.8, height=0.8, plane="horizontal", origin=(-0.4, -0.4, z), pins=None,
                 scaling="physical", stretch_modulus=200.0, **options)


def constrained_step(c, collider):
    """Symplectic Euler, then Provot, then collisions (last, so that nothing ends inside)."""
    provot = ProvotConstraint.from_system(c)
    return collider.stepper(provot.stepper(symplectic_euler), m=c.m, pinned=c.pinned)


def test_cloth_drapes_over_sphere_never_inside():
    """At its stable step, every step of a cloth falling on a sphere ends with no particle inside."""
    c = sheet(damping=0.5)
    ball = Sphere([0.0, 0.0, 0.0], 0.25)
    step = constrained_step(c, Collider(ball, restitution=0.0, friction=0.5, method="project"))
    t, X = c.run(2.0, 0.9 * c.max_stable_step(), method=step)
    depth = np.array([ball.H(Xk[:, 0]).min() for Xk in X])
    assert depth.min() >= -1e-12
    assert np.abs(ball.H(c.X[:, 0])).min() < 1e-3  # it touches the sphere
    corners = c.X[[c.points[p] for p in ("top left", "top right", "bottom left", "bottom right")], 0, 2]
    assert np.all(corners < 0.1)  # and hangs around it
    assert c.kinetic_energy() < 1e-2 * c.m.sum() * 9.81 * 0.3  # nearly at rest: stable, not jittering


def test_cloth_on_floor_settles_flat_at_rest():
    """A damped cloth dropped on a floor never goes below it and comes to rest flat on it."""
    c = sheet(damping=0.5)
    floor = Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])
    step = constrained_step(c, Collider(floor, restitution=0.0, friction=0.3, method="project"))
    t, X = c.run(1.5, 0.9 * c.max_stable_step(), method=step)
    assert min(floor.H(Xk[:, 0]).min() for Xk in X) >= -1e-12
    np.testing.assert_allclose(c.X[:, 0, 2], 0.0, atol=1e-6)
    assert np.abs(c.X[:, 1]).max() < 1e-3


@pytest.mark.parametrize("mu, slides", [(0.0, True), (0.8, False)])
def test_friction_on_an_inclined_plane(mu, slides):
    """Coulomb friction: a cloth lying on a 20 degree slope slides when mu < tan 20, sticks when mu > tan 20."""
    angle = np.radians(20.0)
    normal = np.array([0.0, -np.sin(angle), np.cos(angle)])  # the slope rises towards +y
    up_slope = np.array([0.0, np.cos(angle), np.sin(angle)])
    slope = Plane([0.0, 0.0, 0.0], normal)
    c = sheet(z=0.0, damping=0.0)
    X = c.state()
    X[:, 0] = np.outer(X[:, 0, 0], [1.0, 0.0, 0.0]) + np.outer(X[:, 0, 1], up_slope)  # lay it on the slope, relaxed
    c.X = np.asfortranarray(X)
    step = constrained_step(c, Collider(slope, restitution=0.0, friction=mu, method="project"))
    start = c.X[:, 0].mean(axis=0)
    c.run(0.5, 0.9 * c.max_stable_step(), method=step)
    down = np.array([0.0, -np.cos(angle), -np.sin(angle)])  # down the slope
    travel = (c.X[:, 0].mean(axis=0) - start) @ down
    if slides:
        assert travel == pytest.approx(0.5 * 9.81 * np.sin(angle) * 0.5**2, rel=0.02)
    else:
        assert abs(travel) < 0.01  # the projection's creep, h g sin(20) per second of contact, and no more


def test_pinned_particles_are_left_alone():
    """A pinned corner inside the solid stays where it is; the free particles are pushed out."""
    c = cloth(6, 6, width=0.5, height=0.5, plane="horizontal", origin=(-0.25, -0.25, 0.0), pins="top left")
    ball = Sphere([-0.25, -0.25, 0.0], 0.2)
    collider = Collider(ball, restitution=0.0, method="project")
    X_new, contacts = collider.collide(c.X, c.X, 0.0, 0.01, m=c.m, pinned=c.pinned)
    np.testing.assert_array_equal(X_new[c.pinned], c.X[c.pinned])
    free = np.setdiff1d(np.arange(c.n), c.pinned)
    assert ball.H(X_new[free, 0]).min() >= -1e-12
    assert len(contacts) > 0 and c.pinned[0] not in contacts.index


def test_collisions_with_the_prefactored_solver_at_large_steps():
    """h = 1/60 s with Liu et al.'s solver: stable, and still nothing inside the sphere."""
    c = sheet(n=10, damping=0.5)
    ball = Sphere([0.0, 0.0, 0.0], 0.25)
    collider = Collider(ball, restitution=0.0, friction=0.5, method="project")
    step = collider.stepper(Prefactored(c, 1 / 60), m=c.m, pinned=c.pinned)
    t, X = c.run(2.0, 1 / 60, method=step)
    assert np.all(np.isfinite(X))
    assert min(ball.H(Xk[:, 0]).min() for Xk in X) >= -1e-12
    assert c.max_strain() < 0.3
