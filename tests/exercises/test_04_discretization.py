"""Autograder tests of exercise 04_discretization: physical masses and stiffnesses of a cloth.

The student derives the masses (density x dual-cell area) and the spring
stiffnesses (``k = Y A / L0^2`` by matching elastic energies) that make a
mass-spring cloth the same fabric at every resolution, shows that its static
sag then converges, and fits how the stable step of symplectic Euler shrinks
with the spacing. Public tests use small grids a student can work out by
hand and the lecture's fabric; hidden tests draw sheets, grids and fabrics
from the grading seed (fixture ``rng``). Every expected value comes from the
reference library (:func:`particles.massspring.cloth_masses`,
:func:`~particles.massspring.cloth_stiffness`, the physically scaled
:func:`~particles.massspring.cloth` relaxed by
:func:`particles.studies.discretization.static_sag`,
:meth:`~particles.massspring.MassSpringSystem.max_stable_step` and
:func:`particles.studies.order.fit_order`), computed here in the grader.
"""

import numpy as np
import pytest

from particles.course.grading.expect import LN10, expect_array, expect_float
from particles.course.grading.memo import memoized
from particles.course.worker.runner import GradingFailure, describe_value
from particles.massspring import cloth, cloth_masses, cloth_springs, cloth_stiffness
from particles.studies.discretization import static_sag
from particles.studies.order import fit_order

EXERCISE = "04_discretization"
FORBIDDEN = {
    "particles.massspring.cloth_masses": "it is the mass rule you are asked to derive",
    "particles.massspring.cloth_stiffness": "it is the stiffness rule you are asked to derive",
    "particles.massspring.cloth": "its scaling option builds the physically scaled cloth for you; build yours "
                                  "with build_cloth and your own masses and stiffnesses",
    "particles.studies.discretization.hanging_cloth": "it builds the physically scaled cloth for you",
    "particles.studies.discretization.static_sag": "measure the sag yourself: relax, then the drop of the lowest "
                                                   "particle",
    "particles.studies.discretization.discretization_study": "it runs the whole measurement of this exercise",
    "particles.studies.order.fit_order": "fit the exponent yourself (a least-squares line in log-log coordinates)",
}

KINDS = ("structural", "shear", "flexion")
FABRIC = {"structural": 100.0, "shear": 25.0, "flexion": 10.0}  # the notebook's moduli, N/m
RHO = 0.2  # kg/m^2
SAG_TOLERANCE = 0.03  # "within a few percent"
SAG_TIMEOUT = 15.0  # seconds per cloth_sag call; the master needs well under one
STEP_BELOW = 0.02  # a stable step may lie this far below 2 / omega_max ...
STEP_ABOVE = 1e-4  # ... and no further above it than the reference's eigensolver tolerance: above, it blows up


def _weights(n):
    w = np.ones(n)
    w[[0, -1]] = 0.5
    return w


def _random_sheet(rng, least=3, most=16):
    nx, ny = (int(v) for v in rng.integers(least, most + 1, 2))
    return nx, ny, float(rng.uniform(0.4, 2.0)), float(rng.uniform(0.4, 2.0))


def _random_fabric(rng):
    Ys = float(rng.uniform(50.0, 250.0))
    return float(rng.uniform(0.1, 0.4)), {"structural": Ys, "shear": Ys * float(rng.uniform(0.1, 0.5)),
                                          "flexion": Ys * float(rng.uniform(0.05, 0.2))}


def _moduli_text(Y):
    return "Y={" + ", ".join(f"{k}: {v:.3g}" for k, v in Y.items()) + "}"


def _fabric_text(rho, Y):
    return f"rho={rho:.3g}, {_moduli_text(Y)}"


def _number(value, call):
    """`value` as a float when it is a finite real number, else a GradingFailure."""
    if isinstance(value, np.ndarray) and value.shape == ():
        value = value[()]
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise GradingFailure(f"{call} returned {describe_value(value)}, expected a number")
    if not np.isfinite(value):
        raise GradingFailure(f"{call} returned {value}, expected a finite number")
    return float(value)


# -- particle_masses ---------------------------------------------------------------------------


def _mass_hints(nx, ny, W, H, rho):
    dx, dy = W / (nx - 1), H / (ny - 1)
    n = nx * ny
    return {
        "rho dx dy on every particle (edge particles stand for half a cell, corners for a quarter)":
            np.full(n, rho * dx * dy),
        "the mass of the whole sheet, rho W H, on every particle": np.full(n, rho * W * H),
        "rho W H / (nx ny) on every particle (the total is right, but edges and corners stand for less area)":
            np.full(n, rho * W * H / n),
        "rho W H / ((nx - 1)(ny - 1)) on every particle": np.full(n, rho * W * H / ((nx - 1) * (ny - 1))),
        "the weights of rows and columns swapped (index j nx + i is column i, row j)":
            rho * dx * dy * np.outer(_weights(nx), _weights(ny)).ravel() if nx != ny else np.full(n, np.nan),
    }


_SAME_MASS = ("your particles all have the same mass: a corner stands for a quarter of a cell, an edge particle for "
              "half a cell, an interior one for a whole cell (rho times its dual cell's area)")


def _check_masses(student, nx, ny, W, H, rho, hidden=False):
    """The student's masses against the dual-cell rule; a hidden test (`hidden`) keeps W, H and rho out of messages."""
    call = (f"particle_masses(nx={nx}, ny={ny}, width, height, rho) on a random sheet" if hidden else
            f"particle_masses(nx={nx}, ny={ny}, width={W:.4g}, height={H:.4g}, rho={rho:.4g})")
    got = student.call("particle_masses", nx, ny, W, H, rho)
    expected = cloth_masses(nx, ny, W, H, rho)
    def hints():
        return dict(_mass_hints(nx, ny, W, H, rho), **{_SAME_MASS: lambda m: m.size > 1 and np.ptp(m) == 0})

    if isinstance(got, np.ndarray) and got.shape == expected.shape and got.dtype.kind == "f" \
            and np.all(np.isfinite(got)) and not np.isclose(got.sum(), rho * W * H, rtol=1e-9):
        hint = ""
        for label, wrong in hints().items():
            if (wrong(got) if callable(wrong) else np.allclose(got, wrong, rtol=1e-9)):
                hint = f"; {label}" if label.startswith("your ") else f"; your result matches {label}"
                break
        total = (f"add up to {got.sum() / (rho * W * H):.4g} times rho W H, the mass of the sheet" if hidden else
                 f"add up to {got.sum():.6g} kg, but the sheet weighs rho W H = {rho * W * H:.6g} kg")
        raise GradingFailure(f"the masses of {call} {total}{hint}")
    expect_array(got, expected, call, rtol=1e-9, hints=hints, show_values=not hidden)


@pytest.mark.points(1)
def test_masses_small_grid(student):
    """particle_masses on a 4 x 3 grid of 1 m cells: quarter, half and whole cells."""
    _check_masses(student, 4, 3, 3.0, 2.0, 0.5)


@pytest.mark.points(2)
@pytest.mark.hidden
def test_masses_random(student, rng):
    """particle_masses matches the dual-cell rule on random sheets, grids and densities."""
    for _ in range(4):
        nx, ny, W, H = _random_sheet(rng, 3, 30)
        _check_masses(student, nx, ny, W, H, float(rng.uniform(0.05, 2.0)), hidden=True)


# -- spring_stiffness --------------------------------------------------------------------------


def _stiffness_of(student, nx, ny, W, H, Y, hidden=False):
    call = (f"spring_stiffness(nx={nx}, ny={ny}, width, height, Y) on a random sheet and fabric" if hidden else
            f"spring_stiffness(nx={nx}, ny={ny}, width={W:.4g}, height={H:.4g}, {_moduli_text(Y)})")
    got = student.call("spring_stiffness", nx, ny, W, H, dict(Y))
    if not isinstance(got, dict):
        raise GradingFailure(f"{call} returned {describe_value(got)}, expected a dict with the keys "
                             "'structural', 'shear' and 'flexion'")
    missing = [kind for kind in KINDS if kind not in got]
    if missing:
        raise GradingFailure(f"{call} returned a dict without the key(s) {', '.join(map(repr, missing))}")
    return got, call


def _stiffness_rule(nx, ny, W, H, Y, kind, half_edges=True, flexion_area="shared", flexion_gap=2):
    """k = Y A / L0^2 for one kind, in the order of cloth_springs; the options give typical wrong rules."""
    dx, dy = W / (nx - 1), H / (ny - 1)
    wx, wy = (_weights(nx), _weights(ny)) if half_edges else (np.ones(nx), np.ones(ny))
    if kind == "shear":
        return np.full(2 * (nx - 1) * (ny - 1), Y[kind] * dx * dy / 2 / (dx**2 + dy**2))
    g = 1 if kind == "structural" else 2
    if kind == "flexion" and flexion_area != "shared":  # A = 2 dx w dy: two cells per flexion spring
        A_rows, A_cols = 2 * dx * wy[:, None] * dy, 2 * dy * wx[None, :] * dx
    else:  # the n - g springs of a row (column) share its strip
        A_rows, A_cols = W * wy[:, None] * dy / (nx - g), H * wx[None, :] * dx / (ny - g)
    L = flexion_gap if kind == "flexion" else 1
    rows = (Y[kind] * A_rows / (L * dx) ** 2 * np.ones((ny, nx - g))).ravel()
    cols = (Y[kind] * A_cols / (L * dy) ** 2 * np.ones((ny - g, nx))).ravel()
    return np.concatenate([rows, cols])


def _stiffness_hints(nx, ny, W, H, Y, kind):
    """Typical wrong stiffnesses of one kind, in the order of cloth_springs."""
    dx, dy = W / (nx - 1), H / (ny - 1)
    g = 2 if kind == "flexion" else 1
    along_rows = ny * (nx - g)
    s = len(cloth_springs(nx, ny)[kind])
    L0 = np.full(s, np.hypot(dx, dy)) if kind == "shear" else \
        np.concatenate([np.full(along_rows, g * dx), np.full(s - along_rows, g * dy)])
    ref = _stiffness_rule(nx, ny, W, H, Y, kind)
    hints = {
        f"Y['{kind}'] on every spring (k = Y, whatever the rest length and the area)": np.full(s, Y[kind]),
        "k proportional to the rest length, Y L0 (k = Y A / L0^2 falls with L0)": Y[kind] * L0,
        "Y / L0, the rule of a string (the area A a spring stands for is missing)": Y[kind] / L0,
    }
    if kind == "shear":
        hints["a whole cell per diagonal, A = dx dy (the two diagonals of a cell share it)"] = 2 * ref
        return hints
    hints["the interior value on every spring (the springs of the first and last rows and columns stand for "
          "half a strip)"] = _stiffness_rule(nx, ny, W, H, Y, kind, half_edges=False)
    if kind == "flexion":
        hints["L0 = dx for a flexion spring (it spans two cells: L0 = 2 dx)"] = \
            _stiffness_rule(nx, ny, W, H, Y, kind, flexion_gap=1)
        hints["an area of 2 dx w dy per flexion spring (the nx - 2 springs of a row share its strip, W long)"] = \
            _stiffness_rule(nx, ny, W, H, Y, kind, flexion_area="2 cells")
    return hints


def _check_kind(got, call, nx, ny, W, H, Y, kind, hidden=False):
    expected = cloth_stiffness(nx, ny, W, H, Y)[kind]
    expect_array(got[kind], expected, f"the '{kind}' stiffnesses of {call}", rtol=1e-9,
                 hints=lambda: _stiffness_hints(nx, ny, W, H, Y, kind), show_values=not hidden)


@pytest.mark.points(1)
def test_structural_small_grid(student):
    """spring_stiffness: structural springs of a 4 x 3 grid of 1 m x 0.5 m cells."""
    got, call = _stiffness_of(student, 4, 3, 3.0, 1.0, FABRIC)
    _check_kind(got, call, 4, 3, 3.0, 1.0, FABRIC, "structural")


@pytest.mark.points(1)
def test_shear_small_grid(student):
    """spring_stiffness: shear springs of a 4 x 3 grid of 1 m x 0.5 m cells."""
    got, call = _stiffness_of(student, 4, 3, 3.0, 1.0, FABRIC)
    _check_kind(got, call, 4, 3, 3.0, 1.0, FABRIC, "shear")


@pytest.mark.points(1)
def test_flexion_small_grid(student):
    """spring_stiffness: flexion springs of a 5 x 4 grid of 1 m x 0.5 m cells."""
    got, call = _stiffness_of(student, 5, 4, 4.0, 1.5, FABRIC)
    _check_kind(got, call, 5, 4, 4.0, 1.5, FABRIC, "flexion")


@pytest.mark.points(3)
@pytest.mark.hidden
def test_stiffness_random(student, rng):
    """spring_stiffness matches k = Y A / L0^2 for every kind on random sheets, grids and moduli."""
    for _ in range(3):
        nx, ny, W, H = _random_sheet(rng, 3, 25)
        _, Y = _random_fabric(rng)
        got, call = _stiffness_of(student, nx, ny, W, H, Y, hidden=True)
        for kind in KINDS:
            _check_kind(got, call, nx, ny, W, H, Y, kind, hidden=True)


# -- cloth_sag ---------------------------------------------------------------------------------


@memoized
def _reference_sag(n, W, H, rho, Y):
    c = cloth(n, n, W, H, pins="top edge", scaling="physical", areal_density=rho, stretch_modulus=Y["structural"],
              shear_modulus=Y["shear"], flexion_modulus=Y["flexion"])
    return static_sag(c)


@memoized
def _sag_variants(n, W, H, rho, Y):
    """Typical wrong sags of the library's relaxed n x n cloth: label -> value (m)."""
    c = cloth(n, n, W, H, pins="top edge", scaling="physical", areal_density=rho, stretch_modulus=Y["structural"],
              shear_modulus=Y["shear"], flexion_modulus=Y["flexion"])
    z0 = c.X[:, 0, 2].copy()
    static_sag(c)
    z = c.X[:, 0, 2]
    free = np.ones(len(z), dtype=bool)
    free[c.pinned] = False
    return {
        "your sag is the mean drop of the particles, not the drop of the lowest particle: the sag is "
        "z_flat.min() - z.min()": float(np.mean(z0 - z)),
        "your sag is the mean drop of the free particles, not the drop of the lowest particle: the sag is "
        "z_flat.min() - z.min()": float(np.mean((z0 - z)[free])),
        "your sag is the largest drop of any particle, not the drop of the lowest point (z_flat.min() - z.min())":
            float(np.max(z0 - z)),
        "your sag is the depth of the lowest particle below the pins, -z.min(): subtract the flat sheet's lowest z":
            float(-z.min()),
    }


def _sag_diagnosis(student, got, n, W, H, rho, Y):
    """Why a sag is off: a wrong measurement of the sag, or wrong masses or stiffnesses (checked at this n)."""
    for label, value in _sag_variants(n, W, H, rho, Y).items():
        if abs(got - value) <= 5e-3 * abs(value):
            return f"; {label}"
    return _parts_diagnosis(student, n, W, H, rho, Y) or (
        "; your masses and stiffnesses match the reference, so look at sag: relax the cloth, then the drop of its "
        "lowest particle")


def _parts_diagnosis(student, n, W, H, rho, Y):
    """'; your particle_masses does not match ...' when the student's masses or stiffnesses are wrong at n, else ''."""
    for name, args, reference in (("particle_masses", (n, n, W, H, rho), cloth_masses(n, n, W, H, rho)),
                                  ("spring_stiffness", (n, n, W, H, dict(Y)), None)):
        try:
            value = student.call(name, *args)
            if reference is None:
                expected = cloth_stiffness(n, n, W, H, Y)
                ok = isinstance(value, dict) and all(
                    isinstance(value.get(k), np.ndarray) and value[k].shape == expected[k].shape
                    and np.allclose(value[k], expected[k], rtol=1e-9) for k in KINDS)
            else:
                ok = isinstance(value, np.ndarray) and value.shape == reference.shape and \
                    np.allclose(value, reference, rtol=1e-9)
        except GradingFailure:
            ok = False
        if not ok:
            return f"; your {name} does not match the reference at n = {n}, see the tests of {name}"
    return ""


def _student_sags(student, resolutions, W, H, rho, Y):
    """What the student's cloth_sag gives at `resolutions`, up to its first failure: a list of results.

    Each is what the call returned, or the GradingFailure it raised (the last one then): the figure and
    the check read the same answers, and the student's relaxations run once.
    """
    answers = []
    for n in resolutions:
        try:
            answers.append(student.call("cloth_sag", n, n, W, H, rho, dict(Y), timeout=SAG_TIMEOUT))
        except GradingFailure as failure:
            answers.append(failure)
            break
    return answers


def _check_sag_converges(student, answers, resolutions, W, H, rho, Y, hidden=False):
    """The student's sags at `resolutions` (n x n) agree with each other and with the library's converged sag.

    `answers` are the student's, from :func:`_student_sags`. A hidden test (`hidden`) keeps its random sheet
    and fabric out of the message.
    """
    reference = _reference_sag(max(resolutions), W, H, rho, Y)
    sags = []
    for n, got in zip(resolutions, answers):
        call = (f"cloth_sag(nx={n}, ny={n}, width, height, rho, Y) of a random sheet and fabric" if hidden else
                f"cloth_sag(nx={n}, ny={n}, width={W:.3g}, height={H:.3g}, {_fabric_text(rho, Y)})")
        if isinstance(got, GradingFailure):
            raise got
        got = _number(got, call)
        sags.append(got)
        if not abs(got - reference) <= SAG_TOLERANCE * reference:
            so_far = ", ".join(f"{1000 * s:.4g}" for s in sags)
            fabric = "a random sheet and fabric" if hidden else f"{W:.3g} m x {H:.3g} m, {_fabric_text(rho, Y)}"
            raise GradingFailure(
                f"cloth_sag gives {so_far} mm at {', '.join(map(str, resolutions[:len(sags)]))} particles per side "
                f"for {fabric}: expected the sag of that fabric, "
                f"{1000 * reference:.4g} mm, within {100 * SAG_TOLERANCE:g}% at every resolution "
                f"(off by {100 * (got - reference) / reference:+.1f}% at n = {n})"
                + _sag_diagnosis(student, got, n, W, H, rho, Y))
    spread = (max(sags) - min(sags)) / reference
    if spread > SAG_TOLERANCE:
        raise GradingFailure(f"cloth_sag changes by {100 * spread:.1f}% between {resolutions[0]} and "
                             f"{resolutions[-1]} particles per side; expected the same sag within "
                             f"{100 * SAG_TOLERANCE:g}%")


def _figure_sag(feedback, answers, resolutions, W, H, rho, Y, hidden=False):
    """Attach the student's sag against the resolution beside the library's, before the test judges it.

    `answers` are the student's, from :func:`_student_sags` (up to its first failure, which the test
    reports). A hidden test plots sags relative to the library's at the finest resolution, so that its random
    sheet and fabric do not show.
    """
    reference = np.array([_reference_sag(n, W, H, rho, Y) for n in resolutions])
    yours = []
    for value in answers:
        if isinstance(value, GradingFailure):
            break
        if isinstance(value, np.ndarray) and value.shape == ():
            value = value[()]
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
            break
        yours.append(float(value))
    scale = reference[-1] if hidden else 1e-3
    series = [{"label": "reference", "x": resolutions, "y": reference / scale}]
    if yours:
        series.insert(0, {"label": "yours", "x": resolutions[:len(yours)], "y": np.array(yours) / scale})
    feedback.curve("Static sag of " + ("a random sheet" if hidden else "the 1 m fabric") + " against the resolution",
                   "particles per side n", "sag / the library's sag at the finest n" if hidden else "sag (mm)",
                   series, caption=f"With physical masses and stiffnesses the sag is the same at every n "
                                   f"(within {100 * SAG_TOLERANCE:g}%).")


@pytest.mark.points(2)
def test_sag_converges(student, feedback):
    """cloth_sag of the notebook's 1 m fabric is the same sag at 8 and 16 particles per side."""
    answers = _student_sags(student, [8, 16], 1.0, 1.0, RHO, FABRIC)
    _figure_sag(feedback, answers, [8, 16], 1.0, 1.0, RHO, FABRIC)
    _check_sag_converges(student, answers, [8, 16], 1.0, 1.0, RHO, FABRIC)


@pytest.mark.points(3)
@pytest.mark.hidden
def test_sag_converges_random_fabric(student, rng, feedback):
    """cloth_sag of a random sheet and fabric is the same sag at 8, 12 and 16 particles per side."""
    W, H = float(rng.uniform(0.5, 1.5)), float(rng.uniform(0.5, 1.5))
    rho, Y = _random_fabric(rng)
    answers = _student_sags(student, [8, 12, 16], W, H, rho, Y)
    _figure_sag(feedback, answers, [8, 12, 16], W, H, rho, Y, hidden=True)
    _check_sag_converges(student, answers, [8, 12, 16], W, H, rho, Y, hidden=True)


# -- stable_step and fit_exponent --------------------------------------------------------------


@memoized
def _reference_step(n, W, H, rho, Y):
    c = cloth(n, n, W, H, pins="top edge", scaling="physical", areal_density=rho, stretch_modulus=Y["structural"],
              shear_modulus=Y["shear"], flexion_modulus=Y["flexion"])
    return c.max_stable_step()


def _student_steps(student, resolutions, W, H, rho, Y, random_fabric=False):
    """The student's stable steps at `resolutions`, each at most STEP_BELOW below 2 / omega_max and not above it."""
    steps = []
    for n in resolutions:
        call = (f"stable_step(nx={n}, ny={n}, ...) of a random sheet and fabric" if random_fabric else
                f"stable_step(nx={n}, ny={n}, width={W:.3g}, height={H:.3g}, {_fabric_text(rho, Y)})")
        got = _number(student.call("stable_step", n, n, W, H, rho, dict(Y)), call)
        expected = _reference_step(n, W, H, rho, Y)
        if got > (1 + STEP_ABOVE) * expected:
            above = 100 * (got - expected) / expected
            why = _parts_diagnosis(student, n, W, H, rho, Y) or (
                ": omega_max comes from the eigenvalues of the whole cloth (system.max_stable_step()), not from one "
                "spring")
            percent = f"{above:.2g}%" if above < 100 else f"{above:.0f}%"
            raise GradingFailure(f"{call} returned {1000 * got:.4g} ms, {percent} "
                                 f"above 2 / omega_max = {1000 * expected:.4g} ms of the physically scaled cloth, a "
                                 f"step at which symplectic Euler blows up on it{why}")
        if not got >= (1 - STEP_BELOW) * expected:
            raise GradingFailure(f"{call} returned {1000 * got:.4g} ms, expected 2 / omega_max = "
                                 f"{1000 * expected:.4g} ms for the physically scaled cloth "
                                 f"(off by {100 * (got - expected) / expected:+.1f}%)"
                                 + _parts_diagnosis(student, n, W, H, rho, Y))
        steps.append(got)
    return np.array(steps)


@pytest.mark.points(1)
def test_stable_step(student):
    """stable_step of the notebook's 1 m fabric at 8 and 16 particles per side is 2 / omega_max, not above it."""
    _student_steps(student, [8, 16], 1.0, 1.0, RHO, FABRIC)


@pytest.mark.points(2)
@pytest.mark.hidden
def test_stable_step_shrinks_like_the_spacing(student, rng):
    """stable_step of a random fabric matches the library at 8, 12, 16 (not above it) and shrinks like dx^1."""
    W = float(rng.uniform(0.5, 1.5))
    rho, Y = _random_fabric(rng)
    resolutions = [8, 12, 16]
    steps = _student_steps(student, resolutions, W, W, rho, Y, random_fabric=True)
    p = fit_order(W / (np.array(resolutions) - 1.0), steps)
    if abs(p - 1.0) > 0.1:
        raise GradingFailure(f"your stable steps shrink like dx^{p:.2f} under refinement, expected dx^1 "
                             "(omega_max ~ sqrt(k / m) with k fixed and m ~ dx^2)")


def _check_exponent(student, spacing, h, what, tolerance=0.02, hidden=False):
    """The student's exponent against the least-squares slope; a hidden test (`hidden`) does not print the slope."""
    call = f"fit_exponent(spacing, h_max) on {what}"
    got = student.call("fit_exponent", spacing, h, check_inputs=True)
    expected = fit_order(spacing, h)
    got = _number(got, call)
    if not abs(got - expected) <= tolerance:
        message = (f"{call} returned p = {got:.4g}, {abs(got - expected):.3g} away from the least-squares slope "
                   f"(tolerance {tolerance:g})" if hidden else
                   f"{call} returned p = {got:.4g}, expected {expected:.4g}")
        if expected != 0 and abs(got * LN10 / expected - 1) <= 1e-6:
            message += ("; your result is the slope divided by ln(10) = 2.303: log10 of h_max against ln of the "
                        "spacing; use the same logarithm on both axes")
        elif expected != 0 and abs(got / LN10 / expected - 1) <= 1e-6:
            message += ("; your result is the slope times ln(10) = 2.303: ln of h_max against log10 of the spacing; "
                        "use the same logarithm on both axes")
        swapped = np.polyfit(np.log(h), np.log(spacing), 1)[0] if np.ptp(np.log(h)) > 0 else np.inf
        if "; your" in message:
            pass
        elif abs(got - swapped) <= 1e-6 * max(1.0, abs(swapped)) or (expected != 0 and abs(got * expected - 1) <= 1e-6):
            message += ("; your result is the slope of log(spacing) against log(h_max), the axes swapped "
                        "(h_max is the dependent variable: fit log(h_max) = p log(spacing) + c)")
        elif abs(got + expected) <= tolerance and expected != 0:
            message += "; your result has the wrong sign (h_max ~ spacing^p, not 1 / spacing)"
        raise GradingFailure(message)
    return got


@pytest.mark.points(1)
def test_fit_exponent_power_law(student):
    """fit_exponent recovers p = 1.5 from h = 0.3 spacing^1.5 at spacings 0.2, 0.1, 0.05."""
    spacing = np.array([0.2, 0.1, 0.05])
    _check_exponent(student, spacing, 0.3 * spacing**1.5, "h_max = 0.3 spacing^1.5 at spacings [0.2, 0.1, 0.05]")


@pytest.mark.points(2)
@pytest.mark.hidden
def test_fit_exponent_random(student, rng):
    """fit_exponent matches a least-squares fit on noisy power laws with random exponents, p = 0 included."""
    exponents = [0.0, float(rng.uniform(0.2, 0.7)), float(rng.uniform(1.5, 3.0)), float(rng.uniform(-1.5, -0.5))]
    for p in exponents:
        r = int(rng.integers(3, 7))
        spacing = np.sort(rng.uniform(0.01, 0.3, r))[::-1]
        h = float(rng.uniform(1e-4, 1e-1)) * spacing**p * (1.0 + rng.uniform(-0.01, 0.01, r))
        _check_exponent(student, spacing, h, f"{r} noisy points of a random power law h_max ~ spacing^p", hidden=True)


@pytest.mark.points(1)
@pytest.mark.hidden
def test_fit_exponent_library_steps(student, rng):
    """fit_exponent on the library's stable steps of random cloths: p = 1 (physical) and p = 0 (naive)."""
    W = float(rng.uniform(0.5, 1.5))
    rho, Y = _random_fabric(rng)
    n = np.array([8, 12, 16, 24])
    spacing = W / (n - 1.0)
    kwargs = dict(pins="top edge", areal_density=rho, stretch_modulus=Y["structural"], shear_modulus=Y["shear"],
                  flexion_modulus=Y["flexion"])
    for scaling, theory in (("physical", 1.0), ("naive", 0.0)):
        h = np.array([cloth(int(k), int(k), W, W, scaling=scaling, **kwargs).max_stable_step() for k in n])
        p = _check_exponent(student, spacing, h, f"the {scaling} cloth's stable steps at n = 8, 12, 16, 24",
                            hidden=True)
        if abs(p - theory) > 0.1:
            raise GradingFailure(f"fit_exponent gives p = {p:.3f} for the {scaling} cloth, theory says {theory:g}")
