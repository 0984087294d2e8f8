"""What the steppers share (particles.integrators.common): checks of X, t, h and f(X, t), the (n, 2, d) layout."""

import numpy as np
import pytest

from particles import integrate
from particles.integrators import INTEGRATORS, euler

from .helpers import ALL, SECOND_ORDER_LAYOUT, oscillator_f


def test_f_returning_wrong_shape_is_reported():
    """A right-hand side of the wrong shape gets a clear message."""
    with pytest.raises(ValueError, match=r"f\(X, t\) must return an array of the same shape as X \(2,\), got shape \(3,\)"):
        euler(lambda X, t: np.zeros(3), np.zeros(2), 0.0, 0.1)


@pytest.mark.parametrize("method", SECOND_ORDER_LAYOUT)
def test_second_order_steppers_reject_flat_states(method):
    """Symplectic steppers need the (n, 2, d) layout and say so."""
    with pytest.raises(ValueError, match=r"second-order layout \(n, 2, d\)"):
        integrate(lambda X, t: -X, np.ones(3), 0.0, 1.0, 0.1, method=method)


def _oscillator_state():
    """One unit oscillator in the (n, 2, d) layout every stepper accepts."""
    return oscillator_f(np.array([1.0])), np.array([[[1.0], [0.0]]])


@pytest.mark.parametrize("method", ALL)
@pytest.mark.parametrize(
    "bad, match",
    [
        (dict(X=np.full((1, 2, 1), np.nan)), "X must be finite"),
        (dict(X=np.array([[[np.inf], [0.0]]])), "X must be finite"),
        (dict(X="abc"), "X must be an array of real numbers, got str"),
        (dict(t=np.nan), r"t must be a finite real number \(in seconds\), got nan"),
        (dict(t=np.inf), "t must be a finite real number"),
        (dict(t="a"), "t must be a finite real number .*got 'a'"),
        (dict(t=None), "t must be a finite real number"),
        (dict(h=0.0), "h must be a positive finite number"),
        (dict(h=np.nan), "h must be a positive finite number"),
        (dict(h="0.1"), "h must be a positive finite number"),
    ],
)
def test_direct_stepper_calls_reject_bad_arguments(method, bad, match):
    """A stepper called directly refuses non-finite or non-numeric X, t, h, naming the argument."""
    f, X = _oscillator_state()
    args = dict(X=X, t=0.0, h=0.1)
    args.update(bad)
    with pytest.raises(ValueError, match=match):
        INTEGRATORS[method](f, args["X"], args["t"], args["h"])


@pytest.mark.parametrize("method", ALL)
def test_steppers_accept_every_real_time_and_pass_it_unchanged(method):
    """t may be an int, a NumPy scalar or a 0-d array: same result, and f sees the t given."""
    f, X = _oscillator_state()
    seen = []

    def spy(X, t):
        seen.append(t)
        return f(X, t)

    step = INTEGRATORS[method]
    reference = step(f, X, 0.0, 0.1)
    for t in (0, np.int64(0), np.float32(0.0), np.array(0.0)):
        seen.clear()
        np.testing.assert_array_equal(step(spy, X, t, 0.1), reference)
        if step.explicit:  # explicit steppers evaluate f at t first; implicit Euler only at t + h
            assert seen[0] is t
        else:
            assert seen[0] == 0.1


def test_stepper_on_float32_and_list_input_unchanged():
    """Valid non-float64 states are converted as before (float64 result, same values)."""
    out = euler(lambda X, t: -X, np.array([1.0, 2.0], dtype=np.float32), 0.0, 0.5)
    assert out.dtype == np.float64 and out.tolist() == [0.5, 1.0]
    assert euler(lambda X, t: -X, [1.0], 0, 0.1).tolist() == [0.9]
