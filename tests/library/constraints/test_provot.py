"""Provot's deformation constraint: limit cases, invariants, and the slide's curtain experiment."""

import numpy as np
import pytest

from particles.constraints import ProvotConstraint, color_constraints, provot_projection
from particles.integrators import symplectic_euler
from particles.massspring import cloth

METHODS = ["jacobi", "gauss-seidel"]


def one_spring(free):
    x = np.array([[0.0, 0.0], [2.0, 0.0]])  # rest length 1: strain 100%
    return provot_projection(x, [[0, 1]], [1.0], np.array(free), max_strain=0.1, tol=0.0)


def test_both_free_move_symmetrically_and_keep_centre_of_mass():
    """A spring stretched 20% between two free ends is shortened to 10% from both ends, its centre unchanged."""
    r = one_spring([True, True])
    np.testing.assert_allclose(r.x, [[0.45, 0.0], [1.55, 0.0]])
    assert r.x.mean(axis=0) == pytest.approx([1.0, 0.0])
    assert r.max_strain == pytest.approx(0.1) and r.converged and r.iterations == 1


def test_one_pinned_only_free_end_moves():
    """With one end pinned, only the free end moves, by the whole correction."""
    r = one_spring([True, False])
    np.testing.assert_allclose(r.x, [[0.9, 0.0], [2.0, 0.0]])
    r = one_spring([False, True])
    np.testing.assert_allclose(r.x, [[0.0, 0.0], [1.1, 0.0]])


def test_both_pinned_nothing_moves():
    """A spring between two pins is left as it is."""
    r = one_spring([False, False])
    np.testing.assert_array_equal(r.x, [[0.0, 0.0], [2.0, 0.0]])
    assert r.max_strain == 0.0  # springs between two pins are not constrained


def test_compressed_and_slightly_stretched_springs_untouched():
    """Compressed springs and springs stretched less than the limit are not corrected."""
    x = np.array([[0.0, 0.0], [0.5, 0.0], [1.55, 0.0]])
    r = provot_projection(x, [[0, 1], [1, 2]], [1.0, 1.0], np.ones(3, bool), max_strain=0.1)
    np.testing.assert_array_equal(r.x, x)
    assert r.iterations == 0


@pytest.mark.parametrize("method", METHODS)
def test_random_stretched_cloth_projected_within_limit(method):
    """After projection every spring is within the limit, pins fixed, input untouched."""
    c = cloth(10, 10, pins="top corners")
    rng = np.random.default_rng(0)
    x = c.X[:, 0] + rng.normal(scale=0.05, size=(c.n, 3))
    x[c.pinned] = c.X[c.pinned, 0]
    x_before = x.copy()
    provot = ProvotConstraint.from_system(c, method=method, tol=1e-4, iterations=5000)
    r = provot.project(x)
    np.testing.assert_array_equal(x, x_before)
    assert r.converged
    strain = c.strain(np.stack([r.x, np.zeros_like(r.x)], axis=1))[: len(provot.rest_length)]
    assert strain.max() <= 0.1 + 1e-4
    np.testing.assert_array_equal(r.x[c.pinned], x[c.pinned])


def test_free_pair_centre_of_mass_unchanged_in_cloth():
    """With no pins, corrections are equal and opposite: the centre of mass of equal masses stays put."""
    c = cloth(6, 6, pins=None)
    x = c.X[:, 0] * np.array([1.5, 1.0, 1.3])  # stretched in two directions
    r = ProvotConstraint.from_system(c).project(x)
    np.testing.assert_allclose(r.x.mean(axis=0), x.mean(axis=0), atol=1e-12)


def test_spring_colouring_groups_are_independent_and_complete():
    """The colour groups hold every spring once and no particle twice within a group."""
    c = cloth(8, 7)
    idx = c.spring_indices()
    groups = color_constraints(idx, c.n, seed=3)
    assert np.array_equal(np.sort(np.concatenate(groups)), np.arange(len(idx)))
    for g in groups:
        ends = idx[g].ravel()
        assert len(np.unique(ends)) == len(ends)  # no particle twice in a group
    assert len(groups) <= 2 * 16  # about twice the largest degree (16 in a cloth)


def test_stepper_corrects_velocities_consistently():
    """x_new - x_old == h v_new after a constrained symplectic Euler step."""
    c = cloth(6, 6, plane="horizontal", k_structural=5.0)
    provot = ProvotConstraint.from_system(c)
    step = provot.stepper(symplectic_euler)
    assert step.order == 1 and step.second_order_layout
    X = c.state()
    for k in range(30):
        h = 0.01
        X_new = step(c.derivative, X, k * h, h)
        np.testing.assert_allclose(X_new[:, 0] - X[:, 0], h * X_new[:, 1], atol=1e-12)
        X = X_new
    assert provot.history[-1].max_strain <= 0.1 + provot.tol


def test_curtain_experiment_of_the_slide():
    """Soft springs: after 200 steps the curtain deforms excessively; with Provot it stays within 10%
    (plus the projection's tolerance 0.5%), still hangs below its pins and still swings."""
    def run(constrained):
        c = cloth(12, 12, plane="horizontal", pins="top corners", damping=0.002, k_structural=30.0)
        provot = ProvotConstraint.from_system(c)
        step = provot.stepper(symplectic_euler) if constrained else symplectic_euler
        t, X = c.run(200 * 0.005, 0.005, method=step)
        strain = np.array([c.max_strain(Xk, "structural") for Xk in X])
        return c, X, strain, provot

    _, _, free_strain, _ = run(False)
    c, X, strain, provot = run(True)
    assert free_strain[-1] > 0.3                 # excessive deformation without the constraint
    assert strain.max() <= 0.1 + provot.tol + 1e-12  # within 10% + 0.5% over the whole run
    z_com = np.einsum("n,kn->k", c.m, X[:, :, 0, 2]) / c.m.sum()
    assert z_com[-1] < -0.2                      # it hangs
    vz = np.diff(z_com)
    assert np.any(vz > 1e-4) and np.any(vz < -1e-4)  # and swings back and forth
    np.testing.assert_array_equal(X[:, c.pinned, 0], X[:1, c.pinned, 0].repeat(len(X), axis=0))


def test_bad_arguments():
    """Bad arguments of the projection and the constraint are refused with messages naming them."""
    with pytest.raises(ValueError, match=r"free must be a boolean array of shape \(2,\)"):
        provot_projection(np.zeros((2, 2)), [[0, 1]], [1.0], [True])
    with pytest.raises(ValueError, match="method must be 'gauss-seidel' or 'jacobi'"):
        ProvotConstraint([[0, 1]], [1.0], 2, method="newton")
    with pytest.raises(ValueError, match="indices refer to particle 3 but n = 2"):
        ProvotConstraint([[0, 3]], [1.0], 2)
    with pytest.raises(ValueError, match="has no springs of kinds"):
        ProvotConstraint.from_system(cloth(4, 4), kinds=("bending",))
    for bad in (-1, 2.5, True):
        with pytest.raises(ValueError, match=f"iterations must be an integer >= 0, got {bad!r}"):
            provot_projection(np.zeros((2, 2)), [[0, 1]], [1.0], [True, True], iterations=bad)
    with pytest.raises(ValueError, match=r"pinned must hold particle indices from 0 to 1, got \[4\]"):
        ProvotConstraint([[0, 1]], [1.0], 2, pinned=[4])
    with pytest.raises(ValueError, match="iterations must be an integer >= 1, got 0"):
        ProvotConstraint([[0, 1]], [1.0], 2, iterations=0)
