"""Autograder tests of exercise 03_provot: Provot's deformation constraint on a cloth.

Public tests use a few springs whose answer a student can work out by hand;
hidden tests build random cloths from ``particles.massspring.cloth`` (random
size, plane, pins and stretched positions; springs shuffled and their ends
swapped) from the grading seed (fixture ``rng``).

Two orders of the corrections are right, and both get full marks: Provot's own
sequential pass (each spring corrected from the positions the corrections
before it left: a Gauss-Seidel pass, spring by spring or colour group by
colour group, in any order) and a Jacobi pass (every correction from the same
positions, each particle moved by the average of its corrections). Their
results differ, so a pass and a projection are judged by what every right
order does:

* exactly, where all orders agree: one spring (each pin configuration), springs
  that share no particle (a free pair keeps its midpoint: its momentum), and a
  particle shared by three springs, where the result must be the Jacobi pass or
  the sequential pass in one of the six orders;
* by invariants on any cloth: pinned particles exactly where they were, inputs
  unchanged, nothing moved when nothing is too long, and after the projection
  every spring with a free end within ``max_strain + tol`` (+1e-9), reached
  within a bound of passes (one and a half times the reference Jacobi
  projection's, the slower of the two orders, plus two), stopping as soon as it
  holds (one pass fewer, the student's own projection still leaves a spring too
  long), at most ``iterations`` passes;
* ``constrain_state`` against the student's own ``provot_project`` (the same
  positions and passes) and ``v + dx / h``.
"""

import itertools

import numpy as np
import pytest

from particles.constraints import provot_projection
from particles.course.grading.expect import expect_array, expect_float
from particles.course.grading.memo import memoized
from particles.course.worker.runner import GradingFailure, describe_value
from particles.massspring import cloth

EXERCISE = "03_provot"
FORBIDDEN = {
    "particles.constraints.provot_projection": "it is the projection you are asked to write",
    "particles.constraints.ProvotConstraint": "it applies the projection you are asked to write",
    "particles.constraints.provot.provot_pass": "it is the library's own pass; write the pass with NumPy",
    "particles.constraints.provot.provot_excess": "it is the correction you are asked to write",
    "particles.studies.provot": "it runs the curtain study you are asked to build",
    "particles.forces.Springs": "compute the spring lengths and strains yourself with NumPy",
    "particles.massspring.MassSpringSystem": "its strain and max_strain are what you are asked to write",
}

ROUNDING = 1e-9  # slack on the strain limit and on agreement, relative
SLOWEST = 1.5    # a projection may take this many times the reference Jacobi projection's passes (plus two)


# -- building cloths ---------------------------------------------------------------------------


def _random_cloth(rng, kinds=("structural", "shear"), pinned_pair=None, stretch=1.5):
    """A random stretched cloth: positions x, springs ij (shuffled, ends swapped), rest lengths, free mask.

    Pinned particles stay at their rest positions, so that a configuration within the limit exists;
    with `pinned_pair`, two neighbours are pinned with their spring stretched by 30%.
    """
    nx, ny = (int(k) for k in rng.integers(3, 9, 2))
    c = cloth(nx, ny, width=rng.uniform(0.5, 2.0), height=rng.uniform(0.5, 2.0),
              plane=str(rng.choice(["vertical", "horizontal"])), pins=None)
    ij = np.concatenate([c.springs[k].indices for k in kinds])
    L0 = np.concatenate([c.springs[k].rest_length for k in kinds])
    order = rng.permutation(len(ij))
    ij, L0 = ij[order], L0[order]
    swap = rng.random(len(ij)) < 0.5
    ij[swap] = ij[swap][:, ::-1]
    x0 = c.X[:, 0].copy()
    free = np.ones(c.n, dtype=bool)
    free[rng.choice(c.n, int(rng.integers(0, 6)), replace=False)] = False
    if pinned_pair is None:
        pinned_pair = rng.random() < 0.4
    if pinned_pair:
        a, b = ij[int(rng.integers(len(ij)))]
        free[[a, b]] = False
        x0[b] = x0[a] + 1.3 * (x0[b] - x0[a])
    x = x0 * rng.uniform(1.0, stretch, 3) + rng.normal(0.0, 0.15 * L0.min(), x0.shape)
    x[~free] = x0[~free]
    return x, ij, L0, free


def _converging_cloth(rng, **options):
    """A random cloth (and its limit, tolerance and reference) whose reference Jacobi projection converges."""
    while True:
        x, ij, L0, free = _random_cloth(rng, **options)
        s, tol = rng.uniform(0.05, 0.2), rng.uniform(0.002, 0.01)
        ref = _projection(x, ij, L0, free, s, 500, tol)
        if ref.converged and ref.iterations > 1:
            return x, ij, L0, free, s, tol, ref


def _separate_springs(rng, d, pins=True):
    """Springs that share no particle (a random matching of particles at random places), stretched or not.

    Every order of the corrections gives the same pass on them: the grader knows the answer exactly.
    """
    pairs = int(rng.integers(3, 9))
    x = rng.normal(0.0, 1.0, (2 * pairs, d))
    ij = rng.permutation(2 * pairs).reshape(pairs, 2)
    L = np.linalg.norm(x[ij[:, 1]] - x[ij[:, 0]], axis=1)
    L0 = L / rng.uniform(0.9, 1.6, pairs)                 # some within the limit, most too long
    free = rng.random(2 * pairs) < 0.7 if pins else np.ones(2 * pairs, dtype=bool)
    return x, ij, L0, free


def _relaxed_cloth(rng):
    """A random cloth (springs shuffled, random pins) whose springs are all shorter than their rest length."""
    nx, ny = (int(k) for k in rng.integers(3, 9, 2))
    c = cloth(nx, ny, plane=str(rng.choice(["vertical", "horizontal"])), pins=None)
    ij = np.concatenate([c.springs[k].indices for k in ("structural", "shear")])
    L0 = np.concatenate([c.springs[k].rest_length for k in ("structural", "shear")])
    order = rng.permutation(len(ij))
    x = 0.95 * c.X[:, 0] + rng.normal(0.0, 0.005 * L0.min(), (c.n, 3))
    return x, ij[order], L0[order], rng.random(c.n) < 0.9


def _curtain_springs(n=6):
    c = cloth(n, n, plane="horizontal")
    ij = np.concatenate([c.springs[k].indices for k in ("structural", "shear")])
    L0 = np.concatenate([c.springs[k].rest_length for k in ("structural", "shear")])
    return c, ij, L0


def _strain(x, ij, L0):
    return np.linalg.norm(x[ij[:, 0]] - x[ij[:, 1]], axis=1) / L0 - 1.0


@memoized
def _projection(x, ij, L0, free, s, iterations, tol):
    """The reference library's Jacobi projection (a ``ProjectionResult``)."""
    return provot_projection(x, ij, L0, free, s, iterations, tol)


def _jacobi_pass(x, ij, L0, free, s):
    """One reference Jacobi pass with averaging."""
    return provot_projection(x, ij, L0, free, s, iterations=1, tol=0.0).x


def _sequential_pass(x, ij, L0, free, s, order):
    """Provot's sequential pass: the springs corrected one after another in `order`, each from the current positions."""
    x = np.array(x, dtype=float)
    for k in order:  # a loop over a handful of springs, in the grader
        x = provot_projection(x, ij[[k]], L0[[k]], free, s, iterations=1, tol=0.0).x
    return x


def _describe(x, ij, free, s):
    """A random cloth in a message: its size, not its random parameters (`s` stays out)."""
    return f"a random cloth of {len(x)} particles, {len(ij)} springs, {int((~free).sum())} pinned"


def _pass_variant(x, ij, L0, free, s, ignore_pins=False, one_end=False, from_rest=False, lost=False, summed=False,
                  halves=False):
    """One Jacobi pass with a typical mistake (the options), to name what a wrong pass did."""
    i, j = ij[:, 0], ij[:, 1]
    movable = np.ones(len(x), dtype=bool) if ignore_pins else free
    f_i, f_j = movable[i].astype(float), movable[j].astype(float)
    total = f_i + f_j
    if halves:
        w_i = w_j = 0.5 * np.ones_like(f_i)
    elif one_end == "first":
        w_i, w_j = f_i, f_j * (1.0 - f_i)
    elif one_end:
        w_i, w_j = f_i * (1.0 - f_j), f_j
    else:
        w_i = np.divide(f_i, total, out=np.zeros_like(f_i), where=total > 0)
        w_j = np.divide(f_j, total, out=np.zeros_like(f_j), where=total > 0)
    d = x[j] - x[i]
    L = np.linalg.norm(d, axis=1)
    limit = (1.0 + s) * L0
    too_long = (L > limit) & (total > 0)
    e = np.where(too_long, L - (L0 if from_rest else limit), 0.0)
    u = d / np.where(L > 0, L, 1.0)[:, None]
    dx = np.zeros_like(x)
    if lost:
        dx[i] += (w_i * e)[:, None] * u
        dx[j] -= (w_j * e)[:, None] * u
    else:
        np.add.at(dx, i, (w_i * e)[:, None] * u)
        np.add.at(dx, j, -(w_j * e)[:, None] * u)
    count = np.bincount(i[too_long], minlength=len(x)) + np.bincount(j[too_long], minlength=len(x))
    return x + movable[:, None] * dx / (1.0 if summed else np.maximum(count, 1)[:, None])


def _pass_hints(x, ij, L0, free, s):
    """Typical wrong passes: label -> the positions they give."""
    return {
        "a pass that moves the pinned particles too (their share of the excess goes to the free end)":
            _pass_variant(x, ij, L0, free, s, ignore_pins=True),
        "a pass that shortens the springs to their rest length L0, not to (1 + max_strain) L0":
            _pass_variant(x, ij, L0, free, s, from_rest=True),
        "a pass that moves only the second end of a spring with two free ends (each moves half the excess)":
            _pass_variant(x, ij, L0, free, s, one_end=True),
        "a pass that moves only the first end of a spring with two free ends (each moves half the excess)":
            _pass_variant(x, ij, L0, free, s, one_end="first"),
        "a pass that gives each end half of the excess also when the other end is pinned (the only free end "
        "takes all of it: shares f_i / (f_i + f_j))": _pass_variant(x, ij, L0, free, s, halves=True),
        "a pass that adds up the corrections at a particle instead of averaging them":
            _pass_variant(x, ij, L0, free, s, summed=True),
        "a pass that loses corrections at repeated indices (x[i] += c keeps one per particle; use np.add.at or "
        "np.bincount)": _pass_variant(x, ij, L0, free, s, lost=True),
    }


def _pass_diagnosis(student, x, ij, L0, free, s):
    """After a wrong projection: what one pass of the student's provot_pass does on this cloth, when it says."""
    try:
        got = student.call("provot_pass", x, ij, L0, free, s)
    except GradingFailure:
        return "; your provot_pass fails on this cloth, see its tests"
    if not isinstance(got, np.ndarray) or got.shape != x.shape:
        return ""
    tolerance = ROUNDING * L0.min()
    for label, wrong in _pass_hints(x, ij, L0, free, s).items():
        if np.all(np.abs(got - wrong) <= tolerance) and not np.all(np.abs(got - _jacobi_pass(x, ij, L0, free, s))
                                                                   <= tolerance):
            return f"; one pass of your provot_pass on this cloth matches {label}"
    if np.all(np.abs(got - _jacobi_pass(x, ij, L0, free, s)) <= tolerance):
        return "; one pass of your provot_pass is a right Jacobi pass on this cloth, so look at the loop"
    return ""


# -- common checks -----------------------------------------------------------------------------


def _expect_pair(got, call):
    if not isinstance(got, tuple) or len(got) != 2:
        kind = describe_value(got) if not isinstance(got, tuple) else f"a tuple of {len(got)} values"
        raise GradingFailure(f"{call} returned {kind}, expected the tuple (x_new, passes)")
    x_new, passes = got
    if isinstance(passes, (bool, np.bool_)) or not isinstance(passes, (int, np.integer)):
        raise GradingFailure(f"{call} returned passes = {describe_value(passes)}, expected an int")
    return x_new, int(passes)


def _expect_pins_fixed(x_new, x, free, call, hidden=False):
    moved = np.flatnonzero(~free & np.any(x_new != x, axis=1)) if x_new.shape == x.shape else []
    if len(moved):
        k = int(moved[0])
        where = (f"by {np.linalg.norm(x_new[k] - x[k]):.3g} m" if hidden else
                 f"from {np.round(x[k], 4).tolist()} to {np.round(x_new[k], 4).tolist()}")
        raise GradingFailure(f"{call} moved pinned particle {k} {where}; pinned particles never move (only free "
                             "particles take a share of the excess: all of it when the other end is pinned)")


def _expect_within_limit(x_new, ij, L0, free, s, tol, call):
    movable = free[ij[:, 0]] | free[ij[:, 1]]
    strain = _strain(x_new, ij, L0)
    over = movable & (strain > s + tol + ROUNDING)
    if over.any():
        k = int(np.argmax(np.where(over, strain, -np.inf)))
        raise GradingFailure(f"{call}: after your projection spring {k} {ij[k].tolist()} still has strain "
                             f"{100 * strain[k]:.3f}%, {100 * (strain[k] - s - tol):.3g} percentage points above "
                             "max_strain + tol: keep making passes while a spring with a free end is too long")


# -- spring_strain -----------------------------------------------------------------------------


def _strain_hints(x, ij, L0):
    """Typical wrong strains: label -> the values they give."""
    L = np.linalg.norm(x[ij[:, 0]] - x[ij[:, 1]], axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):  # a spring of length 0 has no upside-down ratio
        upside_down = L0 / L - 1
    return {
        "(L^2 - L0^2) / (2 L0^2), the Green strain: this exercise uses the engineering strain L / L0 - 1":
            (L**2 - L0**2) / (2 * L0**2),
        "L - L0, the elongation in metres: the strain is relative, (L - L0) / L0": L - L0,
        "L0 / L - 1, the ratio upside down (the strain is L / L0 - 1)": upside_down,
        "L / L0, the stretch ratio without the - 1": L / L0,
        "|L / L0 - 1|: a compressed spring has a negative strain": np.abs(L / L0 - 1),
    }


@pytest.mark.points(1)
def test_spring_strain_three_springs(student):
    """spring_strain gives +50%, 0 and -50% for a stretched, a relaxed and a compressed spring."""
    x = np.array([[0.0, 0.0], [1.5, 0.0], [1.5, 2.0], [0.0, 0.0]])
    ij = np.array([[0, 1], [2, 1], [3, 2]])
    L0 = np.array([1.0, 2.0, 5.0])
    got = student.call("spring_strain", x, ij, L0, check_inputs=True)
    expect_array(got, [0.5, 0.0, 2.5 / 5.0 - 1.0], "spring_strain(x, [[0, 1], [2, 1], [3, 2]], L0=[1, 2, 5])",
                 hints=_strain_hints(x, ij, L0))


@pytest.mark.points(1)
@pytest.mark.hidden
def test_spring_strain_random_cloth(student, rng):
    """spring_strain matches the library's strain on a random stretched cloth, in 2D and 3D."""
    x, ij, L0, free = _random_cloth(rng)
    for x_test in (x, x[:, :2]):
        expect_array(student.call("spring_strain", x_test, ij, L0, check_inputs=True), _strain(x_test, ij, L0),
                     f"spring_strain on a random cloth of {len(ij)} springs in {x_test.shape[1]}D",
                     hints=_strain_hints(x_test, ij, L0), show_values=False)


# -- max_strain_history ------------------------------------------------------------------------


_UNCLIPPED = ("the largest strain without the clip at 0: a frame where every spring is compressed has "
              "max_strain_history 0, not a negative strain (max(0, largest strain))")


def _figure_strain(feedback, got, expected, title):
    """Attach the student's largest strain per frame beside the reference's, before the test judges it."""
    feedback.curve(title, "frame", "largest strain L / L0 - 1",
                   [{"label": "yours", "y": got}, {"label": "reference", "y": expected}],
                   caption="A frame where every spring is compressed has largest strain 0, not a negative one.")


@pytest.mark.points(1)
def test_max_strain_history_frames(student, feedback):
    """max_strain_history gives the largest strain of each frame, 0 for a frame where all springs are compressed."""
    L0 = np.array([1.0, 1.0])
    ij = np.array([[0, 1], [1, 2]])
    frames = [[0.0, 1.2, 2.2], [0.0, 0.9, 1.8], [0.0, 1.0, 2.5]]  # x of three particles on a line, per frame
    X = np.zeros((3, 3, 2, 2))
    X[:, :, 0, 0] = frames
    got = student.call("max_strain_history", X, ij, L0, check_inputs=True)
    _figure_strain(feedback, got, [0.2, 0.0, 0.5], "Largest strain of each of the 3 frames")
    expect_array(got, [0.2, 0.0, 0.5], "max_strain_history on 3 frames of 2 springs (strains [0.2, 0], "
                 "[-0.1, -0.1], [0, 0.5])", hints={"the largest |strain| (compression counted)": [0.2, 0.1, 0.5],
                                                   _UNCLIPPED: [0.2, -0.1, 0.5]})


@pytest.mark.points(2)
@pytest.mark.hidden
def test_max_strain_history_recorded_run(student, rng, feedback):
    """max_strain_history matches MassSpringSystem.max_strain on each frame of a recorded cloth simulation."""
    n = int(rng.integers(4, 8))
    c = cloth(n, n, plane=str(rng.choice(["vertical", "horizontal"])), k_structural=rng.uniform(10.0, 50.0))
    steps, h = int(rng.integers(20, 60)), 0.004
    _, X = c.run(steps * h, h, method="symplectic_euler", every=int(rng.integers(1, 4)))
    X[0, :, 0] *= 0.95  # a first frame where every spring is compressed
    for kind in ("structural", "shear"):
        springs = c.springs[kind]
        expected = [c.max_strain(Xk, kind) for Xk in X]
        got = student.call("max_strain_history", X, springs.indices, springs.rest_length, check_inputs=True)
        _figure_strain(feedback, got, expected, f"Largest strain per frame of a recorded cloth, {kind} springs")
        strains = [springs.strain(Xk[:, 0]) for Xk in X]
        expect_array(got, expected, f"max_strain_history on {len(X)} recorded frames of a {n} x {n} cloth "
                     f"({kind} springs; frame 0 compressed)", rtol=1e-9, show_values=False,
                     hints={_UNCLIPPED: [e.max() for e in strains],
                            "the largest |strain| (compression counted)": [np.abs(e).max() for e in strains]})


# -- provot_pass -------------------------------------------------------------------------------


SPRING = np.array([[0.0, 0.0], [1.5, 0.0]])  # rest length 1 m, stretched by 50%


@pytest.mark.points(1)
@pytest.mark.parametrize("ends", ["both free", "first pinned", "second pinned", "both pinned"])
def test_provot_pass_one_spring(student, ends):
    """provot_pass shortens one spring to (1 + s) L0: half the excess at each free end, all of it at the only free one."""
    free = {"both free": [True, True], "first pinned": [False, True], "second pinned": [True, False],
            "both pinned": [False, False]}[ends]
    free = np.array(free)
    call = f"provot_pass(x=[[0, 0], [1.5, 0]], [[0, 1]], L0=[1], free={free.tolist()}, max_strain=0.1)"
    got = student.call("provot_pass", SPRING, np.array([[0, 1]]), np.array([1.0]), free, 0.1, check_inputs=True)
    expected = _jacobi_pass(SPRING, np.array([[0, 1]]), np.array([1.0]), free, 0.1)
    if isinstance(got, np.ndarray) and got.shape == SPRING.shape:
        _expect_pins_fixed(got, SPRING, free, call)
        length = np.linalg.norm(got[1] - got[0])
        if free.any() and abs(length - 1.0) < 1e-9:
            raise GradingFailure(f"{call} shortened the spring to its rest length 1 m; Provot shortens it only to "
                                 "(1 + max_strain) L0 = 1.1 m")
        if free.any() and not free.all() and abs(length - 1.3) < 1e-9:
            raise GradingFailure(f"{call} moved the free end by half the excess only: the spring is {length:.4g} m "
                                 "long, not 1.1 m; a free end whose partner is pinned takes all of the excess "
                                 "(the shares are f_i / (f_i + f_j), 1 for the only free end)")
        if free.all() and abs(length - 1.1) < 1e-9 and abs(got[:, 0].mean() - 0.75) > 1e-9:
            raise GradingFailure(f"{call} moved the midpoint to x = {got[:, 0].mean():.4g} m; with both ends free "
                                 "each end moves half the excess and the midpoint stays at 0.75 m")
    expect_array(got, expected, call)


STAR = np.array([[0.0, 0.0], [1.5, 0.0], [0.0, 1.5], [0.0, -1.2]])  # free particle 0, pinned 1, 2, 3
STAR_SPRINGS = np.array([[0, 1], [0, 2], [3, 0]])                   # particle 0 appears twice as a first end


@pytest.mark.points(2)
def test_provot_pass_shared_particle(student):
    """At a particle shared by three too-long springs, provot_pass is a Jacobi pass (average) or a sequential one."""
    L0, free = np.ones(3), np.array([True, False, False, False])
    call = "provot_pass on three springs from particle 0 (free) to pinned 1, 2, 3, stretched by 50%, 50%, 20%"
    got = student.call("provot_pass", STAR, STAR_SPRINGS, L0, free, 0.1, check_inputs=True)
    right = [_jacobi_pass(STAR, STAR_SPRINGS, L0, free, 0.1)] + [
        _sequential_pass(STAR, STAR_SPRINGS, L0, free, 0.1, order) for order in itertools.permutations(range(3))]
    if isinstance(got, np.ndarray) and got.shape == STAR.shape and got.dtype.kind == "f":
        if any(np.allclose(got, r, rtol=0, atol=1e-10) for r in right):
            return
        _expect_pins_fixed(got, STAR, free, call)
        found = np.round(got[0], 4).tolist()
        hints = {"the sum of the three corrections instead of their average": STAR + [[0.4, 0.3], [0, 0], [0, 0],
                                                                                         [0, 0]],
                 "a lost correction (x[i] += c with a repeated index keeps only the last one)":
                     STAR + [[0.0, 0.1], [0, 0], [0, 0], [0, 0]]}
        for label, wrong in hints.items():
            if np.allclose(got, wrong, rtol=0, atol=1e-10):
                raise GradingFailure(f"{call} moved particle 0 to {found}; your result matches {label}")
        raise GradingFailure(f"{call} moved particle 0 to {found}: neither a Jacobi pass (particle 0 moves by the "
                             f"average of its three corrections, to {np.round(right[0][0], 4).tolist()}) nor Provot's "
                             "sequential pass (the springs corrected one after another, each from the positions the "
                             "corrections before it left, in any order)")
    expect_array(got, right[0], call)  # says what is wrong with the type or shape


@pytest.mark.points(3)
@pytest.mark.hidden
def test_provot_pass_random_cloths(student, rng):
    """provot_pass is exact on random springs that share no particle, keeps pins and leaves a cloth within the limit."""
    for d in (2, 3):
        x, ij, L0, free = _separate_springs(rng, d)
        s = rng.uniform(0.02, 0.2)
        call = f"provot_pass on {len(ij)} random springs that share no particle in {d}D (random pins)"
        got = student.call("provot_pass", x, ij, L0, free, s, check_inputs=True)
        if isinstance(got, np.ndarray) and got.shape == x.shape:
            _expect_pins_fixed(got, x, free, call, hidden=True)
        expect_array(got, _jacobi_pass(x, ij, L0, free, s), call, rtol=ROUNDING, show_values=False,
                     hints=lambda: _pass_hints(x, ij, L0, free, s))
    for _ in range(2):
        x, ij, L0, free = _random_cloth(rng, kinds=("structural", "shear", "flexion")[:int(rng.integers(2, 4))])
        s = rng.uniform(0.02, 0.2)
        if rng.random() < 0.5:
            x = x[:, :2].copy()  # the pass works in any dimension
        call = f"provot_pass on {_describe(x, ij, free, s)}, d = {x.shape[1]}"
        got = student.call("provot_pass", x, ij, L0, free, s, check_inputs=True)
        if not isinstance(got, np.ndarray) or got.shape != x.shape or not np.isfinite(got).all():
            expect_array(got, _jacobi_pass(x, ij, L0, free, s), call, show_values=False)
        _expect_pins_fixed(got, x, free, call, hidden=True)
    x, ij, L0, free = _relaxed_cloth(rng)
    expect_array(student.call("provot_pass", x, ij, L0, free, 0.1), x, "provot_pass on a random cloth where no spring "
                 "is too long (nothing may move)", rtol=0, atol=0, show_values=False)


# -- provot_project ----------------------------------------------------------------------------


def _check_projection(student, x, ij, L0, free, s, iterations, tol, call, hidden=True, reference=None):
    """The projection's invariants: pins exact, within the limit, a bound of passes, no pass more than needed.

    Returns the student's positions and passes.
    """
    got = student.call("provot_project", x, ij, L0, free, s, iterations, tol, check_inputs=True)
    x_new, passes = _expect_pair(got, call)
    ref = reference or _projection(x, ij, L0, free, s, iterations, tol)
    if not isinstance(x_new, np.ndarray) or x_new.shape != x.shape or not np.isfinite(x_new).all():
        expect_array(x_new, ref.x, call, show_values=False)  # says what is wrong with the array
    _expect_pins_fixed(x_new, x, free, call, hidden=hidden)
    if passes > iterations:
        raise GradingFailure(f"{call} reported {passes} passes, more than the {iterations} allowed")
    bound = int(SLOWEST * ref.iterations) + 2
    if ref.converged and passes > bound:
        raise GradingFailure(f"{call} made {passes} passes; a Jacobi projection with averaging needs {ref.iterations}, "
                             f"and the grader allows {bound}. Stop as soon as every spring with a free end holds "
                             "(springs with both ends pinned never do)" + _pass_diagnosis(student, x, ij, L0, free, s))
    if passes < iterations:  # it stopped before the cap: every spring with a free end must hold
        try:
            _expect_within_limit(x_new, ij, L0, free, s, tol, call)
        except GradingFailure as failure:
            raise GradingFailure(str(failure) + _pass_diagnosis(student, x, ij, L0, free, s)) from None
    if passes >= 2:  # one pass fewer must not do
        earlier, _ = _expect_pair(student.call("provot_project", x, ij, L0, free, s, passes - 1, tol), call)
        movable = free[ij[:, 0]] | free[ij[:, 1]]
        if isinstance(earlier, np.ndarray) and earlier.shape == x.shape and \
                np.max(_strain(earlier, ij, L0)[movable], initial=0.0) <= s + tol:
            raise GradingFailure(f"{call} reported {passes} passes, but with iterations={passes - 1} your projection "
                                 "already holds every spring: count only the passes made, and stop as soon as every "
                                 "spring with a free end is within max_strain + tol (checked before each pass)")
    return x_new, passes


@pytest.mark.points(2)
def test_provot_project_chain(student):
    """provot_project brings a stretched chain of 5 particles pinned at one end within the limit, stopping in time."""
    x = np.array([[0.0, 0.0], [1.4, 0.0], [2.6, 0.0], [4.0, 0.0], [5.0, 0.0]])
    ij = np.array([[0, 1], [1, 2], [2, 3], [3, 4]])
    L0, free = np.ones(4), np.array([False, True, True, True, True])
    call = "provot_project on a chain [0, 1.4, 2.6, 4, 5] m, L0 = 1 m, particle 0 pinned, max_strain=0.1, tol=0.005"
    _check_projection(student, x, ij, L0, free, 0.1, 500, 0.005, call, hidden=False)


@pytest.mark.points(1)
def test_provot_project_nothing_to_do(student):
    """provot_project returns the positions unchanged and 0 passes when every spring already holds."""
    c, ij, L0 = _curtain_springs()
    x = c.X[:, 0] * 1.05  # 5% longer everywhere: within 10%
    free = np.ones(c.n, dtype=bool)
    x_new, passes = _expect_pair(student.call("provot_project", x, ij, L0, free, check_inputs=True),
                                 "provot_project on a cloth stretched by 5% (within the limit)")
    expect_array(x_new, x, "provot_project on a cloth stretched by 5% (nothing to correct)", rtol=0, atol=0)
    if passes != 0:
        raise GradingFailure(f"provot_project on a cloth stretched by 5% reported {passes} passes; nothing is too "
                             "long, so it must stop before the first pass (0 passes)")


@pytest.mark.points(3)
@pytest.mark.hidden
@pytest.mark.time_limit(10)
def test_provot_project_random_cloths(student, rng):
    """On random cloths provot_project keeps the pins, ends within the limit in a bounded number of passes, or at the cap."""
    for _ in range(2):
        x, ij, L0, free, s, tol, ref = _converging_cloth(rng)
        _check_projection(student, x, ij, L0, free, s, 500, tol, f"provot_project on {_describe(x, ij, free, s)}",
                          reference=ref)
    x, ij, L0, free, s, tol, ref = _converging_cloth(rng)
    cap = int(rng.integers(1, 4))
    call = f"provot_project on {_describe(x, ij, free, s)}, iterations={cap}"
    x_new, passes = _check_projection(student, x, ij, L0, free, s, cap, tol, call)
    movable = free[ij[:, 0]] | free[ij[:, 1]]
    if passes < cap and np.max(_strain(x_new, ij, L0)[movable], initial=0.0) > s + tol + ROUNDING:
        raise GradingFailure(f"{call} stopped after {passes} passes with a spring still too long: keep making passes "
                             "until every spring with a free end holds or the cap is reached")


@pytest.mark.points(2)
@pytest.mark.hidden
@pytest.mark.time_limit(10)
def test_provot_project_properties(student, rng):
    """provot_project stops though two pinned neighbours stay too long, and a free pair keeps its midpoint."""
    for pinned_pair in (True, False, True):
        x, ij, L0, free, s, tol, ref = _converging_cloth(rng, pinned_pair=pinned_pair)
        _check_projection(student, x, ij, L0, free, s, 500, tol, f"provot_project on {_describe(x, ij, free, s)}",
                          reference=ref)
    x, ij, L0, free = _separate_springs(rng, 3, pins=False)
    s, tol = rng.uniform(0.02, 0.2), rng.uniform(0.002, 0.01)
    call = f"provot_project on {len(ij)} random free pairs (springs that share no particle)"
    x_new, _ = _expect_pair(student.call("provot_project", x, ij, L0, free, s, 500, tol), call)
    if isinstance(x_new, np.ndarray) and x_new.shape == x.shape:
        shift = np.abs(x_new[ij].mean(axis=1) - x[ij].mean(axis=1)).max()
        if shift > ROUNDING * L0.min():
            raise GradingFailure(f"{call} moved the midpoint of a free pair by {shift:.2g} m: with both ends free each "
                                 "moves half the excess, towards the other, and the pair's momentum is kept")
    expect_array(x_new, _projection(x, ij, L0, free, s, 500, tol).x, call, rtol=ROUNDING, show_values=False,
                 hints=lambda: _pass_hints(x, ij, L0, free, s))


# -- constrain_state ---------------------------------------------------------------------------


@pytest.mark.points(1)
def test_constrain_state_one_spring(student):
    """constrain_state moves the free end of a pinned spring back by 0.4 m and its velocity by -0.4 m / h."""
    X = np.array([[[0.0, 0.0], [0.0, 0.0]], [[1.5, 0.0], [2.0, 1.0]]])
    h = 0.01
    call = "constrain_state(X, h=0.01) for a spring 0-1 of L0 = 1 m stretched to 1.5 m, particle 0 pinned"
    got = student.call("constrain_state", X, h, np.array([[0, 1]]), np.array([1.0]), np.array([False, True]),
                       check_inputs=True)
    X_new, passes = _expect_pair(got, call)
    expected = np.array([[[0.0, 0.0], [0.0, 0.0]], [[1.1, 0.0], [2.0 - 40.0, 1.0]]])
    unchanged = expected.copy()
    unchanged[1, 1] = X[1, 1]
    expect_array(X_new, expected, call, hints={"the velocities left unchanged (v += dx / h is missing)": unchanged,
                                               "v = dx / h (the velocity of the step replaced)": expected
                                               - np.array([[[0, 0], [0, 0]], [[0, 0], [2.0, 1.0]]])})
    if passes != 1:
        raise GradingFailure(f"{call} reported {passes} passes, expected 1")


@pytest.mark.points(2)
@pytest.mark.hidden
@pytest.mark.time_limit(10)
def test_constrain_state_random_cloths(student, rng):
    """constrain_state projects the positions as provot_project does and adds dx / h to the velocities; pins keep v = 0."""
    for cap in (500, int(rng.integers(2, 8))):
        x, ij, L0, free, s, tol, ref = _converging_cloth(rng)
        h = rng.uniform(0.001, 0.02)
        v = rng.normal(0.0, 0.5, x.shape)
        v[~free] = 0.0
        X = np.stack([x, v], axis=1)
        call = f"constrain_state(X, h) on {_describe(x, ij, free, s)}, iterations={cap}"
        X_new, passes = _expect_pair(student.call("constrain_state", X, h, ij, L0, free, s, cap, tol,
                                                  check_inputs=True), call)
        x_own, passes_own = _expect_pair(student.call("provot_project", x, ij, L0, free, s, cap, tol),
                                         f"provot_project on the same cloth, iterations={cap}")
        expected = np.stack([x_own, v + (x_own - x) / h], axis=1)
        expect_array(X_new, expected, call, rtol=1e-9, atol=ROUNDING * L0.min() / h, show_values=False,
                     hints={"the velocities left unchanged (v += dx / h is missing)": np.stack([x_own, v], axis=1),
                            "v = dx / h (the velocity of the step replaced; add dx / h to it)":
                                np.stack([x_own, (x_own - x) / h], axis=1),
                            "v + dx, the correction not divided by h (a velocity is dx / h)":
                                np.stack([x_own, v + (x_own - x)], axis=1)})
        if passes != passes_own:
            raise GradingFailure(f"{call} reported {passes} passes, your provot_project on the same positions "
                                 f"{passes_own}")
        if passes < cap:
            _expect_within_limit(X_new[:, 0], ij, L0, free, s, tol, call)
        expect_float(float(np.abs(X_new[~free, 1]).max(initial=0.0)), 0.0, f"the velocity of the pins after {call}",
                     show_values=False)
    x, ij, L0, free = _separate_springs(rng, 2, pins=False)
    v = rng.normal(0.0, 0.5, x.shape)
    X_new, _ = _expect_pair(student.call("constrain_state", np.stack([x, v], axis=1), 0.01, ij, L0, free),
                            "constrain_state on random free pairs")
    if isinstance(X_new, np.ndarray) and X_new.shape == (len(x), 2, 2) and \
            not np.allclose(X_new[:, 1].sum(axis=0), v.sum(axis=0), rtol=1e-9, atol=1e-9):
        raise GradingFailure("constrain_state on random free pairs (springs that share no particle) changed their "
                             "total momentum: with both ends free each end moves half the excess, towards the other, "
                             "so the corrections dx of a pair cancel, and so do their dx / h")
