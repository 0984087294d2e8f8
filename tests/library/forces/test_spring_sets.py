"""Springs and bending: formulas, Newton's third law, energies, Jacobians vs finite differences."""

import numpy as np
import pytest

from particles.forces import Bending, Clamp, Springs


def random_springs(d, seed=0, kd=True):
    rng = np.random.default_rng(seed)
    n = 7
    x = rng.normal(size=(n, d))
    v = rng.normal(size=(n, d))
    idx = np.array([[0, 1], [1, 2], [2, 3], [3, 4], [4, 5], [5, 6], [0, 6], [1, 5], [2, 4], [0, 3]])
    L = np.linalg.norm(x[idx[:, 0]] - x[idx[:, 1]], axis=1)
    # some springs stretched, some compressed
    L0 = L * rng.uniform(0.6, 1.4, len(idx))
    s = Springs(idx, rest_length=L0, k=rng.uniform(1, 10, len(idx)),
                kd=rng.uniform(0.1, 2, len(idx)) if kd else 0.0)
    return s, x, v


def fd_jacobian(fn, y, eps=1e-6):
    """Central-difference Jacobian of fn (array -> array) at y, columns over y.ravel() (test helper)."""
    cols = []
    for c in range(y.size):
        e = np.zeros(y.size)
        e[c] = eps
        cols.append(((fn(y + e.reshape(y.shape)) - fn(y - e.reshape(y.shape))) / (2 * eps)).ravel())
    return np.stack(cols, axis=1)


def test_single_spring_formula():
    """F = k (L0 - L) u plus damping -kd (v_rel . u) u, equal and opposite."""
    s = Springs([[0, 1]], rest_length=2.0, k=3.0, kd=0.5)
    x = np.array([[0.0, 0.0, 0.0], [3.0, 4.0, 0.0]])  # L = 5, u from j to i = -(0.6, 0.8)
    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    F = s(x, v)
    u = np.array([-0.6, -0.8, 0.0])
    expected = 3.0 * (2.0 - 5.0) * u - 0.5 * np.dot(v[0] - v[1], u) * u
    np.testing.assert_allclose(F[0], expected)
    np.testing.assert_allclose(F[1], -expected)


def test_rest_length_defaults_to_current_distance():
    """Without rest_length the springs rest at the given positions: no force, no strain."""
    x = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 1.0]])
    s = Springs([[0, 1], [1, 2]], k=5.0, x=x)
    np.testing.assert_allclose(s.rest_length, [np.sqrt(2), 1.0])
    np.testing.assert_allclose(s(x), 0.0, atol=1e-12)
    np.testing.assert_allclose(s.strain(x), 0.0, atol=1e-15)


@pytest.mark.parametrize("d", [2, 3])
def test_damped_springs_conserve_momentum(d):
    """With damping along the springs the forces are still equal and opposite: no net force."""
    s, x, v = random_springs(d, kd=True)
    F = s(x, v)
    assert np.any(s.kd > 0) and np.abs(F - s(x)).max() > 1e-6  # the damping acts
    assert np.abs(F.sum(axis=0)).max() < 1e-12


@pytest.mark.parametrize("d", [2, 3])
def test_momentum_conserved_and_force_is_minus_energy_gradient(d):
    """Spring forces sum to zero and equal minus the gradient of the elastic energy."""
    s, x, v = random_springs(d, kd=False)
    F = s(x)
    assert np.abs(F.sum(axis=0)).max() < 1e-12
    grad = fd_jacobian(lambda y: np.array(s.potential_energy(y)), x).reshape(x.shape)
    np.testing.assert_allclose(F, -grad, rtol=1e-6, atol=1e-8)


@pytest.mark.parametrize("d", [2, 3])
def test_jacobians_match_finite_differences(d):
    """dF/dx (with damping terms) and dF/dv agree with finite differences to 1e-6."""
    s, x, v = random_springs(d, seed=d)
    Kx, Kv = s.jacobians(x, v)
    Jx = fd_jacobian(lambda y: s(y, v), x)
    Jv = fd_jacobian(lambda w: s(x, w), v)
    assert np.abs(Kx.toarray() - Jx).max() <= 1e-6 * np.abs(Jx).max()
    assert np.abs(Kv.toarray() - Jv).max() <= 1e-6 * np.abs(Jv).max()


def test_clamped_jacobian_is_symmetric_negative_semidefinite():
    """Clamping compressed springs makes -dF/dx PSD; without it, it is indefinite here."""
    s, x, v = random_springs(3, seed=5)
    Kc, _ = s.jacobians(x, v, clamp=True)
    A = Kc.toarray()
    np.testing.assert_allclose(A, A.T, atol=1e-12)
    assert np.linalg.eigvalsh(A).max() < 1e-10
    K, _ = s.jacobians(x, v, clamp=False, damping_position_terms=False)
    assert np.linalg.eigvalsh(K.toarray()).max() > 1e-3  # compressed springs: indefinite


def test_coincident_particles_give_no_force():
    """Two particles at the same point (no direction) get no force rather than NaN."""
    s = Springs([[0, 1]], rest_length=1.0, k=1.0)
    F = s(np.zeros((2, 3)))
    assert np.all(F == 0.0)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(indices=[[0, 0]], rest_length=1.0), "join two different particles"),
        (dict(indices=[0, 1], rest_length=1.0), r"shape \(s, 2\)"),
        (dict(indices=[[0, -1]], rest_length=1.0), "indices >= 0"),
        (dict(indices=[[0, 1]], rest_length=1.0, k=0.0), "k must be > 0"),
        (dict(indices=[[0, 1]], rest_length=1.0, kd=-1.0), "kd must be >= 0"),
        (dict(indices=[[0, 1]], rest_length=[1.0, 2.0]), r"rest_length must be a number or have shape \(1,\)"),
        (dict(indices=[[0, 1]]), "give rest_length, or positions x"),
        (dict(indices=[[0, 5]], x=np.zeros((2, 2))), "refer to particle 5 but x has only 2"),
        (dict(indices=[[0, 1]], rest_length=-0.5), "rest_length must be >= 0"),
    ],
)
def test_bad_input(kwargs, match):
    """Each bad argument is refused with a message naming it."""
    with pytest.raises(ValueError, match=match):
        Springs(**kwargs)


def test_indices_beyond_the_system_are_refused_when_the_force_is_used():
    """A spring or joint pointing at a particle the system does not have raises, instead of NumPy clipping it."""
    x = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    springs = Springs([[0, 5]], rest_length=1.0)
    with pytest.raises(ValueError, match="indices refer to particle 5, but the system has only 3 particles"):
        springs(x)
    with pytest.raises(ValueError, match="indices refer to particle 5, but the system has only 3 particles"):
        springs.jacobians(x)
    with pytest.raises(ValueError, match="triples refer to particle 7, but the system has only 3 particles"):
        Bending([[0, 1, 7]], kb=1.0)(x)


# -- bending -------------------------------------------------------------------


def chain_with_kink(theta, d=2):
    """Three particles, unit segments, turning by theta at the middle one."""
    x = np.zeros((3, d))
    x[1, 0] = 1.0
    x[2, 0] = 1.0 + np.cos(theta)
    x[2, 1] = np.sin(theta)
    return x


def test_bending_zero_for_straight_chain_and_proportional_to_angle():
    """No force when straight; for small angles the force grows linearly with the angle."""
    b = Bending([[0, 1, 2]], kb=2.0)
    np.testing.assert_allclose(b(chain_with_kink(0.0)), 0.0, atol=1e-15)
    f1 = np.linalg.norm(b(chain_with_kink(0.01))[2])
    f2 = np.linalg.norm(b(chain_with_kink(0.02))[2])
    assert f2 / f1 == pytest.approx(2.0, rel=1e-3)
    # torque about the middle: kb theta, so the end force is kb theta / |e2|
    assert f1 == pytest.approx(2.0 * 0.01, rel=1e-3)


@pytest.mark.parametrize("d", [2, 3])
def test_bending_no_net_force_or_torque_and_gradient(d):
    """Bending forces have no net force or torque and equal minus the energy gradient."""
    rng = np.random.default_rng(d)
    x = rng.normal(size=(6, d))
    triples = [[0, 1, 2], [1, 2, 3], [2, 3, 4], [3, 4, 5]]
    b = Bending(triples, kb=rng.uniform(0.5, 2, 4), rest_angle=rng.uniform(0, 1, 4))
    F = b(x)
    assert np.abs(F.sum(axis=0)).max() < 1e-12
    if d == 3:
        assert np.abs(np.cross(x, F).sum(axis=0)).max() < 1e-12
    grad = fd_jacobian(lambda y: np.array(b.potential_energy(y)), x).reshape(x.shape)
    np.testing.assert_allclose(F, -grad, rtol=1e-6, atol=1e-7)


def test_bending_rest_angles_from_positions():
    """Rest angles taken from positions give no force there."""
    x = chain_with_kink(0.3)
    b = Bending([[0, 1, 2]], kb=1.0, x=x)
    assert b.rest_angle[0] == pytest.approx(0.3)
    np.testing.assert_allclose(b(x), 0.0, atol=1e-12)


# -- clamp ---------------------------------------------------------------------


def test_clamp_is_a_bending_joint_with_a_fixed_first_segment():
    """A clamp along u0 gives the force of a Bending joint whose first particle sits at x_i - u0 (a ghost)."""
    rng = np.random.default_rng(5)
    x = np.array([[0.0, 0.0], [1.0, 0.0]]) + 0.3 * rng.normal(size=(2, 2))
    clamp = Clamp([[0, 1]], direction=[2.0, 0.0], kb=1.5)  # direction normalized
    ghost = np.vstack([x[:1] - [1.0, 0.0], x])
    joint = Bending([[0, 1, 2]], kb=1.5)(ghost)
    F = clamp(x)
    np.testing.assert_allclose(F[1], joint[2], rtol=1e-12)
    np.testing.assert_allclose(F.sum(axis=0), 0.0, atol=1e-14)  # the root (a pin) takes the reaction
    assert clamp.angles(x)[0] == pytest.approx(Bending([[0, 1, 2]]).angles(ghost)[0])


@pytest.mark.parametrize("d", [2, 3])
def test_clamp_force_is_minus_energy_gradient_and_proportional_to_angle(d):
    """F = -grad(kb theta^2 / 2) for several clamps; zero along u0, linear in a small angle."""
    rng = np.random.default_rng(d)
    x = rng.normal(size=(4, d))
    clamp = Clamp([[0, 1], [2, 3]], direction=rng.normal(size=(2, d)), kb=[0.7, 1.3])
    grad = fd_jacobian(lambda y: np.array(clamp.potential_energy(y)), x).reshape(x.shape)
    np.testing.assert_allclose(clamp(x), -grad, rtol=1e-6, atol=1e-7)
    straight = Clamp([[0, 1]], direction=np.eye(d)[0], kb=2.0)
    np.testing.assert_allclose(straight(chain_with_kink(0.0, d)[1:]), 0.0, atol=1e-15)
    f1, f2 = (np.linalg.norm(straight(np.array([np.zeros(d), chain_with_kink(a, d)[2] - chain_with_kink(a, d)[1]]))[1])
              for a in (0.01, 0.02))
    assert f2 / f1 == pytest.approx(2.0, rel=1e-3) and f1 == pytest.approx(2.0 * 0.01, rel=1e-3)


def test_clamp_checks_its_directions():
    """Directions must be non-zero and one per clamp (or one for all)."""
    with pytest.raises(ValueError, match="direction must be non-zero"):
        Clamp([[0, 1]], direction=[0.0, 0.0])
    with pytest.raises(ValueError, match=r"direction must have shape \(d,\) or \(2, d\)"):
        Clamp([[0, 1], [1, 2]], direction=np.ones((3, 2)))
