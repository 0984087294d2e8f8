"""The builders' cloth configurations, NumPy against the compiled path, per step of ``run``, in one run.

Each configuration is a 128^2 cloth of :func:`particles.massspring.cloth`
(``scaling="physical"``) as a documented keyword or a wrapper of the library
makes it, stepped by symplectic Euler through :meth:`ParticleSystem.run`
(its divergence guard included), ``h = 5e-5`` s:

* springs + gravity (the defaults, two pinned corners);
* ``damping=0.05``: air damping (:class:`~particles.forces.fields.Damping`, the lectures' cloth);
* ``kd=2e-4``: damping along every spring;
* ``bending_modulus=1e-4``: bending at the joints (:class:`~particles.forces.Bending`);
* ``wind=(2, 0, 1)`` with ``damping=0.05``: wind and drag;
* ``pins="top edge"``: 128 pins;
* Provot's pass (:class:`~particles.constraints.ProvotConstraint`, structural and shear springs, 10%);
* a collider: a horizontal sheet dropped on a sphere at 1 m/s (:class:`~particles.collisions.Collider`,
  backtracking, no bounce, friction 0.3), timed after 0.1 s, when it wraps the sphere's cap;
* all of them at once (damping, kd, bending, wind, Provot's pass and the sphere).

NumPy is ``backends.using("numpy")``, compiled ``backends.using("numba")``
(the compiled step, :class:`particles.massspring.compiled_step.CompiledStep`, and
the compiled fixes, :mod:`particles.constraints.kernels` and
:mod:`particles.collisions.collider_kernels`); "1 thread" is the
compiled path with numba on one thread (the time when the other core is
busy). Each configuration starts both from the same state, and their end
states after one step are checked against each other first (1e-12
relative; 1e-9 with the collider, whose crossing times are found to a
tolerance, ``|H| <= 1e-12`` m, so that states a rounding error apart end a
bounce up to that far apart). Times are the best of several
runs, in rounds that alternate the backends (a shared machine); read the
ratios, measured in the same run.

Run:  python bench/bench_builders.py [--quick] [--size N]
"""

import argparse
import contextlib
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _timing import best_time  # noqa: E402

from particles import backends  # noqa: E402
from particles.collisions import Collider, Sphere  # noqa: E402
from particles.constraints import ProvotConstraint  # noqa: E402
from particles.massspring import cloth  # noqa: E402

H = 5e-5  # s
STEPS = 20  # steps of each timed run
ROUNDS = 3
DRAPE = 0.1  # s of fall on the sphere before the timed runs


def sheet_over_sphere(n, **options):
    """A horizontal sheet 2 mm above a sphere of radius 0.3 m, falling at 1 m/s, and the sphere."""
    c = cloth(n, n, plane="horizontal", pins=None, origin=(-0.5, -0.5, 0.302), scaling="physical", **options)
    X = c.state()
    X[:, 1, 2] = -1.0
    c.set_state(X)
    return c, Sphere([0.0, 0.0, 0.0], 0.3)


def draped(c, method, seconds=DRAPE):
    """`c` after `seconds` of its run (compiled): the sheet wraps the sphere's cap."""
    with backends.using("numba"):
        c.run(seconds, H, method=method, every=10**9)
    c.set_state(t=0.0)
    return c


def configurations(n):
    """(name, build) pairs: build() returns the system and the method of its run."""
    def plain(**options):
        return lambda: (cloth(n, n, scaling="physical", **options), "symplectic_euler")

    def provot():
        c = cloth(n, n, scaling="physical")
        return c, ProvotConstraint.from_system(c).stepper("symplectic_euler")

    def sphere(everything=False):
        extra = dict(damping=0.05, kd=2e-4, bending_modulus=1e-4, wind=(2.0, 0.0, 1.0)) if everything else {}
        c, ball = sheet_over_sphere(n, **extra)
        inner = ProvotConstraint.from_system(c).stepper("symplectic_euler") if everything else "symplectic_euler"
        method = Collider(ball, restitution=0.0, friction=0.3).stepper(inner, m=c.m, pinned=c.pinned)
        return draped(c, method), method

    return [("springs + gravity", plain()), ("damping=0.05 (air)", plain(damping=0.05)),
            ("kd=2e-4 (springs)", plain(kd=2e-4)), ("bending_modulus=1e-4", plain(bending_modulus=1e-4)),
            ("wind + drag", plain(wind=(2.0, 0.0, 1.0), damping=0.05)), ('pins="top edge"', plain(pins="top edge")),
            ("Provot's pass", provot), ("sphere collider", sphere),
            ("all of them", lambda: sphere(everything=True))]


@contextlib.contextmanager
def threads(k):
    """numba on k threads within the block."""
    import numba

    before = numba.get_num_threads()
    numba.set_num_threads(min(k, numba.config.NUMBA_NUM_THREADS))
    try:
        yield
    finally:
        numba.set_num_threads(before)


def timed_run(c, method, X, be):
    """A function that runs STEPS steps from X with backend `be`, and the state after one step."""
    def run(steps=STEPS):
        c.set_state(X, 0.0)
        with backends.using(be):
            return c.run(steps * H, H, method=method, every=steps)[1][-1]
    run()
    return run, run(1)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="64^2 instead of 128^2")
    parser.add_argument("--size", type=int, default=None, help="particles per side (default 128)")
    args = parser.parse_args(argv)
    if "numba" not in backends.available():
        print("numba is not installed (pip install 'particles[fast]'): nothing to compare")
        return
    import numba

    import particles.backends.compile  # noqa: F401  (before numba starts its threads: it picks their pool)

    n = args.size or (64 if args.quick else 128)
    print(f"numba {numba.__version__}, {numba.get_num_threads()} threads; load average before: "
          f"{os.getloadavg()[0]:.2f}; {n}^2 cloth, h = {H} s, {STEPS} steps per run, ms per step")
    start = time.perf_counter()
    runs = []
    for name, build in configurations(n):
        c, method = build()
        X = c.state()
        funcs = {}
        for be in ("numpy", "numba"):
            funcs[be], end = timed_run(c, method, X, be)
            funcs[be + " end"] = end
        error = np.abs(funcs["numpy end"] - funcs["numba end"]).max() / np.abs(funcs["numpy end"]).max()
        if error > (1e-9 if "sphere" in name or "all" in name else 1e-12):
            raise AssertionError(f"{name}: the compiled run differs from the NumPy run by {error:.1e} (relative)")
        runs.append((name, funcs, error))
    times = {name: {} for name, _, _ in runs}
    for _ in range(ROUNDS):  # rounds alternating the backends: the best of each is kept
        for name, funcs, _ in runs:
            for key, be, k in (("numpy", "numpy", None), ("compiled", "numba", None), ("1 thread", "numba", 1)):
                with threads(k) if k else contextlib.nullcontext():
                    t = best_time(funcs[be], repeat=3, min_time=0.1) / STEPS
                times[name][key] = min(times[name].get(key, np.inf), t)
    print(f"{'configuration':>22} {'numpy':>8} {'compiled':>9} {'ratio':>7} {'1 thread':>9} {'ratio':>7} "
          f"{'rel. diff':>10}")
    for name, _, error in runs:
        t = times[name]
        print(f"{name:>22} {1e3 * t['numpy']:>8.2f} {1e3 * t['compiled']:>9.2f} {t['numpy'] / t['compiled']:>6.2f}x "
              f"{1e3 * t['1 thread']:>9.2f} {t['numpy'] / t['1 thread']:>6.2f}x {error:>10.1e}")
    print(f"load average after: {os.getloadavg()[0]:.2f}; {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
