"""The stability study (particles.studies.stability): omega h_max, h_max ~ k^(-1/2), implicit damping, cost."""

import numpy as np
import pytest

from particles.studies import stability


@pytest.mark.parametrize("method", ["symplectic_euler", "verlet", "rk4"])
@pytest.mark.parametrize("k, m", [(100.0, 1.0), (3e4, 0.2)])
def test_measured_stability_limit_matches_theory(method, k, m):
    """Bisection on the blow-up test finds omega h_max = 2 (2.83 for RK4) within 1%."""
    measured = stability.max_stable_step(method, k, m)
    assert measured == pytest.approx(stability.theory_max_step(method, k, m), rel=0.01)


def test_explicit_euler_apparent_limit_shrinks_with_test_length():
    """Without damping explicit Euler is never stable: longer tests find smaller 'limits'."""
    short = stability.max_stable_step("euler", 100.0, 1.0, steps=100)
    long = stability.max_stable_step("euler", 100.0, 1.0, steps=1000)
    assert 0 < long < 0.5 * short
    assert stability.theory_max_step("euler", 100.0, 1.0) == 0.0


def test_h_max_falls_as_one_over_root_k():
    """The measured stable step of symplectic Euler and RK4 falls like k^(-1/2)."""
    study = stability.stability_study(ks=(1.0, 100.0, 1e4), methods=("symplectic_euler", "rk4"), steps=500)
    for method in ("symplectic_euler", "rk4"):
        assert study["slope"][method] == pytest.approx(-0.5, abs=0.01)


def test_chain_needs_about_half_the_step_of_one_spring():
    """The fastest mode of a long chain has omega close to 2 sqrt(k/m)."""
    n, k, m = 10, 100.0, 1.0
    h = stability.chain_max_stable_step("symplectic_euler", n, k, m)
    theory = 2 / (2 * np.sqrt(k / m) * np.sin(n * np.pi / (2 * (n + 1))))
    assert h == pytest.approx(theory, rel=0.01)


def test_implicit_euler_damping_factor():
    """Implicit Euler keeps 1 / sqrt(1 + (omega h)^2) of the amplitude per step."""
    wh = np.array([0.05, 0.5, 2.0, 20.0])
    np.testing.assert_allclose(stability.damping_factor(wh), 1 / np.sqrt(1 + wh**2), rtol=1e-8)


def test_cost_explicit_grows_with_stiffness_implicit_does_not():
    """Explicit steppers pay sqrt(k) in evaluations per simulated second; implicit Euler does not."""
    rows = stability.cost_study(ks=(1e2, 1e6), T=1.0)
    cost = {(r["method"], r["k"]): r["evaluations"] for r in rows}
    # 10^4 times stiffer: 100 times more steps for explicit methods, the same for implicit
    assert cost[("symplectic_euler", 1e6)] / cost[("symplectic_euler", 1e2)] == pytest.approx(100, rel=0.2)
    assert cost[("rk4", 1e6)] / cost[("rk4", 1e2)] == pytest.approx(100, rel=0.2)
    assert cost[("implicit_euler", 1e6)] == cost[("implicit_euler", 1e2)]


@pytest.mark.parametrize("omega_h", [[0.0], 0.0, -0.5, [1.0, -1.0], [], [np.nan]])
def test_damping_factor_requires_positive_omega_h(omega_h):
    """omega h <= 0 (or NaN, or nothing) is refused by name instead of a NaN and a warning."""
    with pytest.raises(ValueError, match="^omega_h must"):
        stability.damping_factor(omega_h)


def test_damping_factor_of_a_scalar():
    """A single omega h gives a one-element array."""
    np.testing.assert_allclose(stability.damping_factor(1.0), [1 / np.sqrt(2)], rtol=1e-8)


@pytest.mark.parametrize("call", [
    lambda: stability.max_stable_step("bogus", 100.0, 1.0),
    lambda: stability.theory_max_step("bogus", 100.0, 1.0),
    lambda: stability.blows_up("bogus", 100.0, 1.0, 0.1),
    lambda: stability.chain_max_stable_step("bogus", 3, 100.0, 1.0),
], ids=["max_stable_step", "theory_max_step", "blows_up", "chain_max_stable_step"])
def test_unknown_method_is_named_with_the_choices(call):
    """An unknown stepper name is a ValueError naming it and listing the valid ones (not a KeyError)."""
    with pytest.raises(ValueError, match=r"unknown method 'bogus'; expected one of ") as error:
        call()
    assert all(f"'{name}'" in str(error.value) for name in ("euler", "symplectic_euler", "verlet", "rk4"))


def test_max_stable_step_accepts_a_stepper_function():
    """A stepper passed as a function is bisected like its name (no theoretical bracket)."""
    from particles.integrators import verlet

    h = stability.max_stable_step(verlet, 100.0, 1.0, steps=300)
    assert h == pytest.approx(0.2, rel=0.01)


@pytest.mark.parametrize("n", [0, -2, 2.0, True])
def test_chain_needs_a_positive_integer_n(n):
    """n = 0 (or a float, or a bool) is a ValueError naming n, not an IndexError."""
    with pytest.raises(ValueError, match=r"^n must be an integer >= 1"):
        stability.chain_max_stable_step("symplectic_euler", n, 100.0, 1.0)


@pytest.mark.parametrize("kwargs, name", [
    ({"k": 0.0}, "k"), ({"m": -1.0}, "m"), ({"steps": 0}, "steps"), ({"rtol": 0.0}, "rtol"),
    ({"h_range": (0.3, 0.1)}, "h_range"), ({"h_range": (-1.0, 1.0)}, r"h_range\[0\]"), ({"h_range": 0.2}, "h_range"),
])
def test_max_stable_step_bad_arguments_are_named(kwargs, name):
    """Non-positive k, m, steps, rtol and a bad bracket are ValueErrors naming the argument."""
    args = {"k": 100.0, "m": 1.0, **kwargs}
    with pytest.raises(ValueError, match=f"^{name} must"):
        stability.max_stable_step("verlet", args.pop("k"), args.pop("m"), **args)


@pytest.mark.parametrize("kwargs, name", [({"h": 0.0}, "h"), ({"growth": 0.5}, "growth"), ({"steps": 1.5}, "steps")])
def test_blows_up_bad_arguments_are_named(kwargs, name):
    """A non-positive step, a growth <= 1 or a fractional step count are named."""
    args = {"h": 0.1, **kwargs}
    with pytest.raises(ValueError, match=f"^{name} must"):
        stability.blows_up("verlet", 100.0, 1.0, **args)
