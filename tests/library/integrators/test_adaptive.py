"""Step doubling (particles.integrators.adaptive): the error estimate, the adapted steps, the cost, the checks."""

import numpy as np
import pytest

from particles import ConvergenceError
from particles.integrators import INTEGRATORS, integrate, step_doubling


def kepler(X, t):
    """A body around a sun of G M = 1 at the origin: X of shape (1, 2, 2)."""
    x = X[:, 0]
    r = np.linalg.norm(x, axis=1)[:, None]
    return np.stack([X[:, 1], -x / r**3], axis=1)


def orbit(e):
    """The start at aphelion of the orbit of semi-major axis 1 and eccentricity e (period 2 pi)."""
    return np.array([[[1.0 + e, 0.0], [0.0, np.sqrt((1.0 - e) / (1.0 + e))]]])


def test_the_estimate_is_the_error_of_the_two_half_steps():
    """On x' = -x, the estimate |X_small - X_big| / (2^p - 1) of one try matches the true error of the two half
    steps within 5% (Richardson), for Euler, midpoint and RK4."""
    for name in ("euler", "midpoint", "rk4"):
        step, h = INTEGRATORS[name], 0.01
        f = lambda X, t: -X
        big = step(f, np.array([1.0]), 0.0, h)
        small = step(f, step(f, np.array([1.0]), 0.0, h / 2), h / 2, h / 2)
        estimate = abs(small - big)[0] / (2**step.order - 1)
        assert estimate == pytest.approx(abs(small[0] - np.exp(-h)), rel=0.05), name


def test_a_close_passage_gets_small_steps_and_the_run_beats_fixed_steps_at_equal_work():
    """On an orbit of eccentricity 0.9, RK4 with step doubling takes its smallest steps at the perihelion and
    returns to its start after a period 1000 times closer than fixed steps with as many evaluations."""
    X0 = orbit(0.9)
    run = step_doubling(kepler, X0, 0.0, 2 * np.pi, tol=1e-6)
    assert run.t[-1] == 2 * np.pi and run.rejected > 0
    r = np.linalg.norm(run.X[:-1, 0, 0], axis=1)
    assert r[np.argmin(run.h)] < 0.2 and run.h.max() > 50 * run.h.min()
    adaptive = np.abs(run.X[-1] - X0).max()
    _, X = integrate(kepler, X0, 0.0, 2 * np.pi, 2 * np.pi / (run.evaluations // 4), method="rk4")
    assert adaptive < 1e-3 * np.abs(X[-1] - X0).max()


def test_a_tighter_tolerance_gives_a_smaller_error_at_more_cost():
    """Dividing tol by 100 divides the error after a period by more than 10 and costs more evaluations."""
    X0 = orbit(0.6)
    runs = [step_doubling(kepler, X0, 0.0, 2 * np.pi, tol=tol) for tol in (1e-5, 1e-7)]
    errors = [np.abs(run.X[-1] - X0).max() for run in runs]
    assert errors[1] < errors[0] / 10 and runs[1].evaluations > runs[0].evaluations


def test_evaluations_are_counted_with_the_rejected_tries():
    """Each try is three steps: with Euler (one evaluation per step) evaluations = 3 x (accepted + rejected)."""
    run = step_doubling(lambda X, t: np.cos(10 * t) * X, [1.0], 0.0, 3.0, tol=1e-4, method="euler")
    assert run.evaluations == 3 * (len(run.t) - 1 + run.rejected)


def test_bad_input_and_an_unreachable_tolerance():
    """Bad tolerances, times and methods are refused by name; a tolerance that the smallest step cannot reach
    raises ConvergenceError."""
    f = lambda X, t: -X
    with pytest.raises(ValueError, match="tol"):
        step_doubling(f, [1.0], 0.0, 1.0, tol=0.0)
    with pytest.raises(ValueError, match="t1 must be > t0"):
        step_doubling(f, [1.0], 1.0, 1.0, tol=1e-6)
    with pytest.raises(ValueError, match="unknown method"):
        step_doubling(f, [1.0], 0.0, 1.0, tol=1e-6, method="rk5")
    with pytest.raises(ConvergenceError, match="smallest step"):
        step_doubling(lambda X, t: 50.0 * X, [1.0], 0.0, 1.0, tol=1e-30, h_min=1e-3)
