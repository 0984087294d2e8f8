"""The prefactorized solver (particles.implicit.prefactored): its residual rule, its backends, the bench's cases.

With the residual rule (the default) a step iterates until the gradient is
small: the cloth falls like backward Euler and settles at relax()'s
equilibrium, where ten fixed iterations fall short; a residual out of reach
raises ConvergenceError.

Both backends run the same Anderson-accelerated iteration; the compiled one
replaces the local step, the triangular solves and the residual's norm,
which agree with NumPy's to rounding (tests/library/backends/test_factored.py).
A step then takes the same iterations, and its end state agrees to 1e-10
relative: the rounding (1e-16) amplified by the iteration's small
least-squares problems, far inside the solver's tolerance (a residual of
0.1 of the forces). The bench's claim, that the implicit run's largest
strain stays within the compiled explicit run's, is checked on its own
configurations.
"""

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

from particles import ConvergenceError, backends
from particles.implicit import BaraffWitkin, Prefactored, relax
from particles.massspring import cloth

from .helpers import energy, readme_cloth, small_cloth, stiff_naive_cloth

NUMBA = pytest.mark.skipif("numba" not in backends.available(),
                           reason="numba is not installed (pip install 'particles[fast]')")


def stiff_cloth(n, modulus=5000.0):
    """The README's stiff cloth (physical scaling, 0.2 kg/m^2), air damping 0.1 /s, two pinned corners."""
    return cloth(n, n, scaling="physical", areal_density=0.2, stretch_modulus=modulus, damping=0.1)


def _relative(a, b):
    return float(np.abs(a - b).max() / np.abs(a).max())


@NUMBA
@pytest.mark.parametrize("h", [1 / 10, 1 / 30])
def test_compiled_steps_agree_with_numpy(h):
    """A run of the compiled solver takes NumPy's iterations and ends within 1e-10 (relative) of NumPy's states."""
    runs = {}
    for backend in ("numpy", "numba"):
        c = stiff_cloth(16)
        solver = Prefactored(c, h, backend=backend)
        t, X = c.run(0.5, h, method=solver)
        runs[backend] = (X, solver.counts, solver._fast is not None)
    assert runs["numba"][2] and not runs["numpy"][2]  # each ran the path it was asked for
    assert runs["numba"][1] == runs["numpy"][1] and min(runs["numpy"][1]) > 1
    assert _relative(runs["numpy"][0], runs["numba"][0]) <= 1e-10


@NUMBA
def test_compiled_fixed_iterations_agree_with_numpy():
    """Liu et al.'s fixed iterations: no residual, the same local and global steps: 1e-12 relative per step."""
    out = {}
    for backend in ("numpy", "numba"):
        c = stiff_cloth(12)
        out[backend] = Prefactored(c, 1 / 30, iterations=10, backend=backend).step(c.state(), 0.0, 1 / 30)
    assert _relative(out["numpy"], out["numba"]) <= 1e-12


@NUMBA
def test_compiled_step_leaves_its_input_alone():
    """The compiled step returns a new state and does not modify X (nor a refactorization at another h)."""
    c = stiff_cloth(12)
    X = c.state()
    X[:, 1] = 0.1
    before = X.copy()
    solver = Prefactored(c, 1 / 30, backend="numba")
    Y = solver.step(X, 0.0, 1 / 30)
    Z = solver.step(X, 0.0, 1 / 60)  # another h: refactorized, new kernels
    np.testing.assert_array_equal(X, before)
    assert not np.shares_memory(Y, X) and not np.shares_memory(Z, X)
    assert solver.h == 1 / 60 and np.abs(Y - Z).max() > 0


@NUMBA
def test_backend_choice_follows_the_package():
    """backend: "numpy" and "numba" as asked; "auto" compiles from AUTO_MIN particles; None follows using()."""
    small = stiff_cloth(8)
    X = small.state()
    for backend, compiled in (("numpy", False), ("numba", True), ("auto", False)):
        solver = Prefactored(small, 1 / 30, backend=backend)
        solver.step(X, 0.0, 1 / 30)
        assert (solver._fast is not None) == compiled, backend
    with backends.using("numba"):
        solver = Prefactored(small, 1 / 30)
        solver.step(X, 0.0, 1 / 30)
        assert solver._fast is not None
    with backends.using("numpy"):
        solver.step(X, 0.0, 1 / 30)  # the choice is made at each step
        assert solver._fast is None
    large = stiff_cloth(64)  # 4096 = AUTO_MIN particles
    solver = Prefactored(large, 1 / 30, backend="auto", iterations=1)
    solver.step(large.state(), 0.0, 1 / 30)
    assert (solver._fast is not None) == (backends.resolve("auto", large.n) == "numba")


def test_backend_is_checked():
    """An unknown backend is refused with a message naming the argument."""
    with pytest.raises(ValueError, match="backend must be 'numpy', 'numba', 'auto' or None"):
        Prefactored(stiff_cloth(4), 1 / 30, backend="fortran")


def _bench():
    """bench/bench_implicit.py as a module (its configurations)."""
    path = Path(__file__).resolve().parents[3] / "bench" / "bench_implicit.py"
    spec = importlib.util.spec_from_file_location("bench_implicit", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@NUMBA
@pytest.mark.slow
@pytest.mark.parametrize("modulus", [5000.0, 20000.0, 80000.0])
def test_bench_configurations_honour_the_strain_criterion(modulus):
    """The bench's longest implicit step keeps the largest strain within compiled explicit's (its first 0.25 s).

    The explicit run's largest strain comes with the first drop; over its first 0.25 s it is at most its
    largest over the bench's whole second, so the check is, if anything, stricter than the bench's.
    """
    bench = _bench()
    assert modulus in bench.MODULI
    with backends.using("numba"):
        c = bench.make(64, modulus)
        h = bench.explicit_config(c)
        t, X = c.run(0.25, h, method="symplectic_euler", every=max(1, math.ceil(0.25 / h) // 100))
    target = max(c.max_strain(x) for x in X)
    c = bench.make(64, modulus)
    h = bench.STEPS[0]
    solver = Prefactored(c, h, backend="numba")
    t, X = c.run(bench.T, h, method=solver)
    strain = max(c.max_strain(x) for x in X)
    assert 0.0 < strain <= target
    assert t[-1] == pytest.approx(bench.T) and len(solver.counts) == round(bench.T / h)


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


def test_prefactored_never_gains_energy_overall():
    """Few local/global iterations: single steps may wobble, the energy never exceeds its start."""
    c = stiff_naive_cloth(plane="horizontal")
    t, X = c.run(2.0, 1 / 30, method=Prefactored(c, 1 / 30, iterations=10))
    E = np.array([energy(c, Xk) for Xk in X])
    assert E.max() <= E[0] + 1e-9 and E[-1] < E[0] - 1.0


def test_prefactored_refactorizes_for_a_new_step():
    """Called with another h, the prefactorized solver builds and factorizes M + h^2 L again."""
    c = small_cloth()
    solver = Prefactored(c, 0.01)
    solver(None, c.X, 0.0, 0.02)
    assert solver.h == 0.02


@pytest.mark.parametrize("options, message", [
    ({"max_iterations": 0}, "max_iterations must be an integer >= 1, got 0"),
    ({"anderson": -1}, "anderson must be an integer >= 0, got -1"),
    ({"tol": -1.0}, "tol must be"),
    ({"chebyshev": 1.0}, r"chebyshev must be a spectral radius estimate in \[0, 1\)"),
    ({"chebyshev": float("nan")}, "chebyshev must be a spectral radius"),
    ({"chebyshev": 0.9}, "choose one acceleration"),
])
def test_prefactored_rejects_bad_options(options, message):
    """The residual rule's options are checked and named in the error."""
    with pytest.raises(ValueError, match=message):
        Prefactored(small_cloth(), 0.01, **options)


@pytest.mark.parametrize("options", [{}, {"warm_start": False}])
def test_the_warm_start_reaches_the_same_fall(options):
    """Anderson's iterations from the last step's answer or from y: the same backward-Euler fall."""
    h, centre = 1 / 30, readme_cloth(16).points["center"]
    c = readme_cloth(16)
    c.run(0.5, h, method=BaraffWitkin(c, linear_solver="direct", newton_iterations=4))
    reference = -c.X[centre, 0, 2]
    c = readme_cloth(16)
    solver = Prefactored(c, h, **options)
    c.run(0.5, h, method=solver)
    assert -c.X[centre, 0, 2] == pytest.approx(reference, rel=0.02)


def test_warm_start_and_chebyshev_take_fewer_iterations():
    """Stiff cloth at h = 1/60 s: the warm start saves Anderson 40% of its iterations; warm Chebyshev beats plain 4x."""
    counts = {}
    for name, options in (("default", {}), ("cold", {"warm_start": False}),
                          ("chebyshev", {"anderson": 0, "chebyshev": 0.95}),
                          ("plain", {"anderson": 0, "warm_start": False})):
        c = stiff_cloth(16)
        solver = Prefactored(c, 1 / 60, **options)
        c.run(0.25, 1 / 60, method=solver)
        counts[name] = np.mean(solver.counts)
    assert counts["default"] < 0.6 * counts["cold"]
    assert counts["chebyshev"] < 0.25 * counts["plain"]


def test_chebyshev_follows_backward_euler():
    """Warm Chebyshev (rho = 0.95) on the hanging stiff cloth: the same states as Anderson to the tolerance."""
    ends = {}
    for name, options in (("anderson", {}), ("chebyshev", {"anderson": 0, "chebyshev": 0.95})):
        c = stiff_cloth(16)
        c.run(0.25, 1 / 60, method=Prefactored(c, 1 / 60, **options))
        ends[name] = c.X[:, 0]
    sag = np.abs(ends["anderson"] - stiff_cloth(16).state()[:, 0]).max()
    assert np.abs(ends["chebyshev"] - ends["anderson"]).max() <= 0.02 * sag


def test_warm_start_is_dropped_with_a_new_step():
    """A refactorization for another h forgets the last answer; a step after it still converges."""
    c = stiff_cloth(8)
    solver = Prefactored(c, 1 / 60)
    X = solver.step(c.state(), 0.0, 1 / 60)
    assert solver._offset is not None
    solver._factor(1 / 30)
    assert solver._offset is None
    solver.step(X, 1 / 60, 1 / 30)
    assert solver._offset is not None and len(solver.counts) == 2
