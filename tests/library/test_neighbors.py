"""Bucket-grid pair search against the all-pairs reference, and the Verlet list."""

import numpy as np
import pytest

from particles.neighbors import CellGrid, VerletList, all_pairs, cell_pairs


def as_set(i, j):
    return set(zip(np.minimum(i, j).tolist(), np.maximum(i, j).tolist()))


@pytest.mark.parametrize("d", [1, 2, 3])
@pytest.mark.parametrize("k", [1, 2, 3])
def test_cell_pairs_equal_all_pairs(d, k):
    """Same set of pairs, each unordered pair once, in 1, 2 and 3 dimensions."""
    rng = np.random.default_rng(d * 10 + k)
    x = rng.uniform(0, 10, size=(400, d))
    i, j = cell_pairs(x, 1.3, cells_per_cutoff=k)
    assert np.all(i != j)
    assert len(as_set(i, j)) == len(i)  # no duplicates
    assert as_set(i, j) == as_set(*all_pairs(x, 1.3))
    assert len(i) > 0


def test_strict_cutoff_and_cell_boundaries():
    """Pairs at exactly the cutoff are excluded; a hair closer included; faces are safe."""
    cut = 1.0
    x = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 0.5], [0.5, 0.5 + (1 - 1e-12)], [3.0, 3.0], [3.5, 3.0]])
    found = as_set(*cell_pairs(x, cut))
    assert (0, 1) not in found and (2, 3) in found and (4, 5) in found
    # every particle on a cell face (spacing = cell size = cutoff / 2)
    g = np.arange(8) * 0.5
    lattice = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2)
    assert as_set(*cell_pairs(lattice, cut)) == as_set(*all_pairs(lattice, cut))


def test_outliers_and_explicit_bounds_are_clamped_exactly():
    """Particles beyond the grid land in edge cells and still find their partners."""
    rng = np.random.default_rng(0)
    bulk = rng.uniform(0, 5, size=(300, 3))
    far = np.array([[1e5, 0, 0], [1e5 + 0.5, 0, 0], [-1e5, 3, 3], [-1e5, 3.2, 3.1]])
    x = np.concatenate([bulk, far])
    ref = as_set(*all_pairs(x, 1.0))
    assert as_set(*cell_pairs(x, 1.0)) == ref
    # a grid deliberately smaller than the cloud: most particles clamped
    grid = CellGrid(x, 1.0, bounds=([1.0, 1.0, 1.0], [2.0, 2.0, 2.0]))
    assert as_set(*grid.pairs()) == ref


def test_sparse_points_get_larger_cells_and_stay_exact():
    """A few points spread over a huge box do not allocate a huge grid."""
    rng = np.random.default_rng(1)
    x = rng.uniform(0, 1e4, size=(50, 3))
    x[1] = x[0] + [0.3, 0.0, 0.0]
    grid = CellGrid(x, 1.0)
    assert np.prod(grid.shape) < 1e6
    assert as_set(*grid.pairs()) == as_set(*all_pairs(x, 1.0)) == {(0, 1)}


def test_grid_sorts_particles_by_cell():
    """order/start describe each cell's particles as a contiguous slice."""
    rng = np.random.default_rng(2)
    x = rng.uniform(0, 4, size=(100, 2))
    grid = CellGrid(x, 1.0, cells_per_cutoff=1)
    counts = np.diff(grid.start)
    assert counts.sum() == 100
    cells = np.floor((x - x.min(axis=0)) / grid.cell_size).astype(int) + 1
    for c in np.flatnonzero(counts)[:10]:
        members = grid.order[grid.start[c]:grid.start[c + 1]]
        keys = cells[members] @ grid.strides
        assert np.all(keys == c)


def test_tiny_inputs():
    """No particles or one give no pairs; coincident particles are all pairs."""
    assert [len(a) for a in cell_pairs(np.zeros((0, 2)), 1.0)] == [0, 0]
    assert [len(a) for a in cell_pairs(np.zeros((1, 3)), 1.0)] == [0, 0]
    i, j = cell_pairs(np.zeros((3, 2)), 1.0)  # coincident points interact
    assert as_set(i, j) == {(0, 1), (0, 2), (1, 2)}


def test_bad_arguments():
    """A bad cutoff, cell count, shape or bounds is refused by name."""
    with pytest.raises(ValueError, match="cutoff must be a positive finite number"):
        cell_pairs(np.zeros((2, 2)), 0.0)
    with pytest.raises(ValueError, match="cells_per_cutoff must be a positive integer"):
        cell_pairs(np.zeros((2, 2)), 1.0, cells_per_cutoff=0)
    with pytest.raises(ValueError, match="x must have 2 dimensions"):
        cell_pairs(np.zeros(5), 1.0)
    with pytest.raises(ValueError, match="bounds must be"):
        CellGrid(np.zeros((2, 2)), 1.0, bounds=([1, 1], [0, 0]))


def test_verlet_list_rebuilds_only_when_needed():
    """Rebuilt when some particle moved more than skin/2, or when n changes."""
    rng = np.random.default_rng(3)
    x = rng.uniform(0, 10, size=(200, 2))
    vl = VerletList(cutoff=1.0, skin=0.4)
    i, j = vl.pairs(x)
    assert vl.builds == 1
    assert as_set(i, j) == as_set(*all_pairs(x, 1.4))
    y = x.copy()
    y[5] += [0.19, 0.0]
    vl.pairs(y)
    assert vl.builds == 1
    y[5] += [0.02, 0.0]  # now 0.21 > skin / 2
    vl.pairs(y)
    assert vl.builds == 2
    vl.pairs(y[:-1])
    assert vl.builds == 3
    vl.reset()
    vl.pairs(y[:-1])
    assert vl.builds == 4


def test_verlet_list_does_not_rebuild_on_non_finite_positions():
    """inf/NaN positions (a blow-up mid-step) return the stored pairs, or none, instead of raising."""
    x = np.array([[0.0, 0.0], [0.5, 0.0], [3.0, 0.0]])
    vl = VerletList(cutoff=1.0, skin=0.2)
    assert as_set(*vl.pairs(x)) == {(0, 1)}
    y = x.copy()
    y[1] = np.inf
    assert as_set(*vl.pairs(y)) == {(0, 1)} and vl.builds == 1
    y[1] = np.nan
    assert as_set(*vl.pairs(y)) == {(0, 1)} and vl.builds == 1
    assert as_set(*vl.pairs(x)) == {(0, 1)} and vl.builds == 1  # the reference positions are kept
    fresh = VerletList(cutoff=1.0, skin=0.2)
    i, j = fresh.pairs(y)
    assert len(i) == len(j) == 0 and fresh.builds == 0
    i, j = vl.pairs(y[:2])  # another number of particles: the stored pairs do not fit
    assert len(i) == 0
    with pytest.raises(ValueError, match="x must be finite"):
        cell_pairs(y, 1.0)  # the grid itself still refuses them


# -- periodic boxes ------------------------------------------------------------


@pytest.mark.parametrize("d", [1, 2, 3])
@pytest.mark.parametrize("k", [1, 2, 3])
def test_periodic_cell_pairs_equal_minimum_image_all_pairs(d, k):
    """In a box, the grid finds exactly the minimum-image pairs, each once, for unwrapped positions."""
    rng = np.random.default_rng(100 + 10 * d + k)
    for sides in ([2.0] * d, rng.uniform(2.0, 5.0, d)):  # the smallest box allowed, and others
        L = 1.3 * np.array(sides)
        x = rng.uniform(-2, 3, size=(250, d)) * L  # anywhere: the grid wraps a copy
        i, j = cell_pairs(x, 1.3, cells_per_cutoff=k, box=L)
        assert np.all(i != j) and len(as_set(i, j)) == len(i) > 0
        assert as_set(i, j) == as_set(*all_pairs(x, 1.3, box=L))


def test_periodic_pairs_through_the_walls():
    """Two points near opposite faces are neighbours; positions shifted by whole boxes change nothing."""
    x = np.array([[0.1, 5.0], [9.9, 5.0], [5.0, 0.2], [5.0, 9.7], [5.0, 5.0]])
    assert as_set(*cell_pairs(x, 1.0, box=10.0)) == {(0, 1), (2, 3)}
    moved = x + np.array([[10.0, 0.0], [-20.0, 30.0], [0.0, 0.0], [0.0, -10.0], [40.0, 40.0]])
    assert as_set(*cell_pairs(moved, 1.0, box=10.0)) == {(0, 1), (2, 3)}
    assert as_set(*cell_pairs(x, 1.0)) == set()  # open space: far apart


def test_periodic_lattice_on_cell_faces_and_sparse_box():
    """Points exactly on cell faces, and a few points in a huge box (fewer, larger cells), stay exact."""
    g = np.arange(8) * 0.5
    lattice = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    for k in (1, 2, 3):
        i, j = cell_pairs(lattice, 1.0, cells_per_cutoff=k, box=4.0)
        assert len(i) == 512 * 26 // 2  # 6 + 12 + 8 neighbours closer than 1 each
    rng = np.random.default_rng(4)
    x = rng.uniform(0, 1e4, size=(40, 3))
    x[1], x[3] = x[0] + [0.3, 0.0, 0.0], [1e4 - 0.1, 5.0, 5.0]
    x[2] = [0.2, 5.0, 5.1]
    grid = CellGrid(x, 1.0, box=1e4)
    assert np.prod(grid.shape) < 1e5
    assert as_set(*grid.pairs()) == as_set(*all_pairs(x, 1.0, box=1e4)) == {(0, 1), (2, 3)}


def test_ranked_pairs_are_the_pairs_in_cell_order():
    """pairs(ranks=True) gives a permutation and ranks whose pairs are those of pairs()."""
    rng = np.random.default_rng(5)
    x = rng.uniform(0, 6, size=(300, 3))
    for box in (None, 6.0):
        grid = CellGrid(x, 1.2, box=box)
        perm, i, j = grid.pairs(ranks=True)
        assert sorted(perm.tolist()) == list(range(300))
        a, b = grid.pairs()
        np.testing.assert_array_equal(perm[i], a)
        np.testing.assert_array_equal(perm[j], b)


@pytest.mark.parametrize("box, match", [
    (0.0, "box must hold positive finite side lengths"),
    ([3.0, -1.0], "box must hold positive finite side lengths"),
    ([3.0, np.inf], "box must hold positive finite side lengths"),
    ([3.0, 3.0, 3.0], "box must have 2 side lengths"),
    ([3.0, 1.9], r"box must be at least 2 x cutoff = 2 m along every axis"),
])
def test_bad_boxes_are_refused_by_name(box, match):
    """A box that is not positive, has the wrong length, or is shorter than 2 cutoffs raises naming box."""
    with pytest.raises(ValueError, match=match):
        cell_pairs(np.zeros((3, 2)), 1.0, box=box)
    with pytest.raises(ValueError, match=match):
        all_pairs(np.zeros((3, 2)), 1.0, box=box)


def test_box_and_bounds_exclude_each_other_and_the_list_checks_its_skin():
    """bounds and box together are refused; a Verlet list needs a box of 2 (cutoff + skin)."""
    with pytest.raises(ValueError, match="not both"):
        CellGrid(np.zeros((2, 2)), 1.0, bounds=([0, 0], [1, 1]), box=5.0)
    with pytest.raises(ValueError, match=r"box must be at least 2 x \(cutoff \+ skin\) = 2.6 m"):
        VerletList(cutoff=1.0, skin=0.3, box=2.5)
    VerletList(cutoff=1.0, skin=0.3, box=2.6)


def test_periodic_verlet_list_stores_the_images():
    """The list's minimum_image maps x_i - x_j to the nearest copy, also after moves and for chunks."""
    from particles.forces import pair_differences
    from particles.md import minimum_image

    rng = np.random.default_rng(6)
    L = np.array([5.0, 6.0, 7.0])
    x = rng.uniform(0, 1, size=(400, 3)) * L
    vl = VerletList(cutoff=1.0, skin=0.4, box=L)
    for step in range(3):
        i, j = vl.pairs(x)
        r = pair_differences(x, i, j)
        expected = minimum_image(r, L, axis=0)
        np.testing.assert_allclose(vl.minimum_image(r.copy()), expected, atol=1e-12)
        half = len(i) // 2  # a chunk of the list: pairs half:
        np.testing.assert_allclose(vl.minimum_image(r[:, half:].copy(), half, len(i)), expected[:, half:],
                                   atol=1e-12)
        x = x + rng.uniform(-0.05, 0.05, x.shape)  # small moves: the list and its images stay
    assert vl.builds == 1
    assert as_set(*vl.pairs(x)) >= as_set(*all_pairs(x, 1.0, box=L))
