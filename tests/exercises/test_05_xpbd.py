"""Autograder tests of exercise 05_xpbd: XPBD distance constraints, substeps, and the measured stiffness.

Public tests use one rod, a chain of three particles and the notebook's
string, whose answers a student can work out or read in the notebook; hidden
tests build random chains and cloths (sizes, masses, pins, compliances,
multipliers, steps) from the grading seed (fixture ``rng``) and never print
their parameters (``show_values=False``, calls described without numbers).
Every expected value comes from the reference library, computed here in the
grader: :func:`particles.xpbd.distance_pass` (one pass: Gauss-Seidel over the
colours given, or Jacobi with averaging) and :class:`particles.xpbd.XPBD`
(the step).

Gauss-Seidel or Jacobi. The notebook asks for a Gauss-Seidel pass over the
colours in increasing order and offers Jacobi with averaging as an
alternative; where constraints share particles the two differ, and a pass or
step is accepted when it matches either reference (to 1e-9). The measured
stiffness must match the reference measurement made with either kind of
pass to 1% (with one Jacobi pass per substep the string is about half as
stiff: the notebook's experiment shows why Gauss-Seidel is the default).

Typical mistakes are named from the wrong answers they produce: the
multiplier ignored or not accumulated, the gradient's sign, the inverse masses
swapped, alpha used without dividing by the substep squared (or by the whole
step squared), the multipliers reset every iteration or never, velocities not
taken from the positions, gravity on pinned particles.
"""

import numpy as np
import pytest

from particles.course.grading.expect import expect_array, expect_float
from particles.course.grading.memo import memoized
from particles.course.worker.runner import GradingFailure, describe_value
from particles.forces import Gravity
from particles.massspring import cloth
from particles.constraints import color_constraints
from particles.xpbd import XPBD, Distance, distance_pass

EXERCISE = "05_xpbd"
FORBIDDEN = {
    "particles.xpbd.distance_pass": "it is the pass you are asked to write",
    "particles.xpbd.multiplier_step": "it is the multiplier update you are asked to write",
    "particles.xpbd.XPBD": "it is the solver you are asked to write",
    "particles.xpbd.PBD": "it is a position-based solver: write your own step",
    "particles.xpbd.Distance": "it projects distance constraints for you; write the projection with NumPy",
    "particles.xpbd.constraints_from_system": "build the constraints yourself",
    "particles.studies.pbd.settled_sag": "measure the rest state with your own step",
    "particles.studies.pbd.stiffness_study": "it runs the measurement of this exercise",
}

G = 9.81
TIGHT = 1e-9  # agreement with a reference: the same arithmetic up to rounding
STRING = dict(n=12, mass=0.01, length=1.0)  # the notebook's string


# -- references and typical mistakes -----------------------------------------------------------


def _groups(colour):
    return [np.flatnonzero(colour == c) for c in range(int(colour.max()) + 1) if np.any(colour == c)]


@memoized
def _reference_pass(x, w, ij, L0, at, lam, colour):
    """The two accepted passes: Gauss-Seidel over the colours, Jacobi with averaging (library)."""
    return {"gauss-seidel": distance_pass(x, w, ij, L0, at, lam, np.asarray(colour)),
            "jacobi": distance_pass(x, w, ij, L0, at, lam, None)}


def _variant_pass(x, w, ij, L0, at, lam, colour, sign=1.0, swap=False, multiplier=True):
    """A Gauss-Seidel pass with one typical mistake (for the hints), written as the notebook's master."""
    x, lam, w = np.array(x, dtype=float), np.array(lam, dtype=float), np.asarray(w, dtype=float)
    at = np.broadcast_to(np.asarray(at, dtype=float), lam.shape)
    for k in _groups(np.asarray(colour)):
        i, j = ij[k, 0], ij[k, 1]
        d = x[i] - x[j]
        L = np.linalg.norm(d, axis=1)
        n = sign * d / L[:, None]
        wi, wj = (w[j], w[i]) if swap else (w[i], w[j])
        denom = w[i] + w[j] + at[k]
        dlam = np.divide(-(L - L0[k]) - (at[k] * lam[k] if multiplier else 0.0), denom,
                         out=np.zeros(len(k)), where=denom > 0)
        x[i] += (wi * dlam)[:, None] * n
        x[j] -= (wj * dlam)[:, None] * n
        lam[k] += dlam
    return x, lam


def _pass_hints(x, w, ij, L0, at, lam, colour, part):
    """Typical wrong results of a pass (positions, part 0, or multipliers, part 1)."""
    hints = {
        "a pass that ignores the multiplier accumulated so far (the - alpha_tilde * lambda term)":
            _variant_pass(x, w, ij, L0, at, lam, colour, multiplier=False)[part],
        "a pass with the gradient's sign reversed: n must point from x_j to x_i":
            _variant_pass(x, w, ij, L0, at, lam, colour, sign=-1.0)[part],
        "a pass with the inverse masses swapped: x_i moves by w_i dlambda n, x_j by w_j":
            _variant_pass(x, w, ij, L0, at, lam, colour, swap=True)[part],
    }
    if part == 1:
        hints["the multipliers you were given, unchanged: add every dlambda to lambda"] = np.asarray(lam, float)
    else:
        order = np.arange(len(ij))
        hints["a Gauss-Seidel sweep in the order of the rows, not colour by colour"] = \
            distance_pass(x, w, ij, L0, at, lam, order)[0] if len(ij) else x
    return hints


@memoized
def _reference_step(x, v, w, ij, L0, compliance, colour, g, h, substeps, iterations, method):
    free = np.asarray(w) > 0
    m = np.where(free, 1.0 / np.where(free, w, 1.0), 1.0)
    groups = np.asarray(colour) if method == "gauss-seidel" else None
    solver = XPBD([Distance(ij, L0, compliance=compliance, groups=groups)], m, np.flatnonzero(~free),
                  substeps=substeps, iterations=iterations, method=method, forces=[Gravity(g)])
    X = solver(None, np.stack([x, v], axis=1), 0.0, h)
    return X[:, 0], X[:, 1]


def _variant_step(x, v, w, ij, L0, compliance, colour, g, h, substeps, iterations, alpha="substep",
                  reset="substep", velocities=True, pins=True):
    """One step with one typical mistake (Gauss-Seidel passes of the library)."""
    x, v = np.array(x, dtype=float), np.array(v, dtype=float)
    free = np.asarray(w) > 0 if pins else np.ones(len(x), dtype=bool)
    hs = h / substeps
    at = np.asarray(compliance, float) / {"substep": hs**2, "step": h**2, "none": 1.0}[alpha]
    lam = np.zeros(len(ij))
    for _ in range(substeps):
        v[free] += hs * np.asarray(g, dtype=float)
        x_n = x.copy()
        x = x + hs * v
        if reset == "substep":
            lam = np.zeros(len(ij))
        for _ in range(iterations):
            if reset == "iteration":
                lam = np.zeros(len(ij))
            x, lam = distance_pass(x, w, ij, L0, at, lam, np.asarray(colour))
        if velocities:
            v = (x - x_n) / hs
    return x, v


def _step_hints(args, part):
    return {
        "the compliance alpha used as alpha_tilde: divide it by the substep squared, h_s^2":
            _variant_step(*args, alpha="none")[part],
        "alpha / h^2 with the whole step h: use the substep h_s = h / substeps":
            _variant_step(*args, alpha="step")[part],
        "multipliers reset at every iteration: reset them once per substep and carry them across the passes":
            _variant_step(*args, reset="iteration")[part],
        "multipliers carried from one substep to the next: reset them to 0 at the start of every substep":
            _variant_step(*args, reset="never")[part],
        "velocities not taken from the positions: v = (x - x_n) / h_s after the passes":
            _variant_step(*args, velocities=False)[part],
        "gravity applied to pinned particles (w = 0): they must not move":
            _variant_step(*args, pins=False)[part],
    }


def _matches_one(got, references, call, hints, show_values, rtol=TIGHT, atol=1e-12):
    """Pass when `got` matches one of the references; else fail against the first, with the hints."""
    for expected in references:
        if isinstance(got, np.ndarray) and got.shape == np.shape(expected) and got.dtype.kind == "f" \
                and np.all(np.abs(got - expected) <= atol + rtol * np.abs(expected)):
            return
    expect_array(got, references[0], call, rtol=rtol, atol=atol, hints=hints, show_values=show_values)


def _pair(got, call, names):
    if not isinstance(got, tuple) or len(got) != 2:
        kind = describe_value(got) if not isinstance(got, tuple) else f"a tuple of {len(got)} values"
        raise GradingFailure(f"{call} returned {kind}, expected the tuple ({', '.join(names)})")
    return got


def _check_pass(student, x, w, ij, L0, at, lam, colour, call, show_values):
    got = _pair(student.call("xpbd_pass", x, w, ij, L0, at, lam, colour, check_inputs=True), call,
                ("x_new", "lam_new"))
    refs = _reference_pass(x, w, ij, L0, at, lam, colour)
    _matches_one(got[0], [refs["gauss-seidel"][0], refs["jacobi"][0]], f"x_new of {call}",
                 lambda: _pass_hints(x, w, ij, L0, at, lam, colour, 0), show_values)
    jacobi = not _close(got[0], refs["gauss-seidel"][0])  # the positions matched Jacobi's: so must lambda
    _matches_one(got[1], [refs["jacobi" if jacobi else "gauss-seidel"][1]], f"lam_new of {call}",
                 lambda: _pass_hints(x, w, ij, L0, at, lam, colour, 1), show_values)


def _close(got, expected, rtol=TIGHT, atol=1e-12):
    return bool(np.all(np.abs(got - expected) <= atol + rtol * np.abs(expected)))


# -- building test systems ---------------------------------------------------------------------


def _colours(ij, n):
    colour = np.zeros(len(ij), dtype=np.int64)
    for c, g in enumerate(color_constraints(ij, n)):
        colour[g] = c
    return colour


def _random_cloth(rng, stretch=1.2):
    """A random cloth: positions, inverse masses (some pinned), constraints (shuffled, ends swapped), colours."""
    nx, ny = (int(k) for k in rng.integers(3, 7, 2))
    c = cloth(nx, ny, width=float(rng.uniform(0.5, 1.5)), height=float(rng.uniform(0.5, 1.5)), pins=None,
              plane=str(rng.choice(["vertical", "horizontal"])))
    kinds = ["structural", "shear", "flexion"][:int(rng.integers(1, 4))]
    ij = np.concatenate([c.springs[k].indices for k in kinds])
    L0 = np.concatenate([c.springs[k].rest_length for k in kinds])
    order = rng.permutation(len(ij))
    ij, L0 = ij[order], L0[order]
    swap = rng.random(len(ij)) < 0.5
    ij[swap] = ij[swap][:, ::-1]
    x = c.X[:, 0] * rng.uniform(1.0, stretch, 3) + rng.normal(0.0, 0.1 * L0.min(), c.X[:, 0].shape)
    w = rng.uniform(0.5, 20.0, c.n)
    w[rng.choice(c.n, int(rng.integers(1, 4)), replace=False)] = 0.0
    return x, w, ij, L0, _colours(ij, c.n)


def _random_chain(rng, d=2):
    """A random hanging chain along -y: positions near rest, inverse masses, its top pinned, two colours."""
    n = int(rng.integers(4, 10))
    L0 = rng.uniform(0.05, 0.2, n - 1)
    x = np.zeros((n, d))
    x[1:, -1] = -np.cumsum(L0 * rng.uniform(0.95, 1.1, n - 1))
    x[1:, 0] += rng.normal(0.0, 0.02, n - 1)
    w = 1.0 / rng.uniform(0.005, 0.05, n)
    w[0] = 0.0
    ij = np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)
    return x, w, ij, L0, np.arange(n - 1) % 2


# -- distance_constraints ----------------------------------------------------------------------


@pytest.mark.points(1)
def test_distance_constraints_two_rods(student):
    """distance_constraints gives C = +0.5 and -0.25 and the unit vectors from x_j to x_i."""
    x = np.array([[0.0, 0.0], [1.5, 0.0], [1.5, 0.75]])
    ij, L0 = np.array([[1, 0], [1, 2]]), np.array([1.0, 1.0])
    call = "distance_constraints(x=[[0, 0], [1.5, 0], [1.5, 0.75]], ij=[[1, 0], [1, 2]], L0=[1, 1])"
    C, n = _pair(student.call("distance_constraints", x, ij, L0, check_inputs=True), call, ("C", "n"))
    expect_array(C, [0.5, -0.25], f"C of {call}", hints={"|C| instead of C (keep the sign)": [0.5, 0.25]})
    expect_array(n, [[1.0, 0.0], [0.0, -1.0]], f"n of {call}",
                 hints={"n from x_i to x_j: the gradient of C at x_i points from x_j to x_i": [[-1.0, 0.0], [0.0, 1.0]],
                        "x_i - x_j not divided by its length": [[1.5, 0.0], [0.0, -0.75]]})


@pytest.mark.points(1)
@pytest.mark.hidden
def test_distance_constraints_random_cloth(student, rng):
    """distance_constraints matches |x_i - x_j| - L0 and (x_i - x_j) / |x_i - x_j| on a random cloth, 2D and 3D."""
    x, w, ij, L0, colour = _random_cloth(rng)
    for xd in (x, x[:, :2].copy()):
        call = f"distance_constraints on a random cloth in {xd.shape[1]}D"
        C, n = _pair(student.call("distance_constraints", xd, ij, L0, check_inputs=True), call, ("C", "n"))
        d = xd[ij[:, 0]] - xd[ij[:, 1]]
        L = np.linalg.norm(d, axis=1)
        expect_array(C, L - L0, f"C of {call}", show_values=False)
        expect_array(n, d / L[:, None], f"n of {call}", show_values=False, hints={"n reversed": -d / L[:, None]})


# -- xpbd_pass ---------------------------------------------------------------------------------


ROD = np.array([[0.0, 0.0], [0.0, -1.3]])  # rest length 1 m, stretched by 30%


@pytest.mark.points(1)
@pytest.mark.parametrize("case", ["rigid, top pinned", "both free, unequal masses", "soft, with a multiplier"])
def test_xpbd_pass_one_rod(student, case):
    """xpbd_pass on one rod: exact for a rigid pinned rod, mass-weighted when free, the multiplier's term when soft."""
    w, at, lam = {"rigid, top pinned": ([0.0, 2.0], 0.0, 0.0),
                  "both free, unequal masses": ([1.0, 3.0], 0.0, 0.0),
                  "soft, with a multiplier": ([0.0, 2.0], 0.25, -0.05)}[case]
    w, lam = np.array(w), np.array([lam])
    call = (f"xpbd_pass on a rod of L0 = 1 m stretched to 1.3 m, w = {w.tolist()}, alpha_tilde = {at}, "
            f"lam = {lam.tolist()}")
    _check_pass(student, ROD, w, np.array([[0, 1]]), np.array([1.0]), at, lam, np.array([0]), call, True)


@pytest.mark.points(2)
def test_xpbd_pass_colour_order(student):
    """xpbd_pass on a stretched chain of three particles sweeps the colours in increasing order (or is Jacobi)."""
    x = np.array([[0.0, 0.0], [0.0, -1.2], [0.0, -2.5]])
    ij, L0, w = np.array([[0, 1], [1, 2]]), np.ones(2), np.array([0.0, 1.0, 1.0])
    for colour in (np.array([0, 1]), np.array([1, 0])):
        call = f"xpbd_pass on the chain [0, -1.2, -2.5] m (L0 = 1 m, top pinned, rigid), colour = {colour.tolist()}"
        _check_pass(student, x, w, ij, L0, 0.0, np.zeros(2), colour, call, True)


@pytest.mark.points(3)
@pytest.mark.hidden
def test_xpbd_pass_random_cloths(student, rng):
    """xpbd_pass matches the reference pass on random cloths: random masses, pins, alpha_tilde per row, multipliers."""
    for trial in range(3):
        x, w, ij, L0, colour = _random_cloth(rng)
        at = rng.uniform(0.0, 2.0, len(ij)) if trial else float(rng.uniform(0.0, 1.0))
        lam = rng.normal(0.0, 0.02, len(ij))
        if trial == 2:
            x = x[:, :2].copy()
        call = f"xpbd_pass on a random cloth (trial {trial + 1}, {x.shape[1]}D)"
        _check_pass(student, x, w, ij, L0, at, lam, colour, call, False)


# -- xpbd_step ---------------------------------------------------------------------------------


def _check_step(student, args, call, show_values):
    got = _pair(student.call("xpbd_step", *args, check_inputs=True), call, ("x_new", "v_new"))
    refs = {m: _reference_step(*args, method=m) for m in ("gauss-seidel", "jacobi")}
    x, w = args[0], args[2]
    if isinstance(got[0], np.ndarray) and got[0].shape == x.shape:
        moved = np.flatnonzero((np.asarray(w) == 0) & np.any(got[0] != x, axis=1))
        if len(moved):
            raise GradingFailure(f"{call} moved pinned particle {int(moved[0])} (w = 0); pinned particles get no "
                                 "gravity and never move")
    for part, label in ((0, "x_new"), (1, "v_new")):
        _matches_one(got[part], [refs["gauss-seidel"][part], refs["jacobi"][part]], f"{label} of {call}",
                     lambda part=part: _step_hints(args, part), show_values, rtol=1e-9, atol=1e-10)


@pytest.mark.points(2)
def test_xpbd_step_pendulum(student):
    """xpbd_step on a pendulum (one soft rod, 2 substeps of 3 iterations) matches the reference step."""
    x = np.array([[0.0, 0.0], [0.6, -0.8]])
    v = np.array([[0.0, 0.0], [0.5, 0.0]])
    args = (x, v, np.array([0.0, 10.0]), np.array([[0, 1]]), np.array([1.0]), 1e-3, np.array([0]),
            np.array([0.0, -G]), 0.02, 2, 3)
    _check_step(student, args, "xpbd_step on a pendulum (L0 = 1 m, w = [0, 10], alpha = 1e-3, h = 0.02 s, "
                "2 substeps, 3 iterations)", True)


@pytest.mark.points(2)
def test_xpbd_step_chain(student):
    """xpbd_step on a stretched chain hanging from its top, h = 1/60 s with 10 substeps of 2 iterations."""
    x, w, ij, L0, colour = _random_chain(np.random.default_rng(0))
    args = (x, np.zeros_like(x), w, ij, L0, 0.02, colour, np.array([0.0, -G]), 1 / 60, 10, 2)
    _check_step(student, args, f"xpbd_step on a stretched chain of {len(x)} particles (top pinned, alpha = 0.02 "
                "m/N, h = 1/60 s, 10 substeps, 2 iterations)", True)


@pytest.mark.points(3)
@pytest.mark.hidden
def test_xpbd_step_random(student, rng):
    """xpbd_step matches the reference on random chains and cloths: compliances, steps, substeps, iterations."""
    for trial in range(3):
        if trial < 2:
            x, w, ij, L0, colour = _random_chain(rng, d=2 + trial)
        else:
            x, w, ij, L0, colour = _random_cloth(rng)
        v = rng.normal(0.0, 0.3, x.shape)
        v[w == 0] = 0.0
        g = np.zeros(x.shape[1])
        g[-1] = -G
        compliance = rng.uniform(1e-4, 0.05, len(ij)) if trial else float(rng.uniform(1e-3, 0.05))
        args = (x, v, w, ij, L0, compliance, colour, g, float(rng.choice([1 / 30, 1 / 60])),
                int(rng.integers(1, 6)), int(rng.integers(1, 5)))
        _check_step(student, args, f"xpbd_step on a random {'chain' if trial < 2 else 'cloth'} (trial {trial + 1})",
                    False)


# -- chain_stiffness ---------------------------------------------------------------------------


def _chain_stiffness(x, m, L0, g):
    e = np.linalg.norm(x[1:] - x[:-1], axis=1) - L0
    W = g * np.cumsum(m[::-1])[::-1][1:]
    return W.sum() / e.sum()


def _stiffness_hints(x, m, L0, g):
    e = np.linalg.norm(x[1:] - x[:-1], axis=1) - L0
    return {"the weight of link s including particle s itself (count only the particles below it)":
            g * np.cumsum(m[::-1])[::-1][:-1].sum() / e.sum(),
            "the whole weight over the whole stretch (each link carries only what hangs below it)":
            g * m.sum() / e.sum(),
            "the lengths instead of the stretches L - L0": _chain_stiffness(x, m, 0.0 * L0, g)}


@pytest.mark.points(1)
def test_chain_stiffness_by_hand(student):
    """chain_stiffness of three particles of 1 kg on links of 1 m stretched by 0.2 m and 0.1 m is 3 g / 0.3."""
    x = np.array([[0.0, 0.0], [0.0, -1.2], [0.0, -2.3]])
    m, L0 = np.ones(3), np.ones(2)
    call = "chain_stiffness(x=[[0, 0], [0, -1.2], [0, -2.3]], m=[1, 1, 1], L0=[1, 1], g=9.81)"
    expect_float(student.call("chain_stiffness", x, m, L0, G, check_inputs=True), 3 * G / 0.3, call,
                 rtol=1e-9, hints=lambda: _stiffness_hints(x, m, L0, G))


@pytest.mark.points(1)
@pytest.mark.hidden
def test_chain_stiffness_random(student, rng):
    """chain_stiffness matches sum W_s / sum e_s on random stretched chains with unequal masses."""
    x, w, ij, L0, colour = _random_chain(rng)
    x[1:, -1] = -np.cumsum(L0 * rng.uniform(1.01, 1.1, len(L0)))
    m = rng.uniform(0.005, 0.05, len(x))
    g = float(rng.uniform(5.0, 15.0))
    expect_float(student.call("chain_stiffness", x, m, L0, g, check_inputs=True), _chain_stiffness(x, m, L0, g),
                 "chain_stiffness on a random chain", rtol=1e-9, hints=lambda: _stiffness_hints(x, m, L0, g),
                 show_values=False)


# -- measured_stiffness ------------------------------------------------------------------------


@memoized
def _reference_measurement(k, h, substeps, iterations, method):
    """The notebook's measurement with the library's solver."""
    n, mass, length = STRING["n"], STRING["mass"], STRING["length"]
    L0 = np.full(n - 1, length / (n - 1))
    W = G * mass * np.arange(n - 1, 0, -1)
    X = np.zeros((n, 2, 2))
    X[1:, 0, 1] = -np.cumsum(L0 + W / k)
    ij = np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)
    groups = np.arange(n - 1) % 2 if method == "gauss-seidel" else None
    solver = XPBD([Distance(ij, L0, compliance=1.0 / k, groups=groups)], np.full(n, mass), [0], substeps=substeps,
                  iterations=iterations, method=method, forces=[Gravity([0.0, -G])])
    for _ in range(2000):
        X = solver(None, X, 0.0, h)
        X[:, 1] *= 0.8
        if np.abs(X[:, 1]).max() < 1e-6:
            break
    return _chain_stiffness(X[:, 0], np.full(n, mass), L0, G)


def _check_measurement(student, k, h, substeps, iterations, call, show_values):
    got = student.call("measured_stiffness", k, h, substeps, iterations)
    if isinstance(got, np.ndarray) and got.shape == ():
        got = got[()]
    if isinstance(got, (bool, np.bool_)) or not isinstance(got, (int, float, np.integer, np.floating)):
        raise GradingFailure(f"{call} returned {describe_value(got)}, expected a number (N/m)")
    if not np.isfinite(got):
        raise GradingFailure(f"{call} returned {got}, expected a finite stiffness (N/m): the string blew up or its "
                             "stretch was zero")
    refs = [_reference_measurement(k, h, substeps, iterations, m) for m in ("gauss-seidel", "jacobi")]
    if any(abs(got - r) <= 0.01 * r for r in refs):
        return float(got)
    ratio = got / k
    if ratio > 2.0:
        hint = ("; far stiffer than the springs: is alpha_tilde = alpha / h_s^2, and are the multipliers reset "
                "once per substep, not every iteration?")
    elif ratio < 0.5:
        hint = "; far softer than the springs: are the multipliers accumulated across the passes?"
    else:
        hint = ""
    if show_values:
        raise GradingFailure(f"{call} returned {got:.4g} N/m, expected {refs[0]:.4g} N/m (within 1%){hint}")
    raise GradingFailure(f"{call} returned {100 * (got / refs[0] - 1):+.1f}% off the reference measurement "
                         f"(1% allowed){hint}")


@pytest.mark.points(2)
@pytest.mark.time_limit(10)
def test_measured_stiffness_notebook_string(student):
    """measured_stiffness(50 N/m, h = 1/60 s, 10 substeps, 20 iterations) is 50 N/m: XPBD's stiffness is 1 / alpha."""
    got = _check_measurement(student, 50.0, 1 / 60, 10, 20, "measured_stiffness(k=50, h=1/60, substeps=10, "
                             "iterations=20)", True)
    expect_float(got, 50.0, "measured_stiffness(k=50, h=1/60, substeps=10, iterations=20)", rtol=0.01)


@pytest.mark.points(3)
@pytest.mark.hidden
@pytest.mark.time_limit(10)
def test_measured_stiffness_random(student, rng):
    """measured_stiffness for a random k and step matches the reference measurement at 1 and 20 iterations."""
    k = float(rng.uniform(20.0, 100.0))
    h = float(rng.choice([1 / 30, 1 / 60]))
    values = [_check_measurement(student, k, h, 10, it, f"measured_stiffness of a random string at {it} "
                                 f"iteration{'s' if it > 1 else ''}", False) for it in (1, 20)]
    if abs(values[1] / k - 1.0) > 0.01:
        raise GradingFailure("measured_stiffness of a random string at 20 iterations is "
                             f"{100 * (values[1] / k - 1):+.1f}% off k = 1 / alpha")
