"""The XPBD and PBD solvers (particles.xpbd.solver): projections, invariants, multipliers, composition, input."""

import numpy as np
import pytest

from particles import Collider, ParticleSystem
from particles.collisions import Plane, Sphere
from particles.forces import Gravity
from particles.massspring import cloth, string
from particles.constraints import color_constraints
from particles.xpbd import PBD, XPBD, Attachment, Distance, IsometricBending, distance_pass

G = 9.81


def _free_cloth(n=6, seed=0):
    """A crumpled cloth without pins or gravity, with random velocities."""
    c = cloth(n, n, plane="horizontal", pins=None, gravity=0.0)
    rng = np.random.default_rng(seed)
    X = c.state()
    X[:, 0] += rng.normal(scale=0.02, size=X[:, 0].shape)
    X[:, 1] = rng.normal(scale=0.5, size=X[:, 1].shape)
    return c, X


def _sequential_pass(x, w, ij, L0, alpha, lam, order):
    """One XPBD pass written as the paper's loop over constraints, in the given order (the reference)."""
    x, lam = np.array(x, dtype=float), np.array(lam, dtype=float)
    for k in order:
        i, j = ij[k]
        d = x[i] - x[j]
        L = np.linalg.norm(d)
        dl = (-(L - L0[k]) - alpha[k] * lam[k]) / (w[i] + w[j] + alpha[k])
        x[i] += w[i] * dl * d / L
        x[j] -= w[j] * dl * d / L
        lam[k] += dl
    return x, lam


def test_gauss_seidel_pass_is_the_sequential_loop():
    """A coloured pass equals the constraint-by-constraint loop taken colour by colour."""
    c, X = _free_cloth()
    ij = np.concatenate([s.indices for s in c.springs.values()])
    L0 = np.concatenate([s.rest_length for s in c.springs.values()])
    rng = np.random.default_rng(1)
    w = rng.uniform(0.5, 2.0, c.n)
    w[[0, 5]] = 0.0
    alpha, lam = rng.uniform(0, 0.3, len(ij)), rng.normal(0, 0.01, len(ij))
    groups = color_constraints(ij, c.n)
    x_new, lam_new = distance_pass(X[:, 0], w, ij, L0, alpha, lam, groups)
    x_ref, lam_ref = _sequential_pass(X[:, 0], w, ij, L0, alpha, lam, np.concatenate(groups))
    assert np.allclose(x_new, x_ref, rtol=0, atol=1e-13) and np.allclose(lam_new, lam_ref, rtol=0, atol=1e-13)


def test_zero_compliance_distance_holds_its_length_to_round_off():
    """A rigid XPBD rod (alpha = 0) keeps a swinging pendulum's length to round-off at every step."""
    ps = ParticleSystem([[0.0, 0.0], [0.8, -0.6]], m=[1.0, 0.3], forces=[Gravity([0, -G])], pinned=[0])
    solver = XPBD([Distance([[0, 1]], 1.0)], ps.m, ps.pinned, substeps=4)
    t, X = ps.run(3.0, 1 / 60, method=solver)
    lengths = np.linalg.norm(X[:, 1, 0] - X[:, 0, 0], axis=1)
    assert np.abs(lengths - 1.0).max() < 1e-14
    assert max(solver.violation) < 1e-14


def test_one_constraint_is_solved_by_one_iteration():
    """With one constraint the linearized projection is exact along the rod: one pass gives C + alpha~ lambda = 0."""
    x, lam = distance_pass([[0.0, 0.0], [0.0, -1.3]], [0.0, 2.0], [[0, 1]], [1.0], 0.25, [0.0])
    C = np.linalg.norm(x[1] - x[0]) - 1.0
    assert abs(C + 0.25 * lam[0]) < 1e-15 and np.array_equal(x[0], [0.0, 0.0])


def test_jacobi_and_gauss_seidel_converge():
    """Iterated, Jacobi with averaging and Gauss-Seidel both solve C + alpha~ lambda = 0, at nearby positions."""
    c, X = _free_cloth(4)
    ij = c.spring_indices()
    L0 = c.rest_lengths()
    w = np.ones(c.n)
    w[0] = 0.0
    alpha = np.full(len(ij), 0.5)
    results = {}
    for name, groups in (("jacobi", None), ("gauss-seidel", color_constraints(ij, c.n))):
        x, lam = X[:, 0], np.zeros(len(ij))
        for _ in range(3000):
            x, lam = distance_pass(x, w, ij, L0, alpha, lam, groups)
        C = np.linalg.norm(x[ij[:, 0]] - x[ij[:, 1]], axis=1) - L0
        assert np.abs(C + alpha * lam).max() < 1e-12, name
        results[name] = x
    # the nonlinear iterations follow different paths: close, not equal
    assert np.abs(results["jacobi"] - results["gauss-seidel"]).max() < 2e-3 * L0.min()


def test_inputs_are_not_modified():
    """distance_pass and the solvers leave the arrays they are given unchanged."""
    c, X = _free_cloth()
    ij, L0 = c.spring_indices(), c.rest_lengths()
    x0, lam0, X0 = X[:, 0].copy(), np.full(len(ij), 0.01), X.copy()
    lam = lam0.copy()
    distance_pass(X[:, 0], np.ones(c.n), ij, L0, 0.1, lam, color_constraints(ij, c.n))
    for method in ("gauss-seidel", "jacobi"):
        XPBD.from_system(c, method=method, iterations=3)(None, X, 0.0, 0.01)
    assert np.array_equal(X[:, 0], x0) and np.array_equal(lam, lam0) and np.array_equal(X, X0)


def _string_stiffness(X, c):
    """Static stiffness of a hanging string: total weight carried over total stretch."""
    e = np.linalg.norm(X[1:, 0] - X[:-1, 0], axis=1) - c.springs["structural"].rest_length
    carried = G * np.cumsum(c.m[::-1])[::-1][1:]
    return carried.sum() / e.sum()


def test_compliance_is_the_inverse_spring_stiffness():
    """A hanging string of XPBD compliance 1/k rests where the string of springs k rests (k measured)."""
    c = string(12, k=50.0)
    solver = XPBD.from_system(c, substeps=2, iterations=30)
    X = c.state()
    for _ in range(3000):  # until it rests, helped by removing a fifth of the velocities every step
        X = solver(None, X, 0.0, 1 / 60)
        X[:, 1] *= 0.8
        if np.abs(X[:, 1]).max() < 1e-9:
            break
    assert abs(_string_stiffness(X, c) / 50.0 - 1.0) < 1e-6


@pytest.mark.parametrize("method", ["gauss-seidel", "jacobi"])
def test_internal_constraints_conserve_momentum(method):
    """Distance, bending and damped constraints between free particles leave the total momentum unchanged."""
    c, X = _free_cloth()
    triples = np.stack([np.arange(0, 4), np.arange(1, 5), np.arange(2, 6)], axis=1)
    constraints = [Distance(c.spring_indices(), c.rest_lengths(), compliance=1e-3, damping=0.5),
                   IsometricBending(triples, x=c.X[:, 0], compliance=1e-2)]
    m = np.random.default_rng(2).uniform(0.5, 2.0, c.n)
    solver = XPBD(constraints, m, substeps=3, iterations=4, method=method,
                  forces=[])
    X_new = solver(None, X, 0.0, 0.02)
    assert np.allclose(m @ X_new[:, 1], m @ X[:, 1], rtol=0, atol=1e-12)
    assert np.allclose(m @ X_new[:, 0], m @ (X[:, 0] + 0.02 * X[:, 1]), rtol=0, atol=1e-12)


def test_multipliers_give_the_constraint_force():
    """A particle hanging at rest on a soft attachment: lambda / hs^2 is its weight, and it sags m g alpha."""
    m, alpha = 0.2, 1e-3
    c = Attachment([0], [[0.0, 0.0]], compliance=alpha)
    solver = XPBD([c], [m], substeps=2, forces=[Gravity([0.0, -G])])
    X = np.zeros((1, 2, 2))
    for _ in range(400):
        X = solver(None, X, 0.0, 0.01)
        X[:, 1] *= 0.8
    hs = 0.005
    assert abs(X[0, 0, 1] / (-m * G * alpha) - 1.0) < 1e-9
    assert abs(solver.multipliers[0][1, 0] / hs**2 / (m * G) - 1.0) < 1e-9


def test_composes_with_run_and_a_collider():
    """XPBD runs inside ParticleSystem.run and under Collider.stepper: a cloth drapes on a ball, nothing inside."""
    sheet = cloth(10, 10, plane="horizontal", origin=(-0.5, -0.5, 0.45), pins=None, damping=0.01)
    ball = Sphere([0.0, 0.0, 0.0], 0.3)
    collider = Collider(ball, restitution=0.0, friction=0.3, method="project")
    for step in (collider.stepper(XPBD.from_system(sheet, substeps=4), m=sheet.m),
                 XPBD.from_system(sheet, substeps=4, collider=collider)):
        c = cloth(10, 10, plane="horizontal", origin=(-0.5, -0.5, 0.45), pins=None, damping=0.01)
        t, X = c.run(1.0, 1 / 60, method=step)
        assert np.isfinite(X).all() and len(t) == 61
        assert ball.H(X[-1, :, 0]).min() >= -1e-12
        assert (np.abs(ball.H(X[-1, :, 0])) < 1e-3).sum() > 10


def test_pbd_and_a_floor():
    """PBD with a floor collider per substep keeps a falling string above the floor."""
    c = string(8, pin="none", direction=[1.0, 0.0])
    floor = Collider(Plane([0.0, -0.5], [0.0, 1.0]), restitution=0.0)
    t, X = c.run(1.0, 1 / 60, method=PBD.from_system(c, collider=floor, iterations=3))
    assert X[-1, :, 0, 1].min() >= -0.5 - 1e-12


@pytest.mark.parametrize("make, name", [
    (lambda: XPBD([Distance([[0, 1]], 1.0)], [1.0, 1.0], substeps=0), "substeps"),
    (lambda: XPBD([Distance([[0, 1]], 1.0)], [1.0, 1.0], iterations=2.5), "iterations"),
    (lambda: XPBD([Distance([[0, 1]], 1.0)], [1.0, 1.0], method="sor"), "method"),
    (lambda: XPBD([Distance([[0, 1]], 1.0)], [1.0, -1.0]), "m"),
    (lambda: XPBD([Distance([[0, 3]], 1.0)], [1.0, 1.0]), "constraints"),
    (lambda: XPBD(["a spring"], [1.0, 1.0]), "constraints"),
    (lambda: XPBD([Distance([[0, 1]], 1.0)], [1.0, 1.0], collider="floor"), "collider"),
    (lambda: distance_pass([[0.0, 0.0], [1.0, 0.0]], [1.0, -1.0], [[0, 1]], [1.0], 0.0, [0.0]), "w"),
    (lambda: distance_pass([[0.0, 0.0], [1.0, 0.0]], [1.0, 1.0], [[0, 1]], [1.0], 0.0, [0.0, 0.0]), "lam"),
    (lambda: XPBD.from_system(string(4), kinds=["shear"]), "kinds"),
])
def test_bad_input_names_the_argument(make, name):
    """Bad arguments raise ValueError naming the argument."""
    with pytest.raises(ValueError, match=name):
        make()


def test_bad_state_and_step():
    """A state of the wrong shape and a step h <= 0 are refused by name."""
    solver = XPBD([Distance([[0, 1]], 1.0)], [1.0, 1.0])
    with pytest.raises(ValueError, match="X"):
        solver(None, np.zeros((3, 2, 2)), 0.0, 0.01)
    with pytest.raises(ValueError, match="h"):
        solver(None, np.zeros((2, 2, 2)), 0.0, -0.01)
