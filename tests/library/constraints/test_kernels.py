"""Provot's projection compiled (particles.constraints.kernels): NumPy's bits, the same passes, any thread count."""

import numpy as np
import pytest

from particles import backends
from particles.constraints import ProvotConstraint
from particles.massspring import cloth

from ..backends.helpers import _close, assert_same_bits, needs_numba, on_thread_counts


def _provot_runs(method, outer, inner="numpy", seconds=0.3):
    """A soft 16^2 curtain under Provot's constraint: end states and histories with the projection on each backend.

    `inner` is the backend of the rest of the run (the step); `outer` the projection's backends to compare.
    """
    out = {}
    for backend in outer:
        c = cloth(16, 16, k_structural=5.0, kd=0.01)
        with backends.using(inner):
            provot = ProvotConstraint.from_system(c, method=method, backend=backend)
            X = c.run(seconds, 2e-3, method=provot.stepper("symplectic_euler"))[1][-1]
        out[backend] = X, [(r.iterations, r.max_strain, r.converged) for r in provot.history]
    return out


@needs_numba
@pytest.mark.parametrize("method", ["jacobi", "gauss-seidel"])
def test_compiled_provot_projection_agrees_with_numpy(method):
    """Provot's pass compiled, 150 steps of a soft curtain (thousands of passes): the same bits, the same passes."""
    out = _provot_runs(method, ("numpy", "numba"))
    (X_np, history_np), (X_nb, history_nb) = out["numpy"], out["numba"]
    assert sum(passes for passes, _, _ in history_np) > 1000
    assert history_nb == history_np
    np.testing.assert_array_equal(X_nb, X_np)


@needs_numba
@pytest.mark.parametrize("method", ["jacobi", "gauss-seidel"])
def test_compiled_provot_around_the_compiled_step_agrees_with_numpy(method):
    """On the compiled step's C-ordered states, in place: NumPy's bits; and the NumPy run's to 1e-12 for 20 steps.

    The number of passes is a verdict on a threshold (the largest strain
    against ``max_strain + tol``): the compiled step's states, a rounding
    error from NumPy's, can take one more pass, and from then on the runs
    part (at step 34 of this one); the projection itself is the same.
    """
    on_compiled = _provot_runs(method, ("numpy", "numba"), inner="numba", seconds=0.1)
    np.testing.assert_array_equal(on_compiled["numba"][0], on_compiled["numpy"][0])
    assert on_compiled["numba"][1] == on_compiled["numpy"][1]
    numpy_run = _provot_runs(method, ("numpy",), inner="numpy", seconds=0.04)["numpy"]
    compiled_run = _provot_runs(method, ("numba",), inner="numba", seconds=0.04)["numba"]
    _close(numpy_run[0], compiled_run[0])
    assert [p for p, _, _ in numpy_run[1]] == [p for p, _, _ in compiled_run[1]]


@needs_numba
def test_the_compiled_projection_has_the_same_bits_on_any_number_of_threads(monkeypatch):
    """Provot's passes, Jacobi and Gauss-Seidel: one thread, two threads and the serial kernel give the same bits."""
    def run():
        return [_provot_runs(m, ("numba",), seconds=0.1)["numba"][0] for m in ("jacobi", "gauss-seidel")]

    assert_same_bits(on_thread_counts(monkeypatch, run))
