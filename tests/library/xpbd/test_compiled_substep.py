"""The compiled XPBD substep (particles.xpbd.compiled_substep): NumPy's XPBD and PBD runs, fallbacks, threads."""

import numpy as np
import pytest

from particles import ParticleSystem
from particles.collisions import Collider, Sphere
from particles.forces import Damping, Gravity, Wind
from particles.massspring import cloth, hair, string
from particles.xpbd import PBD, XPBD, Attachment, Distance, constraints_from_system

from ..backends.helpers import _close, assert_same_bits, needs_numba, on_thread_counts


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


G = 9.81


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
    from particles.xpbd import compiled_substep

    calls = []
    original = compiled_substep.CompiledSubstep.substep

    def counted(self, *args, **options):
        calls.append(1)
        return original(self, *args, **options)

    monkeypatch.setattr(compiled_substep.CompiledSubstep, "substep", counted)
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


@needs_numba
@pytest.mark.parametrize("case", list(COMPILED_CASES))
def test_the_compiled_substep_agrees_with_numpy(case, monkeypatch):
    """One compiled call per substep: positions, velocities, multipliers and violations as NumPy's to 1e-12."""
    calls = _count_compiled_substeps(monkeypatch)
    (X_np, lam_np, viol_np), (X_nb, lam_nb, viol_nb) = _run_both(COMPILED_CASES[case], substeps=3, iterations=2)
    assert len(calls) == 12 * 3
    _close(X_np[:, 0], X_nb[:, 0])
    _close(X_np[:, 1], X_nb[:, 1])
    assert len(lam_np) == len(lam_nb)
    for a, b in zip(lam_np, lam_nb):  # a loop over the constraint sets
        _close(a, b)
    _close(viol_np, viol_nb)
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
    _close(out[0], out[1])


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
        _close(out[0], out[1])
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
    _close(out[0], out[1])


@needs_numba
def test_the_compiled_substep_has_the_same_bits_on_any_number_of_threads(monkeypatch):
    """Every colour group in parallel on one thread, on two, and no parallel loop at all: the same bits."""
    def run():
        X, lams, violation = _run_both(COMPILED_CASES["cloth, bending, air damping"], steps=4, substeps=2,
                                       iterations=2)[1]
        return [X] + list(lams) + [np.array(violation)]

    assert_same_bits(on_thread_counts(monkeypatch, run))
