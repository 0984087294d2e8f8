"""Compile the kernels ahead of use: every compiled path of the library once, on small systems (``particles warm``).

numba compiles a kernel the first time it is called with new argument types
(seconds per kernel, 148 s for all of them in one process on the 2-core machine) and keeps
the machine code in its disk cache (:mod:`particles.backends.compile`). Without a
warm cache, each new process pays again, and processes started at the same
time (two test workers, a class's notebooks opened at once) each compile the
same kernel. :func:`warm` pays once, ahead: it runs each compiled path of the
library (the explicit step of cloth, strings and hair with all their forces,
Provot's pass, the collider, XPBD and PBD, Lennard-Jones, N-body gravity, the
cloth collision pipeline, the prefactorized solver) on systems of a few
dozen particles, once with every loop parallel and once with every loop on
one thread, so that both copies of each kernel are compiled for the
argument types the library passes.

``particles warm`` runs it from the command line (:func:`command`, for example in a
course's container image, or before ``make test``); a kernel already in the cache is
loaded, not compiled, so a second call takes a few seconds. It sits with the command
line, above the library: it runs every area's compiled path, and the backends know none. Kernels that
:func:`warm` misses are compiled on first use, as before: nothing depends on
it but the time.
"""

import contextlib
import sys
import time

import numpy as np

__all__ = ["warm", "command"]


@contextlib.contextmanager
def _loops(parallel):
    """Every compiled loop parallel (`parallel`) or none, within the block (numba on two threads if it can)."""
    import numba

    from .backends import compile as kernels
    from .forces import kernels as force_kernels

    before = kernels.PARALLEL_MIN, force_kernels.SPRING_THREADS, numba.get_num_threads()
    kernels.PARALLEL_MIN = 0 if parallel else 10**9  # what pick() compares a loop's size with
    force_kernels.SPRING_THREADS = 1 if parallel else before[1]  # springs: forces per spring, then a gather
    numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
    try:
        yield
    finally:
        kernels.PARALLEL_MIN, force_kernels.SPRING_THREADS = before[:2]
        numba.set_num_threads(before[2])


def _explicit():
    """The compiled step and the per-force kernels: cloth, strings and hair with their documented forces."""
    from .collisions import Collider, Sphere
    from .constraints import ProvotConstraint
    from .massspring import cloth, hair, string

    h = 1e-4
    systems = [cloth(6, 6, scaling="physical", damping=0.05, kd=2e-4, bending_modulus=1e-4, wind=(2.0, 0.0, 1.0)),
               cloth(6, 6, scaling="physical", pins="top edge"),
               string(12, kd=0.01), string(12, d=3, kd=0.01, damping=0.1), hair(10, kd=0.001),
               hair(10, d=3, direction=[1.0, 0.0, 0.2], damping=0.05)]
    for c in systems:  # a loop over the few systems
        c.run(3 * h, h, method="symplectic_euler")
        c.derivative(c.state(), 0.0)
        c.set_state(np.asfortranarray(c.state()), 0.0)  # states NumPy's steppers give: the F-ordered forms
        c.run(c.t + 2 * h, h, method="symplectic_euler")
        c.derivative(np.asfortranarray(c.state()), c.t)
    c = cloth(6, 6, scaling="physical")
    X = c.state()
    X[:, 0] *= 1.3  # every spring 30% too long: the passes correct the springs, not only measure them
    for method in ("jacobi", "gauss-seidel"):
        c.set_state(X, 0.0)
        c.run(3 * h, h, method=ProvotConstraint.from_system(c, method=method).stepper("symplectic_euler"))
    falling = [(string(12, pin="none", kd=0.01), Sphere([0.5, -0.3], 0.3)),
               (cloth(6, 6, plane="horizontal", pins=None, origin=(-0.5, -0.5, 0.02), scaling="physical"),
                Sphere([0.0, 0.0, -0.3], 0.3))]
    for c, ball in falling:  # a string in 2D and a sheet in 3D, falling at 1 m/s onto a ball
        X = c.state()
        X[:, 1, -1] = -1.0
        c.set_state(X, 0.0)
        for inner in ("symplectic_euler", ProvotConstraint.from_system(c).stepper("symplectic_euler")):
            c.run(c.t + 3 * h, h, method=Collider(ball, restitution=0.0, friction=0.3).stepper(inner, m=c.m,
                                                                                             pinned=c.pinned))


def _constraints():
    """XPBD and PBD substeps (Gauss-Seidel and Jacobi), on cloth and hair."""
    from .massspring import cloth, hair
    from .xpbd import PBD, XPBD

    for c in (cloth(6, 6, kd=0.1), cloth(6, 6, bending_modulus=1e-4, damping=0.05), hair(10, kd=0.2)):
        for solver in (XPBD.from_system(c, substeps=2), XPBD.from_system(c, substeps=2, method="jacobi"),
                       PBD.from_system(c, substeps=2)):
            X = c.state()
            solver(None, X, 0.0, 0.01)
            solver(None, np.asfortranarray(X), 0.0, 0.01)


def _pairs():
    """Lennard-Jones (open and periodic) and N-body gravity."""
    from .forces import LennardJones, NBodyGravity
    from .md import fcc_lattice

    x, box = fcc_lattice(4, 0.8)
    for lj in (LennardJones.from_epsilon_sigma(skin=0.3, box=box), LennardJones.from_epsilon_sigma(skin=0.3)):
        lj(x)
    rng = np.random.default_rng(0)
    NBodyGravity(G=1.0, softening=0.05)(rng.normal(size=(50, 3)), m=rng.uniform(0.5, 2.0, 50))


def _cloth_collisions():
    """The cloth collision pipeline (broad phase, proximity, the continuous test, impact zones, the strain limit):
    a small sheet dropped on a ball on the floor (:func:`particles.explore.cloth_drop`), just above it, a sheet
    folded onto itself (:func:`_folded_sheet`) and a stretched one (:func:`_strain_limited`)."""
    from .explore import cloth_drop

    cloth_drop(200.0, n=8, T=0.1, h=1 / 40, drop=0.005, snapshots=2)
    _folded_sheet()


def _folded_sheet(n=8):
    """Steps of an n x n sheet folded in two whose upper half (or one vertex of it) falls through the lower: the
    self-collision stages that a sheet on a ball never reaches (the proximity iterations; without them, the
    continuous test's passes over the vertices still moving, by a grid or, for a few, box against box)."""
    from .collisions import ClothCollisions, Plane, TriangleMesh

    s = 1.0 / (n - 1)
    thickness = 0.25 * s
    i, j = np.meshgrid(np.arange(n), np.arange(n))  # particle (i, j) is vertex j n + i
    upper = j >= n // 2
    x0 = np.stack([i * s, np.where(upper, n - 1 - j, j) * s, 0.5 + np.where(upper, 3 * thickness, 0.0)], axis=-1)
    x0 = x0.reshape(-1, 3)
    fall = np.where(upper.reshape(-1, 1), [0.0, 0.0, 6 * thickness], 0.0)  # the upper half through the lower
    poke = np.zeros_like(x0)
    poke[(n - 2) * n + n // 2, 2] = 6 * thickness  # one vertex of it
    h = 0.01
    for proximity, dx in ((True, fall), (False, fall), (False, poke)):
        guard = ClothCollisions(TriangleMesh.grid(n, n), thickness, friction=0.3, proximity=proximity,
                                bodies=[Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])])
        guard.resolve(x0, x0 - dx, -dx / h, 0.0, h)
    _strain_limited(n)


def _strain_limited(n=8):
    """The strain limit inside the pipeline (Provot's Gauss-Seidel passes on a step's end): a sheet stretched
    20% along x falling onto the floor."""
    from .collisions import ClothCollisions, Plane
    from .massspring import cloth

    c = cloth(n, n, plane="horizontal", origin=(-0.5, -0.5, 0.02), pins=None, scaling="physical")
    guard = ClothCollisions.from_system(c, thickness=0.25 / (n - 1), friction=0.3, max_strain=0.1,
                                        bodies=[Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])])
    x0 = c.X[:, 0].copy()
    x1 = x0 * [1.2, 1.0, 1.0] - [0.0, 0.0, 0.03]
    guard.resolve(x0, x1, (x1 - x0) / 0.01, 0.0, 0.01)


def _implicit():
    """The prefactorized solver's compiled local step and solves, in 2D and 3D."""
    from .implicit import Prefactored
    from .massspring import cloth, string

    for c in (cloth(6, 6, kd=0.0), string(12, kd=0.0)):
        h = 0.01
        c.run(2 * h, h, method=Prefactored(c, h, backend="numba"))


PARTS = {"explicit step": _explicit, "cloth collisions": _cloth_collisions, "constraints": _constraints,
         "pairs": _pairs, "implicit": _implicit}
"""The parts of :func:`warm`, the two long ones first (each took 57.6, 63.2, 16.1, 9.2 and 0.0 s to compile in
``particles warm --jobs 2`` on a fresh clone on the 2-core machine, 2026-12-07, 75.3 s in all. Each kernel
is compiled for one memory order and one type of element table (C-ordered states, read-only index tables):
compiled for both, the same parts took 96.7 s in all on a fresh clone the day before, and 183.5 s in one
process against 148.3 s, on the same host in the same hour)."""


def _part(name):
    """One part, both loop modes, in this process: (name, seconds)."""
    from .backends import using

    t = time.perf_counter()
    with using("numba"):
        for parallel in (True, False):
            with _loops(parallel):
                PARTS[name]()
    return name, time.perf_counter() - t


def warm(parts=None, jobs=1, report=None):
    """Compile (or load from the disk cache) the kernels of each compiled path, parallel and serial copies.

    Parameters
    ----------
    parts : list of str, optional
        Keys of :data:`PARTS` (default: all).
    jobs : int, optional
        Processes that share the parts (default 1: this one). Parts in other processes compile into the
        same disk cache; this process's own kernels are then loaded on first use.
    report : callable, optional
        Called with one line per part as it ends (its name and seconds).

    Returns
    -------
    float
        Seconds taken.

    Raises
    ------
    ImportError
        When numba is not installed (``pip install 'particles[fast]'``).
    ValueError
        For a part that is not in :data:`PARTS`, or `jobs` below 1.
    """
    from .backends import available

    if "numba" not in available():
        raise ImportError("warm compiles the numba kernels, and numba is not installed: "
                          "pip install 'particles[fast]'")
    names = list(PARTS) if parts is None else list(parts)
    unknown = [p for p in names if p not in PARTS]
    if unknown:
        raise ValueError(f"parts must be among {list(PARTS)}, got {unknown}")
    if isinstance(jobs, bool) or not isinstance(jobs, (int, np.integer)) or jobs < 1:
        raise ValueError(f"jobs must be a positive integer, got {jobs!r}")
    start = time.perf_counter()
    if jobs == 1:
        done = map(_part, names)
    else:  # in the order of PARTS (the two long parts first), each to the next free process
        import concurrent.futures
        import multiprocessing

        pool = concurrent.futures.ProcessPoolExecutor(min(jobs, len(names)),
                                                      mp_context=multiprocessing.get_context("spawn"))
        done = (f.result() for f in concurrent.futures.as_completed([pool.submit(_part, n) for n in names]))
    try:
        for name, seconds in done:  # a loop over the few parts
            if report is not None:
                report(f"{name}: {seconds:.1f} s")
    finally:
        if jobs > 1:
            pool.shutdown()
    return time.perf_counter() - start


def command(jobs=1):
    """``particles warm [--jobs N]``: :func:`warm`, a line per part; exit status 2 with the reason on bad input."""
    try:
        seconds = warm(jobs=jobs, report=lambda line: print(f"  {line}", flush=True))
    except (ImportError, ValueError) as error:
        print(f"particles warm: {error}", file=sys.stderr)
        return 2
    print(f"kernels compiled or loaded in {seconds:.1f} s")
    return 0
