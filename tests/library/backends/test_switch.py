"""The backend switch (particles.backends): numpy, numba, auto, the global choice; numba loaded only when used."""

import os
import subprocess
import sys

import pytest

from particles import backends
from particles._vectors import select
from particles.forces import LennardJones
from particles.forces import Springs

from .helpers import needs_numba


def fresh_environment(monkeypatch):
    """Neither PARTICLES_BACKEND nor NUMBA_DISABLE_JIT set: "auto" decides by size alone."""
    monkeypatch.delenv("PARTICLES_BACKEND", raising=False)
    monkeypatch.delenv("NUMBA_DISABLE_JIT", raising=False)


def spy(monkeypatch, owner, name, calls):
    """Replace ``owner.name`` by a wrapper that appends `name` to `calls`, then calls the original."""
    original = getattr(owner, name)
    monkeypatch.setattr(owner, name, lambda *a, **k: calls.append(name) or original(*a, **k))


def test_import_particles_does_not_import_numba():
    """numba is loaded only by a force pass that uses it, never by ``import particles`` or the NumPy backend."""
    code = ("import sys, numpy as np, particles; from particles.forces import Springs; "
            "Springs([[0, 1]], 1.0, k=2.0)(np.array([[0.0, 0.0], [2.0, 0.0]])); print('numba' in sys.modules)")
    env = dict(os.environ, PARTICLES_BACKEND="numpy")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert done.stdout.strip() == "False"


def test_auto_is_numpy_for_small_problems_and_under_particles_backend_numpy(monkeypatch):
    """"auto" compiles only from AUTO_MIN particles, never with PARTICLES_BACKEND=numpy or NUMBA_DISABLE_JIT=1."""
    fresh_environment(monkeypatch)
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
@pytest.mark.parametrize("side, compiled", [(31, False), (32, True)])
def test_auto_compiles_xpbd_from_1024_particles(monkeypatch, side, compiled):
    """"auto" runs XPBD's substeps compiled from 1024 particles (a 32 x 32 sheet), NumPy below (31 x 31)."""
    from particles.massspring import cloth  # noqa: PLC0415
    from particles.xpbd import XPBD  # noqa: PLC0415
    from particles.xpbd.compiled_substep import CompiledSubstep  # noqa: PLC0415
    from particles.xpbd.solver import XPBD_WEIGHT  # noqa: PLC0415

    fresh_environment(monkeypatch)
    calls = []
    spy(monkeypatch, CompiledSubstep, "substep", calls)
    c = cloth(side, side, scaling="physical")
    c.run(0.01, 0.01, method=XPBD.from_system(c, substeps=2, backend="auto"))
    assert XPBD_WEIGHT * 1024 == backends.AUTO_MIN
    assert len(calls) == (2 if compiled else 0)


@needs_numba
@pytest.mark.parametrize("side, compiled", [(7, False), (8, True)])
def test_auto_compiles_the_cloth_collisions_from_64_vertices(monkeypatch, side, compiled):
    """"auto" runs every stage of ClothCollisions compiled from 64 vertices (an 8 x 8 sheet), NumPy below."""
    import numpy as np  # noqa: PLC0415

    from particles.collisions import ClothCollisions, Plane, TriangleMesh  # noqa: PLC0415
    from particles.collisions import compiled_stages as kernels  # noqa: PLC0415
    from particles.collisions.candidate_cache import CLOTH_COLLISION_WEIGHT  # noqa: PLC0415

    fresh_environment(monkeypatch)
    calls = []
    for name in ("cloth_candidate_rows", "cloth_proximity", "cloth_impulses", "cloth_first_contacts"):
        spy(monkeypatch, kernels, name, calls)
    u, v = np.meshgrid(np.linspace(0, 0.02, side), np.linspace(0, 0.02, side))  # spacing < thickness: contacts
    x0 = np.stack([u.ravel(), v.ravel(), 0.004 * np.sin(40 * u.ravel())], axis=1)
    x1 = x0 + [0.0, 0.0, -0.01]
    cc = ClothCollisions(TriangleMesh.grid(side, side), 0.005, bodies=[Plane([0, 0, 0.0], [0, 0, 1.0])],
                         backend="auto")
    cc.resolve(x0, x1, (x1 - x0) / 0.01, 0.0, 0.01)
    assert CLOTH_COLLISION_WEIGHT * 64 == backends.AUTO_MIN
    assert sorted(set(calls)) == (["cloth_candidate_rows", "cloth_first_contacts", "cloth_impulses", "cloth_proximity"]
                                  if compiled else [])


def test_auto_falls_back_to_numpy_when_numba_cannot_load(monkeypatch):
    """With numba unusable, 'auto' warns and uses NumPy from then on; an explicit 'numba' raises."""
    monkeypatch.delattr(backends, "compile", raising=False)
    monkeypatch.setitem(sys.modules, "particles.backends.compile", None)  # importing it now fails
    monkeypatch.setitem(backends._state, "broken", False)
    with pytest.warns(RuntimeWarning, match="numba could not be loaded"):
        assert backends.compiled("auto", 10**6) is False
    assert backends.resolve("auto", 10**6) == "numpy"
    with pytest.raises(ImportError):
        backends.compiled("numba", 10)


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


_LAYER = ("import os, numpy as np, numba, particles.backends.compile as k; "
          "from particles.xpbd.kernels import distance_violation as v; "
          "x = np.random.rand(3, 9000); ij = np.stack([np.arange(8999), np.arange(1, 9000)], 1).astype(np.int32); "
          "v(x, ij, np.ones((8999, 4)), np.empty(8999)); "
          "print(numba.threading_layer(), os.environ.get('GOMP_SPINCOUNT'))")
_OMP_LOADS = ("import importlib, sys\ntry:\n    importlib.import_module('numba.np.ufunc.omppool')\n"
              "except ImportError:\n    sys.exit(1)")


@needs_numba
@pytest.mark.parametrize("chosen", [None, "workqueue"], ids=["the library's choice", "the user's"])
def test_the_threads_are_openmp_with_a_bounded_spin_unless_the_user_chose(chosen):
    """No NUMBA_THREADING_LAYER: OpenMP (or the work queue where it cannot load), spinning 10000; else the user's."""
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_THREADING_LAYER", "GOMP_SPINCOUNT")}
    if chosen:
        env["NUMBA_THREADING_LAYER"] = chosen
    done = subprocess.run([sys.executable, "-c", _LAYER], capture_output=True, text=True, env=env, check=True)
    layer, spin = done.stdout.split()
    if chosen:
        assert (layer, spin) == (chosen, "None")
    else:  # OpenMP wherever numba's OpenMP pool loads; the work queue only where it cannot
        omp = subprocess.run([sys.executable, "-c", _OMP_LOADS], env=env).returncode == 0
        assert (layer, spin) == ("omp" if omp else "workqueue", "10000")



def _ratio_or_zero(a, b):
    """A law written for arrays and kernels alike: ``a / b`` where ``b != 0``, else 0 (``select`` computes both)."""
    return select(b != 0.0, a / b, 0.0)


def _ratio_or_zero_again(a, b):
    """The same law again, to be given a kernel form (a law has one form for every kernel)."""
    return select(b != 0.0, a / b, 0.0)


@needs_numba
def test_a_kernel_form_computes_only_the_branch_taken():
    """A law's kernel form (kernel_form) is what kernels run: compiled, the law itself divides by zero (numba
    raises), its form does not; the form agrees with the law where both are defined."""
    import numba  # noqa: PLC0415

    from particles.backends.compile import inline, kernel_form  # noqa: PLC0415

    inline(_ratio_or_zero)
    plain = numba.njit(lambda a, b: _ratio_or_zero(a, b))
    with pytest.raises(ZeroDivisionError):
        plain(1.0, 0.0)

    @kernel_form(_ratio_or_zero_again)
    def ratio_in_kernels(a, b):
        if b != 0.0:
            return a / b
        return 0.0

    kernel = numba.njit(lambda a, b: _ratio_or_zero_again(a, b))
    assert kernel(1.0, 0.0) == 0.0
    assert kernel(3.0, 4.0) == float(_ratio_or_zero_again(3.0, 4.0)) == 0.75
