"""ODE steppers: observed orders, exact amplification factors, invariants, errors."""

import numpy as np
import pytest
import scipy.sparse

from particles import ConvergenceError, SimulationDiverged, integrate
from particles.integrators import (
    INTEGRATORS,
    euler,
    implicit_euler,
    midpoint,
    rk4,
    symplectic_euler,
    trapezoid,
    verlet,
)
from particles.problems import circle, harmonic_oscillator, projectile_drag
from particles.studies import fit_order, global_error

ALL = list(INTEGRATORS)
GENERIC = [name for name, s in INTEGRATORS.items() if not s.second_order_layout]
SECOND_ORDER_LAYOUT = ["symplectic_euler", "verlet"]


def test_orders_are_declared():
    """Each stepper carries the order the issue lists."""
    assert {name: s.order for name, s in INTEGRATORS.items()} == {
        "euler": 1, "midpoint": 2, "trapezoid": 2, "rk4": 4,
        "symplectic_euler": 1, "verlet": 2, "implicit_euler": 1,
    }


def observed_order(problem, method, n_steps=(200, 400, 800, 1600)):
    h = (problem.t1 - problem.t0) / np.array(n_steps)
    errors = [global_error(problem, method, n) for n in n_steps]
    return fit_order(h, errors)


@pytest.mark.parametrize("method", ALL)
def test_order_on_harmonic_oscillator(method):
    """Observed global order on x'' = -w^2 x matches .order within 0.1."""
    p = observed_order(harmonic_oscillator(omega=2.0, x0=0.7, v0=0.3), method)
    assert abs(p - INTEGRATORS[method].order) < 0.1, p


@pytest.mark.parametrize("method", GENERIC)
def test_order_on_circle_field(method):
    """Observed order on the lecture's circle field f = (-y, x) matches .order."""
    p = observed_order(circle(X0=(0.3, -1.2)), method)
    assert abs(p - INTEGRATORS[method].order) < 0.1, p


@pytest.mark.parametrize("method", ALL)
def test_order_with_velocity_dependent_force(method):
    """Linear drag (a velocity-dependent force) does not lower any stepper's order."""
    p = observed_order(projectile_drag(c=0.8), method, n_steps=(20, 40, 80, 160))
    assert abs(p - INTEGRATORS[method].order) < 0.1, p


def oscillator_f(omega):
    """x'' = -omega^2 x for a vector of independent oscillators, layout (n, 2, 1)."""
    w2 = np.asarray(omega, dtype=float)[:, None] ** 2

    def f(X, t):
        return np.stack([X[:, 1], -w2 * X[:, 0]], axis=1)

    return f


def test_euler_amplitude_grows_by_exact_factor():
    """Explicit Euler multiplies sqrt(x^2 + (v/w)^2) by sqrt(1 + (w h)^2) every step."""
    omega, h = np.array([1.0, 3.0, 10.0]), 0.05
    f = oscillator_f(omega)
    X = np.zeros((3, 2, 1))
    X[:, 0, 0] = [1.0, 0.2, -0.5]
    X[:, 1, 0] = [0.0, 1.0, 2.0]

    def amplitude(X):
        return np.hypot(X[:, 0, 0], X[:, 1, 0] / omega)

    for _ in range(20):
        X_new = euler(f, X, 0.0, h)
        np.testing.assert_allclose(amplitude(X_new) / amplitude(X), np.sqrt(1 + (omega * h) ** 2), rtol=1e-13)
        X = X_new


def test_implicit_euler_amplitude_decays_by_exact_factor():
    """Backward Euler divides the amplitude by sqrt(1 + (w h)^2) every step (numerical damping)."""
    omega, h = np.array([1.0, 30.0]), 0.1
    X = np.array([[[1.0], [0.0]], [[0.0], [5.0]]])

    def amplitude(X):
        return np.hypot(X[:, 0, 0], X[:, 1, 0] / omega)

    X_new = implicit_euler(oscillator_f(omega), X, 0.0, h)
    np.testing.assert_allclose(amplitude(X_new) / amplitude(X), 1 / np.sqrt(1 + (omega * h) ** 2), rtol=1e-9)


# Largest relative energy error over an orbit started at rest (x0, 0), a = w h.
# Symplectic Euler conserves v^2 + w^2 x^2 - a w x v exactly, Verlet conserves
# v^2 + (1 - a^2/4) w^2 x^2; the energy oscillates between the extremes these allow.
ENERGY_ERROR_BOUND = {
    "symplectic_euler": lambda a: a / (2 - a),
    "verlet": lambda a: a**2 / 4,
}


@pytest.mark.parametrize("method", SECOND_ORDER_LAYOUT)
def test_symplectic_energy_error_bounded_for_long_runs(method):
    """Over 10^5 steps with w h < 2 the energy error stays within its exact bound: no drift."""
    # not 1.0: there the discrete orbit has period 6 and never reaches the extreme
    wh = np.array([0.1, 0.5, 0.9, 1.5, 1.9])
    h = 0.1
    omega = wh / h
    X0 = np.zeros((len(wh), 2, 1))
    X0[:, 0, 0] = 1.0
    t, X = integrate(oscillator_f(omega), X0, 0.0, 1e5 * h, h, method=method)
    assert len(t) == 100_001
    E = 0.5 * X[:, :, 1, 0] ** 2 + 0.5 * omega**2 * X[:, :, 0, 0] ** 2
    rel = np.abs(E - E[0]) / E[0]
    bound = ENERGY_ERROR_BOUND[method](wh)
    assert np.all(rel.max(axis=0) <= bound * (1 + 1e-8))
    # the bound is reached, early and late alike: oscillation, not drift
    assert np.all(rel[:10_000].max(axis=0) >= 0.99 * bound)
    assert np.all(rel[-10_000:].max(axis=0) >= 0.99 * bound)


@pytest.mark.parametrize("method", SECOND_ORDER_LAYOUT)
def test_symplectic_unstable_beyond_limit(method):
    """Just above w h = 2 the same steppers blow up: the limit is sharp."""
    h, omega = 0.1, np.array([2.05 / 0.1])
    X = np.array([[[1.0], [0.0]]])
    for k in range(300):
        X = INTEGRATORS[method](oscillator_f(omega), X, 0.0, h)
    assert np.abs(X).max() > 1e3


def test_explicit_euler_unstable_without_damping_any_h():
    """Even a tiny step lets explicit Euler's energy grow without damping."""
    t, X = integrate(oscillator_f(np.array([1.0])), [[[1.0], [0.0]]], 0.0, 10.0, 0.001, method="euler")
    E = 0.5 * (X[:, 0, 1, 0] ** 2 + X[:, 0, 0, 0] ** 2)
    assert np.all(np.diff(E) > 0)


@pytest.mark.parametrize("method", ALL)
def test_input_state_not_modified(method):
    """No stepper writes into X (a read-only array would raise)."""
    f = oscillator_f(np.array([1.0, 2.0]))
    X = np.array([[[1.0], [0.5]], [[-1.0], [0.25]]])
    X.setflags(write=False)
    X_new = INTEGRATORS[method](f, X, 0.0, 0.1)
    assert X_new.shape == X.shape and X_new is not X
    np.testing.assert_array_equal(X, [[[1.0], [0.5]], [[-1.0], [0.25]]])


@pytest.mark.parametrize("method", GENERIC)
def test_generic_steppers_take_any_shape(method):
    """A scalar ODE x' = -x works with the generic steppers."""
    X = INTEGRATORS[method](lambda X, t: -X, np.float64(1.0), 0.0, 0.1)
    assert np.shape(X) == ()
    assert abs(X - np.exp(-0.1)) < 0.01


def test_one_step_formulas():
    """The steppers' single steps equal the textbook formulas on x' = x t."""
    f = lambda X, t: X * t  # noqa: E731
    X, t, h = np.array([2.0]), 0.5, 0.1
    assert euler(f, X, t, h) == pytest.approx(X + h * X * t)
    Xm = X + h / 2 * X * t
    assert midpoint(f, X, t, h) == pytest.approx(X + h * Xm * (t + h / 2))
    X1 = X + h * X * t
    assert trapezoid(f, X, t, h) == pytest.approx(X + h / 2 * (X * t + X1 * (t + h)))
    k1 = f(X, t)
    k2 = f(X + h / 2 * k1, t + h / 2)
    k3 = f(X + h / 2 * k2, t + h / 2)
    k4 = f(X + h * k3, t + h)
    assert rk4(f, X, t, h) == pytest.approx(X + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4))
    # backward Euler on a linear ODE: Y = X / (1 - h (t + h))
    assert implicit_euler(f, X, t, h) == pytest.approx(X / (1 - h * (t + h)), rel=1e-10)


def test_symplectic_euler_and_verlet_formulas():
    """Symplectic Euler updates v then x; Verlet is kick-drift-kick."""
    f = oscillator_f(np.array([2.0]))
    X = np.array([[[1.0], [0.5]]])
    h = 0.1
    x, v = 1.0, 0.5
    v1 = v - h * 4.0 * x
    np.testing.assert_allclose(symplectic_euler(f, X, 0.0, h), [[[x + h * v1], [v1]]])
    vh = v - h / 2 * 4.0 * x
    x1 = x + h * vh
    np.testing.assert_allclose(verlet(f, X, 0.0, h), [[[x1], [vh - h / 2 * 4.0 * x1]]])


@pytest.mark.parametrize("jac_kind", ["dense", "sparse", "finite differences"])
def test_implicit_euler_linear_system_matches_direct_solve(jac_kind):
    """For f = A X, backward Euler is (I - h A)^-1 X, whatever the Jacobian source."""
    rng = np.random.default_rng(3)
    A = rng.normal(size=(6, 6)) - 4 * np.eye(6)
    f = lambda X, t: A @ X  # noqa: E731
    jac = {"dense": lambda X, t: A, "sparse": lambda X, t: scipy.sparse.csr_matrix(A),
           "finite differences": None}[jac_kind]
    X = rng.normal(size=6)
    expected = np.linalg.solve(np.eye(6) - 0.7 * A, X)
    np.testing.assert_allclose(implicit_euler(f, X, 0.0, 0.7, jac=jac), expected, rtol=1e-9, atol=1e-12)


def test_implicit_euler_large_state_matrix_free():
    """States above the dense limit are solved matrix-free (GMRES) to the same answer."""
    n = 300
    k = np.linspace(1.0, 100.0, n)
    f = lambda X, t: -k * X  # noqa: E731
    X = np.ones(n)
    np.testing.assert_allclose(implicit_euler(f, X, 0.0, 0.1), 1 / (1 + 0.1 * k), rtol=1e-8)


def test_implicit_euler_stable_at_huge_step():
    """A-stability: a stiff decay x' = -1e6 x stays bounded with h = 1."""
    t, X = integrate(lambda X, t: -1e6 * X, [1.0], 0.0, 10.0, 1.0, method="implicit_euler")
    assert np.all(np.abs(X) <= 1.0) and X[-1, 0] < 1e-50


def test_implicit_euler_reports_newton_failure():
    """No solution of Y = 1 + h Y^2 for h = 1: a clear ConvergenceError."""
    with pytest.raises(ConvergenceError, match="Newton's method did not converge.*Reduce h"):
        implicit_euler(lambda X, t: X**2, np.array([1.0]), 0.0, 1.0, max_iter=20)


def test_implicit_euler_checks_jacobian_shape():
    """A jacobian of the wrong shape is reported, not silently broadcast."""
    with pytest.raises(ValueError, match=r"jac\(X, t\) must return a \(2, 2\) matrix"):
        implicit_euler(lambda X, t: -X, np.ones(2), 0.0, 0.1, jac=lambda X, t: np.eye(3))


# -- integrate ---------------------------------------------------------------


def test_integrate_lands_on_t1_with_shortened_last_step():
    """The last step is shortened so that t[-1] == t1 exactly."""
    t, X = integrate(lambda X, t: np.ones_like(X), [0.0], 0.0, 1.0, 0.3, method="euler")
    np.testing.assert_allclose(t, [0.0, 0.3, 0.6, 0.9, 1.0])
    assert t[-1] == 1.0
    np.testing.assert_allclose(X[:, 0], t)  # x' = 1 is integrated exactly by Euler


def test_integrate_equal_steps_when_h_divides_interval():
    """(t1 - t0) / h integral up to round-off: no tiny extra step."""
    t, _ = integrate(lambda X, t: -X, [1.0], 0.0, 1.0, 0.1)
    assert len(t) == 11
    np.testing.assert_allclose(np.diff(t), 0.1)


def test_integrate_every_records_first_and_last():
    """every=k records every k-th state, always including the first and last."""
    t, X = integrate(lambda X, t: -X, [1.0], 0.0, 1.0, 0.1, every=4)
    np.testing.assert_allclose(t, [0.0, 0.4, 0.8, 1.0])
    assert X.shape == (4, 1)


def test_integrate_zero_length_interval():
    """t1 == t0 returns just the initial state."""
    t, X = integrate(lambda X, t: -X, [2.0], 1.0, 1.0, 0.1)
    assert t.tolist() == [1.0] and X.tolist() == [[2.0]]


def test_integrate_exact_decay():
    """RK4 on x' = -x reaches e^-1 with error ~h^4."""
    t, X = integrate(lambda X, t: -X, [1.0], 0.0, 1.0, 0.01)
    assert abs(X[-1, 0] - np.exp(-1)) < 1e-10


def test_integrate_passes_options_to_stepper():
    """Options such as jac= reach the stepper."""
    calls = []

    def jac(X, t):
        calls.append(t)
        return -np.eye(1)

    integrate(lambda X, t: -X, [1.0], 0.0, 0.3, 0.1, method="implicit_euler", jac=jac)
    assert len(calls) >= 3


def test_integrate_accepts_a_stepper_function():
    """method may be a stepper callable instead of a name."""
    t, X = integrate(lambda X, t: -X, [1.0], 0.0, 1.0, 0.1, method=midpoint)
    assert abs(X[-1, 0] - np.exp(-1)) < 1e-3


def test_integrate_does_not_modify_initial_state():
    """integrate never writes into the initial state (a read-only X0 works)."""
    X0 = np.array([[[1.0], [0.0]]])
    X0.setflags(write=False)
    integrate(oscillator_f(np.array([1.0])), X0, 0.0, 1.0, 0.1, method="verlet")
    assert X0[0, 0, 0] == 1.0


def test_divergence_raises_with_step_time_and_cause():
    """Explicit Euler on a stiff spring blows up: the error names step, time and cause."""
    f = oscillator_f(np.array([100.0]))
    with pytest.raises(SimulationDiverged) as info:
        integrate(f, [[[1.0], [0.0]]], 0.0, 100.0, 0.05, method="euler")
    err = info.value
    assert isinstance(err, RuntimeError)
    assert err.step > 1 and err.t == pytest.approx((err.step - 1) * 0.05)
    message = str(err)
    assert f"step {err.step}" in message and "t = " in message
    assert "stability limit" in message and "'euler'" in message and "h = 0.05" in message


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(h=0.0), "h must be a positive finite number"),
        (dict(h=-0.1), "h must be a positive finite number"),
        (dict(h=float("nan")), "h must be a positive finite number"),
        (dict(h="0.1"), "h must be a positive finite number"),
        (dict(method="rk5"), "unknown method 'rk5'; expected one of 'euler'"),
        (dict(X0=[np.inf]), "X0 must be finite"),
        (dict(X0="abc"), "X0 must be an array of real numbers"),
        (dict(t1=-1.0), "t1 must be >= t0"),
        (dict(every=0), "every must be a positive integer"),
    ],
)
def test_integrate_bad_input(kwargs, match):
    """Bad arguments raise ValueError naming the argument and what was expected."""
    args = dict(f=lambda X, t: -X, X0=[1.0], t0=0.0, t1=1.0, h=0.1)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        integrate(**args)


def test_f_returning_wrong_shape_is_reported():
    """A right-hand side of the wrong shape gets a clear message."""
    with pytest.raises(ValueError, match=r"f\(X, t\) must return an array of the same shape as X \(2,\), got shape \(3,\)"):
        euler(lambda X, t: np.zeros(3), np.zeros(2), 0.0, 0.1)


@pytest.mark.parametrize("method", SECOND_ORDER_LAYOUT)
def test_second_order_steppers_reject_flat_states(method):
    """Symplectic steppers need the (n, 2, d) layout and say so."""
    with pytest.raises(ValueError, match=r"second-order layout \(n, 2, d\)"):
        integrate(lambda X, t: -X, np.ones(3), 0.0, 1.0, 0.1, method=method)


def _oscillator_state():
    """One unit oscillator in the (n, 2, d) layout every stepper accepts."""
    return oscillator_f(np.array([1.0])), np.array([[[1.0], [0.0]]])


@pytest.mark.parametrize("method", ALL)
@pytest.mark.parametrize(
    "bad, match",
    [
        (dict(X=np.full((1, 2, 1), np.nan)), "X must be finite"),
        (dict(X=np.array([[[np.inf], [0.0]]])), "X must be finite"),
        (dict(X="abc"), "X must be an array of real numbers, got str"),
        (dict(t=np.nan), r"t must be a finite real number \(in seconds\), got nan"),
        (dict(t=np.inf), "t must be a finite real number"),
        (dict(t="a"), "t must be a finite real number .*got 'a'"),
        (dict(t=None), "t must be a finite real number"),
        (dict(h=0.0), "h must be a positive finite number"),
        (dict(h=np.nan), "h must be a positive finite number"),
        (dict(h="0.1"), "h must be a positive finite number"),
    ],
)
def test_direct_stepper_calls_reject_bad_arguments(method, bad, match):
    """A stepper called directly refuses non-finite or non-numeric X, t, h, naming the argument."""
    f, X = _oscillator_state()
    args = dict(X=X, t=0.0, h=0.1)
    args.update(bad)
    with pytest.raises(ValueError, match=match):
        INTEGRATORS[method](f, args["X"], args["t"], args["h"])


@pytest.mark.parametrize("method", ALL)
def test_steppers_accept_every_real_time_and_pass_it_unchanged(method):
    """t may be an int, a NumPy scalar or a 0-d array: same result, and f sees the t given."""
    f, X = _oscillator_state()
    seen = []

    def spy(X, t):
        seen.append(t)
        return f(X, t)

    step = INTEGRATORS[method]
    reference = step(f, X, 0.0, 0.1)
    for t in (0, np.int64(0), np.float32(0.0), np.array(0.0)):
        seen.clear()
        np.testing.assert_array_equal(step(spy, X, t, 0.1), reference)
        if step.explicit:  # explicit steppers evaluate f at t first; implicit Euler only at t + h
            assert seen[0] is t
        else:
            assert seen[0] == 0.1


def test_stepper_on_float32_and_list_input_unchanged():
    """Valid non-float64 states are converted as before (float64 result, same values)."""
    out = euler(lambda X, t: -X, np.array([1.0, 2.0], dtype=np.float32), 0.0, 0.5)
    assert out.dtype == np.float64 and out.tolist() == [0.5, 1.0]
    assert euler(lambda X, t: -X, [1.0], 0, 0.1).tolist() == [0.9]


def test_implicit_euler_accepts_a_jacobian_given_as_a_list():
    """A jac returning a nested list is converted (it used to raise AttributeError)."""
    f = lambda X, t: np.array([-2.0 * X[0], -3.0 * X[1]])  # noqa: E731
    jac = lambda X, t: [[-2.0, 0.0], [0.0, -3.0]]  # noqa: E731
    Y = implicit_euler(f, np.array([1.0, 1.0]), 0.0, 0.5, jac=jac)
    np.testing.assert_allclose(Y, [1.0 / 2.0, 1.0 / 2.5], rtol=1e-12)


@pytest.mark.parametrize(
    "options, match",
    [
        (dict(tol=-1e-3), "tol must be a finite number >= 0"),
        (dict(tol=np.nan), "tol must be a finite number >= 0"),
        (dict(max_iter=0), "max_iter must be an integer >= 1"),
        (dict(max_iter=2.5), "max_iter must be an integer >= 1"),
        (dict(jac="dense"), "jac must be a function"),
        (dict(jac=lambda X, t: [["a"]]), r"jac\(X, t\) must return a \(1, 1\) array of real numbers"),
    ],
)
def test_implicit_euler_bad_options(options, match):
    """Newton's tolerance, iteration cap and Jacobian are checked, naming the option."""
    with pytest.raises(ValueError, match=match):
        implicit_euler(lambda X, t: -X, np.array([1.0]), 0.0, 0.1, **options)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(t0="a"), "t0 must be a finite real number"),
        (dict(t1="b"), "t1 must be a finite real number"),
        (dict(t0=np.nan), "t0 must be a finite real number"),
        (dict(t1=np.inf), "t1 must be a finite real number"),
        (dict(blowup=1.0), "blowup must be None or a growth factor > 1"),
        (dict(blowup="big"), "blowup must be a positive finite number"),
    ],
)
def test_integrate_bad_times_and_blowup(kwargs, match):
    """Times that are not finite numbers and a growth factor <= 1 are reported by name."""
    args = dict(f=lambda X, t: -X, X0=[1.0], t0=0.0, t1=1.0, h=0.1)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        integrate(**args)


def test_exponential_growth_is_not_divergence_with_blowup_none():
    """x' = x over 30 s (e^30 ~ 1e13-fold) runs to the accurate answer with blowup=None."""
    t, X = integrate(lambda X, t: X, [1.0], 0.0, 30.0, 0.01, blowup=None)
    assert X[-1, 0] == pytest.approx(np.exp(30.0), rel=1e-8)
    t, X = integrate(lambda X, t: X, [1.0], 0.0, 30.0, 0.01, blowup=1e15)
    assert X[-1, 0] == pytest.approx(np.exp(30.0), rel=1e-8)


def test_growth_rule_message_says_growth_and_how_to_lift_it():
    """The default growth rule still stops e^30, and says it was growth (by how much), not inf/NaN."""
    with pytest.raises(SimulationDiverged) as info:
        integrate(lambda X, t: X, [1.0], 0.0, 30.0, 0.01)
    err, message = info.value, str(info.value)
    assert err.step == 2833 and err.t == pytest.approx(28.32)
    assert "still finite but grew too much" in message and "from 1 to 2.01e+12" in message
    assert "blowup = 1e+12" in message and "blowup=None" in message
    assert "inf or NaN" in message  # only in the advice "stop only on inf or NaN"
    assert "became inf or NaN" not in message


def test_overflow_message_says_inf_or_nan():
    """With blowup=None a real blow-up still raises, and the message says the state overflowed."""
    f = oscillator_f(np.array([100.0]))
    with pytest.raises(SimulationDiverged, match=r"stability limit .*The state became inf or NaN") as info:
        integrate(f, [[[1.0], [0.0]]], 0.0, 100.0, 0.05, method="euler", blowup=None)
    assert "grew too much" not in str(info.value)
    # 5.1-fold per step: the default rule stops ~400 steps before the overflow
    with pytest.raises(SimulationDiverged) as early:
        integrate(f, [[[1.0], [0.0]]], 0.0, 100.0, 0.05, method="euler")
    assert early.value.step < info.value.step - 300


def test_step_times_names_its_arguments():
    """step_times checks t0, t1 and h by name and lands on t1."""
    from particles.integrators import step_times

    assert step_times(0, 0.25, 0.1).tolist() == [0.0, 0.1, 0.2, 0.25]
    assert step_times(np.float32(1.0), np.array(1.0), 0.1).tolist() == [1.0]
    with pytest.raises(ValueError, match="t0 must be a finite real number"):
        step_times("0", 1.0, 0.1)


def test_step_times_never_makes_a_step_of_length_zero():
    """Far from t = 0, where t0 + k h rounds, every step stays > 0 and at most h (to round-off) and ends on t1."""
    from particles.integrators import step_times

    rng = np.random.default_rng(3)
    for _ in range(3000):
        t0, h, n = rng.uniform(-1e6, 1e6), 10 ** rng.uniform(-5, 0), int(rng.integers(1, 400))
        t1 = t0 + n * h * (1 + rng.choice([0.0, 1e-15, -1e-15, 1e-10]))
        t = step_times(t0, t1, h)
        steps = np.diff(t)
        assert t[0] == t0 and t[-1] == t1 and steps.min() > 0, (t0, t1, h)
        assert steps.max() <= h + 4 * np.spacing(abs(t0) + abs(t1)), (t0, t1, h)
        assert len(steps) in (n, n + 1)


def test_convergence_plot_lines_are_distinguishable_and_h_axis_labelled():
    """Every method has its own marker and line style; the h axis labels every step size."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from particles.studies import convergence_study, plot_convergence

    study = convergence_study("harmonic_oscillator", n_steps=[16, 32, 64, 128])
    fig = plot_convergence(study)
    try:
        ax = fig.axes[0]
        fig.canvas.draw()
        lines = ax.get_lines()
        assert len(lines) == len(ALL)
        looks = {(ln.get_marker(), str(ln.get_linestyle()), ln.get_markersize(), ln.get_fillstyle()) for ln in lines}
        assert len(looks) == len(lines)
        by_name = {ln.get_label().split()[0]: ln for ln in lines}
        for a, b in [("midpoint", "trapezoid"), ("euler", "implicit_euler")]:
            la, lb = by_name[a], by_name[b]
            assert la.get_marker() != lb.get_marker() and la.get_linestyle() != lb.get_linestyle()
            assert la.get_markersize() < lb.get_markersize() and lb.get_fillstyle() == "none"
        labels = [t.get_text() for t in ax.get_xticklabels() if t.get_text()]
        assert len(labels) == 4
        np.testing.assert_allclose(sorted(float(s) for s in labels), np.sort(study["h"]), rtol=1e-2)
    finally:
        plt.close(fig)
