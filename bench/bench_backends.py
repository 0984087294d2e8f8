"""Backends: the NumPy reference against the compiled kernels (numba), Warp's CPU backend and Taichi.

In one run, on the same springs and the same pairs:

1. One explicit step of a hanging cloth (structural, shear and flexion
   springs, all with damping along the spring, gravity, two pinned corners,
   float64), 64^2 and 128^2 particles: the library's symplectic Euler step
   with ``backend="numpy"`` and ``backend="numba"``, called as
   ``c.stepper("symplectic_euler")(c.derivative, X, t, h)`` (with numba the compiled
   step, :meth:`particles.massspring.MassSpringSystem.stepper`), then per step of
   ``run`` itself (its divergence guard included), and the force pass
   alone; then the same step written as a Warp kernel on its CPU backend
   (one thread) and as a Taichi kernel on the CPU (as many threads as numba),
   when those are installed (``pip install 'particles[bench]'``). Every
   implementation's step is checked against the NumPy step first.
2. The Lennard-Jones force pass over a ready Verlet list (12-6, cutoff 2.5
   sigma, skin 0.3 sigma) in a periodic box at rho* = 0.86 (an FCC lattice,
   jittered: the pair count of the liquid), 16k and 64k particles.
3. An XPBD substep sweep (one Gauss-Seidel pass over the colour groups of
   the 128^2 cloth's distance constraints) and N-body gravity (4k particles).
4. Compile time: the first cloth step, Lennard-Jones pass and XPBD step in a
   fresh process with an empty numba cache (compiling), then again in
   another fresh process with that cache (loading), against the run time.

Times are the best of several runs in ms, in three rounds (the two threads
of a shared machine are not always both free: a round's best can be a
one-thread time); ratios are measured in the same run (read the ratios).

Run:  python bench/bench_backends.py [--quick]
"""

import argparse
import contextlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _timing import best_time  # noqa: E402

from particles import backends  # noqa: E402
from particles.forces import LennardJones, NBodyGravity  # noqa: E402
from particles.integrators import symplectic_euler  # noqa: E402
from particles.md import fcc_lattice  # noqa: E402
from particles.massspring import cloth  # noqa: E402
from particles.xpbd import XPBD  # noqa: E402

H = 1e-5  # s: one explicit step of the stiff cloth
KD = 0.05  # kg/s, damping along every spring
LJ_CELLS = {16000: (20, 20, 10), 64000: (20, 20, 40)}


def cloth_state(n):
    """The cloth and a state with stretched springs and moving particles (the same for every backend)."""
    c = cloth(n, n, kd=KD)
    X = np.asfortranarray(c.state())  # the layout of the system's own state (ParticleSystem.run)
    rng = np.random.default_rng(0)
    free = np.setdiff1d(np.arange(c.n), c.pinned)
    X[free, 0] += rng.normal(scale=0.05 / n, size=(len(free), 3))
    X[free, 1] = rng.normal(scale=0.1, size=(len(free), 3))
    return c, X


def flat_springs(c):
    """All the cloth's springs in one list: i, j, L0, k, kd."""
    sets = list(c.springs.values())
    return [np.concatenate([getattr(s, a) for s in sets]) for a in ("i", "j", "rest_length", "k", "kd")]


def warp_step(c, X):
    """The cloth step as two Warp kernels (springs with atomic adds, then symplectic Euler); None if absent."""
    try:
        import warp as wp
    except ImportError:
        return None
    wp.config.quiet = True
    wp.init()
    f64, v3 = wp.float64, wp.vec3d

    @wp.kernel
    def springs(x: wp.array(dtype=v3), v: wp.array(dtype=v3), i: wp.array(dtype=int), j: wp.array(dtype=int),
                L0: wp.array(dtype=f64), k: wp.array(dtype=f64), kd: wp.array(dtype=f64), F: wp.array(dtype=v3)):
        s = wp.tid()
        a, b = i[s], j[s]
        d = x[a] - x[b]
        inv = f64(1.0) / wp.max(wp.length(d), f64(1e-300))
        w = k[s] * (L0[s] * inv - f64(1.0)) - kd[s] * wp.dot(v[a] - v[b], d) * (inv * inv)
        wp.atomic_add(F, a, d * w)
        wp.atomic_sub(F, b, d * w)

    @wp.kernel
    def integrate(x: wp.array(dtype=v3), v: wp.array(dtype=v3), F: wp.array(dtype=v3), m: wp.array(dtype=f64),
                  free: wp.array(dtype=f64), g: v3, h: f64):
        p = wp.tid()
        a = (F[p] + m[p] * g) / m[p] * free[p]
        v[p] = v[p] + h * a
        x[p] = x[p] + h * v[p]

    i, j, L0, k, kd = flat_springs(c)
    free = np.ones(c.n)
    free[c.pinned] = 0.0
    arrays = dict(x=wp.array(X[:, 0].copy(), dtype=v3, device="cpu"),
                  v=wp.array(X[:, 1].copy(), dtype=v3, device="cpu"),
                  F=wp.zeros(c.n, dtype=v3, device="cpu"))
    data = [wp.array(a, dtype=t, device="cpu") for a, t in ((i.astype(np.int32), int), (j.astype(np.int32), int),
                                                             (L0, f64), (k, f64), (kd, f64))]
    m, fr = wp.array(c.m, dtype=f64, device="cpu"), wp.array(free, dtype=f64, device="cpu")
    g = v3(0.0, 0.0, -9.81)

    def step():
        arrays["F"].zero_()
        wp.launch(springs, dim=len(i), inputs=[arrays["x"], arrays["v"], *data, arrays["F"]], device="cpu")
        wp.launch(integrate, dim=c.n, inputs=[arrays["x"], arrays["v"], arrays["F"], m, fr, g, f64(H)], device="cpu")

    def result():
        out = np.empty_like(X)
        out[:, 0], out[:, 1] = arrays["x"].numpy(), arrays["v"].numpy()
        return out

    return step, result


def taichi_step(c, X, threads):
    """The cloth step as two Taichi kernels on the CPU (atomic adds); None if Taichi is absent."""
    try:
        import taichi as ti
    except ImportError:
        return None
    ti.init(arch=ti.cpu, default_fp=ti.f64, cpu_max_num_threads=threads, log_level=ti.ERROR)
    i, j, L0, k, kd = flat_springs(c)
    n, s = c.n, len(i)
    x, v, F = (ti.Vector.field(3, ti.f64, n) for _ in range(3))
    ti_i, ti_j = ti.field(ti.i32, s), ti.field(ti.i32, s)
    ti_L0, ti_k, ti_kd = (ti.field(ti.f64, s) for _ in range(3))
    m, free = ti.field(ti.f64, n), ti.field(ti.f64, n)
    for field, a in ((x, X[:, 0]), (v, X[:, 1]), (ti_i, i.astype(np.int32)), (ti_j, j.astype(np.int32)),
                     (ti_L0, L0), (ti_k, k), (ti_kd, kd), (m, c.m)):
        field.from_numpy(np.ascontiguousarray(a))
    fr = np.ones(n)
    fr[c.pinned] = 0.0
    free.from_numpy(fr)

    @ti.kernel
    def step_kernel(h: ti.f64):
        for p in range(n):
            F[p] = ti.Vector([0.0, 0.0, 0.0])
        for q in range(s):
            a, b = ti_i[q], ti_j[q]
            d = x[a] - x[b]
            inv = 1.0 / ti.max(d.norm(), 1e-300)
            w = ti_k[q] * (ti_L0[q] * inv - 1.0) - ti_kd[q] * (v[a] - v[b]).dot(d) * (inv * inv)
            F[a] += d * w
            F[b] -= d * w
        for p in range(n):
            acc = (F[p] + m[p] * ti.Vector([0.0, 0.0, -9.81])) / m[p] * free[p]
            v[p] += h * acc
            x[p] += h * v[p]

    def step():
        step_kernel(H)
        ti.sync()

    def result():
        out = np.empty_like(X)
        out[:, 0], out[:, 1] = x.to_numpy(), v.to_numpy()
        return out

    return step, result


def compare(name, step_result, reference, c, X):
    """Run one step from X and check it against the NumPy step; then return the step for timing."""
    step, result = step_result
    step()
    error = np.abs(result() - reference).max() / np.abs(reference).max()
    if error > 1e-9:
        raise AssertionError(f"{name}: its step differs from the NumPy step by {error:.1e} (relative)")
    return step


ROUNDS = 3  # the two threads of a shared machine are not always both there: three rounds, the best of each kept
RUN_STEPS = 50  # steps of each timed run (the per-step time of ParticleSystem.run, its divergence guard included)


def run_step_time(c, X):
    """Best time per step of ``c.run`` (symplectic Euler, RUN_STEPS steps from X) with the current backend."""
    def run():
        c.set_state(X, 0.0)
        c.run(RUN_STEPS * H, H, method="symplectic_euler", every=RUN_STEPS)
    run()
    return best_time(run, repeat=10) / RUN_STEPS


@contextlib.contextmanager
def one_thread():
    """numba on one thread within the block (the compiled step's time when the second core is busy)."""
    import numba

    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(before)


def part1(sizes, threads):
    print("1. One explicit cloth step (springs with damping + gravity + symplectic Euler), ms")
    print("   step: c.stepper('symplectic_euler')(c.derivative, X, t, h) (numba: the compiled step of the system);")
    print("   run: per step of c.run, its divergence guard included;")
    print("   forces: c.total_force alone (numba: the per-force kernels); 1 thread: the compiled step on one thread")
    print(f"{'particles':>10} {'springs':>8} {'numpy':>8} {'numba':>8} {'1 thread':>8} {'run np':>8} {'run nb':>8} "
          f"{'forces np':>10} "
          f"{'forces nb':>10} {'warp cpu':>9} {'taichi':>8} {'np/nb':>7} {'run np/nb':>10} {'warp/nb':>8} "
          f"{'taichi/nb':>10}")
    for n in sizes:
        c, X = cloth_state(n)
        c.set_state(X)
        times = {}
        with backends.using("numpy"):
            reference = symplectic_euler(c.derivative, X, 0.0, H)
        step = c.stepper("symplectic_euler")  # with numba, the compiled step of the system
        for _ in range(ROUNDS):  # rounds spread over a second or so: the best of each is kept
            for be in ("numpy", "numba"):
                with backends.using(be):
                    f = c.derivative
                    got = step(f, X, 0.0, H)
                    assert np.abs(got - reference).max() <= 1e-12 * np.abs(reference).max(), be
                    for key, t in ((be, best_time(lambda: step(f, X, 0.0, H), repeat=50)),
                                   ("run " + be, run_step_time(c, X)),
                                   ("forces " + be, best_time(lambda: c.total_force(X, 0.0), repeat=50))):
                        times[key] = min(times.get(key, np.inf), t)
            with backends.using("numba"), one_thread():
                t = best_time(lambda: step(f, X, 0.0, H), repeat=50)
                times["numba 1"] = min(times.get("numba 1", np.inf), t)
        for name, make in (("warp", lambda: warp_step(c, X)), ("taichi", lambda: taichi_step(c, X, threads))):
            made = make()
            times[name] = None if made is None else best_time(compare(name, made, reference, c, X), repeat=50)
        ms = {key: (f"{1e3 * t:.2f}" if t is not None else "-") for key, t in times.items()}
        ratio = {key: (f"{times[key] / times['numba']:.2f}x" if times.get(key) else "-") for key in times}
        print(f"{n:>6}^2 {len(flat_springs(c)[0]):>10} {ms['numpy']:>8} {ms['numba']:>8} {ms['numba 1']:>8} "
              f"{ms['run numpy']:>8} "
              f"{ms['run numba']:>8} {ms['forces numpy']:>10} {ms['forces numba']:>10} {ms['warp']:>9} "
              f"{ms['taichi']:>8} {ratio['numpy']:>7} {times['run numpy'] / times['run numba']:>9.2f}x "
              f"{ratio['warp']:>8} {ratio['taichi']:>10}")


def lj_liquid(n):
    """A jittered FCC lattice at rho* = 0.86 in its periodic box: positions (n, 3), box (3,)."""
    x, box = fcc_lattice(LJ_CELLS[n], 0.86)
    return x + np.random.default_rng(1).uniform(-0.1, 0.1, x.shape), box


def part2(sizes):
    print("\n2. Lennard-Jones force pass over a ready Verlet list (periodic, rho* = 0.86), ms")
    print(f"{'N':>6} {'pairs':>9} {'numpy':>8} {'numba':>8} {'np/nb':>7} {'virial rel. diff':>17}")
    for n in sizes:
        x, box = lj_liquid(n)
        out, forces = {}, {}
        for be in ("numpy", "numba"):
            forces[be] = lj = LennardJones.from_epsilon_sigma(skin=0.3, box=box, backend=be)
            out[be] = [np.inf, lj(x), lj.last_virial, len(lj.neighbor_list.ranked_pairs(x)[1])]  # builds, compiles
        for _ in range(ROUNDS):  # rounds, the best of each kept (as in part 1)
            for be, lj in forces.items():
                t = best_time(lambda: lj.add_to(np.zeros_like(x), x, None, 0.0, None), repeat=5)
                out[be][0] = min(out[be][0], t)
        (t_np, F_np, W_np, pairs), (t_nb, F_nb, W_nb, _) = out["numpy"], out["numba"]
        assert np.abs(F_np - F_nb).max() <= 1e-12 * np.abs(F_np).max()
        print(f"{n:>6} {pairs:>9} {1e3 * t_np:>8.1f} {1e3 * t_nb:>8.1f} {t_np / t_nb:>6.2f}x "
              f"{abs(W_np - W_nb) / abs(W_np):>17.1e}")


def part3(quick):
    print("\n3. XPBD sweep and N-body gravity, ms")
    n = 64 if quick else 128
    c, X = cloth_state(n)
    times = {}
    for be in ("numpy", "numba"):
        solver = XPBD.from_system(c, substeps=1, iterations=1, backend=be)
        solver(None, X, 0.0, 1 / 600)
        times[be] = best_time(lambda: solver(None, X, 0.0, 1 / 600), repeat=20)
    print(f"  XPBD substep, {n}^2 cloth (Gauss-Seidel over colours): numpy {1e3 * times['numpy']:.2f}, "
          f"numba {1e3 * times['numba']:.2f}, {times['numpy'] / times['numba']:.2f}x")
    rng = np.random.default_rng(2)
    k = 1000 if quick else 4000
    x, m = rng.normal(size=(k, 3)), rng.uniform(0.5, 2.0, k)
    for be in ("numpy", "numba"):
        g = NBodyGravity(softening=0.05, backend=be)
        g(x, m=m)
        times[be] = best_time(lambda: g(x, m=m), repeat=3)
    print(f"  N-body gravity, {k} particles (all pairs): numpy {1e3 * times['numpy']:.1f}, "
          f"numba {1e3 * times['numba']:.1f}, {times['numpy'] / times['numba']:.2f}x")


FIRST_CALLS = """
import json, sys, time
import numpy as np
t0 = time.perf_counter()
sys.path.insert(0, {bench!r})
from bench_backends import cloth_state, lj_liquid, H
from particles.integrators import symplectic_euler
from particles.forces import LennardJones
from particles.xpbd import XPBD
from particles import backends
out = {{"import": time.perf_counter() - t0}}
c, X = cloth_state(32)
solver = XPBD.from_system(c, substeps=1, backend="numba")
x, box = lj_liquid(16000)
lj = LennardJones.from_epsilon_sigma(skin=0.3, box=box, backend="numba")
lj.neighbor_list.ranked_pairs(x)  # the pair list (NumPy), not timed
with backends.using("numba"):
    for key, call in (("cloth step", lambda: symplectic_euler(c.derivative, X, 0.0, H)),
                      ("xpbd step", lambda: solver(None, X, 0.0, 1e-3)), ("lj pass", lambda: lj(x))):
        t0 = time.perf_counter(); call(); first = time.perf_counter() - t0
        t0 = time.perf_counter(); call(); out[key] = (first, time.perf_counter() - t0)
print(json.dumps(out))
"""


def part4():
    print("\n4. JIT: first call in a fresh process (compiling, then from the disk cache) vs a later call, s")
    script = FIRST_CALLS.format(bench=str(Path(__file__).resolve().parent))
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        runs = []
        for _ in range(2):  # compile (empty cache), then load
            done = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True)
            runs.append(json.loads(done.stdout.strip().splitlines()[-1]))
    print(f"{'kernel':>12} {'compile':>9} {'cached':>8} {'later call':>11}")
    for key in ("cloth step", "xpbd step", "lj pass"):
        print(f"{key:>12} {runs[0][key][0]:>9.2f} {runs[1][key][0]:>8.2f} {runs[1][key][1]:>11.4f}")
    print(f"  (import particles + bench helpers: {runs[1]['import']:.2f} s; cache folder: NUMBA_CACHE_DIR)")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small sizes only")
    parser.add_argument("--skip-jit", action="store_true", help="leave out part 4 (compile times)")
    args = parser.parse_args(argv)
    if "numba" not in backends.available():
        print("numba is not installed (pip install 'particles[fast]'): nothing to compare")
        return
    import numba

    import particles.backends.compile  # noqa: F401  (before numba starts its threads: it picks their pool)

    threads = numba.get_num_threads()
    print(f"numba {numba.__version__}, {threads} threads; load average before: {os.getloadavg()[0]:.2f}")
    start = time.perf_counter()
    part1([32, 64] if args.quick else [64, 128], threads)
    part2([16000] if args.quick else [16000, 64000])
    part3(args.quick)
    if not args.skip_jit:
        part4()
    print(f"\nnumba threading layer: {numba.threading_layer()}; load average after: {os.getloadavg()[0]:.2f}; "
          f"{time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
