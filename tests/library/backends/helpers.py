"""Helpers of the backend tests: the numba marker and the agreement to a relative tolerance."""

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
