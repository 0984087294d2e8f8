"""The compiled cloth collision stages (particles.collisions.compiled_stages) against the NumPy reference."""

import numpy as np
import pytest

numba = pytest.importorskip("numba")

from particles.collisions import compiled_stages as cloth  # noqa: E402
from particles.collisions import ClothCollisions, MovingSurface, Plane, Sphere, TriangleMesh, intersections  # noqa: E402
from particles.collisions.candidates import candidates_in_boxes, candidates_touching  # noqa: E402
from particles.collisions.ccd import BISECTIONS, F_TOL, first_contacts  # noqa: E402
from particles.collisions.proximity import PARALLEL, edge_edge_kernel, vertex_face_kernel  # noqa: E402
from particles.massspring import cloth as cloth_system  # noqa: E402
from particles.xpbd import XPBD  # noqa: E402

N = 12
H = 0.01


def crumpled(seed=0, n=N, noise=0.02):
    """A sheet with random bumps of about `noise` m (pairs near and across each other), and a random motion."""
    rng = np.random.default_rng(seed)
    mesh = TriangleMesh.grid(n, n)
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    x = np.stack([u.ravel(), v.ravel(), 0.1 * np.sin(6 * u.ravel()) * np.cos(5 * v.ravel())], axis=1)
    x += noise * rng.standard_normal(x.shape)
    dx = 0.03 * rng.standard_normal(x.shape)
    return mesh, np.ascontiguousarray(x), np.ascontiguousarray(dx)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_candidates_are_the_numpy_sets(seed):
    """The compiled grid finds exactly the vertex-face and edge-edge pairs of the NumPy broad phase, sorted alike."""
    mesh, x, dx = crumpled(seed)
    lo, hi = np.minimum(x, x + dx), np.maximum(x, x + dx)
    ref = candidates_in_boxes(mesh, lo, hi, 0.02)
    got = cloth.cloth_candidates(mesh, lo, hi, 0.02)
    assert len(ref[0]) > 100 and len(ref[2]) > 100
    for a, b in zip(ref, got):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("n, count", [(N, 20), (24, 1), (24, 300)],
                         ids=["12^2, 20 masked", "24^2 (the queries in parallel), 1 masked", "24^2, 300 masked"])
def test_masked_candidates_are_the_numpy_sets(n, count):
    """With a vertex mask, the pairs holding one of those vertices, as candidates_touching finds them."""
    mesh, x, dx = crumpled(3, n=n)
    lo, hi = np.minimum(x, x + dx), np.maximum(x, x + dx)
    mask = np.zeros(mesh.n, dtype=bool)
    mask[np.random.default_rng(3).choice(mesh.n, count, replace=False)] = True
    ref = candidates_touching(mesh, lo, hi, 0.02, mask)
    got = cloth.cloth_candidates(mesh, lo, hi, 0.02, mask)
    assert len(ref[0]) > 0
    for a, b in zip(ref, got):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("left, memo_used", [(0, True), (4, True), (40, False)],
                         ids=["every box within", "4 vertices left theirs", "40 left: a new search"])
def test_a_search_within_an_earlier_ones_boxes_gives_the_pairs_of_a_new_search(left, memo_used, monkeypatch):
    """With a memo, a search whose padded boxes lie within the last unmasked search's filters its pairs and
    searches again around the vertices that left their boxes (up to one in LEFT_MAX): the pairs of a search
    from scratch, whichever way they were found."""
    mesh, x, dx = crumpled(5, n=24)
    lo, hi = np.minimum(x, x + dx), np.maximum(x, x + dx)
    memo = {}
    cloth.cloth_candidate_rows(mesh, lo, hi, 0.02, memo=memo)
    searched = memo["v_lo"]
    gone = np.random.default_rng(5).choice(mesh.n, left, replace=False)
    lo2, hi2 = lo + 0.25 * (hi - lo), hi.copy()  # smaller boxes, and a smaller pad below
    lo2[gone] += 0.05  # these vertices moved out of their boxes
    hi2[gone] += 0.05
    used = []
    kept = cloth._kept_keys
    monkeypatch.setattr(cloth, "_kept_keys", lambda *a: used.append(1) or kept(*a))
    got = cloth.cloth_candidate_rows(mesh, lo2, hi2, 0.01, memo=memo)
    ref = cloth.cloth_candidate_rows(mesh, lo2, hi2, 0.01)
    assert bool(used) == memo_used
    assert (memo["v_lo"] is searched) == memo_used  # a search from scratch is the new memo
    assert len(ref[0]) > 50 and len(ref[1]) > 50
    if left:
        assert np.isin(ref[1], gone).any()  # pairs of the vertices that left, found by the search again
    for a, b in zip(ref, got):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("left", [0, 1], ids=["every box within", "a vertex left its box"])
def test_a_masked_search_neither_reads_nor_replaces_the_memo(left, monkeypatch):
    """The memo holds the pairs of a search without a mask; a masked search (the continuous test's passes after
    the first) walks grids of the masked elements instead, whether or not a vertex left the memo's boxes,
    finds the pairs of a search without the memo, and leaves the memo as it was."""
    mesh, x, dx = crumpled(6)
    lo, hi = np.minimum(x, x + dx), np.maximum(x, x + dx)
    memo = {}
    cloth.cloth_candidate_rows(mesh, lo, hi, 0.02, memo=memo)
    before = dict(memo)
    mask = np.zeros(mesh.n, dtype=bool)
    mask[::5] = True
    lo[3] += left * 0.1  # vertex 3 (not in the mask) moves out of its box
    hi[3] += left * 0.1
    used = []
    kept = cloth._kept_keys
    monkeypatch.setattr(cloth, "_kept_keys", lambda *a: used.append(1) or kept(*a))
    got = cloth.cloth_candidate_rows(mesh, lo, hi, 0.01, mask, memo=memo)
    ref = candidates_touching(mesh, lo, hi, 0.01, mask)
    assert not used
    assert all(memo[k] is before[k] for k in before) and memo.keys() == before.keys()
    assert len(got[0]) > 10 and len(got[1]) > 10
    np.testing.assert_array_equal(got[0], np.concatenate([ref[0][:, None], mesh.faces[ref[1]]], axis=1))
    np.testing.assert_array_equal(got[1], np.concatenate([mesh.edges[ref[2]], mesh.edges[ref[3]]], axis=1))


@pytest.mark.parametrize("same", [False, True], ids=["vertices against faces", "edges against edges"])
def test_a_masked_search_finds_each_pair_once_on_any_thread_count(same):
    """The masked grids report every pair that holds a masked vertex once (two masked elements too), in an order
    fixed by the boxes, the same bits on one thread and on two; an empty mask finds nothing."""
    mesh, x, dx = crumpled(10, n=24)
    lo, hi = np.minimum(x, x + dx) - 0.02, np.maximum(x, x + dx) + 0.02
    Q, T, _ = cloth._kinds(mesh)[same]
    mask = np.zeros(mesh.n, dtype=bool)
    mask[np.random.default_rng(10).choice(mesh.n, 40, replace=False)] = True
    boxes = cloth._boxes(lo, hi, Q, T, same)
    whole = cloth._search(*boxes, Q, T, same, None)
    q, t = np.divmod(whole, len(T))
    want = whole[mask[Q[q]].any(axis=1) | mask[T[t]].any(axis=1)]
    before = numba.get_num_threads()
    runs = []
    try:
        for threads in (1, numba.config.NUMBA_NUM_THREADS):
            numba.set_num_threads(threads)
            runs.append(cloth._search(*boxes, Q, T, same, mask, ordered=False))
    finally:
        numba.set_num_threads(before)
    assert len(want) > 50
    assert runs[0].tobytes() == runs[1].tobytes()
    assert len(np.unique(runs[0])) == len(runs[0])  # once each
    np.testing.assert_array_equal(np.sort(runs[0]), want)
    assert len(cloth._search(*boxes, Q, T, same, np.zeros(mesh.n, dtype=bool))) == 0


def _in_key_order(rows):
    """Rows of five columns (``ordered=False``) sorted by their key and stripped of it: the rows of four."""
    assert rows.shape[1] == 5
    return rows[cloth.in_key_order(rows, np.ones(len(rows), dtype=bool)), :4]


@pytest.mark.parametrize("masked", [False, True])
def test_unordered_rows_are_the_ordered_ones_with_their_keys(masked, monkeypatch):
    """``ordered=False``: the same rows, each with its key, in an order fixed by the boxes (the same on one thread
    and two, and from a search or a memo) and not the sorted one (the sort is what it spares)."""
    mesh, x, dx = crumpled(7, n=24)
    lo, hi = np.minimum(x, x + dx), np.maximum(x, x + dx)
    mask = (np.arange(mesh.n) % 3 == 0) if masked else None
    ref = cloth.cloth_candidate_rows(mesh, lo, hi, 0.02, mask)
    runs = [cloth.cloth_candidate_rows(mesh, lo, hi, 0.02, mask, ordered=False)]
    monkeypatch.setattr(cloth, "QUERY_WEIGHT", 10**9)  # every search parallel where threads exist
    runs.append(cloth.cloth_candidate_rows(mesh, lo, hi, 0.02, mask, ordered=False))
    memo = {}
    cloth.cloth_candidate_rows(mesh, lo - 0.01, hi + 0.01, 0.02, memo=memo, ordered=False)
    runs.append(cloth.cloth_candidate_rows(mesh, lo, hi, 0.02, mask, memo=memo, ordered=False))
    for got in runs:
        for a, b in zip(ref, got):
            assert len(a) > 100
            np.testing.assert_array_equal(_in_key_order(b), a)
    assert not np.array_equal(runs[0][1][:, :4], ref[1])
    for a, b in zip(runs[0], runs[1]):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("edge", [False, True])
def test_the_stages_keep_the_pairs_of_unordered_rows_in_key_order(edge):
    """The proximity tests and the continuous test on unordered rows keep the pairs, and give the results, of
    the sorted rows, in the same order."""
    mesh, x, dx = crumpled(8, n=24, noise=0.005)
    lo, hi = np.minimum(x, x + dx), np.maximum(x, x + dx)
    ordered = cloth.cloth_candidate_rows(mesh, lo, hi, 0.02)[edge]
    unordered = cloth.cloth_candidate_rows(mesh, lo, hi, 0.02, ordered=False)[edge]
    w = np.ones(mesh.n)
    runs = [(cloth.cloth_proximity(x, dx / H, w, None, rows, edge, H, 0.02, 0.04, PARALLEL),
             cloth.cloth_first_contacts(x, dx, rows, edge, 1e-5, F_TOL, BISECTIONS, PARALLEL))
            for rows in (ordered, unordered)]
    assert len(runs[0][0][0]) > 5 and len(runs[0][1][0]) > 5
    for a, b in zip(*runs):
        for u, v in zip(a, b):
            np.testing.assert_array_equal(u, v)


def test_cached_pairs_are_the_numpy_rows():
    """Compiled, CandidateCache.pairs (a search of the call's own boxes) gives the NumPy cache's rows (with their keys,
    in another order), masked or not."""
    mesh, x, dx = crumpled(4)
    ccs = [ClothCollisions(mesh, 0.02, backend=b) for b in ("numpy", "numba")]
    moved = np.zeros(mesh.n, dtype=bool)
    moved[::7] = True
    for mask in (None, moved):
        ref, got = (cc.candidates.pairs(x, dx, 0.02, mask) for cc in ccs)
        assert len(ref[0]) > 0 and len(ref[1]) > 0
        for a, b in zip(ref, got):
            np.testing.assert_array_equal(a, _in_key_order(b))


def test_pairs_agree_as_the_cache_is_reused_grown_and_searched_again():
    """Over a sequence of motions (the cache reused, grown around a few vertices, searched again) the rows agree."""
    mesh, x, dx = crumpled(9)
    rng = np.random.default_rng(9)
    ccs = [ClothCollisions(mesh, 0.02, backend=b) for b in ("numpy", "numba")]
    for step in range(12):  # a loop over steps: small moves, a few fast vertices, then everything
        move = np.zeros_like(x)
        if step % 4 == 1:
            move[rng.choice(mesh.n, 5)] = 0.05 * rng.standard_normal((5, 3))
        elif step % 4 == 3:
            move = 0.02 * rng.standard_normal(x.shape)
        x = np.ascontiguousarray(x + move + 0.1)  # and a common translation
        ref, got = (cc.candidates.pairs(x, 0.2 * dx, 0.02) for cc in ccs)
        for a, b in zip(ref, got):
            np.testing.assert_array_equal(a, _in_key_order(b))
    assert ccs[0].searches == ccs[1].searches > 1


@pytest.mark.parametrize("edge", [False, True])
def test_closest_points_agree(edge):
    """Distances, normals and weights of the compiled closest points agree with proximity's to 1e-12."""
    mesh, x, _ = crumpled(5)
    lo, hi = x, x
    iv, jf, ie, je = candidates_in_boxes(mesh, lo, hi, 0.05)
    rows = np.concatenate([mesh.edges[ie], mesh.edges[je]], axis=1) if edge else \
        np.concatenate([iv[:, None], mesh.faces[jf]], axis=1)
    p = x[rows]
    ref = (edge_edge_kernel if edge else vertex_face_kernel)(p[:, 0], p[:, 1], p[:, 2], p[:, 3])
    distance, normal, weights = cloth.cloth_closest(x, rows, edge, PARALLEL)
    np.testing.assert_allclose(distance, ref.distance, rtol=0, atol=1e-12)
    np.testing.assert_allclose(normal, ref.normal, rtol=0, atol=1e-12)
    np.testing.assert_allclose(weights, ref.weights, rtol=0, atol=1e-12)


@pytest.mark.parametrize("edge", [False, True])
@pytest.mark.parametrize("scale", [1.0, 1.0 - 1e-12, 1.0 + 1e-12, 1.5, 2.0])
def test_rest_verdicts_are_the_closest_points_ones(edge, scale):
    """Pairs of a flat grid at rest, and the grid's own distances as rest_distance (ties, and a hair either
    side): the box-gap shortcut of rest_far gives the verdict of comparing the closest points' distance."""
    from particles.collisions.contact_kernels import rest_far  # noqa: PLC0415

    n = 8
    mesh = TriangleMesh.grid(n, n)
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    xr = np.ascontiguousarray(np.stack([u.ravel(), v.ravel(), np.zeros(n * n)], axis=1))
    iv, jf, ie, je = candidates_in_boxes(mesh, xr, xr, 0.5)  # most pairs of the sheet, near and far
    rows = np.concatenate([mesh.edges[ie], mesh.edges[je]], axis=1) if edge else \
        np.concatenate([iv[:, None], mesh.faces[jf]], axis=1)
    spacing = 1.0 / (n - 1)
    distance, _, _ = cloth.cloth_closest(xr, rows, edge, PARALLEL)
    rest_distance = scale * spacing
    got = np.array([rest_far(xr, rows, k, edge, rest_distance, PARALLEL) for k in range(len(rows))])
    np.testing.assert_array_equal(got, distance >= rest_distance)
    assert got.any() and not got.all()
    assert np.any(np.abs(distance - spacing) <= 1e-15)  # ties with the rest distance are among them


@pytest.mark.parametrize("edge", [False, True])
def test_closest_points_at_zero_distance_take_numpys_fallback_normals(edge):
    """Pairs that touch: the normal falls back to the face's (the edges' cross product), and for a flat
    triangle (parallel edges) to a perpendicular, as in proximity's kernels; a unit vector in every case."""
    if edge:  # crossing edges; collinear overlapping edges; a point-like edge on another
        pairs = [[[0, 0, 0], [1, 0, 0], [0.5, -1, 0], [0.5, 1, 0]],
                 [[0, 0, 0], [1, 1, 0], [0.5, 0.5, 0], [2, 2, 0]],
                 [[0.5, 0.5, 0], [0.5, 0.5, 0], [0, 0, 0], [1, 1, 0]]]
    else:  # a vertex inside a face; a vertex on a flat (collinear) triangle; one at a corner
        pairs = [[[0.2, 0.2, 0], [0, 0, 0], [1, 0, 0], [0, 1, 0]],
                 [[0.5, 0.5, 0], [0, 0, 0], [1, 1, 0], [2, 2, 0]],
                 [[0, 0, 0], [0, 0, 0], [1, 0, 0], [0, 1, 0]]]
    x = np.array(pairs, dtype=float).reshape(-1, 3)
    rows = np.arange(len(x)).reshape(-1, 4)
    p = x[rows]
    ref = (edge_edge_kernel if edge else vertex_face_kernel)(p[:, 0], p[:, 1], p[:, 2], p[:, 3])
    distance, normal, weights = cloth.cloth_closest(x, rows, edge, PARALLEL)
    assert np.all(distance == 0) and np.all(ref.distance == 0)
    np.testing.assert_allclose(normal, ref.normal, rtol=0, atol=1e-12)
    np.testing.assert_allclose(weights, ref.weights, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(normal, axis=1), 1.0, rtol=0, atol=1e-12)
    assert abs(normal[0, 2]) == 1.0  # the face's normal, the edges' cross product: e_z
    assert normal[1, 2] == 0.0  # perpendicular to the line (1, 1, 0), in the plane z = 0


@pytest.mark.parametrize("edge", [False, True])
def test_first_contacts_give_the_same_verdicts(edge):
    """The compiled cubic finds the same colliding pairs, times, normals and weights as ccd.first_contacts."""
    mesh, x, dx = crumpled(6, noise=0.03)
    dx = 4 * dx
    iv, jf, ie, je = candidates_in_boxes(mesh, np.minimum(x, x + dx), np.maximum(x, x + dx), 1e-4)
    rows = np.concatenate([mesh.edges[ie], mesh.edges[je]], axis=1) if edge else \
        np.concatenate([iv[:, None], mesh.faces[jf]], axis=1)
    ref = first_contacts(x[rows], dx[rows], edge, 1e-5)
    got_rows, W, N_, T = cloth.cloth_first_contacts(x, dx, rows, edge, 1e-5, F_TOL, BISECTIONS, PARALLEL)
    assert len(ref) > 5
    np.testing.assert_array_equal(got_rows, rows[ref.vertices[:, 0]])
    np.testing.assert_allclose(T, ref.time, rtol=0, atol=1e-12)
    np.testing.assert_allclose(N_, ref.normal, rtol=0, atol=1e-12)
    np.testing.assert_allclose(W, ref.weights, rtol=0, atol=1e-12)


def fold(backend, steps, n=N):
    """A sheet dropped upright on a floor, folding onto itself; the states and the results of each step."""
    c = cloth_system(n, n, width=1.0, height=1.0, plane="vertical", origin=(-0.5, 0.0, 0.4), pins=None,
                     scaling="physical", stretch_modulus=200.0, damping=0.2)
    X = c.state()
    X[:, 0, 1] += 0.05 * np.sin(np.pi * (X[:, 0, 0] + 0.5)) * (0.4 - X[:, 0, 2])
    c.set_state(np.asfortranarray(X))
    mesh = TriangleMesh.grid(n, n)
    cc = ClothCollisions.from_system(c, mesh, thickness=0.5 / (n - 1), bodies=[Plane([0, 0, 0], [0, 0, 1.0])],
                                     friction=0.3, backend=backend)
    step = cc.stepper(XPBD.from_system(c, substeps=4, backend="numpy"))
    states = []
    for _ in range(steps):  # a loop over time steps
        c.run(c.t + H, H, method=step)
        states.append(c.X[:, 0].copy())
    return mesh, states, cc.history


def test_a_fold_never_crosses_itself():
    """Compiled, a sheet folding on a floor has zero crossing triangle pairs at every step (the exact test)."""
    mesh, states, history = fold("numba", 40)
    assert sum(r.proximity for r in history) > 0
    for x in states:  # a loop over steps
        assert len(intersections(x, mesh.faces)) == 0


@pytest.mark.parametrize("i", [0, 3, 8])
def test_one_step_agrees_with_numpy(i):
    """From the same state, a compiled step's treatment matches NumPy's: same counts, positions to 1e-12 m."""
    mesh, states, _ = fold("numpy", 10)
    x0, x1 = states[i], states[i] + 2.0 * (states[i + 1] - states[i])  # faster than the fold: more contacts
    v1 = (x1 - x0) / H
    out = []
    for backend in ("numpy", "numba"):
        cc = ClothCollisions(mesh, 0.5 / (N - 1), m=1.0 / N ** 2, bodies=[Plane([0, 0, 0], [0, 0, 1.0])],
                             friction=0.3, x_rest=states[0], backend=backend)
        out.append((*cc.resolve(x0, x1, v1, 0.0, H), cc.last))
    (xa, va, ra), (xb, vb, rb) = out
    assert ra.proximity > 0 and ra == rb
    np.testing.assert_allclose(xb, xa, rtol=0, atol=1e-12)
    np.testing.assert_allclose(vb, va, rtol=0, atol=1e-10)


BODIES = {"none": [], "floor": [Plane([0, 0, -0.02], [0, 0, 1.0])],
          "floor and ball": [Plane([0, 0, -0.02], [0, 0, 1.0]), Sphere([0.5, 0.5, -0.3], 0.31)],
          "union (NumPy's pass)": [Plane([0, 0, -0.02], [0, 0, 1.0]) | Sphere([0.5, 0.5, -0.3], 0.31)],
          "moving (NumPy's pass)": [MovingSurface(Plane([0, 0, -0.02], [0, 0, 1.0]), velocity=[0.0, 0.1, 0.0])]}


@pytest.mark.parametrize("part_min", [cloth.JACOBI_PART_MIN, 16])
@pytest.mark.parametrize("bodies", list(BODIES))
def test_the_jacobi_iterations_agree_with_numpy(bodies, part_min, monkeypatch):
    """The compiled proximity iterations, bodies' pass included, change vbar as ClothCollisions' NumPy ones do,
    with each vertex's terms summed in one slice of the active contacts or in slices of 16."""
    monkeypatch.setattr(cloth, "JACOBI_PART_MIN", part_min)
    mesh, x, dx = crumpled(8)
    dx[:, 2] -= 0.04  # towards the bodies
    out = []
    for backend in ("numpy", "numba"):
        cc = ClothCollisions(mesh, 0.03, m=np.linspace(1.0, 2.0, mesh.n), pinned=[0], friction=0.3,
                             bodies=BODIES[bodies], iterations=20, backend=backend)
        vbar = np.ascontiguousarray(dx / H)
        contacts = ClothCollisions(mesh, 0.03, backend="numpy")._proximity_contacts(x, vbar, H)
        touched = cc._proximity(contacts, x, vbar, 0.0, H)
        out.append((touched, vbar, len(contacts[0])))
    (ta, va, k), (tb, vb, _) = out
    assert ta == tb > 10 and k > ta
    assert np.abs(va - dx / H).max() > 0.1  # the impulses changed something
    np.testing.assert_allclose(vb, va, rtol=0, atol=1e-12 * np.abs(va).max())
    assert part_min == cloth.JACOBI_PART_MIN or k > 2 * part_min  # the small slices were used


SMALL_BALL = [Sphere([0.5 + 0.5 / (N - 1), 0.5 + 0.3 / (N - 1), 0.0], 0.03)]  # between two vertices of the sheet


@pytest.mark.parametrize("bodies", ["floor and ball", "small ball", "union (NumPy's pass)"])
def test_the_body_pass_agrees_with_numpy(bodies):
    """Compiled, the bodies' pass (vertices, then edge samples) moves the sheet as NumPy's does, with its counts."""
    mesh, x, dx = crumpled(8)
    dx[:, 2] -= 0.04
    shapes = dict(BODIES, **{"small ball": SMALL_BALL})[bodies]
    out = []
    for backend in ("numpy", "numba"):
        cc = ClothCollisions(mesh, 0.03, m=np.linspace(1.0, 2.0, mesh.n), pinned=[0], friction=0.3, bodies=shapes,
                             backend=backend)
        vbar = np.ascontiguousarray(dx / H)
        out.append((cc._bodies(x, vbar, 0.0, H), vbar))
    (ca, va), (cb, vb) = out
    assert ca == cb and ca[0] > 0 and ca[1] > 0  # vertices and edge samples moved out
    assert np.abs(va - dx / H).max() > 1.0
    np.testing.assert_allclose(vb, va, rtol=0, atol=1e-12 * np.abs(va).max())


def test_the_jacobi_iterations_stop_when_no_contact_is_active():
    """With a large tolerance no contact is active: no iteration runs and vbar is left as it was."""
    mesh, x, dx = crumpled(8)
    vbar = np.ascontiguousarray(dx / H)
    V, W, N_, D = ClothCollisions(mesh, 0.03, backend="numpy")._proximity_contacts(x, vbar, H)
    before = vbar.copy()
    w = np.ones(mesh.n)
    target = np.zeros(len(V))
    done, touched, _ = cloth.cloth_impulses(vbar, x, V, W, N_, np.ones(len(V)), target, w, H, 1e3, 0.3, 50, 0.03)
    assert done == 0 and not touched.any()
    assert vbar.tobytes() == before.tobytes()


def test_jacobi_iterations_one_call_at_a_time_give_the_bits_of_one_call():
    """The pipeline calls the kernel one iteration at a time when the bodies are not primitives at rest:
    with `start` counting the iterations made, the over-relaxation starts where one call of all of them
    starts it, and the bits are the same."""
    mesh, x, dx = crumpled(8)
    dx[:, 2] -= 0.04
    vbar = np.ascontiguousarray(dx / H)
    V, W, N_, D = ClothCollisions(mesh, 0.03, backend="numpy")._proximity_contacts(x, vbar, H)
    S, target, w = np.sum(W ** 2, axis=1), np.where(D < 0.03, 0.1 * (0.03 - D), 0.03 - D) / H, np.ones(mesh.n)
    args = (x, V, W, N_, S, target, w, H, 3e-4, 0.3)
    whole = vbar.copy()
    done, _, _ = cloth.cloth_impulses(whole, *args, 12, 0.03, None, 2.0)
    steps = vbar.copy()
    for it in range(12):  # a loop over iterations, as the pipeline's
        cloth.cloth_impulses(steps, *args, 1, 0.03, None, 2.0, it)
    assert done > 2  # several iterations, relaxed after the first
    assert steps.tobytes() == whole.tobytes()
    plain = vbar.copy()
    cloth.cloth_impulses(plain, *args, 12, 0.03, None, 1.0)
    assert np.abs(plain - whole).max() > 1e-3  # the relaxation changes the outcome


def test_same_bits_on_one_and_two_threads():
    """The compiled stages give the same bits on one thread and on two (fixed partitions, no atomics)."""
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("one thread only")
    mesh, x, dx = crumpled(7, n=40)
    lo, hi = np.minimum(x, x + dx), np.maximum(x, x + dx)
    rows_of = lambda k: np.concatenate([k[0][:, None], mesh.faces[k[1]]], axis=1)  # noqa: E731
    before = numba.get_num_threads()
    out = []
    try:
        for threads in (1, 2):
            numba.set_num_threads(threads)
            from particles.collisions.broad_kernels import box_candidates  # noqa: PLC0415  (the parallel one)
            from particles.collisions.contact_kernels import first_contact_pairs  # noqa: PLC0415
            k = cloth.cloth_candidates(mesh, lo, hi, 0.01)
            v_lo, v_hi = lo - 0.01, hi + 0.01
            f_lo, f_hi = np.empty((mesh.m, 3)), np.empty((mesh.m, 3))
            from particles.collisions.broad_kernels import corner_bounds  # noqa: PLC0415
            corner_bounds(v_lo, v_hi, mesh.faces, f_lo, f_hi)
            keys = [box_candidates(v_lo, v_hi, f_lo, f_hi, cloth._own(mesh.n), mesh.faces, False, ordered)
                    for ordered in (True, False)]
            rows = rows_of(k)
            hit, t = np.empty(len(rows), dtype=bool), np.full(len(rows), np.nan)
            nrm, w = np.full((len(rows), 3), np.nan), np.full((len(rows), 4), np.nan)
            first_contact_pairs(x, 4 * dx, rows, False, 1e-5, F_TOL, BISECTIONS, PARALLEL, hit, t, nrm, w)
            out.append((*keys, hit, t[hit], nrm[hit], w[hit]))
    finally:
        numba.set_num_threads(before)
    for a, b in zip(*out):
        assert a.tobytes() == b.tobytes()


def test_the_jacobi_iterations_give_the_same_bits_on_one_and_two_threads(monkeypatch):
    """The proximity iterations (each vertex's terms summed in slices of the active contacts) give the same bits
    on one thread and on two."""
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("one thread only")
    import particles.backends.compile as kernels  # noqa: PLC0415

    monkeypatch.setattr(kernels, "PARALLEL_MIN", 0)  # every loop parallel, however small
    monkeypatch.setattr(cloth, "JACOBI_PART_MIN", 16)  # the sums in slices
    mesh, x, dx = crumpled(7, n=40)
    dx[:, 2] -= 0.04
    vbar = np.ascontiguousarray(dx / H)
    V, W, N_, D = ClothCollisions(mesh, 0.03, backend="numpy")._proximity_contacts(x, vbar, H)
    S, target, w = np.sum(W ** 2, axis=1), np.where(D < 0.03, 0.1 * (0.03 - D), 0.03 - D) / H, np.ones(mesh.n)
    rows = (np.array([0]), np.array([[0.0, 0.0, 1.0, 0.02] + [0.0] * 9]))  # a floor at z = -0.02
    before = numba.get_num_threads()
    out = []
    try:
        for threads in (1, 2):
            numba.set_num_threads(threads)
            v = vbar.copy()
            done, touched, _ = cloth.cloth_impulses(v, x, V, W, N_, S, target, w, H, 3e-4, 0.3, 30, 0.03, rows, 2.0)
            out.append((done, touched.sum(), v.tobytes()))
    finally:
        numba.set_num_threads(before)
    assert out[0][0] > 1 and out[0][1] > 100
    assert out[0] == out[1]
