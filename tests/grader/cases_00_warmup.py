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
        "replace": {"euler_step": '''
def euler_step(f, X, t, h):
    X_new = X.copy()
    X_new + h * f(X, t)
    return X_new
'''},
        "fails": {UNCHANGED: "your result matches X itself: the step X + h f(X, t) is missing",
                  "test_euler_step_circle": "is off by", "test_euler_step_random": "is off by",
                  "test_run_circle": "the states X of run"},
        "passes": FORCE,
    },
    # A result array prepared and never filled in.
    "step_left_at_zeros": {
        "replace": {"euler_step": '''
def euler_step(f, X, t, h):
    slope = f(X, t)
    X_new = np.zeros_like(X)   # to fill with X + h * slope
    return X_new
'''},
        "fails": {UNCHANGED: "your result matches zeros, not the new state X + h f(X, t)",
                  "test_euler_step_oscillator": "is off by"},
        "passes": FORCE,
    },
    # The two public answers hard-coded, a copy of X for every other state: only the hidden test used to
    # catch it, the test of an unchanged X passed it.
    "hard_codes_public_steps": {
        "replace": {"euler_step": '''
def euler_step(f, X, t, h):
    f(X, t)
    if X.shape == (2,):
        return np.array([1.0, 0.1])
    if X.shape == (1, 2, 1):
        return np.array([[[1.025], [0.3]]])
    return X.copy()
'''},
        "fails": {UNCHANGED: "your result matches X itself", "test_euler_step_random": "is off by"},
        "passes": ["test_euler_step_circle", "test_euler_step_oscillator"] + FORCE,
    },
}
