"""The exact triangle-triangle crossing test and the box broad phase, against known answers and brute force."""

from fractions import Fraction
from itertools import combinations

import numpy as np
import pytest

from particles.collisions import TriangleMesh, box_pairs, intersections, orientation


# ---------------------------------------------------------------- references written for the tests

def _sub(p, q):
    return [p[0] - q[0], p[1] - q[1], p[2] - q[2]]


def _cross(u, v):
    return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]


def _dot(u, v):
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def _edge_through(p, q, tri):
    """Does the segment pq cross triangle tri, strictly (rational arithmetic, plane point + barycentric)?"""
    a, b, c = tri
    n = _cross(_sub(b, a), _sub(c, a))
    dp, dq = _dot(n, _sub(p, a)), _dot(n, _sub(q, a))
    if dp * dq >= 0:
        return False
    s = dp / (dp - dq)
    X = [p[k] + s * (q[k] - p[k]) for k in range(3)]
    return all(_dot(n, _cross(_sub(v, u), _sub(X, u))) > 0 for u, v in ((a, b), (b, c), (c, a)))


def brute_force(x, faces):
    """All pairs of faces sharing no vertex, tested with exact rationals, edge by edge."""
    X = [[Fraction(float(v)) for v in row] for row in np.asarray(x, dtype=float)]
    T = np.asarray(x, dtype=float)[np.asarray(faces)]
    lo, hi = T.min(axis=1), T.max(axis=1)
    out = []
    for fa, fb in combinations(range(len(faces)), 2):  # the reference may loop
        A, B = faces[fa], faces[fb]
        if set(A) & set(B) or np.any(lo[fa] > hi[fb]) or np.any(lo[fb] > hi[fa]):  # disjoint boxes
            continue
        TA, TB = [X[i] for i in A], [X[i] for i in B]
        hit = any(_edge_through(TA[k], TA[(k + 1) % 3], TB) for k in range(3)) or \
            any(_edge_through(TB[k], TB[(k + 1) % 3], TA) for k in range(3))
        if hit:
            out.append([fa, fb])
    return np.array(out, dtype=np.int64).reshape(-1, 2)


def two(x):
    """Intersections of the two triangles (0, 1, 2) and (3, 4, 5) of x."""
    return intersections(x, [[0, 1, 2], [3, 4, 5]]).tolist()


# ---------------------------------------------------------------- orientation

def test_orientation_sign_convention():
    """+1 on the side of (b - a) x (c - a), -1 on the other, 0 when coplanar; alternating in its arguments."""
    a, b, c = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]
    assert orientation(a, b, c, [0.3, 0.3, 2.0]) == 1
    assert orientation(a, b, c, [0.3, 0.3, -2.0]) == -1
    assert orientation(a, b, c, [7.0, -3.0, 0.0]) == 0
    assert orientation(b, a, c, [0.3, 0.3, 2.0]) == -1  # one swap flips
    assert orientation(c, [0.3, 0.3, 2.0], a, b) == 1  # (a c)(b d): two swaps keep


def test_orientation_is_exact_where_float64_fails():
    """Near-coplanar quadruples: the signs equal the rational ones although the plain float determinant errs."""
    rng = np.random.default_rng(1)
    k = 400
    a, b, c = (rng.uniform(-1, 1, (k, 3)) for _ in range(3))
    s, r = rng.uniform(0, 1, (2, k, 1))
    d = a + s * (b - a) + r * (c - a)  # coplanar up to rounding
    d[: k // 2] = np.round(d[: k // 2] * 8) / 8  # and some on dyadic grids
    a[: k // 2], b[: k // 2], c[: k // 2] = (np.round(p[: k // 2] * 8) / 8 for p in (a, b, c))
    exact = []
    for row in range(k):  # reference: rationals
        A, B, C, D = ([Fraction(float(v)) for v in p[row]] for p in (a, b, c, d))
        det = _dot(_cross(_sub(B, A), _sub(C, A)), _sub(D, A))
        exact.append((det > 0) - (det < 0))
    got = orientation(a, b, c, d)
    np.testing.assert_array_equal(got, exact)
    naive = np.sign(np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a))
    assert np.any(naive != np.array(exact))  # the test does reach the cases that need exactness


def test_orientation_underflow_is_decided_exactly():
    """Tiny offsets whose products underflow to zero still get their sign."""
    assert orientation([0, 0, 0], [1e-200, 0, 0], [0, 1e-200, 0], [1e-200, 1e-200, 1e-200]) == 1


def test_orientation_refuses_bad_shapes():
    """Points must have three coordinates and matching row counts."""
    with pytest.raises(ValueError, match=r"d must have shape \(k, 3\)"):
        orientation([0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0])
    with pytest.raises(ValueError, match="same number of rows"):
        orientation(np.zeros((2, 3)), np.zeros((3, 3)), np.zeros((2, 3)), np.zeros((2, 3)))


# ---------------------------------------------------------------- two triangles

LOW = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]]


def test_two_crossing_triangles():
    """A vertical triangle whose edge pierces a horizontal one crosses it, in either vertex order."""
    up = [[0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [3.0, 3.0, 0.5]]
    assert two(LOW + up) == [[0, 1]]
    assert two(LOW + up[::-1]) == [[0, 1]]
    assert two(up + LOW) == [[0, 1]]


def test_crossing_by_an_edge_through_the_middle_only():
    """Two triangles linked like chain rings: no vertex inside the other, each crosses the other's edge."""
    ring = [[1.0, -1.0, -0.5], [1.0, 1.0, -0.5], [1.0, 0.0, 1.5]]  # in the plane x = 1, pierced by edge 0-1
    assert two(LOW[:1] + [[2.0, 0.5, 0.0], [2.0, -0.5, 0.0]] + ring) == [[0, 1]]


def test_separated_triangles_do_not_cross():
    """A triangle above another, and one beside it in the same plane, do not cross."""
    assert two(LOW + [[0.2, 0.2, 0.1], [1.0, 0.2, 0.1], [0.2, 1.0, 0.3]]) == []
    assert two(LOW + [[3.0, 0.0, 0.0], [4.0, 0.0, 0.0], [3.0, 1.0, 0.0]]) == []
    assert two(LOW + [[0.5, 0.5, 0.5], [0.5, 0.5, 2.0], [3.0, 3.0, 1.0]]) == []  # the edge stops short


def test_touching_is_not_crossing():
    """Contacts on the boundary only: a vertex on the face, an edge on the face, an edge meeting an edge."""
    assert two(LOW + [[0.5, 0.5, 0.0], [0.5, 0.5, 1.0], [1.0, 0.2, 1.0]]) == []  # vertex on the face
    assert two(LOW + [[0.2, 0.2, 0.0], [1.0, 0.2, 0.0], [0.5, 0.5, 1.0]]) == []  # edge lying on the face
    assert two(LOW + [[1.0, 1.0, -1.0], [1.0, 1.0, 1.0], [2.0, 2.0, 0.0]]) == []  # edge through LOW's edge
    assert two(LOW + [[0.5, -1.0, 0.0], [0.5, -1.0, 1.0], [0.5, 0.0, 0.5]]) == []  # vertex on LOW's edge


def test_coplanar_overlapping_triangles_do_not_cross():
    """Two overlapping triangles in one plane have no side to cross to: not a crossing."""
    assert two(LOW + [[0.5, 0.5, 0.0], [3.0, 0.5, 0.0], [0.5, 3.0, 0.0]]) == []
    tilted = [[0.5, 0.5, -1e-9], [3.0, 0.5, 3e-9], [0.5, 3.0, 3e-9]]  # tipped off the plane: it crosses
    assert two(LOW + tilted) == [[0, 1]]
    tipped = [[0.5, 0.5, -1e-9], [3.0, 0.5, 1e-9], [0.5, 3.0, 1e-9]]  # crosses z = 0 where x + y = 2.25
    assert two(LOW + tipped) == []


def test_shared_vertex_pairs_are_skipped_even_when_crossing():
    """Faces that share a vertex are adjacent by construction and never reported."""
    x = LOW + [[0.5, 0.5, -1.0], [0.5, 0.5, 1.0]]
    assert intersections(x, [[0, 1, 2], [3, 4, 1]]).tolist() == []  # crosses, but shares vertex 1
    assert brute_force(x, [[0, 1, 2], [3, 4, 1]]).tolist() == []


def test_degenerate_triangles_are_not_crossed_but_their_edges_cross():
    """A triangle squashed to a segment has nothing inside to cross, but the segment still pierces others."""
    squashed = [[0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [0.5, 0.5, 2.0]]
    assert two(LOW + squashed) == [[0, 1]]
    flat = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 2.0, 0.0]]  # on the line x = y of z = 0
    assert two(flat + [[1.0, 0.0, -1.0], [0.0, 1.0, 1.0], [3.0, 3.0, 5.0]]) == []


# ---------------------------------------------------------------- grids

def grid_positions(nx, ny, y, z):
    """Vertex j nx + i at (i, y[j], z[j])."""
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    return np.stack([i, np.asarray(y, float)[j], np.asarray(z, float)[j]], axis=-1).reshape(-1, 3)


def test_flat_grid_has_no_crossing():
    """A flat 40 x 30 cloth: 0 pairs, although many non-adjacent boxes touch."""
    nx, ny = 40, 30
    x = grid_positions(nx, ny, np.arange(ny), np.zeros(ny))
    assert intersections(x, TriangleMesh.grid(nx, ny)).shape == (0, 2)


def folded(nx, J, rows, dip):
    """A grid lying flat for rows 0..J and folded back over itself for J + k, k = 1..rows."""
    k = np.arange(1, rows + 1)
    y = np.concatenate([np.arange(J + 1), J + 0.5 - k])
    z = np.concatenate([np.zeros(J + 1), 1.0 - dip * k])
    return grid_positions(nx, J + 1 + rows, y, z), TriangleMesh.grid(nx, J + 1 + rows)


def test_grid_folded_through_itself_has_the_known_count():
    """The folded plane cuts the flat part in a line: 3 crossing pairs per column of cells."""
    nx = 12
    x, mesh = folded(nx, J=8, rows=5, dip=0.3)  # crosses z = 0 at k = 10/3: y = 8 - 2.83
    pairs = intersections(x, mesh)
    assert len(pairs) == 3 * (nx - 1)
    np.testing.assert_array_equal(pairs, brute_force(x, mesh.faces.tolist()))
    flat_faces = 2 * (nx - 1) * 8
    assert np.all(pairs[:, 0] < flat_faces) and np.all(pairs[:, 1] >= flat_faces)


def test_grid_folded_above_itself_has_no_crossing():
    """The same fold that stays above the flat part (z > 0): 0 pairs."""
    x, mesh = folded(10, J=8, rows=5, dip=0.15)
    assert intersections(x, mesh).tolist() == []


def test_exact_grid_coordinates_agree_with_brute_force():
    """A crumpled grid on a coarse lattice (many exact ties) gives exactly the brute-force pairs."""
    rng = np.random.default_rng(7)
    nx, ny = 7, 6
    x = grid_positions(nx, ny, np.arange(ny), np.zeros(ny)) / 2.0
    x[:, 2] = rng.integers(-2, 3, nx * ny) / 2.0
    x[:, :2] += rng.integers(-1, 2, (nx * ny, 2)) / 2.0
    mesh = TriangleMesh.grid(nx, ny)
    expected = brute_force(x, mesh.faces.tolist())
    assert len(expected) > 0
    np.testing.assert_array_equal(intersections(x, mesh), expected)


# ---------------------------------------------------------------- random triangles

@pytest.mark.parametrize("seed, lattice", [(0, None), (1, None), (2, 3), (3, 2), (4, 0.1)])
def test_random_triangles_agree_with_brute_force(seed, lattice):
    """Random triangle soups (continuous, or on lattices with ties) match the O(m^2) rational reference."""
    rng = np.random.default_rng(seed)
    m = 60
    centres = rng.uniform(0, 3, (m, 1, 3))
    x = (centres + rng.uniform(-0.6, 0.6, (m, 3, 3))).reshape(-1, 3)
    if lattice is not None:
        x = np.round(x * lattice) / lattice if lattice >= 1 else np.round(x / lattice) * lattice
    faces = np.arange(3 * m).reshape(m, 3)
    faces[rng.random(m) < 0.2, 0] = rng.integers(0, 3 * m)  # some shared vertices
    faces = faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 0] != faces[:, 2])]
    expected = brute_force(x, faces.tolist())
    assert len(expected) > 5
    np.testing.assert_array_equal(intersections(x, faces), expected)
    np.testing.assert_array_equal(intersections(x, faces, block=7), expected)


def test_input_is_not_modified_and_bad_input_is_refused():
    """x and faces stay as given; wrong shapes and indices raise clear errors."""
    x = np.array(LOW + [[0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [3.0, 3.0, 0.5]])
    faces = np.array([[0, 1, 2], [3, 4, 5]])
    x0, f0 = x.copy(), faces.copy()
    intersections(x, faces)
    np.testing.assert_array_equal(x, x0)
    np.testing.assert_array_equal(faces, f0)
    with pytest.raises(ValueError, match=r"x must have shape \(n, 3\)"):
        intersections(x[:, :2], faces)
    with pytest.raises(ValueError, match=r"vertex indices in \[0, 6\)"):
        intersections(x, [[0, 1, 6]])
    with pytest.raises(ValueError, match="the mesh has 9 vertices but x has only 6 rows"):
        intersections(x, TriangleMesh.grid(3, 3))


# ---------------------------------------------------------------- boxes

def brute_boxes(lo_a, hi_a, lo_b, hi_b, one_set):
    """All overlapping pairs by testing every pair (closed boxes)."""
    over = np.all((lo_a[:, None] <= hi_b[None]) & (lo_b[None] <= hi_a[:, None]), axis=2)
    if one_set:
        over = np.triu(over, 1)
    return np.nonzero(over)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_box_pairs_within_one_set_match_all_pairs(seed):
    """Random boxes of mixed sizes (and a few huge and flat ones): the same pairs as the O(k^2) test."""
    rng = np.random.default_rng(seed)
    k = 400
    lo = rng.uniform(0, 10, (k, 3))
    size = rng.exponential(0.4, (k, 3))
    size[:3] *= 30  # a few huge boxes
    size[3:20, 2] = 0.0  # and some flat ones
    hi = lo + size
    i, j = box_pairs(lo, hi)
    ei, ej = brute_boxes(lo, hi, lo, hi, True)
    np.testing.assert_array_equal(i, ei)
    np.testing.assert_array_equal(j, ej)
    assert np.all(i < j)


def test_box_pairs_between_two_sets_match_all_pairs():
    """Points (zero-size boxes) against boxes: every (a, b) pair with a in A and b in B."""
    rng = np.random.default_rng(5)
    pa = rng.uniform(0, 5, (300, 3))
    lo_b = rng.uniform(0, 5, (200, 3))
    hi_b = lo_b + rng.uniform(0, 0.8, (200, 3))
    i, j = box_pairs(pa, pa, lo_b, hi_b)
    ei, ej = brute_boxes(pa, pa, lo_b, hi_b, False)
    np.testing.assert_array_equal(i, ei)
    np.testing.assert_array_equal(j, ej)


def test_box_pairs_touching_counts_and_edge_cases():
    """Touching boxes overlap; empty sets give no pairs; 2D boxes work; bad input is refused."""
    i, j = box_pairs([[0.0, 0.0], [1.0, 0.0]], [[1.0, 1.0], [2.0, 1.0]])
    assert (i.tolist(), j.tolist()) == ([0], [1])
    assert box_pairs(np.zeros((0, 3)), np.zeros((0, 3)))[0].shape == (0,)
    assert box_pairs(np.zeros((2, 3)), np.ones((2, 3)), np.zeros((0, 3)), np.zeros((0, 3)))[0].shape == (0,)
    with pytest.raises(ValueError, match="hi_a must be >= lo_a"):
        box_pairs([[1.0, 0.0, 0.0]], [[0.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match="both lo_b and hi_b"):
        box_pairs([[0.0, 0.0, 0.0]], [[1.0, 1.0, 1.0]], lo_b=[[0.0, 0.0, 0.0]])


def test_a_flat_sheet_needs_no_rational_arithmetic(monkeypatch):
    """All-zero determinants of a flat sheet are exact in float64 (P = 0): the rational fallback is not called."""
    import particles.collisions.triangle_crossing as module

    calls = []
    monkeypatch.setattr(module, "_exact_signs", lambda *p: calls.append(len(p[0])) or np.zeros(len(p[0]), np.int8))
    x = grid_positions(20, 20, np.arange(20) * 0.1, np.full(20, 0.3))
    assert intersections(x, TriangleMesh.grid(20, 20)).shape == (0, 2)
    assert calls == []
