"""Autograder tests of exercise 01_integrator_order: four steppers and the measurement of their order.

Public tests use fixed inputs a student can reason about (the circle field from
(1, 0), a driven oscillator, made-up error sequences); hidden tests draw random
states, shapes, times, problems and error sequences from the grading seed
(fixture ``rng``). A measured order must be near the method's order in the
asymptotic range and, at any step counts, within 0.02 of the slope the reference
measures on the same problem (coarse steps, where that slope is not the nominal
order, catch an answer that returns the order without measuring it). Every
expected value comes from the reference library
(``particles.integrators``, ``particles.studies.order``), computed here in the
grader, never in the student's process.
"""

import math

import numpy as np
import pytest

from particles.course.grading.expect import LN10, expect_array, expect_float, expect_order
from particles.course.grading.memo import memoized
from particles.course.worker.registry import remote
from particles.course.worker.runner import GradingFailure, describe_value
from particles.integrators import euler, midpoint, rk4, trapezoid
from particles.problems import get_problem
from particles.studies.order import fit_order, global_error

EXERCISE = "01_integrator_order"
FORBIDDEN = {
    "particles.integrators.euler": "it is the Euler step you are asked to write",
    "particles.integrators.midpoint": "it is the midpoint step you are asked to write",
    "particles.integrators.trapezoid": "it is the trapezoid step you are asked to write",
    "particles.integrators.rk4": "it is the RK4 step you are asked to write",
    "particles.integrators.INTEGRATORS": "it holds the library's own steppers; write the steps yourself",
    "particles.integrators.integrate": "it is the time loop of the convergence study; write the loop yourself",
    "particles.studies.order.fit_order": "it is the least-squares slope you are asked to write",
    "particles.studies.order.global_error": "it is the global error you are asked to compute",
    "particles.studies.order.convergence_study": "it is the whole convergence study you are asked to write",
}

STEPS = {  # method -> (the student's function, the reference, its order, evaluations of f per step)
    "euler": ("euler_step", euler, 1, 1),
    "midpoint": ("midpoint_step", midpoint, 2, 2),
    "trapezoid": ("trapezoid_step", trapezoid, 2, 2),
    "rk4": ("rk4_step", rk4, 4, 4),
}
METHODS = list(STEPS)
OPTIONAL = {"rk4"}  # the notebook's stretch goal: its tests are shown apart and not scored
PARAMS = [pytest.param(m, marks=pytest.mark.optional) if m in OPTIONAL else m for m in METHODS]

# Numbers of steps of the order tests: in the asymptotic range of each method on every problem
# the hidden tests draw (checked against the reference below), and fast: at most 3000 steps.
N_STEPS = {"euler": [200, 400, 800, 1600], "midpoint": [40, 80, 160, 320],
           "trapezoid": [40, 80, 160, 320], "rk4": [20, 40, 80, 160]}
ORDER_TOLERANCE = 0.15
SLOPE_TOLERANCE = 0.02  # measured_order against the reference slope on the same problem and step counts


# -- helpers -----------------------------------------------------------------------------------


def _wrong_steps(method, f, X, t, h):
    """Typical wrong answers for one step of `method`: label -> the state they give."""
    f0 = f(X, t)
    wrong = {}
    if method == "euler":
        wrong["a midpoint step"] = midpoint(f, X, t, h)
        wrong["an Euler step with f evaluated at t + h instead of t"] = X + h * f(X, t + h)
        return wrong
    wrong["an Euler step"] = X + h * f0
    if method == "midpoint":
        wrong["a midpoint step that evaluates f at t instead of t + h/2"] = X + h * f(X + 0.5 * h * f0, t)
        wrong["a midpoint step that evaluates f at t + h instead of t + h/2"] = X + h * f(X + 0.5 * h * f0, t + h)
        wrong["a midpoint step that goes a full Euler step (not h/2) to the midpoint"] = \
            X + h * f(X + h * f0, t + 0.5 * h)
        wrong["a trapezoid step"] = trapezoid(f, X, t, h)
    elif method == "trapezoid":
        f1 = f(X + h * f0, t + h)
        wrong["a trapezoid step without the factor 1/2, X + h (f_0 + f_1)"] = X + h * (f0 + f1)
        wrong["a trapezoid step that evaluates f_1 at t instead of t + h"] = X + 0.5 * h * (f0 + f(X + h * f0, t))
        wrong["a step with the end slope f_1 only"] = X + h * f1
        wrong["a midpoint step"] = midpoint(f, X, t, h)
    else:
        k1 = f0
        k2 = f(X + 0.5 * h * k1, t + 0.5 * h)
        k3 = f(X + 0.5 * h * k2, t + 0.5 * h)
        k4 = f(X + h * k3, t + h)
        wrong["an RK4 step with the weights (1, 1, 1, 1)/4 instead of (1, 2, 2, 1)/6"] = \
            X + h / 4 * (k1 + k2 + k3 + k4)
        wrong["an RK4 step that divides by 4 instead of 6"] = X + h / 4 * (k1 + 2 * k2 + 2 * k3 + k4)
        wrong["an RK4 step with k4 taken at X + h k2 instead of X + h k3"] = \
            X + h / 6 * (k1 + 2 * k2 + 2 * k3 + f(X + h * k2, t + h))
        wrong["an RK4 step with k3 taken at X + h/2 k1 instead of X + h/2 k2"] = \
            X + h / 6 * (k1 + 4 * k2 + f(X + h * k2, t + h))
        wrong["a midpoint step"] = midpoint(f, X, t, h)
    return wrong


# the stages of each method, and their weights in X_new = X + h sum_i b_i k_i
_STAGE_NAMES = {"euler": ["f(X, t)"], "midpoint": ["f_0", "f_m"], "trapezoid": ["f_0", "f_1"],
                "rk4": ["k1", "k2", "k3", "k4"]}
_WEIGHTS = {"euler": [1.0], "midpoint": [0.0, 1.0], "trapezoid": [0.5, 0.5], "rk4": [1 / 6, 1 / 3, 1 / 3, 1 / 6]}
_WEIGHT_TEXT = {"euler": "1", "midpoint": "(0, 1): all of the midpoint slope f_m", "trapezoid": "(1/2, 1/2)",
                "rk4": "(1, 2, 2, 1)/6"}


def _stages(method, f, X, t, h):
    """The reference's slopes of one step of `method` (the k_i of its Butcher tableau)."""
    f0 = f(X, t)
    if method == "euler":
        return [f0]
    if method == "midpoint":
        return [f0, f(X + 0.5 * h * f0, t + 0.5 * h)]
    if method == "trapezoid":
        return [f0, f(X + h * f0, t + h)]
    k2 = f(X + 0.5 * h * f0, t + 0.5 * h)
    k3 = f(X + 0.5 * h * k2, t + 0.5 * h)
    return [f0, k2, k3, f(X + h * k3, t + h)]


def _weights_diagnosis(got, method, f, X, t, h):
    """'your step is X + h (0.333 f_0 + 0.667 f_1) ...' when the result combines the right slopes with wrong weights."""
    stages = _stages(method, f, X, t, h)
    if not isinstance(got, np.ndarray) or got.shape != np.shape(X) or got.dtype.kind != "f" \
            or np.size(X) < len(stages) + 2 or not np.all(np.isfinite(got)):
        return ""
    A = h * np.stack([np.ravel(k) for k in stages], axis=1)
    y = np.ravel(got - X)
    w, *_ = np.linalg.lstsq(A, y, rcond=None)
    if np.linalg.norm(A @ w - y) > 1e-9 * (np.linalg.norm(y) + 1e-12) or np.allclose(w, _WEIGHTS[method], atol=1e-6):
        return ""
    terms = " + ".join(f"{wi:.3g} {name}" for wi, name in zip(w, _STAGE_NAMES[method]))
    return (f"; your step is X + h ({terms}): the right slopes with the wrong weights (the {method} step weights them "
            f"{_WEIGHT_TEXT[method]})")


def _check_step(student, method, f, X, t, h, where, check_inputs=False, count=False, hidden=False):
    """One step of the student's stepper against the reference, with hints for typical slips.

    A hidden test (`hidden`) keeps its random t and h out of the message.
    """
    name, reference, _, evaluations = STEPS[method]
    call = (f"{name}(f, X of shape {X.shape}, t, h) on {where} (random X, t and h)" if hidden else
            f"{name}(f, X of shape {X.shape}, t={t:.4g}, h={h:.4g}) on {where}")
    got = student.call(name, f, X, t, h, check_inputs=check_inputs)
    try:
        expect_array(got, reference(f, X, t, h), call, hints=lambda: _wrong_steps(method, f, X, t, h),
                     show_values=not hidden)
    except GradingFailure as failure:
        message = str(failure)
        if "; your " not in message:
            message += _weights_diagnosis(got, method, f, X, t, h)
        raise GradingFailure(message) from None
    if count and student.calls_of(0) != evaluations:
        raise GradingFailure(f"{name} evaluated f {student.calls_of(0)} times in one step; the {method} method "
                             f"uses exactly {evaluations}")


def _random_problem(rng, name):
    """Random parameters of problem `name` (an end time included)."""
    if name == "circle":
        a, r = rng.uniform(0.0, 2 * np.pi), rng.uniform(0.5, 2.0)
        return {"X0": [r * math.cos(a), r * math.sin(a)], "t1": rng.uniform(2.0, 6.0)}
    if name == "harmonic_oscillator":
        return {"omega": rng.uniform(0.5, 2.5), "x0": rng.uniform(-2.0, 2.0), "v0": rng.uniform(-2.0, 2.0),
                "t1": rng.uniform(2.0, 6.0)}
    if name == "projectile_drag":
        return {"g": rng.uniform(5.0, 15.0), "c": rng.uniform(0.2, 2.0), "v0": rng.uniform(-5.0, 10.0, 2).tolist(),
                "t1": rng.uniform(1.0, 3.0)}
    omega = rng.uniform(0.5, 2.5)
    return {"omega": omega, "amplitude": rng.uniform(0.5, 2.0), "frequency": omega + rng.uniform(0.5, 1.5),
            "x0": rng.uniform(-2.0, 2.0), "v0": rng.uniform(-2.0, 2.0), "t1": rng.uniform(2.0, 6.0)}


@memoized
def _reference_errors(name, params, method, n_steps):
    """The reference stepper's global errors on problem `name` with `params`, one per step count (an array)."""
    problem = get_problem(name, **params)
    return np.array([global_error(problem, method, int(n)) for n in n_steps])


def _reference_order(name, params, method, n_steps):
    """The slope the reference library measures on problem `name` with `params` and these step counts."""
    problem = get_problem(name, **params)
    h = (problem.t1 - problem.t0) / np.asarray(n_steps, dtype=float)
    return fit_order(h, _reference_errors(name, params, method, list(n_steps)))


def _clean_problem(rng, name, method):
    """Random parameters on which the reference stepper shows its order within 0.05.

    Some draws (an error constant that nearly vanishes at t1, a step too coarse
    for a fast oscillator) would make a correct submission miss its order; the
    grader redraws those, so a failure is always the submission's.
    """
    for _ in range(50):
        params = _random_problem(rng, name)
        order = _reference_order(name, params, method, N_STEPS[method])
        if abs(order - STEPS[method][2]) < 0.05:
            return params
    raise RuntimeError(f"no clean {name} problem for {method} in 50 draws")


_LABELS = {"circle": "the circle field", "harmonic_oscillator": "the harmonic oscillator",
           "projectile_drag": "the projectile with drag", "forced_oscillator": "the driven oscillator"}


def _clause(failure):
    """The diagnosis a failure message ends with ("your result matches ...", "your step is ..."), or ""."""
    text = str(failure)
    if "; your result matches " in text:
        return "your result matches " + text.split("; your result matches ", 1)[1]
    if "; your " in text:
        return "your " + text.rsplit("; your ", 1)[1]
    return ""


def _diagnosis(student, method, only_step=False):
    """Why a measured order is off: the step itself, the errors of the study, or the slope fitted to them.

    With `only_step` (the errors are known to be wrong), only whether the step is.
    """
    name, reference, _, _ = STEPS[method]
    f = remote("forced_oscillator", omega=1.7, amplitude=1.3, frequency=2.9)
    X = np.array([[[0.8, -0.3], [0.4, 1.1]], [[-1.2, 0.5], [0.2, -0.7]]])
    try:
        got = student.call(name, f, X, 0.35, 0.05, check_inputs=True)
        try:
            expect_array(got, reference(f, X, 0.35, 0.05), name,
                         hints=lambda: _wrong_steps(method, f, X, 0.35, 0.05))
        except GradingFailure as failure:
            clause = _clause(failure) or _weights_diagnosis(got, method, f, X, 0.35, 0.05)[2:]
            raise GradingFailure(f"; one step of your {name} does not match the reference"
                                 + (f" ({clause})" if clause else "") + f", see the tests of {name}") from None
    except GradingFailure as failure:
        if "in place" in str(failure):
            return f"; your {name} modifies X in place, which can overwrite X0 between the runs of the study"
        return str(failure) if str(failure).startswith("; one step") else \
            f"; one step of your {name} does not match the reference, see the tests of {name}"
    if only_step:
        return f"; your {name} matches the reference on a single step, so look at the loop and the error"
    # the step is right: the errors of the study, then the slope
    driven = {"omega": 1.3, "amplitude": 0.8, "frequency": 2.1, "x0": 0.5, "v0": -0.2, "t1": 2.0}  # depends on t
    field, exact = remote("forced_oscillator", **driven), remote("forced_oscillator", attr="exact", **driven)
    problem = field.problem
    try:
        got = student.call("convergence_errors", method, field, problem.X0, problem.t0, problem.t1, exact, [10, 20])
        errors = np.asarray(got[1], dtype=float) if isinstance(got, (tuple, list)) and len(got) == 2 else got
        expect_array(errors, _reference_errors("forced_oscillator", driven, method, [10, 20]),
                     "convergence_errors", rtol=1e-6, atol=1e-13,
                     hints=lambda: _error_hints(method, field, exact, problem.X0, problem.t0, problem.t1, [10, 20]))
    except (GradingFailure, TypeError, ValueError) as failure:
        clause = _clause(failure)
        return ("; your steps are right, but your convergence_errors does not give the reference errors"
                + (f" ({clause})" if clause else "") + ", see the tests of convergence_errors")
    h, e = np.array([0.2, 0.1, 0.05, 0.025]), np.array([0.031, 0.0088, 0.0021, 0.00052])
    try:
        _check_slope(student, h, e, "observed_order")
    except GradingFailure as failure:
        clause = _clause(failure)
        return ("; your steps and errors are right, but your observed_order does not give the least-squares slope"
                + (f" ({clause})" if clause else "") + ", see the tests of observed_order")
    return (f"; your {name}, convergence_errors and observed_order match the reference on small cases, so look at "
            "how measured_order combines them")


def _log_diagnosis(got, reference):
    """'; ... log10 and ln mixed ...' when `got` is the reference slope divided or multiplied by ln(10)."""
    if reference != 0 and abs(got * LN10 / reference - 1) <= 0.005:
        return ("; your order is the measured slope divided by ln(10) = 2.303: log10 on the errors' axis and ln on "
                "the steps' axis (or the other way round) in observed_order; use the same logarithm on both axes")
    if reference != 0 and abs(got / LN10 / reference - 1) <= 0.005:
        return ("; your order is the measured slope times ln(10) = 2.303: ln on the errors' axis and log10 on the "
                "steps' axis in observed_order; use the same logarithm on both axes")
    return ""


def _judge_order(student, method, name, params, n_steps=None, hidden=False, feedback=None):
    """measured_order(method, ...) of the student on problem `name`, judged against what it should measure.

    With the default step counts (asymptotic range) the value must be within ORDER_TOLERANCE of the
    method's order; with any step counts it must be within SLOPE_TOLERANCE of the slope the reference
    library measures for the same problem and step counts, so a hard-coded order does not pass. A hidden
    test (`hidden`) keeps its random end time and step counts out of the message. With `feedback`, the
    figure of the errors is attached first, its label giving the order measured_order returned: the
    figure and the message show the same number.
    """
    f, exact = remote(name, **params), remote(name, attr="exact", **params)
    problem = f.problem
    asymptotic = n_steps is None
    n_steps = N_STEPS[method] if asymptotic else list(n_steps)
    try:
        got = student.call("measured_order", method, f, problem.X0, problem.t0, problem.t1, exact, n_steps)
    except GradingFailure:
        if feedback is not None:
            _figure_errors(feedback, student, method, name, params, n_steps, hidden=hidden)
        raise
    if feedback is not None:
        number = isinstance(got, (int, float, np.integer, np.floating)) and not isinstance(got, (bool, np.bool_))
        _figure_errors(feedback, student, method, name, params, n_steps, hidden=hidden,
                       measured=float(got) if number else None)
    call = (f"measured_order('{method}', f, X0, t0, t1, exact, n_steps) on {_LABELS[name]} (random problem and "
            "step counts)" if hidden else f"measured_order('{method}', f, X0, t0={problem.t0:g}, t1={problem.t1:.3g}, "
            f"exact, n_steps={n_steps}) on {_LABELS[name]}")
    if isinstance(got, np.ndarray) and got.shape == ():
        got = got[()]
    if isinstance(got, (bool, np.bool_)) or not isinstance(got, (int, float, np.integer, np.floating)):
        raise GradingFailure(f"{call} returned {describe_value(got)}, expected a number")
    got = float(got)
    nominal = STEPS[method][2]
    reference = _reference_order(name, params, method, n_steps)
    if asymptotic:
        try:
            expect_order(got, nominal, f"your {method} step ({call})", tolerance=ORDER_TOLERANCE)
        except GradingFailure as failure:
            swapped = ("; your result is 1 / the slope: the slope of log(h) against log(error), the axes swapped "
                       "(measured_order must pass h then the errors to observed_order, as observed_order(h, errors))"
                       if reference != 0 and abs(got * reference - 1) <= 0.01 else "")
            raise GradingFailure(str(failure) + (_log_diagnosis(got, reference) or swapped
                                                 or _diagnosis(student, method))) from None
    if not abs(got - reference) <= SLOPE_TOLERANCE:
        message = (f"{call} returned {got:.4g}, but the global errors of the {method} method at these step "
                   f"counts fall with a least-squares slope of {reference:.4g} (measured by the reference, "
                   f"tolerance {SLOPE_TOLERANCE:g})")
        if got == nominal:
            message += (f"; {got:g} is the method's nominal order, not a measurement: return the slope of "
                        "your own errors, whatever it comes out as")
        elif reference != 0 and abs(got * reference - 1) <= 0.01:
            message += ("; your result is 1 / the slope: the slope of log(h) against log(error), the axes swapped "
                        "(measured_order must pass h then the errors to observed_order, as observed_order(h, errors))")
        else:
            message += _log_diagnosis(got, reference) or _diagnosis(student, method)
        raise GradingFailure(message)


def _reference_final(step, f, X0, t0, t1, N):
    h = (t1 - t0) / N
    X = np.asarray(X0, dtype=float)
    for k in range(N):
        X = step(f, X, t0 + k * h, h)
    return X


def _check_errors(student, method, name, params, n_steps, check_inputs=False, hidden=False):
    """convergence_errors(method, ...) of the student against the reference global errors.

    A hidden test (`hidden`) keeps its random problem and step counts out of the message.
    """
    f, exact = remote(name, **params), remote(name, attr="exact", **params)
    problem = f.problem
    X0, t0, t1 = problem.X0, problem.t0, problem.t1
    call = (f"convergence_errors('{method}', f, X0 of shape {X0.shape}, t0, t1, exact, n_steps) on {_LABELS[name]} "
            "(random problem and step counts)" if hidden else
            f"convergence_errors('{method}', f, X0 of shape {X0.shape}, t0={t0:g}, t1={t1:.3g}, exact, "
            f"n_steps={list(n_steps)}) on {_LABELS[name]}")
    got = student.call("convergence_errors", method, f, X0, t0, t1, exact, list(n_steps), check_inputs=check_inputs)
    if not isinstance(got, (tuple, list)) or len(got) != 2:
        kind = f"a {type(got).__name__} of {len(got)} values" if isinstance(got, (tuple, list)) else describe_value(got)
        raise GradingFailure(f"{call} returned {kind}, expected the tuple (h, errors)")
    n = np.asarray(n_steps, dtype=float)
    expect_array(np.asarray(got[0]) if isinstance(got[0], list) else got[0], (t1 - t0) / n,
                 f"the step sizes h of {call}", rtol=1e-12, show_values=not hidden,
                 hints={"the numbers of steps N instead of the step sizes h = (t1 - t0) / N": n,
                        "t1 / N: the step sizes without t0 (h = (t1 - t0) / N)": t1 / n})
    expected = _reference_errors(name, params, method, list(n_steps))
    errors = np.asarray(got[1]) if isinstance(got[1], list) else got[1]
    try:
        expect_array(errors, expected, f"the errors of {call}", rtol=1e-6, atol=1e-13,
                     hints=lambda: _error_hints(method, f, exact, X0, t0, t1, n_steps), show_values=not hidden)
    except GradingFailure as failure:
        extra = _diagnosis(student, method, only_step=True)
        if "; your result matches" in str(failure) and "matches the reference on a single step" in extra:
            extra = ""  # the hint says what is wrong, and the step is right
        raise GradingFailure(str(failure) + extra) from None


def _error_hints(method, f, exact, X0, t0, t1, n_steps):
    """Typical wrong global errors of convergence_errors: label -> the errors they give."""
    step, X1 = STEPS[method][1], exact(t1)
    finals = {k: _reference_final(step, f, X0, t0, t1, int(k)) for k in n_steps}
    more = {k: step(f, finals[k], t1, (t1 - t0) / k) for k in n_steps}
    fewer = {k: _reference_final(step, f, X0, t0, t1 - (t1 - t0) / k, int(k) - 1) for k in n_steps}
    def late_step(f_, X_, t_, h_):
        return step(f_, X_, t_ + h_, h_)

    late = {k: _reference_final(late_step, f, X0, t0, t1, int(k)) for k in n_steps}
    return {
        "the Euclidean norm of X_N - X(t1) instead of its largest component":
            [np.linalg.norm((finals[k] - X1).ravel()) for k in n_steps],
        "the largest component of X_N - X(t1) with its sign, not its absolute value":
            [np.max(finals[k] - X1) for k in n_steps],
        "the errors after N + 1 steps: your loop takes one step too many (N steps of h = (t1 - t0) / N go from "
        "t0 to t1; a loop over the N + 1 times of np.linspace(t0, t1, N + 1) takes N + 1)":
            [np.max(np.abs(more[k] - X1)) for k in n_steps],
        "the errors after N + 1 steps, against X(t1 + h): your loop takes one step too many (N steps of h = "
        "(t1 - t0) / N go from t0 to t1)": [np.max(np.abs(more[k] - exact(t1 + (t1 - t0) / k))) for k in n_steps],
        "the errors after N - 1 steps: your loop takes one step too few (N steps of h = (t1 - t0) / N go from t0 "
        "to t1; range(1, N) or the times of np.linspace(t0, t1, N) take N - 1)":
            [np.max(np.abs(fewer[k] - X1)) for k in n_steps],
        "the errors of a loop that passes t + h to each step instead of t0 + k h (the step from t_k starts at t_k)":
            [np.max(np.abs(late[k] - X1)) for k in n_steps],
        "the errors relative to the largest component of X(t1), not the absolute errors":
            [np.max(np.abs(finals[k] - X1)) / np.max(np.abs(X1)) for k in n_steps],
    }


def _slope_hints(h, e):
    """Typical wrong slopes for the error sequence e(h): label -> value."""
    u, w = np.log(h), np.log(e)
    p = fit_order(h, e)
    return {
        "the slope between the first two points only": (w[1] - w[0]) / (u[1] - u[0]),
        "the slope between the first and the last point only": (w[-1] - w[0]) / (u[-1] - u[0]),
        "the mean of the slopes between neighbouring points": float(np.mean(np.diff(w) / np.diff(u))),
        "the least-squares slope with log10 on one axis and ln on the other": p / math.log(10),
        "the least-squares slope with ln on one axis and log10 on the other": p * math.log(10),
        "the slope of log(h) against log(error), the axes swapped": float(np.polyfit(w, u, 1)[0]),
        "minus the slope": -p,
        "the slope of log(error) against h: the step axis is not logarithmic (fit log(error) against log(h))":
            lambda got: _slope_of(got, [np.polyfit(h, w, 1)[0], np.polyfit(h, w / math.log(10), 1)[0]]),
        "the slope of the errors against log(h): the error axis is not logarithmic (fit log(error) against "
        "log(h))": lambda got: _slope_of(got, [np.polyfit(u, e, 1)[0], np.polyfit(u / math.log(10), e, 1)[0]]),
        "the slope of the errors against h: neither axis is logarithmic (fit log(error) against log(h))":
            float(np.polyfit(h, e, 1)[0]),
    }


def _slope_of(got, candidates):
    """A predicate's verdict: whether the number `got` is one of the wrong slopes `candidates` (to 1e-8)."""
    got = float(np.asarray(got))
    return any(abs(got - c) <= 1e-8 * abs(c) + 1e-10 for c in candidates)


def _check_slope(student, h, e, call, check_inputs=False, hidden=False):
    """observed_order(h, e) of the student against the reference least-squares slope, with typical wrong slopes."""
    got = student.call("observed_order", h, e, check_inputs=check_inputs)
    expect_float(got, fit_order(h, e), call, rtol=1e-8, atol=1e-10, hints=lambda: _slope_hints(h, e),
                 show_values=not hidden)


# -- figures for the feedback ------------------------------------------------------------------


def _figure_errors(feedback, student, method, name, params, n_steps, hidden=False, measured=None):
    """Attach the student's global errors against h beside the reference's, before the test judges them.

    The student's errors come from their convergence_errors; a hidden test plots h / h_0 and errors relative
    to the reference's at h_0, so that its random problem does not show. With `measured` (what the student's
    measured_order returned, which the test's message shows), the label gives that number, and the caption
    the slope of the errors drawn when it is another.
    """
    f, exact = remote(name, **params), remote(name, attr="exact", **params)
    problem = f.problem
    h = (problem.t1 - problem.t0) / np.asarray(n_steps, dtype=float)
    reference = _reference_errors(name, params, method, list(n_steps))
    try:
        got = student.call("convergence_errors", method, f, problem.X0, problem.t0, problem.t1, exact, list(n_steps))
        yours = np.asarray(got[1], dtype=float) if isinstance(got, (tuple, list)) and len(got) == 2 else None
    except (GradingFailure, TypeError, ValueError):
        yours = None
    usable = yours is not None and yours.shape == h.shape and bool(np.all(np.isfinite(yours)) and np.all(yours > 0))
    slope = f" (slope {fit_order(h, yours):.2f})" if usable else ""
    note = ""
    if measured is not None:  # the number of the message, and the slope drawn when it is another
        drawn = fit_order(h, yours) if usable else None
        other = (f"; the errors drawn fall with {drawn:.2f}" if drawn is not None
                 and not abs(drawn - measured) <= SLOPE_TOLERANCE else "")
        slope = f" (slope {measured:.2f} by your measured_order{other})"
    yours = yours if yours is not None and yours.ndim == 1 else None
    x, scale = (h / h[0], reference[0]) if hidden else (h, 1.0)
    series = [{"label": f"reference (slope {fit_order(h, reference):.2f})", "x": x, "y": reference / scale}]
    if yours is not None:
        series.insert(0, {"label": f"yours{slope}", "x": x[:len(yours)], "y": yours / scale})
    where = "a random problem" if hidden else _LABELS[name]
    feedback.curve(f"Global error of your {method} steps on {where}",
                   "step h / coarsest step" if hidden else "step h (s)",
                   "error / reference error at the coarsest step" if hidden else "largest error at t1",
                   series, loglog=True,
                   caption=f"The slope of each line is the order measured from it; {method} has order "
                           f"{STEPS[method][2]}." + note + ("" if yours is not None else
                                                            " Your convergence_errors gave no errors to draw."))


# -- the steppers ------------------------------------------------------------------------------


@pytest.mark.points(1)
@pytest.mark.parametrize("method", PARAMS)
def test_step_circle(student, method):
    """One step of each stepper on the circle field f = (-y, x) from (1, 0) with h = 0.1."""
    _check_step(student, method, remote("circle"), np.array([1.0, 0.0]), 0.0, 0.1, "the circle field")


@pytest.mark.points(1)
@pytest.mark.parametrize("method", PARAMS)
def test_step_driven_particles(student, method):
    """One step on three particles in 2D driven in time: right values, X unchanged, right number of evaluations."""
    f = remote("forced_oscillator", counted=True, omega=2.0, amplitude=1.5, frequency=3.0)  # the grader counts
    X = np.array([[[1.0, 0.0], [0.0, 1.0]], [[0.5, -0.5], [2.0, 0.0]], [[-1.0, 0.25], [0.0, -1.0]]])
    _check_step(student, method, f, X, 0.7, 0.1, "the driven oscillator with omega = 2, A = 1.5, Omega = 3",
                check_inputs=True, count=True)


@pytest.mark.points(2)
@pytest.mark.hidden
@pytest.mark.parametrize("method", PARAMS)
def test_step_random(student, rng, method):
    """Each stepper matches the reference on random states of several shapes, times and steps."""
    for name in ["forced_oscillator", "forced_oscillator", "projectile_drag", "harmonic_oscillator", "circle"]:
        t, h = rng.uniform(0.0, 10.0), rng.uniform(0.001, 0.3)
        n, d = int(rng.integers(1, 6)), int(rng.integers(1, 4))
        if name == "circle":
            f, X = remote("circle"), rng.normal(size=2)
        elif name == "projectile_drag":
            f = remote("projectile_drag", g=rng.uniform(5.0, 15.0), c=rng.uniform(0.1, 2.0))
            X = rng.normal(size=(n, 2, 2))
        elif name == "harmonic_oscillator":
            f, X = remote("harmonic_oscillator", omega=rng.uniform(0.5, 3.0)), rng.normal(size=(n, 2, d))
        else:
            omega = rng.uniform(0.5, 3.0)
            f = remote("forced_oscillator", omega=omega, amplitude=rng.uniform(0.5, 2.0),
                       frequency=omega + rng.uniform(0.5, 2.0))
            X = rng.normal(size=(n, 2, d) if rng.random() < 0.5 else (n, 2))
        _check_step(student, method, f, X, t, h, _LABELS[name], check_inputs=True, hidden=True)


# -- the global errors -------------------------------------------------------------------------


@pytest.mark.points(1)
def test_convergence_errors_circle(student, feedback):
    """convergence_errors gives h = 5/N and Euler's max-norm errors at t1 = 5 s on the circle field."""
    _figure_errors(feedback, student, "euler", "circle", {"X0": [1.0, 0.0], "t1": 5.0}, [20, 40, 80])
    _check_errors(student, "euler", "circle", {"X0": [1.0, 0.0], "t1": 5.0}, [20, 40, 80], check_inputs=True)


@pytest.mark.points(2)
@pytest.mark.hidden
def test_convergence_errors_random(student, rng, feedback):
    """convergence_errors matches the reference global errors on random problems, methods and step counts."""
    for name in ["forced_oscillator", "projectile_drag", str(rng.choice(["circle", "harmonic_oscillator"]))]:
        method = str(rng.choice(["euler", "midpoint", "trapezoid"]))
        n_steps = sorted(int(k) for k in rng.choice(np.arange(5, 150), size=3, replace=False))
        params = _random_problem(rng, name)
        _figure_errors(feedback, student, method, name, params, n_steps, hidden=True)
        _check_errors(student, method, name, params, n_steps, check_inputs=True, hidden=True)


# -- the slope ---------------------------------------------------------------------------------


@pytest.mark.points(1)
def test_observed_order_exact_powers(student):
    """observed_order returns 2 for errors exactly 3 h^2 at h = 0.1, 0.05, 0.025, 0.0125."""
    h = np.array([0.1, 0.05, 0.025, 0.0125])
    _check_slope(student, h, 3 * h**2, "observed_order(h=[0.1, 0.05, 0.025, 0.0125], errors=3 h^2)")


@pytest.mark.points(1)
def test_observed_order_noisy(student):
    """observed_order fits the least-squares slope through all points of a noisy error sequence."""
    h = np.array([0.2, 0.1, 0.05, 0.025])
    e = np.array([0.031, 0.0088, 0.0021, 0.00052])
    _check_slope(student, h, e, "observed_order(h=[0.2, 0.1, 0.05, 0.025], errors=[0.031, 0.0088, 0.0021, 0.00052])",
                 check_inputs=True)


@pytest.mark.points(2)
@pytest.mark.hidden
def test_observed_order_random(student, rng):
    """observed_order matches the reference least-squares slope on random noisy, unevenly spaced sequences."""
    for _ in range(3):
        m = int(rng.integers(4, 8))
        h = rng.uniform(0.05, 0.5) * np.cumprod(np.r_[1.0, rng.uniform(0.3, 0.8, m - 1)])
        p, C = rng.uniform(0.5, 4.5), math.exp(rng.uniform(-3.0, 3.0))
        e = C * h**p * np.exp(rng.normal(0.0, 0.15, m))
        _check_slope(student, h, e, f"observed_order on {m} random step sizes with errors ~ C h^p (random C and p, "
                     "with noise)", check_inputs=True, hidden=True)


# -- the measured orders -----------------------------------------------------------------------


@pytest.mark.points(1)
@pytest.mark.parametrize("method", PARAMS)
def test_measured_order_circle(student, method, feedback):
    """measured_order finds the order of each stepper (1, 2, 2, 4) on the circle field up to t1 = 5 s."""
    _judge_order(student, method, "circle", {"X0": [1.0, 0.0], "t1": 5.0}, feedback=feedback)


@pytest.mark.points(2)
@pytest.mark.hidden
@pytest.mark.parametrize("method", PARAMS)
def test_measured_order_random(student, rng, method, feedback):
    """measured_order finds each stepper's order on a random driven oscillator and one other random problem."""
    for name in ["forced_oscillator", str(rng.choice(["circle", "harmonic_oscillator", "projectile_drag"]))]:
        params = _clean_problem(rng, name, method)
        _judge_order(student, method, name, params, hidden=True, feedback=feedback)


def _coarse_problem(rng, method):
    """A random problem and coarse step counts on which the reference slope misses the nominal order.

    Far from the asymptotic range (a handful of steps over several seconds) the measured slope differs
    from the order by 0.1 or more (Euler on the circle at 4, 8, 16 steps measures 1.23): a submission
    that measures passes, one that returns the textbook order does not.
    """
    for _ in range(50):
        name = str(rng.choice(["circle", "harmonic_oscillator", "forced_oscillator"]))
        params = _random_problem(rng, name)
        n0 = int(rng.integers(3, 7))
        n_steps = [n0, 2 * n0, 4 * n0]
        order = _reference_order(name, params, method, n_steps)
        if 0.1 <= abs(order - STEPS[method][2]) <= 1.0:
            return name, params, n_steps
    raise RuntimeError(f"no coarse problem for {method} in 50 draws")


@pytest.mark.points(1)
@pytest.mark.hidden
@pytest.mark.parametrize("method", PARAMS)
def test_measured_order_coarse_steps(student, rng, method):
    """measured_order reports the slope it measures, also at coarse steps where it is not the nominal order."""
    name, params, n_steps = _coarse_problem(rng, method)
    _judge_order(student, method, name, params, n_steps, hidden=True)
