"""The collider compiled (particles.collisions.collider_kernels): NumPy's contacts and bits, any thread count."""

import numpy as np
import pytest

from particles import backends
from particles.collisions import Box, Collider, Cylinder, Plane, Sphere
from particles.integrators import symplectic_euler
from particles.massspring import cloth, string

from ..backends.helpers import _close, assert_same_bits, needs_numba, on_thread_counts


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
    from particles.collisions import collider_kernels

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
            index, *columns = collider_kernels.collide(collider, X, mine, k * h, h, np.ascontiguousarray(c.m), free)
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
def test_the_compiled_collider_has_the_same_bits_on_any_number_of_threads(monkeypatch):
    """The collider's fix: one thread, two threads and the serial kernels give the same bits."""
    def run():
        return [_collider_runs(SURFACES[0][1], 3, "backtrack", steps=60, outer=("numba",))["numba"][0]]

    assert_same_bits(on_thread_counts(monkeypatch, run))
