"""Autograder tests of exercise 02_stiffness: stability limits measured, implicit Euler, its damping, the cost.

Public tests use the spring of the notebook (k = 100 N/m, m = 1 kg, omega = 10 rad/s); hidden tests draw
stiffnesses, masses, chains and steps from the grading seed (fixture ``rng``). Every expected value comes
from the reference library, computed here in the grader: the theoretical limits and the measurements of
``particles.studies.stability``, ``particles.massspring.string(...).max_stable_step()`` for a chain,
``particles.integrators.implicit_euler`` for the implicit step. A measured limit must pass the blow-up test it
was measured with (for one spring the library's ``stability.blows_up``; for a chain the notebook's test from
x_j = (-1)^j, run here with the library's steppers) and lie at most 3% below the largest step that test lets
pass, with the default length (200 steps) and with short tests (20 steps and fewer), whose limits lie 5-10%
above theory for RK4: an answer computed from theory fails those, the unstable upper end of a bisection's
bracket fails all of them.
"""

import numpy as np
import pytest

from particles.course.grading.expect import expect_array
from particles.course.grading.memo import memoized
from particles.course.worker.runner import GradingFailure, describe_value
from particles.integrators import INTEGRATORS, euler, implicit_euler, symplectic_euler
from particles.massspring import string
from particles.studies import stability

EXERCISE = "02_stiffness"
_MEASURE = "measuring the limit is what this exercise asks; write the blow-up test and the bisection yourself"
FORBIDDEN = {
    "particles.studies.stability.theory_max_step": "it gives the theoretical limit; measure it instead",
    "particles.studies.stability.THEORY_OMEGA_H": "it holds the theoretical limits; measure them instead",
    "particles.studies.stability.blows_up": _MEASURE,
    "particles.studies.stability.max_stable_step": _MEASURE,
    "particles.studies.stability.chain_max_stable_step": _MEASURE,
    "particles.studies.stability.stability_study": _MEASURE,
    "particles.studies.stability.damping_factor": "it is the damping measurement you are asked to write",
    "particles.studies.stability.cost_study": "it is the cost table you are asked to write",
    "particles.integrators.implicit_euler": "it is the implicit step you are asked to write (solve the 2 x 2 system by hand)",
    "particles.integrators.integrate": "it stops a diverging run for you; write the loop and the amplitude test yourself",
    "particles.massspring.string": "its max_stable_step() computes the chain's limit from theory; measure it instead",
}

STABLE = {"symplectic_euler": 2.0, "verlet": 2.0, "rk4": 2.0 * np.sqrt(2.0)}
LIMIT_BELOW = 0.03  # a measured limit may lie up to 3% below the largest step its blow-up test lets pass, not above


def _number(value, call):
    """The float a student's function returned, or a GradingFailure saying what came back."""
    if isinstance(value, np.ndarray) and value.shape == ():
        value = value[()]
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise GradingFailure(f"{call} returned {describe_value(value)}, expected a number (a step in seconds)")
    return float(value)


def _check_limit(got, h_max, unstable, omega, call, test, symbol="omega h", advice="", theory=None):
    """Check a measured step limit: stable in the blow-up test `unstable`, at most LIMIT_BELOW below its limit h_max.

    h_max is the largest step that test lets pass. Messages are in units of `symbol` (omega h, omega_max h);
    `test` names the blow-up test ("the library's 200-step blow-up test"), `advice` ends a message. A step
    equal to the theoretical limit `theory` (s), or 0.9 times the limit, is named as such.
    """
    h = _number(got, call)
    if h == 0.0:
        raise GradingFailure(f"{call} returned 0.0 (no stable step); {test} lets steps up to {symbol} = "
                             f"{omega * h_max:.4g} pass, a real limit: is the step your bisection returned stable, "
                             "and is your check with a longer test too strict (a short test's limit may lie 10% "
                             "above a long test's)?")
    if not np.isfinite(h) or h < 0:
        raise GradingFailure(f"{call} returned {h}, expected a step in seconds > 0")
    ratio = h / h_max
    scale = ""
    if symbol == "omega h" and abs(np.log(omega)) > 1 and abs(np.log(ratio) / np.log(omega) + 1) < 0.05:
        scale = "; your step scales like m/k instead of sqrt(m/k) (use omega = sqrt(k/m))"
    if unstable(h):
        raise GradingFailure(f"{call} returned {symbol} = {omega * h:.4g}, a step that blows up in {test}, which "
                             f"lets steps up to {symbol} = {omega * h_max:.4g} pass: return the largest step known "
                             f"to be stable, the lower end of the bisection's bracket{scale}")
    if not abs(ratio - 1) <= LIMIT_BELOW:
        if not scale and theory is not None and abs(h / theory - 1) <= 2e-3:
            scale = (f"; your step is the theoretical limit {symbol} = {omega * theory:.4g}, not a measurement: run "
                     "your blow-up test with the `steps` you are given and bisect")
        elif not scale and 0.88 <= ratio <= 0.905:
            scale = ("; your step is 0.9 times the limit: return the limit the bisection found, not the smaller "
                     "step your longer test checked")
        raise GradingFailure(f"{call} returned {symbol} = {omega * h:.4g}; {test} lets steps up to {symbol} = "
                             f"{omega * h_max:.4g} pass, and the limit must lie within {100 * LIMIT_BELOW:g}% "
                             f"below that{scale or advice}")


@memoized
def _spring_blows_up(method, k, m, h, steps):
    """The library's blow-up test of one spring (x = 1 m, v = 0): True when h blows up within `steps` steps."""
    return stability.blows_up(method, k, m, h, steps=steps)


def _spring_test(method, k, m, steps):
    """The library's blow-up test of one spring as a function: h -> True when h blows up within `steps` steps."""
    return lambda h: _spring_blows_up(method, k, m, h, steps)


@memoized
def _spring_limit(method, k, m, steps):
    """The largest step that passes the library's blow-up test of `steps` steps, to 1e-4."""
    return stability.max_stable_step(method, k, m, steps=steps, rtol=1e-4)


@memoized
def _chain_blows_up(method, n, k, m, steps, h):
    """The notebook's blow-up test of a chain, run with the library's stepper: True when h blows up.

    n masses m between two walls, springs k, from x_j = (-1)^j, v = 0; a blow-up is an amplitude
    sqrt(sum x^2 + sum (v / omega)^2), omega = sqrt(k / m), above 1000 times its start within `steps`
    steps. The library's own chain test (``stability.chain_max_stable_step``) starts from the fastest mode
    and lets steps up to 1% larger pass: a step just past the notebook's limit can pass it.
    """
    step, w2 = INTEGRATORS[method], k / m
    X = np.zeros((n, 2, 1))
    X[:, 0, 0] = (-1.0) ** np.arange(n)

    def f(X, t):
        a = w2 * np.diff(np.concatenate([[0.0], X[:, 0, 0], [0.0]]), 2)
        return np.stack([X[:, 1], a[:, None]], axis=1)

    def amplitude(X):
        return np.sqrt(np.sum(X[:, 0] ** 2) + np.sum(X[:, 1] ** 2) / w2)

    limit = 1e3 * amplitude(X)
    with np.errstate(over="ignore", invalid="ignore"):
        for s in range(steps):  # a loop over time steps
            X = step(f, X, s * h, h)
            if not amplitude(X) <= limit:
                return True
    return False


def _chain_test(method, n, k, m, steps):
    """The chain's blow-up test (:func:`_chain_blows_up`) as a function: h -> True when h blows up."""
    return lambda h: _chain_blows_up(method, n, k, m, steps, h)


@memoized
def _chain_limit(method, n, k, m, steps, rtol=1e-4):
    """The largest step the chain's blow-up test lets pass, by geometric bisection around its theory, to `rtol`."""
    unstable, theory = _chain_test(method, n, k, m, steps), _chain_reference(method, n, k, m)
    lo, hi = 0.5 * theory, 2.0 * theory
    if unstable(lo) or not unstable(hi):  # a grader bug, not the student's
        raise RuntimeError("the chain's limit is not within half to twice its theory")
    while hi > (1 + rtol) * lo:
        mid = np.sqrt(lo * hi)
        lo, hi = (lo, mid) if unstable(mid) else (mid, hi)
    return lo


def _blows_up(student, method, k, m, h, steps, hidden=False):
    got = student.call("blows_up", method, k, m, h, steps, timeout=10)
    if not isinstance(got, (bool, np.bool_)):
        call = (f"blows_up({method!r}, k, m, h, steps={steps}) on a random spring" if hidden else
                f"blows_up({method!r}, k={k:.3g}, m={m:.3g}, h={h:.3g}, steps={steps})")
        raise GradingFailure(f"{call} returned {describe_value(got)}, expected True or False")
    return bool(got)


# -- blows_up ----------------------------------------------------------------------------------


@pytest.mark.points(1)
def test_blows_up_around_the_limits(student):
    """blows_up tells stable from unstable steps on both sides of the limits (k = 100 N/m, m = 1 kg)."""
    k, m = 100.0, 1.0
    for method, h, steps, expected in (("symplectic_euler", 0.19, 200, False), ("symplectic_euler", 0.21, 200, True),
                                       ("rk4", 0.27, 200, False), ("rk4", 0.30, 200, True),
                                       ("euler", 0.05, 2000, True), ("euler", 0.001, 200, False)):
        got = _blows_up(student, method, k, m, h, steps)
        if got != expected:
            raise GradingFailure(f"blows_up({method!r}, k=100, m=1, h={h}, steps={steps}) (omega h = {10 * h:g}) "
                                 f"returned {got}, expected {expected}: the amplitude "
                                 f"{'grows past 1000 times its start' if expected else 'stays near 1 m'}")


@pytest.mark.points(1)
@pytest.mark.hidden
def test_blows_up_random(student, rng):
    """blows_up agrees with the library's blow-up test at random stiffnesses, masses and steps."""
    for method in ("symplectic_euler", "verlet", "rk4"):
        k, m = 10 ** rng.uniform(-1, 6), 10 ** rng.uniform(-2, 2)
        omega = np.sqrt(k / m)
        for factor in (rng.uniform(0.5, 0.9), rng.uniform(1.1, 1.5)):
            h = factor * STABLE[method] / omega
            expected = _spring_blows_up(method, k, m, h, 200)
            got = _blows_up(student, method, k, m, h, 200, hidden=True)
            if got != expected:
                raise GradingFailure(f"blows_up({method!r}, k, m, h) on a random spring at omega h = {omega * h:.3g} "
                                     f"returned {got}, expected {expected}: the amplitude "
                                     f"{'grows past 1000 times its start' if expected else 'stays bounded'} within "
                                     "200 steps")
    # Just above RK4's limit the amplitude grows so slowly that a 20-step test does not see it blow up:
    # the library's test says stable, a comparison of omega h with the theoretical 2.83 says unstable.
    k, m = 10 ** rng.uniform(-1, 6), 10 ** rng.uniform(-2, 2)
    omega, theory = np.sqrt(k / m), stability.theory_max_step("rk4", k, m)
    h_short = stability.max_stable_step("rk4", k, m, steps=20, rtol=1e-3)
    h = theory * rng.uniform(1.01, 0.99 * h_short / theory)
    expected = stability.blows_up("rk4", k, m, h, steps=20)
    got = _blows_up(student, "rk4", k, m, h, 20, hidden=True)
    if got != expected:
        raise GradingFailure(f"blows_up('rk4', k, m, h, steps=20) on a random spring at omega h = {omega * h:.4g} "
                             f"(just above the theoretical 2.83) returned {got}, expected {expected}: so close to the "
                             "limit the amplitude grows too slowly to reach 1000 times its start in 20 steps; run the "
                             "test instead of comparing omega h with the theory")


# -- max_stable_step ---------------------------------------------------------------------------


@pytest.mark.points(2)
def test_max_stable_step_one_spring(student):
    """max_stable_step measures omega h_max = 2 (symplectic Euler) and 2.83 (RK4) for k = 100 N/m, m = 1 kg."""
    for method in ("symplectic_euler", "rk4"):
        _check_limit(student.call("max_stable_step", method, 100.0, 1.0, timeout=20),
                     _spring_limit(method, 100.0, 1.0, 200), _spring_test(method, 100.0, 1.0, 200), 10.0,
                     f"max_stable_step({method!r}, k=100, m=1)", "the library's 200-step blow-up test")


@pytest.mark.points(1)
def test_max_stable_step_euler_has_none(student):
    """max_stable_step reports 0.0 (no stable step) for explicit Euler and midpoint on the undamped spring."""
    for method in ("euler", "midpoint"):
        call = f"max_stable_step({method!r}, k=100, m=1)"
        h = _number(student.call("max_stable_step", method, 100.0, 1.0, timeout=20), call)
        if h != 0.0:
            raise GradingFailure(f"{call} returned {h:.4g} s (omega h = {10 * h:.3g}); {method} has no stable step on "
                                 "the undamped spring (its amplitude grows at every step), so the limit must be 0.0: "
                                 "the step your test lets pass shrinks as the test gets longer; check your step with "
                                 "a longer test")


@pytest.mark.points(3)
@pytest.mark.hidden
def test_max_stable_step_random(student, rng):
    """max_stable_step passes the library's blow-up test, at most 3% below its limit, on random springs, 3 methods."""
    for method in ("symplectic_euler", "verlet", "rk4"):
        k, m = 10 ** rng.uniform(-1, 7), 10 ** rng.uniform(-3, 2)
        _check_limit(student.call("max_stable_step", method, k, m, timeout=20), _spring_limit(method, k, m, 200),
                     _spring_test(method, k, m, 200), np.sqrt(k / m), f"max_stable_step({method!r}, k, m) on a random "
                     "spring", "the library's 200-step blow-up test")


@pytest.mark.points(1)
@pytest.mark.hidden
def test_max_stable_step_is_measured(student, rng):
    """With 20-step and shorter blow-up tests, max_stable_step finds the larger limits such short tests measure."""
    k, m = 10 ** rng.uniform(0, 5), 10 ** rng.uniform(-2, 1)
    for steps in (20, int(rng.integers(10, 12))):   # a second, shorter test: no fixed factor fits both
        length = "steps=20" if steps == 20 else "a shorter test"
        _check_limit(student.call("max_stable_step", "rk4", k, m, steps, timeout=20), _spring_limit("rk4", k, m, steps),
                     _spring_test("rk4", k, m, steps), np.sqrt(k / m),
                     f"max_stable_step('rk4', k, m, steps) with {length} on a random spring",
                     "a 20-step test" if steps == 20 else "that test",
                     advice=": measure the limit with the `steps` you are given",
                     theory=stability.theory_max_step("rk4", k, m))


# -- chain_max_stable_step ---------------------------------------------------------------------


@memoized
def _chain_reference(method, n, k, m):
    """(omega h)_max / omega_max, with omega_max from the library's taut string pinned at both ends."""
    h_symplectic = string(n + 2, pin="both", k=k, mass=m, gravity=0.0).max_stable_step()   # 2 / omega_max
    return STABLE[method] / 2.0 * h_symplectic


def _check_chain(got, method, n, k, m, steps, call, test, advice=""):
    """The student's chain limit against the notebook's chain test of `steps` steps (units of omega_max h)."""
    theory = _chain_reference(method, n, k, m)
    unstable = _chain_test(method, n, k, m, steps)
    _check_limit(got, _chain_limit(method, n, k, m, steps), unstable, STABLE[method] / theory, call, test,
                 symbol="omega_max h", advice=advice, theory=theory)


@pytest.mark.points(1)
def test_chain_max_stable_step_four_masses(student):
    """chain_max_stable_step measures 2 / omega_max for 4 masses of 1 kg between walls, springs 100 N/m."""
    _check_chain(student.call("chain_max_stable_step", "symplectic_euler", 4, 100.0, 1.0, timeout=20),
                 "symplectic_euler", 4, 100.0, 1.0, 200, "chain_max_stable_step('symplectic_euler', n=4, k=100, m=1)",
                 "a 200-step blow-up test from x_j = (-1)^j")


@pytest.mark.points(2)
@pytest.mark.hidden
def test_chain_max_stable_step_random(student, rng):
    """chain_max_stable_step passes the chain's blow-up test and is within 3% below its limit, random chains."""
    for method in ("symplectic_euler", "rk4"):
        n, k, m = int(rng.integers(2, 20)), 10 ** rng.uniform(0, 5), 10 ** rng.uniform(-2, 1)
        _check_chain(student.call("chain_max_stable_step", method, n, k, m, timeout=20), method, n, k, m, 200,
                     f"chain_max_stable_step({method!r}, n, k, m) on a random chain",
                     "a 200-step blow-up test from x_j = (-1)^j")


@pytest.mark.points(1)
@pytest.mark.hidden
def test_chain_max_stable_step_is_measured(student, rng):
    """With 20-step and shorter blow-up tests, chain_max_stable_step finds the larger limits such tests measure."""
    n, k, m = int(rng.integers(2, 20)), 10 ** rng.uniform(0, 5), 10 ** rng.uniform(-2, 1)
    for steps in (20, int(rng.integers(10, 12))):
        length = "steps=20" if steps == 20 else "a shorter test"
        _check_chain(student.call("chain_max_stable_step", "rk4", n, k, m, steps, timeout=20), "rk4", n, k, m, steps,
                     f"chain_max_stable_step('rk4', n, k, m, steps) with {length} on a random chain",
                     "a 20-step test" if steps == 20 else "that test",
                     advice=" (more than the 2.83 of theory, which holds for long tests): measure the limit "
                            "with the `steps` you are given")


# -- implicit_euler_spring ---------------------------------------------------------------------


def _state(x, v):
    return np.stack([np.atleast_1d(x), np.atleast_1d(v)], axis=1)[:, :, None].astype(float)


def _check_implicit(got, x, v, k, m, h, call, hidden=False):
    if not isinstance(got, tuple) or len(got) != 2:
        kind = describe_value(got) if not isinstance(got, tuple) else f"a tuple of {len(got)} values"
        raise GradingFailure(f"{call} returned {kind}, expected the tuple (x_new, v_new)")
    f, X = stability.oscillator(k, m), _state(x, v)
    reference = implicit_euler(f, X, 0.0, h, tol=1e-13)
    w2h2 = k / m * h**2
    hints = {"an explicit Euler step": euler(f, X, 0.0, h), "a symplectic Euler step": symplectic_euler(f, X, 0.0, h),
             "an implicit step divided by 1 + omega h instead of 1 + (omega h)^2":
                 reference * (1 + w2h2) / (1 + np.sqrt(w2h2))}
    shape = np.shape(x)
    for part, name in ((0, "x_new"), (1, "v_new")):
        value = got[part]
        if shape == () and isinstance(value, (float, int, np.floating, np.integer)) and not isinstance(value, bool):
            value = np.array(float(value))
        expect_array(value, reference[:, part, 0].reshape(shape), f"{name} of {call}", rtol=1e-8, atol=1e-12,
                     hints={label: H[:, part, 0].reshape(shape) for label, H in hints.items()}, show_values=not hidden)


@pytest.mark.points(1)
def test_implicit_euler_spring_one_step(student):
    """implicit_euler_spring takes one backward-Euler step from x = 1 m, v = 0 (k = 100 N/m, m = 1 kg, h = 0.05 s)."""
    call = "implicit_euler_spring(x=1, v=0, k=100, m=1, h=0.05)"
    _check_implicit(student.call("implicit_euler_spring", 1.0, 0.0, 100.0, 1.0, 0.05), 1.0, 0.0, 100.0, 1.0, 0.05, call)


@pytest.mark.points(2)
@pytest.mark.hidden
def test_implicit_euler_spring_random(student, rng):
    """implicit_euler_spring matches the library's implicit Euler on arrays of springs, up to omega h = 100, inputs unchanged."""
    for _ in range(3):
        p = int(rng.integers(2, 8))
        x, v = rng.normal(size=p), rng.normal(size=p) * 5
        k, m = 10 ** rng.uniform(0, 6), 10 ** rng.uniform(-2, 1)
        h = 10 ** rng.uniform(-2, 2) / np.sqrt(k / m)
        call = f"implicit_euler_spring(x, v of shape ({p},), k, m, h) on random springs, x and v"
        got = student.call("implicit_euler_spring", x, v, k, m, h, check_inputs=True)
        _check_implicit(got, x, v, k, m, h, call, hidden=True)


# -- damping_factor ----------------------------------------------------------------------------


def _per_second(omega_h, reference):
    """A pattern: factors per unit of time (per second of a spring of some omega, or per period), not per step.

    Simulated at omega with h = omega h / omega, the factor per second is the factor per step to the power
    1 / h = omega / (omega h): log(got) / log(reference) * omega h is then the same omega for every omega h.
    """
    def wrong(got):
        if not isinstance(got, np.ndarray) or got.shape != reference.shape or got.size < 2 or np.any(got <= 0):
            return False
        omega = np.log(got) / np.log(reference) * omega_h
        if not (np.all(np.isfinite(omega)) and np.all(omega > 0) and np.ptp(omega) <= 1e-6 * omega[0]):
            return False
        if abs(omega[0] / (2 * np.pi) - 1) <= 1e-6:
            return ("your factors are per period (2 pi / (omega h) steps), not per step: take the N-th root of "
                    "A_N / A_0 over N steps")
        return (f"your factors are per second of a spring with omega = {omega[0]:.3g} rad/s, not per step: the "
                "amplitude factor per step is (A_N / A_0) ** (1 / N), with the number of steps N, not the simulated "
                "time N h")
    return wrong


def _check_damping(got, omega_h, call, hidden=False, steps=50):
    exact = 1.0 / np.sqrt(1.0 + omega_h**2)
    reference = stability.damping_factor(omega_h)
    expect_array(got, reference, call, rtol=1e-6, atol=1e-12, show_values=not hidden,
                 hints={"1 / (1 + (omega h)^2), the factor of the energy, not of the amplitude": exact**2,
                        "1: no damping at all (an explicit or symplectic step?)": np.ones_like(omega_h),
                        f"the factor over all {steps} steps, A_N / A_0, not per step (take its N-th root)":
                            reference**steps,
                        "per second": _per_second(omega_h, reference),
                        "your factors exceed 1 at some omega h: the amplitude grows, so the steps are not implicit "
                        "Euler's, which damps at every step (look at implicit_euler_spring)":
                            lambda got: bool(np.any(got > 1 + 1e-9))})


@pytest.mark.points(1)
def test_damping_factor_public(student):
    """damping_factor gives 1 / sqrt(1 + (omega h)^2) per step at omega h = 0.1, 1 and 10."""
    omega_h = np.array([0.1, 1.0, 10.0])
    _check_damping(student.call("damping_factor", omega_h, timeout=10), omega_h, "damping_factor([0.1, 1, 10])")


@pytest.mark.points(1)
@pytest.mark.hidden
def test_damping_factor_random(student, rng):
    """damping_factor matches the library's measurement at random omega h from 0.01 to 100, inputs unchanged."""
    omega_h = np.sort(10 ** rng.uniform(-2, 2, size=int(rng.integers(5, 15))))
    got = student.call("damping_factor", omega_h, timeout=10, check_inputs=True)
    _check_damping(got, omega_h, f"damping_factor(omega_h of {len(omega_h)} random values between 0.01 and 100)",
                   hidden=True)


# -- cost_table --------------------------------------------------------------------------------


def _check_cost(got, ks, m, T, h_implicit, call, hidden=False):
    """The student's step counts against ceil(T / h); a hidden test (`hidden`) names a stiffness by its rank."""
    names = ("symplectic_euler", "rk4", "implicit_euler")
    if not isinstance(got, dict) or any(name not in got for name in names):
        have = sorted(got) if isinstance(got, dict) else describe_value(got)
        raise GradingFailure(f"{call} returned {have}, expected a dict with the keys {', '.join(names)}")
    for name in names:
        steps = np.asarray(got[name]) if isinstance(got[name], (np.ndarray, list, tuple)) else None
        if steps is None or steps.shape != ks.shape or steps.dtype.kind not in "iuf":
            raise GradingFailure(f"{call}[{name!r}] is {describe_value(got[name])}, expected {len(ks)} step counts")
        if name == "implicit_euler":
            expected = np.full(len(ks), np.ceil(T / h_implicit))
        else:
            expected = np.ceil(T / (0.9 * np.array([stability.theory_max_step(name, k, m) for k in ks])))
        growth = np.polyfit(np.log(ks), np.log(np.maximum(steps.astype(float), 1e-300)), 1)[0]
        trend = 0.0 if name == "implicit_euler" else 0.5
        if not abs(growth - trend) <= 0.05:
            why = ("the same count at every stiffness: implicit Euler is stable at any step, so its step is "
                   "h_implicit whatever k" if trend == 0 else "h_max falls like 1/sqrt(k)")
            raise GradingFailure(f"in {call}, the {name} step counts grow like k^{growth:.2f}, expected k^{trend:g} "
                                 f"({why})")
        bad = np.abs(steps - expected) > 0.05 * expected + 1
        if bad.any():
            i = int(np.argmax(bad))
            where = f"at the stiffness number {i + 1} of {len(ks)}" if hidden else f"at k = {ks[i]:.3g} N/m"
            why = ""
            if name != "implicit_euler":
                h_max = np.array([stability.theory_max_step(name, k, m) for k in ks])
                if np.all(np.abs(steps - np.ceil(T / h_max)) <= 0.02 * expected + 1):
                    why = "; your counts are ceil(T / h_max): step at 0.9 h_max, a margin below the limit"
                elif np.all(np.abs(steps - np.floor(T / (0.9 * h_max))) <= 1):
                    why = "; your counts are rounded down: ceil(T / h) steps cover T, floor(T / h) fall short of it"
            raise GradingFailure(f"in {call}, {name} {where} takes {steps[i]:g} steps, expected about "
                                 f"{expected[i]:.0f} (ceil(T / h) with h = "
                                 f"{'h_implicit' if name == 'implicit_euler' else '0.9 h_max'}){why}")


def _figure_cost(feedback, got, ks, m, T, h_implicit, hidden=False):
    """Attach the student's step counts against k beside the expected ones, before the test judges them.

    A hidden test plots k / k_0 and counts relative to the expected count at k_0 of each method, so that its
    random mass, T and h_implicit do not show.
    """
    series = []
    for name in ("symplectic_euler", "rk4", "implicit_euler"):
        if name == "implicit_euler":
            expected = np.full(len(ks), np.ceil(T / h_implicit))
        else:
            expected = np.ceil(T / (0.9 * np.array([stability.theory_max_step(name, k, m) for k in ks])))
        yours = got.get(name) if isinstance(got, dict) else None
        scale = expected[0] if hidden else 1.0
        try:
            yours = None if yours is None else np.asarray(yours, dtype=float) / scale
        except (TypeError, ValueError):
            yours = None
        x = ks / ks[0] if hidden else ks
        if yours is not None:
            series.append({"label": f"yours: {name}", "x": x, "y": yours, "group": name})
        series.append({"label": f"expected: {name}", "x": x, "y": expected / scale, "group": name,
                       "role": "reference"})
    feedback.curve("Steps of one simulated second against the stiffness" + (" (relative)" if hidden else ""),
                   "k / softest k" if hidden else "k (N/m)",
                   "steps / expected steps at the softest k" if hidden else "steps", series, loglog=True,
                   caption="Explicit steppers need steps growing like sqrt(k) (h_max falls like 1/sqrt(k)); "
                           "implicit Euler's count stays flat.")


@pytest.mark.points(1)
def test_cost_table_public(student, feedback):
    """cost_table counts the steps of one simulated second for k = 100 to 1e8 N/m, m = 1 kg, h_implicit = 0.01 s."""
    ks = np.array([1e2, 1e4, 1e6, 1e8])
    got = student.call("cost_table", ks, timeout=20)
    _figure_cost(feedback, got, ks, 1.0, 1.0, 0.01)
    _check_cost(got, ks, 1.0, 1.0, 0.01, "cost_table(ks=[1e2, 1e4, 1e6, 1e8], m=1, T=1, h_implicit=0.01)")


@pytest.mark.points(2)
@pytest.mark.hidden
def test_cost_table_trend(student, rng, feedback):
    """cost_table: explicit step counts grow like sqrt(k), implicit Euler's stay flat, for a random mass, T and h."""
    ks = 10 ** (rng.uniform(5, 6) + np.array([0.0, 1.5, 3.0, 4.5]))
    m, T, h_implicit = 10 ** rng.uniform(-1, 1), rng.uniform(0.5, 2.0), rng.choice([1 / 24, 1 / 30, 1 / 60, 0.01])
    m = float(m)
    call = "cost_table(ks, m, T, h_implicit) for 4 random stiffnesses, a random mass, T and h_implicit"
    got = student.call("cost_table", ks, m, T, float(h_implicit), timeout=20)
    _figure_cost(feedback, got, ks, m, T, float(h_implicit), hidden=True)
    _check_cost(got, ks, m, T, float(h_implicit), call, hidden=True)
