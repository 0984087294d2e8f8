"""Each kernel is compiled once, whatever the memory order of the state or the writability of an index table.

numba compiles a kernel anew for each combination of argument types, and a
Fortran-ordered array, a C-ordered one and a read-only one are three types.
The compiled step's kernel took 7 to 12 s per variant to compile, the broad
phase's largest 8 to 18 s: the library hands the kernels one form of each
(C-ordered states, read-only element tables), converting once where it must.
These tests give the library both forms and check that no kernel met a new
type, and that the results have the same bits either way.
"""

import numpy as np
import pytest

from particles import backends
from particles.collisions import Collider, Sphere, TriangleMesh
from particles.constraints import ProvotConstraint
from particles.massspring import cloth

from .helpers import needs_numba

pytestmark = needs_numba


def _variants(*kernels):
    """How many types each kernel (its parallel copy and its one-thread copy) has been compiled for, so far."""
    return [len(k.signatures) + len(k.serial.signatures) for k in kernels]


def _stretched(c):
    """The system's state with every spring 30% too long and a velocity field: Provot's passes will correct it."""
    X = c.state()
    X[:, 0] *= 1.3
    X[:, 1] = np.sin(7.0 * X[:, 0]) * 0.1
    X[c.pinned, 1] = 0.0
    return X


def test_the_compiled_step_reads_a_fortran_ordered_state_without_a_kernel_of_its_own():
    """A step from a C-ordered state (the compiled step's own) and from the same state in F order (a NumPy
    step's, or set_state's): one kernel, the same bits."""
    from particles.massspring.step_kernels import symplectic_euler_steps

    c = cloth(8, 8, scaling="physical", damping=0.05)
    X = _stretched(c)
    with backends.using("numba"):
        step = c.compiled_step()
        c_step = step.symplectic_euler(np.ascontiguousarray(X), 0.0, 1e-4)  # the C-ordered variant from here on
        before = _variants(symplectic_euler_steps)
        f_step = step.symplectic_euler(np.asfortranarray(X), 0.0, 1e-4)
    assert _variants(symplectic_euler_steps) == before
    np.testing.assert_array_equal(f_step, c_step)


@pytest.mark.parametrize("method", ["jacobi", "gauss-seidel"])
def test_provot_corrects_a_fortran_ordered_state_in_place_without_kernels_of_its_own(method):
    """Provot's pass on an F-ordered state (a NumPy step's) and on the same state in C order (the compiled step's):
    no new kernel, the F-ordered array corrected in place, the same bits."""
    from particles.constraints.kernels import CompiledProjection, provot_passes

    kernels = [provot_passes]
    c = cloth(8, 8, scaling="physical")
    constraint = ProvotConstraint.from_system(c, method=method, backend="numba")
    provot = lambda constraint, X, h: CompiledProjection(constraint).project(X, h)  # noqa: E731
    X_c = np.ascontiguousarray(_stretched(c))
    provot(constraint, X_c.copy(), 1e-3)  # the C-ordered variants exist from here on
    before = _variants(*kernels)
    X_f = np.asfortranarray(X_c)
    f_result = provot(constraint, X_f, 1e-3)
    assert _variants(*kernels) == before
    assert f_result[1] > 0 and X_f.flags.f_contiguous  # passes were made, in the array given
    assert provot(constraint, X_c, 1e-3) == f_result
    np.testing.assert_array_equal(X_f, X_c)


def test_the_collider_fixes_a_fortran_ordered_state_in_place_without_kernels_of_its_own():
    """A sheet's end state inside a ball, in F order (a NumPy step's) and in C order (the compiled step's): no
    new kernel, the F-ordered array fixed in place, the same bits and the same contacts."""
    from particles.collisions import collider_kernels as ck
    from particles.collisions.collider_kernels import collide

    c = cloth(8, 8, scaling="physical")
    collider = Collider(Sphere([0.5, 0.32, -0.5], 0.3), restitution=0.0, friction=0.3)  # 2 cm off the sheet
    X_old = np.ascontiguousarray(c.state())
    X_end = X_old.copy()
    X_end[:, 0, 1] += 0.05  # every particle 5 cm towards the ball: those facing it end inside
    free = ~np.isin(np.arange(c.n), c.pinned)
    m = np.ascontiguousarray(c.m, dtype=float)
    X_c = X_end.copy()
    c_contacts = collide(collider, X_old, X_c, 0.0, 1e-2, m, free)  # the C-ordered variants from here on
    before = _variants(ck.collider_candidates, ck.collider_resolve)
    X_f = np.asfortranarray(X_end)
    f_contacts = collide(collider, np.asfortranarray(X_old), X_f, 0.0, 1e-2, m, free)
    assert _variants(ck.collider_candidates, ck.collider_resolve) == before
    assert len(c_contacts[0]) > 0 and X_f.flags.f_contiguous  # contacts were fixed, in the array given
    np.testing.assert_array_equal(X_f, X_c)
    for a, b in zip(f_contacts, c_contacts):
        np.testing.assert_array_equal(a, b)


def test_vertex_face_and_edge_edge_searches_share_one_kernel():
    """The vertices' one-vertex elements are read-only like the mesh's faces and edges: the vertex-face and the
    edge-edge searches (with and without a mask) run the same compiled kernels."""
    from particles.collisions import broad_kernels as bk
    from particles.collisions import compiled_stages as compiled_cloth

    mesh = TriangleMesh.grid(6, 6)
    assert not compiled_cloth._own(mesh.n).flags.writeable and not mesh.edges.flags.writeable
    x = np.random.default_rng(3).uniform(size=(mesh.n, 3))
    lo, hi = x - 0.1, x + 0.1
    masked = np.zeros(mesh.n, dtype=bool)
    masked[[3, 17]] = True
    searches = [bk.box_candidates, bk.subset_pairs]
    (Q, T, same), *others = compiled_cloth._kinds(mesh)
    boxes = compiled_cloth._boxes(lo, hi, Q, T, same)
    assert not Q.flags.writeable
    for mask in (masked, None):  # the masked search and the grid
        compiled_cloth._search(*boxes, Q, T, same, mask)
    before = _variants(*searches)
    for Q, T, same in others:  # edges against edges
        for mask in (masked, None):
            compiled_cloth._search(*compiled_cloth._boxes(lo, hi, Q, T, same), Q, T, same, mask)
    assert _variants(*searches) == before
