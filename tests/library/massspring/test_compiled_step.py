"""The compiled symplectic Euler step of a mass-spring system (particles.massspring.compiled_step).

With the springs on numba, a :class:`~particles.massspring.MassSpringSystem`'s
runs of symplectic Euler (:meth:`~particles.massspring.MassSpringSystem.stepper`:
alone or inside a wrapper such as Provot's constraint) take the whole step in
one compiled pass; the generic :func:`~particles.integrators.symplectic_euler`
stays the NumPy reference. These tests compare its runs with the NumPy runs
(1e-12 relative) on cloths, strings and hair, with every kind of force beside
the springs, with blocks small enough that springs cross several of them, and
check that it follows what the user changes between steps (stiffness in place,
pins, particles removed), that it is the same on one thread and on two, and
that it steps aside where it does not apply.
"""

import numpy as np
import pytest

from particles import backends
from particles.constraints import ProvotConstraint
from particles.errors import SimulationDiverged
from particles.forces import Attractor, Bending, Damping, Field, Force, Springs, Vortex, Wind
from particles.integrators import symplectic_euler
from particles.massspring import cloth, hair, string

from ..backends.helpers import _close, assert_same_bits, on_thread_counts
from ..backends.helpers import shaken as _shaken

pytestmark = pytest.mark.skipif("numba" not in backends.available(),
                                reason="numba is not installed (pip install 'particles[fast]')")

H = 1e-4  # s


def _systems():
    """Mass-spring systems of every shape the compiled step handles (name, builder)."""
    return [
        ("cloth, three damped sets, two pins", lambda: cloth(12, 12, kd=0.05)),
        ("cloth, undamped", lambda: cloth(10, 9, kd=0.0)),
        ("cloth with air damping and wind", lambda: cloth(10, 10, kd=0.02, damping=0.1, wind=[0.5, 0.0, 0.2])),
        ("string in 2D", lambda: string(30, kd=0.01)),
        ("string in 3D", lambda: string(30, d=3, kd=0.01)),
        ("hair: springs beside bending and a clamp", lambda: hair(25, kd=0.001)),
    ]


def _with(make, *forces):
    """`make` with more forces appended."""
    def made():
        system = make()
        system.forces += list(forces)
        return system
    return made


def _builder_systems():
    """The builders' documented options, each covered by the compiled step (name, builder)."""
    phys = dict(scaling="physical")
    return [
        ("cloth, physical, air damping (rate)", lambda: cloth(10, 10, damping=0.05, **phys)),
        ("cloth, naive, air damping in kg/s", lambda: cloth(10, 10, damping=0.01, kd=0.02)),
        ("cloth, bending and spring damping", lambda: cloth(10, 10, bending_modulus=1e-3, kd=1e-3, **phys)),
        ("cloth, naive bending", lambda: cloth(9, 11, kb=0.002)),
        ("cloth, wind and drag", lambda: cloth(10, 10, wind=[2.0, 0.0, 1.0], damping=0.05, **phys)),
        ("cloth, top edge pinned", lambda: cloth(10, 10, pins="top edge", **phys)),
        ("cloth, horizontal, no pins", lambda: cloth(8, 8, plane="horizontal", pins=None, **phys)),
        ("cloth, gusts and a force wind, two dampings",
         _with(lambda: cloth(10, 10, kd=0.01), Wind([0.3, 0.1, 0.0], gust=0.5, period=0.01, wavelength=0.3),
               Wind([1.0, 0.0, 0.5], gust=0.2, period=0.02, per_mass=True), Damping(rate=0.3), Damping(0.002))),
        ("string, physical, damped, 3D", lambda: string(30, d=3, scaling="physical", damping=0.1, kd=0.01)),
        ("string pinned at both ends", lambda: string(30, pin="both", span=0.8, scaling="physical", damping=0.2)),
        ("hair, physical, root clamp", lambda: hair(25, scaling="physical", damping=0.05)),
        ("hair in 3D, rest angles", lambda: _bent_hair()),
        ("hair, pair pin, gusts in 2D", _with(lambda: hair(20, pin="pair", kd=0.001),
                                             Wind([0.2, 0.0], gust=0.4, period=0.01, wavelength=0.2))),
    ]


def _bent_hair():
    """A 3D hair whose joints rest bent (rest angles from a curved start), and its clamp."""
    system = hair(20, d=3, direction=[1.0, 0.0, 0.2])
    bend = [f for f in system.forces if isinstance(f, Bending)][0]
    x = system.X[:, 0].copy()
    x[:, 1] = 0.02 * np.sin(6 * x[:, 0])
    bend.rest_angle = bend.angles(x)
    return system


def _runs(make, steps=5, method="symplectic_euler", block=None, monkeypatch=None):
    """The end states of the same run with every force on NumPy, then on numba."""
    out = {}
    for backend in ("numpy", "numba"):
        system = _shaken(make())
        if block is not None:
            from particles.massspring import compiled_step
            monkeypatch.setattr(compiled_step, "STEP_BLOCK", block)
        with backends.using(backend):
            t, X = system.run(steps * H, H, method=method(system) if callable(method) else method)
        out[backend] = X[-1]
    return out["numpy"], out["numba"]


@pytest.mark.parametrize("name, make", _systems(), ids=[n for n, _ in _systems()])
def test_compiled_runs_agree_with_numpy_runs(name, make):
    """Five steps of every system: the compiled step and the NumPy step agree to 1e-12 relative."""
    reference, compiled_run = _runs(make)
    _close(reference, compiled_run)


@pytest.mark.parametrize("name, make", _builder_systems(), ids=[n for n, _ in _builder_systems()])
def test_every_builder_option_runs_compiled_and_agrees_with_numpy(name, make):
    """Each builder option (damping, bending, wind, pins, clamps) is in the compiled step; runs agree to 1e-12."""
    system = make()
    with backends.using("numba"):
        step = system.compiled_step()
        assert step is not None and step.parts(system.n).others == []
    reference, compiled_run = _runs(make)
    _close(reference, compiled_run)


@pytest.mark.parametrize("block", [1, 7, 16, 40])
@pytest.mark.parametrize("bending", [0.0, 1e-3], ids=["springs", "bending"])
def test_blocks_smaller_than_a_spring_agree(block, bending, monkeypatch):
    """Blocks of 1 to 40 particles on a 12 x 12 cloth (flexion springs and joints cross blocks): still 1e-12."""
    reference, compiled_run = _runs(lambda: cloth(12, 12, kd=0.05, scaling="physical", bending_modulus=bending),
                                    block=block, monkeypatch=monkeypatch)
    _close(reference, compiled_run)


def test_the_systems_stepper_takes_the_compiled_step_and_the_generic_stepper_does_not(monkeypatch):
    """With numba, the system's symplectic Euler (its run's, its stepper's) is the compiled step; with NumPy, and
    the generic symplectic_euler whatever the backend (its forces then compiled one by one), the NumPy step."""
    from particles.massspring.compiled_step import CompiledStep

    calls = []
    for name in ("symplectic_euler", "symplectic_euler_steps"):  # one step, and the steps of a run in one call
        original = getattr(CompiledStep, name)
        monkeypatch.setattr(CompiledStep, name, lambda *a, original=original: calls.append(1) or original(*a))
    system = _shaken(cloth(8, 8, kd=0.05))
    with backends.using("numpy"):
        assert system.compiled_step() is None
    X = system.state()
    given = X.copy()
    step = system.stepper("symplectic_euler")
    with backends.using("numba"):
        fused = system.compiled_step().symplectic_euler(X, 0.0, H)
        np.testing.assert_array_equal(step(system.derivative, X, 0.0, H), fused)
        t, states = system.run(H, H, method="symplectic_euler")  # the run's step too
        np.testing.assert_array_equal(states[-1], fused)
        assert len(calls) == 3
        generic = symplectic_euler(system.derivative, X, 0.0, H)  # the reference: no compiled step inside
        assert len(calls) == 3
    with backends.using("numpy"):
        reference = symplectic_euler(system.derivative, X, 0.0, H)
        assert system.compiled_step() is None
        np.testing.assert_array_equal(step(system.derivative, X, 0.0, H), reference)
    _close(reference, generic)
    _close(reference, fused)
    np.testing.assert_array_equal(X, given)  # the state given is not modified


@pytest.mark.parametrize("make", [lambda: cloth(24, 24, kd=0.05),
                                  lambda: cloth(24, 24, kd=0.05, scaling="physical", bending_modulus=1e-3,
                                                damping=0.05, wind=[1.0, 0.0, 0.5]),
                                  lambda: hair(600, kd=0.001, damping=0.1)],
                         ids=["springs", "bending, damping, wind", "hair with its clamp"])
def test_the_same_bits_on_one_thread_and_on_two(make, monkeypatch):
    """Blocks of 50 particles: one thread, two threads and the serial kernel give the same bits."""
    from particles.massspring import compiled_step

    monkeypatch.setattr(compiled_step, "STEP_BLOCK", 50)
    system = _shaken(make())
    X = system.state()

    def run():
        with backends.using("numba"):
            return [system.compiled_step().symplectic_euler(X, 0.0, H)]

    assert_same_bits(on_thread_counts(monkeypatch, run))


def test_changes_between_steps_are_followed():
    """A stiffness changed in place, new pins and added particles: each next step agrees with NumPy's."""
    def changed(backend):
        system = _shaken(cloth(10, 10, kd=0.05))
        with backends.using(backend):
            system.run(3 * H, H, method="symplectic_euler")
            system.springs["shear"].k *= 3.0  # in place: the same array
            system.run(system.t + 3 * H, H, method="symplectic_euler")
            X = system.state()
            X[5, 1] = 0.0
            system.set_state(X)
            system.pinned = np.append(system.pinned, 5)
            system.run(system.t + 3 * H, H, method="symplectic_euler")
            system.add_particles([[0.0, 0.0, -2.0], [0.1, 0.0, -2.0]], v=[[0.0, 0.0, 1.0], [0.0, 0.5, 0.0]], m=0.01)
            system.run(system.t + 3 * H, H, method="symplectic_euler")
        return system.state()

    _close(changed("numpy"), changed("numba"))


def test_wrapped_steppers_take_the_compiled_step_too():
    """Provot's constraint around symplectic Euler: the run agrees with NumPy's (its inner step is compiled)."""
    def provot(system):
        s = system.springs["structural"]
        return ProvotConstraint(s.indices, s.rest_length, system.n, pinned=system.pinned).stepper("symplectic_euler")

    reference, compiled_run = _runs(lambda: cloth(10, 10, kd=0.05), method=provot)
    _close(reference, compiled_run)


class _Stiffer(Springs):
    """Springs with their own force law (twice the stiffness): the compiled step must not take them for Springs."""

    def add_to(self, F, x, v, t, m):
        G = np.zeros_like(F)
        super().add_to(G, x, v, t, m)
        F += 2.0 * G


class _Custom(Force):
    """A force of the user's own: the compiled step has no form of it."""

    def add_to(self, F, x, v, t, m):
        F[:, 0] += 0.01 * m


UNCOVERED = [Field(lambda x, t: -0.1 * x), Attractor([0.5, 0.5, -1.0], 0.01), Vortex([0.5, 0.5, 0.0], 0.01),
             _Custom()]


@pytest.mark.parametrize("extra", UNCOVERED, ids=[type(f).__name__ for f in UNCOVERED])
def test_auto_takes_the_compiled_step_exactly_where_it_covers_every_force(extra, monkeypatch):
    """"auto": the compiled step for the builders' systems; with a force it has no form of, the NumPy step.

    A force left to its own ``add_to`` would read the compiled step's
    C-ordered rows with NumPy's slow strided loops, so ``"auto"`` keeps the
    NumPy step then (its springs still on their compiled kernel); an
    explicit ``"numba"`` takes the compiled step all the same.
    """
    monkeypatch.setattr(backends, "AUTO_MIN", 1)  # "auto" compiles these small systems too
    for name, make in _builder_systems():  # a loop over the builders' options: all covered
        system = make()
        with backends.using("auto"):
            assert system.compiled_step() is not None, name
    system = _with(lambda: cloth(10, 10, damping=0.05, scaling="physical"), extra)()
    with backends.using("auto"):
        assert system.compiled_step() is None
        assert system.stepper("symplectic_euler").steps(system.derivative, system.state(), np.array([0.0, H]),
                                                         np.inf) is None
    with backends.using("numba"):
        assert system.compiled_step().parts(system.n).others == [extra]
    bending_on_numpy = cloth(10, 10, scaling="physical", bending_modulus=1e-3)
    [f for f in bending_on_numpy.forces if isinstance(f, Bending)][0]._backend = "numpy"
    with backends.using("auto"):
        assert bending_on_numpy.compiled_step() is None  # a bending set kept on NumPy by its own choice
    out = {}
    for backend in ("numpy", "auto", "numba"):
        s = _shaken(_with(lambda: cloth(10, 10, damping=0.05, scaling="physical"), extra)())
        with backends.using(backend):
            out[backend] = s.run(5 * H, H, method="symplectic_euler")[1][-1]
    _close(out["numpy"], out["auto"])
    _close(out["numpy"], out["numba"])


def test_where_it_does_not_apply_the_numpy_step_is_taken():
    """A Springs subclass with its own add_to, four spring sets, other steppers: no compiled step, right results."""
    def subclassed():
        system = _shaken(string(20, kd=0.01))
        s = system.forces[0]
        system.forces[0] = _Stiffer(s.indices, s.rest_length, k=s.k, kd=s.kd)
        return system

    def four_sets():
        system = _shaken(cloth(8, 8, kd=0.05))
        s = system.springs["structural"]
        half = len(s) // 2
        system.forces += [Springs(s.indices[:half], s.rest_length[:half], k=1.0),
                          Springs(s.indices[half:], s.rest_length[half:], k=1.0)]
        return system

    assert subclassed().forces[0].compiled_role is None and string(3).forces[0].compiled_role == "springs"
    for make in (subclassed, four_sets):
        with backends.using("numba"):
            system = make()
            assert system.compiled_step() is None
        _close(*_runs(make))
    _close(*_runs(lambda: cloth(8, 8, kd=0.05), method="verlet"))  # verlet calls it as the derivative


def test_a_diverging_compiled_run_is_reported_with_its_step():
    """A step far above the stability limit: SimulationDiverged names symplectic Euler and the step."""
    system = _shaken(cloth(8, 8, kd=0.0, k_structural=1e4))
    with backends.using("numba"), pytest.raises(SimulationDiverged, match=r"symplectic_euler.*|step \d+"):
        system.run(1.0, 0.05, method="symplectic_euler")


def test_other_forces_get_the_state_as_total_force_gives_it():
    """Damping and a Springs set beside the cloth's: the compiled step adds them as total_force does."""
    def extra():
        system = _shaken(cloth(9, 9, kd=0.05))
        system.forces.append(Damping(0.3))
        return system

    _close(*_runs(extra))


def test_a_state_still_held_is_never_reused():
    """Steps whose results are kept: each is a new array and keeps its values; a dropped one may be reused."""
    system = _shaken(cloth(8, 8, kd=0.05))
    X = system.state()
    with backends.using("numba"):
        f = system.compiled_step()
        first = f.symplectic_euler(X, 0.0, H)
        kept = first.copy()
        view = f.symplectic_euler(X, 0.0, 2 * H)[:, 0]  # only a view of the second is held
        third = f.symplectic_euler(X, 0.0, 3 * H)
        assert not np.shares_memory(third, first) and not np.shares_memory(third, view)
        np.testing.assert_array_equal(first, kept)
        _close(view, symplectic_euler(system.derivative, X, 0.0, 2 * H)[:, 0])
        del first, view
        again = f.symplectic_euler(X, 0.0, H)
        np.testing.assert_array_equal(again, kept)


def test_hooks_see_the_compiled_rows_and_the_run_ends_in_fortran_order():
    """With hooks (Collider.run), the compiled step's states are not converted between steps; the end state is."""
    from particles.collisions import Collider, Sphere

    def run(backend):
        system = _shaken(cloth(10, 10, plane="horizontal", pins=None, origin=(-0.5, -0.5, 0.0), kd=0.05))
        seen = []
        with backends.using(backend):
            collider = Collider(Sphere([0.0, 0.0, -0.3], 0.29), restitution=0.0, friction=0.2)
            step = collider.stepper("symplectic_euler", m=system.m, pinned=system.pinned)
            system.run(20 * H, H, method=step, between_steps=lambda s, t0: seen.append(s.X.flags.c_contiguous))
        return system, seen

    compiled_system, seen = run("numba")
    assert all(seen) and compiled_system.X.flags.f_contiguous
    numpy_system, seen = run("numpy")
    assert not any(seen) and numpy_system.X.flags.f_contiguous
    _close(numpy_system.X, compiled_system.X)
