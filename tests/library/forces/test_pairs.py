"""The kernels of pair interactions (particles.forces.pairs): scattered pair forces."""

import numpy as np

from particles.forces import scatter_pair_forces


def test_scatter_pair_forces_equal_and_opposite_with_repeats():
    """Repeated indices accumulate (unlike F[i] += f) and the total is zero."""
    F = np.zeros((3, 2))
    i, j = np.array([0, 0, 1]), np.array([1, 2, 2])
    f = np.array([[1.0, 0.0], [0.0, 2.0], [3.0, 3.0]])
    scatter_pair_forces(F, i, j, f)
    np.testing.assert_allclose(F, [[1.0, 2.0], [2.0, 3.0], [-3.0, -5.0]])
    np.testing.assert_allclose(F.sum(axis=0), 0.0)
