"""The prefactorized solver's compiled pieces (particles.implicit.compiled_factorization) against its NumPy methods.

The local step gives NumPy's bits for ``J d``; the triangular solves over
the Cholesky factor taken from SuperLU's symmetric factorization, the springs' energy and the gradient's norm agree with
NumPy to 1e-12 relative (rounding: sums in another order). Cloths in 3D and
strings in 2D, with pins, off rest; the inputs are not modified.
"""

import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.linalg

from particles import backends
from particles.implicit import Prefactored
from particles.implicit.compiled_factorization import cholesky_factor
from particles.implicit.sparse import factorize
from particles.massspring import cloth, string

from ..backends.helpers import _close

pytestmark = pytest.mark.skipif("numba" not in backends.available(),
                                reason="numba is not installed (pip install 'particles[fast]')")

H = 1 / 30


SYSTEMS = [pytest.param(lambda: cloth(12, 10, scaling="physical", stretch_modulus=5000.0, damping=0.1), id="cloth-3d"),
           pytest.param(lambda: string(20, kd=0.0), id="string-2d")]


def _case(make, seed=0):
    """A solver on `make()`, its compiled kernels, a perturbed state as (d, n) positions, and the step's y, b."""
    c = make()
    solver = Prefactored(c, H, backend="numpy")
    rng = np.random.default_rng(seed)
    x = c.state()[:, 0]
    xt = np.ascontiguousarray((x + rng.normal(scale=0.02, size=x.shape)).T)
    xt[:, c.pinned] = x[c.pinned].T
    free = solver._free
    y = xt[:, free] + rng.normal(scale=0.01, size=(c.d, len(free)))
    b = (y * c.m[free]) - (solver._Q_fp @ x[c.pinned]).T
    return c, solver, solver._compiled(), xt, y, b


@pytest.mark.parametrize("make", SYSTEMS)
def test_local_step_gives_numpys_projections_and_energy(make):
    """The compiled local step: J d with NumPy's bits, the springs' energy to 1e-12, xt not modified."""
    c, solver, fast, xt, y, b = _case(make)
    before = xt.copy()
    Jd, E = solver._local(xt)
    fast.begin(y, H * H)
    Jd_c, E_c = fast.local(xt)
    np.testing.assert_array_equal(Jd_c, Jd)
    assert abs(E_c - E) <= 1e-12 * E
    np.testing.assert_array_equal(xt, before)


@pytest.mark.parametrize("make", SYSTEMS)
def test_solves_over_the_cholesky_factor_agree_with_superlu(make):
    """The compiled Cholesky solves of Q x = b + h^2 J d agree with SuperLU's solve to 1e-12; inputs kept."""
    c, solver, fast, xt, y, b = _case(make)
    Jd, _ = solver._local(xt)
    kept = (b.copy(), Jd.copy())
    out = fast.solve(b, Jd, H * H)
    _close(out, solver._global(b, Jd, H))
    np.testing.assert_array_equal(b, kept[0])
    np.testing.assert_array_equal(Jd, kept[1])
    # and it solves the system: Q out = b + h^2 J d
    residual = np.array([solver._Q_ff @ out[a] for a in range(c.d)]) - (b + H * H * Jd)
    assert np.abs(residual).max() <= 1e-10 * np.abs(b + H * H * Jd).max()


@pytest.mark.parametrize("make", SYSTEMS)
def test_gradient_norm_from_the_local_step_and_from_q(make):
    """|g| computed in the local step (M (x - y) / h^2 - F_springs) and by a product with Q: NumPy's to 1e-12."""
    c, solver, fast, xt, y, b = _case(make)
    u = xt[:, solver._free]
    Jd, _ = solver._local(xt)
    reference = solver._gradient_norm(solver._Q_ff, u, b, Jd, H * H)
    fast.begin(y, H * H)
    Jd_c, _ = fast.local(xt)
    fused = fast.gradient_norm(u, b, Jd_c, H * H)
    by_product = fast.gradient_norm(u, b, Jd_c.copy(), H * H)  # another J d: computed with Q
    assert reference > 0
    assert abs(fused - reference) <= 1e-12 * reference
    assert abs(by_product - reference) <= 1e-12 * reference


def test_the_local_steps_norm_is_that_of_its_own_positions():
    """After a local step at other positions, the norm is not reused for the earlier J d: it is recomputed."""
    c, solver, fast, xt, y, b = _case(SYSTEMS[0].values[0])
    u = xt[:, solver._free]
    fast.begin(y, H * H)
    Jd, _ = fast.local(xt)
    first = fast.gradient_norm(u, b, Jd, H * H)
    moved = xt.copy()
    moved[:, solver._free] += 0.01
    fast.local(moved)
    assert fast.gradient_norm(u, b, Jd, H * H) == pytest.approx(first, rel=1e-12)


@pytest.mark.parametrize("make", SYSTEMS)
def test_cholesky_factor_reproduces_the_permuted_matrix(make):
    """R from SuperLU's symmetric factorization: P Q P^T = R^T R to 1e-13, R upper with a positive diagonal."""
    c, solver, fast, xt, y, b = _case(make)
    perm, Rp, Rj, Rx, Rd = cholesky_factor(solver._lu)
    f = len(Rd)
    R = scipy.sparse.csr_matrix((Rx, Rj, Rp), shape=(f, f)) + scipy.sparse.diags(Rd)
    Q = solver._Q_ff.toarray()
    P = np.zeros((f, f))
    P[perm, np.arange(f)] = 1.0  # the solve's convention: row r of Q goes to row perm[r]
    assert np.all(Rd > 0) and scipy.sparse.tril(R, -1).nnz == 0
    np.testing.assert_allclose((R.T @ R).toarray(), P @ Q @ P.T, atol=1e-13 * np.abs(Q).max())


def test_cholesky_factor_refuses_an_unsymmetric_factorization():
    """A factorization with row pivots (not SuperLU's symmetric mode) is refused with a message."""
    A = scipy.sparse.csc_matrix(np.array([[1e-3, 1.0, 0.0], [1.0, 1.0, 0.5], [0.0, 0.5, 3.0]]))
    lu = scipy.sparse.linalg.splu(A, permc_spec="NATURAL")
    with pytest.raises(ValueError, match="lu must be a symmetric factorization"):
        cholesky_factor(lu)
    with pytest.raises(ValueError, match="symmetric positive definite"):
        cholesky_factor(factorize(scipy.sparse.csc_matrix(np.diag([1.0, -2.0, 3.0]))))
