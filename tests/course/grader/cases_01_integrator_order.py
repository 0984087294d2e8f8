"""Wrong and alternative submissions of exercise 01_integrator_order (format: ``exercise_corpus.py``).

The wrong ones are the slips students make with these methods: a midpoint step
at the wrong time (invisible on the time-independent circle field, caught by
the driven oscillator), trapezoid weights that are off, an RK4 with a wrong
coefficient, an Euler step that overwrites the caller's state, an order fit
from two points or with mixed logarithms, the Euclidean norm for the error,
the library's own stepper, and a measured_order that returns the textbook order
without measuring (caught where coarse steps make the measured slope differ from
it). The correct variant is written differently from
the master throughout.
"""

EXERCISE = "01_integrator_order"

WRONG_TIME = "your result matches a midpoint step that evaluates f at t instead of t + h/2"

REJECTED = {
    "midpoint_at_wrong_time": {
        "culprit": "midpoint_step",
        "replace": {"midpoint_step": '''
def midpoint_step(f, X, t, h):
    X_m = X + 0.5 * h * f(X, t)
    return X + h * f(X_m, t)
'''},
        "fails": {
            "test_step_driven_particles[midpoint]": WRONG_TIME,
            "test_step_random[midpoint]": WRONG_TIME,
            "test_measured_order_random[midpoint]": "expected 2; one step of your midpoint_step does not match the "
                                                    "reference (your result matches a midpoint step that evaluates f "
                                                    "at t instead of t + h/2)",
        },
        "passes": ["test_step_circle[midpoint]", "test_measured_order_circle[midpoint]",
                   "test_step_driven_particles[trapezoid]", "test_convergence_errors_circle"],
    },
    "trapezoid_without_one_half": {
        "culprit": "trapezoid_step",
        "replace": {"trapezoid_step": '''
def trapezoid_step(f, X, t, h):
    f_0 = f(X, t)
    f_1 = f(X + h * f_0, t + h)
    return X + h * (f_0 + f_1)
'''},
        "fails": {
            "test_step_circle[trapezoid]": "your result matches a trapezoid step without the factor 1/2",
            "test_step_random[trapezoid]": "without the factor 1/2",
            "test_measured_order_circle[trapezoid]": "your trapezoid step (measured_order('trapezoid'",
            "test_measured_order_random[trapezoid]": "(your result matches a trapezoid step without the factor 1/2",
        },
        "passes": ["test_step_circle[midpoint]", "test_measured_order_circle[midpoint]"],
    },
    "trapezoid_uneven_weights": {
        "culprit": "trapezoid_step",
        "replace": {"trapezoid_step": '''
def trapezoid_step(f, X, t, h):
    f_0 = f(X, t)
    f_1 = f(X + h * f_0, t + h)
    return X + h * (f_0 + 2 * f_1) / 3
'''},
        "fails": {
            "test_step_circle[trapezoid]": "trapezoid_step(f, X of shape (2,), t=0, h=0.1) on the circle field is off",
            "test_step_driven_particles[trapezoid]": "your step is X + h (0.333 f_0 + 0.667 f_1): the right slopes with "
                                                     "the wrong weights (the trapezoid step weights them (1/2, 1/2))",
            "test_step_random[trapezoid]": "your step is X + h (0.333 f_0 + 0.667 f_1)",
            "test_measured_order_circle[trapezoid]": "converges with order 1.",
            "test_measured_order_random[trapezoid]": "expected 2; one step of your trapezoid_step does not match the "
                                                     "reference (your step is X + h (0.333 f_0 + 0.667 f_1)",
        },
        "passes": ["test_step_circle[euler]", "test_measured_order_circle[euler]", "test_observed_order_noisy"],
    },
    "rk4_equal_weights": {
        "culprit": "rk4_step",
        "replace": {"rk4_step": '''
def rk4_step(f, X, t, h):
    k1 = f(X, t)
    k2 = f(X + 0.5 * h * k1, t + 0.5 * h)
    k3 = f(X + 0.5 * h * k2, t + 0.5 * h)
    k4 = f(X + h * k3, t + h)
    return X + h / 4 * (k1 + k2 + k3 + k4)
'''},
        "fails": {
            "test_step_circle[rk4]": "your result matches an RK4 step with the weights (1, 1, 1, 1)/4",
            "test_measured_order_circle[rk4]": "expected 4; one step of your rk4_step does not match the reference "
                                               "(your result matches an RK4 step with the weights (1, 1, 1, 1)/4",
        },
        "passes": ["test_step_circle[midpoint]", "test_measured_order_circle[trapezoid]"],
    },
    "euler_overwrites_X": {
        "culprit": "euler_step",
        "replace": {"euler_step": '''
def euler_step(f, X, t, h):
    X += h * f(X, t)
    return X
'''},
        "fails": {
            "test_step_driven_particles[euler]": "`euler_step` modified its input `X` in place",
            "test_step_random[euler]": "modified its input `X` in place",
            "test_measured_order_circle[euler]": "expected 1; your euler_step modifies X in place",
        },
        "passes": ["test_step_circle[euler]", "test_observed_order_noisy"],
    },
    "order_from_first_two_errors": {
        "culprit": "observed_order",
        "replace": {"observed_order": '''
def observed_order(h, errors):
    return float(np.log(errors[0] / errors[1]) / np.log(h[0] / h[1]))
'''},
        "fails": {
            "test_observed_order_noisy": "your result matches the slope between the first two points only",
            "test_observed_order_random": "your result matches the slope between the first two points only",
            "test_measured_order_coarse_steps[euler]": "your steps and errors are right, but your observed_order does "
                                                       "not give the least-squares slope (your result matches the "
                                                       "slope between the first two points only)",
        },
        "passes": ["test_observed_order_exact_powers", "test_step_circle[euler]"],
    },
    "order_with_mixed_logarithms": {
        "culprit": "observed_order",
        "replace": {"observed_order": '''
def observed_order(h, errors):
    return float(np.polyfit(np.log(h), np.log10(errors), 1)[0])
'''},
        "fails": {
            "test_observed_order_exact_powers": "matches the least-squares slope with log10 on one axis and ln",
            "test_observed_order_random": "log10 on one axis and ln on the other",
            "test_measured_order_circle[midpoint]": "order 0.87, expected 2; your order is the measured slope divided "
                                                    "by ln(10) = 2.303: log10 on the errors' axis and ln on the "
                                                    "steps' axis",
            "test_measured_order_coarse_steps[rk4]": "your order is the measured slope divided by ln(10)",
        },
        "passes": ["test_convergence_errors_circle", "test_step_circle[midpoint]"],
    },
    "euclidean_error": {
        "culprit": "convergence_errors",
        "replace": {"convergence_errors": '''
def convergence_errors(method, f, X0, t0, t1, exact, n_steps):
    step = STEPPERS[method] if isinstance(method, str) else method
    h = (t1 - t0) / np.asarray(n_steps, dtype=float)
    errors = []
    for N, h_N in zip(n_steps, h):
        X = X0
        for k in range(N):
            X = step(f, X, t0 + k * h_N, h_N)
        errors.append(np.linalg.norm(X - exact(t1)))
    return h, np.array(errors)
'''},
        "fails": {
            "test_convergence_errors_circle": "your result matches the Euclidean norm of X_N - X(t1)",
            "test_measured_order_random[midpoint]": "your convergence_errors does not give the reference errors (your "
                                                    "result matches the Euclidean norm of X_N - X(t1)",
        },
        "passes": ["test_measured_order_circle[euler]", "test_observed_order_noisy"],
    },
    # The clock advanced before the step: each step gets t + h, invisible on the circle field (f does not depend
    # on t), caught on the driven oscillator.
    "errors_with_the_clock_ahead": {
        "culprit": "convergence_errors",
        "replace": {"convergence_errors": '''
def convergence_errors(method, f, X0, t0, t1, exact, n_steps):
    step = STEPPERS[method] if isinstance(method, str) else method
    h = (t1 - t0) / np.asarray(n_steps, dtype=float)
    errors = []
    for N, h_N in zip(n_steps, h):
        X, t = np.asarray(X0, dtype=float), t0
        for _ in range(N):
            t = t + h_N                 # the clock first, then the step
            X = step(f, X, t, h_N)
        errors.append(np.max(np.abs(X - exact(t1))))
    return h, np.array(errors)
'''},
        "fails": {
            "test_convergence_errors_random": "your result matches the errors of a loop that passes t + h to each step",
            "test_measured_order_random[midpoint]": "your steps are right, but your convergence_errors does not give "
                                                    "the reference errors (your result matches the errors of a loop "
                                                    "that passes t + h to each step",
        },
        "passes": ["test_convergence_errors_circle", "test_measured_order_circle[euler]", "test_step_random[euler]"],
    },
    # No measurement at all: the nominal orders, hard-coded. Close enough to the measured slopes in the
    # asymptotic range of the circle field, but not at coarse steps, where the slope is 1.1-1.4 for Euler.
    "hardcoded_measured_order": {
        "culprit": "measured_order",
        "replace": {"measured_order": '''
def measured_order(method, f, X0, t0, t1, exact, n_steps):
    return {"euler": 1, "midpoint": 2, "trapezoid": 2, "rk4": 4}[method]
'''},
        "fails": {
            "test_measured_order_coarse_steps[euler]": "1 is the method's nominal order, not a measurement",
            "test_measured_order_coarse_steps[midpoint]": "2 is the method's nominal order, not a measurement",
            "test_measured_order_coarse_steps[trapezoid]": "but the global errors of the trapezoid method",
            "test_measured_order_coarse_steps[rk4]": "4 is the method's nominal order, not a measurement",
        },
        "passes": ["test_measured_order_circle[euler]", "test_measured_order_circle[rk4]",
                   "test_convergence_errors_circle", "test_observed_order_noisy", "test_step_circle[rk4]"],
    },
    "midpoint_from_the_library": {
        "culprit": "midpoint_step",
        "replace": {"midpoint_step": '''
from particles.integrators import midpoint

def midpoint_step(f, X, t, h):
    return midpoint(f, X, t, h)
'''},
        "fails": {
            "test_step_circle[midpoint]": "uses `particles.integrators.midpoint`, which this exercise forbids",
            "test_measured_order_circle[euler]": "measured_order -> convergence_errors -> STEPPERS -> midpoint_step",
        },
        "passes": ["test_step_circle[euler]", "test_observed_order_noisy"],
    },
}

REJECTED.update({
    # A loop over the N + 1 times of np.linspace: N + 1 steps, one too many, then compared with X(t1).
    "errors_loop_over_linspace": {
        "replace": {"convergence_errors": '''
def convergence_errors(method, f, X0, t0, t1, exact, n_steps):
    step = STEPPERS[method]
    hs, errors = [], []
    for N in n_steps:
        h = (t1 - t0) / N
        X = np.array(X0, dtype=float)
        for t in np.linspace(t0, t1, N + 1):   # every time from t0 to t1
            X = step(f, X, t, h)
        hs.append(h)
        errors.append(np.max(np.abs(X - exact(t1))))
    return np.array(hs), np.array(errors)
'''},
        "fails": {
            "test_convergence_errors_circle": "your loop takes one step too many",
            "test_convergence_errors_random": "one step too many",
            "test_measured_order_random[midpoint]": "one step too many",
        },
        "passes": ["test_step_circle[euler]", "test_observed_order_noisy"],
        "culprit": "convergence_errors",
    },
    # The loop starts counting at 1: N - 1 steps.
    "errors_loop_from_one": {
        "replace": {"convergence_errors": '''
def convergence_errors(method, f, X0, t0, t1, exact, n_steps):
    step = STEPPERS[method]
    h = (t1 - t0) / np.array(n_steps)
    errors = np.zeros(len(n_steps))
    for j in range(len(n_steps)):
        X = X0
        for k in range(1, n_steps[j]):
            X = step(f, X, t0 + k * h[j], h[j])
        errors[j] = np.abs(X - exact(t1)).max()
    return h, errors
'''},
        "fails": {
            "test_convergence_errors_circle": "your loop takes one step too few",
        },
        "passes": ["test_step_circle[euler]", "test_observed_order_noisy"],
        "culprit": "convergence_errors",
    },
    # log10 of the errors fitted against h itself.
    "order_log_errors_against_h": {
        "replace": {"observed_order": '''
def observed_order(h, errors):
    p = np.polyfit(h, np.log10(errors), 1)
    return p[0]
'''},
        "fails": {
            "test_observed_order_exact_powers": "the step axis is not logarithmic",
            "test_observed_order_random": "the step axis is not logarithmic",
            "test_measured_order_circle[euler]": "the step axis is not logarithmic",
        },
        "passes": ["test_convergence_errors_circle", "test_step_circle[midpoint]"],
        "culprit": "observed_order",
    },
    # The two arrays passed the wrong way round.
    "measured_order_swaps_the_arguments": {
        "replace": {"measured_order": '''
def measured_order(method, f, X0, t0, t1, exact, n_steps):
    h, e = convergence_errors(method, f, X0, t0, t1, exact, n_steps)
    return observed_order(e, h)
'''},
        "fails": {
            "test_measured_order_circle[midpoint]": "your result is 1 / the slope",
            "test_measured_order_coarse_steps[euler]": "the axes swapped",
        },
        "passes": ["test_convergence_errors_circle", "test_observed_order_noisy", "test_step_circle[midpoint]"],
        "culprit": "measured_order",
    },
    # An Euler step that takes the slope at the end of the step: every function built on it is off too.
    "euler_slope_at_the_end": {
        "replace": {"euler_step": '''
def euler_step(f, X, t, h):
    return X + h * f(X, t + h)
'''},
        "fails": {
            "test_step_driven_particles[euler]": "f evaluated at t + h instead of t",
            "test_convergence_errors_random": "`convergence_errors` calls `euler_step`, which fails its own tests: "
                                              "fix `euler_step` first",
        },
        "passes": ["test_step_circle[euler]", "test_step_circle[midpoint]", "test_observed_order_noisy"],
        "culprit": "euler_step",
    },
})

CORRECT = {
    # RK4 is the stretch goal: left as the stub, the submission still scores full marks.
    "rk4_left_as_stub": {
        "replace": {"rk4_step": '''
def rk4_step(f, X, t, h):
    """One classical fourth-order Runge-Kutta step of dX/dt = f(X, t)."""
    raise NotImplementedError("rk4_step: stretch goal")
'''},
        "optional_fail": {"test_step_circle[rk4]": "`rk4_step` is not implemented yet",
                          "test_measured_order_circle[rk4]": "`measured_order` calls `rk4_step` (through "
                                                             "`convergence_errors`), which is not implemented yet"},
    },
    "tableau_and_polyfit": {
        "replace": {
            "euler_step": '''
def euler_step(f, X, t, h):
    dX = np.asarray(f(X, t), dtype=float)
    return np.add(X, h * dX)
''',
            "midpoint_step": '''
def midpoint_step(f, X, t, h):
    half = h / 2
    slope = f(X + half * f(X, t), t + half)
    return X + h * slope
''',
            "trapezoid_step": '''
def trapezoid_step(f, X, t, h):
    predictor = euler_step(f, X, t, h)
    return 0.5 * (predictor + X + h * f(predictor, t + h))
''',
            "rk4_step": '''
RK4_A = [[], [0.5], [0.0, 0.5], [0.0, 0.0, 1.0]]
RK4_B = [1 / 6, 1 / 3, 1 / 3, 1 / 6]
RK4_C = [0.0, 0.5, 0.5, 1.0]


def rk4_step(f, X, t, h):
    k = []
    for a, c in zip(RK4_A, RK4_C):
        stage = X.copy()
        for a_j, k_j in zip(a, k):
            stage = stage + h * a_j * k_j
        k.append(f(stage, t + c * h))
    return X + h * sum(b * k_i for b, k_i in zip(RK4_B, k))
''',
            "convergence_errors": '''
def convergence_errors(method, f, X0, t0, t1, exact, n_steps):
    step = {"euler": euler_step, "midpoint": midpoint_step, "trapezoid": trapezoid_step,
            "rk4": rk4_step}.get(method, method)
    target = exact(t1)
    hs, errors = [], []
    for N in n_steps:
        h = (t1 - t0) / N
        X, t = np.array(X0, dtype=float), t0
        for _ in range(N):
            X = step(f, X, t, h)
            t += h
        hs.append(h)
        errors.append(np.abs(X - target).max())
    return np.array(hs), np.array(errors)
''',
            "observed_order": '''
def observed_order(h, errors):
    slope, intercept = np.polyfit(np.log10(h), np.log10(errors), 1)
    return slope
''',
            "measured_order": '''
def measured_order(method, f, X0, t0, t1, exact, n_steps):
    return observed_order(*convergence_errors(method, f, X0, t0, t1, exact, n_steps))
''',
        },
    },
}
