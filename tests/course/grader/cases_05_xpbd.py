"""Wrong and alternative submissions of exercise 05_xpbd (see ``exercise_corpus.py``)."""

EXERCISE = "05_xpbd"

# -- pieces of the master, to change one thing at a time ---------------------------------------

_PASS = '''
def xpbd_pass(x, w, ij, L0, alpha_tilde, lam, colour):
    x = np.array(x, dtype=float)
    lam = np.array(lam, dtype=float)
    w = np.asarray(w, dtype=float)
    ij, L0, colour = np.asarray(ij), np.asarray(L0, dtype=float), np.asarray(colour)
    alpha_tilde = np.broadcast_to(np.asarray(alpha_tilde, dtype=float), lam.shape)
    for c in range(int(colour.max()) + 1 if len(colour) else 0):
        k = np.flatnonzero(colour == c)
        i, j = ij[k, 0], ij[k, 1]
        C, n = distance_constraints(x, ij[k], L0[k])
        denom = w[i] + w[j] + alpha_tilde[k]
        dlam = np.divide(-C - alpha_tilde[k] * lam[k], denom, out=np.zeros_like(C), where=denom > 0)
        x[i] += (w[i] * dlam)[:, None] * n
        x[j] -= (w[j] * dlam)[:, None] * n
        lam[k] += dlam
    return x, lam
'''

_STEP = '''
def xpbd_step(x, v, w, ij, L0, compliance, colour, g, h, substeps, iterations):
    x, v = np.array(x, dtype=float), np.array(v, dtype=float)
    free = np.asarray(w) > 0
    hs = h / substeps
    alpha_tilde = np.asarray(compliance, dtype=float) / hs**2
    for _ in range(substeps):
        v[free] += hs * np.asarray(g, dtype=float)
        x_n = x.copy()
        x = x + hs * v
        lam = np.zeros(len(ij))
        for _ in range(iterations):
            x, lam = xpbd_pass(x, w, ij, L0, alpha_tilde, lam, colour)
        v = (x - x_n) / hs
    return x, v
'''


_RESET_PER_SUBSTEP = "        lam = np.zeros(len(ij))\n        for _ in range(iterations):\n"
_RESET_PER_ITERATION = "        for _ in range(iterations):\n            lam = np.zeros(len(ij))\n"


def _changed(code, old, new):
    assert old in code, old
    return code.replace(old, new)


PASS_TESTS = ["test_xpbd_pass_one_rod[rigid, top pinned]", "test_xpbd_pass_one_rod[both free, unequal masses]",
              "test_xpbd_pass_one_rod[soft, with a multiplier]", "test_xpbd_pass_colour_order",
              "test_xpbd_pass_random_cloths"]
STEP_TESTS = ["test_xpbd_step_pendulum", "test_xpbd_step_chain", "test_xpbd_step_random"]
MEASURE_TESTS = ["test_measured_stiffness_notebook_string", "test_measured_stiffness_random"]
OTHER_TESTS = ["test_distance_constraints_two_rods", "test_distance_constraints_random_cloth",
               "test_chain_stiffness_by_hand", "test_chain_stiffness_random"]

REJECTED = {
    "alpha_not_divided_by_substep": {
        "culprit": "xpbd_step",
        # alpha_tilde = alpha: the compliance is negligible next to w, the string nearly rigid
        "replace": {"xpbd_step": _changed(_STEP, "np.asarray(compliance, dtype=float) / hs**2",
                                          "np.asarray(compliance, dtype=float)")},
        "fails": {
            "test_xpbd_step_pendulum": "the compliance alpha used as alpha_tilde",
            "test_xpbd_step_chain": "the compliance alpha used as alpha_tilde",
            "test_xpbd_step_random": "the compliance alpha used as alpha_tilde",
            "test_measured_stiffness_notebook_string": "far stiffer than the springs",
            "test_measured_stiffness_random": "far stiffer than the springs",
        },
        "passes": PASS_TESTS + OTHER_TESTS,
    },
    "alpha_over_the_whole_step": {
        "culprit": "xpbd_step",
        "replace": {"xpbd_step": _changed(_STEP, "np.asarray(compliance, dtype=float) / hs**2",
                                          "np.asarray(compliance, dtype=float) / h**2")},
        "fails": {
            "test_xpbd_step_pendulum": "with the whole step h",
            "test_xpbd_step_chain": "with the whole step h",
            "test_measured_stiffness_notebook_string": "far stiffer than the springs",
        },
        "passes": PASS_TESTS + OTHER_TESTS,
    },
    "multiplier_ignored_in_the_pass": {
        "culprit": "xpbd_pass",
        # dlambda = -C / (w_i + w_j + alpha_tilde): the correction never stops at the spring's stretch
        "replace": {"xpbd_pass": _changed(_PASS, "-C - alpha_tilde[k] * lam[k]", "-C")},
        "fails": {
            "test_xpbd_pass_one_rod[soft, with a multiplier]": "ignores the multiplier",
            "test_xpbd_pass_random_cloths": "ignores the multiplier",
            "test_xpbd_step_pendulum": "multipliers reset at every iteration",
            "test_measured_stiffness_notebook_string": "expected",
        },
        "passes": ["test_xpbd_pass_one_rod[rigid, top pinned]", "test_xpbd_pass_one_rod[both free, unequal masses]",
                   "test_xpbd_pass_colour_order"] + OTHER_TESTS,
    },
    "multiplier_not_accumulated": {
        "culprit": "xpbd_pass",
        # the positions move, but lambda is returned as it came: every pass starts from lambda = 0 again
        "replace": {"xpbd_pass": _changed(_PASS, "        lam[k] += dlam\n", "")},
        "fails": {
            "test_xpbd_pass_one_rod[rigid, top pinned]": "the multipliers you were given, unchanged",
            "test_xpbd_pass_random_cloths": "the multipliers you were given, unchanged",
            "test_xpbd_step_pendulum": "multipliers reset at every iteration",
            "test_xpbd_step_random": "multipliers reset at every iteration",
        },
        "passes": OTHER_TESTS,
    },
    "multipliers_reset_every_iteration": {
        "culprit": "xpbd_step",
        # the multipliers start from zero at every pass: the correction never stops at the spring's stretch
        "replace": {"xpbd_step": _changed(_STEP, _RESET_PER_SUBSTEP, _RESET_PER_ITERATION)},
        "fails": {
            "test_xpbd_step_pendulum": "multipliers reset at every iteration",
            "test_xpbd_step_chain": "multipliers reset at every iteration",
            "test_xpbd_step_random": "multipliers reset at every iteration",
            "test_measured_stiffness_notebook_string": "expected",
        },
        "passes": PASS_TESTS + OTHER_TESTS,
    },
    "gradient_sign_reversed": {
        "culprit": "distance_constraints",
        # n from x_i to x_j: every correction pushes the wrong way
        "replace": {"distance_constraints": '''
def distance_constraints(x, ij, L0):
    x = np.asarray(x, dtype=float)
    i, j = np.asarray(ij).T
    d = x[j] - x[i]
    L = np.linalg.norm(d, axis=1)
    return L - np.asarray(L0, dtype=float), d / np.where(L > 0, L, 1.0)[:, None]
'''},
        "fails": {
            "test_distance_constraints_two_rods": "n from x_i to x_j",
            "test_distance_constraints_random_cloth": "n reversed",
            "test_xpbd_pass_one_rod[rigid, top pinned]": "the gradient's sign reversed",
            "test_xpbd_pass_random_cloths": "the gradient's sign reversed",
            "test_xpbd_step_pendulum": "is off by",
        },
        "passes": ["test_chain_stiffness_by_hand", "test_chain_stiffness_random"],
    },
    "inverse_masses_swapped": {
        "culprit": "xpbd_pass",
        "replace": {"xpbd_pass": _changed(_changed(_PASS, "x[i] += (w[i] * dlam)", "x[i] += (w[j] * dlam)"),
                                          "x[j] -= (w[j] * dlam)", "x[j] -= (w[i] * dlam)")},
        "fails": {
            "test_xpbd_pass_one_rod[rigid, top pinned]": "the inverse masses swapped",
            "test_xpbd_pass_one_rod[both free, unequal masses]": "the inverse masses swapped",
            "test_xpbd_pass_random_cloths": "is off by",
            "test_xpbd_step_pendulum": "moved pinned particle 0",
        },
        "passes": OTHER_TESTS,
    },
    "velocities_not_from_positions": {
        "culprit": "xpbd_step",
        # v keeps the prediction's velocity: the string never comes to rest
        "replace": {"xpbd_step": _changed(_STEP, "        v = (x - x_n) / hs\n", "")},
        "fails": {
            "test_xpbd_step_pendulum": "velocities not taken from the positions",
            "test_xpbd_step_chain": "velocities not taken from the positions",
            "test_xpbd_step_random": "velocities not taken from the positions",
            "test_measured_stiffness_notebook_string": "",
        },
        "passes": PASS_TESTS + OTHER_TESTS,
    },
}



CORRECT = {
    "jacobi_pass": {
        # the alternative the notebook offers: all corrections from the same positions, averaged
        "replace": {"xpbd_pass": '''
def xpbd_pass(x, w, ij, L0, alpha_tilde, lam, colour):
    x = np.array(x, dtype=float)
    w = np.asarray(w, dtype=float)
    ij = np.asarray(ij)
    i, j = ij[:, 0], ij[:, 1]
    at = np.broadcast_to(np.asarray(alpha_tilde, dtype=float), (len(ij),))
    count = np.bincount(i, minlength=len(x)) + np.bincount(j, minlength=len(x))
    shared = np.maximum(np.where(w[i] > 0, count[i], 0), np.where(w[j] > 0, count[j], 0))
    C, n = distance_constraints(x, ij, L0)
    denom = w[i] + w[j] + at
    dlam = np.divide(-C - at * np.asarray(lam, dtype=float), denom, out=np.zeros(len(ij)), where=denom > 0)
    dlam = dlam / np.maximum(shared, 1)
    for a in range(x.shape[1]):
        x[:, a] += (np.bincount(i, w[i] * dlam * n[:, a], minlength=len(x))
                    - np.bincount(j, w[j] * dlam * n[:, a], minlength=len(x)))
    return x, np.asarray(lam, dtype=float) + dlam
'''},
    },
    "written_differently": {
        # einsum lengths, np.unique colours, np.add.at scatters, while loops, a loop over the links
        "replace": {
            "distance_constraints": '''
def distance_constraints(x, ij, L0):
    p = np.asarray(x, dtype=float)
    diff = p[np.asarray(ij)[:, 0]] - p[np.asarray(ij)[:, 1]]
    length = np.sqrt(np.einsum("sd,sd->s", diff, diff))
    return length - L0, diff / length[:, None]
''',
            "xpbd_pass": '''
def xpbd_pass(x, w, ij, L0, alpha_tilde, lam, colour):
    pos = np.asarray(x, dtype=float).copy()
    mult = np.asarray(lam, dtype=float).copy()
    inv_m = np.asarray(w, dtype=float)
    comp = np.full(len(ij), 1.0) * alpha_tilde
    for c in np.unique(colour):
        rows = np.asarray(colour) == c
        a, b = np.asarray(ij)[rows].T
        C, grad = distance_constraints(pos, np.asarray(ij)[rows], np.asarray(L0)[rows])
        total = inv_m[a] + inv_m[b] + comp[rows]
        safe = np.where(total > 0, total, 1.0)
        delta = np.where(total > 0, (-C - comp[rows] * mult[rows]) / safe, 0.0)
        np.add.at(pos, a, inv_m[a, None] * delta[:, None] * grad)
        np.add.at(pos, b, -inv_m[b, None] * delta[:, None] * grad)
        mult[rows] = mult[rows] + delta
    return pos, mult
''',
            "xpbd_step": '''
def xpbd_step(x, v, w, ij, L0, compliance, colour, g, h, substeps, iterations):
    pos, vel = np.array(x, dtype=float), np.array(v, dtype=float)
    moves = (np.asarray(w) > 0)[:, None]
    dt = h / substeps
    step = 0
    while step < substeps:
        vel = vel + dt * np.asarray(g) * moves
        start = pos.copy()
        pos = pos + dt * vel
        lam = np.zeros(len(ij))
        k = 0
        while k < iterations:
            pos, lam = xpbd_pass(pos, w, ij, L0, compliance / dt / dt, lam, colour)
            k += 1
        vel = (pos - start) / dt
        step += 1
    return pos, vel
''',
            "chain_stiffness": '''
def chain_stiffness(x, m, L0, g):
    below, weights, stretches = 0.0, [], []
    for s in range(len(L0) - 1, -1, -1):
        below += m[s + 1]
        weights.append(g * below)
        stretches.append(np.linalg.norm(np.asarray(x)[s + 1] - np.asarray(x)[s]) - L0[s])
    return sum(weights) / sum(stretches)
''',
        },
    },
}
