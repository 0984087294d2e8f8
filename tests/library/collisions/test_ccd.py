"""Continuous collision detection: the coplanarity cubic, its roots in [0, 1], times of impact, candidates."""

import numpy as np
import pytest

from particles.collisions import TriangleMesh
from particles.collisions.ccd import candidates, coplanarity_cubic, cubic_roots, detect, first_contact

TRIANGLE = [[0.0, 0, 0], [1.0, 0, 0], [0.0, 1, 0]]


def test_cubic_is_the_volume_along_the_motion():
    """f(t) equals det[x1 - x0, x2 - x0, x3 - x0] at x + t dx for random motions."""
    rng = np.random.default_rng(0)
    x, dx = rng.normal(size=(50, 4, 3)), rng.normal(size=(50, 4, 3))
    coef = coplanarity_cubic(x, dx)
    for t in (0.0, 0.3, 1.0):  # a loop over three test times
        y = x + t * dx
        det = np.linalg.det(np.stack([y[:, 1] - y[:, 0], y[:, 2] - y[:, 0], y[:, 3] - y[:, 0]], axis=1))
        np.testing.assert_allclose(np.polyval(coef.T, t), det, atol=1e-12)


def test_roots_of_known_cubics():
    """Three roots, one root, a linear and a constant 'cubic', and none in [0, 1]."""
    coef = np.array([np.poly([0.2, 0.5, 0.9]), np.poly([0.4, 2.0, 3.0]), [0.0, 0.0, 2.0, -1.0],
                     [0.0, 0.0, 0.0, 1.0], np.poly([-1.0, 1.5, 2.0])])
    r = cubic_roots(coef)
    np.testing.assert_allclose(r[0], [0.2, 0.5, 0.9], atol=1e-14)
    np.testing.assert_allclose(r[1, 0], 0.4, atol=1e-14)
    np.testing.assert_allclose(r[2, 0], 0.5, atol=1e-14)
    assert np.isnan(r[1, 1:]).all() and np.isnan(r[3]).all() and np.isnan(r[4]).all()


def test_a_touching_double_root_is_found_within_the_tolerance():
    """(t - 0.5)^2 (t + 1) + 1e-14 does not change sign; with ftol it is a root at 0.5, without none."""
    coef = np.poly([0.5, 0.5, -1.0]) + [0, 0, 0, 1e-14]
    assert np.isnan(cubic_roots([coef])).all()
    assert cubic_roots([coef], ftol=1e-12)[0, 0] == pytest.approx(0.5, abs=1e-6)


def test_random_cubics_agree_with_numpy_roots():
    """Every real root of np.roots in [0, 1] (a reference, used only here) is found, to 1e-9."""
    rng = np.random.default_rng(1)
    coef = rng.normal(size=(300, 4))
    mine = cubic_roots(coef)
    for k in range(len(coef)):  # a loop over test cases, comparing with the reference
        ref = np.roots(coef[k])
        ref = np.sort(ref[(np.abs(ref.imag) < 1e-9) & (ref.real >= 0) & (ref.real <= 1)].real)
        got = mine[k][~np.isnan(mine[k])]
        assert all(np.min(np.abs(got - t)) < 1e-9 for t in ref), (coef[k], ref, got)


def test_vertex_through_a_triangle_within_one_step():
    """A vertex falling 4 m through a triangle 1 m below it hits it at t = 1/4, with the normal against its motion."""
    x = np.array([[[0.2, 0.2, 1.0], *TRIANGLE]])
    dx = np.zeros((1, 4, 3))
    dx[0, 0, 2] = -4.0
    hit = first_contact(x, dx, edge=False, eta=1e-9)
    assert len(hit) == 1 and hit.time[0] == pytest.approx(0.25, abs=1e-14)
    np.testing.assert_allclose(hit.normal[0], [0, 0, 1])
    np.testing.assert_allclose(hit.weights[0], [1.0, -0.6, -0.2, -0.2])


def test_vertex_beside_the_triangle_and_a_moving_triangle():
    """Crossing the plane outside the triangle is no contact; a triangle rising through a vertex is one."""
    x = np.array([[[1.0, 1.0, 1.0], *TRIANGLE], [[0.2, 0.2, 1.0], *TRIANGLE]])
    dx = np.zeros((2, 4, 3))
    dx[0, 0, 2] = -4.0
    dx[1, 1:, 2] = 2.0
    hit = first_contact(x, dx, edge=False, eta=1e-9)
    assert hit.vertices[:, 0].tolist() == [1] and hit.time[0] == pytest.approx(0.5, abs=1e-14)
    np.testing.assert_allclose(hit.normal[0], [0, 0, 1])  # the triangle moves up: pushed down, vertex up


def test_two_edges_crossing():
    """An edge sweeping down through another, crossing it at t = 0.5; one moving parallel above does not."""
    x = np.array([[[-1.0, 0, 1], [1.0, 0, 1], [0.0, -1, 0], [0.0, 1, 0]],
                  [[-1.0, 0, 1], [1.0, 0, 1], [-1.0, 0.5, 0], [1.0, 0.5, 0]]])
    dx = np.zeros((2, 4, 3))
    dx[0, :2, 2] = -2.0
    dx[1, :2, 1] = 3.0  # moves sideways above the other edge, never meets it
    hit = first_contact(x, dx, edge=True, eta=1e-9)
    assert hit.vertices[:, 0].tolist() == [0] and hit.time[0] == pytest.approx(0.5, abs=1e-14)
    np.testing.assert_allclose(hit.weights[0], [0.5, 0.5, -0.5, -0.5])


def test_coplanar_motion_is_tested_at_the_end():
    """A vertex sliding in the triangle's plane into it is a contact at t = 1; staying outside, none."""
    x = np.array([[[2.0, 0.2, 0.0], *TRIANGLE], [[2.0, 0.2, 0.0], *TRIANGLE]])
    dx = np.zeros((2, 4, 3))
    dx[0, 0, 0] = -1.8
    dx[1, 0, 0] = -0.5
    hit = first_contact(x, dx, edge=False, eta=1e-9)
    assert hit.vertices[:, 0].tolist() == [0] and hit.time.tolist() == [1.0]


def test_candidates_leave_out_incident_pairs():
    """On a grid, no candidate vertex is a corner of its face, and no two candidate edges share a vertex."""
    mesh = TriangleMesh.grid(5, 5)
    g = np.stack(np.meshgrid(np.linspace(0, 1, 5), np.linspace(0, 1, 5)), -1).reshape(-1, 2)
    x = np.c_[g, np.zeros(25)]
    vf, ee = candidates(mesh, x, x, pad=0.05)
    assert len(vf) and len(ee)
    assert not (vf[:, 1:] == vf[:, :1]).any()
    assert not (ee[:, :2, None] == ee[:, None, 2:]).any()
    only = np.zeros(25, dtype=bool)
    only[12] = True
    vf12, ee12 = candidates(mesh, x, x, pad=0.05, vertices=only)
    assert (vf12 == 12).any(axis=1).all() and (ee12 == 12).any(axis=1).all()
    assert len(vf12) == (vf == 12).any(axis=1).sum()


def test_detect_finds_a_falling_triangle_and_nothing_in_a_flat_sheet():
    """Two triangles, one falling through the other; a flat sheet falling as a whole collides with nothing."""
    mesh = TriangleMesh([[0, 1, 2], [3, 4, 5]])
    x0 = np.array([TRIANGLE[0], TRIANGLE[1], TRIANGLE[2], [0.2, 0.2, 0.5], [1.2, 0.2, 0.5], [0.2, 1.2, 0.5]])
    dx = np.zeros((6, 3))
    dx[3:, 2] = -1.0
    hits = detect(mesh, x0, dx, eta=1e-9)
    assert [3, 0, 1, 2] in hits.vertices.tolist() and np.allclose(hits.time, 0.5)
    sheet = TriangleMesh.grid(6, 6)
    g = np.stack(np.meshgrid(np.linspace(0, 1, 6), np.linspace(0, 1, 6)), -1).reshape(-1, 2)
    x = np.c_[g, np.zeros(36)]
    assert len(detect(sheet, x, np.tile([0.0, 0.0, -0.3], (36, 1)), eta=1e-6)) == 0


def test_bad_input_is_refused():
    """Shapes, a non-mesh and a non-positive tolerance give errors that name the argument."""
    with pytest.raises(ValueError, match=r"x must have shape \(k, 4, 3\)"):
        coplanarity_cubic(np.zeros((2, 3, 3)), np.zeros((2, 3, 3)))
    with pytest.raises(ValueError, match=r"coef must have shape \(k, 4\)"):
        cubic_roots([[1.0, 2.0]])
    with pytest.raises(ValueError, match="eta must be a positive"):
        first_contact(np.zeros((1, 4, 3)), np.zeros((1, 4, 3)), edge=False, eta=0.0)
    with pytest.raises(ValueError, match="mesh must be a particles.collisions.mesh.TriangleMesh"):
        candidates([[0, 1, 2]], np.zeros((3, 3)), np.zeros((3, 3)))
    with pytest.raises(ValueError, match=r"x1 must have shape \(3, 3\)"):
        candidates(TriangleMesh([[0, 1, 2]]), np.zeros((3, 3)), np.zeros((4, 3)))
