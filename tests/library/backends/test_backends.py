"""The backends: the compiled kernels agree with the NumPy reference, and the switch does what it says.

The whole force contract (``tests/library/forces/test_force_contract.py``) runs
again with the numba backend forced for every object, and every force of it
is compared between the two backends to 1e-12 relative; larger problems
(a cloth, a Lennard-Jones liquid, XPBD sweeps, N-body) are compared too, and
repeated with one and two threads for determinism. Tests that need numba are
skipped when the extra ``[fast]`` is not installed.
"""

import os
import subprocess
import sys

import numpy as np
import pytest

from particles import backends
from particles.collisions import Box, Collider, Cylinder, Plane, Sphere
from particles.constraints import ProvotConstraint
from particles.forces import LennardJones, NBodyGravity
from particles.integrators import symplectic_euler
from particles.md import fcc_lattice
from particles.massspring import cloth, hair, string
from particles.springs import Bending, Springs
from particles.xpbd import PBD, XPBD, distance_pass

from ..forces import test_force_contract as contract

needs_numba = pytest.mark.skipif("numba" not in backends.available(),
                                 reason="numba is not installed (pip install 'particles[fast]')")

BACKEND_NAMES = [pytest.param("numpy"), pytest.param("numba", marks=needs_numba)]


def _close(a, b, rtol=1e-12):
    """Arrays equal to `rtol` relative to their largest entry."""
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape
    assert np.abs(a - b).max(initial=0.0) <= rtol * max(np.abs(a).max(initial=0.0), 1e-300)


# the force contract, run again with every object on the backend
CONTRACT = [contract.test_inputs_are_not_modified, contract.test_add_to_adds_in_place_with_the_right_shape_and_dtype,
            contract.test_forces_between_particles_conserve_momentum,
            contract.test_force_is_minus_the_gradient_of_its_potential_energy,
            contract.test_declared_independence_of_velocity_and_time_holds]


def _contract_params():
    out = []
    for check in CONTRACT:  # each check of the contract, on the cases it applies to
        chosen = [m for m in check.pytestmark if m.name == "parametrize"][0].args[1]
        out += [pytest.param(check, *p.values, id=f"{check.__name__[5:]}-{p.id}") for p in chosen]
    return out


@pytest.mark.parametrize("backend", BACKEND_NAMES)
@pytest.mark.parametrize("check, case, d", _contract_params())
def test_the_force_contract_holds_on_each_backend(check, case, d, backend):
    """Every check of the force contract passes with every object on this backend."""
    with backends.using(backend):
        check(case, d)


@needs_numba
@pytest.mark.parametrize("case, d", contract._params())
def test_numba_forces_agree_with_numpy_on_every_contract_case(case, d):
    """Each contract force on numba equals its NumPy value to 1e-12 relative (with velocities and masses)."""
    x, v, m, t = contract._state(d)
    out = {}
    for backend in ("numpy", "numba"):
        with backends.using(backend):
            force = case.make(x)
            out[backend] = force(x, v, t, m), getattr(force, "last_virial", 0.0)
    _close(out["numpy"][0], out["numba"][0])
    assert out["numba"][1] == pytest.approx(out["numpy"][1], rel=1e-12, abs=1e-300)


def _cloth_state(n, seed=0):
    c = cloth(n, n, kd=0.05)
    X = c.state()
    rng = np.random.default_rng(seed)
    X[:, 0] += rng.normal(scale=0.05 / n, size=X[:, 0].shape)
    X[:, 1] = rng.normal(scale=0.1, size=X[:, 1].shape)
    return c, X


@needs_numba
def test_a_cloth_step_agrees_and_is_the_same_every_time():
    """A 40^2 cloth (4.6k damped springs): the derivative agrees to 1e-12, repeated calls give the same bits."""
    c, X = _cloth_state(40)
    with backends.using("numpy"):
        reference = c.derivative(X, 0.0)
    with backends.using("numba"):
        first = c.derivative(X, 0.0)
        np.testing.assert_array_equal(c.derivative(X, 0.0), first)
    _close(reference, first)


def _liquid(cells=(6, 6, 6), seed=1):
    x, box = fcc_lattice(cells, 0.86)
    return x + np.random.default_rng(seed).uniform(-0.1, 0.1, x.shape), box


@needs_numba
@pytest.mark.parametrize("periodic", [True, False], ids=["periodic", "open"])
def test_lennard_jones_on_a_liquid_agrees_with_numpy(periodic):
    """864 particles at rho* = 0.86 (about 34k listed pairs): forces to 1e-12, the virial to 1e-12."""
    x, box = _liquid()
    out = {}
    for backend in ("numpy", "numba"):
        lj = LennardJones.from_epsilon_sigma(skin=0.3, box=box if periodic else None, backend=backend)
        out[backend] = lj(x), lj.last_virial
    _close(out["numpy"][0], out["numba"][0])
    assert out["numba"][1] == pytest.approx(out["numpy"][1], rel=1e-12)


@needs_numba
def test_lennard_jones_follows_its_list_when_particles_move():
    """Across list rebuilds (particles moving, unwrapped positions leaving the box) both backends agree."""
    x, box = _liquid(seed=3)
    lj = {b: LennardJones.from_epsilon_sigma(skin=0.2, box=box, backend=b) for b in ("numpy", "numba")}
    rng = np.random.default_rng(4)
    for _ in range(4):  # a loop over moves: some reuse the list, some rebuild it
        x = x + rng.normal(scale=0.06, size=x.shape) + np.array([0.5, 0.0, 0.0]) * box
        _close(lj["numpy"](x), lj["numba"](x))
    assert lj["numba"].neighbor_list.builds == lj["numpy"].neighbor_list.builds > 1


@needs_numba
@pytest.mark.parametrize("d", [2, 3])
def test_nbody_and_bending_agree_with_numpy(d):
    """N-body gravity (300 particles) and a long chain's bending agree to 1e-12."""
    rng = np.random.default_rng(5)
    x, m = rng.normal(size=(300, d)), rng.uniform(0.5, 2.0, 300)
    triples = np.stack([np.arange(298), np.arange(1, 299), np.arange(2, 300)], axis=1)
    kb = rng.uniform(0.5, 1.0, 298)
    for make in (lambda b: NBodyGravity(G=2.0, softening=0.05, backend=b),
                 lambda b: Bending(triples, kb=kb, rest_angle=0.2, backend=b)):
        _close(make("numpy")(x, m=m), make("numba")(x, m=m))


@needs_numba
@pytest.mark.parametrize("solver", [XPBD, PBD])
@pytest.mark.parametrize("method", ["gauss-seidel", "jacobi"])
@pytest.mark.parametrize("kd", [0.0, 0.3], ids=["undamped", "damped"])
def test_xpbd_and_pbd_runs_agree_with_numpy(solver, method, kd):
    """Half a second of a 12^2 cloth and of a hair (bending, clamp), 4 substeps x 2 iterations: same positions."""
    for build in (lambda: cloth(12, 12, kd=kd), lambda: hair(10, kd=kd)):
        out = []
        for backend in ("numpy", "numba"):
            c = build()
            step = solver.from_system(c, substeps=4, iterations=2, method=method, backend=backend)
            out.append(c.run(0.5, 1 / 60, method=step)[1][-1])
        _close(out[0], out[1])


@needs_numba
def test_distance_pass_agrees_with_numpy_with_given_groups():
    """distance_pass with colour groups given as lists of rows, and as one Jacobi pass, on both backends."""
    rng = np.random.default_rng(6)
    x = rng.normal(size=(6, 3))
    ij = [[0, 1], [2, 3], [1, 2], [3, 4], [4, 5]]
    w = np.array([0.0, 1.0, 0.5, 2.0, 1.0, 1.0])
    for groups in ([[0, 1, 4], [2, 3]], None):
        out = [distance_pass(x, w, ij, 1.0, 0.01, np.zeros(5), groups=groups, backend=b) for b in ("numpy", "numba")]
        _close(out[0][0], out[1][0])
        _close(out[0][1], out[1][1])


@needs_numba
def test_results_do_not_depend_on_the_number_of_threads(monkeypatch):
    """Springs, bending, Lennard-Jones, N-body and XPBD: the same bits on one thread, on two, and serial.

    (For springs the serial form is a one-pass scatter, the parallel one forces per spring then a gather.)
    """
    import numba

    from particles.backends import _kernels, compiled

    c, X = _cloth_state(32)
    x, box = _liquid()
    rng = np.random.default_rng(7)
    xn, m = rng.normal(size=(200, 3)), rng.uniform(0.5, 2.0, 200)
    chain = np.stack([np.arange(198), np.arange(1, 199), np.arange(2, 200)], axis=1)
    results = []
    before = numba.get_num_threads()
    try:
        for threads, parallel_min in ((1, 0), (min(2, numba.config.NUMBA_NUM_THREADS), 0), (1, 10**9)):
            monkeypatch.setattr(_kernels, "PARALLEL_MIN", parallel_min)  # 0: every loop parallel; 10**9: none
            monkeypatch.setattr(compiled, "SPRING_THREADS", 1)  # springs too: the two-pass form, then one pass
            numba.set_num_threads(threads)
            with backends.using("numba"):
                lj = LennardJones.from_epsilon_sigma(skin=0.3, box=box)
                xpbd = XPBD.from_system(_cloth_state(32)[0], substeps=2)
                results.append([c.derivative(X, 0.0), lj(x), np.array(lj.last_virial), xpbd(None, X, 0.0, 0.01),
                                NBodyGravity()(xn, m=m), Bending(chain, kb=0.5)(xn)])
    finally:
        numba.set_num_threads(before)
    for runs in zip(*results):  # a loop over the quantities: each the same in the three runs
        for other in runs[1:]:
            np.testing.assert_array_equal(other, runs[0])


def _provot_runs(method, outer, inner="numpy", seconds=0.3):
    """A soft 16^2 curtain under Provot's constraint: end states and histories with the projection on each backend.

    `inner` is the backend of the rest of the run (the step); `outer` the projection's backends to compare.
    """
    out = {}
    for backend in outer:
        c = cloth(16, 16, k_structural=5.0, kd=0.01)
        with backends.using(inner):
            provot = ProvotConstraint.from_system(c, method=method, backend=backend)
            X = c.run(seconds, 2e-3, method=provot.stepper("symplectic_euler"))[1][-1]
        out[backend] = X, [(r.iterations, r.max_strain, r.converged) for r in provot.history]
    return out


@needs_numba
@pytest.mark.parametrize("method", ["jacobi", "gauss-seidel"])
def test_compiled_provot_projection_agrees_with_numpy(method):
    """Provot's pass compiled, 150 steps of a soft curtain (thousands of passes): the same bits, the same passes."""
    out = _provot_runs(method, ("numpy", "numba"))
    (X_np, history_np), (X_nb, history_nb) = out["numpy"], out["numba"]
    assert sum(passes for passes, _, _ in history_np) > 1000
    assert history_nb == history_np
    np.testing.assert_array_equal(X_nb, X_np)


@needs_numba
@pytest.mark.parametrize("method", ["jacobi", "gauss-seidel"])
def test_compiled_provot_around_the_compiled_step_agrees_with_numpy(method):
    """On the compiled step's C-ordered states, in place: NumPy's bits; and the NumPy run's to 1e-12 for 20 steps.

    The number of passes is a verdict on a threshold (the largest strain
    against ``max_strain + tol``): the compiled step's states, a rounding
    error from NumPy's, can take one more pass, and from then on the runs
    part (at step 34 of this one); the projection itself is the same.
    """
    on_compiled = _provot_runs(method, ("numpy", "numba"), inner="numba", seconds=0.1)
    np.testing.assert_array_equal(on_compiled["numba"][0], on_compiled["numpy"][0])
    assert on_compiled["numba"][1] == on_compiled["numpy"][1]
    numpy_run = _provot_runs(method, ("numpy",), inner="numpy", seconds=0.04)["numpy"]
    compiled_run = _provot_runs(method, ("numba",), inner="numba", seconds=0.04)["numba"]
    _close(numpy_run[0], compiled_run[0])
    assert [p for p, _, _ in numpy_run[1]] == [p for p, _, _ in compiled_run[1]]


def _falling_sheet(n=10, d=3):
    """A small horizontal sheet (3D) or a string lying along x (2D), falling at 1 m/s from z = 0 (or y = 0)."""
    if d == 3:
        c = cloth(n, n, plane="horizontal", pins=None, origin=(-0.45, -0.45, 0.0), kd=0.01)
    else:
        c = string(n, 0.9, pin="none", direction=[1.0, 0.0], kd=0.01)
        X = c.state()
        X[:, 0, 0] -= 0.45
        c.set_state(X)
    X = c.state()
    X[:, 1, -1] = -1.0
    c.set_state(X)
    return c


SURFACES = [
    ("sphere", lambda d: Sphere(np.eye(d)[-1] * -0.3, 0.25)),
    ("sphere container", lambda d: Sphere(np.zeros(d), 0.6, container=True)),
    ("tilted plane", lambda d: Plane(np.eye(d)[-1] * -0.1, np.eye(d)[-1] + 0.3 * np.eye(d)[0])),
    ("box", lambda d: Box(-0.3 * np.ones(d) - 0.1 * np.eye(d)[-1], 0.3 * np.ones(d) - 0.5 * np.eye(d)[-1])),
    ("box container", lambda d: Box(-0.5 * np.ones(d) + 0.2 * np.eye(d)[-1], 0.5 * np.ones(d), container=True)),
    ("cylinder", lambda d: Cylinder([0.0, 0.0, -0.3], [1.0, 0.2, 0.1], 0.2) if d == 3 else None),
]


def _surface_params():
    out = []
    for name, make in SURFACES:  # each surface in 2D and 3D (a cylinder only in 3D), both methods
        for d in (2, 3):
            if make(d) is None:
                continue
            for method in ("backtrack", "project"):
                out.append(pytest.param(make, d, method, id=f"{name}-{d}D-{method}"))
    return out


def _collider_runs(make, d, method, friction=0.3, steps=250, inner="numpy", outer=("numpy", "numba")):
    """The falling sheet on the surface, the collider on each backend of `outer` around a step on `inner`."""
    out = {}
    for backend in outer:
        c = _falling_sheet(d=d)
        collider = Collider(make(d), restitution=0.3, friction=friction, method=method, backend=backend)
        with backends.using(inner):
            step = collider.stepper("symplectic_euler", m=c.m, pinned=c.pinned)
            found = []
            X = c.run(steps * 2e-3, 2e-3, method=step, between_steps=lambda system, t0: found.append(step.contacts))
        out[backend] = X[1][-1], found
    return out


@needs_numba
@pytest.mark.parametrize("make, d, method", _surface_params())
def test_compiled_collider_finds_the_same_contacts_as_numpy(make, d, method):
    """Planes, spheres, boxes, cylinders (solid, containers), 2D and 3D, both fixes: NumPy's bits.

    At each of 250 steps of a NumPy run (a sheet, or a string, falling onto
    the surface, bouncing with friction, then resting on it), the compiled
    fix and NumPy's fix of the same states: the same contacts (particles, in
    order, times, points, normals, impulses) and the same fixed states, to
    the last bit. Both sum each dot product in coordinate order
    (``particles._vectors.rowdot``), so that even the rounding verdicts of
    resting contact (whether a bounce ends a rounding error inside) agree.
    """
    from particles.backends import compiled

    c = _falling_sheet(d=d)
    collider = Collider(make(d), restitution=0.3, friction=0.3, method=method)
    h, X = 2e-3, c.state()
    free = np.ones(c.n, dtype=bool)
    count = 0
    with backends.using("numpy"):
        for k in range(250):  # a loop over the steps of the run
            X_new = symplectic_euler(c.derivative, X, k * h, h)
            fixed, contacts = collider.collide(X, X_new, k * h, h, m=c.m)
            mine = X_new.copy()
            index, *columns = compiled.collide(collider, X, mine, k * h, h, np.ascontiguousarray(c.m), free)
            np.testing.assert_array_equal(index, contacts.index)
            for field, got in zip(("time", "point", "normal", "impulse", "friction"), columns):
                np.testing.assert_array_equal(got, getattr(contacts, field))
            np.testing.assert_array_equal(mine, fixed)
            count += len(index)
            X = fixed
    assert count > 400  # the sheet meets the surface


@needs_numba
@pytest.mark.parametrize("d", [2, 3])
def test_a_run_with_the_compiled_collider_is_the_numpy_run(d):
    """The stepper's compiled fix, in place on NumPy steps, 250 steps on a sphere: the same contacts and bits."""
    out = _collider_runs(SURFACES[0][1], d, "backtrack")
    (X_np, found_np), (X_nb, found_nb) = out["numpy"], out["numba"]
    assert sum(len(f) for f in found_np) > 400
    for a, b in zip(found_np, found_nb):  # a loop over the steps
        np.testing.assert_array_equal(a.index, b.index)
        np.testing.assert_array_equal(a.impulse, b.impulse)
    np.testing.assert_array_equal(X_np, X_nb)


@needs_numba
def test_the_compiled_step_and_collider_together_agree_with_numpy():
    """The compiled step with the compiled collider, 40 steps onto a sphere: the same contacts, states to 1e-9.

    The compiled step's states are a rounding error from NumPy's (fused
    multiply-adds), and the crossing times are found to a tolerance
    (``|H| <= 1e-12`` m): two such states may end a bounce that far apart.
    """
    make = SURFACES[0][1]
    numpy_run = _collider_runs(make, 3, "backtrack", steps=40, inner="numpy", outer=("numpy",))["numpy"]
    compiled_run = _collider_runs(make, 3, "backtrack", steps=40, inner="numba", outer=("numba",))["numba"]
    assert sum(len(f) for f in numpy_run[1]) > 100
    for a, b in zip(numpy_run[1], compiled_run[1]):  # a loop over the steps
        np.testing.assert_array_equal(a.index, b.index)
    _close(numpy_run[0], compiled_run[0], rtol=1e-9)


@needs_numba
def test_a_combined_surface_stays_on_numpy():
    """A union of two spheres has no compiled form: the fix is NumPy's, with the same bits."""
    union = lambda d: Sphere([0.0, 0.0, -0.3], 0.25) | Sphere([0.3, 0.0, -0.3], 0.2)  # noqa: E731
    out = _collider_runs(union, 3, "backtrack", steps=60)
    np.testing.assert_array_equal(out["numpy"][0], out["numba"][0])


@needs_numba
def test_the_compiled_step_and_collider_together_agree_with_numpy():
    """The compiled step with the compiled collider, 40 steps onto a sphere: the same contacts, states to 1e-9.

    (The crossing times are found to a tolerance, ``|H| <= 1e-12``: two
    states a rounding error apart may end a bounce that far apart.)
    """
    make = SURFACES[0][1]
    numpy_run = _collider_runs(make, 3, "backtrack", steps=40, inner="numpy", outer=("numpy",))["numpy"]
    compiled_run = _collider_runs(make, 3, "backtrack", steps=40, inner="numba", outer=("numba",))["numba"]
    for a, b in zip(numpy_run[1], compiled_run[1]):  # a loop over the steps
        np.testing.assert_array_equal(a.index, b.index)
    _close(numpy_run[0], compiled_run[0], rtol=1e-9)


@needs_numba
def test_compiled_fixes_have_the_same_bits_on_any_number_of_threads(monkeypatch):
    """Provot's passes and the collider: one thread, two threads and the serial kernels give the same bits."""
    import numba

    from particles.backends import _kernels

    results = []
    before = numba.get_num_threads()
    try:
        for threads, parallel_min in ((1, 0), (min(2, numba.config.NUMBA_NUM_THREADS), 0), (1, 10**9)):
            monkeypatch.setattr(_kernels, "PARALLEL_MIN", parallel_min)  # 0: every loop parallel; 10**9: none
            numba.set_num_threads(threads)
            results.append([_provot_runs(m, ("numba",), seconds=0.1)["numba"][0] for m in ("jacobi", "gauss-seidel")]
                           + [_collider_runs(SURFACES[0][1], 3, "backtrack", steps=60, outer=("numba",))["numba"][0]])
    finally:
        numba.set_num_threads(before)
    for runs in zip(*results):  # a loop over the quantities: each the same in the three runs
        for other in runs[1:]:
            np.testing.assert_array_equal(other, runs[0])


def test_import_particles_does_not_import_numba():
    """numba is loaded only by a force pass that uses it, never by ``import particles`` or the NumPy backend."""
    code = ("import sys, numpy as np, particles; from particles.springs import Springs; "
            "Springs([[0, 1]], 1.0, k=2.0)(np.array([[0.0, 0.0], [2.0, 0.0]])); print('numba' in sys.modules)")
    env = dict(os.environ, PARTICLES_BACKEND="numpy")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert done.stdout.strip() == "False"


def test_auto_is_numpy_for_small_problems_and_under_particles_backend_numpy(monkeypatch):
    """"auto" compiles only from AUTO_MIN particles, never with PARTICLES_BACKEND=numpy or NUMBA_DISABLE_JIT=1."""
    monkeypatch.delenv("PARTICLES_BACKEND", raising=False)
    monkeypatch.delenv("NUMBA_DISABLE_JIT", raising=False)
    assert backends.resolve("auto", backends.AUTO_MIN - 1) == "numpy"
    assert backends.resolve("numpy", 10**9) == "numpy"
    expected = "numba" if "numba" in backends.available() else "numpy"
    assert backends.resolve("auto", backends.AUTO_MIN) == expected
    monkeypatch.setenv("NUMBA_DISABLE_JIT", "1")  # as in the grader's workers
    assert backends.resolve(None, 10**9) == backends.resolve("auto", 10**9) == "numpy"
    monkeypatch.delenv("NUMBA_DISABLE_JIT")
    monkeypatch.setenv("PARTICLES_BACKEND", "numpy")
    assert backends.get_backend() == "numpy"
    assert backends.resolve(None, 10**9) == backends.resolve("auto", 10**9) == "numpy"


def test_the_grader_workers_never_compile():
    """The worker's environment turns 'auto' into NumPy (no numba, no cache in the sandbox)."""
    import inspect

    from particles.course.worker import process

    assert '"NUMBA_DISABLE_JIT": "1"' in inspect.getsource(process.Worker)


@needs_numba
def test_auto_falls_back_to_numpy_when_numba_cannot_load(monkeypatch):
    """With numba unusable, 'auto' warns and uses NumPy from then on; an explicit 'numba' raises."""
    monkeypatch.delattr(backends, "compiled", raising=False)
    monkeypatch.setitem(sys.modules, "particles.backends.compiled", None)  # importing it now fails
    monkeypatch.setitem(backends._state, "broken", False)
    with pytest.warns(RuntimeWarning, match="numba could not be loaded"):
        assert backends.kernels_for("auto", 10**6) is None
    assert backends.resolve("auto", 10**6) == "numpy"
    with pytest.raises(ImportError):
        backends.kernels_for("numba", 10)


def test_the_global_switch_applies_to_objects_built_before_it():
    """``using`` sets the choice of objects with backend=None for the block, and restores it after."""
    before = backends.get_backend()
    with backends.using("numpy"):
        assert backends.resolve(None, 10**9) == "numpy"
        assert backends.resolve("auto", 10) == "numpy"
    assert backends.get_backend() == before


def test_bad_backends_are_refused_with_a_clear_message(monkeypatch):
    """An unknown name names the argument; 'numba' without numba names the extra to install."""
    with pytest.raises(ValueError, match="backend must be 'numpy', 'numba', 'auto' or None, got 'cuda'"):
        Springs([[0, 1]], 1.0, backend="cuda")
    with pytest.raises(ValueError, match="PARTICLES_BACKEND"):
        monkeypatch.setenv("PARTICLES_BACKEND", "fast")
        backends.get_backend()
    monkeypatch.delenv("PARTICLES_BACKEND")
    monkeypatch.setitem(backends._state, "numba", False)
    assert backends.available() == ("numpy",)
    with pytest.raises(ValueError, match=r"pip install 'particles\[fast\]'"):
        LennardJones.from_epsilon_sigma(backend="numba")
    assert backends.resolve("auto", 10**9) == "numpy"
