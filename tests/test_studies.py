"""The measured studies reproduce the theory they illustrate."""

import numpy as np
import pytest

from particles.studies import discretization, provot, stability
from particles.studies.report import write_study


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
    wh = np.array([0.05, 0.5, 2.0, 20.0])
    np.testing.assert_allclose(stability.damping_factor(wh), 1 / np.sqrt(1 + wh**2), rtol=1e-8)


def test_cost_explicit_grows_with_stiffness_implicit_does_not():
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


def test_write_study_files_and_errors(tmp_path):
    lines = []
    files = write_study("order", tmp_path, log=lines.append)
    assert sorted(p.name for p in files) == ["order.csv", "order.png", "order.svg"]
    assert all(p.stat().st_size > 0 for p in files)
    assert any("rk4" in line and "observed 4.0" in line for line in lines)
    with pytest.raises(ValueError, match="unknown study 'speed'"):
        write_study("speed", tmp_path)
