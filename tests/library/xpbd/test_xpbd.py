"""Position-based dynamics (particles.xpbd, particles.xpbd.constraints): projections, solvers, invariants."""

import numpy as np
import pytest

from particles import Collider, ParticleSystem, backends
from particles.collisions import Plane, Sphere
from particles.forces import Damping, Gravity, Wind
from particles.implicit import relax
from particles.massspring import cloth, hair, string
from particles.xpbd import color_constraints
from particles.studies import pbd
from particles.xpbd import PBD, XPBD, Attachment, Distance, IsometricBending, constraints_from_system, distance_pass

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


# -- projections ----------------------------------------------------------------------------------


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


def test_groups_share_no_particle_and_cover_every_row():
    """Every colour group of pairs and triples is independent, and the groups cover each row once."""
    c = cloth(8, 8)
    for idx in (c.spring_indices(), np.stack([np.arange(40), np.arange(1, 41), np.arange(2, 42)], axis=1)):
        groups = color_constraints(idx, 64)
        assert np.array_equal(np.sort(np.concatenate(groups)), np.arange(len(idx)))
        for g in groups:
            used = idx[g].ravel()
            assert len(np.unique(used)) == len(used)


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


# -- the physics ------------------------------------------------------------------------------------


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


def test_xpbd_stiffness_does_not_depend_on_iterations_pbd_does():
    """On lecture 7's curtain XPBD's effective stiffness varies < 5% from 1 to 50 iterations, PBD's > 2x."""
    study = pbd.stiffness_study(iterations=(1, 50), steps=())
    xpbd, pbd_k = study["by_iterations"]["xpbd"], study["by_iterations"]["pbd"]
    assert max(xpbd) / min(xpbd) < 1.05 and all(abs(k / 30.0 - 1.0) < 0.05 for k in xpbd)
    assert pbd_k[1] / pbd_k[0] > 2.0


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


def test_isometric_bending_holds_a_hair_like_the_bending_force():
    """A clamped hair with isometric bending of compliance 1/kb droops as the spring hair with Bending kb."""
    h = hair(12, kb=0.002, k=2000.0)
    springs = hair(12, kb=0.002, k=2000.0)
    relax(springs, h=0.05)
    solver = XPBD.from_system(h, substeps=20)
    X = h.state()
    for _ in range(240):
        X = solver(None, X, 0.0, 1 / 60)
        X[:, 1] *= 0.7
    droop, droop_springs = -X[-1, 0, 1], -springs.X[-1, 0, 1]
    assert droop > 0.01 and abs(droop / droop_springs - 1.0) < 0.05


def test_straight_bending_at_rest_stays_at_rest():
    """A straight hair without gravity under isometric bending stays at rest (no chatter at theta = 0)."""
    h = hair(8, gravity=0.0)
    solver = XPBD.from_system(h, iterations=5)
    t, X = h.run(1.0, 1 / 60, method=solver)
    assert np.abs(X[-1] - X[0]).max() < 1e-15


def test_xpbd_damping_removes_relative_motion():
    """Constraint damping kd (Macklin et al. eq. 26) takes energy out of a bouncing string; kd = 0 keeps more."""
    energies = []
    for kd in (0.0, 0.5):
        c = string(10, k=50.0, kd=kd)
        c.run(1.0, 1 / 60, method=XPBD.from_system(c, substeps=10))
        energies.append(c.kinetic_energy() + c.potential_energy())
    assert energies[1] < energies[0]


# -- composition ------------------------------------------------------------------------------------


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


# -- bad input --------------------------------------------------------------------------------------


@pytest.mark.parametrize("make, name", [
    (lambda: XPBD([Distance([[0, 1]], 1.0)], [1.0, 1.0], substeps=0), "substeps"),
    (lambda: XPBD([Distance([[0, 1]], 1.0)], [1.0, 1.0], iterations=2.5), "iterations"),
    (lambda: XPBD([Distance([[0, 1]], 1.0)], [1.0, 1.0], method="sor"), "method"),
    (lambda: XPBD([Distance([[0, 1]], 1.0)], [1.0, -1.0]), "m"),
    (lambda: XPBD([Distance([[0, 3]], 1.0)], [1.0, 1.0]), "constraints"),
    (lambda: XPBD(["a spring"], [1.0, 1.0]), "constraints"),
    (lambda: XPBD([Distance([[0, 1]], 1.0)], [1.0, 1.0], collider="floor"), "collider"),
    (lambda: Distance([[0, 1]], 1.0, compliance=-1.0), "compliance"),
    (lambda: Distance([[0, 1]], 1.0, stiffness=1.5), "stiffness"),
    (lambda: Distance([[0, 1]], 1.0, damping=-0.1), "damping"),
    (lambda: Distance([[0, 0]], 1.0), "indices"),
    (lambda: Distance([[0, 1, 2]], 1.0), "indices"),
    (lambda: Distance([[0, 1]]), "rest_length"),
    (lambda: Distance([[0, 1], [1, 2]], 1.0, groups=[[0, 1]]), "groups"),
    (lambda: Distance([[0, 1], [1, 2]], 1.0, groups=[[0]]), "groups"),
    (lambda: IsometricBending([[0, 1, 2]], rest_lengths=[[1.0, 0.0]]), "rest_lengths"),
    (lambda: Attachment([0, 1], [[0.0, 0.0]]), "targets"),
    (lambda: distance_pass([[0.0, 0.0], [1.0, 0.0]], [1.0, -1.0], [[0, 1]], [1.0], 0.0, [0.0]), "w"),
    (lambda: distance_pass([[0.0, 0.0], [1.0, 0.0]], [1.0, 1.0], [[0, 1]], [1.0], 0.0, [0.0, 0.0]), "lam"),
    (lambda: XPBD.from_system(string(4), kinds=["shear"]), "kinds"),
    (lambda: pbd.effective_stiffness(10.0, pbd.spring_sags([30.0, 60.0], n=4)), "sag"),
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


# -- the compiled substep (particles.backends.xpbdstep) -----------------------------------------------

needs_numba = pytest.mark.skipif("numba" not in backends.available(),
                                 reason="numba is not installed (pip install 'particles[fast]')")


def _rigid_cloth():
    """A 12^2 curtain of rigid rods (compliance 0), pinned at its top corners, under gravity alone."""
    c = cloth(12, 12)
    return c, lambda **o: XPBD([Distance(c.spring_indices(), c.rest_lengths())], c.m, c.pinned,
                               forces=[Gravity([0.0, 0.0, -G])], **o)


def _hair_and_attachment():
    """A 2D hair (distance, isometric bending, clamp) whose tip is also held softly to a point."""
    h = hair(10, kd=0.2)
    constraints, converted = constraints_from_system(h)
    constraints.append(Attachment([9], [[0.25, -0.05]], compliance=1e-3, damping=0.1))
    forces = [f for f in h.forces if f not in converted]
    return h, lambda **o: XPBD(constraints, h.m, h.pinned, forces=forces, **o)


def _ball_sheet():
    """A falling 10^2 sheet with air damping, caught by a ball (a collider at every substep)."""
    c = cloth(10, 10, plane="horizontal", origin=(-0.5, -0.5, 0.35), pins=None, damping=0.05)
    ball = Collider(Sphere([0.0, 0.0, 0.0], 0.3), restitution=0.0, friction=0.3, method="project")
    return c, lambda **o: XPBD.from_system(c, collider=ball, **o)


def _string_with(*forces):
    """A 3D string of 12 particles pinned at one end, its springs as constraints, with these external forces."""
    c = string(12, d=3, direction=[1.0, 0.0, 0.0], kd=0.1)
    constraints, _ = constraints_from_system(c)
    return c, lambda **o: XPBD(constraints, c.m, c.pinned, forces=[Gravity([0.0, 0.0, -G]), *forces], **o)


COMPILED_CASES = {
    "string, damping d": lambda: _string_with(Damping(d=0.002)),
    "string, damping, wind (NumPy forces)": lambda: _string_with(Damping(rate=0.5), Wind([0.3, 0.2, 0.0], gust=0.5)),
    "cloth, pins, damped, compliance 1/k": lambda: (lambda c: (c, lambda **o: XPBD.from_system(c, **o)))(
        cloth(12, 12, kd=0.3)),
    "cloth, compliance 0": _rigid_cloth,
    "cloth, bending, air damping": lambda: (lambda c: (c, lambda **o: XPBD.from_system(c, **o)))(
        cloth(10, 10, scaling="physical", bending_modulus=1e-4, damping=0.05, kd=0.01)),
    "hair, clamp, attachment (2D)": _hair_and_attachment,
    "cloth, PBD": lambda: (lambda c: (c, lambda **o: PBD.from_system(c, **o).set_stiffness(0.7)))(cloth(12, 12)),
    "sheet on a ball (collider)": _ball_sheet,
}


def _count_compiled_substeps(monkeypatch):
    """Count the calls of CompiledSubstep.substep (one per compiled substep)."""
    from particles.backends import xpbdstep

    calls = []
    original = xpbdstep.CompiledSubstep.substep

    def counted(self, *args, **options):
        calls.append(1)
        return original(self, *args, **options)

    monkeypatch.setattr(xpbdstep.CompiledSubstep, "substep", counted)
    return calls


def _run_both(make, steps=12, h=1 / 60, **options):
    """The final state, the multipliers and the violations of a run on NumPy and on numba."""
    out = []
    for backend in ("numpy", "numba"):
        c, build = make()
        solver = build(backend=backend, **options)
        t, X = c.run(steps * h, h, method=solver)
        out.append((X[-1], solver.multipliers, solver.violation))
    return out


def _agree(a, b, rtol=1e-12):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape
    assert np.abs(a - b).max(initial=0.0) <= rtol * max(np.abs(a).max(initial=0.0), 1e-300)


@needs_numba
@pytest.mark.parametrize("case", list(COMPILED_CASES))
def test_the_compiled_substep_agrees_with_numpy(case, monkeypatch):
    """One compiled call per substep: positions, velocities, multipliers and violations as NumPy's to 1e-12."""
    calls = _count_compiled_substeps(monkeypatch)
    (X_np, lam_np, viol_np), (X_nb, lam_nb, viol_nb) = _run_both(COMPILED_CASES[case], substeps=3, iterations=2)
    assert len(calls) == 12 * 3
    _agree(X_np[:, 0], X_nb[:, 0])
    _agree(X_np[:, 1], X_nb[:, 1])
    assert len(lam_np) == len(lam_nb)
    for a, b in zip(lam_np, lam_nb):  # a loop over the constraint sets
        _agree(a, b)
    _agree(viol_np, viol_nb)
    assert np.abs(X_nb[:, 1]).max() > 0.01  # it moved


@needs_numba
def test_the_compiled_substep_takes_f_when_the_solver_has_no_forces(monkeypatch):
    """A solver without forces of its own takes the accelerations from f (the system's derivative), compiled too."""
    calls = _count_compiled_substeps(monkeypatch)
    out = []
    for backend in ("numpy", "numba"):
        ps = ParticleSystem([[0.0, 0.0], [0.8, -0.6], [1.5, -1.0]], m=[1.0, 0.3, 0.5], forces=[Gravity([0, -G])],
                            pinned=[0])
        solver = XPBD([Distance([[0, 1], [1, 2]], [1.0, 0.8], compliance=[0.0, 1e-3])], ps.m, ps.pinned,
                      substeps=4, iterations=3, backend=backend)
        out.append(ps.run(1.0, 1 / 60, method=solver)[1][-1])
    assert len(calls) == 60 * 4
    _agree(out[0], out[1])


@needs_numba
def test_kinds_without_a_compiled_form_and_jacobi_fall_back(monkeypatch):
    """A set with its own projection, and the Jacobi method, take the per-pass path, still as NumPy's."""
    class Halved(Distance):
        def project(self, b, x, x_n, lam, hs, formulation):
            """Distance.project, as a subclass of its own."""
            return Distance.project(self, b, x, x_n, lam, hs, formulation)

    calls = _count_compiled_substeps(monkeypatch)
    for method, kind in (("gauss-seidel", Halved), ("jacobi", Distance)):
        out = []
        for backend in ("numpy", "numba"):
            c = cloth(8, 8)
            solver = XPBD([kind(c.spring_indices(), c.rest_lengths(), compliance=1e-4)], c.m, c.pinned,
                          forces=[Gravity([0.0, 0.0, -G])], substeps=2, iterations=2, method=method,
                          backend=backend)
            out.append(c.run(0.2, 1 / 60, method=solver)[1][-1])
        _agree(out[0], out[1])
    assert calls == []
    assert Halved([[0, 1]], 1.0).compiled_form is None and Distance([[0, 1]], 1.0).compiled_form == "distance"


@needs_numba
def test_a_new_stiffness_takes_a_new_layout():
    """PBD's set_stiffness between steps rebuilds the batches; the compiled substep follows."""
    out = []
    for backend in ("numpy", "numba"):
        c = cloth(8, 8)
        solver = PBD.from_system(c, substeps=2, iterations=3, backend=backend)
        X = c.state()
        for k in (1.0, 0.3):  # a loop over two stiffnesses, a few steps each
            solver.set_stiffness(k)
            for _ in range(5):
                X = solver(None, X, 0.0, 1 / 60)
        out.append(X)
    _agree(out[0], out[1])


@needs_numba
def test_the_compiled_substep_has_the_same_bits_on_any_number_of_threads(monkeypatch):
    """Every colour group in parallel on one thread, on two, and no parallel loop at all: the same bits."""
    import numba

    from particles.backends import _kernels

    results = []
    before = numba.get_num_threads()
    try:
        for threads, parallel_min in ((1, 0), (min(2, numba.config.NUMBA_NUM_THREADS), 0), (1, 10**9)):
            monkeypatch.setattr(_kernels, "PARALLEL_MIN", parallel_min)  # 0: every loop parallel; 10**9: none
            numba.set_num_threads(threads)
            X, lams, violation = _run_both(COMPILED_CASES["cloth, bending, air damping"], steps=4, substeps=2,
                                           iterations=2)[1]
            results.append([X] + list(lams) + [np.array(violation)])
    finally:
        numba.set_num_threads(before)
    for runs in zip(*results):  # a loop over the quantities: each the same in the three runs
        for other in runs[1:]:
            np.testing.assert_array_equal(other, runs[0])
