"""A cloth dropped upright on a floor folds onto itself: no two triangles may cross at any step.

The acceptance run of issue 15: a 64 x 64 sheet (1 m, physical scaling),
standing on its lower edge with a slight bow, falls for 2 s onto a floor,
buckles and folds onto itself. It is stepped by XPBD (10 substeps, h = 10
ms) inside :class:`particles.collisions.pipeline.ClothCollisions` (thickness half
the spacing, friction 0.3), and after every step the exact test
:func:`particles.collisions.triangle_crossing.intersections` counts the crossing triangle
pairs. The treated sheet keeps its structural (stretch) springs within
Provot's 10% inside the treatment (``ClothCollisions.from_system(...,
max_strain=0.1)``, :mod:`particles.collisions.strain_limit`). The same sheet
with the floor alone (no self-collision treatment, no strain limit) is
the baseline of the same run. Printed per quarter second: time per step,
the largest number of crossing pairs, the closest pair over the thickness,
the largest structural, shear and bending (flexion) strain of a step; then
the median and the worst time per step, the most crossing pairs of a step
and the largest strain of each kind over all steps. ``--peer newton`` runs
the same sheet (particles, springs, masses, step, substeps, thickness,
friction, floor) with Newton's VBD solver and its self-contact on Warp's CPU
device and prints the same columns, crossings counted by our exact test
(:mod:`_newton_peer`, beside it; ``pip install newton``, the ``[bench]`` extra). Each run is made ``--repeat`` times (default 2), and each step's time is its best: the
runs are the same steps bit for bit (checked), so the best leaves out what the host took from one of them
(one run alone showed a worst step of 325 ms where the step itself takes 241). ``--backend`` chooses who runs the collision stages
(:mod:`particles.collisions.compiled_stages`) and the XPBD substeps (:mod:`particles.xpbd.compiled_substep`)
("auto": the collision stages compiled from 64 vertices, :data:`particles.collisions.candidate_cache.CLOTH_COLLISION_WEIGHT`;
XPBD from 1024 particles, :data:`particles.xpbd.solver.XPBD_WEIGHT`);
``--compare`` runs the treated sheet with NumPy and with numba side by side
(a column each), after a warm-up that loads the compiled kernels. ``--iterations`` sets the proximity
stage's Jacobi iterations (``ClothCollisions``' default, 50, otherwise; 20 was no faster on the fold's
worst step, 215 ms, and let pairs come closer, 0.00 of the thickness against 0.02).

    python bench/bench_cloth_fold.py            # 64^2 (with --no-baseline: 1 min 21 s on 2026-12-08)
    python bench/bench_cloth_fold.py --n 32 --compare   # NumPy against numba
    python bench/bench_cloth_fold.py --xpbd-sizes       # XPBD alone per size: where "auto" compiles it
    python bench/bench_cloth_fold.py --n 32 --peer newton --steps 20 --no-baseline   # beside Newton's VBD
    python bench/bench_cloth_fold.py --one-thread       # on a host whose cores are busy with other work
"""

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from particles.backends import available  # noqa: E402
from particles.collisions import ClothCollisions  # noqa: E402
from particles.collisions import intersections  # noqa: E402
from particles.massspring import cloth  # noqa: E402
from particles.collisions import TriangleMesh  # noqa: E402
from particles.collisions import Plane  # noqa: E402
from particles.xpbd import XPBD  # noqa: E402

FLOOR = Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])
H = 0.01  # s
MAX_STRAIN = 0.1  # Provot's limit on the stretch springs of the treated sheet
KINDS = ("structural", "shear", "flexion")  # the cloth's spring kinds: stretch, shear, bending


def upright_sheet(n):
    """An n x n sheet of 1 m standing upright above the floor, bowed a little so that it buckles one way."""
    c = cloth(n, n, width=1.0, height=1.0, plane="vertical", origin=(-0.5, 0.0, 1.05), pins=None,
              scaling="physical", stretch_modulus=200.0, damping=0.2)
    X = c.state()
    X[:, 0, 1] += 0.05 * np.sin(np.pi * (X[:, 0, 0] + 0.5)) * (1.05 - X[:, 0, 2])
    c.set_state(np.asfortranarray(X))
    return c


def strains(c, x):
    """The largest strain of each spring kind of KINDS at positions x (0 for a kind the sheet lacks)."""
    out = []
    for kind in KINDS:  # a loop over the three spring kinds
        s = c.springs.get(kind)
        if s is None:
            out.append(0.0)
            continue
        L = np.sqrt(sum((x[s.i, a] - x[s.j, a]) ** 2 for a in range(3)))  # a loop over the coordinates
        out.append(float(max(0.0, np.max(L / s.rest_length - 1.0))))
    return tuple(out)


def run(n, seconds, treat, backend=None, iterations=None):
    """Step the sheet; per step: time, wall time, crossing pairs, closest pair / thickness (None untreated),
    and the largest structural, shear and flexion strains."""
    c = upright_sheet(n)
    mesh = TriangleMesh.grid(n, n)
    thickness = 0.5 / (n - 1)
    cc = ClothCollisions.from_system(c, mesh, thickness=thickness, bodies=[FLOOR], friction=0.3,
                                     proximity=treat, ccd=treat, zones=treat, backend=backend,
                                     **({} if iterations is None else {"iterations": iterations}),
                                     max_strain=MAX_STRAIN if treat else None)
    step = cc.stepper(XPBD.from_system(c, substeps=10, backend=backend))
    rows = []
    for _ in range(round(seconds / H)):
        t0 = time.perf_counter()
        c.run(c.t + H, H, method=step)
        wall = time.perf_counter() - t0
        crossing = len(intersections(c.X[:, 0], mesh.faces))
        near = cc.pairs_closer_than(c.X[:, 0]) if treat else None
        closest = (near.min() / thickness if near is not None and len(near) else 1.0) if treat else None
        rows.append((c.t, wall, crossing, closest, *strains(c, c.X[:, 0])))
    return rows, c.X.copy()


def best_of(repeat, *args, **kwargs):
    """:func:`run` `repeat` times: its rows with each step's best wall time. The runs must agree bit for bit."""
    runs = [run(*args, **kwargs) for _ in range(repeat)]
    (rows, X), others = runs[0], runs[1:]
    for rows_k, X_k in others:  # a loop over the repeats
        if not np.array_equal(X, X_k) or [r[2:] for r in rows] != [r[2:] for r in rows_k]:
            raise SystemExit("FAILED: two runs of the same sheet differ")
    return [(r[0], min(o[k][1] for o, _ in runs), *r[2:]) for k, r in enumerate(rows)]


def summary(rows):
    """Median and worst wall time per step (ms), the most crossing pairs of a step, the largest strains."""
    wall = 1e3 * np.array([r[1] for r in rows])
    return (float(np.median(wall)), float(wall.max()), max(r[2] for r in rows),
            *(max(r[4 + k] for r in rows) for k in range(len(KINDS))))


def report(label, runs, window=0.25):
    """Per window: ms per step of each run (columns), the most crossing pairs, the closest pair; then a summary."""
    print(f"\n{label}")
    names = list(runs)
    first = runs[names[0]]
    print(f"{'t (s)':>12} " + " ".join(f"{'ms/step ' + k:>16}" for k in names)
          + f" {'max crossing pairs':>19} {'closest / thickness':>20}"
          + "".join(f" {'strain ' + kind:>17}" for kind in KINDS))
    t = np.array([r[0] for r in first])
    for lo in np.arange(0.0, t[-1] - 1e-9, window):
        sel = {k: [r for r in rows if lo < r[0] <= lo + window + 1e-9] for k, rows in runs.items()}
        closest = [r[3] for rows in sel.values() for r in rows if r[3] is not None]
        crossing = max(r[2] for rows in sel.values() for r in rows)
        strain = [100 * max(r[4 + q] for rows in sel.values() for r in rows) for q in range(len(KINDS))]
        print(f"{lo:5.2f}-{lo + window:4.2f} " + " ".join(f"{1e3 * np.mean([r[1] for r in sel[k]]):>16.1f}" for k in names)
              + f" {crossing:>19d} {(f'{min(closest):.2f}' if closest else '-'):>20}"
              + "".join(f" {s:>16.2f}%" for s in strain))
    for k in names:
        median, worst, crossing, *strain = summary(runs[k])
        print(f"{k}: median {median:.1f} ms per step, worst {worst:.1f} ms, most crossing pairs of a step "
              f"{crossing}, largest strain " + ", ".join(f"{kind} {100 * s:.2f}%" for kind, s in zip(KINDS, strain)))
    return {k: summary(rows) for k, rows in runs.items()}


def xpbd_sizes(sides=(8, 16, 24, 32, 48, 64), rounds=2, steps=20):
    """The sheet's XPBD steps alone (10 substeps, no collisions), NumPy against compiled, per size: the
    measurements behind :data:`particles.xpbd.solver.XPBD_WEIGHT` (best of `rounds` alternating runs)."""
    from particles.backends import AUTO_MIN
    from particles.xpbd.solver import XPBD_WEIGHT

    print(f"\nXPBD alone, 10 substeps, ms per step (auto compiles from {AUTO_MIN // XPBD_WEIGHT} particles)")
    print(f"{'sheet':>8} {'particles':>10} {'NumPy':>8} {'compiled':>9} {'ratio':>6}")
    for n in sides:  # a loop over the few sizes
        best = {}
        for _ in range(rounds):  # alternating rounds
            for backend in ("numpy", "numba"):
                c = upright_sheet(n)
                solver = XPBD.from_system(c, substeps=10, backend=backend)
                c.run(2 * H, H, method=solver)
                t0 = time.perf_counter()
                c.run(c.t + steps * H, H, method=solver)
                best[backend] = min(best.get(backend, np.inf), (time.perf_counter() - t0) / steps)
        print(f"{f'{n}^2':>8} {n * n:>10} {1e3 * best['numpy']:>8.2f} {1e3 * best['numba']:>9.2f} "
              f"{best['numpy'] / best['numba']:>6.1f}")


def warm_up():
    """Load (or, with a cold cache, compile) the kernels before the timing: the collision pipeline's and
    XPBD's (:func:`particles.warm.warm`), then one step of a small sheet.

    A first run in a fresh clone compiles them here (about half a minute), not in its first steps: one
    step of an 8 x 8 sheet alone met a few of them, and the 64^2 run's worst step was then 17.7 s.
    """
    from particles.warm import warm

    warm(["cloth collisions", "constraints"])
    run(8, H, True, backend="numba")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=64, help="particles per side (default 64)")
    parser.add_argument("--seconds", type=float, default=2.0, help="simulated time (default 2 s)")
    parser.add_argument("--steps", type=int, default=None, help="steps to take (overrides --seconds)")
    parser.add_argument("--one-thread", action="store_true",
                        help="every compiled loop on one thread (a shared host: other work on its cores)")
    parser.add_argument("--peer", choices=["newton"], default=None,
                        help="also step the same sheet with Newton's VBD solver and self-contact (CPU)")
    parser.add_argument("--newton-iterations", type=int, default=4,
                        help="VBD iterations per substep of the peer (default 4; with 1 the 64^2 sheet stretched "
                             "26%% in its first step and 134%% by its eighth)")
    parser.add_argument("--backend", default="auto", choices=["auto", "numpy", "numba"],
                        help="who runs the collision stages and the XPBD substeps (default auto)")
    parser.add_argument("--iterations", type=int, default=None,
                        help="proximity iterations of the treatment (default: ClothCollisions' own)")
    parser.add_argument("--compare", action="store_true", help="the treated sheet with NumPy and with numba")
    parser.add_argument("--no-baseline", action="store_true", help="skip the floor-only run")
    parser.add_argument("--repeat", type=int, default=2, help="runs of each sheet; per step the best (default 2)")
    parser.add_argument("--xpbd-sizes", action="store_true",
                        help="only the sheet's XPBD steps, NumPy against compiled, from 8^2 to 64^2")
    args = parser.parse_args(argv)
    if args.repeat < 1:
        parser.error(f"--repeat must be at least 1, got {args.repeat}")
    if args.steps is not None:
        if args.steps < 1:
            parser.error(f"--steps must be at least 1, got {args.steps}")
        args.seconds = args.steps * H
    if args.one_thread:
        import particles.backends.compile as kernels  # noqa: PLC0415

        kernels.PARALLEL_MIN = 10**9  # what pick() compares a loop's size with: every loop takes its one-thread copy
        if "numba" in available():
            import numba  # noqa: PLC0415

            numba.set_num_threads(1)  # and the loops that are always parallel run on one
    if args.xpbd_sizes:
        warm_up()
        xpbd_sizes()
        return
    print(f"{args.n}^2 sheet ({2 * (args.n - 1) ** 2} triangles), {args.seconds:g} s, h = {1e3 * H:g} ms, "
          f"load average {os.getloadavg()[0]:.2f}; each step's time the best of {args.repeat} runs"
          + ("; every compiled loop on one thread" if args.one_thread else ""))
    backends = ["numpy", "numba"] if args.compare else [args.backend]
    if "numpy" != backends[-1]:
        warm_up()
    if not args.no_baseline:
        report("floor only (no self-collision treatment)",
               {"floor": best_of(args.repeat, args.n, args.seconds, False)})
    out = report(f"ClothCollisions (proximity, strain limit {100 * MAX_STRAIN:g}%, continuous test, impact zones)",
                 {b: best_of(args.repeat, args.n, args.seconds, True, backend=b, iterations=args.iterations)
                  for b in backends})
    if args.peer == "newton":
        from _newton_peer import newton_rows  # noqa: PLC0415  (imports newton and warp)
        report(f"Newton's VBD solver with self-contact on Warp's CPU device (the same sheet, "
               f"{args.newton_iterations} iterations per substep; 1 run)",
               {"newton": newton_rows(upright_sheet(args.n), args.n, args.seconds, H, strains, args.newton_iterations)})
    if any(crossing for _, _, crossing, *_ in out.values()):
        raise SystemExit("FAILED: triangles crossed")
    if any(o[3] > MAX_STRAIN + 1e-9 for o in out.values()):  # o: median, worst, crossings, then the strains
        raise SystemExit(f"FAILED: a structural spring passed {100 * MAX_STRAIN:g}%")


if __name__ == "__main__":
    main()
