"""Wrong and alternative submissions of exercise 02_stiffness (format: see exercise_corpus.py)."""

EXERCISE = "02_stiffness"

ONE_SPRING = "test_max_stable_step_one_spring"
RANDOM = "test_max_stable_step_random"
EULER = "test_max_stable_step_euler_has_none"
MEASURED = "test_max_stable_step_is_measured"
CHAIN = ["test_chain_max_stable_step_four_masses", "test_chain_max_stable_step_random"]
CHAIN_MEASURED = "test_chain_max_stable_step_is_measured"
BLOWS_UP = ["test_blows_up_around_the_limits", "test_blows_up_random"]
IMPLICIT = ["test_implicit_euler_spring_one_step", "test_implicit_euler_spring_random"]
DAMPING = ["test_damping_factor_public", "test_damping_factor_random"]
COST = ["test_cost_table_public", "test_cost_table_trend"]
STEP_BLOWS_UP = "a step that blows up in"
TOO_SMALL = "and the limit must lie within 3% below that"

REJECTED = {
    # The bisection stops at a bracket a factor 2 wide and returns its upper end, a step known to blow up: for one
    # spring the master's check of that step over a longer test then fails too, and the limit reported is 0.0.
    "bisection_returns_upper_bound": {
        "culprit": "bisect_stable",
        "replace": {"bisect_stable": '''
def bisect_stable(unstable, lo, hi, rtol=0.01):
    while hi > 2 * lo:
        mid = np.sqrt(lo * hi)
        if unstable(mid):
            hi = mid
        else:
            lo = mid
    return hi
'''},
        "fails": {ONE_SPRING: "returned 0.0 (no stable step)",
                  RANDOM: "is the step your bisection returned stable",
                  CHAIN[0]: "returned omega_max h = 2.197, a step that blows up"},
        "passes": BLOWS_UP + IMPLICIT + DAMPING,
    },
    # The bisection narrows its bracket to rtol but returns its upper end: a step within 1% above the limit,
    # which blows up (a check against theory within a few per cent let it pass).
    "bisection_returns_upper_end": {
        "culprit": "bisect_stable",
        "replace": {"bisect_stable": '''
def bisect_stable(unstable, lo, hi, rtol=0.01):
    while hi > (1 + rtol) * lo:
        mid = np.sqrt(lo * hi)
        if unstable(mid):
            hi = mid
        else:
            lo = mid
    return hi
'''},
        "fails": {ONE_SPRING: STEP_BLOWS_UP, RANDOM: STEP_BLOWS_UP, MEASURED: STEP_BLOWS_UP,
                  CHAIN[0]: STEP_BLOWS_UP, CHAIN[1]: STEP_BLOWS_UP, CHAIN_MEASURED: STEP_BLOWS_UP},
        "passes": [EULER] + BLOWS_UP + IMPLICIT + DAMPING + COST,
    },
    # Six halvings of the bracket 0.01 / omega to 10 / omega, then its midpoint: a bracket 11% wide, and a
    # step 4.5% above symplectic Euler's limit (1.7% above RK4's) that blows up.
    "bisection_too_few_halvings": {
        "culprit": "bisect_stable",
        "replace": {"bisect_stable": '''
def bisect_stable(unstable, lo, hi, rtol=0.01):
    for _ in range(6):
        mid = np.sqrt(lo * hi)
        if unstable(mid):
            hi = mid
        else:
            lo = mid
    return np.sqrt(lo * hi)
'''},
        "fails": {ONE_SPRING: "omega h = 2.091, a step that blows up", RANDOM: STEP_BLOWS_UP,
                  CHAIN[0]: STEP_BLOWS_UP},
        "passes": [EULER] + BLOWS_UP + IMPLICIT + DAMPING,
    },
    # The step confirmed by the longer test, 0.9 h, returned instead of h: stable, but 10% short of the limit.
    "returns_the_confirmed_step": {
        "culprit": "stable_limit",
        "replace": {"stable_limit": '''
def stable_limit(unstable, omega, steps=200, rtol=0.01):
    lo, hi = 0.01 / omega, 10.0 / omega
    if not unstable(hi, steps):
        return np.inf
    if unstable(lo, steps):
        return 0.0
    h = 0.9 * bisect_stable(lambda h: unstable(h, steps), lo, hi, rtol)
    if unstable(h, 4 * steps):
        return 0.0
    return h
'''},
        "fails": {ONE_SPRING: "the limit must lie within 3% below that; your step is 0.9 times the limit: return the "
                              "limit the bisection found, not the smaller step your longer test checked",
                  RANDOM: TOO_SMALL, MEASURED: "your step is 0.9 times the limit", CHAIN[0]: TOO_SMALL,
                  CHAIN[1]: "your step is 0.9 times the limit", CHAIN_MEASURED: TOO_SMALL},
        "passes": [EULER] + BLOWS_UP + IMPLICIT + DAMPING,
    },
    # No measurement at all: the theoretical limit, with omega = k/m instead of sqrt(k/m).
    "theory_with_k_over_m": {
        "culprit": "max_stable_step",
        "replace": {"max_stable_step": '''
def max_stable_step(method, k, m, steps=200, rtol=0.01):
    limits = {"symplectic_euler": 2.0, "verlet": 2.0, "rk4": 2.0 * np.sqrt(2.0)}
    return limits.get(method, 0.0) / (k / m)
'''},
        "fails": {ONE_SPRING: "m/k instead of sqrt(m/k)", RANDOM: "lets steps up to omega h = 2 pass",
                  MEASURED: "your step scales like m/k instead of sqrt(m/k)",
                  COST[0]: "step counts grow like k^1.00, expected k^0.5"},
        "passes": [EULER] + CHAIN + BLOWS_UP + IMPLICIT + DAMPING,
    },
    # The theoretical limit, right this time, but not measured: a short test finds a larger limit.
    "theory_not_measured": {
        "culprit": "max_stable_step",
        "replace": {"max_stable_step": '''
def max_stable_step(method, k, m, steps=200, rtol=0.01):
    limits = {"symplectic_euler": 2.0, "verlet": 2.0, "rk4": 2.0 * np.sqrt(2.0)}
    return limits.get(method, 0.0) / np.sqrt(k / m)
'''},
        "fails": {MEASURED: "your step is the theoretical limit omega h = 2.828, not a measurement: run your blow-up "
                            "test with the `steps` you are given"},
        "passes": [ONE_SPRING, RANDOM, EULER] + CHAIN + BLOWS_UP + IMPLICIT + DAMPING + COST,
    },
    # The chain's limit from the formula for omega_max given in the notebook, not measured: right for long
    # tests, but a 20-step test lets RK4 go 5% past it.
    "chain_from_theory": {
        "culprit": "chain_max_stable_step",
        "replace": {"chain_max_stable_step": '''
def chain_max_stable_step(method, n, k, m, steps=200, rtol=0.01):
    limit = {"symplectic_euler": 2.0, "verlet": 2.0, "rk4": 2.0 * np.sqrt(2.0)}.get(method, 0.0)
    return limit / (2 * np.sqrt(k / m) * np.sin(n * np.pi / (2 * (n + 1))))
'''},
        "fails": {CHAIN_MEASURED: "your step is the theoretical limit omega_max h = 2.828, not a measurement"},
        "passes": [ONE_SPRING, RANDOM, EULER, MEASURED] + CHAIN + BLOWS_UP + IMPLICIT + DAMPING + COST,
    },
    # Everything from theory: the blow-up test compares omega h with the limit, the limits are the table of
    # lecture 7 (with a 5% allowance for short tests), the cost uses them, the damping is the closed form.
    "all_from_theory": {
        "culprit": ["blows_up", "max_stable_step", "chain_max_stable_step", "cost_table", "damping_factor"],
        "replace": {
            "blows_up": '''
def blows_up(method, k, m, h, steps=200):
    limit = {"symplectic_euler": 2.0, "verlet": 2.0, "rk4": 2.0 * np.sqrt(2.0)}.get(method, 0.0)
    w = np.sqrt(k / m)
    if limit == 0.0:
        return steps * (w * h) ** 2 > 13.8
    return w * h > limit
''',
            "max_stable_step": '''
def max_stable_step(method, k, m, steps=200, rtol=0.01):
    limit = {"symplectic_euler": 2.0, "verlet": 2.0, "rk4": 2.0 * np.sqrt(2.0) * (1.05 if steps < 50 else 1.0)}
    return limit.get(method, 0.0) / np.sqrt(k / m)
''',
            "chain_max_stable_step": '''
def chain_max_stable_step(method, n, k, m, steps=200, rtol=0.01):
    limit = {"symplectic_euler": 2.0, "verlet": 2.0, "rk4": 2.0 * np.sqrt(2.0)}.get(method, 0.0)
    return limit / (2 * np.sqrt(k / m) * np.sin(n * np.pi / (2 * (n + 1))))
''',
            "cost_table": '''
def cost_table(ks, m=1.0, T=1.0, h_implicit=0.01):
    w = np.sqrt(np.asarray(ks, dtype=float) / m)
    return {"symplectic_euler": np.ceil(T / (0.9 * 2.0 / w)).astype(int),
            "rk4": np.ceil(T / (0.9 * 2.0 * np.sqrt(2.0) / w)).astype(int),
            "implicit_euler": np.full(len(w), int(np.ceil(T / h_implicit)))}
''',
            "damping_factor": '''
def damping_factor(omega_h, steps=50):
    return 1 / np.sqrt(1 + np.asarray(omega_h, dtype=float) ** 2)
''',
        },
        "fails": {BLOWS_UP[1]: "just above the theoretical 2.83) returned True, expected False",
                  MEASURED: "test lets steps up to omega h = 3.1",
                  CHAIN_MEASURED: "a 20-step test lets steps up to omega_max h = 2.9"},
        "passes": [ONE_SPRING, RANDOM, EULER, BLOWS_UP[0]] + CHAIN + IMPLICIT + DAMPING + COST,
    },
    # No confirmation with a longer test: explicit Euler gets the 'limit' of a 200-step test.
    "euler_gets_a_limit": {
        "culprit": "stable_limit",
        "replace": {"stable_limit": '''
def stable_limit(unstable, omega, steps=200, rtol=0.01):
    lo, hi = 0.01 / omega, 10.0 / omega
    if not unstable(hi, steps):
        return np.inf
    if unstable(lo, steps):
        return 0.0
    return bisect_stable(lambda h: unstable(h, steps), lo, hi, rtol)
'''},
        "fails": {EULER: "euler has no stable step on the undamped spring"},
        "passes": [ONE_SPRING, RANDOM, MEASURED] + CHAIN + BLOWS_UP + IMPLICIT + DAMPING + COST,
    },
    # The 'implicit' step uses the old position in the force: that is symplectic Euler.
    "implicit_step_is_explicit": {
        "culprit": "implicit_euler_spring",
        "replace": {"implicit_euler_spring": '''
def implicit_euler_spring(x, v, k, m, h):
    v_new = v - h * k / m * x
    x_new = x + h * v_new
    return x_new, v_new
'''},
        "fails": {IMPLICIT[0]: "your result matches a symplectic Euler step",
                  IMPLICIT[1]: "your result matches a symplectic Euler step",
                  DAMPING[0]: "your factors exceed 1 at some omega h: the amplitude grows, so the steps are not "
                              "implicit Euler's"},
        "passes": [ONE_SPRING, RANDOM, EULER, MEASURED] + CHAIN + BLOWS_UP + COST,
    },
    # The energy's factor per step, not the amplitude's.
    "damping_squared": {
        "culprit": "damping_factor",
        "replace": {"damping_factor": '''
def damping_factor(omega_h, steps=50):
    return 1.0 / (1.0 + np.asarray(omega_h, dtype=float) ** 2)
'''},
        "fails": {DAMPING[0]: "your result matches 1 / (1 + (omega h)^2), the factor of the energy",
                  DAMPING[1]: "the factor of the energy, not of the amplitude"},
        "passes": [ONE_SPRING, RANDOM, EULER, MEASURED] + CHAIN + BLOWS_UP + IMPLICIT + COST,
    },
    # The notebook's spring (omega = 10 rad/s) simulated at h = omega h / omega, and the amplitude's factor taken per
    # second of simulated time, (A_N / A_0) ** (1 / (N h)), instead of per step.
    "damping_per_second": {
        "culprit": "damping_factor",
        "replace": {"damping_factor": '''
def damping_factor(omega_h, steps=50):
    wh = np.asarray(omega_h, dtype=float)
    k, m = 100.0, 1.0                                  # the spring of the notebook, omega = 10 rad/s
    omega = np.sqrt(k / m)
    h = wh / omega
    x, v = np.ones_like(wh), np.zeros_like(wh)
    for _ in range(steps):
        x, v = implicit_euler_spring(x, v, k, m, h)
    return np.hypot(x, v / omega) ** (1.0 / (steps * h))   # per second of simulated time
'''},
        "fails": {DAMPING[0]: "your factors are per second of a spring with omega = 10 rad/s, not per step: the "
                              "amplitude factor per step is (A_N / A_0) ** (1 / N)",
                  DAMPING[1]: "your factors are per second of a spring with omega = 10 rad/s, not per step"},
        "passes": [ONE_SPRING, RANDOM, EULER, MEASURED] + CHAIN + BLOWS_UP + IMPLICIT + COST,
    },
    # Implicit Euler held to the explicit limit 'to be safe': its cost grows with k like the others.
    "implicit_held_to_explicit_limit": {
        "culprit": "cost_table",
        "replace": {"cost_table": '''
def cost_table(ks, m=1.0, T=1.0, h_implicit=0.01):
    table = {}
    for method in ("symplectic_euler", "rk4"):
        table[method] = np.array([int(np.ceil(T / (0.9 * max_stable_step(method, k, m)))) for k in ks])
    h = np.minimum(h_implicit, np.array([0.9 * max_stable_step("symplectic_euler", k, m) for k in ks]))
    table["implicit_euler"] = np.ceil(T / h).astype(int)
    return table
'''},
        "fails": {COST[0]: "implicit_euler step counts grow like k^0.30, expected k^0",
                  COST[1]: "the same count at every stiffness: implicit Euler is stable at any step, so its step is "
                           "h_implicit whatever k"},
        "passes": [ONE_SPRING, RANDOM, EULER, MEASURED] + CHAIN + BLOWS_UP + IMPLICIT + DAMPING,
    },
}

REJECTED.update({
    # The amplitude of the velocities not divided by omega: a stiff spring's steady oscillation reads as growth.
    "amplitude_without_omega": {
        "culprit": "amplitude",
        "replace": {"amplitude": '''
def amplitude(X, omega):
    return np.sqrt(np.sum(X[:, 0] ** 2) + np.sum(X[:, 1] ** 2))
'''},
        "fails": {"test_blows_up_random": "returned True, expected False"},
    },
})


CORRECT = {
    # The text says what stable_limit must find, not how: here no fixed bracket (halving down from omega h = 10
    # until a step passes), and a check of its own that the limit is the method's: 20% below it, a test 8 times
    # longer must still pass (explicit Euler's and midpoint's spurious limits shrink faster than that).
    "own_bracket_and_check": {
        "replace": {"stable_limit": '''
def stable_limit(unstable, omega, steps=200, rtol=0.01):
    top = 10.0 / omega
    if not unstable(top, steps):
        return np.inf
    lo = top
    while unstable(lo, steps):                 # halve until a step passes
        lo = lo / 2
        if omega * lo < 1e-4:
            return 0.0
    h = bisect_stable(lambda s: unstable(s, steps), lo, min(2 * lo, top), rtol)
    return 0.0 if unstable(0.8 * h, 8 * steps) else h
'''},
    },
    # Energy instead of amplitude, a linear bisection with a fixed number of halvings, the implicit step
    # by a linear solve, the damping factor in closed form, the cost table with plain Python loops.
    "written_differently": {
        "replace": {
            "grows": '''
def grows(step, f, X0, omega, h, steps=200, growth=1e3):
    def energy(X):
        return float(np.sum(X[:, 1] ** 2) + omega**2 * np.sum(X[:, 0] ** 2))
    limit = growth**2 * energy(X0)
    X, t = X0.copy(), 0.0
    with np.errstate(all="ignore"):
        for _ in range(steps):
            X, t = step(f, X, t, h), t + h
            E = energy(X)
            if np.isnan(E) or E > limit:
                return True
    return False
''',
            "bisect_stable": '''
def bisect_stable(unstable, lo, hi, rtol=0.01):
    for _ in range(60):
        if hi - lo <= rtol * lo:
            break
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if unstable(mid) else (mid, hi)
    return lo
''',
            "implicit_euler_spring": '''
def implicit_euler_spring(x, v, k, m, h):
    A = np.array([[1.0, -h], [h * k / m, 1.0]])
    solution = np.linalg.solve(A, np.stack([np.asarray(x, dtype=float), np.asarray(v, dtype=float)]))
    return solution[0], solution[1]
''',
            "damping_factor": '''
def damping_factor(omega_h, steps=50):
    return 1.0 / np.sqrt(1.0 + np.square(np.asarray(omega_h, dtype=float)))
''',
            "cost_table": '''
import math

def cost_table(ks, m=1.0, T=1.0, h_implicit=0.01):
    out = {"symplectic_euler": [], "rk4": [], "implicit_euler": []}
    for k in ks:
        for method in ("symplectic_euler", "rk4"):
            out[method].append(math.ceil(T / (0.9 * max_stable_step(method, float(k), m))))
        out["implicit_euler"].append(math.ceil(T / h_implicit))
    return {name: np.array(counts) for name, counts in out.items()}
''',
        },
    },
}
