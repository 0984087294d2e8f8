"""Implicit mass-spring integration: stability at large steps, dissipation, convergence, pins.

The acceptance cases of issue 13 use the README's "stiff" cloth: 1 m square, 0.2 kg/m^2,
stretch modulus 5000 N/m under physical scaling, falling from flat at h = 1/30 s.
"""

import numpy as np
import pytest

from particles import ConvergenceError, SimulationDiverged
from particles.implicit import BaraffWitkin, Prefactored, relax
from particles.integrators import rk4
from particles.massspring import cloth, string


def stiff_cloth(**options):
    """A cloth stiff enough that symplectic Euler needs h < 1e-3 s."""
    return cloth(16, 16, k_structural=5000.0, k_shear=1250.0, k_flexion=500.0, **options)


def energy(c, X):
    return c.kinetic_energy(X) + c.potential_energy(X)


def readme_cloth(n, **options):
    """The README's stiff cloth (5000 N/m, physical scaling), n x n, lying flat, held by its top corners."""
    return cloth(n, n, scaling="physical", areal_density=0.2, stretch_modulus=5000.0, plane="horizontal", **options)


def largest_rise(E):
    """The largest energy gain over any stretch of a run, max over k of E[k] - min(E[:k + 1])."""
    E = np.asarray(E)
    return float(np.max(E - np.minimum.accumulate(E)))


def test_symplectic_euler_needs_tiny_steps_on_the_stiff_cloth():
    """Symplectic Euler blows up at h = 1 ms on the stiff cloth and needs h < 0.5 ms."""
    with pytest.raises(SimulationDiverged):
        stiff_cloth().run(0.5, 1e-3, method="symplectic_euler")
    c = stiff_cloth()
    c.run(0.1, 4e-4, method="symplectic_euler")
    assert c.max_strain() < 0.05


@pytest.mark.parametrize("make", [lambda c: BaraffWitkin(c), lambda c: Prefactored(c, 1 / 30)],
                         ids=["baraff_witkin", "prefactored"])
def test_implicit_stable_at_one_thirtieth(make):
    """h = 1/30 s, 33 times the explicit limit: finite, bounded, hanging below its pins."""
    c = stiff_cloth(plane="horizontal")
    t, X = c.run(2.0, 1 / 30, method=make(c))
    assert np.all(np.isfinite(X))
    assert max(c.max_strain(Xk) for Xk in X) < 0.1
    assert c.X[:, 0, 2].mean() < -0.3
    np.testing.assert_array_equal(X[:, c.pinned, 0], np.broadcast_to(X[0, c.pinned, 0], X[:, c.pinned, 0].shape))


def test_backward_euler_energy_non_increasing_at_large_h():
    """With its defaults (a Newton iteration after the paper's step, the energy check) no step gains energy."""
    c = cloth(12, 12, k_structural=5000.0, k_shear=1250.0, k_flexion=500.0, plane="horizontal")
    t, X = c.run(2.0, 1 / 30, method=BaraffWitkin(c))
    E = np.array([energy(c, Xk) for Xk in X])
    assert np.all(np.diff(E) <= 1e-9 * np.abs(E).max())
    assert E[-1] < E[0] - 1.0  # it falls and dissipates


SLOW = pytest.mark.slow  # 64^2, three steps: 1.5 to 5 s per solver, depending on the load
SIZES = [pytest.param(16, 0.5, 1 / 30, id="16-h30"), pytest.param(32, 0.2, 1 / 30, id="32-h30"),
         pytest.param(64, 0.1, 1 / 30, id="64-h30", marks=SLOW), pytest.param(16, 0.5, 1 / 60, id="16-h60"),
         pytest.param(64, 0.05, 1 / 60, id="64-h60", marks=SLOW)]
SOLVERS = [pytest.param(lambda c, h: BaraffWitkin(c), id="baraff_witkin"),
           pytest.param(lambda c, h: Prefactored(c, h), id="prefactored")]


@pytest.mark.parametrize("make", SOLVERS)
@pytest.mark.parametrize("n, T, h", SIZES)
def test_readme_stiff_cloth_with_defaults(make, n, T, h):
    """Issue 13: both solvers step the 5000 N/m cloth with defaults, gain < 1% of M g H, stretch < 10%."""
    c = readme_cloth(n)
    t, X = c.run(T, h, method=make(c, h))
    E = [energy(c, Xk) for Xk in X]
    M_g_H = c.m.sum() * 9.81 * 1.0  # the cloth is 1 m high
    assert largest_rise(E) <= 0.01 * M_g_H
    assert max(c.max_strain(Xk) for Xk in X) < 0.10
    assert E[-1] < E[0]  # it fell


def test_one_linearized_solve_gains_energy_and_the_check_prevents_it():
    """The paper's single solve gains > 5% of M g H on the falling cloth; the energy check adds solves until none does."""
    h = 1 / 30
    runs = {}
    for check in (False, True):
        c = readme_cloth(16)
        solver = BaraffWitkin(c, newton_iterations=1, energy_check=check, linear_solver="direct")
        t, X = c.run(1.0, h, method=solver)
        runs[check] = ([energy(c, Xk) for Xk in X], max(c.max_strain(Xk) for Xk in X), solver.newton)
    M_g_H = c.m.sum() * 9.81
    assert largest_rise(runs[False][0]) > 0.05 * M_g_H and runs[False][1] > 0.05
    assert largest_rise(runs[True][0]) <= 1e-9 * M_g_H and runs[True][1] < 0.025
    assert set(runs[False][2]) == {1} and 1 < max(runs[True][2]) <= 10


def test_energy_check_raises_when_iterations_run_out():
    """A step that still gains energy after max_newton_iterations raises ConvergenceError instead of being taken."""
    c = readme_cloth(16)
    solver = BaraffWitkin(c, newton_iterations=1, max_newton_iterations=1, linear_solver="direct")
    with pytest.raises(ConvergenceError, match="still gains .* J after max_newton_iterations = 1"):
        c.run(1.0, 1 / 30, method=solver)


def test_auto_solver_falls_back_to_the_factorization_once_cg_stalls():
    """The default solver: block-Jacobi CG until a solve needs 100 iterations, then the factorization; same steps."""
    h = 1 / 30
    stiff, reference = readme_cloth(16), readme_cloth(16)
    auto = BaraffWitkin(stiff)
    stiff.run(0.2, h, method=auto)
    reference.run(0.2, h, method=BaraffWitkin(reference, linear_solver="direct"))
    assert BaraffWitkin.AUTO_CG_ITERATIONS in auto.iterations and auto.direct_solves > 0
    assert auto.iterations[auto.iterations.index(100) + 1:] == [0] * (auto.direct_solves - 1)  # factorized from then on
    np.testing.assert_allclose(stiff.X, reference.X, atol=1e-6)
    soft = small_cloth()
    solver = BaraffWitkin(soft)
    soft.run(0.2, 0.01, method=solver)
    assert solver.direct_solves == 0 and max(solver.iterations) < 100


def test_block_jacobi_cg_converges_on_the_stiff_cloth():
    """Conjugate gradients with the 3 x 3 block-Jacobi preconditioner solve the 16^2 cloth's steps in < 300 iterations."""
    c = readme_cloth(16)
    solver = BaraffWitkin(c, linear_solver="cg", maxiter=1000)
    c.run(0.5, 1 / 30, method=solver)
    assert solver.converged and solver.direct_solves == 0 and max(solver.iterations) < 300


def test_prefactored_damps_like_implicit_euler():
    """With the residual rule the prefactorized cloth falls like backward Euler; 10 fixed iterations hold it back."""
    h, centre = 1 / 30, readme_cloth(16).points["center"]
    drops = {}
    for name, make in (("implicit Euler", lambda c: BaraffWitkin(c, linear_solver="direct", newton_iterations=4)),
                       ("residual", lambda c: Prefactored(c, h)), ("10 iterations", lambda c: Prefactored(c, h, iterations=10))):
        c = readme_cloth(16)
        c.run(0.5, h, method=make(c))
        drops[name] = -c.X[centre, 0, 2]
    assert drops["residual"] == pytest.approx(drops["implicit Euler"], rel=0.02)
    assert drops["10 iterations"] < 0.5 * drops["implicit Euler"]


def test_prefactored_settles_at_the_static_equilibrium():
    """A hanging stiff curtain run with the residual rule rests at relax()'s strain; 10 fixed iterations stop short."""
    rest = cloth(16, 16, scaling="physical", areal_density=0.2, stretch_modulus=5000.0)
    relax(rest, h=0.2)
    strains = {}
    for iterations in (None, 10):
        c = cloth(16, 16, scaling="physical", areal_density=0.2, stretch_modulus=5000.0)
        c.run(1.0, 1 / 30, method=Prefactored(c, 1 / 30, iterations=iterations))
        strains[iterations] = c.max_strain()
    assert strains[None] == pytest.approx(rest.max_strain(), rel=0.01)
    assert strains[10] > 2 * rest.max_strain()


def test_prefactored_reports_a_residual_it_cannot_reach():
    """A step whose residual does not reach tol within max_iterations raises ConvergenceError."""
    c = readme_cloth(16)
    solver = Prefactored(c, 1 / 30, max_iterations=5)
    with pytest.raises(ConvergenceError, match="did not reach tol = 0.1 within max_iterations = 5"):
        solver(None, c.X, 0.0, 1 / 30)
    assert solver.counts == [5]


@pytest.mark.parametrize("make", [lambda c: BaraffWitkin(c, tol=1e-10), lambda c: Prefactored(c, 1 / 30, iterations=50)],
                         ids=["baraff_witkin", "prefactored"])
def test_energy_non_increasing_stretched_release(make):
    """A stretched cloth released without gravity: the elastic energy only decays."""
    c = cloth(12, 12, gravity=0.0, k_structural=5000.0, k_shear=1250.0, k_flexion=500.0)
    X0 = c.state()
    X0[:, 0] *= 1.3
    X0[c.pinned, 0] = c.X[c.pinned, 0]
    c.X = np.asfortranarray(X0)
    t, X = c.run(2.0, 1 / 30, method=make(c))
    E = np.array([energy(c, Xk) for Xk in X])
    assert np.all(np.diff(E) <= 1e-9 * E[0])
    assert E[-1] < 0.5 * E[0]


def test_prefactored_never_gains_energy_overall():
    """Few local/global iterations: single steps may wobble, the energy never exceeds its start."""
    c = stiff_cloth(plane="horizontal")
    t, X = c.run(2.0, 1 / 30, method=Prefactored(c, 1 / 30, iterations=10))
    E = np.array([energy(c, Xk) for Xk in X])
    assert E.max() <= E[0] + 1e-9 and E[-1] < E[0] - 1.0


def small_cloth():
    return cloth(5, 5, width=0.4, height=0.4, mass=0.01, k_structural=20.0, k_shear=5.0, k_flexion=2.0,
                 plane="horizontal")


@pytest.fixture(scope="module")
def explicit_reference():
    """The small cloth at T = 0.15 s by RK4 with a tiny step."""
    ref = small_cloth()
    ref.run(0.15, 2e-4, method=rk4, every=10_000)
    return ref.X[:, 0]


@pytest.mark.parametrize("make", [lambda c, h: BaraffWitkin(c, linear_solver="direct"),
                                  lambda c, h: Prefactored(c, h, iterations=60)],
                         ids=["baraff_witkin", "prefactored"])
def test_implicit_converges_to_explicit_solution(make, explicit_reference):
    """As h -> 0 the implicit solution approaches a fine RK4 solution, at first order."""
    errors = []
    for h in (0.004, 0.002, 0.001):
        c = small_cloth()
        c.run(0.15, h, method=make(c, h))
        errors.append(np.abs(c.X[:, 0] - explicit_reference).max())
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all(ratios > 1.6) and np.all(ratios < 2.6), (errors, ratios)


def test_cg_and_direct_solvers_agree_and_iterations_are_reported():
    """CG and the factorization give the same steps; CG's iterations are recorded, its cap raises ConvergenceError."""
    c1, c2 = stiff_cloth(), stiff_cloth()
    cg = BaraffWitkin(c1, tol=1e-12, maxiter=5000, linear_solver="cg")
    direct = BaraffWitkin(c2, linear_solver="direct")
    c1.run(0.2, 1 / 30, method=cg)
    c2.run(0.2, 1 / 30, method=direct)
    np.testing.assert_allclose(c1.X, c2.X, atol=1e-8)
    assert len(cg.iterations) == sum(cg.newton) and cg.newton == direct.newton and min(cg.iterations) > 5
    assert cg.converged and cg.direct_solves == 0 and direct.direct_solves == sum(direct.newton)
    capped = BaraffWitkin(stiff_cloth(), maxiter=3, linear_solver="cg")
    with pytest.raises(ConvergenceError, match="did not reach the relative residual tol = 1e-06 within maxiter = 3"):
        capped(None, capped.system.X, 0.0, 1 / 30)
    assert capped.iterations == [3] and not capped.converged


def test_prefactored_refactorizes_for_a_new_step():
    """Called with another h, the prefactorized solver builds and factorizes M + h^2 L again."""
    c = small_cloth()
    solver = Prefactored(c, 0.01)
    solver(None, c.X, 0.0, 0.02)
    assert solver.h == 0.02


@pytest.mark.parametrize("pin", ["top", "both"])
def test_relax_converges_on_a_stiff_chain_with_its_defaults(pin):
    """Issue 13: an 81-node chain with EA = 1e5 N relaxes with the default tol (each node's weight sets it)."""
    s = string(81, 1.0, pin=pin, span=0.8 if pin == "both" else None, scaling="physical", linear_density=0.2,
               stretch_modulus=1e5)
    relax(s)
    tension = s.springs["structural"].k * (s.springs["structural"].lengths(s.X[:, 0]) - 1.0 / 80)
    free = np.setdiff1d(np.arange(s.n), s.pinned)
    assert np.abs(s.total_force(s.X, 0.0)[free]).max() <= 1e-8 * tension.max()
    np.testing.assert_allclose(s.reaction_forces().sum(axis=0), [0.0, 0.2 * 9.81], rtol=1e-7, atol=1e-8)
    if pin == "top":  # each spring carries the weight below it
        below = s.m[::-1].cumsum()[::-1][1:] * 9.81
        np.testing.assert_allclose(tension, below, rtol=1e-6)


def test_relax_finds_rest_and_rejects_bad_method():
    """relax() brings a pinned cloth to rest (net forces ~ 0) and names the allowed methods otherwise."""
    c = cloth(6, 6, pins="top edge", scaling="physical")
    relax(c)
    F = c.total_force(c.X, 0.0)
    free = np.setdiff1d(np.arange(c.n), c.pinned)
    assert np.abs(F[free]).max() < 1e-8 * c.m.max() * 9.81 * 10
    with pytest.raises(ValueError, match="method must be 'auto', 'implicit' or 'newton'"):
        relax(c, method="euler")


def test_relax_newton_finds_a_large_droop():
    """Newton relaxation settles a soft hair with stiff segments that droops far beyond linear beam theory."""
    from particles.massspring import hair

    mu, L, EI = 0.05, 0.3, 0.002
    h = hair(6, L, scaling="physical", linear_density=mu, stretch_modulus=1e3, bending_modulus=EI)
    relax(h, method="newton")
    F = h.total_force(h.X, 0.0)
    assert np.abs(F[2:]).max() < 1e-9  # the free particles are at rest
    droop = -h.X[-1, 0, 1]
    assert 0.2 * L < droop < mu * 9.81 * L**4 / (8 * EI)  # large, and below the linear prediction
    assert np.linalg.norm(h.X[-1, 0] - h.X[0, 0]) <= L * 1.001  # the hair does not get longer


def test_implicit_steppers_check_their_input():
    """Wrong systems, states and options raise ValueError naming the argument."""
    c = small_cloth()
    with pytest.raises(ValueError, match="system must be a MassSpringSystem"):
        BaraffWitkin(object())
    with pytest.raises(ValueError, match=r"X must have the shape of the system's state \(25, 2, 3\)"):
        BaraffWitkin(c).step(np.zeros((3, 2, 3)), 0.0, 0.01)
    with pytest.raises(ValueError, match="iterations must be a positive integer or None"):
        Prefactored(c, 0.01, iterations=0)
    with pytest.raises(ValueError, match="linear_solver must be 'auto', 'cg' or 'direct'"):
        BaraffWitkin(c, linear_solver="lu")


@pytest.mark.parametrize("options, message", [
    ({"maxiter": 0}, "maxiter must be an integer >= 1, got 0"),
    ({"maxiter": 2.5}, "maxiter must be an integer >= 1, got 2.5"),
    ({"newton_iterations": 0}, "newton_iterations must be an integer >= 1, got 0"),
    ({"max_newton_iterations": 0}, "max_newton_iterations must be an integer >= 1, got 0"),
    ({"tol": 0.0}, "tol must be"),
])
def test_baraff_witkin_rejects_bad_counts(options, message):
    """Iteration caps must be positive integers, named in the error."""
    with pytest.raises(ValueError, match=message):
        BaraffWitkin(small_cloth(), **options)


@pytest.mark.parametrize("options, message", [
    ({"max_iterations": 0}, "max_iterations must be an integer >= 1, got 0"),
    ({"anderson": -1}, "anderson must be an integer >= 0, got -1"),
    ({"tol": -1.0}, "tol must be"),
])
def test_prefactored_rejects_bad_options(options, message):
    """The residual rule's options are checked and named in the error."""
    with pytest.raises(ValueError, match=message):
        Prefactored(small_cloth(), 0.01, **options)


def test_relax_returns_at_once_from_an_equilibrium():
    """Relaxing a system that is already at rest in equilibrium takes no step (no ConvergenceError)."""
    s = string(10, 1.0)
    relax(s)
    x = s.X[:, 0].copy()
    assert relax(s) == 0
    np.testing.assert_array_equal(s.X[:, 0], x)


# -- implicit_euler without a Jacobian: inexact Newton-GMRES --------------------


def heat_equation(N=300):
    """f(X) = X'' on (0, 1), X = 0 at both ends, N interior points; returns f, a start X and the matrix."""
    import scipy.sparse

    dx = 1.0 / (N + 1)
    calls = []

    def f(X, t):
        calls.append(1)
        Xp = np.concatenate([[0.0], X, [0.0]])
        return (Xp[2:] - 2 * Xp[1:-1] + Xp[:-2]) / dx**2

    x = np.linspace(dx, 1 - dx, N)
    L = scipy.sparse.diags([np.ones(N - 1), -2 * np.ones(N), np.ones(N - 1)], [-1, 0, 1]) / dx**2
    return f, np.sin(np.pi * x) + 0.3 * np.sin(7 * np.pi * x), L.tocsc(), calls


@pytest.mark.parametrize("h", [1e-4, 1e-3, 1e-2])
def test_matrix_free_implicit_euler_costs_less_than_a_dense_jacobian(h):
    """Issue 13: on a 300-unknown heat equation a step costs fewer evaluations of f than 2 dense FD Jacobians (602)."""
    import scipy.sparse
    import scipy.sparse.linalg

    from particles.integrators import implicit_euler

    f, X, L, calls = heat_equation()
    Y = implicit_euler(f, X, 0.0, h)
    exact = scipy.sparse.linalg.spsolve(scipy.sparse.identity(len(X), format="csc") - h * L, X)
    np.testing.assert_allclose(Y, exact, rtol=0, atol=1e-10)
    assert len(calls) < 602


def test_matrix_free_implicit_euler_reports_a_gmres_failure():
    """GMRES that cannot reduce the linear residual (a large cyclic shift) raises ConvergenceError; jac= solves it."""
    from particles.integrators import implicit_euler

    X = np.zeros(300)
    X[0] = 1.0
    f = lambda X, t: 1e3 * np.roll(X, 1)  # noqa: E731
    with pytest.raises(ConvergenceError, match=r"GMRES did not reach .* no usable Newton step.*Pass the Jacobian"):
        implicit_euler(f, X, 0.0, 1.0)
    P = np.roll(np.eye(300), 1, axis=0)
    Y = implicit_euler(f, X, 0.0, 1.0, jac=lambda X, t: 1e3 * P)
    np.testing.assert_allclose(Y - 1e3 * np.roll(Y, 1), X, atol=1e-9)


def test_solvers_leave_a_system_at_rest_without_forces_at_rest():
    """A gravity-free cloth at its rest shape: both solvers return it unchanged, without iterating to a cap."""
    for make in (lambda c: BaraffWitkin(c), lambda c: Prefactored(c, 1 / 30)):
        c = cloth(8, 8, gravity=0.0, k_structural=5000.0)
        solver = make(c)
        X = solver(None, c.X, 0.0, 1 / 30)
        np.testing.assert_allclose(X, c.X, atol=1e-12)
    assert solver.counts == [0]


@pytest.mark.parametrize("make", [lambda c: BaraffWitkin(c, linear_solver="direct"), lambda c: Prefactored(c, 0.02)],
                         ids=["baraff_witkin", "prefactored"])
def test_solvers_say_what_they_use(make):
    """A solver's step is step(X, t, h) (no f: it uses its system); the old form solver(f, X, t, h) is the same."""
    import inspect

    c = small_cloth()
    solver = make(c)
    assert list(inspect.signature(solver.step).parameters) == ["X", "t", "h"] and solver.order == 1
    X = c.state()
    X.setflags(write=False)
    new = solver.step(X, 0.0, 0.02)
    np.testing.assert_array_equal(make(c)(None, X, 0.0, 0.02), new)  # the stepper form, f unused
    t, Y = c.run(0.02, 0.02, method=make(c))
    np.testing.assert_array_equal(Y[-1], new)
    doc = inspect.getdoc(type(solver).step) + inspect.getdoc(type(solver))
    assert ("A = M - h D - h^2 K" in doc) if isinstance(solver, BaraffWitkin) else ("M + h^2 L" in doc)
