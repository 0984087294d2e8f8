"""The time loop (particles.integrators.loop): integrate's time grid and options, the divergence guard, step_times."""

import numpy as np
import pytest

from particles import SimulationDiverged, integrate
from particles.integrators import midpoint

from .helpers import oscillator_f


def test_integrate_lands_on_t1_with_shortened_last_step():
    """The last step is shortened so that t[-1] == t1 exactly."""
    t, X = integrate(lambda X, t: np.ones_like(X), [0.0], 0.0, 1.0, 0.3, method="euler")
    np.testing.assert_allclose(t, [0.0, 0.3, 0.6, 0.9, 1.0])
    assert t[-1] == 1.0
    np.testing.assert_allclose(X[:, 0], t)  # x' = 1 is integrated exactly by Euler


def test_integrate_equal_steps_when_h_divides_interval():
    """(t1 - t0) / h integral up to round-off: no tiny extra step."""
    t, _ = integrate(lambda X, t: -X, [1.0], 0.0, 1.0, 0.1)
    assert len(t) == 11
    np.testing.assert_allclose(np.diff(t), 0.1)


def test_integrate_every_records_first_and_last():
    """every=k records every k-th state, always including the first and last."""
    t, X = integrate(lambda X, t: -X, [1.0], 0.0, 1.0, 0.1, every=4)
    np.testing.assert_allclose(t, [0.0, 0.4, 0.8, 1.0])
    assert X.shape == (4, 1)


def test_integrate_zero_length_interval():
    """t1 == t0 returns just the initial state."""
    t, X = integrate(lambda X, t: -X, [2.0], 1.0, 1.0, 0.1)
    assert t.tolist() == [1.0] and X.tolist() == [[2.0]]


def test_integrate_exact_decay():
    """RK4 on x' = -x reaches e^-1 with error ~h^4."""
    t, X = integrate(lambda X, t: -X, [1.0], 0.0, 1.0, 0.01)
    assert abs(X[-1, 0] - np.exp(-1)) < 1e-10


def test_integrate_passes_options_to_stepper():
    """Options such as jac= reach the stepper."""
    calls = []

    def jac(X, t):
        calls.append(t)
        return -np.eye(1)

    integrate(lambda X, t: -X, [1.0], 0.0, 0.3, 0.1, method="implicit_euler", jac=jac)
    assert len(calls) >= 3


def test_integrate_accepts_a_stepper_function():
    """method may be a stepper callable instead of a name."""
    t, X = integrate(lambda X, t: -X, [1.0], 0.0, 1.0, 0.1, method=midpoint)
    assert abs(X[-1, 0] - np.exp(-1)) < 1e-3


def test_integrate_does_not_modify_initial_state():
    """integrate never writes into the initial state (a read-only X0 works)."""
    X0 = np.array([[[1.0], [0.0]]])
    X0.setflags(write=False)
    integrate(oscillator_f(np.array([1.0])), X0, 0.0, 1.0, 0.1, method="verlet")
    assert X0[0, 0, 0] == 1.0


def test_divergence_raises_with_step_time_and_cause():
    """Explicit Euler on a stiff spring blows up: the error names step, time and cause."""
    f = oscillator_f(np.array([100.0]))
    with pytest.raises(SimulationDiverged) as info:
        integrate(f, [[[1.0], [0.0]]], 0.0, 100.0, 0.05, method="euler")
    err = info.value
    assert isinstance(err, RuntimeError)
    assert err.step > 1 and err.t == pytest.approx((err.step - 1) * 0.05)
    message = str(err)
    assert f"step {err.step}" in message and "t = " in message
    assert "stability limit" in message and "'euler'" in message and "h = 0.05" in message


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(h=0.0), "h must be a positive finite number"),
        (dict(h=-0.1), "h must be a positive finite number"),
        (dict(h=float("nan")), "h must be a positive finite number"),
        (dict(h="0.1"), "h must be a positive finite number"),
        (dict(method="rk5"), "unknown method 'rk5'; expected one of 'euler'"),
        (dict(X0=[np.inf]), "X0 must be finite"),
        (dict(X0="abc"), "X0 must be an array of real numbers"),
        (dict(t1=-1.0), "t1 must be >= t0"),
        (dict(every=0), "every must be a positive integer"),
    ],
)
def test_integrate_bad_input(kwargs, match):
    """Bad arguments raise ValueError naming the argument and what was expected."""
    args = dict(f=lambda X, t: -X, X0=[1.0], t0=0.0, t1=1.0, h=0.1)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        integrate(**args)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(t0="a"), "t0 must be a finite real number"),
        (dict(t1="b"), "t1 must be a finite real number"),
        (dict(t0=np.nan), "t0 must be a finite real number"),
        (dict(t1=np.inf), "t1 must be a finite real number"),
        (dict(blowup=1.0), "blowup must be None or a growth factor > 1"),
        (dict(blowup="big"), "blowup must be a positive finite number"),
    ],
)
def test_integrate_bad_times_and_blowup(kwargs, match):
    """Times that are not finite numbers and a growth factor <= 1 are reported by name."""
    args = dict(f=lambda X, t: -X, X0=[1.0], t0=0.0, t1=1.0, h=0.1)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        integrate(**args)


def test_exponential_growth_is_not_divergence_with_blowup_none():
    """x' = x over 30 s (e^30 ~ 1e13-fold) runs to the accurate answer with blowup=None."""
    t, X = integrate(lambda X, t: X, [1.0], 0.0, 30.0, 0.01, blowup=None)
    assert X[-1, 0] == pytest.approx(np.exp(30.0), rel=1e-8)
    t, X = integrate(lambda X, t: X, [1.0], 0.0, 30.0, 0.01, blowup=1e15)
    assert X[-1, 0] == pytest.approx(np.exp(30.0), rel=1e-8)


def test_growth_rule_message_says_growth_and_how_to_lift_it():
    """The default growth rule still stops e^30, and says it was growth (by how much), not inf/NaN."""
    with pytest.raises(SimulationDiverged) as info:
        integrate(lambda X, t: X, [1.0], 0.0, 30.0, 0.01)
    err, message = info.value, str(info.value)
    assert err.step == 2833 and err.t == pytest.approx(28.32)
    assert "still finite but grew too much" in message and "from 1 to 2.01e+12" in message
    assert "blowup = 1e+12" in message and "blowup=None" in message
    assert "inf or NaN" in message  # only in the advice "stop only on inf or NaN"
    assert "became inf or NaN" not in message


def test_overflow_message_says_inf_or_nan():
    """With blowup=None a real blow-up still raises, and the message says the state overflowed."""
    f = oscillator_f(np.array([100.0]))
    with pytest.raises(SimulationDiverged, match=r"stability limit .*The state became inf or NaN") as info:
        integrate(f, [[[1.0], [0.0]]], 0.0, 100.0, 0.05, method="euler", blowup=None)
    assert "grew too much" not in str(info.value)
    # 5.1-fold per step: the default rule stops ~400 steps before the overflow
    with pytest.raises(SimulationDiverged) as early:
        integrate(f, [[[1.0], [0.0]]], 0.0, 100.0, 0.05, method="euler")
    assert early.value.step < info.value.step - 300


def test_step_times_names_its_arguments():
    """step_times checks t0, t1 and h by name and lands on t1."""
    from particles.integrators import step_times

    assert step_times(0, 0.25, 0.1).tolist() == [0.0, 0.1, 0.2, 0.25]
    assert step_times(np.float32(1.0), np.array(1.0), 0.1).tolist() == [1.0]
    with pytest.raises(ValueError, match="t0 must be a finite real number"):
        step_times("0", 1.0, 0.1)


def test_step_times_never_makes_a_step_of_length_zero():
    """Far from t = 0, where t0 + k h rounds, every step stays > 0 and at most h (to round-off) and ends on t1."""
    from particles.integrators import step_times

    rng = np.random.default_rng(3)
    for _ in range(3000):
        t0, h, n = rng.uniform(-1e6, 1e6), 10 ** rng.uniform(-5, 0), int(rng.integers(1, 400))
        t1 = t0 + n * h * (1 + rng.choice([0.0, 1e-15, -1e-15, 1e-10]))
        t = step_times(t0, t1, h)
        steps = np.diff(t)
        assert t[0] == t0 and t[-1] == t1 and steps.min() > 0, (t0, t1, h)
        assert steps.max() <= h + 4 * np.spacing(abs(t0) + abs(t1)), (t0, t1, h)
        assert len(steps) in (n, n + 1)
