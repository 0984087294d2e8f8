"""Implicit solvers against compiled explicit springs at equal largest strain, 5000 to 80000 N/m (issue 24).

The stiff cloth of ``bench_cloth.py`` (part 2): 64^2 particles, 1 m^2, 0.2
kg/m^2, physical scaling, air damping 0.1 /s, hanging from its two top
corners, released at rest in the vertical plane, simulated for 1 s, at
stretch moduli of 5000, 20000 and 80000 N/m. For each modulus:

* compiled explicit: symplectic Euler at 90% of its stability limit, the
  springs on numba (the whole step in one compiled pass,
  :mod:`particles.backends`); its largest spring strain over the second
  (over about 200 recorded states) is the target;
* each implicit solver at its best step: the longest of h = 1/10, 1/15,
  1/20, 1/30, 1/60 s whose largest strain (over every step) is at most the
  target, the solver at its defaults: the prefactorized solver
  (:class:`~particles.implicit.Prefactored`, Anderson-accelerated
  local/global iterations to ``tol = 0.1``) compiled and in NumPy, and
  Baraff-Witkin (:class:`~particles.implicit.BaraffWitkin`, two Newton
  solves per step, block-Jacobi CG falling back to a factorization);
* each implicit solver at the frame step, h = 1/60 s (an animation at 60
  frames a second), whatever its strain there;
* the ratio: the explicit run's wall time over the implicit run's.

Every compiled kernel is compiled (or loaded from the cache) before the
timed runs. Wall times are of one run each, on a shared machine: read the
ratios, measured in the same run; the load average is printed before and
after. The configurations are those of :func:`explicit_config` and
:data:`STEPS` (``tests/library/implicit/test_prefactored.py``
checks the strain criterion on them).

Run:  python bench/bench_implicit.py [--quick] [--moduli 5000 20000 80000] [--no-baraff-witkin]
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

from particles import ConvergenceError, backends  # noqa: E402
from particles.implicit import BaraffWitkin, Prefactored  # noqa: E402
from particles.massspring import cloth  # noqa: E402

T = 1.0
MODULI = (5000.0, 20000.0, 80000.0)
STEPS = (1 / 10, 1 / 15, 1 / 20, 1 / 30, 1 / 60)
FRAME = 1 / 60  # the step of an animation at 60 frames a second
RECORDS = 200  # states recorded by the explicit run (its largest strain is the largest over them)


def make(n, modulus):
    """The stiff cloth: n x n, 1 m^2, 0.2 kg/m^2, physical scaling, air damping 0.1 /s, two pinned corners."""
    return cloth(n, n, scaling="physical", areal_density=0.2, stretch_modulus=modulus, damping=0.1)


def explicit_config(c):
    """Symplectic Euler's step for cloth `c`: 90% of its stability limit, in seconds."""
    return 0.9 * c.max_stable_step()


def run(c, method, h, T=T, records=None):
    """Wall time (s) of T seconds, and the largest strain over the recorded states (every step by default)."""
    steps = math.ceil(T / h - 1e-9)
    every = 1 if records is None else max(1, steps // records)
    start = time.perf_counter()
    _, X = c.run(T, h, method=method, every=every)
    wall = time.perf_counter() - start
    return wall, max(c.max_strain(x) for x in X)


def explicit(n, modulus):
    """Compiled symplectic Euler at 0.9 h_max: a row."""
    with backends.using("numba"):
        c = make(n, modulus)
        h = explicit_config(c)
        run(make(n, modulus), "symplectic_euler", h, T=50 * h)  # compile (or load) the step first
        wall, strain = run(c, "symplectic_euler", h, records=RECORDS)
    return {"name": "explicit (numba)", "h": h, "steps": math.ceil(T / h - 1e-9), "wall": wall, "strain": strain,
            "work": "-"}


def work(solver):
    """Local/global iterations (prefactorized) or linear solves (Baraff-Witkin) per step."""
    if isinstance(solver, Prefactored):
        return f"{np.mean(solver.counts):.1f} it."
    return f"{np.mean(solver.newton):.2f} solves"


def implicit(name, n, modulus, target, build, log):
    """The longest step of STEPS whose run stays within the target strain: a row (None if none does)."""
    for h in STEPS:  # a loop over the few candidate steps, longest first
        c = make(n, modulus)
        solver = build(c, h)
        try:
            wall, strain = run(c, solver, h)
        except ConvergenceError as error:  # a step the solver could not solve: try a shorter one
            log(f"    {name} at h = 1/{round(1 / h)} s: {str(error)[:70]}...")
            continue
        log(f"    {name} at h = 1/{round(1 / h)} s: strain {100 * strain:.3f}%, {wall:.2f} s, {work(solver)}")
        if strain <= target:
            return {"name": name, "h": h, "steps": math.ceil(T / h - 1e-9), "wall": wall, "strain": strain,
                    "work": work(solver)}
    return None


def at_frame_step(name, n, modulus, build):
    """The solver at h = FRAME whatever its strain: a row (None if it cannot solve a step)."""
    c = make(n, modulus)
    solver = build(c, FRAME)
    try:
        wall, strain = run(c, solver, FRAME)
    except ConvergenceError:
        return None
    return {"name": f"{name} 1/60", "h": FRAME, "steps": math.ceil(T / FRAME - 1e-9), "wall": wall,
            "strain": strain, "work": work(solver)}


def warm_up():
    """Compile (or load) the prefactorized solver's kernels before any timed run."""
    c = make(8, 5000.0)
    Prefactored(c, 1 / 30, backend="numba").step(c.state(), 0.0, 1 / 30)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a 32^2 cloth")
    parser.add_argument("--moduli", type=float, nargs="+", default=MODULI, help="stretch moduli, N/m")
    parser.add_argument("--no-baraff-witkin", action="store_true", help="skip Baraff-Witkin (the slowest)")
    args = parser.parse_args(argv)
    n = 32 if args.quick else 64
    if "numba" not in backends.available():
        print("numba is not installed (pip install 'particles[fast]'): nothing compiled to compare")
        return
    import numba

    warm_up()
    solvers = [("prefactorized (numba)", lambda c, h: Prefactored(c, h, backend="numba")),
               ("prefactorized (numpy)", lambda c, h: Prefactored(c, h, backend="numpy"))]
    if not args.no_baraff_witkin:
        solvers.append(("Baraff-Witkin", lambda c, h: BaraffWitkin(c)))
    print(f"Simulate {T:g} s of a stiff {n}^2 cloth at equal largest strain (numba {numba.__version__}, "
          f"{numba.get_num_threads()} threads); load average before: {os.getloadavg()[0]:.2f}")
    rows = []
    for modulus in args.moduli:  # a loop over the stiffnesses
        reference = explicit(n, modulus)
        print(f"  {modulus:g} N/m: explicit {reference['steps']} steps, {reference['wall']:.2f} s, "
              f"largest strain {100 * reference['strain']:.3f}% (the target)", flush=True)
        rows.append((modulus, reference, reference))
        for name, build in solvers:  # a loop over the implicit solvers
            row = implicit(name, n, modulus, reference["strain"], build, lambda s: print(s, flush=True))
            if row is not None:
                rows.append((modulus, row, reference))
            if row is None or row["h"] != FRAME:
                frame = at_frame_step(name, n, modulus, build)
                if frame is not None:
                    rows.append((modulus, frame, reference))
    print(f"{'N/m':>6} {'method':>27} {'h (s)':>9} {'steps':>6} {'per step':>12} {'wall (s)':>9} "
          f"{'max strain':>11} {'vs explicit':>12}")
    for modulus, row, reference in rows:
        print(f"{modulus:>6g} {row['name']:>27} {row['h']:>9.2e} {row['steps']:>6} {row['work']:>12} "
              f"{row['wall']:>9.2f} {100 * row['strain']:>10.3f}% {reference['wall'] / row['wall']:>11.2f}x")
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
