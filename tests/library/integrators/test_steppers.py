"""The ODE steppers (particles.integrators.steppers): orders, amplification factors, invariants, Newton."""

import numpy as np
import pytest
import scipy.sparse

from particles import ConvergenceError, integrate
from particles.integrators import INTEGRATORS, euler, implicit_euler, midpoint, rk4, symplectic_euler, trapezoid, verlet
from particles.problems import circle, harmonic_oscillator, projectile_drag
from particles.studies import fit_order, global_error

from .helpers import ALL, GENERIC, SECOND_ORDER_LAYOUT, oscillator_f


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


# -- implicit_euler without a Jacobian: inexact Newton-GMRES --------------------


def heat_equation(N=300):
    """f(X) = X'' on (0, 1), X = 0 at both ends, N interior points; returns f, a start X and the matrix."""
    import scipy.sparse

    dx = 1.0 / (N + 1)
    calls = []

    def f(X, t):
        calls.append(1)
        Xp = np.concatenate([[0.0], X, [0.0]])
        return (Xp[2:] - 2 * Xp[1:-1] + Xp[:-2]) / dx**2

    x = np.linspace(dx, 1 - dx, N)
    L = scipy.sparse.diags([np.ones(N - 1), -2 * np.ones(N), np.ones(N - 1)], [-1, 0, 1]) / dx**2
    return f, np.sin(np.pi * x) + 0.3 * np.sin(7 * np.pi * x), L.tocsc(), calls


@pytest.mark.parametrize("h", [1e-4, 1e-3, 1e-2])
def test_matrix_free_implicit_euler_costs_less_than_a_dense_jacobian(h):
    """Issue 13: on a 300-unknown heat equation a step costs fewer evaluations of f than 2 dense FD Jacobians (602)."""
    import scipy.sparse
    import scipy.sparse.linalg

    from particles.integrators import implicit_euler

    f, X, L, calls = heat_equation()
    Y = implicit_euler(f, X, 0.0, h)
    exact = scipy.sparse.linalg.spsolve(scipy.sparse.identity(len(X), format="csc") - h * L, X)
    np.testing.assert_allclose(Y, exact, rtol=0, atol=1e-10)
    assert len(calls) < 602


def test_matrix_free_implicit_euler_reports_a_gmres_failure():
    """GMRES that cannot reduce the linear residual (a large cyclic shift) raises ConvergenceError; jac= solves it."""
    from particles.integrators import implicit_euler

    X = np.zeros(300)
    X[0] = 1.0
    f = lambda X, t: 1e3 * np.roll(X, 1)  # noqa: E731
    with pytest.raises(ConvergenceError, match=r"GMRES did not reach .* no usable Newton step.*Pass the Jacobian"):
        implicit_euler(f, X, 0.0, 1.0)
    P = np.roll(np.eye(300), 1, axis=0)
    Y = implicit_euler(f, X, 0.0, 1.0, jac=lambda X, t: 1e3 * P)
    np.testing.assert_allclose(Y - 1e3 * np.roll(Y, 1), X, atol=1e-9)
