"""Wrong and alternative submissions of exercise 03_provot (see ``exercise_corpus.py``)."""

EXERCISE = "03_provot"

# -- pieces of wrong submissions ---------------------------------------------------------------

_PASS_HEAD = '''
def provot_pass(x, indices, L0, free, max_strain=0.1):
    x = np.asarray(x, dtype=float)
    i, j = np.asarray(indices).T
    free = np.asarray(free, dtype=bool)
    f_i, f_j = free[i].astype(float), free[j].astype(float)
    total = f_i + f_j
'''

_SHARES = '''
    w_i = np.divide(f_i, total, out=np.zeros_like(f_i), where=total > 0)
    w_j = np.divide(f_j, total, out=np.zeros_like(f_j), where=total > 0)
'''

_EXCESS = '''
    d = x[j] - x[i]
    L = np.linalg.norm(d, axis=1)
    limit = (1.0 + max_strain) * np.asarray(L0, dtype=float)
    too_long = (L > limit) & (total > 0)
    e = np.where(too_long, L - limit, 0.0)
    u = d / np.where(L > 0, L, 1.0)[:, None]
'''

_SCATTER = '''
    dx = np.zeros_like(x)
    np.add.at(dx, i, (w_i * e)[:, None] * u)
    np.add.at(dx, j, -(w_j * e)[:, None] * u)
    n_p = np.bincount(i[too_long], minlength=len(x)) + np.bincount(j[too_long], minlength=len(x))
    return x + free[:, None] * dx / np.maximum(n_p, 1)[:, None]
'''


def _pass(shares=_SHARES, excess=_EXCESS, scatter=_SCATTER):
    return _PASS_HEAD + shares + excess + scatter


def _sequential(share):
    """Provot's sequential pass, spring by spring in the given order, with the first end's share `share`."""
    return f'''
def provot_pass(x, indices, L0, free, max_strain=0.1):
    x = np.array(x, dtype=float)
    for (i, j), rest in zip(np.asarray(indices).tolist(), np.asarray(L0, dtype=float).tolist()):
        if not (free[i] or free[j]):
            continue
        d = x[j] - x[i]
        L = np.sqrt(d @ d)
        e = L - (1 + max_strain) * rest
        if e > 0:
            share_i = {share}
            x[i] += share_i * e * d / L
            x[j] -= (1 - share_i) * e * d / L
    return x
'''


PASS_TESTS = ["test_provot_pass_one_spring[both free]", "test_provot_pass_one_spring[first pinned]",
              "test_provot_pass_one_spring[second pinned]", "test_provot_pass_one_spring[both pinned]",
              "test_provot_pass_shared_particle", "test_provot_pass_random_cloths"]
OTHER_TESTS = ["test_spring_strain_three_springs", "test_spring_strain_random_cloth",
               "test_max_strain_history_frames", "test_max_strain_history_recorded_run"]

REJECTED = {
    "pinned_particles_move": {
        "culprit": "provot_pass",
        # the pins are ignored: every spring's excess is split half and half
        "replace": {"provot_pass": '''
def provot_pass(x, indices, L0, free, max_strain=0.1):
    x = np.asarray(x, dtype=float)
    i, j = np.asarray(indices).T
    d = x[j] - x[i]
    L = np.linalg.norm(d, axis=1)
    limit = (1.0 + max_strain) * np.asarray(L0, dtype=float)
    e = np.where(L > limit, L - limit, 0.0)
    u = d / np.where(L > 0, L, 1.0)[:, None]
    dx = np.zeros_like(x)
    np.add.at(dx, i, 0.5 * e[:, None] * u)
    np.add.at(dx, j, -0.5 * e[:, None] * u)
    n_p = np.bincount(i[e > 0], minlength=len(x)) + np.bincount(j[e > 0], minlength=len(x))
    return x + dx / np.maximum(n_p, 1)[:, None]
'''},
        "fails": {
            "test_provot_pass_one_spring[first pinned]": "moved pinned particle 0",
            "test_provot_pass_one_spring[both pinned]": "moved pinned particle 0",
            "test_provot_pass_random_cloths": "moved pinned particle",
            "test_provot_project_properties": "moved pinned particle",
        },
        "passes": ["test_provot_pass_one_spring[both free]"] + OTHER_TESTS,
    },
    "one_end_only": {
        "culprit": "provot_pass",
        # both ends free, only the second end moves (by the whole excess)
        "replace": {"provot_pass": _pass(shares="\n    w_j = f_j\n    w_i = f_i * (1.0 - f_j)\n")},
        "fails": {
            "test_provot_pass_one_spring[both free]": "moved the midpoint",
            "test_provot_pass_random_cloths": "your result matches a pass that moves only the second end of a spring "
                                              "with two free ends",
            "test_provot_project_random_cloths": "one pass of your provot_pass on this cloth matches a pass that "
                                                 "moves only the second end of a spring with two free ends",
            "test_constrain_state_random_cloths": "changed their total momentum",
        },
        "passes": ["test_provot_pass_one_spring[first pinned]", "test_provot_pass_one_spring[second pinned]",
                   "test_provot_pass_one_spring[both pinned]"] + OTHER_TESTS,
    },
    "repeated_indices_lose_corrections": {
        "culprit": "provot_pass",
        # dx[i] += c keeps one correction per repeated index
        "replace": {"provot_pass": _pass(scatter='''
    dx = np.zeros_like(x)
    dx[i] += (w_i * e)[:, None] * u
    dx[j] -= (w_j * e)[:, None] * u
    n_p = np.bincount(i[too_long], minlength=len(x)) + np.bincount(j[too_long], minlength=len(x))
    return x + free[:, None] * dx / np.maximum(n_p, 1)[:, None]
''')},
        "fails": {
            "test_provot_pass_shared_particle": "your result matches a lost correction (x[i] += c with a repeated "
                                                "index keeps only the last one)",
            "test_provot_project_random_cloths": "one pass of your provot_pass on this cloth matches a pass that loses "
                                                 "corrections at repeated indices",
        },
        "passes": PASS_TESTS[:4] + ["test_provot_pass_random_cloths"] + OTHER_TESTS,
    },
    "shortened_to_rest_length": {
        "culprit": "provot_pass",
        # the excess measured from L0 instead of (1 + s) L0
        "replace": {"provot_pass": _pass(excess=_EXCESS.replace("e = np.where(too_long, L - limit, 0.0)",
                                                                "e = np.where(too_long, L - np.asarray(L0), 0.0)"))},
        "fails": {
            "test_provot_pass_one_spring[both free]": "shortened the spring to its rest length",
            "test_provot_pass_one_spring[first pinned]": "shortened the spring to its rest length",
            "test_provot_pass_random_cloths": "your result matches a pass that shortens the springs to their rest "
                                              "length L0, not to (1 + max_strain) L0",
            "test_provot_pass_shared_particle": "neither a Jacobi pass",
            "test_provot_project_properties": "your result matches a pass that shortens the springs to their rest "
                                              "length L0",
            "test_constrain_state_one_spring": "is off by",
        },
        "passes": ["test_provot_pass_one_spring[both pinned]"] + OTHER_TESTS,
    },
    "corrections_summed_not_averaged": {
        "culprit": "provot_pass",
        "replace": {"provot_pass": _pass(scatter='''
    dx = np.zeros_like(x)
    np.add.at(dx, i, (w_i * e)[:, None] * u)
    np.add.at(dx, j, -(w_j * e)[:, None] * u)
    return x + free[:, None] * dx
''')},
        "fails": {
            "test_provot_pass_shared_particle": "your result matches the sum of the three corrections instead of "
                                                "their average",
        },
        "passes": PASS_TESTS[:4] + OTHER_TESTS,
    },
    "velocities_not_updated": {
        "culprit": "constrain_state",
        "replace": {"constrain_state": '''
def constrain_state(X, h, indices, L0, free, max_strain=0.1, iterations=500, tol=0.005):
    X = np.asarray(X, dtype=float)
    x_new, passes = provot_project(X[:, 0], indices, L0, free, max_strain, iterations, tol)
    X_new = X.copy()
    X_new[:, 0] = x_new
    return X_new, passes
'''},
        "fails": {
            "test_constrain_state_one_spring": "the velocities left unchanged",
            "test_constrain_state_random_cloths": "the velocities left unchanged",
        },
        "passes": PASS_TESTS + OTHER_TESTS + ["test_provot_project_chain", "test_provot_project_nothing_to_do",
                                              "test_provot_project_random_cloths",
                                              "test_provot_project_properties"],
    },
    "no_early_stop": {
        "culprit": "provot_project",
        "replace": {"provot_project": '''
def provot_project(x, indices, L0, free, max_strain=0.1, iterations=500, tol=0.005):
    x = np.array(x, dtype=float)
    for _ in range(iterations):
        x = provot_pass(x, indices, L0, free, max_strain)
    return x, iterations
'''},
        "fails": {
            "test_provot_project_chain": "made 500 passes; a Jacobi projection with averaging needs 79",
            "test_provot_project_nothing_to_do": "0 passes",
            "test_provot_project_random_cloths": "Stop as soon as every spring with a free end holds (springs with "
                                                 "both ends pinned never do); one pass of your provot_pass is a right "
                                                 "Jacobi pass on this cloth, so look at the loop",
            "test_provot_project_properties": "and the grader allows",
        },
        "passes": PASS_TESTS + OTHER_TESTS,
    },
    "pinned_springs_block_the_stop": {
        "culprit": "provot_project",
        # the stopping test also looks at springs whose two ends are pinned, which never get shorter
        "replace": {"provot_project": '''
def provot_project(x, indices, L0, free, max_strain=0.1, iterations=500, tol=0.005):
    x = np.array(x, dtype=float)
    passes = 0
    while passes < iterations and spring_strain(x, indices, L0).max() > max_strain + tol:
        x = provot_pass(x, indices, L0, free, max_strain)
        passes += 1
    return x, passes
'''},
        "fails": {"test_provot_project_properties": "Stop as soon as every spring with a free end holds (springs with "
                                                    "both ends pinned never do)"},
        "passes": PASS_TESTS + OTHER_TESTS + ["test_provot_project_chain", "test_provot_project_nothing_to_do"],
    },
    "compression_counted_as_strain": {
        "culprit": "max_strain_history",
        "replace": {"max_strain_history": '''
def max_strain_history(X, indices, L0):
    return np.array([np.abs(spring_strain(Xk[:, 0], indices, L0)).max() for Xk in np.asarray(X)])
'''},
        "fails": {
            "test_max_strain_history_frames": "the largest |strain|",
            "test_max_strain_history_recorded_run": "your result matches the largest |strain| (compression counted)",
        },
        "passes": PASS_TESTS + ["test_spring_strain_three_springs", "test_spring_strain_random_cloth",
                                "test_provot_project_random_cloths", "test_constrain_state_random_cloths"],
    },
    # The largest strain of each frame, without max(0, ...): a frame where every spring is compressed gives a
    # negative number, where the master (and the docstring) say 0.
    "strain_history_not_clipped": {
        "culprit": "max_strain_history",
        "replace": {"max_strain_history": '''
def max_strain_history(X, indices, L0):
    return np.array([spring_strain(Xk[:, 0], indices, L0).max() for Xk in np.asarray(X, dtype=float)])
'''},
        "fails": {
            "test_max_strain_history_frames": "your result matches the largest strain without the clip at 0: a frame "
                                              "where every spring is compressed has max_strain_history 0",
            "test_max_strain_history_recorded_run": "the largest strain without the clip at 0",
        },
        "passes": PASS_TESTS + ["test_spring_strain_three_springs", "test_spring_strain_random_cloth"],
    },
    # The Green (Green-Lagrange) strain of continuum mechanics, (L^2 - L0^2) / (2 L0^2), instead of the engineering
    # strain L / L0 - 1 that the exercise (and Provot's limit) uses: equal to first order, 12% apart at 50%.
    "green_strain": {
        "culprit": "spring_strain",
        "replace": {"spring_strain": '''
def spring_strain(x, indices, L0):
    x = np.asarray(x, dtype=float)
    i, j = np.asarray(indices).T
    L2 = np.sum((x[j] - x[i]) ** 2, axis=1)          # no square root needed
    L0 = np.asarray(L0, dtype=float)
    return (L2 - L0**2) / (2 * L0**2)
'''},
        "fails": {
            "test_spring_strain_three_springs": "your result matches (L^2 - L0^2) / (2 L0^2), the Green strain: this "
                                                "exercise uses the engineering strain L / L0 - 1",
            "test_spring_strain_random_cloth": "the Green strain",
        },
        "passes": PASS_TESTS,
    },
}

REJECTED.update({
    # Provot's spring-by-spring pass with the shares computed from NumPy booleans: free[i] + free[j] is True, not 2,
    # so with both ends free the first takes the whole excess and the second none.
    "sequential_shares_from_a_sum_of_booleans": {
        "culprit": "provot_pass",
        "replace": {"provot_pass": _sequential("free[i] / (free[i] + free[j])")},
        "fails": {"test_provot_pass_one_spring[both free]": "moved the midpoint to x = 0.95 m; with both ends free "
                                                            "each end moves half the excess",
                  "test_provot_pass_random_cloths": "your result matches a pass that moves only the first end of a "
                                                    "spring with two free ends",
                  "test_constrain_state_random_cloths": "changed their total momentum: with both ends free each end "
                                                        "moves half the excess"},
        "passes": ["test_provot_pass_one_spring[first pinned]", "test_provot_pass_one_spring[second pinned]",
                   "test_provot_pass_one_spring[both pinned]", "test_provot_pass_shared_particle"],
    },
    # Both ends get half of every correction, pinned or not: provot_pass moves the pins through its helper.
    "shares_ignore_the_pins": {
        "culprit": "end_shares",
        "replace": {"end_shares": '''
def end_shares(indices, free):
    i, j = np.asarray(indices).T
    half = 0.5 * np.ones(len(i))
    return half, half
'''},
        "fails": {"test_provot_pass_one_spring[first pinned]": "moved the free end by half the excess only",
                  "test_provot_pass_random_cloths": "your result matches a pass that gives each end half of the "
                                                    "excess also when the other end is pinned"},
        "passes": ["test_provot_pass_one_spring[both free]"] + OTHER_TESTS,
    },
    # The excess measured from the rest length in the helper: springs come back to L0, not (1 + s) L0.
    "excess_from_the_rest_length": {
        "culprit": "spring_excess",
        "replace": {"spring_excess": '''
def spring_excess(x, indices, L0, max_strain=0.1):
    i, j = np.asarray(indices).T
    d = x[j] - x[i]
    L = np.linalg.norm(d, axis=1)
    too_long = L > (1.0 + max_strain) * np.asarray(L0)
    return np.where(too_long, L - L0, 0.0), d / L[:, None]
'''},
        "fails": {"test_provot_pass_one_spring[both free]": "shortened the spring to its rest length"},
        "passes": OTHER_TESTS,
    },
})


CORRECT = {
    # Provot's own order, vectorized: a Gauss-Seidel pass through groups of springs that share no particle (the
    # library's colouring), each group corrected at once from the positions the groups before it left.
    "gauss_seidel_by_colour_groups": {
        "replace": {"provot_pass": '''
from particles.constraints import color_constraints

def provot_pass(x, indices, L0, free, max_strain=0.1):
    x = np.array(x, dtype=float)
    ij, L0 = np.asarray(indices), np.asarray(L0, dtype=float)
    free = np.asarray(free, dtype=bool)
    for g in color_constraints(ij, len(x)):               # no particle twice within a group
        (w_i, w_j), (e, u) = end_shares(ij[g], free), spring_excess(x, ij[g], L0[g], max_strain)
        x[ij[g, 0]] += (w_i * e)[:, None] * u
        x[ij[g, 1]] -= (w_j * e)[:, None] * u
    return x
'''},
    },
    # Provot's sequential pass as he wrote it, spring by spring in the order given, each correction in place:
    # slow in Python, but within the time limits on the grader's cloths.
    "provot_spring_by_spring": {
        "replace": {"provot_pass": _sequential("float(free[i]) / (float(free[i]) + float(free[j]))")},
    },
    "bincount_per_coordinate": {
        # the same mathematics written differently: einsum lengths, bincount scatters, frames at once
        "replace": {
            "spring_strain": '''
def spring_strain(x, indices, L0):
    ij = np.asarray(indices)
    d = np.asarray(x, dtype=float)[ij[:, 0]] - np.asarray(x, dtype=float)[ij[:, 1]]
    return np.sqrt(np.einsum("sa,sa->s", d, d)) / L0 - 1
''',
            "max_strain_history": '''
def max_strain_history(X, indices, L0):
    ij = np.asarray(indices)
    x = np.asarray(X, dtype=float)[:, :, 0]
    L = np.linalg.norm(x[:, ij[:, 1]] - x[:, ij[:, 0]], axis=-1)
    if L.shape[1] == 0:
        return np.zeros(len(x))
    return np.clip((L / L0 - 1).max(axis=1), 0, None)
''',
            "provot_pass": '''
def provot_pass(x, indices, L0, free, max_strain=0.1):
    x = np.array(x, dtype=float)
    n, dim = x.shape
    ij = np.asarray(indices)
    a, b = ij[:, 0], ij[:, 1]
    movable = np.asarray(free, dtype=bool)
    ma, mb = movable[a], movable[b]
    diff = x[a] - x[b]                                   # from b to a
    L = np.sqrt((diff ** 2).sum(axis=1))
    target = (1 + max_strain) * np.asarray(L0, dtype=float)
    active = (L > target) & (ma | mb)
    share_a = np.where(ma & mb, 0.5, np.where(ma, 1.0, 0.0))
    share_b = np.where(ma & mb, 0.5, np.where(mb, 1.0, 0.0))
    k = np.where(active, (L - target) / np.where(L > 0, L, 1), 0.0)
    count = np.bincount(np.concatenate([a[active], b[active]]), minlength=n)
    for c in range(dim):                                 # one coordinate at a time
        move = np.bincount(b, share_b * k * diff[:, c], minlength=n) - np.bincount(a, share_a * k * diff[:, c], minlength=n)
        x[:, c] = np.where(movable & (count > 0), x[:, c] + move / np.maximum(count, 1), x[:, c])
    return x
''',
            "provot_project": '''
def provot_project(x, indices, L0, free, max_strain=0.1, iterations=500, tol=0.005):
    x = np.array(x, dtype=float)
    ij = np.asarray(indices)
    free = np.asarray(free, dtype=bool)
    watched = free[ij[:, 0]] | free[ij[:, 1]]
    for k in range(iterations + 1):
        strain = spring_strain(x, ij, L0)[watched]
        if k == iterations or strain.size == 0 or strain.max() <= max_strain + tol:
            return x, k
        x = provot_pass(x, ij, L0, free, max_strain)
''',
            "constrain_state": '''
def constrain_state(X, h, indices, L0, free, max_strain=0.1, iterations=500, tol=0.005):
    x, v = np.asarray(X, dtype=float)[:, 0], np.asarray(X, dtype=float)[:, 1]
    x_new, n_passes = provot_project(x, indices, L0, free, max_strain=max_strain, iterations=iterations, tol=tol)
    return np.stack([x_new, v + (x_new - x) / h], axis=1), n_passes
''',
        },
    },
    "python_loop_over_springs": {
        # slow but right: a Jacobi pass with a Python loop over the springs (small cloths fit the time limit)
        "replace": {"provot_pass": '''
def provot_pass(x, indices, L0, free, max_strain=0.1):
    x = np.asarray(x, dtype=float)
    rows = x.tolist()
    dx = [[0.0] * x.shape[1] for _ in rows]
    count = [0] * len(rows)
    for (i, j), rest in zip(np.asarray(indices).tolist(), np.asarray(L0, dtype=float).tolist()):
        fi, fj = bool(free[i]), bool(free[j])
        if not (fi or fj):
            continue
        d = [b - a for a, b in zip(rows[i], rows[j])]
        L = sum(c * c for c in d) ** 0.5
        e = L - (1 + max_strain) * rest
        if e <= 0:
            continue
        wi, wj = fi / (fi + fj), fj / (fi + fj)
        for a in range(len(d)):
            dx[i][a] += wi * e * d[a] / L
            dx[j][a] -= wj * e * d[a] / L
        count[i] += 1
        count[j] += 1
    out = x.copy()
    for p in range(len(rows)):
        if free[p] and count[p]:
            out[p] += np.array(dx[p]) / count[p]
    return out
'''},
    },
}
