"""Backends: the NumPy reference, or the same loops compiled with numba (``pip install particles[fast]``).

The library's force passes are written in NumPy, the code students read: a
spring force is about ten whole-array operations (gather ``x_i`` and ``x_j``,
subtract, square, sum, square root, divide, ... scatter), each one pass over
arrays of all the springs. A compiled loop does the same arithmetic in one
pass, spring by spring, with every value still in a register. Where memory
traffic and not arithmetic sets the time (cloth springs, Lennard-Jones
pairs), that is worth a factor of several (``bench/bench_backends.py``).

**The switch.** Every object that has a compiled kernel takes a ``backend``
argument (:class:`~particles.springs.Springs`,
:class:`~particles.springs.Bending`,
:class:`~particles.forces.lennardjones.LennardJones`,
:class:`~particles.forces.nbody.NBodyGravity`, :class:`~particles.xpbd.XPBD`,
:func:`~particles.xpbd.distance_pass` and :class:`~particles.implicit.Prefactored`):

* ``"numpy"``: the reference code, always;
* ``"numba"``: the compiled kernels (an error, naming the extra to install,
  when numba is missing);
* ``"auto"``: numba when it is installed and the system has at least
  :data:`AUTO_MIN` particles (a 64^2 cloth, a 4k liquid), NumPy otherwise:
  small problems (the lectures' examples, the tests) stay bit for bit those
  of the reference and never wait for a compiler. The cloth collision
  pipeline, whose work per vertex is that of dozens of force passes, counts
  its vertices :data:`CLOTH_COLLISION_WEIGHT` times: it compiles from 64
  vertices (its contacts and verdicts are NumPy's either way); XPBD and PBD,
  whose step is its substeps' sweeps over the colour groups, count their
  particles :data:`XPBD_WEIGHT` times: they compile from 1024 (a 32^2 sheet;
  the lectures' 10^2 and 12^2 curtains stay on NumPy);
* ``None`` (the default of every object): the global choice, set by
  :func:`set_backend` or, for a block, :func:`using`; it starts as the
  environment variable ``PARTICLES_BACKEND`` (``numpy``, ``numba`` or
  ``auto``), or ``"auto"`` when that is unset.

``PARTICLES_BACKEND=numpy`` also turns ``"auto"`` into NumPy everywhere, and
so does numba's own ``NUMBA_DISABLE_JIT=1``: the grader's workers run with the
latter (:mod:`particles.course.worker.process`), so they never import numba or need
its cache. Should numba fail to load, ``"auto"`` falls back to NumPy (once,
with a warning). The choice is made at each force evaluation, so
:func:`using` applies to objects built before it too.

**Agreement.** A kernel does the operations of the NumPy code in the same
order wherever that costs nothing (springs, bending and XPBD give the same
bits as NumPy), and sums per particle in a fixed order what NumPy scatters
with ``np.bincount``, so the two agree to about 1e-15 relative (tested to
1e-12 on every problem of the force contract,
``tests/library/backends/test_force_contract.py``, and on larger ones,
``tests/library/backends/test_compiled.py``).

**Determinism and threads.** Loops of 4096 items or more run on numba's
threads (``NUMBA_NUM_THREADS``, or :func:`numba.set_num_threads`); shorter
ones on one. The result has the same bits for any number of threads: each
output (a particle's force, a constraint's correction) is written by one
thread, as a sum in a fixed order, through a per-particle incidence list in
compressed-row form (for Lennard-Jones, per block of particles, a number
that depends on the system only) rather than with atomic additions; totals
(the virial) are summed after the parallel loop. Springs have two forms with
the same bits: a one-pass scatter on one thread, and forces per spring in
parallel then a per-particle gather, which moves more memory and is used
from four threads on. Unless ``NUMBA_THREADING_LAYER`` says otherwise, the
threads are GNU OpenMP's (numba's work queue where OpenMP does not load),
with their wait between two parallel loops bounded by ``GOMP_SPINCOUNT=10000``
(``bench/bench_threads.py``): the work queue took 17 to 38 us to start a
parallel loop and woke its second thread too late to halve a 0.2 ms loop,
OpenMP starts one in 2 to 7 us and halves it; OpenMP's default wait, a spin
of milliseconds, once made an XPBD substep (a parallel loop per colour) a
hundred times slower beside another process doing the same on a 2-core
machine.
GNU OpenMP is not fork-safe: a process forked (not spawned) from one that
ran a parallel loop must not run one itself (numba stops it with
"Terminating: fork() called from a process already using GNU OpenMP");
set ``NUMBA_THREADING_LAYER=workqueue`` for such a program.

**The compiled step.** A force pass is only part of a step: around it the
NumPy symplectic Euler step zeroes the force array, divides by the masses,
clears the pins, and makes the new velocities and positions, each one more
pass over all particles, and the per-force kernels read the state in the
system's Fortran order, each coordinate of all particles together. When a
system's springs run compiled, :func:`~particles.integrators.symplectic_euler`
given the system's ``derivative`` (in :meth:`particles.ParticleSystem.run`,
inside a wrapper such as Provot's constraint or a collider, or called
directly) takes the whole step from :func:`compiled_step`, one parallel pass
over blocks of particles (:mod:`particles.backends._step_kernels`): each
block reads the particles its springs touch from the state's rows ``(x, v)``
(a state in Fortran order is copied to C order once, before the first
step), computes its springs and bending joints, adds air damping, wind and gravity, and
updates its own particles; clamps have a kernel of their own
(:attr:`~particles.forces.fields.Force.compiled_role` says what each force is).
Provot's pass and a collider's fix run compiled after the step, in place
(:mod:`particles.backends.fixes`). A force without a compiled form is added
by its own ``add_to`` with ``"numba"``; with ``"auto"`` the system keeps the
NumPy step (NumPy's loops over the compiled step's C-ordered rows would be
slower than the NumPy step). It agrees with the NumPy step to rounding, has
the same bits on any number of threads, and is what ``bench/bench_backends.py``
times against Warp (``bench/bench_builders.py``: the builders'
configurations). With the NumPy backend (or below :data:`AUTO_MIN`
particles on ``"auto"``) the step is the slide's, bit for bit.

**Why numba.** It compiles plain Python loops over NumPy arrays, so the
kernel reads as the slide's loop, with the same names; it ships as wheels
for the platforms the course supports, needs no compiler on the student's
machine, caches its machine code on disk, and runs on the CPU that every
student has. Warp and Taichi are GPU-first, with their own array types and
runtimes to initialize; Cython and C extensions need a build step; JAX
traces array code (the NumPy formulation again, not a loop) and is a large
dependency. ``bench/bench_backends.py`` times Warp's and Taichi's CPU
backends beside numba when they are installed (extra ``[bench]``).

**Compile cache.** Kernels are compiled on first use (seconds) and cached on
disk (``cache=True``) in ``NUMBA_CACHE_DIR`` if it is set, else in
``~/.cache/particles/numba`` (or ``$XDG_CACHE_HOME/particles/numba``, or a
folder of the temporary directory): never inside the package, which may be
read-only and whose files the grader checksums. With no writable place,
kernels are compiled in memory, once per process. ``bench/bench_backends.py``
reports the compile time and the cached load time apart from the run times.

Modules
-------
* :mod:`particles.backends.compiled`: the numba drivers, one per compiled force, and the compiled step;
* :mod:`particles.backends.xpbdstep`: the compiled XPBD substep;
* :mod:`particles.backends.warm`: every compiled path run once on small systems, so that the kernels are
  compiled into the disk cache ahead of use (``particles warm``, which ``make test`` runs first);
* :mod:`particles.backends.fixes`: Provot's pass and the collider as compiled fixes of a step's end state;
* :mod:`particles.backends.factored`: the prefactorized implicit solver's local step, triangular solves
  over its kept factorization and residual (:class:`~particles.implicit.Prefactored` with ``backend=``);
* :mod:`particles.backends.cloth`: the cloth collision pipeline's broad phase, proximity impulses and
  continuous test, compiled (the same contacts and verdicts as NumPy);
* ``_kernels.py``, ``_step_kernels.py``, ``_pbd_kernels.py``, ``_provot_kernels.py``,
  ``_collider_kernels.py``, ``_factored_kernels.py``, ``_broad_kernels.py``, ``_contact_kernels.py``,
  ``_jacobi_kernels.py``, ``_body_kernels.py``: the numba loops they call (private to the package).

Examples
--------
>>> from particles import backends
>>> "numpy" in backends.available()
True
>>> with backends.using("numpy"):
...     backends.resolve(None, 10**6)
'numpy'
"""

import contextlib
import importlib.util
import os
import warnings

__all__ = ["BACKENDS", "AUTO_MIN", "CLOTH_COLLISION_WEIGHT", "XPBD_WEIGHT", "available", "check_backend", "resolve",
           "set_backend", "get_backend", "using", "kernels_for", "compiled_step"]

BACKENDS = ("auto", "numpy", "numba")

# "auto" compiles for systems of this many particles or more: below, a NumPy force pass costs about a
# millisecond or less, and loading the compiled code (a fraction of a second) would cost more than it saves
AUTO_MIN = 4096

# the cloth collision pipeline (particles.collisions.ClothCollisions) asks "auto" with this many times its
# vertices: each vertex carries dozens of force passes' work (its candidate pairs' closest points, up to 50
# Jacobi iterations, the continuous test), and NumPy's calls cost the same whatever the sheet. Measured with
# bench/bench_cloth_fold.py --compare (median ms per step, NumPy / compiled): 8^2 6.3 / 1.3, 16^2 18.6 / 2.8,
# 32^2 about 60 / 8: compiled from 64 vertices
CLOTH_COLLISION_WEIGHT = 64

# XPBD and PBD (particles.xpbd) ask "auto" with this many times their particles: a step is its substeps' sweeps
# over the colour groups, a few dozen NumPy calls each. `python bench/bench_cloth_fold.py --xpbd-sizes` (the
# fold's sheet, 10 substeps, ms per step, NumPy / compiled, 2026-12-06): 8^2 1.92 / 0.33, 16^2 2.48 / 0.50,
# 24^2 3.46 / 0.77, 32^2 4.46 / 1.17, 48^2 8.28 / 2.32, 64^2 12.22 / 3.97. Compiled from 1024 particles: a 32^2
# sheet, not the lectures' curtains (10^2 and 12^2), which stay bit for bit the reference's
XPBD_WEIGHT = 4

ENVIRONMENT = "PARTICLES_BACKEND"

_state = {"default": None, "numba": None}


def _numba_installed():
    if _state["numba"] is None:
        _state["numba"] = importlib.util.find_spec("numba") is not None
    return _state["numba"]


def available():
    """The backends that can run here: ``("numpy",)``, or ``("numpy", "numba")`` with the extra installed.

    Returns
    -------
    tuple of str
    """
    return ("numpy", "numba") if _numba_installed() else ("numpy",)


def check_backend(backend, name="backend"):
    """`backend` checked: None, ``"auto"``, ``"numpy"`` or ``"numba"`` (numba only when installed).

    Raises
    ------
    ValueError
        For another value, or ``"numba"`` without numba (the message names the extra to install).
    """
    if backend is not None and backend not in BACKENDS:
        raise ValueError(f"{name} must be 'numpy', 'numba', 'auto' or None, got {backend!r}")
    if backend == "numba" and not _numba_installed():
        raise ValueError(f"{name}='numba' needs numba, which is not installed: pip install 'particles[fast]' "
                         "(or use backend='numpy' or 'auto')")
    return backend


def _environment():
    value = os.environ.get(ENVIRONMENT, "").strip().lower()
    if value and value not in BACKENDS:
        raise ValueError(f"the environment variable {ENVIRONMENT} must be 'numpy', 'numba' or 'auto', "
                         f"got {value!r}")
    return value or None


def get_backend():
    """The global choice: from :func:`set_backend` or :func:`using`, else ``$PARTICLES_BACKEND``, else "auto"."""
    return _state["default"] or _environment() or "auto"


def set_backend(backend):
    """Set the global choice (``"auto"``, ``"numpy"`` or ``"numba"``; None: back to the environment's).

    Objects built with ``backend=None`` (the default) follow it at their next
    evaluation.
    """
    _state["default"] = check_backend(backend)


@contextlib.contextmanager
def using(backend):
    """Within the block, the global choice is `backend` (e.g. ``with using("numba"): ...``)."""
    before = _state["default"]
    set_backend(backend)
    try:
        yield backend
    finally:
        _state["default"] = before


def resolve(backend, size):
    """Which backend runs a pass over `size` particles, for an object's `backend` option: "numpy" or "numba".

    Parameters
    ----------
    backend : {None, "auto", "numpy", "numba"}
        The object's option (None: :func:`get_backend`).
    size : int
        Particles of the system (``"auto"`` compiles from :data:`AUTO_MIN`).

    Returns
    -------
    str
    """
    choice = get_backend() if backend is None else backend
    if choice == "auto":
        if size < AUTO_MIN or _environment() == "numpy" or os.environ.get("NUMBA_DISABLE_JIT", "0") != "0" \
                or not _numba_installed() or _state.get("broken"):
            return "numpy"
        return "numba"
    if choice == "numba" and not _numba_installed():
        check_backend("numba")
    return choice


def kernels_for(backend, size):
    """The compiled kernels (:mod:`particles.backends.compiled`) if `backend` resolves to numba, else None.

    The force modules call it at each evaluation; numba is imported only here,
    at the first pass that uses it, never by ``import particles``.
    """
    if resolve(backend, size) != "numba":
        return None
    try:
        from . import compiled  # noqa: PLC0415  (imports numba)
    except Exception as error:  # numba installed but unusable (a broken install, a sandbox)
        if (get_backend() if backend is None else backend) != "auto":
            raise
        _state["broken"] = True
        warnings.warn(f"backend 'auto': numba could not be loaded ({error}); using NumPy", RuntimeWarning,
                      stacklevel=3)
        return None
    return compiled


def compiled_step(system):
    """`system`'s compiled symplectic Euler step when its springs run compiled, or None.

    :meth:`particles.ParticleSystem.fused_symplectic_euler` calls it at each
    step: :func:`~particles.integrators.symplectic_euler` given the system's
    ``derivative`` (by :meth:`particles.ParticleSystem.run`, by a wrapper such
    as Provot's or a collider, or directly) then takes the whole step in one
    compiled pass (:class:`particles.backends.compiled.CompiledStep`).

    Returns
    -------
    CompiledStep or None
        None unless the system has one to three
        :class:`~particles.springs.Springs` sets (``compiled_role ==
        "springs"``), in 2D or 3D, and all of them resolve to numba for the
        system's size. Nothing imports numba otherwise.
    """
    springs = [f for f in system.forces if getattr(f, "compiled_role", None) == "springs"]
    if not springs or not _all_compiled(springs, system.n):
        return None
    from .compiled import CompiledStep  # noqa: PLC0415  (loaded by _all_compiled already)
    step = CompiledStep(system, _all_compiled, _automatic)
    return step if step.parts(system.n) is not None else None


def _all_compiled(forces, n):
    """Whether every one of `forces` runs on the compiled kernels for `n` particles (each by its ``_backend``)."""
    return all(kernels_for(backend, n) is not None for backend in {f._backend for f in forces})


def _automatic(forces):
    """Whether one of `forces` leaves the choice to ``"auto"`` (its own ``_backend`` or the global choice)."""
    return any((get_backend() if f._backend is None else f._backend) == "auto" for f in forces)
