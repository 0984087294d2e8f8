"""Warp's own cloth benchmark, set up with the library: NumPy, compiled, Warp CPU and Taichi CPU in one run.

Warp ships a mass-spring cloth benchmark (``warp/examples/benchmarks/benchmark_cloth.py`` in
NVIDIA/warp) that times one scene on NumPy, numba, Warp, Taichi and others, each through its own
integrator class. This script runs the same scene, with the same step count, through the
library's loop (:meth:`particles.ParticleSystem.run`, its divergence guard included) with
``backend="numpy"`` and ``backend="numba"`` (the compiled step, :mod:`particles.backends`), beside
the same two kernels written here for Warp's CPU device and for Taichi on the CPU (``pip install
'particles[bench]'``; their columns are skipped, with a note, when a package is missing).

The scene (Warp's set-up, in the library's axes: its sheet lies in Warp's x-z plane with y up,
here in the x-y plane with z up):

* a flat square grid of n x n particles, n = 32, 64 and 128, 0.1 m apart, 0.1 kg each
  (:func:`particles.massspring.cloth` with ``plane="horizontal"`` and the naive scaling);
* springs to the next particle along rows and columns (structural), to the one after it
  (flexion) and across both diagonals of every cell (shear), every spring k = 1000 N/m with
  damping along the spring kd = 10 kg/s, rest lengths those of the flat grid;
* the two corners of the first row pinned, gravity 9.81 m/s^2 (Warp's and Taichi's kernels
  there; its NumPy version uses 9.8);
* symplectic Euler, ``v += h a`` then ``x += h v``, at 60 frames per second with 16 substeps per
  frame: h = 1/960 s, 60 frames, 960 steps (1 s); positions read back once per frame.

Its topology, as the builder makes it (``tests/library/test_bench_scripts.py`` checks these
counts and that the springs join exactly the neighbours listed above):

    32^2: 1024 particles, 5826 springs (1984 structural, 1922 shear, 1920 flexion), 2 pinned
    64^2: 4096 particles, 23938 springs (8064 structural, 7938 shear, 7936 flexion), 2 pinned
    128^2: 16384 particles, 97026 springs (32512 structural, 32258 shear, 32256 flexion), 2 pinned

What differs from Warp's harness: everything here is float64 (Warp's and Taichi's runs are
timed in float32 as there, and in float64 as the library computes); Warp's harness times every
frame, the first one with its kernels' compilation, here one frame is run first (compiling) and
three runs of the 60 timed frames follow, each from the initial state, in rounds that alternate
NumPy, numba and Warp (a slow minute of a shared machine then falls on all of them; Taichi runs
after them, one precision at a time, as ``ti.init`` requires); the time per step is the best
frame's time over 16 (the mean frame's in brackets). A run of ``run`` takes the 16 steps of a
frame in one compiled call (:meth:`particles.massspring.compiled_step.CompiledStep.symplectic_euler_steps`),
its divergence guard included. Warp's CPU backend runs its kernels on
one thread; numba runs the compiled step on ``numba.get_num_threads()`` threads (also timed on
one) and Taichi on as many.

The runs must agree: after the 960 steps the library's NumPy and compiled positions agree to
1e-9 m (checked), and the largest distance of every other run's end positions from the NumPy
one is printed (the Warp and Taichi kernels here are the same arithmetic, up to the order of
their atomic additions and, in float32, to its rounding).

Run:  python bench/bench_warp_harness.py [--sizes 32 64 128]
"""

import argparse
import os
import sys
import time

import numpy as np

from particles import backends
from particles.massspring import cloth

SIZES = (32, 64, 128)
SPACING = 0.1  # m between neighbours
MASS = 0.1  # kg per particle
K = 1000.0  # N/m, every spring
KD = 10.0  # kg/s, damping along every spring
G = 9.81  # m/s^2
FPS, SUBSTEPS, FRAMES = 60, 16, 60
H = 1.0 / (FPS * SUBSTEPS)  # s: 1/960
AGREE = 1e-9  # m: the NumPy and compiled end positions
ROUNDS = 3  # runs of the 60 frames per implementation: the machine is shared, the best frame is kept
# the neighbours of particle (i, j) that a spring joins, (di, dj): structural, flexion and shear
OFFSETS = {"structural": [(1, 0), (0, 1)], "flexion": [(2, 0), (0, 2)], "shear": [(1, 1), (1, -1)]}


def scene(n):
    """Warp's cloth at n x n particles, as the library builds it (a MassSpringSystem, at rest)."""
    side = SPACING * (n - 1)
    return cloth(n, n, width=side, height=side, plane="horizontal", pins="top corners", mass=MASS,
                 k_structural=K, k_shear=K, k_flexion=K, kd=KD, gravity=G)


def stencil_pairs(n, kind):
    """The springs of one kind written as offsets on the grid (particle (i, j) is j n + i): shape (s, 2)."""
    i, j = np.meshgrid(np.arange(n), np.arange(n))
    pairs = []
    for di, dj in OFFSETS[kind]:  # a loop over the two offsets of the kind
        ok = (i + di < n) & (j + dj >= 0) & (j + dj < n)
        pairs.append(np.stack([(j * n + i)[ok], ((j + dj) * n + i + di)[ok]], axis=1))
    return np.concatenate(pairs)


def topology(c):
    """Counts of the built cloth: particles, springs by kind, pins."""
    return {"particles": c.n, "pinned": len(c.pinned), **{kind: len(s) for kind, s in c.springs.items()}}


def flat(c):
    """The scene's data as the kernels take them: x, m, free (1 or 0), and i, j, L0, k, kd of all springs."""
    sets = list(c.springs.values())
    i, j, L0, k, kd = (np.concatenate([getattr(s, a) for s in sets]) for a in ("i", "j", "rest_length", "k", "kd"))
    free = np.ones(c.n)
    free[c.pinned] = 0.0
    return dict(x=c.X[:, 0].copy(), m=c.m.copy(), free=free, i=i.astype(np.int32), j=j.astype(np.int32),
                L0=L0, k=k, kd=kd)


def frames(runners):
    """Each runner's first frame (compiling), then ROUNDS rounds in which every runner, in turn, runs FRAMES
    timed frames from the start: {name: (times (s), end positions)}.

    A runner is ``(simulate, reset, result)``. The rounds alternate the runners, so that a slow minute of a
    shared machine falls on all of them alike and the ratios of their best frames stay fair.
    """
    times = {name: [] for name in runners}
    for simulate, _, _ in runners.values():  # a loop over the few runners
        simulate(0)
    for _ in range(ROUNDS):  # a loop over the rounds
        for name, (simulate, reset, _) in runners.items():  # a loop over the runners, in turn
            reset()
            for f in range(FRAMES):  # a loop over the frames
                start = time.perf_counter()
                simulate(f)
                times[name].append(time.perf_counter() - start)
    return {name: (np.array(times[name]), result()) for name, (_, _, result) in runners.items()}


def ours(n, backend, threads=None):
    """The library's loop as a runner: ``run`` over each frame of 16 steps, symplectic Euler, with `backend`
    (and numba on `threads` threads if given)."""
    import numba

    c = scene(n)
    X0 = c.state()

    def simulate(f):
        before = numba.get_num_threads()
        numba.set_num_threads(threads or before)
        try:
            with backends.using(backend):
                c.run((f + 1) / FPS, H, method="symplectic_euler", every=SUBSTEPS)
        finally:
            numba.set_num_threads(before)

    return simulate, lambda: c.set_state(X0, 0.0), lambda: c.X[:, 0].copy()


def warp(n, double):
    """The two kernels on Warp's CPU device (springs by atomic adds, then the step); None without Warp."""
    try:
        import warp as wp
    except ImportError:
        return None
    wp.config.log_level = getattr(wp, "LOG_WARNING", 30)  # no banner, no line per compiled module
    wp.init()
    real, vec = (wp.float64, wp.vec3d) if double else (wp.float32, wp.vec3f)
    kernels = _warp_kernels(wp, real, vec)
    d = flat(scene(n))
    dtype = np.float64 if double else np.float32
    arrays = {}

    def reset():
        arrays.update(x=wp.array(d["x"].astype(dtype), dtype=vec, device="cpu"),
                      v=wp.zeros(len(d["x"]), dtype=vec, device="cpu"),
                      F=wp.zeros(len(d["x"]), dtype=vec, device="cpu"))

    i, j = (wp.array(d[a], dtype=wp.int32, device="cpu") for a in ("i", "j"))
    L0, k, kd, m, free = (wp.array(d[a].astype(dtype), dtype=real, device="cpu")
                          for a in ("L0", "k", "kd", "m", "free"))
    springs = len(d["i"])
    g, h = vec(0.0, 0.0, -G), real(H)

    def simulate(f):
        x, v, F = arrays["x"], arrays["v"], arrays["F"]
        for _ in range(SUBSTEPS):  # a loop over the substeps of a frame
            F.zero_()
            wp.launch(kernels[0], dim=springs, inputs=[x, v, i, j, L0, k, kd, F], device="cpu")
            wp.launch(kernels[1], dim=len(d["x"]), inputs=[x, v, F, m, free, g, h], device="cpu")
        arrays["read"] = x.numpy()  # back to the host, once per frame

    reset()
    return simulate, reset, lambda: arrays["read"].astype(np.float64)


def _warp_kernels(wp, real, vec):
    """The springs' and the step's kernels for one precision (a closure: Warp makes one module each)."""

    @wp.kernel(module="unique")
    def springs(x: wp.array(dtype=vec), v: wp.array(dtype=vec), i: wp.array(dtype=wp.int32),
                j: wp.array(dtype=wp.int32), L0: wp.array(dtype=real), k: wp.array(dtype=real),
                kd: wp.array(dtype=real), F: wp.array(dtype=vec)):
        s = wp.tid()
        a, b = i[s], j[s]
        d = x[a] - x[b]
        inv_L = real(1.0) / wp.length(d)
        w = k[s] * (L0[s] * inv_L - real(1.0)) - kd[s] * wp.dot(v[a] - v[b], d) * (inv_L * inv_L)
        wp.atomic_add(F, a, d * w)
        wp.atomic_sub(F, b, d * w)

    @wp.kernel(module="unique")
    def step(x: wp.array(dtype=vec), v: wp.array(dtype=vec), F: wp.array(dtype=vec), m: wp.array(dtype=real),
             free: wp.array(dtype=real), g: vec, h: real):
        p = wp.tid()
        a = (F[p] / m[p] + g) * free[p]
        v[p] = v[p] + h * a
        x[p] = x[p] + h * v[p]

    return springs, step


def taichi(n, double, threads):
    """The same two loops as one Taichi kernel on the CPU (atomic adds); None without Taichi."""
    try:
        import taichi as ti
    except ImportError:
        return None
    real = ti.f64 if double else ti.f32
    ti.init(arch=ti.cpu, default_fp=real, cpu_max_num_threads=threads, log_level=ti.ERROR)
    d = flat(scene(n))
    p_count, s_count = len(d["x"]), len(d["i"])
    x, v, F = (ti.Vector.field(3, real, p_count) for _ in range(3))
    i, j = ti.field(ti.i32, s_count), ti.field(ti.i32, s_count)
    L0, k, kd = (ti.field(real, s_count) for _ in range(3))
    m, free = ti.field(real, p_count), ti.field(real, p_count)
    dtype = np.float64 if double else np.float32
    i.from_numpy(d["i"])
    j.from_numpy(d["j"])
    for field, a in ((L0, "L0"), (k, "k"), (kd, "kd"), (m, "m"), (free, "free")):  # the per-item data
        field.from_numpy(d[a].astype(dtype))

    @ti.kernel
    def substep(h: real):
        for p in range(p_count):
            F[p] = ti.Vector([0.0, 0.0, 0.0], dt=real)
        for s in range(s_count):
            a, b = i[s], j[s]
            dx = x[a] - x[b]
            inv_L = 1.0 / dx.norm()
            w = k[s] * (L0[s] * inv_L - 1.0) - kd[s] * (v[a] - v[b]).dot(dx) * (inv_L * inv_L)
            F[a] += dx * w
            F[b] -= dx * w
        for p in range(p_count):
            acc = (F[p] / m[p] + ti.Vector([0.0, 0.0, -G], dt=real)) * free[p]
            v[p] += h * acc
            x[p] += h * v[p]

    read = {}

    def reset():
        x.from_numpy(d["x"].astype(dtype))
        v.fill(0.0)

    def simulate(f):
        for _ in range(SUBSTEPS):  # a loop over the substeps of a frame
            substep(H)
        read["x"] = x.to_numpy()  # back to the host (and a sync), once per frame

    reset()
    return frames({"taichi": (simulate, reset, lambda: read["x"].astype(np.float64))})["taichi"]


def measure(n, threads):
    """Every implementation at n x n: {name: (times per frame, end positions)} (None: not installed).

    NumPy, numba (on all threads and on one) and Warp run in alternating rounds (:func:`frames`); Taichi
    after them, each precision alone (``ti.init`` starts a new runtime, which drops the other's fields).
    """
    runners = {"numpy": ours(n, "numpy"), "numba": ours(n, "numba"), "numba 1 thread": ours(n, "numba", 1),
               "warp f32": warp(n, False), "warp f64": warp(n, True)}
    out = dict.fromkeys(runners)
    out.update(frames({name: r for name, r in runners.items() if r is not None}))
    out["taichi f32"], out["taichi f64"] = taichi(n, False, threads), taichi(n, True, threads)
    return out


def report(results):
    """The tables: ms per step (best frame / 16, the mean in brackets), ratios, agreement."""
    names = list(next(iter(results.values())))
    print(f"ms per step (the best of {ROUNDS} x {FRAMES} frames of {SUBSTEPS} steps, / {SUBSTEPS}; "
          "the mean frame in brackets)")
    print(f"{'cloth':>7} {'springs':>8}" + "".join(f"{name:>17}" for name in names))
    for n, out in results.items():
        cells = [_ms(_times(out[name])) for name in names]
        print(f"{n:>5}^2 {_springs(n):>8}" + "".join(f"{cell:>17}" for cell in cells))
    print("\nratios of the best times (> 1: the compiled step is faster)")
    pairs = [("numpy", "numba"), ("warp f32", "numba"), ("warp f64", "numba"), ("warp f32", "numba 1 thread"),
             ("warp f64", "numba 1 thread"), ("taichi f32", "numba"), ("taichi f64", "numba")]
    print(f"{'cloth':>7}" + "".join(f"{a + ' / ' + b:>26}" for a, b in pairs))
    for n, out in results.items():
        cells = ["-" if _times(out[a]) is None else f"{_times(out[a]).min() / _times(out[b]).min():.2f}x"
                 for a, b in pairs]
        print(f"{n:>5}^2" + "".join(f"{cell:>26}" for cell in cells))
    print("\nlargest distance of the end positions (after 960 steps) from the NumPy run's, m")
    print(f"{'cloth':>7}" + "".join(f"{name:>17}" for name in names[1:]) + f"{'lowest z (numpy)':>18}")
    for n, out in results.items():
        x_np = out["numpy"][1]
        cells = ["-" if out[name] is None else f"{np.abs(out[name][1] - x_np).max():.1e}" for name in names[1:]]
        print(f"{n:>5}^2" + "".join(f"{cell:>17}" for cell in cells) + f"{x_np[:, 2].min():>18.4f}")


def _ms(t):
    """A cell of the times table: ms per step of the best frame, and of the mean frame in brackets."""
    return "-" if t is None else f"{1e3 * t.min() / SUBSTEPS:7.3f} ({1e3 * t.mean() / SUBSTEPS:6.3f})"


def _times(run):
    return None if run is None else run[0]


def _springs(n):
    return 2 * n * (n - 1) + 2 * (n - 1) ** 2 + 2 * n * (n - 2)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES), help="particles per side")
    args = parser.parse_args(argv)
    if "numba" not in backends.available():
        print("numba is not installed (pip install 'particles[fast]'): nothing to compare")
        return
    import numba

    import particles.backends.compile  # noqa: F401  (before numba starts its threads: it picks their pool)

    threads = numba.get_num_threads()
    notes = [f"{name} is not installed (pip install 'particles[bench]'): its columns are skipped"
             for name in ("warp", "taichi") if _missing(name)]
    print(f"Warp's cloth benchmark set-up; numba {numba.__version__} on {threads} threads; "
          f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    for note in notes:
        print("  " + note)
    start = time.perf_counter()
    results = {}
    for n in args.sizes:  # a loop over the sizes
        results[n] = out = measure(n, threads)
        gap = np.abs(out["numba"][1] - out["numpy"][1]).max()
        if gap > AGREE:
            raise AssertionError(f"{n}^2: the compiled run ends {gap:.1e} m from the NumPy run (> {AGREE:g} m)")
    report(results)
    print(f"\nload average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}; "
          f"{time.perf_counter() - start:.0f} s")


def _missing(name):
    import importlib.util

    return importlib.util.find_spec(name) is None


if __name__ == "__main__":
    sys.exit(main())
