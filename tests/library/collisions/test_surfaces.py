"""Implicit surfaces: signs, gradients, closest points, and their combinations."""

import numpy as np
import pytest

from particles.collisions import Box, Complement, Intersection, Plane, Sphere, Union

SURFACES_3D = {
    "plane": Plane([0.0, 0.0, 0.5], [1.0, 2.0, 3.0]),
    "sphere": Sphere([0.1, -0.2, 0.3], 0.8),
    "container sphere": Sphere([0.1, -0.2, 0.3], 0.8, container=True),
    "box": Box([-1.0, -0.5, -0.25], [1.0, 0.5, 0.75]),
    "container box": Box([-1.0, -0.5, -0.25], [1.0, 0.5, 0.75], container=True),
    "union": Sphere([0.0, 0.0, 0.0], 0.7) | Box([0.3, -0.3, -0.3], [1.2, 0.3, 0.3]),
    "intersection": Sphere([0.0, 0.0, 0.0], 1.0) & Plane([0.2, 0.0, 0.0], [-1.0, 0.0, 0.0]),
    "complement": ~Box([-0.5, -0.5, -0.5], [0.5, 0.5, 0.5]),
}
SURFACES_2D = {
    "plane": Plane([0.0, 0.0], [0.0, 1.0]),
    "sphere": Sphere([0.5, 0.0], 1.0),
    "container box": Box([-1.0, -1.0], [1.0, 2.0], container=True),
    "union": Sphere([0.0, 0.0], 0.5) | Sphere([0.6, 0.0], 0.4),
}
ALL = [(f"3d {k}", s) for k, s in SURFACES_3D.items()] + [(f"2d {k}", s) for k, s in SURFACES_2D.items()]
PRIMITIVES = [(k, s) for k, s in ALL if not any(w in k for w in ("union", "intersection", "complement"))]


def random_points(surface, n=400, seed=0):
    return np.random.default_rng(seed).uniform(-1.5, 1.5, (n, surface.d))


@pytest.mark.parametrize(
    "surface, inside, outside, on",
    [
        (Plane([0, 0, 0], [0, 0, 1]), [0, 0, -1], [3, 4, 0.1], [5, -2, 0]),
        (Sphere([1, 1], 2.0), [1.5, 1.0], [4.0, 1.0], [3.0, 1.0]),
        (Sphere([1, 1], 2.0, container=True), [4.0, 1.0], [1.5, 1.0], [1.0, 3.0]),
        (Box([0, 0, 0], [1, 2, 3]), [0.5, 1.0, 2.9], [0.5, 1.0, 3.1], [1.0, 1.0, 1.0]),
        (Box([0, 0], [1, 2], container=True), [1.5, 1.0], [0.5, 1.0], [0.0, 0.5]),
        (Sphere([0, 0], 1.0) | Sphere([2, 0], 1.0), [2.5, 0.0], [1.0, 0.5], [3.0, 0.0]),
        (Sphere([0, 0], 1.0) & Sphere([1, 0], 1.0), [0.5, 0.0], [-0.5, 0.0], [0.0, 0.0]),
        (~Sphere([0, 0], 1.0), [0.0, 2.0], [0.0, 0.5], [1.0, 0.0]),
    ],
)
def test_sign_of_H(surface, inside, outside, on):
    """H < 0 inside the solid, > 0 in free space, 0 on the surface."""
    assert surface.H(inside) < 0 and surface.inside(inside)
    assert surface.H(outside) > 0 and not surface.inside(outside)
    assert surface.H(on) == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("name, surface", ALL)
def test_gradient_matches_finite_differences(name, surface):
    """grad H agrees with central differences wherever H is smooth (kinks are rare)."""
    x = random_points(surface)
    grad = surface.gradient(x)
    delta = 1e-6
    fd, kink = np.empty_like(x), np.zeros(len(x), dtype=bool)
    H0 = surface.H(x)
    for a in range(surface.d):
        e = np.zeros(surface.d)
        e[a] = delta
        Hp, Hm = surface.H(x + e), surface.H(x - e)
        fd[:, a] = (Hp - Hm) / (2 * delta)
        kink |= np.abs(Hp + Hm - 2 * H0) > 1e-9  # a kink within delta (curvature alone gives ~1e-12)
    assert kink.mean() < 0.02
    np.testing.assert_allclose(grad[~kink], fd[~kink], atol=1e-6)
    normal = surface.normal(x)
    np.testing.assert_allclose(np.linalg.norm(normal, axis=1), 1.0)


@pytest.mark.parametrize("name, surface", PRIMITIVES)
def test_closest_point_of_primitives_is_on_surface_and_nearest(name, surface):
    """The closest point has H = 0 and lies at distance |H(x)| along the normal (exact signed distance)."""
    x = random_points(surface, seed=1)
    p = surface.closest_point(x)
    np.testing.assert_allclose(surface.H(p), 0.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(p - x, axis=1), np.abs(surface.H(x)), atol=1e-12)
    away = np.abs(surface.H(x)) > 1e-3  # x - p is along the normal at x
    np.testing.assert_allclose((x - p)[away], surface.H(x)[away, None] * surface.normal(x)[away], atol=1e-12)


def test_closest_point_on_sphere_against_brute_force():
    """Against a dense sampling of the sphere, no surface point is closer than the one returned."""
    rng = np.random.default_rng(2)
    ball = Sphere([0.2, 0.0, -0.1], 0.9)
    u = rng.normal(size=(20000, 3))
    samples = ball.center + ball.radius * u / np.linalg.norm(u, axis=1)[:, None]
    x = rng.uniform(-2, 2, (50, 3))
    brute = np.min(np.linalg.norm(x[:, None] - samples[None], axis=2), axis=1)
    ours = np.linalg.norm(ball.closest_point(x) - x, axis=1)
    assert np.all(ours <= brute + 1e-12)
    assert np.all(brute - ours < 0.03)  # the sampling is dense enough to come close


@pytest.mark.parametrize("name, surface", [(k, s) for k, s in ALL if k not in dict(PRIMITIVES)])
def test_closest_point_of_combinations(name, surface):
    """Combinations: the closest point is on the combined surface; outside a union it is the nearest."""
    x = random_points(surface, seed=3)
    p = surface.closest_point(x)
    np.testing.assert_allclose(surface.H(p), 0.0, atol=1e-9)
    if isinstance(surface, Union):
        out = surface.H(x) > 0  # outside, min of signed distances is the exact distance
        np.testing.assert_allclose(np.linalg.norm(p - x, axis=1)[out], surface.H(x)[out], atol=1e-12)


def test_operators_build_combinations():
    """a | b, a & b and ~a build Union, Intersection and Complement; unions flatten."""
    a, b, c = Sphere([0, 0], 1.0), Sphere([1, 0], 1.0), Plane([0, 0], [0, 1])
    assert isinstance(a | b, Union) and isinstance(a & b, Intersection) and isinstance(~a, Complement)
    assert len(((a | b) | c).parts) == 3
    x = random_points(a)
    np.testing.assert_allclose((~a).H(x), Sphere([0, 0], 1.0, container=True).H(x))
    np.testing.assert_allclose((~a).gradient(x), Sphere([0, 0], 1.0, container=True).gradient(x))
