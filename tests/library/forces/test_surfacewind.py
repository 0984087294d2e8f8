"""Provot's wind on a surface (particles.forces.surfacewind): the force on a plate, its invariances, its checks."""

import numpy as np
import pytest

from particles.forces import SurfaceWind, Wind


def grid_sheet(n, side=1.0):
    """An n x n grid of a square sheet in the plane z = 0 and its 2 (n - 1)^2 triangles."""
    s = np.linspace(0.0, side, n)
    X, Y = np.meshgrid(s, s)
    x = np.stack([X.ravel(), Y.ravel(), np.zeros(n * n)], axis=1)
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    faces = np.concatenate([np.stack([a, b, d], axis=1), np.stack([a, d, c], axis=1)])
    return x, faces


def test_a_plate_facing_the_wind_feels_c_times_area_times_speed():
    """A flat plate across the wind feels C A |u| along its normal; along the wind's direction at an angle
    theta to the normal it feels C A |u| cos(theta) along the normal, and nothing edge-on."""
    x, faces = grid_sheet(5, side=2.0)                       # area 4 m^2
    C = 0.7
    for theta in (0.0, 0.4, 1.1, np.pi / 2):
        u = 3.0 * np.array([np.sin(theta), 0.0, np.cos(theta)])
        total = SurfaceWind(faces, u, C)(x).sum(axis=0)
        np.testing.assert_allclose(total, [0.0, 0.0, C * 4.0 * 3.0 * np.cos(theta)], atol=1e-12)


def test_the_total_force_does_not_depend_on_the_mesh():
    """The same sheet meshed with 2 or 128 triangles, tilted and in a skew wind, feels the same total force
    (the coefficient is per unit area), and each vertex gets a third of each of its triangles' share."""
    rotation = np.linalg.qr(np.random.default_rng(3).normal(size=(3, 3)))[0]
    u = np.array([0.3, -1.2, 2.0])
    totals = []
    for n in (2, 9):
        x, faces = grid_sheet(n)
        totals.append(SurfaceWind(faces, u, 1.3)(x @ rotation.T).sum(axis=0))
    np.testing.assert_allclose(totals[0], totals[1], rtol=1e-12)
    x, faces = grid_sheet(2)
    F = SurfaceWind(faces, [0.0, 0.0, 1.0], 1.0)(x)
    np.testing.assert_allclose(F[:, 2], [1 / 3, 1 / 6, 1 / 6, 1 / 3])   # corners 0 and 3 touch both triangles


def test_only_the_relative_velocity_counts():
    """A sheet moving with the wind feels nothing; one moving against still air feels the opposite of the
    wind's force on it at rest; motion along the sheet changes nothing."""
    x, faces = grid_sheet(4)
    u = np.array([0.5, 0.2, 1.5])
    wind = SurfaceWind(faces, u, 2.0)
    np.testing.assert_allclose(wind(x, np.tile(u, (len(x), 1))), 0.0, atol=1e-15)
    still = SurfaceWind(faces, [0.0, 0.0, 0.0], 2.0)
    np.testing.assert_allclose(still(x, np.tile(u, (len(x), 1))), -wind(x), atol=1e-15)
    sliding = np.tile([4.0, -3.0, 0.0], (len(x), 1))
    np.testing.assert_allclose(wind(x, sliding), wind(x), atol=1e-15)


def test_orientation_and_degenerate_triangles():
    """Flipping every triangle gives the same force; a triangle of zero area feels nothing (and no NaN)."""
    x, faces = grid_sheet(3)
    u = [1.0, 2.0, 3.0]
    np.testing.assert_array_equal(SurfaceWind(faces[:, ::-1], u, 1.0)(x), SurfaceWind(faces, u, 1.0)(x))
    line = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    np.testing.assert_array_equal(SurfaceWind([[0, 1, 2]], u, 1.0)(line), 0.0)


def test_a_sail_held_along_two_edges_billows_downwind():
    """A vertical sheet held along its left and right edges, in a wind along its normal, relaxes into a
    bulge downwind, deepest midway between the edges; curved, it catches less than the flat sheet's C A |u|."""
    from particles.collisions import TriangleMesh
    from particles.implicit import relax
    from particles.massspring import cloth

    n = 7
    idx = np.arange(n * n).reshape(n, n)
    sail = cloth(n, n, pins=list(idx[:, 0]) + list(idx[:, -1]), scaling="physical", stretch_modulus=20.0)
    wind = SurfaceWind(TriangleMesh.grid(n, n).faces, [0.0, 10.0, 0.0], 0.2)
    flat = wind(sail.X[:, 0]).sum(axis=0)
    np.testing.assert_allclose(flat, [0.0, 0.2 * 1.0 * 10.0, 0.0], atol=1e-12)
    sail.forces.append(wind)
    relax(sail, h=0.2, method="implicit")
    y = sail.X[:, 0, 1].reshape(n, n)
    assert y[n // 2, n // 2] > 0.05                              # the middle went downwind
    assert np.all(y[1:-1, n // 2] > y[1:-1, 1]) and np.all(y[1:-1, n // 2] > y[1:-1, -2])   # deepest midway
    assert 0.5 * flat[1] < wind(sail.X[:, 0]).sum(axis=0)[1] < flat[1]


def test_per_mass_wind_is_not_surface_wind():
    """The library's Wind is a field: the same push on a particle whatever the surface's orientation,
    while SurfaceWind vanishes edge-on."""
    x, faces = grid_sheet(3)
    edge_on = [2.0, 0.0, 0.0]
    assert np.abs(SurfaceWind(faces, edge_on, 1.0)(x)).max() < 1e-15
    np.testing.assert_array_equal(Wind(edge_on)(x), np.tile(edge_on, (len(x), 1)))


def test_bad_input_is_refused_by_name():
    """Faces of the wrong shape or pointing past the particles, a wind of the wrong size, a negative
    coefficient and 2D positions are refused with messages that name them."""
    x, faces = grid_sheet(3)
    with pytest.raises(ValueError, match="faces must be an integer array of shape"):
        SurfaceWind([[0, 1]], [0, 0, 1], 1.0)
    with pytest.raises(ValueError, match="velocity"):
        SurfaceWind(faces, [0, 1], 1.0)
    with pytest.raises(ValueError, match="coefficient"):
        SurfaceWind(faces, [0, 0, 1], -1.0)
    with pytest.raises(ValueError, match="faces refer to particle 9"):
        SurfaceWind([[0, 1, 9]], [0, 0, 1], 1.0)(x)
    with pytest.raises(ValueError, match="3 dimensions"):
        SurfaceWind([[0, 1, 2]], [0, 0, 1], 1.0)(x[:, :2])
    with pytest.raises(ValueError, match="velocity"):
        SurfaceWind(faces, lambda t: [0.0, t], 1.0)(x, t=1.0)
