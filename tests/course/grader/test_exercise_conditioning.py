"""The random cases of an exercise's tests are ones where two correct programs agree far inside the tolerance.

A hidden test draws its inputs at random; a correct submission must pass whatever the draw. Where the graded
quantity is ill-conditioned (a difference of nearly equal numbers), rounding alone can move it by more than
the tolerance, and a right answer fails. These tests take the reference's own computation, add noise of the
size of rounding to every step, and check that the answer moves by at most a hundredth of the tolerance at
the worst corner of each random range.
"""

import importlib.util
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parents[2] / "exercises"


def _exercise_tests(name):
    spec = importlib.util.spec_from_file_location(f"conditioning_{name}", HERE / f"test_{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _rate(t, h, T, rng=None):
    """The damping rate of exercise 06's plucked string, with rounding-sized noise on every step if `rng`."""
    x_rest, m, ij, L0, free, pluck = t._taut()
    k = t.TAUT["k"]
    x, v, N = x_rest + pluck, np.zeros_like(x_rest), round(T / h)
    E_rest = t._energy(x_rest, 0 * x_rest, m, ij, k, L0)
    E0 = t._energy(x, v, m, ij, k, L0) - E_rest
    for _ in range(N):  # a loop over time steps
        x, v = t._reference_step(x, v, h, m, ij, k, L0, 0.0, free)
        if rng is not None:
            x = x * (1 + np.finfo(float).eps * rng.standard_normal(x.shape))
            v = v * (1 + np.finfo(float).eps * rng.standard_normal(v.shape))
    return -np.log((t._energy(x, v, m, ij, k, L0) - E_rest) / E0) / (2 * N * h)


def test_damping_rates_random_cases_are_well_conditioned():
    """Exercise 06: at the longest random duration (0.8 s), rounding moves the rate by < 1e-8 (rtol is 1e-6)."""
    t = _exercise_tests("06_implicit_step")
    rng = np.random.default_rng(3)
    for h in (0.05, 0.1, 0.2):  # the steps where the energy falls fastest
        exact = _rate(t, h, 0.8)
        worst = max(abs(_rate(t, h, 0.8, rng) - exact) / exact for _ in range(4))
        assert worst < 1e-8, f"h = {h}: rounding moves the rate by {worst:.1e}"


def test_the_conditioning_check_sees_an_ill_conditioned_duration():
    """The same check over 2 s (the duration the tests once drew) finds rounding moving the rate beyond 1e-6."""
    t = _exercise_tests("06_implicit_step")
    rng = np.random.default_rng(3)
    exact = _rate(t, 0.1, 2.0)
    worst = max(abs(_rate(t, 0.1, 2.0, rng) - exact) / exact for _ in range(4))
    assert worst > 1e-6
