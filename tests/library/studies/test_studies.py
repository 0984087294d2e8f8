"""The measured studies reproduce the theory they illustrate."""

import csv
import re

import numpy as np
import pytest

from particles.studies import discretization, provot, stability
from particles.studies.report import write_study, write_table


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


def test_discretization_study_small():
    """Physical scaling: same sag and period at 6 and 12 per side, h_max ~ dx; naive: neither."""
    study = discretization.discretization_study(resolutions=(6, 12), reference=6)
    phys, naive = study["physical"], study["naive"]
    assert phys["sag"][1] == pytest.approx(phys["sag"][0], rel=0.02)
    assert phys["period"][1] == pytest.approx(phys["period"][0], rel=0.05)
    assert naive["sag"][1] > 2 * naive["sag"][0]
    assert naive["period"][1] > 1.5 * naive["period"][0]
    assert phys["h_exponent"] == pytest.approx(1.0, abs=0.1)
    assert abs(naive["h_exponent"]) < 0.1


def test_provot_study_small():
    """Soft springs stretch several times past 10%; the constraint holds them at 10% + tolerance."""
    study = provot.provot_study(n=8, steps=200)
    assert study["strain"]["free"].max() > 0.3
    assert study["strain"]["provot"].max() <= 0.1 + study["tol"] + 1e-12
    assert len(study["iterations"]) == 200


def _key_number(lines, pattern):
    """The number captured by `pattern` in the one summary line it matches."""
    found = [m for m in (re.search(pattern, line.strip()) for line in lines) if m]
    assert len(found) == 1, f"{pattern!r} should match one line of {lines}"
    return float(found[0].group(1))


# study -> (files written, checks of the summary: (pattern capturing a number, lower bound, upper bound))
STUDY_OUTPUTS = {
    "order": (["order.csv", "order.png", "order.svg"],
              [(r"^rk4 .*observed (\d+\.\d+)", 3.9, 4.1), (r"^verlet .*observed (\d+\.\d+)", 1.9, 2.1)]),
    "stability": (["stability.csv", "stability.png", "stability.svg", "stability_cost.csv"],
                  [(r"^verlet .*omega h_max = (\d+\.\d+)", 1.98, 2.0), (r"^rk4 .*omega h_max = (\d+\.\d+)", 2.80, 2.83),
                   (r"^symplectic_euler .*slope of h_max vs k: ([-+]\d+\.\d+)", -0.51, -0.49)]),
    "provot": (["provot.csv", "provot.png", "provot.svg"],
               [(r"soft springs (\d+)%", 30, 100), (r"with the constraint (\d+\.\d+)%", 9.0, 11.0)]),
    "discretization": (["discretization.csv", "discretization.png", "discretization.svg"],
                       [(r"^physical +sag \(mm\) \[(\d+\.\d+)", 8.0, 9.0), (r"^physical .*h_max ~ dx\^(\d+\.\d+)", 0.9, 1.1), (r"^naive .*h_max ~ dx\^(-?\d+\.\d+)", -0.1, 0.1)]),
}


@pytest.mark.parametrize("name", sorted(STUDY_OUTPUTS))
def test_write_study_files_and_summary(name, tmp_path):
    """Each study writes a non-empty PNG, SVG and CSV table(s) and prints its key numbers."""
    lines = []
    files = write_study(name, tmp_path, log=lines.append)
    expected, checks = STUDY_OUTPUTS[name]
    assert sorted(p.name for p in files) == expected
    assert all(p.parent == tmp_path and p.stat().st_size > 0 for p in files)
    for p in files:
        head = p.read_bytes()[:400]
        if p.suffix == ".png":
            assert head.startswith(b"\x89PNG\r\n\x1a\n")
        elif p.suffix == ".svg":
            assert b"<svg" in head
        else:
            with open(p, newline="") as fh:
                rows = list(csv.reader(fh))
            assert len(rows) >= 3 and all(len(r) == len(rows[0]) for r in rows)
    assert lines[0].startswith(f"study {name} (") and all(p.name in lines[0] for p in files)
    for pattern, low, high in checks:
        assert low <= _key_number(lines[1:], pattern) <= high, (pattern, lines)


def test_write_study_and_write_table_errors(tmp_path):
    """Unknown study names, a non-callable log and empty tables are ValueErrors naming the problem."""
    with pytest.raises(ValueError, match="unknown study 'speed'; expected one of 'order'"):
        write_study("speed", tmp_path)
    with pytest.raises(ValueError, match="name must be a study's name"):
        write_study(["order"], tmp_path)
    with pytest.raises(ValueError, match="log must be callable"):
        write_study("order", tmp_path, log="stdout")
    with pytest.raises(ValueError, match="rows must be a non-empty list of dicts"):
        write_table(tmp_path, "empty", [])
    assert write_table(str(tmp_path), "t", [{"a": 1, "b": 2}]).read_text().splitlines() == ["a,b", "1,2"]


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


@pytest.mark.parametrize("kwargs, name", [
    ({"h": -1.0}, "h"), ({"h": 0.0}, "h"), ({"steps": 0}, "steps"), ({"n": 2}, "n"), ({"k": -30.0}, "k"),
    ({"max_strain": 0.0}, "max_strain"), ({"every": 0}, "every"),
])
def test_provot_study_bad_arguments_are_named(kwargs, name):
    """provot_study names its own argument (h, not the integrator's t1)."""
    with pytest.raises(ValueError, match=f"^{name} must"):
        provot.provot_study(**kwargs)


@pytest.mark.parametrize("call, name", [
    (lambda: discretization.hanging_cloth(2, "physical"), "n"),
    (lambda: discretization.bounce_period(discretization.hanging_cloth(4, "physical"), periods=0), "periods"),
    (lambda: discretization.bounce_period(discretization.hanging_cloth(4, "physical"), safety=1.5), "safety"),
], ids=["n", "periods", "safety"])
def test_discretization_bad_arguments_are_named(call, name):
    """A too small cloth, no periods, a step past the stability limit are named."""
    with pytest.raises(ValueError, match=f"^{name} must"):
        call()
