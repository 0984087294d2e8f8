"""What both implicit solvers (BaraffWitkin, Prefactored) promise: issue 13's acceptance cases.

The acceptance cases use the README's "stiff" cloth: 1 m square, 0.2 kg/m^2,
stretch modulus 5000 N/m under physical scaling, falling from flat at h = 1/30 s,
where symplectic Euler needs h < 0.5 ms. Each test runs both solvers: stable at
large steps, no energy gained, first order as h -> 0, at rest stays at rest, and
the solver form ``solver.step(X, t, h)`` with its input checks
(:class:`particles.implicit.sparse.SpringSolver`).
"""

import numpy as np
import pytest

from particles import SimulationDiverged
from particles.implicit import BaraffWitkin, Prefactored
from particles.integrators import rk4
from particles.massspring import cloth

from .helpers import energy, largest_rise, readme_cloth, small_cloth, stiff_naive_cloth


def test_symplectic_euler_needs_tiny_steps_on_the_stiff_cloth():
    """Symplectic Euler blows up at h = 1 ms on the stiff cloth and needs h < 0.5 ms."""
    with pytest.raises(SimulationDiverged):
        stiff_naive_cloth().run(0.5, 1e-3, method="symplectic_euler")
    c = stiff_naive_cloth()
    c.run(0.1, 4e-4, method="symplectic_euler")
    assert c.max_strain() < 0.05


@pytest.mark.parametrize("make", [lambda c: BaraffWitkin(c), lambda c: Prefactored(c, 1 / 30)],
                         ids=["baraff_witkin", "prefactored"])
def test_implicit_stable_at_one_thirtieth(make):
    """h = 1/30 s, 33 times the explicit limit: finite, bounded, hanging below its pins."""
    c = stiff_naive_cloth(plane="horizontal")
    t, X = c.run(2.0, 1 / 30, method=make(c))
    assert np.all(np.isfinite(X))
    assert max(c.max_strain(Xk) for Xk in X) < 0.1
    assert c.X[:, 0, 2].mean() < -0.3
    np.testing.assert_array_equal(X[:, c.pinned, 0], np.broadcast_to(X[0, c.pinned, 0], X[:, c.pinned, 0].shape))


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
