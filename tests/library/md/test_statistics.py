"""Block averages: the standard error of a correlated series, against exact results."""

import numpy as np
import pytest

from particles.md import block_average, blocking


def ar1(n, phi, seed):
    """An AR(1) series x_k = phi x_{k-1} + noise, started in its stationary state (test helper)."""
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal(n) * np.sqrt(1 - phi**2)
    x = np.empty(n)
    x[0] = rng.standard_normal()
    for k in range(1, n):  # a loop over time: the series is sequential by definition
        x[k] = phi * x[k - 1] + noise[k]
    return x


def test_block_average_of_a_small_series_by_hand():
    """Two blocks of [1, 3, 2, 4]: means 2 and 3, SE = std([2, 3], ddof=1) / sqrt(2) = 0.5."""
    est = block_average([1.0, 3.0, 2.0, 4.0], blocks=2)
    assert est.mean == 2.5 and est.error == pytest.approx(0.5)
    assert block_average([9.0, 1.0, 3.0, 2.0, 4.0], blocks=2) == est  # the oldest sample is dropped


def test_block_error_of_independent_samples_is_the_naive_one():
    """For white noise, block SE ~ sigma / sqrt(N) (within the scatter of 20 blocks)."""
    x = np.random.default_rng(0).normal(3.0, 2.0, size=40000)
    est = block_average(x, blocks=20)
    assert est.mean == pytest.approx(3.0, abs=4 * 2.0 / 200)
    assert est.error == pytest.approx(2.0 / 200, rel=0.4)


def test_block_error_of_a_correlated_series_is_the_true_one():
    """AR(1), phi = 0.95: blocks find SE = sqrt((1 + phi) / ((1 - phi) N)); the naive SE is 6x too small."""
    phi, n = 0.95, 100000
    x = ar1(n, phi, 1)
    true = np.sqrt((1 + phi) / (1 - phi) / n)
    assert block_average(x, blocks=20).error == pytest.approx(true, rel=0.4)
    lengths, errors = blocking(x)
    assert lengths[0] == 1 and errors[0] == pytest.approx(1 / np.sqrt(n), rel=0.05)  # naive
    assert errors[-4] == pytest.approx(true, rel=0.4)  # the plateau, blocks of 2^k >> correlation time
    assert np.all(np.diff(lengths) > 0)


def test_bad_series_and_block_counts_are_refused_by_name():
    """blocks < 2, blocks > N, non-finite or 2-d samples raise ValueError naming the argument."""
    with pytest.raises(ValueError, match="blocks must be an integer >= 2"):
        block_average([1.0, 2.0, 3.0], blocks=1)
    with pytest.raises(ValueError, match="blocks must be at most the number of samples, 3"):
        block_average([1.0, 2.0, 3.0], blocks=4)
    with pytest.raises(ValueError, match="samples must be finite"):
        block_average([1.0, np.nan, 3.0], blocks=2)
    with pytest.raises(ValueError, match="samples must have 1 dimensions"):
        block_average(np.zeros((3, 2)), blocks=2)
