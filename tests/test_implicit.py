"""Implicit mass-spring integration: stability at large steps, dissipation, convergence, pins."""

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


def test_symplectic_euler_needs_tiny_steps_on_the_stiff_cloth():
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
    """With its nonlinear equations solved (2 Newton iterations), no step gains energy."""
    c = cloth(12, 12, k_structural=5000.0, k_shear=1250.0, k_flexion=500.0, plane="horizontal")
    t, X = c.run(2.0, 1 / 30, method=BaraffWitkin(c, linear_solver="direct", newton_iterations=2))
    E = np.array([energy(c, Xk) for Xk in X])
    assert np.all(np.diff(E) <= 1e-9 * np.abs(E).max())
    assert E[-1] < E[0] - 1.0  # it falls and dissipates


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
    c1, c2 = stiff_cloth(), stiff_cloth()
    cg = BaraffWitkin(c1, tol=1e-12, maxiter=5000)
    direct = BaraffWitkin(c2, linear_solver="direct")
    c1.run(0.2, 1 / 30, method=cg)
    c2.run(0.2, 1 / 30, method=direct)
    np.testing.assert_allclose(c1.X, c2.X, atol=1e-8)
    assert len(cg.iterations) == 6 and min(cg.iterations) > 5 and cg.converged
    capped = BaraffWitkin(stiff_cloth(), maxiter=3)
    with pytest.raises(ConvergenceError, match="did not reach the relative residual tol = 1e-06 within maxiter = 3"):
        capped(None, capped.system.X, 0.0, 1 / 30)
    assert capped.iterations == [3] and not capped.converged


def test_prefactored_refactorizes_for_a_new_step():
    c = small_cloth()
    solver = Prefactored(c, 0.01)
    solver(None, c.X, 0.0, 0.02)
    assert solver.h == 0.02


def test_relax_finds_rest_and_rejects_bad_method():
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
    c = small_cloth()
    with pytest.raises(ValueError, match="system must be a MassSpringSystem"):
        BaraffWitkin(object())
    with pytest.raises(ValueError, match=r"X must have the shape of the system's state \(25, 2, 3\)"):
        BaraffWitkin(c)(None, np.zeros((3, 2, 3)), 0.0, 0.01)
    with pytest.raises(ValueError, match="iterations must be a positive integer"):
        Prefactored(c, 0.01, iterations=0)
    with pytest.raises(ValueError, match="linear_solver must be 'cg' or 'direct'"):
        BaraffWitkin(c, linear_solver="lu")


@pytest.mark.parametrize("options, message", [
    ({"maxiter": 0}, "maxiter must be an integer >= 1, got 0"),
    ({"maxiter": 2.5}, "maxiter must be an integer >= 1, got 2.5"),
    ({"newton_iterations": 0}, "newton_iterations must be an integer >= 1, got 0"),
])
def test_baraff_witkin_rejects_bad_counts(options, message):
    """Iteration caps must be positive integers, named in the error."""
    with pytest.raises(ValueError, match=message):
        BaraffWitkin(small_cloth(), **options)


def test_relax_returns_at_once_from_an_equilibrium():
    """Relaxing a system that is already at rest in equilibrium takes no step (no ConvergenceError)."""
    s = string(10, 1.0)
    relax(s)
    x = s.X[:, 0].copy()
    assert relax(s) == 0
    np.testing.assert_array_equal(s.X[:, 0], x)
