"""Closest points of vertex-triangle and edge-edge pairs: exact answers, degenerate cases, the contact form."""

import numpy as np
import pytest

from particles.collisions import edge_edge, point_segment, vertex_face

A, B, C = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]


def tri(p):
    p = np.atleast_2d(np.asarray(p, dtype=float))
    k = len(p)
    return p, np.tile(A, (k, 1)), np.tile(B, (k, 1)), np.tile(C, (k, 1))


def test_vertex_above_the_interior_projects_onto_the_plane():
    """A vertex over the triangle: distance = height, normal = face normal, weights = barycentric coordinates."""
    r = vertex_face(*tri([0.2, 0.3, -0.5]))
    assert r.distance[0] == pytest.approx(0.5)
    np.testing.assert_allclose(r.normal[0], [0, 0, -1])
    np.testing.assert_allclose(r.weights[0], [1.0, -0.5, -0.2, -0.3])


def test_vertex_beyond_an_edge_and_beyond_a_corner():
    """Outside the triangle the closest point lies on an edge or at a corner."""
    r = vertex_face(*tri([[1.0, 1.0, 0.0], [-1.0, -2.0, 0.0], [0.5, -1.0, 1.0]]))
    np.testing.assert_allclose(r.distance, [np.sqrt(0.5), np.sqrt(5.0), np.sqrt(2.0)])
    np.testing.assert_allclose(r.weights[0], [1.0, 0.0, -0.5, -0.5], atol=1e-15)
    np.testing.assert_allclose(r.weights[1], [1.0, -1.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(r.weights[2], [1.0, -0.5, -0.5, 0.0], atol=1e-15)


def test_vertex_on_the_triangle_gets_the_face_normal():
    """Distance zero: the normal is the face's normal (b - a) x (c - a)."""
    r = vertex_face(*tri([0.25, 0.25, 0.0]))
    assert r.distance[0] == 0.0
    np.testing.assert_allclose(r.normal[0], [0, 0, 1])


def test_degenerate_triangles_use_their_edges():
    """A sliver (collinear corners) or a point still gives the distance to the segment or the point."""
    p = np.array([[0.5, 1.0, 0.0], [3.0, 4.0, 0.0]])
    a = np.zeros((2, 3))
    b = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    c = np.array([[2.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    r = vertex_face(p, a, b, c)
    np.testing.assert_allclose(r.distance, [1.0, 5.0])
    assert np.all(np.isfinite(r.normal)) and np.allclose(np.linalg.norm(r.normal, axis=1), 1.0)


def test_random_pairs_match_a_dense_sampling():
    """Vertex-triangle and edge-edge distances are exact: never above a sampled minimum, and within its resolution."""
    rng = np.random.default_rng(3)
    P = rng.normal(size=(300, 4, 3))
    g = np.linspace(0.0, 1.0, 101)
    s, u = (a.ravel() for a in np.meshgrid(g, g))
    r = vertex_face(P[:, 0], P[:, 1], P[:, 2], P[:, 3])
    inside = s + u <= 1
    e1, e2 = (P[:, 2] - P[:, 1])[:, None], (P[:, 3] - P[:, 1])[:, None]
    pts = P[:, 1, None] + s[inside, None] * e1 + u[inside, None] * e2
    sampled = np.linalg.norm(pts - P[:, 0, None], axis=2).min(axis=1)
    assert np.all(r.distance <= sampled + 1e-12) and np.all(sampled - r.distance < 0.05)
    r = edge_edge(P[:, 0], P[:, 1], P[:, 2], P[:, 3])
    pa = P[:, 0, None] + s[:, None] * (P[:, 1] - P[:, 0])[:, None]
    qb = P[:, 2, None] + u[:, None] * (P[:, 3] - P[:, 2])[:, None]
    sampled = np.linalg.norm(pa - qb, axis=2).min(axis=1)
    assert np.all(r.distance <= sampled + 1e-12) and np.all(sampled - r.distance < 0.05)


@pytest.mark.parametrize("kind", ["vf", "ee"])
def test_the_contact_form_gives_the_separation(kind):
    """sum_j w_j x_j = distance * normal, and sum_j w_j = 0 (so impulses w_j I n conserve momentum)."""
    P = np.random.default_rng(4).normal(size=(200, 4, 3))
    f = vertex_face if kind == "vf" else edge_edge
    r = f(P[:, 0], P[:, 1], P[:, 2], P[:, 3])
    sep = np.einsum("kj,kjd->kd", r.weights, P)
    np.testing.assert_allclose(sep, r.distance[:, None] * r.normal, atol=1e-12)
    np.testing.assert_allclose(r.weights.sum(axis=1), 0.0, atol=1e-15)


def test_crossing_edges_meet_at_their_middles():
    """Two perpendicular edges 1 m apart: s = u = 1/2, normal from the second to the first."""
    r = edge_edge([[-1.0, 0, 1]], [[1.0, 0, 1]], [[0.0, -1, 0]], [[0.0, 1, 0]])
    assert r.distance[0] == 1.0
    np.testing.assert_allclose(r.normal[0], [0, 0, 1])
    np.testing.assert_allclose(r.weights[0], [0.5, 0.5, -0.5, -0.5])


def test_parallel_edges_take_the_middle_of_their_overlap():
    """Parallel edges overlapping on [1, 2] (in the first's length 4): s at the overlap's middle, 1.5 / 4."""
    r = edge_edge([[0.0, 0, 0]], [[4.0, 0, 0]], [[1.0, 2, 0]], [[2.0, 2, 0]])
    assert r.distance[0] == pytest.approx(2.0)
    assert r.weights[0, 1] == pytest.approx(1.5 / 4)
    assert -r.weights[0, 3] == pytest.approx(0.5)
    np.testing.assert_allclose(r.normal[0], [0, -1, 0])


def test_collinear_touching_and_zero_length_edges_have_a_unit_normal():
    """Collinear overlapping edges (distance 0) and point-like edges still give a unit normal."""
    r = edge_edge([[0.0, 0, 0], [0.0, 0, 0]], [[2.0, 0, 0], [0.0, 0, 0]],
                  [[1.0, 0, 0], [0.0, 0, 3]], [[3.0, 0, 0], [0.0, 0, 3]])
    np.testing.assert_allclose(r.distance, [0.0, 3.0])
    np.testing.assert_allclose(np.linalg.norm(r.normal, axis=1), 1.0)
    assert abs(r.normal[0, 0]) < 1e-12  # perpendicular to the common line


def test_point_segment():
    """The closest parameter is clamped to [0, 1]; a zero-length segment gives s = 0."""
    s, d = point_segment(np.array([[2.0, 1, 0], [0.5, 1, 0], [1.0, 1, 0]]), np.zeros((3, 3)),
                         np.array([[1.0, 0, 0], [1.0, 0, 0], [0.0, 0, 0]]))
    np.testing.assert_allclose(s, [1.0, 0.5, 0.0])
    np.testing.assert_allclose(d, [np.sqrt(2), 1.0, np.sqrt(2)])


def test_bad_shapes_are_refused():
    """Arguments of different shapes, or not 3D, raise errors naming them."""
    with pytest.raises(ValueError, match="b must have the shape of p"):
        vertex_face([[0.0, 0, 0]], [[0.0, 0, 0]], [[0.0, 0, 0], [1.0, 0, 0]], [[0.0, 0, 0]])
    with pytest.raises(ValueError, match=r"p1 must have shape \(k, 3\)"):
        edge_edge([[0.0, 0]], [[0.0, 0]], [[0.0, 0]], [[0.0, 0]])
    with pytest.raises(ValueError, match="finite"):
        vertex_face([[np.nan, 0, 0]], [[0.0, 0, 0]], [[1.0, 0, 0]], [[0.0, 1, 0]])
