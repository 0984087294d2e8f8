"""Helpers of the backend tests: the numba marker, the agreement to a relative tolerance, a shaken system."""

import numpy as np
import pytest

from particles import backends

needs_numba = pytest.mark.skipif("numba" not in backends.available(),
                                 reason="numba is not installed (pip install 'particles[fast]')")


def _close(a, b, rtol=1e-12):
    """Arrays equal to `rtol` relative to their largest entry."""
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape
    assert np.abs(a - b).max(initial=0.0) <= rtol * max(np.abs(a).max(initial=0.0), 1e-300)


def on_thread_counts(monkeypatch, run):
    """`run()` on one thread and on two with every compiled loop parallel, then with none: its three results.

    The determinism tests compare them bit for bit (:func:`assert_same_bits`): the kernels' reductions
    must not depend on how the loops are split between threads.
    """
    import numba

    from particles.backends import compile as kernels

    results = []
    before = numba.get_num_threads()
    try:
        for threads, parallel_min in ((1, 0), (min(2, numba.config.NUMBA_NUM_THREADS), 0), (1, 10**9)):
            monkeypatch.setattr(kernels, "PARALLEL_MIN", parallel_min)  # 0: every loop parallel; 10**9: none
            numba.set_num_threads(threads)
            results.append(run())
    finally:
        numba.set_num_threads(before)
    return results


def assert_same_bits(results):
    """Every run's quantities (one list of arrays per run) equal, bit for bit, to the first run's."""
    for runs in zip(*results):  # a loop over the quantities: each the same in every run
        for other in runs[1:]:
            np.testing.assert_array_equal(other, runs[0])


def shaken(system, seed=0):
    """`system` with its free particles moved off rest and moving (pinned ones stay at rest)."""
    X = system.state()
    rng = np.random.default_rng(seed)
    free = np.setdiff1d(np.arange(system.n), system.pinned)
    X[free, 0] += rng.normal(scale=0.01, size=(len(free), system.d))
    X[free, 1] = rng.normal(scale=0.1, size=(len(free), system.d))
    system.set_state(X, 0.0)
    return system
