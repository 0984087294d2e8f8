"""Helpers of the force tests."""

import numpy as np


def numerical_gradient(energy, x, eps=1e-6):
    """Central-difference gradient of a scalar function of positions (test helper)."""
    grad = np.zeros_like(x)
    for idx in np.ndindex(x.shape):
        e = np.zeros_like(x)
        e[idx] = eps
        grad[idx] = (energy(x + e) - energy(x - e)) / (2 * eps)
    return grad
