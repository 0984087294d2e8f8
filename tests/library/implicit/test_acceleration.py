"""Accelerations of a fixed-point iteration (particles.implicit.acceleration) on linear maps of known spectrum.

``G(u) = B u + c`` with a symmetric ``B`` whose eigenvalues lie in ``[-rho, rho]``: the plain iteration's
error falls like ``rho^k``; Chebyshev's like its polynomial's bound; Anderson with a depth at least the
number of distinct eigenvalues finds the fixed point in that many mixed steps (GMRES's property).
"""

import numpy as np
import pytest

from particles.implicit.acceleration import Anderson, Chebyshev


def _linear_map(n, rho, seed=0):
    """A symmetric iteration matrix with eigenvalues spread over [-rho, rho], a constant, and the fixed point."""
    rng = np.random.default_rng(seed)
    V, _ = np.linalg.qr(rng.normal(size=(n, n)))
    B = V @ np.diag(np.linspace(-rho, rho, n)) @ V.T
    c = rng.normal(size=n)
    return B, c, np.linalg.solve(np.eye(n) - B, c)


def _errors(mixing, B, c, fixed, iterations):
    """|u_k - u*| over the iterations of u <- mixing.propose(u, G(u)) from zero."""
    u, errors = np.zeros_like(c), []
    for _ in range(iterations):  # a loop over iterations
        image = B @ u + c
        u = image if mixing is None else mixing.propose(u, image)
        errors.append(float(np.linalg.norm(u - fixed)))
    return np.array(errors)


def test_chebyshev_beats_the_plain_iteration_at_its_rate():
    """rho = 0.95: after 60 iterations Chebyshev's error is below its polynomial bound, the plain one near rho^k."""
    B, c, fixed = _linear_map(40, 0.95)
    start = np.linalg.norm(fixed)
    plain = _errors(None, B, c, fixed, 60)
    fast = _errors(Chebyshev(0.95, delay=0), B, c, fixed, 60)
    assert plain[-1] / start == pytest.approx(0.95 ** 60, rel=0.5)
    bound = 2 * (0.95 / (1 + np.sqrt(1 - 0.95 ** 2))) ** 59
    assert fast[-1] / start <= bound
    assert fast[-1] < 1e-3 * plain[-1]


def test_chebyshev_restarts_with_plain_iterations():
    """After restart the next `delay` proposals are the plain images themselves."""
    mixing = Chebyshev(0.9, delay=2)
    u, image = np.zeros(3), np.ones(3)
    for _ in range(4):  # a loop over iterations
        mixing.propose(u, image)
    mixing.restart(u)
    assert mixing.propose(u, image) is image and mixing.propose(u, image) is image
    assert mixing.propose(u, image) is not image


def test_anderson_finds_the_fixed_point_of_a_small_spectrum():
    """Four distinct eigenvalues and depth 6: the fixed point to 1e-10 within 6 iterations; plain is far off."""
    rng = np.random.default_rng(1)
    V, _ = np.linalg.qr(rng.normal(size=(30, 30)))
    B = V @ np.diag(np.repeat([0.99, 0.5, -0.3, -0.9], [8, 8, 7, 7])) @ V.T
    c = rng.normal(size=30)
    fixed = np.linalg.solve(np.eye(30) - B, c)
    errors = _errors(Anderson(6, 30), B, c, fixed, 6)
    assert errors[-1] <= 1e-10 * np.linalg.norm(fixed)
    assert _errors(None, B, c, fixed, 6)[-1] > 0.5 * np.linalg.norm(fixed)


def test_anderson_keeps_the_ring_and_its_gram_matrix():
    """Past its depth the ring overwrites the oldest rows; the Gram matrix stays dF dF^T of the rows kept."""
    B, c, fixed = _linear_map(12, 0.9, seed=3)
    mixing = Anderson(3, 12)
    _errors(mixing, B, c, fixed, 9)
    np.testing.assert_allclose(mixing.gram, mixing.dF @ mixing.dF.T, rtol=1e-12, atol=1e-14)
    mixing.restart(None)
    assert mixing.kept == 0 and mixing.last is not None
