"""The compiled XPBD projections (particles.xpbd.kernels), one batch at a time, against the NumPy sets' project."""

import numpy as np
import pytest

from particles.xpbd import Distance, distance_pass

from ..backends.helpers import _close, needs_numba


@needs_numba
@pytest.mark.parametrize("formulation", ["xpbd", "pbd"])
def test_distance_batches_agree_with_numpy_with_given_groups(formulation):
    """A Distance set's colour groups given as lists of rows, and its one Jacobi batch: the compiled projection
    equals the NumPy project to 1e-12, and a Jacobi or Gauss-Seidel XPBD pass equals distance_pass, the reference."""
    from particles.xpbd.kernels import CompiledPasses

    rng = np.random.default_rng(6)
    x = rng.normal(size=(6, 3))
    ij = [[0, 1], [2, 3], [1, 2], [3, 4], [4, 5]]
    w = np.array([0.0, 1.0, 0.5, 2.0, 1.0, 1.0])
    for method, groups in (("gauss-seidel", [[0, 1, 4], [2, 3]]), ("jacobi", None)):
        s = Distance(ij, 1.0, compliance=0.01, damping=0.2, groups=groups)
        out = []
        for project in (s.project, CompiledPasses().project):
            xt, lam = np.ascontiguousarray(x.T), np.zeros(5)
            for b in s.batches(w, method):  # a loop over the colours
                project(b, xt, np.ascontiguousarray(x.T + 0.01), lam, 1.0, formulation)
            out.append((xt.T, lam))
        _close(out[0][0], out[1][0])
        _close(out[0][1], out[1][1])
        if formulation == "xpbd":
            undamped = Distance(ij, 1.0, compliance=0.01, groups=groups)
            xt, lam = np.ascontiguousarray(x.T), np.zeros(5)
            for b in undamped.batches(w, method):
                undamped.project(b, xt, xt, lam, 1.0, "xpbd")
            reference = distance_pass(x, w, ij, 1.0, 0.01, np.zeros(5), groups=groups)
            _close(xt.T, reference[0])
            _close(lam, reference[1])
