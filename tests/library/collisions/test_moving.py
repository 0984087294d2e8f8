"""The cylinder and moving bodies: signs of H, gradients, closest points, rigid motion and material velocity."""

import numpy as np
import pytest

from particles.collisions import Box, Cylinder, MovingSurface, Plane, RigidlyMoved, Sphere, rotation_matrix


def finite_difference_gradient(surface, x, h=1e-6):
    """Central differences of H along each axis, shape (n, d)."""
    return np.stack([(surface.H(x + h * e) - surface.H(x - h * e)) / (2 * h) for e in np.eye(x.shape[1])], axis=1)


# ---------------------------------------------------------------- the cylinder

BAR = Cylinder([0.0, 1.0, 0.5], [1.0, 1.0, 0.0], 0.3)


def test_cylinder_H_is_the_signed_distance_to_the_axis_minus_the_radius():
    """H < 0 inside, 0 on the surface, > 0 outside; the axis direction does not change H."""
    a = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    across = np.array([0.0, 0.0, 1.0])  # perpendicular to the axis
    p = BAR.point + 7.0 * a
    np.testing.assert_allclose(BAR.H([p, p + 0.3 * across, p + 1.3 * across, p - 0.1 * across]),
                               [-0.3, 0.0, 1.0, -0.2], atol=1e-15)
    assert BAR.H(p + 100 * a + 0.5 * across) == pytest.approx(0.2)  # no caps
    hollow = Cylinder([0.0, 1.0, 0.5], [-2.0, -2.0, 0.0], 0.3, container=True)
    assert hollow.H(p + 1.3 * across) == pytest.approx(-1.0)
    assert hollow.inside([p + 1.3 * across]).tolist() == [True]


def test_cylinder_gradient_is_the_finite_difference_and_unit():
    """grad H equals central differences of H, has unit length and is perpendicular to the axis."""
    rng = np.random.default_rng(0)
    x = rng.uniform(-2, 2, (50, 3))
    for body in (BAR, Cylinder([0.3, 0.0, 0.0], [0.2, -1.0, 3.0], 0.7, container=True)):
        g = body.gradient(x)
        np.testing.assert_allclose(g, finite_difference_gradient(body, x), atol=1e-7)
        np.testing.assert_allclose(np.linalg.norm(g, axis=1), 1.0)
        np.testing.assert_allclose(g @ body.axis, 0.0, atol=1e-14)


def test_cylinder_closest_point_is_on_the_surface_along_the_normal():
    """The closest point has H = 0 and lies at distance |H| along the normal; points on the axis get one too."""
    rng = np.random.default_rng(1)
    x = rng.uniform(-2, 2, (50, 3))
    p = BAR.closest_point(x)
    np.testing.assert_allclose(BAR.H(p), 0.0, atol=1e-14)
    np.testing.assert_allclose(x - p, BAR.H(x)[:, None] * BAR.normal(x), atol=1e-14)
    for on_axis in (BAR.point + 2.0 * BAR.axis, BAR.point):  # the first one is off by rounding, along the axis
        assert BAR.H(BAR.closest_point(on_axis)) == pytest.approx(0.0, abs=1e-15)
        assert np.linalg.norm(BAR.gradient(on_axis)) == pytest.approx(1.0)
        assert BAR.gradient(on_axis) @ BAR.axis == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("args, message", [
    (([0.0, 0.0], [1.0, 0.0, 0.0], 1.0), r"point must have shape \(3\)"),
    (([0.0, 0.0, 0.0], [0.0, 0.0, 0.0], 1.0), "axis must be a non-zero vector"),
    (([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], -1.0), "radius must be a positive finite number"),
])
def test_cylinder_refuses_bad_arguments(args, message):
    """Bad point, axis or radius raise ValueError naming the argument."""
    with pytest.raises(ValueError, match=message):
        Cylinder(*args)


# ---------------------------------------------------------------- rigid motion

def test_rotation_matrix_is_a_rotation_about_omega():
    """R is orthogonal with determinant 1, keeps the axis, and turns by |omega| t."""
    omega = np.array([0.3, -1.2, 0.5])
    R = rotation_matrix(omega, 0.7)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(R) == pytest.approx(1.0)
    np.testing.assert_allclose(R @ omega, omega, atol=1e-15)
    u = np.cross(omega, [1.0, 0.0, 0.0])
    angle = np.arccos(u @ R @ u / (u @ u))
    assert angle == pytest.approx(np.linalg.norm(omega) * 0.7)
    np.testing.assert_allclose(rotation_matrix(2.0, np.pi / 4) @ [1.0, 0.0], [0.0, 1.0], atol=1e-15)


def test_translating_sphere_is_the_sphere_at_its_new_centre():
    """A ball moving at v is, at time t, the sphere of centre c + v (t - t0); its velocity is v everywhere."""
    v = np.array([0.5, -1.0, 2.0])
    ball = MovingSurface(Sphere([0.0, 0.0, 1.0], 0.4), velocity=v, t0=1.0)
    x = np.random.default_rng(2).uniform(-2, 2, (30, 3))
    moved = Sphere(np.array([0.0, 0.0, 1.0]) + v * 1.5, 0.4)
    np.testing.assert_allclose(ball.at(2.5).H(x), moved.H(x), atol=1e-14)
    np.testing.assert_allclose(ball.at(2.5).gradient(x), moved.gradient(x), atol=1e-14)
    np.testing.assert_allclose(ball.at(2.5).closest_point(x), moved.closest_point(x), atol=1e-14)
    np.testing.assert_allclose(ball.velocity(x, 2.5), np.broadcast_to(v, x.shape))
    assert ball.at(1.0) is ball.surface  # not moved yet


def test_a_path_gives_the_translation_and_its_velocity():
    """A body on a path c(t): at(t) follows it and the velocity is c'(t) (given or by central differences)."""
    path = lambda t: np.array([np.sin(t), 0.0, 0.0])  # noqa: E731
    plate = Plane([0.0, 0.0, 0.0], [1.0, 0.0, 0.0])
    for body in (MovingSurface(plate, path=path),
                 MovingSurface(plate, path=path, path_velocity=lambda t: np.array([np.cos(t), 0.0, 0.0]))):
        assert body.at(1.0).H([2.0, 0.0, 0.0]) == pytest.approx(2.0 - np.sin(1.0))
        np.testing.assert_allclose(body.velocity([[3.0, 1.0, 1.0]], 1.0), [[np.cos(1.0), 0.0, 0.0]], atol=1e-8)


def test_rotating_cylinder_velocity_is_omega_cross_r():
    """A roller turning about its own axis: its shape is unchanged, and its material moves at omega x r."""
    roller = Cylinder([0.0, 0.5, 0.2], [1.0, 0.0, 0.0], 0.1)
    omega = np.array([4.0, 0.0, 0.0])
    body = MovingSurface(roller, omega=omega)
    x = roller.closest_point(np.random.default_rng(3).uniform(-1, 1, (20, 3)))
    np.testing.assert_allclose(body.at(0.8).H(x), 0.0, atol=1e-14)  # the surface stays in place
    v = body.velocity(x, 0.8)
    np.testing.assert_allclose(v, np.cross(omega, x - roller.point))
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 4.0 * 0.1)  # |omega| R at the surface
    np.testing.assert_allclose(np.einsum("ij,ij->i", v, roller.normal(x)), 0.0, atol=1e-14)  # tangent


def test_material_points_ride_on_the_moving_body():
    """A point of the body keeps its H along the motion, and the velocity is the motion's time derivative."""
    box = Box([-0.2, -0.1, -0.3], [0.4, 0.1, 0.3])
    body = MovingSurface(box, velocity=[0.1, 0.0, -0.2], omega=[0.5, 1.0, -2.0], pivot=[0.1, 0.2, 0.0])
    y = np.random.default_rng(4).uniform(-0.5, 0.5, (25, 3))  # points at the placement

    def where(t):  # x(t) = p + c(t) + R(t) (y - p)
        return body.pivot + body.displacement(t) + (y - body.pivot) @ body.rotation(t).T

    t, dt = 0.9, 1e-6
    np.testing.assert_allclose(body.at(t).H(where(t)), box.H(y), atol=1e-13)
    np.testing.assert_allclose(body.velocity(where(t), t), (where(t + dt) - where(t - dt)) / (2 * dt), atol=1e-7)
    moved = body.at(t)
    assert isinstance(moved, RigidlyMoved)
    np.testing.assert_allclose(moved.gradient(where(t)), finite_difference_gradient(moved, where(t)), atol=1e-6)
    np.testing.assert_allclose(moved.H(moved.closest_point(where(t))), 0.0, atol=1e-13)


def test_2d_rotation_uses_a_scalar_omega():
    """In 2D omega is a number and the velocity is omega (-r_y, r_x)."""
    disk = MovingSurface(Sphere([1.0, 0.0], 0.5), omega=3.0)
    np.testing.assert_allclose(disk.velocity([[1.0, 0.5]], 0.0), [[-1.5, 0.0]])
    np.testing.assert_allclose(disk.at(0.3).H([[2.0, 0.0]]), [0.5])


@pytest.mark.parametrize("kwargs, message", [
    (dict(velocity=[1.0, 0.0, 0.0], path=lambda t: np.zeros(3)), "velocity .* or path .*, not both"),
    (dict(velocity=[1.0, 0.0]), r"velocity must have shape \(3\)"),
    (dict(omega=2.0), r"omega must have shape \(3\)"),
    (dict(path=3.0), "path must be a function of t"),
    (dict(path_velocity=lambda t: np.zeros(3)), "path_velocity must be a function of t, given together with path"),
])
def test_moving_surface_refuses_bad_arguments(kwargs, message):
    """Conflicting or misshapen motions raise ValueError naming the argument."""
    with pytest.raises(ValueError, match=message):
        MovingSurface(Sphere([0.0, 0.0, 0.0], 1.0), **kwargs)
    with pytest.raises(ValueError, match="surface must be a Surface"):
        MovingSurface("sphere")


def test_velocity_refuses_points_of_the_wrong_dimension():
    """x of the wrong width is refused with the expected shape."""
    body = MovingSurface(Sphere([0.0, 0.0, 0.0], 1.0), velocity=[1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"x must have shape \(n, 3\)"):
        body.velocity([[0.0, 0.0]], 0.0)
