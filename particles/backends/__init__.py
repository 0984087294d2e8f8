"""Backends: the NumPy reference, or the same formulas compiled with numba (``pip install particles[fast]``).

The library's passes are written in NumPy, the code students read: a
spring force is about ten whole-array operations (gather ``x_i`` and ``x_j``,
subtract, square, sum, square root, divide, ... scatter), each one pass over
arrays of all the springs. A compiled loop does the same arithmetic in one
pass, spring by spring, with every value still in a register. Where memory
traffic and not arithmetic sets the time (cloth springs, Lennard-Jones
pairs), that is worth a factor of several (``bench/bench_backends.py``).

**One formula, one place.** Each per-item formula (a damped spring's force,
a constraint's multiplier update, Provot's correction, a contact's impulse)
is one small function of its concept's module, which the NumPy code applies
to whole arrays and the compiled loop inlines for one item
(:func:`particles.backends.compile.inline`). The loops live beside their
concept, in its package's ``kernels.py`` (as Newton keeps ``kernels.py``
beside each solver); this package holds only what all of them share, and
imports no concept.

**The switch.** Every object that has a compiled form takes a ``backend``
argument (:class:`~particles.forces.Springs`, :class:`~particles.forces.Bending`,
:class:`~particles.forces.LennardJones`, :class:`~particles.forces.NBodyGravity`,
:class:`~particles.xpbd.XPBD`, :class:`~particles.constraints.ProvotConstraint`,
:class:`~particles.collisions.Collider`, :class:`~particles.collisions.ClothCollisions`
and :class:`~particles.implicit.Prefactored`):

* ``"numpy"``: the reference code, always;
* ``"numba"``: the compiled kernels (an error, naming the extra to install,
  when numba is missing);
* ``"auto"``: numba when it is installed and the system has at least
  :data:`AUTO_MIN` particles (a 64^2 cloth, a 4k liquid), NumPy otherwise:
  small problems (the lectures' examples, the tests) stay bit for bit those
  of the reference and never wait for a compiler. A concept whose work per
  particle is that of many force passes asks with a weight: the cloth
  collision pipeline (``particles.collisions.pipeline.CLOTH_COLLISION_WEIGHT``)
  compiles from 64 vertices, XPBD and PBD (``particles.xpbd.solver.XPBD_WEIGHT``)
  from 1024 particles;
* ``None`` (the default of every object): the global choice, set by
  :func:`set_backend` or, for a block, :func:`using`; it starts as the
  environment variable ``PARTICLES_BACKEND`` (``numpy``, ``numba`` or
  ``auto``), or ``"auto"`` when that is unset.

``PARTICLES_BACKEND=numpy`` also turns ``"auto"`` into NumPy everywhere, and
so does numba's own ``NUMBA_DISABLE_JIT=1``: the grader's workers run with the
latter (:mod:`particles.course.worker.process`), so they never import numba or need
its cache. Should numba fail to load, ``"auto"`` falls back to NumPy (once,
with a warning). The choice is made at each evaluation (:func:`compiled`), so
:func:`using` applies to objects built before it too.

**Agreement.** A kernel computes its laws with the NumPy code's functions and
sums per particle in a fixed order what NumPy scatters with ``np.bincount``,
so the two agree to about 1e-15 relative (tested to 1e-12 on every problem of
the force contract, ``tests/library/forces/test_force_contract.py``, and on
larger ones beside each concept's tests).

**Determinism and threads.** Loops of 4096 items or more run on numba's
threads (``NUMBA_NUM_THREADS``, or :func:`numba.set_num_threads`); shorter
ones on one. The result has the same bits for any number of threads: each
output (a particle's force, a constraint's correction) is written by one
thread, as a sum in a fixed order, through a per-particle incidence list in
compressed-row form (:func:`particles.backends.layout.incidence`; for
Lennard-Jones, per block of particles, a number that depends on the system
only) rather than with atomic additions; totals (the virial) are summed after
the parallel loop. The threads and their layer are set in
:mod:`particles.backends.compile`. GNU OpenMP is not fork-safe: a process
forked (not spawned) from one that ran a parallel loop must not run one
itself (numba stops it with "Terminating: fork() called from a process
already using GNU OpenMP"); set ``NUMBA_THREADING_LAYER=workqueue`` for such
a program.

**The compiled step.** A mass-spring system's symplectic Euler step can run
in one compiled pass (:mod:`particles.massspring.compiled_step`): chosen once,
where the system runs (:meth:`particles.massspring.MassSpringSystem.stepper`),
never inside the generic stepper.

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
disk (:mod:`particles.backends.compile`); ``particles warm``
(:mod:`particles.warm`) compiles them all ahead of use.

Modules
-------
* :mod:`particles.backends.compile`: the compile wrapper (:func:`~particles.backends.compile.jit`,
  :func:`~particles.backends.compile.inline`), numba's threads and the cache;
* :mod:`particles.backends.layout`: the layouts the kernels share (compressed-row incidence lists, a state
  in C order, work arrays kept between calls).

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

__all__ = ["BACKENDS", "AUTO_MIN", "available", "check_backend", "resolve", "compiled", "set_backend",
           "get_backend", "using"]

BACKENDS = ("auto", "numpy", "numba")

# "auto" compiles for systems of this many particles or more: below, a NumPy force pass costs about a
# millisecond or less, and loading the compiled code (a fraction of a second) would cost more than it saves
AUTO_MIN = 4096

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


def compiled(backend, size):
    """Whether a pass over `size` particles runs compiled, for an object's `backend` option.

    An object with a compiled form asks at each evaluation; when the answer
    is True it imports its own kernels (its package's ``kernels.py``), which
    import numba: ``import particles`` never does.

    Returns
    -------
    bool
        True when `backend` resolves to numba (:func:`resolve`) and numba
        loads. With ``"auto"``, a numba that cannot be loaded (a broken
        install, a sandbox) gives False, with a warning, from then on; with
        ``"numba"`` its error is raised.
    """
    if resolve(backend, size) != "numba":
        return False
    try:
        from . import compile  # noqa: F401, PLC0415  (numba and its settings)
    except Exception as error:
        if (get_backend() if backend is None else backend) != "auto":
            raise
        _state["broken"] = True
        warnings.warn(f"backend 'auto': numba could not be loaded ({error}); using NumPy", RuntimeWarning,
                      stacklevel=3)
        return False
    return True
