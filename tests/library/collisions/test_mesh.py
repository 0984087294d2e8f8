"""Triangle meshes: the grid's numbering, edges, face edges, adjacency and the input checks."""

import numpy as np
import pytest

from particles.massspring import cloth_springs
from particles.collisions import TriangleMesh


def test_grid_faces_follow_the_cloth_numbering():
    """Each grid cell gives (a, b, d) and (a, d, c) with particle (i, j) numbered j nx + i."""
    nx, ny = 4, 3
    mesh = TriangleMesh.grid(nx, ny)
    assert mesh.n == nx * ny and mesh.m == 2 * (nx - 1) * (ny - 1)
    i, j = 2, 1  # the last cell of the second row
    a, b, c, d = j * nx + i, j * nx + i + 1, (j + 1) * nx + i, (j + 1) * nx + i + 1
    cell = j * (nx - 1) + i
    assert mesh.faces[2 * cell].tolist() == [a, b, d]
    assert mesh.faces[2 * cell + 1].tolist() == [a, d, c]


def test_grid_triangles_are_counter_clockwise_in_the_column_row_plane():
    """Every face of the grid has a positive area in the (i, j) plane (consistent normals)."""
    nx, ny = 5, 4
    mesh = TriangleMesh.grid(nx, ny)
    ij = np.stack(np.divmod(np.arange(nx * ny), nx)[::-1], axis=1).astype(float)  # (i, j)
    p = ij[mesh.faces]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    np.testing.assert_array_equal(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0], 1.0)


def test_grid_edges_are_the_structural_springs_and_one_diagonal():
    """Edges: all structural springs and the (i, j)-(i+1, j+1) diagonal, once each, sorted."""
    nx, ny = 5, 4
    mesh = TriangleMesh.grid(nx, ny)
    springs = cloth_springs(nx, ny)
    diagonal = springs["shear"][: (nx - 1) * (ny - 1)]  # (i,j)-(i+1,j+1) come first
    expected = np.sort(np.concatenate([springs["structural"], diagonal]), axis=1)
    expected = expected[np.lexsort((expected[:, 1], expected[:, 0]))]
    np.testing.assert_array_equal(mesh.edges, expected)
    assert len(mesh.edges) == (nx - 1) * ny + nx * (ny - 1) + (nx - 1) * (ny - 1)  # Euler: V - E + F = 1


def test_face_edges_point_to_the_faces_own_vertex_pairs():
    """face_edges[f, k] is the edge (v_k, v_k+1) of face f; interior edges belong to two faces."""
    mesh = TriangleMesh.grid(6, 5)
    F, E = mesh.faces, mesh.edges
    for k in range(3):  # the three edges of a face
        ends = np.sort(np.stack([F[:, k], F[:, (k + 1) % 3]], axis=1), axis=1)
        np.testing.assert_array_equal(E[mesh.face_edges[:, k]], ends)
    uses = np.bincount(mesh.face_edges.ravel(), minlength=len(E))
    boundary = 2 * (6 - 1) + 2 * (5 - 1)
    assert set(uses.tolist()) == {1, 2} and (uses == 1).sum() == boundary


def test_share_vertex_is_vectorized_and_exact():
    """Faces of one cell share two vertices, of cells two apart none, a face shares all with itself."""
    mesh = TriangleMesh.grid(4, 4)
    fa = np.array([0, 0, 0, 0])
    fb = np.array([0, 1, 4, 3])  # itself; same cell; two cells to the right; next cell, shares b and d
    assert mesh.share_vertex(fa, fb).tolist() == [True, True, False, True]
    assert mesh.share_vertex([], []).tolist() == []


def test_mesh_from_faces_counts_vertices_and_keeps_loose_ones():
    """n defaults to the largest index + 1; a larger n keeps vertices that are in no face."""
    assert TriangleMesh([[0, 1, 2]]).n == 3
    mesh = TriangleMesh([[0, 1, 2]], n=5)
    assert mesh.n == 5 and mesh.edges.tolist() == [[0, 1], [0, 2], [1, 2]]
    assert TriangleMesh(np.zeros((0, 3), dtype=int), n=2).edges.shape == (0, 2)


def test_mesh_arrays_are_read_only():
    """The connectivity cannot be changed behind the mesh's back."""
    mesh = TriangleMesh.grid(3, 3)
    with pytest.raises(ValueError):
        mesh.faces[0, 0] = 5


@pytest.mark.parametrize("faces, n, message", [
    ([[0, 1]], None, r"shape \(m, 3\)"),
    ([[0.0, 1.0, 2.0]], None, "integer array"),
    ([[0, 1, 3]], 3, r"vertex indices in \[0, 3\)"),
    ([[0, -1, 2]], 4, r"vertex indices in \[0, 4\)"),
    ([[0, 1, 2], [2, 3, 2]], None, r"three different vertices, but face 1 is \[2, 3, 2\]"),
    ([[0, 1, 2]], 2.5, "n must be an integer"),
])
def test_bad_faces_are_refused_with_a_clear_message(faces, n, message):
    """Bad faces or counts raise ValueError naming the argument and what was expected."""
    with pytest.raises(ValueError, match=message):
        TriangleMesh(faces, n)


def test_share_vertex_refuses_bad_indices():
    """Face indices outside [0, m) or of different shapes are refused."""
    mesh = TriangleMesh.grid(3, 3)
    with pytest.raises(ValueError, match=r"fb must hold face indices in \[0, 8\)"):
        mesh.share_vertex([0], [8])
    with pytest.raises(ValueError, match="same shape"):
        mesh.share_vertex([0, 1], [1])
