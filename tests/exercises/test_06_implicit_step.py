"""Autograder tests of exercise 06_implicit_step: a spring's Jacobian, the stiffness matrix, Baraff and Witkin's
step, the stiff thread at a hundred times the explicit limit, and the numerical damping against the step.

Public tests use one spring at an angle, a chain of three particles, two particles on one spring and the
notebook's thread and taut string; hidden tests draw springs (stretched and compressed), strings (sizes, shuffled
springs with ends swapped, rest lengths, stiffnesses, masses, pins, velocities) and steps from the grading seed
(fixture ``rng``) and never print them (``show_values=False``).

Every expected value comes from the reference library, computed here in the grader: the springs' forces and
their exact Jacobians (``Springs(...)``, ``jacobians(..., clamp=False)``; the exercise asks for the exact
derivative, compressed springs included), and the step solved from them as lecture 7 writes it,
``(M - h^2 K) dv = h (F + h K v)`` on the free coordinates (the library's ``BaraffWitkin`` with one solve gives
the same step where no spring is compressed; it clamps compressed springs). The Jacobian is also checked against
central finite differences of the library's force (to 1e-6 of its size) and for symmetry, so any correct way of
writing it passes: outer products, components or ``np.einsum``.

Typical mistakes are named from the wrong answers they produce: the Jacobian's sign, its transverse term missing,
``1 - L / L0`` for ``1 - L0 / L``, the compressed spring clamped; the stiffness matrix with off-diagonal blocks of
the wrong sign, coordinates laid out axis by axis (a transposed layout), additions lost at a shared particle; the
step without ``h K v``, with ``h K`` for ``h^2 K``, with the old velocity in the positions, an explicit step, pins
that move; a measurement on the last step only; the damping rate of the amplitude, per step, or of the energy
including the taut string's own.
"""

import numpy as np
import pytest

from particles.course.grading.expect import expect_array, expect_float
from particles.course.grading.memo import memoized
from particles.course.worker.runner import GradingFailure
from particles.forces import Springs

EXERCISE = "06_implicit_step"
_STEP = "it is the implicit step you are asked to write"
_JACOBIAN = "it is the Jacobian you are asked to write"
FORBIDDEN = {
    "particles.implicit.BaraffWitkin": _STEP,
    "particles.implicit.Prefactored": _STEP,
    "particles.integrators.implicit_euler": _STEP,
    "particles.forces.spring_jacobian_blocks": _JACOBIAN,
    "particles.forces.Springs.jacobians": _JACOBIAN,
    "particles.massspring.MassSpringSystem.spring_jacobians": _JACOBIAN,
    "particles.studies.stability.damping_factor": "measure the damping with your own step",
}

G = 9.81
THREAD = dict(n=10, mass=0.01, k=1e4, length=1.0)                      # the notebook's thread, hanging
TAUT = dict(n=9, mass=0.01, k=100.0, length=1.0, span=1.2, pluck=0.01)  # the plucked taut string
TIGHT = 1e-8  # relative agreement of a step with the reference: the same arithmetic up to rounding


# -- references ----------------------------------------------------------------------------------


def _springs(ij, k, L0):
    return Springs(np.asarray(ij), rest_length=np.asarray(L0, dtype=float), k=float(k))


def _forces(x, ij, k, L0):
    return _springs(ij, k, L0)(np.asarray(x, dtype=float))


def _K(x, ij, k, L0):
    """The exact stiffness matrix dF/dx (dense), from the library."""
    x = np.asarray(x, dtype=float)
    return _springs(ij, k, L0).jacobians(x, np.zeros_like(x), clamp=False)[0].toarray()


def _reference_step(x, v, h, m, ij, k, L0, g, free, variant=None):
    """Baraff and Witkin's step (or a typical wrong one, `variant`) from the library's forces and Jacobian."""
    x, v, m = np.asarray(x, dtype=float), np.asarray(v, dtype=float), np.asarray(m, dtype=float)
    n, d = x.shape
    F = _forces(x, ij, k, L0)
    F[:, -1] -= {"no gravity": 0.0, "gravity without masses": g}.get(variant, m * g)
    K = _K(x, ij, k, L0)
    A = np.diag(np.repeat(m, d)) - (h if variant == "h K" else h**2) * K
    b = h * F.ravel() + (0.0 if variant == "no h K v" else h**2 * K @ v.ravel())
    dofs = np.repeat(np.asarray(free, dtype=bool), d) if variant != "pins move" else np.ones(n * d, dtype=bool)
    if variant == "explicit":  # explicit Euler: no stiffness anywhere
        A, b = np.diag(np.repeat(m, d)), h * F.ravel()
    dv = np.zeros(n * d)
    dv[dofs] = np.linalg.solve(A[np.ix_(dofs, dofs)], b[dofs])
    v_new = v + dv.reshape(n, d)
    return (x + h * (v if variant == "old velocity" else v_new)), v_new


def _step_hints(x, v, h, m, ij, k, L0, g, free, part):
    return lambda: {label: _reference_step(x, v, h, m, ij, k, L0, g, free, variant)[part] for label, variant in (
        ("a step without the h K v term: the force is linearized about the end of the step, x + h v_new, so "
         "b = h (F + h K v)", "no h K v"),
        ("a step with M - h K instead of M - h^2 K", "h K"),
        ("a step whose positions use the old velocity, x + h v, instead of the new one, x + h v_new",
         "old velocity"),
        ("an explicit step (the system solved with M alone: the h^2 K term is missing)", "explicit"),
        ("a step that moves the pinned particles (their rows and columns must be left out)", "pins move"),
        ("a step without gravity: F is the springs' forces plus -m g on the last axis", "no gravity"),
        ("a step with gravity without the masses (-g instead of -m g in F, a force in newtons)",
         "gravity without masses"))}


def _thread():
    """The notebook's thread: positions (hanging straight down from particle 0), masses, springs, rest lengths."""
    n = THREAD["n"]
    x = np.zeros((n, 2))
    x[:, 1] = -np.linspace(0.0, THREAD["length"], n)
    ij = np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)
    L0 = np.full(n - 1, THREAD["length"] / (n - 1))
    free = np.ones(n, dtype=bool)
    free[0] = False
    return x, np.full(n, THREAD["mass"]), ij, L0, free


@memoized
def _explicit_limit():
    """2 / omega_max of the thread at rest, from the library's exact stiffness matrix."""
    x, m, ij, L0, free = _thread()
    dofs = np.repeat(free, 2)
    w = 1 / np.sqrt(np.repeat(m, 2)[dofs])
    K = _K(x, ij, THREAD["k"], L0)[np.ix_(dofs, dofs)]
    return 2.0 / np.sqrt(np.linalg.eigvalsh(-w[:, None] * K * w[None, :]).max())


@memoized
def _strains(h, T, kick):
    """The strain of the thread's worst spring after each reference step, from hanging straight with the swing."""
    x, m, ij, L0, free = _thread()
    v = np.zeros_like(x)
    v[:, 0] = kick * (x[0, 1] - x[:, 1])
    worst = []
    for _ in range(round(T / h)):  # a loop over time steps
        x, v = _reference_step(x, v, h, m, ij, THREAD["k"], L0, G, free)
        worst.append(float(np.max(np.linalg.norm(x[ij[:, 0]] - x[ij[:, 1]], axis=1) / L0 - 1.0)))
    return np.array(worst)


def _taut():
    n, a = TAUT["n"], TAUT["span"] / (TAUT["n"] - 1)
    x = np.zeros((n, 2))
    x[:, 0] = a * np.arange(n)
    ij = np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)
    L0 = np.full(n - 1, TAUT["length"] / (n - 1))
    free = np.ones(n, dtype=bool)
    free[[0, n - 1]] = False
    pluck = np.zeros_like(x)
    pluck[:, 1] = TAUT["pluck"] * np.sin(np.pi * np.arange(n) / (n - 1))
    return x, np.full(n, TAUT["mass"]), ij, L0, free, pluck


def _energy(x, v, m, ij, k, L0):
    L = np.linalg.norm(x[ij[:, 0]] - x[ij[:, 1]], axis=1)
    return 0.5 * np.sum(m * np.sum(v**2, axis=1)) + 0.5 * np.sum(k * (L - L0) ** 2)


@memoized
def _energies(h, T):
    """(E_0, E_N, E_rest, N) of the plucked taut string under N = round(T / h) reference steps."""
    x_rest, m, ij, L0, free, pluck = _taut()
    k = TAUT["k"]
    x, v = x_rest + pluck, np.zeros_like(x_rest)
    E0, N = _energy(x, v, m, ij, k, L0), round(T / h)
    for _ in range(N):  # a loop over time steps
        x, v = _reference_step(x, v, h, m, ij, k, L0, 0.0, free)
    return E0, _energy(x, v, m, ij, k, L0), _energy(x_rest, 0 * x_rest, m, ij, k, L0), N


def _rates(hs, T, variant=None):
    """The reference damping rates (or those of a typical wrong measurement)."""
    out = []
    for h in hs:
        E0, EN, E_rest, N = _energies(float(h), float(T))
        if variant == "rest energy kept":
            E_rest = 0.0
        ratio = (EN - E_rest) / (E0 - E_rest)
        rate = -np.log(ratio) / (2 * N * h)
        out.append({None: rate, "amplitude": 2 * rate, "per step": rate * h, "rest energy kept": rate}[variant])
    return np.array(out)


def _rate_hints(hs, T):
    return lambda: {
        "-ln(E_N / E_0) / (N h), without the 1/2: the rate sigma of exp(-2 sigma t) is half the energy's rate":
            _rates(hs, T, "amplitude"),
        "the rate per step, -ln(E_N / E_0) / (2N): divide by the time N h, not by the number of steps":
            _rates(hs, T, "per step"),
        "the rate of the whole energy, E_rest included: subtract the energy of the taut string at rest":
            _rates(hs, T, "rest energy kept"),
    }


# -- spring_jacobian -----------------------------------------------------------------------------


def _jacobian_hints(xi, xj, k, L0):
    d = np.asarray(xi, dtype=float) - np.asarray(xj, dtype=float)
    L = np.linalg.norm(d)
    u = d / L
    uu, P = np.outer(u, u), np.eye(len(u)) - np.outer(u, u)
    clamped = {"-k u u^T, the clamped Jacobian of a compressed spring (max(0, 1 - L0/L) = 0): the exact derivative "
               "keeps the transverse term -k (1 - L0/L)(I - u u^T), here a negative stiffness (clamping is the "
               "solver's choice, question 1)": -k * (uu + max(0.0, 1 - L0 / L) * P)}
    return {
        **(clamped if L < L0 else {}),  # compressed, the clamped Jacobian is -k u u^T: say why
        "+k [u u^T + (1 - L0/L)(I - u u^T)]: the sign is wrong (the force pulls back, dF_i/dx_i = -k [...])":
            k * (uu + (1 - L0 / L) * P),
        "-k u u^T alone: the transverse term -k (1 - L0/L)(I - u u^T) is missing": -k * uu,
        "-k [u u^T + (1 - L/L0)(I - u u^T)]: the factor across the spring is 1 - L0/L, not 1 - L/L0":
            -k * (uu + (1 - L / L0) * P),
        "-k [u u^T + (L0/L)(I - u u^T)]: the factor across the spring is 1 - L0/L": -k * (uu + L0 / L * P),
        **clamped,
    }


def _finite_differences(xi, xj, k, L0, eps=1e-6):
    """dF_i/dx_i by central differences of the library's spring force."""
    def force(p):
        return _forces(np.array([p, xj]), [[0, 1]], k, [L0])[0]
    scale = eps * max(1.0, float(np.abs(xi - xj).max()))
    return np.column_stack([(force(xi + scale * e) - force(xi - scale * e)) / (2 * scale)
                            for e in np.eye(len(xi))])


def _check_jacobian(got, xi, xj, k, L0, call, hidden):
    exact = _K(np.array([xi, xj]), [[0, 1]], k, [L0])[:2, :2]
    expect_array(got, exact, call, rtol=1e-6, atol=1e-9 * k, hints=_jacobian_hints(xi, xj, k, L0),
                 show_values=not hidden)
    fd = _finite_differences(xi, xj, k, L0)
    expect_array(got, fd, f"{call} against finite differences of the force", rtol=1e-5, atol=1e-6 * k,
                 show_values=not hidden)
    if not np.allclose(got, got.T, rtol=1e-12, atol=1e-12 * k):
        raise GradingFailure(f"{call} is not symmetric; dF_i/dx_i of a spring is (it is minus the Hessian of its "
                             "energy)")


@pytest.mark.points(1)
def test_spring_jacobian_at_an_angle(student):
    """spring_jacobian of a spring at an angle, stretched by half: -k [u u^T + (1 - L0/L)(I - u u^T)]."""
    xi, xj = np.array([1.2, 0.9]), np.array([0.0, 0.0])
    got = student.call("spring_jacobian", xi, xj, 10.0, 1.0, check_inputs=True)
    _check_jacobian(got, xi, xj, 10.0, 1.0, "spring_jacobian(xi=[1.2, 0.9], xj=[0, 0], k=10, L0=1)", False)


@pytest.mark.points(1)
def test_spring_jacobian_compressed(student):
    """spring_jacobian of a compressed spring is the exact derivative: a negative stiffness across it."""
    xi, xj = np.array([0.0, 0.0]), np.array([0.3, -0.4])
    got = student.call("spring_jacobian", xi, xj, 20.0, 1.0, check_inputs=True)
    _check_jacobian(got, xi, xj, 20.0, 1.0, "spring_jacobian(xi=[0, 0], xj=[0.3, -0.4], k=20, L0=1) "
                    "(compressed to half its length)", False)


@pytest.mark.points(2)
@pytest.mark.hidden
def test_spring_jacobian_random(student, rng):
    """spring_jacobian matches finite differences and is symmetric on random springs, stretched and compressed."""
    for stretch in (rng.uniform(1.05, 2.0), rng.uniform(0.3, 0.95), rng.uniform(1.05, 2.0)):
        xi, direction = rng.normal(0.0, 2.0, 2), rng.normal(size=2)
        L0, k = rng.uniform(0.1, 3.0), 10 ** rng.uniform(0, 5)
        xj = xi - stretch * L0 * direction / np.linalg.norm(direction)
        kind = "stretched" if stretch > 1 else "compressed"
        got = student.call("spring_jacobian", xi, xj, k, L0, check_inputs=True)
        _check_jacobian(got, xi, xj, k, L0, f"spring_jacobian on a random {kind} spring", True)


# -- stiffness_matrix ----------------------------------------------------------------------------


def _stiffness_hints(x, ij, k, L0):
    def blocks(sign_off=-1.0, lose=False):
        n, d = np.asarray(x).shape
        K = np.zeros((n * d, n * d))
        done = set()
        for s, (i, j) in enumerate(np.asarray(ij)):
            J = _K(np.array([x[i], x[j]]), [[0, 1]], k, [L0[s]])[:2, :2]
            for p, q, sign in ((i, i, 1.0), (j, j, 1.0), (i, j, sign_off), (j, i, sign_off)):
                block = (slice(d * p, d * p + d), slice(d * q, d * q + d))
                if lose and p == q and (p, q) in done:
                    K[block] = sign * J
                else:
                    K[block] += sign * J
                done.add((p, q))
        return K

    def axis_major():
        n, d = np.asarray(x).shape
        order = (np.arange(n)[None, :] * d + np.arange(d)[:, None]).ravel()  # axis a, particle p -> a n + p
        K = _K(x, ij, k, L0)
        return K[np.ix_(order, order)]

    return lambda: {
        "blocks K_ij = +J: the off-diagonal blocks are -J (dF_i/dx_j = -dF_i/dx_i)": blocks(sign_off=1.0),
        "the coordinates laid out axis by axis (entry a n + p): the layout is particle by particle, 2 p + a, "
        "as x.ravel()": axis_major(),
        "a diagonal block overwritten where two springs share a particle: add their contributions (+=)":
            blocks(lose=True),
    }


def _check_stiffness(got, x, ij, k, L0, call, hidden):
    expect_array(got, _K(x, ij, k, L0), call, rtol=1e-9, atol=1e-9 * k, hints=_stiffness_hints(x, ij, k, L0),
                 show_values=not hidden)


@pytest.mark.points(2)
def test_stiffness_matrix_three_particles(student):
    """stiffness_matrix of a bent chain of three particles: each spring's four blocks, added at the shared one."""
    x = np.array([[0.0, 0.0], [1.2, 0.5], [1.5, 1.6]])
    ij, L0 = np.array([[0, 1], [1, 2]]), np.array([1.0, 1.0])
    got = student.call("stiffness_matrix", x, ij, 50.0, L0, check_inputs=True)
    _check_stiffness(got, x, ij, 50.0, L0, "stiffness_matrix of the chain (0, 0) - (1.2, 0.5) - (1.5, 1.6), "
                     "k=50, L0=1", False)


def _random_string(rng, n=None):
    """A random bent string: positions, masses, springs (shuffled, ends swapped), rest lengths, stiffness, pins."""
    n = int(rng.integers(3, 12)) if n is None else n
    steps = rng.normal(0.0, 1.0, (n - 1, 2))
    lengths = rng.uniform(0.2, 0.6, n - 1)
    x = np.concatenate([[[0.0, 0.0]], np.cumsum(lengths[:, None] * steps / np.linalg.norm(steps, axis=1)[:, None],
                                                axis=0)])
    ij = np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)
    L0 = lengths / rng.uniform(0.8, 1.3, n - 1)          # some springs stretched, some compressed
    order = rng.permutation(n - 1)
    ij, L0 = ij[order], L0[order]
    swap = rng.random(n - 1) < 0.5
    ij[swap] = ij[swap][:, ::-1]
    free = rng.random(n) < 0.8
    free[int(rng.integers(n))] = False
    return x, rng.uniform(0.005, 0.05, n), ij, L0, 10 ** rng.uniform(1, 4), free


@pytest.mark.points(2)
@pytest.mark.hidden
def test_stiffness_matrix_random(student, rng):
    """stiffness_matrix matches the library's exact Jacobian on random strings (shuffled springs, ends swapped)."""
    for _ in range(2):
        x, _, ij, L0, k, _ = _random_string(rng)
        got = student.call("stiffness_matrix", x, ij, k, L0, check_inputs=True)
        _check_stiffness(got, x, ij, k, L0, f"stiffness_matrix of a random string of {len(x)} particles", True)


# -- implicit_step -------------------------------------------------------------------------------


def _check_step(student, x, v, h, m, ij, k, L0, g, free, call, hidden):
    got = student.call("implicit_step", x, v, h, m, ij, k, L0, g, free, check_inputs=True)
    if not isinstance(got, tuple) or len(got) != 2:
        raise GradingFailure(f"{call} returned {type(got).__name__}, expected the pair (x_new, v_new)")
    x_ref, v_ref = _reference_step(x, v, h, m, ij, k, L0, g, free)
    for part, (value, expected, name) in enumerate(((got[0], x_ref, "x_new"), (got[1], v_ref, "v_new"))):
        if isinstance(value, np.ndarray) and value.shape == x.shape and part == 0:
            moved = np.flatnonzero(~free & np.any(value != x, axis=1))
            if len(moved):
                raise GradingFailure(f"{call} moved pinned particle {int(moved[0])}; a pinned particle keeps its "
                                     "position and a zero velocity: leave its rows and columns out of the system")
        expect_array(value, expected, f"{name} of {call}", rtol=TIGHT, atol=TIGHT * np.abs(expected).max(),
                     hints=_step_hints(x, v, h, m, ij, k, L0, g, free, part), show_values=not hidden)


@pytest.mark.points(2)
def test_implicit_step_one_spring(student):
    """implicit_step of a particle hanging on one spring from a pinned one, at a large step, with gravity."""
    x, v = np.array([[0.0, 0.0], [0.3, -1.1]]), np.array([[0.0, 0.0], [0.5, 0.2]])
    _check_step(student, x, v, 0.1, np.array([1.0, 0.2]), np.array([[0, 1]]), 100.0, np.array([1.0]), G,
                np.array([False, True]), "implicit_step(x=[[0, 0], [0.3, -1.1]], v=[[0, 0], [0.5, 0.2]], h=0.1, "
                "m=[1, 0.2], k=100, L0=1, g=9.81, particle 0 pinned)", False)


@pytest.mark.points(3)
@pytest.mark.hidden
def test_implicit_step_random(student, rng):
    """implicit_step matches Baraff and Witkin's step on random strings, pins, velocities and steps up to 0.1 s."""
    for h in (10 ** rng.uniform(-4, -2), 10 ** rng.uniform(-2, -1)):
        x, m, ij, L0, k, free = _random_string(rng)
        v = rng.normal(0.0, 1.0, x.shape) * free[:, None]
        _check_step(student, x, v, h, m, ij, k, L0, G * rng.uniform(0.0, 2.0), free,
                    f"implicit_step on a random string of {len(x)} particles ({int((~free).sum())} pinned)", True)


# -- largest_strain ------------------------------------------------------------------------------


def _check_strain(student, h, T, kick, call, hidden):
    got = student.call("largest_strain", h, T, kick)
    strains = _strains(h, T, kick)
    expect_float(got, strains.max(), call, rtol=1e-6, atol=1e-12, show_values=not hidden, hints={
        "the strain after the last step only: return the largest over all the steps": strains[-1],
        "the strain of the first step only: keep the largest over all the steps": strains[0]})


@pytest.mark.points(2)
def test_largest_strain_at_a_hundred_times_the_limit(student):
    """largest_strain of the notebook's thread over 3 s at 100 times the explicit limit: stable, as the reference."""
    h = 100 * _explicit_limit()
    _check_strain(student, h, 3.0, 0.5, "largest_strain(h=100 h_explicit, T=3, kick=0.5)", False)


@pytest.mark.points(2)
@pytest.mark.hidden
def test_largest_strain_random(student, rng):
    """largest_strain matches the reference run at a random multiple of the explicit limit, duration and swing."""
    h = rng.uniform(20.0, 200.0) * _explicit_limit()
    _check_strain(student, h, rng.uniform(1.0, 3.0), rng.uniform(0.2, 1.0),
                  "largest_strain of the thread at a random step, duration and swing", True)


# -- damping_rates -------------------------------------------------------------------------------


def _check_rates(student, feedback, hs, T, call, hidden):
    got = student.call("damping_rates", hs, T, check_inputs=True)
    expected = _rates(hs, T)
    if isinstance(got, np.ndarray) and got.shape == expected.shape:
        feedback.curve("Energy decay rate of the plucked string against the step", "time step h (s)",
                       "sigma (1/s)", [{"label": "yours", "x": hs, "y": got},
                                       {"label": "reference", "x": hs, "y": expected}], loglog=True)
    expect_array(got, expected, call, rtol=1e-6, hints=_rate_hints(hs, T), show_values=not hidden)


@pytest.mark.points(1)
def test_damping_rates_public(student, feedback):
    """damping_rates at h = 5 ms, 20 ms and 0.1 s over 0.5 s: the reference's energy decay rates."""
    _check_rates(student, feedback, np.array([0.005, 0.02, 0.1]), 0.5, "damping_rates(hs=[0.005, 0.02, 0.1], T=0.5)",
                 False)


@pytest.mark.points(2)
@pytest.mark.hidden
def test_damping_rates_random(student, rng, feedback):
    """damping_rates at random steps and duration: the reference's rates, growing like h at small steps.

    T stays below 0.8 s, where the vibration keeps more than 1e-5 of its energy: two correct programs then
    agree on the rate to about 1e-8 (measured with rounding-sized noise on every step); over 2 s, E_N - E_rest
    is down to rounding and they differ by up to 3e-2 at h = 0.1 s, far beyond rtol = 1e-6.
    """
    hs = np.sort(10 ** rng.uniform(np.log10(0.004), np.log10(0.2), 4))
    _check_rates(student, feedback, hs, float(rng.uniform(0.3, 0.8)), "damping_rates at random steps", True)
