"""The driven oscillator test problem (used by the autograder's hidden tests): exact, and usable."""

import numpy as np
import pytest

from particles.problems import forced_oscillator, get_problem
from particles.studies import convergence_study


def test_exact_solution_satisfies_the_ode():
    """x(t) of the exact solution satisfies x'' = -w^2 x + A cos(W t) (centred differences) and v = x'."""
    p = forced_oscillator(omega=1.7, amplitude=0.8, frequency=0.6, x0=0.3, v0=-0.2)
    t, dt = np.linspace(0.1, 4.0, 9), 1e-4
    x = lambda s: p.exact(s)[0, 0, 0]  # noqa: E731
    for s in t:
        acc = (x(s + dt) - 2 * x(s) + x(s - dt)) / dt**2
        assert acc == pytest.approx(-1.7**2 * x(s) + 0.8 * np.cos(0.6 * s), abs=1e-5)
        assert (x(s + dt) - x(s - dt)) / (2 * dt) == pytest.approx(p.exact(s)[0, 1, 0], abs=1e-7)
    assert np.allclose(p.exact(0.0), [[[0.3], [-0.2]]])


def test_steppers_reach_their_order_on_a_time_dependent_problem():
    """Euler, midpoint and RK4 converge with orders 1, 2 and 4 although f depends on t."""
    study = convergence_study(get_problem("forced_oscillator", omega=2.0, frequency=0.7),
                              methods=["euler", "midpoint", "rk4"], n_steps=[100, 200, 400, 800])
    for method, expected in (("euler", 1), ("midpoint", 2), ("rk4", 4)):
        assert study["order"][method] == pytest.approx(expected, abs=0.1)


def test_resonance_is_refused():
    """Driving at the natural frequency has no bounded solution: a ValueError names the argument."""
    with pytest.raises(ValueError, match="frequency must differ from omega"):
        forced_oscillator(omega=2.0, frequency=2.0)
