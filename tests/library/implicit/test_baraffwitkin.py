"""Backward Euler after Baraff and Witkin (particles.implicit.baraffwitkin): energy check, CG, options."""

import numpy as np
import pytest

from particles import ConvergenceError
from particles.implicit import BaraffWitkin
from particles.massspring import cloth

from .helpers import energy, largest_rise, readme_cloth, small_cloth, stiff_naive_cloth


def test_backward_euler_energy_non_increasing_at_large_h():
    """With its defaults (a Newton iteration after the paper's step, the energy check) no step gains energy."""
    c = cloth(12, 12, k_structural=5000.0, k_shear=1250.0, k_flexion=500.0, plane="horizontal")
    t, X = c.run(2.0, 1 / 30, method=BaraffWitkin(c))
    E = np.array([energy(c, Xk) for Xk in X])
    assert np.all(np.diff(E) <= 1e-9 * np.abs(E).max())
    assert E[-1] < E[0] - 1.0  # it falls and dissipates


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


def test_cg_and_direct_solvers_agree_and_iterations_are_reported():
    """CG and the factorization give the same steps; CG's iterations are recorded, its cap raises ConvergenceError."""
    c1, c2 = stiff_naive_cloth(), stiff_naive_cloth()
    cg = BaraffWitkin(c1, tol=1e-12, maxiter=5000, linear_solver="cg")
    direct = BaraffWitkin(c2, linear_solver="direct")
    c1.run(0.2, 1 / 30, method=cg)
    c2.run(0.2, 1 / 30, method=direct)
    np.testing.assert_allclose(c1.X, c2.X, atol=1e-8)
    assert len(cg.iterations) == sum(cg.newton) and cg.newton == direct.newton and min(cg.iterations) > 5
    assert cg.converged and cg.direct_solves == 0 and direct.direct_solves == sum(direct.newton)
    capped = BaraffWitkin(stiff_naive_cloth(), maxiter=3, linear_solver="cg")
    with pytest.raises(ConvergenceError, match="did not reach the relative residual tol = 1e-06 within maxiter = 3"):
        capped(None, capped.system.X, 0.0, 1 / 30)
    assert capped.iterations == [3] and not capped.converged


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
