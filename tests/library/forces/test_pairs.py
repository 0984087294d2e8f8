"""Pair interactions (particles.forces.pairs): differences over pairs, and the laws of one pair."""

import numpy as np

from particles.forces.pairs import gravitational_pull, integer_power, lennard_jones_virial, pair_differences


def test_pair_differences_are_columns_of_x_i_minus_x_j():
    """Column k of pair_differences is x[i[k]] - x[j[k]] (the transpose of the rows' differences)."""
    x = np.random.default_rng(0).normal(size=(6, 3))
    i, j = np.array([0, 3, 5, 5]), np.array([1, 1, 0, 2])
    np.testing.assert_array_equal(pair_differences(x, i, j), (x[i] - x[j]).T)


def test_gravitational_pull_is_newtons_law_softened_and_zero_for_a_particle_and_itself():
    """G m_i m_j / (r^2 + eps^2)^(3/2): 1 / r^3 unsoftened, finite at r = 0 with softening, 0 at r^2 = inf."""
    assert gravitational_pull(2.0, 3.0, 5.0, 4.0, 0.0) == 2.0 * 3.0 * 5.0 / 8.0
    assert gravitational_pull(1.0, 1.0, 1.0, 0.0, 0.25) == 1.0 / 0.125
    assert gravitational_pull(1.0, 1.0, 1.0, np.inf, 0.01) == 0.0


def test_lennard_jones_virial_is_r_times_the_force_law():
    """u^q (k1 u^(p-q) - k2) equals r f(r) = k1 / r^(m-1) - k2 / r^(n-1), for integer and other exponents."""
    r = np.linspace(0.8, 2.5, 7)
    for m, n in ((13, 7), (9.5, 4.5)):
        expected = r * (3.0 / r**m - 2.0 / r**n)
        got = lennard_jones_virial(1.0 / r**2, 3.0, 2.0, (m - 1) / 2, (n - 1) / 2)
        np.testing.assert_allclose(got, expected, rtol=1e-13)
    assert lennard_jones_virial(0.0, 3.0, 2.0, 6.0, 3.0) == 0.0  # beyond the cutoff: no force


def test_integer_powers_are_repeated_products():
    """integer_power multiplies an integer exponent out (the same bits as the product) and falls back to **."""
    u = np.array([0.3, 1.7, 2.0])
    np.testing.assert_array_equal(integer_power(u, 3.0), u * u * u)
    np.testing.assert_allclose(integer_power(u, 2.5), u**2.5, rtol=1e-15)
