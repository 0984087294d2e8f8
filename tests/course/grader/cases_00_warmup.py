"""Wrong submissions of exercise 00_warmup that test the exercise's tests (format: ``exercise_corpus.py``).

``corpus.py`` holds the warm-up's large corpus of hostile and broken submissions, which tests the
grader's defences; these are plain wrong answers the exercise's own tests must catch. Each returns a
new array without touching ``X``, so the check that ``X`` is left unchanged passes them: the test
that makes it must also compare the result with the reference.
"""

EXERCISE = "00_warmup"

UNCHANGED = "test_euler_step_leaves_X_unchanged"
FORCE = ["test_total_force_three_particles", "test_total_force_random"]

REJECTED = {
    # The sum is computed and thrown away: the copy of X comes back, untouched and unstepped.
    "step_result_discarded": {
        "culprit": "euler_step",
        "replace": {"euler_step": '''
def euler_step(f, X, t, h):
    X_new = X.copy()
    X_new + h * f(X, t)
    return X_new
'''},
        "fails": {UNCHANGED: "your result matches X itself: the step X + h f(X, t) is missing",
                  "test_euler_step_circle": "your result matches X itself",
                  "test_euler_step_random": "your result matches X itself",
                  "test_run_circle": "your result matches X0 in every record: the state never advances"},
        "passes": FORCE,
    },
    # A result array prepared and never filled in.
    "step_left_at_zeros": {
        "culprit": "euler_step",
        "replace": {"euler_step": '''
def euler_step(f, X, t, h):
    slope = f(X, t)
    X_new = np.zeros_like(X)   # to fill with X + h * slope
    return X_new
'''},
        "fails": {UNCHANGED: "your result matches zeros, not the new state X + h f(X, t)",
                  "test_euler_step_oscillator": "your result matches zeros"},
        "passes": FORCE,
    },
    # (the public answers hard-coded are hard_codes_public_answers of corpus.py, the same notebook: graded once there)
    # Single precision "to save memory": 7 significant digits, far from the reference's 1e-10.
    "euler_in_float32": {
        "culprit": "euler_step",
        "replace": {"euler_step": '''
def euler_step(f, X, t, h):
    X32 = np.asarray(X, dtype=np.float32)          # single precision: half the memory
    return X32 + np.float32(h) * np.asarray(f(X, t), dtype=np.float32)
'''},
        "fails": {"test_euler_step_circle": "your result is float32 (single precision, about 7 significant digits): "
                                            "compute in float64",
                  "test_euler_step_random": "your result is float32",
                  "test_run_circle": "your numbers were rounded to single precision (float32) on the way"},
        "passes": FORCE,
    },
    # The state recorded after each step: the trajectory starts one step late, X[0] is not X0.
    "run_records_after_the_step": {
        "culprit": "run",
        "replace": {"run": '''
def run(f, X0, t0, h, n_steps):
    t = t0 + h * np.arange(n_steps + 1)
    X = np.empty((n_steps + 1,) + np.shape(X0))
    state = np.asarray(X0, dtype=float)
    for k in range(n_steps + 1):
        state = euler_step(f, state, t[k], h)
        X[k] = state                    # recorded after the step
    return t, X
'''},
        "fails": {"test_run_circle": "your first record is not X0 (the trajectory must start with the initial state",
                  "test_run_random": "the states one step ahead, X[k] after k + 1 steps: your first record is not X0"},
        "passes": ["test_euler_step_circle", "test_euler_step_random"] + FORCE,
    },
    # The first record left as np.empty found it: the trajectory does not start with X0.
    "run_never_stores_X0": {
        "culprit": "run",
        "replace": {"run": '''
def run(f, X0, t0, h, n_steps):
    t = t0 + h * np.arange(n_steps + 1)
    X = np.zeros((n_steps + 1,) + np.shape(X0))
    for k in range(n_steps):
        X[k + 1] = euler_step(f, X0 if k == 0 else X[k], t[k], h)
    return t, X
'''},
        "fails": {"test_run_circle": "your first record is not X0: the trajectory must start with the initial state",
                  "test_run_random": "your first record is not X0"},
        "passes": ["test_euler_step_circle", "test_euler_step_random"] + FORCE,
    },
    # The time of the end of the step given to each step: invisible on the circle field, which does not
    # depend on t, caught on the driven oscillator.
    "run_passes_the_next_time": {
        "culprit": "run",
        "replace": {"run": '''
def run(f, X0, t0, h, n_steps):
    t = t0 + h * np.arange(n_steps + 1)
    X = np.empty((n_steps + 1,) + np.shape(X0))
    X[0] = X0
    for k in range(n_steps):
        X[k + 1] = euler_step(f, X[k], t[k + 1], h)
    return t, X
'''},
        "fails": {"test_run_random": "a loop that passes t + h to each step instead of t[k]"},
        "passes": ["test_run_circle", "test_euler_step_random"] + FORCE,
    },
    # Every step taken from X0: each record is one step from the start.
    "run_restarts_from_X0": {
        "culprit": "run",
        "replace": {"run": '''
def run(f, X0, t0, h, n_steps):
    t = t0 + h * np.arange(n_steps + 1)
    X = np.empty((n_steps + 1,) + np.shape(X0))
    X[0] = X0
    for k in range(n_steps):
        X[k + 1] = euler_step(f, X0, t[k], h)
    return t, X
'''},
        "fails": {"test_run_circle": "your result matches one step from X0 in every record: each step must start "
                                    "from the previous state X[k]",
                  "test_run_random": "one step from X0 in every record"},
        "passes": ["test_euler_step_circle"] + FORCE,
    },
    # The weight g instead of m g: right for unit masses only.
    "gravity_without_the_masses": {
        "culprit": "total_force",
        "replace": {"total_force": '''
def total_force(x, v, m, g, d):
    return np.asarray(g, dtype=float) - d * np.asarray(v, dtype=float)
'''},
        "fails": {"test_total_force_three_particles": "your result matches g - d v, gravity without the masses",
                  "test_total_force_random": "gravity without the masses"},
        "passes": ["test_euler_step_circle", "test_run_circle"],
    },
    # A loop over every time of the trajectory: one step from the last time too.
    "run_loops_over_every_time": {
        "culprit": "run",
        "replace": {"run": '''
def run(f, X0, t0, h, n_steps):
    t = np.linspace(t0, t0 + n_steps * h, n_steps + 1)
    X = [np.array(X0, dtype=float)]
    for t_k in t:
        X.append(euler_step(f, X[-1], t_k, h))
    return t, np.array(X)
'''},
        "fails": {"test_run_circle": "your loop takes one step too many",
                  "test_run_random": "your loop takes one step too many"},
        "passes": ["test_euler_step_circle", "test_euler_step_random"] + FORCE,
    },
    # np.arange leaves out the end time: one record, one step short.
    "run_with_arange_times": {
        "culprit": "run",
        "replace": {"run": '''
def run(f, X0, t0, h, n_steps):
    t = np.arange(t0, t0 + n_steps * h, h)
    X = np.zeros((len(t),) + np.shape(X0))
    X[0] = X0
    for k in range(len(t) - 1):
        X[k + 1] = euler_step(f, X[k], t[k], h)
    return t, X
'''},
        "fails": {"test_run_circle": "your loop takes one step too few"},
        "passes": ["test_euler_step_circle", "test_euler_step_random"] + FORCE,
    },
    # The slope taken at the end of the step: the loop built on it goes wrong too, and is not to blame.
    "euler_slope_at_the_end": {
        "culprit": "euler_step",
        "replace": {"euler_step": '''
def euler_step(f, X, t, h):
    return X + h * f(X, t + h)
'''},
        "fails": {"test_euler_step_random": "your result matches an Euler step with f evaluated at t + h instead of t",
                  "test_run_random": "`run` calls `euler_step`, which fails its own tests: fix `euler_step` first"},
        "passes": ["test_euler_step_circle", "test_euler_step_oscillator", "test_run_circle"] + FORCE,
    },
    # The drag multiplied by the mass along with gravity.
    "drag_times_the_mass": {
        "culprit": "total_force",
        "replace": {"total_force": '''
def total_force(x, v, m, g, d):
    m = np.asarray(m, dtype=float)[:, None]
    return m * (np.asarray(g) - d * np.asarray(v))
'''},
        "fails": {"test_total_force_three_particles": "the drag multiplied by the mass",
                  "test_total_force_random": "the drag multiplied by the mass"},
        "passes": ["test_euler_step_circle", "test_run_circle"],
    },
}
