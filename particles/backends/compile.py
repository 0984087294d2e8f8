"""The compile wrapper every kernel module uses, numba's threads, and where the machine code is cached.

A kernel module (``kernels.py`` beside its concept: :mod:`particles.forces.kernels`,
:mod:`particles.xpbd.kernels`, ...) imports :func:`jit`, :func:`inline`, :data:`prange` and
:func:`pick` from here, and nothing else of the backends. Importing this module imports numba
(:func:`particles.backends.compiled` does so only when a pass resolves to numba); without numba it
still imports (``jit`` and ``inline`` then return the plain Python functions), so that a walk over the
package never fails.

* :func:`jit`: ``numba.njit`` with the machine code cached on disk; a parallel kernel also gets a
  one-thread copy, ``kernel.serial`` (the same bits, no threads), and :func:`pick` chooses between the
  two by the length of the loop (:data:`PARALLEL_MIN`).
* :func:`inline`: a law of a concept's module (a per-item formula the NumPy code uses on whole arrays,
  written with arithmetic, ``np.sqrt``, ``np.minimum`` and ``np.maximum``) compiled into each kernel that
  calls it, so that the NumPy reference and the kernel compute it with one function.

**Threads.** Unless ``NUMBA_THREADING_LAYER`` says otherwise, GNU OpenMP where it loads, else numba's
own work queue. On the 2-core VM this was measured on (``bench/bench_threads.py``), the work queue took
17 to 38 us to start a parallel loop and woke its second thread so late that a loop of 0.2 ms ran 0.96x
to 1.46x as fast on two threads as on one; OpenMP starts one in 2 to 7 us and halves such a loop. Its
idle threads wait for the next loop by spinning, by default for milliseconds, which on a machine shared
with other processes takes their cores (in one of our runs an XPBD substep, a parallel loop per colour,
took 179 ms instead of 1.8 beside a second such process); ``GOMP_SPINCOUNT`` bounds the spin, which keeps
the back-to-back loops of a step fast.

**Cache.** In ``NUMBA_CACHE_DIR`` if it is set, else in a folder of ``~/.cache/particles/numba`` (or
``$XDG_CACHE_HOME/particles/numba``, or of the temporary directory) named for the state of the kernels'
sources: numba checks only the file that defines a kernel, and a kernel inlines the laws of another
file, so an edit of a law must not find the machine code of the old one. Never inside the package,
which may be read-only and whose files the grader checksums.
"""

import hashlib
import inspect
import os
import tempfile
import time
import types
import warnings
from pathlib import Path

from .._vectors import any_of, select, vadd, vcross, vdot, vscale, vselect, vsub

try:
    import numba
    from numba import prange
except ImportError:  # without the extra: importable (a walk over the package), never called
    numba, prange = None, range

__all__ = ["jit", "inline", "kernel_form", "prange", "pick", "parallel", "PARALLEL_MIN", "numba"]

if numba is not None:  # numba's own pedantic check, on a law inlined into a kernel with a branch: benign
    warnings.filterwarnings("ignore", message="variable '.*' is not in scope", category=numba.NumbaIRAssumptionWarning)

if numba is not None and "NUMBA_THREADING_LAYER" not in os.environ:
    os.environ["NUMBA_THREADING_LAYER"] = "default"
    os.environ.setdefault("NUMBA_THREADING_LAYER_PRIORITY", "omp workqueue tbb")  # tbb: not a dependency
    os.environ.setdefault("GOMP_SPINCOUNT", "10000")  # read by GNU OpenMP when numba first loads it
    numba.config.reload_config()  # numba reads its settings from the environment (until its threads start)

# the packages whose modules hold kernels or the laws they inline: an edit there is a new cache folder
KERNEL_PACKAGES = ("backends", "collisions", "constraints", "forces", "implicit", "massspring", "xpbd")
STALE_DAYS = 7  # cache folders of older states of the sources not used for this long are removed


def sources_state():
    """A short hash of the size and time of every module of :data:`KERNEL_PACKAGES` (their state on disk)."""
    root = Path(__file__).resolve().parents[1]
    digest = hashlib.sha1()
    for package in KERNEL_PACKAGES:  # a loop over the few packages, then their modules
        for path in sorted((root / package).glob("*.py")):
            stat = path.stat()
            digest.update(f"{package}/{path.name}:{stat.st_size}:{stat.st_mtime_ns};".encode())
    return digest.hexdigest()[:16]


def _cache_folder():
    """Where compiled kernels are kept: the user's cache, never the package (read-only, checksummed by the grader)."""
    home = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    for base in (os.path.join(home, "particles", "numba"),
                 os.path.join(tempfile.gettempdir(), f"particles-numba-{getattr(os, 'getuid', lambda: 0)()}")):
        folder = os.path.join(base, sources_state())
        try:
            os.makedirs(folder, exist_ok=True)
            if os.access(folder, os.W_OK):
                _prune(base, folder)
                return folder
        except OSError:
            continue
    return None


def _prune(base, keep):
    """Remove the cache folders of other states of the sources that were not used for STALE_DAYS days."""
    old = time.time() - STALE_DAYS * 86400
    for entry in os.scandir(base):  # a loop over the few cache folders
        if entry.is_dir() and entry.path != keep and entry.stat().st_mtime < old:
            for path in sorted(Path(entry.path).rglob("*"), reverse=True):
                try:
                    path.rmdir() if path.is_dir() else path.unlink()
                except OSError:  # another process is using it: left for later
                    pass


if numba is not None and "NUMBA_CACHE_DIR" not in os.environ and (_folder := _cache_folder()):
    os.environ["NUMBA_CACHE_DIR"] = _folder
    numba.config.reload_config()

# loops shorter than this run on one thread: starting the threads would cost more than they save (OpenMP starts
# a parallel loop in 2 to 7 us; 4096 springs or constraint rows take 25-40 us on one thread)
PARALLEL_MIN = 4096


def _compile(fn, parallel, fastmath=False):
    """``numba.njit`` with the machine code cached on disk; in memory only when no cache folder is writable."""
    if numba is None:
        return fn
    try:
        return numba.njit(cache=True, parallel=parallel, fastmath=fastmath)(fn)
    except RuntimeError:  # numba found no writable cache location (a read-only install)
        return numba.njit(cache=False, parallel=parallel, fastmath=fastmath)(fn)


def jit(parallel=False, fastmath=False):
    """Compile the decorated kernel; with `parallel`, also a one-thread copy, ``kernel.serial`` (the same bits).

    `fastmath` as numba takes it: a set of LLVM flags (e.g. ``{"contract"}``, fused multiply-adds), or False.
    """
    def wrap(fn):
        kernel = _compile(fn, parallel, fastmath)
        if parallel and numba is not None:  # a copy under its own name, so that the two have their own cache files
            copy = types.FunctionType(fn.__code__, fn.__globals__, fn.__name__ + "_serial", fn.__defaults__)
            copy.__qualname__ = fn.__qualname__ + "_serial"
            kernel.serial = _compile(copy, False, fastmath)
        return kernel
    return wrap


def inline(law, into="always"):
    """Let compiled kernels call `law`, a per-item function of a concept's module; returns `law` unchanged.

    The concept's NumPy code calls the law on whole arrays; a kernel calls the same function on one
    item, and numba compiles it into the kernel (``into="always"``: in numba's own representation, so
    that the kernel's constants reach it; ``"never"``: a function of its own, for a law with a loop,
    which LLVM still inlines). The law may use arithmetic, comparisons, ``np.sqrt``, ``np.arccos``,
    ``np.minimum``, ``np.maximum`` and other laws made callable the same way.
    """
    if numba is not None and law not in _INLINED:  # once: a law two kernel modules call is one overload
        from numba.extending import register_jitable  # noqa: PLC0415

        register_jitable(inline=into)(law)
        _INLINED.add(law)
    return law


_INLINED = set()


def kernel_form(law):
    """Decorate the form compiled kernels run for `law`: the same laws, each branch computed only where taken.

    A law written for NumPy and kernels alike chooses with ``select``, which computes both of its
    arguments first; where one is costly (an ``acos``) or the fallbacks are many, the kernel's form
    branches before computing. The form takes the law's arguments. Without numba the kernels run as
    Python, with the law itself, and the form is not used.
    """
    def register(form):
        if numba is not None:
            from numba.extending import overload  # noqa: PLC0415

            def typing(*args):
                return form
            typing.__signature__ = inspect.signature(form)  # numba matches it with the form's
            overload(law)(typing)
        return form
    return register


def _register_vector_helpers():
    """The tuple helpers of :mod:`particles._vectors` callable in kernels; ``select`` a branch, ``any_of`` the bool."""
    from numba.extending import overload  # noqa: PLC0415

    @overload(select)
    def _select(condition, a, b):
        return lambda condition, a, b: a if condition else b

    @overload(any_of)
    def _any_of(condition):
        return lambda condition: condition

    for helper in (vdot, vsub, vadd, vcross, vscale, vselect):
        inline(helper)


if numba is not None:
    _register_vector_helpers()


def parallel(size, threads=2):
    """Whether a loop of `size` items runs in parallel: at least PARALLEL_MIN items and `threads` threads."""
    return size >= PARALLEL_MIN and numba.get_num_threads() >= threads


def pick(kernel, size):
    """The parallel `kernel` for loops of at least PARALLEL_MIN items, else its one-thread copy."""
    return kernel if parallel(size) else kernel.serial
