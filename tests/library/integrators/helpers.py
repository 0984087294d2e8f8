"""Helpers of the stepper and loop tests: the steppers by kind, and independent oscillators."""

import numpy as np

from particles.integrators import INTEGRATORS

ALL = list(INTEGRATORS)
GENERIC = [name for name, s in INTEGRATORS.items() if not s.second_order_layout]
SECOND_ORDER_LAYOUT = ["symplectic_euler", "verlet"]


def oscillator_f(omega):
    """x'' = -omega^2 x for a vector of independent oscillators, layout (n, 2, 1)."""
    w2 = np.asarray(omega, dtype=float)[:, None] ** 2

    def f(X, t):
        return np.stack([X[:, 1], -w2 * X[:, 0]], axis=1)

    return f
