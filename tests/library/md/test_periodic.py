"""Periodic boxes: checking a box, wrapping positions, the minimum image."""

import numpy as np
import pytest

from particles.md import box_option, check_box, minimum_image, volume, wrap


def test_wrap_folds_into_the_box_and_keeps_the_input():
    """wrap returns x - L floor(x / L) in [0, L] per axis and leaves x unchanged."""
    rng = np.random.default_rng(0)
    L = np.array([2.0, 3.0, 5.0])
    x = rng.uniform(-20, 20, size=(100, 3))
    x.setflags(write=False)
    y = wrap(x, L)
    assert np.all((y >= 0) & (y <= L))
    np.testing.assert_allclose((x - y) / L, np.round((x - y) / L), atol=1e-12)  # whole boxes apart
    np.testing.assert_array_equal(wrap(y, L), y)


def test_minimum_image_picks_the_nearest_copy_in_either_layout():
    """Each component lands in [-L/2, L/2] and differs from the input by whole box lengths."""
    rng = np.random.default_rng(1)
    L = np.array([4.0, 6.0])
    r = rng.uniform(-30, 30, size=(50, 2))
    m = minimum_image(r, L)
    assert np.all(np.abs(m) <= L / 2 + 1e-12)
    np.testing.assert_allclose((r - m) / L, np.round((r - m) / L), atol=1e-12)
    np.testing.assert_array_equal(minimum_image(r.T, L, axis=0), m.T)
    assert minimum_image([[4.0, -6.0]], 10.0).tolist() == [[4.0, 4.0]]


def test_check_box_broadcasts_a_number_and_checks_the_cutoff():
    """A number is a cube; sides below 2 cutoffs, non-positive or non-finite sides raise naming the box."""
    assert check_box(3.0, 2).tolist() == [3.0, 3.0]
    assert check_box([3.0, 4.0], 2, cutoff=1.5).tolist() == [3.0, 4.0]
    with pytest.raises(ValueError, match=r"box must be at least 2 x cutoff = 3 m"):
        check_box([3.0, 2.9], 2, cutoff=1.5)
    for bad in (0.0, -2.0, np.nan, [1.0, np.inf]):
        with pytest.raises(ValueError, match="box must hold positive finite side lengths"):
            check_box(bad, 2)
    with pytest.raises(ValueError, match="L must have 3 side lengths"):
        check_box([1.0, 2.0], 3, name="L")
    assert box_option(None) is None and box_option(5.0) == 5.0
    assert box_option([5.0, 6.0], cutoff=2.0).tolist() == [5.0, 6.0]


def test_volume_is_the_product_of_the_sides():
    """volume([2, 3, 4]) = 24."""
    assert volume([2.0, 3.0, 4.0]) == 24.0
