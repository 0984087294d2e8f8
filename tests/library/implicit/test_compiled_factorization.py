"""The prefactorized solver's compiled pieces (particles.implicit.compiled_factorization) against its NumPy methods.

The local step gives NumPy's bits for ``J d``; the triangular solves over
SuperLU's factors, the springs' energy and the gradient's norm agree with
NumPy to 1e-12 relative (rounding: sums in another order). Cloths in 3D and
strings in 2D, with pins, off rest; the inputs are not modified.
"""

import numpy as np
import pytest

from particles import backends
from particles.implicit import Prefactored
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
def test_solves_over_superlus_factors_agree_with_superlu(make):
    """The compiled triangular solves of Q x = b + h^2 J d agree with SuperLU's solve to 1e-12; inputs kept."""
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
