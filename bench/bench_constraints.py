"""Constraints against springs on a stiff cloth: wall time per simulated second at equal maximum strain.

The stiff cloth of ``bench_cloth.py`` (part 2): 64^2 particles, 1 m^2, 0.2 kg/m^2,
stretch modulus 5000 N/m with physical scaling, damping 0.1 /s, hanging from its
two top corners, released at rest in the vertical plane, simulated for 1 s.
With its springs stepped explicitly (symplectic Euler at 90% of its stable
step) its largest strain over the second sets the target; every method then
runs at its cheapest setting, among a few, whose largest strain stays within
the target plus 5%:

* explicit springs: symplectic Euler at 0.9 h_max (sets the target);
* Provot: springs ten times softer (an explicit step sqrt(10) times longer),
  the constraint capping structural and shear springs at the target (limit
  0.9 x target, tolerance 0.1 x target, Jacobi passes);
* Baraff-Witkin (conjugate gradients) and the prefactorized solver (Liu et
  al.): the longest of h = 1/30, 1/60, 1/120, 1/240 s within the target;
* XPBD, compliance 1 / k (the same springs as constraints), h = 1/60 s: the
  fewest substeps of one iteration within the target, from a doubling
  sequence, or the same budget split into fewer substeps of 2 or 4
  iterations if that is cheaper (searched on the first 0.25 s, where the
  largest strain occurs; the chosen setting is then timed over 1 s).

Wall times are the best of one run each (a shared machine: read the ratios,
measured in the same run). The load average is printed before and after.

First, the XPBD substep itself (issue 24's acceptance: compiled at 128^2 at
least 8x the NumPy solver), NumPy against the compiled substep
(:class:`particles.xpbd.compiled_substep.CompiledSubstep`: one compiled call per
substep), both as ``XPBD.from_system(..., backend=...)``, Gauss-Seidel, one
iteration: a step of one substep (the violation measured at its end
included), and a step of 10 substeps divided by 10, on

* the cloth of ``bench_backends.py`` part 3 (128^2, damped springs kd = 0.05
  kg/s, gravity, two pinned corners, a perturbed moving state);
* the same with isometric bending (``bending_modulus`` 1e-4 N m, physical
  scaling): 97k distance and 32k bending constraints;
* the lectures' cloth with air damping (physical scaling, ``damping=0.05``):
  the damping force folded into the compiled prediction.

Times are the best of several calls in three rounds, NumPy and compiled
alternating; "1 thread" is the compiled substep with numba on one thread.

Run:  python bench/bench_constraints.py [--quick] [--substep-only]    (--quick: 32^2, substeps at 64^2)
"""

import argparse
import math
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # steadier timings for the small solves (set before NumPy)

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import best_time  # noqa: E402

from particles import ConvergenceError, backends  # noqa: E402
from particles.constraints import ProvotConstraint  # noqa: E402
from particles.implicit import BaraffWitkin, Prefactored  # noqa: E402
from particles.integrators import symplectic_euler  # noqa: E402
from particles.massspring import cloth  # noqa: E402
from particles.xpbd import XPBD  # noqa: E402

T = 1.0
SLACK = 1.05
STEPS = (1 / 30, 1 / 60, 1 / 120, 1 / 240)


def make(n, modulus=5000.0):
    return cloth(n, n, scaling="physical", areal_density=0.2, stretch_modulus=modulus, damping=0.1)


def run(system, method, h, T=T):
    """Wall time (s) of T seconds and the largest strain of any spring over about 100 records."""
    steps = math.ceil(T / h - 1e-9)
    every = max(1, steps // 100)
    start = time.perf_counter()
    t, X = system.run(T, h, method=method, every=every)
    wall = time.perf_counter() - start
    return wall, max(system.max_strain(x) for x in X)


def explicit(n):
    c = make(n)
    h = 0.9 * c.max_stable_step()
    wall, strain = run(c, "symplectic_euler", h)
    return {"name": "explicit springs", "setting": f"h = {1e3 * h:.3f} ms", "wall": wall, "strain": strain}


def provot(n, target):
    c = make(n, modulus=500.0)
    h = 0.9 * c.max_stable_step()
    constraint = ProvotConstraint.from_system(c, max_strain=0.9 * target, tol=0.1 * target)
    wall, strain = run(c, constraint.stepper(symplectic_euler), h)
    passes = np.mean([r.iterations for r in constraint.history])
    return {"name": "Provot (springs / 10)", "setting": f"h = {1e3 * h:.3f} ms, {passes:.0f} passes/step",
            "wall": wall, "strain": strain}


def longest_step(name, n, target, solver):
    """The longest step of STEPS whose run stays within the target (the last one tried otherwise)."""
    for h in STEPS:  # a loop over the few candidate steps, longest first
        c = make(n)
        try:
            wall, strain = run(c, solver(c, h), h)
        except ConvergenceError as error:  # a step the solver could not solve: try a shorter one
            print(f"    {name} at h = 1/{round(1 / h)} s: {str(error)[:80]}...")
            continue
        if strain <= SLACK * target:
            break
    return {"name": name, "setting": f"h = 1/{round(1 / h)} s", "wall": wall, "strain": strain}


def xpbd(n, target, log, search=0.25):
    """The cheapest XPBD setting within the target: substeps doubled (one iteration), then the same budget split.

    The search runs the first `search` seconds (the largest strain comes with the first drop, within 0.15 s)
    and times only the chosen setting over T; should that run exceed the target, the search goes on.
    """
    def quarter(substeps, iterations):
        c = make(n)
        wall, strain = run(c, XPBD.from_system(c, substeps=substeps, iterations=iterations), 1 / 60, search)
        log(f"    XPBD {substeps:4d} substeps x {iterations} iteration{'s' if iterations > 1 else ' '} "
            f"({search:g} s): strain {100 * strain:.2f}%, {wall:.2f} s")
        return wall, strain

    substeps = 50
    while True:  # a loop over doubling substep counts
        wall, strain = quarter(substeps, 1)
        if strain <= SLACK * target or substeps >= 3200:
            choices = [(wall, substeps, 1)]
            for iterations in (2, 4):  # the same budget as fewer substeps of more iterations
                w, s = quarter(substeps // iterations, iterations)
                if s <= SLACK * target:
                    choices.append((w, substeps // iterations, iterations))
            _, chosen_s, chosen_i = min(choices)
            c = make(n)
            wall, strain = run(c, XPBD.from_system(c, substeps=chosen_s, iterations=chosen_i), 1 / 60)
            if strain <= SLACK * target or substeps >= 3200:
                break
        substeps *= 2
    return {"name": "XPBD", "setting": f"h = 1/60 s, {chosen_s} substeps x {chosen_i} iter.", "wall": wall,
            "strain": strain}


def substep_cases(n):
    """The cloths of the substep table: name -> (system, state)."""
    rng = np.random.default_rng(0)

    def moving(c):
        X = c.state()
        free = np.setdiff1d(np.arange(c.n), c.pinned)
        X[free, 0] += rng.normal(scale=0.05 / n, size=(len(free), 3))
        X[free, 1] = rng.normal(scale=0.1, size=(len(free), 3))
        return c, np.asfortranarray(X)

    return {"damped springs, gravity": moving(cloth(n, n, kd=0.05)),
            "+ isometric bending": moving(cloth(n, n, kd=0.05, scaling="physical", bending_modulus=1e-4)),
            "air damping": moving(cloth(n, n, scaling="physical", damping=0.05))}


def xpbd_substeps(n, rounds=3):
    """NumPy and compiled XPBD substeps on the cloths of substep_cases: a table in ms, and the ratios."""
    if "numba" not in backends.available():
        print("  (numba is not installed: no compiled substep to time)")
        return
    import numba

    import particles.backends.compile  # noqa: F401  (before numba starts its threads: it picks their pool)

    threads = numba.get_num_threads()
    print(f"XPBD substep at {n}^2, Gauss-Seidel, 1 iteration (numba {numba.__version__}, {threads} threads, "
          f"load average {os.getloadavg()[0]:.2f}), ms")
    print(f"{'cloth':>27} {'constraints':>11} {'substeps':>8} {'numpy':>8} {'compiled':>9} {'1 thread':>9} "
          f"{'np/compiled':>12}")
    for name, (c, X) in substep_cases(n).items():
        for substeps, h in ((1, 1 / 600), (10, 1 / 60)):
            solvers = {be: XPBD.from_system(c, substeps=substeps, iterations=1, backend=be)
                       for be in ("numpy", "numba")}
            out = {be: s(None, X, 0.0, h) for be, s in solvers.items()}  # compiles, checks
            assert np.abs(out["numpy"] - out["numba"]).max() <= 1e-12 * np.abs(out["numpy"]).max(), name
            best = {}
            for _ in range(rounds):  # rounds, NumPy and compiled alternating, the best of each kept
                for key, be in (("numpy", "numpy"), ("numba", "numba"), ("1 thread", "numba")):
                    before = numba.get_num_threads()
                    numba.set_num_threads(1 if key == "1 thread" else before)
                    try:
                        t = best_time(lambda: solvers[be](None, X, 0.0, h), repeat=10 if substeps == 1 else 3)
                    finally:
                        numba.set_num_threads(before)
                    best[key] = min(best.get(key, np.inf), t / substeps)
            count = sum(len(k) for k in solvers["numba"].constraints)
            print(f"{name:>27} {count:>11} {substeps:>8} {1e3 * best['numpy']:>8.2f} {1e3 * best['numba']:>9.2f} "
                  f"{1e3 * best['1 thread']:>9.2f} {best['numpy'] / best['numba']:>11.1f}x")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a 32^2 cloth (substeps at 64^2)")
    parser.add_argument("--substep-only", action="store_true", help="only the XPBD substep table")
    args = parser.parse_args(argv)
    xpbd_substeps(64 if args.quick else 128)
    if args.substep_only:
        return
    print()
    n = 32 if args.quick else 64
    load = os.getloadavg()[0]
    print(f"Simulate {T:g} s of a stiff {n}^2 cloth at equal largest strain; load average before: {load:.2f}")
    rows = [explicit(n)]
    target = rows[0]["strain"]
    print(f"  target: the explicit springs' largest strain, {100 * target:.2f}% (+{100 * (SLACK - 1):.0f}% slack)")
    rows.append(provot(n, target))
    rows.append(longest_step("Baraff-Witkin (CG)", n, target, lambda c, h: BaraffWitkin(c)))
    rows.append(longest_step("prefactorized (Liu)", n, target, lambda c, h: Prefactored(c, h)))
    rows.append(xpbd(n, target, print))
    print(f"{'method':>22} {'setting':>38} {'strain':>7} {'wall (s)':>9} {'vs explicit':>12}")
    for r in rows:
        print(f"{r['name']:>22} {r['setting']:>38} {100 * r['strain']:>6.2f}% {r['wall']:>9.2f} "
              f"{rows[0]['wall'] / r['wall']:>11.2f}x")
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
