"""Cloth: cost of an explicit step, and explicit vs implicit on a stiff cloth.

Part 1. One explicit step (all forces + symplectic Euler) of a hanging cloth
with structural, shear and flexion springs in one generic spring list, at
32^2 ... 256^2 particles:

* vectorized  ParticleSystem with one particles.forces.Springs force;
* loop        the same step written with Python loops over springs and
              particles (the naive baseline).

Part 2. A stiff cloth that symplectic Euler can only step at h < 1e-4 s (64^2,
1 m^2, 0.2 kg/m^2, stretch modulus 5000 N/m with physical scaling, hanging from
its top corners, released unstretched): wall time to simulate 1 s with
symplectic Euler at 90% of its stability limit, against the implicit solvers
with their defaults at h = 1/60 s (Baraff-Witkin: the paper's solve and one
Newton iteration, block-Jacobi CG falling back to a sparse factorization;
prefactorized: local/global iterations to a residual, Anderson-accelerated)
and Liu et al.'s fixed 10 iterations. For each: the work per step, the largest
energy gain over any stretch of the run (% of M g H, H = 1 m) and the largest
strain.

Run:  python bench/bench_cloth.py [--quick]
"""

import argparse
import math
import os
import sys
import time
from pathlib import Path

# single-threaded BLAS (set before NumPy loads it): steadier timings for the
# small vectors of conjugate gradients on a shared machine
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import scipy.sparse.linalg  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _timing import best_time  # noqa: E402

from particles import ParticleSystem  # noqa: E402
from particles.forces import Damping, Gravity  # noqa: E402
from particles.implicit import BaraffWitkin, Prefactored  # noqa: E402
from particles.integrators import symplectic_euler  # noqa: E402
from particles.massspring import cloth  # noqa: E402
from particles.forces import Springs  # noqa: E402

G = (0.0, 0.0, -9.81)
DAMPING = 0.01


def generic_system(n):
    """The cloth with all its springs in one list (the generic spring force)."""
    c = cloth(n, n)
    k = np.concatenate([s.k for s in c.springs.values()])
    springs = Springs(c.spring_indices(), c.rest_lengths(), k=k)
    return ParticleSystem(c.X[:, 0], m=c.m, forces=[springs, Gravity(G), Damping(DAMPING)], pinned=c.pinned), springs


def loop_step(x, v, m, pinned, springs, h):
    """The naive baseline: Python loops over springs, then over particles."""
    n = len(x)
    F = [[m[p] * G[0] - DAMPING * v[p][0], m[p] * G[1] - DAMPING * v[p][1], m[p] * G[2] - DAMPING * v[p][2]]
         for p in range(n)]
    for a, b, L0, k in springs:
        dx, dy, dz = x[a][0] - x[b][0], x[a][1] - x[b][1], x[a][2] - x[b][2]
        L = math.sqrt(dx * dx + dy * dy + dz * dz)
        f = k * (L0 - L) / L
        F[a][0] += f * dx
        F[a][1] += f * dy
        F[a][2] += f * dz
        F[b][0] -= f * dx
        F[b][1] -= f * dy
        F[b][2] -= f * dz
    for p in range(n):
        if p in pinned:
            continue
        for c in range(3):
            v[p][c] += h * F[p][c] / m[p]
            x[p][c] += h * v[p][c]


def part1(sizes):
    print("Part 1: one explicit step of a hanging cloth (ms)")
    print(f"{'particles':>10} {'springs':>8} {'vectorized':>11} {'loop':>10} {'speed-up':>9}")
    h = 1e-4
    for n in sizes:
        ps, springs = generic_system(n)
        X = ps.state()
        t_vec = best_time(lambda: symplectic_euler(ps.derivative, X, 0.0, h), repeat=5)
        # check the loop does the same step, then time it
        x, v = X[:, 0].tolist(), X[:, 1].tolist()
        spring_list = list(zip(springs.i.tolist(), springs.j.tolist(), springs.rest_length.tolist(), springs.k.tolist()))
        pinned = set(ps.pinned.tolist())
        perturbed = X.copy()
        perturbed[:, 0] += np.random.default_rng(0).normal(scale=1e-3, size=perturbed[:, 0].shape)
        perturbed[ps.pinned, 0] = X[ps.pinned, 0]
        x, v = perturbed[:, 0].tolist(), perturbed[:, 1].tolist()
        loop_step(x, v, ps.m.tolist(), pinned, spring_list, h)
        assert np.allclose(np.array(x), symplectic_euler(ps.derivative, perturbed, 0.0, h)[:, 0], atol=1e-12)
        t_loop = best_time(lambda: loop_step(X[:, 0].tolist(), X[:, 1].tolist(), ps.m.tolist(), pinned,
                                             spring_list, h), repeat=1, min_time=0.0)
        print(f"{n:>6}^2 {len(springs):>10} {1e3 * t_vec:>11.2f} {1e3 * t_loop:>10.1f} {t_loop / t_vec:>8.0f}x")


def stable_step(system):
    """90% of symplectic Euler's limit h < 2 / omega_max, omega_max^2 = largest eigenvalue of -M^-1 K."""
    Kx, _ = system.spring_jacobians(clamp=True)
    free = np.setdiff1d(np.arange(system.n), system.pinned)
    dofs = (free[:, None] * 3 + np.arange(3)).ravel()
    K = -Kx.tocsr()[dofs][:, dofs]
    m = np.repeat(system.m[free], 3)
    s = 1 / np.sqrt(m)
    A = scipy.sparse.diags(s) @ K @ scipy.sparse.diags(s)  # symmetric, same eigenvalues as M^-1 K
    lam = scipy.sparse.linalg.eigsh(A, k=1, which="LA", return_eigenvectors=False)[0]
    return 0.9 * 2 / math.sqrt(lam)


def work(method):
    """Linear solves (Baraff-Witkin) or local/global iterations (prefactorized) per step."""
    if isinstance(method, BaraffWitkin):
        return f"{np.mean(method.newton):.2f} solves"
    if isinstance(method, Prefactored):
        return f"{np.mean(method.counts):.0f} iterations"
    return "-"


def part2(n):
    print(f"\nPart 2: simulate 1 s of a stiff {n}^2 hanging cloth")
    make = dict(nx=n, ny=n, scaling="physical", areal_density=0.2, stretch_modulus=5000.0, damping=0.1)
    h_explicit = stable_step(cloth(**make))
    runs = [("symplectic Euler", h_explicit, lambda c: "symplectic_euler"),
            ("Baraff-Witkin", 1 / 60, lambda c: BaraffWitkin(c)),
            ("prefactorized", 1 / 60, lambda c: Prefactored(c, 1 / 60)),
            ("prefactorized, 10 its", 1 / 60, lambda c: Prefactored(c, 1 / 60, iterations=10))]
    rows = []
    for name, h, solver in runs:
        c = cloth(**make)
        method = solver(c)
        t0 = time.perf_counter()
        t, X = c.run(1.0, h, method=method, every=max(1, round(1 / 60 / h)))
        wall = time.perf_counter() - t0
        E = np.array([c.kinetic_energy(Xk) + c.potential_energy(Xk) for Xk in X]) / (c.m.sum() * 9.81)
        gain = float(np.max(E - np.minimum.accumulate(E)))
        rows.append((name, h, wall, work(method), gain, max(c.max_strain(Xk) for Xk in X)))
    print(f"{'method':>22} {'h (s)':>10} {'steps':>7} {'wall (s)':>9} {'vs explicit':>12} {'per step':>15} "
          f"{'E gain':>7} {'max strain':>11}")
    for name, h, wall, per_step, gain, strain in rows:
        print(f"{name:>22} {h:>10.2e} {math.ceil(1 / h):>7} {wall:>9.2f} {rows[0][2] / wall:>11.2f}x {per_step:>15} "
              f"{100 * gain:>6.2f}% {strain:>11.4f}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small sizes only")
    args = parser.parse_args(argv)
    part1([32, 64] if args.quick else [32, 64, 128, 256])
    part2(32 if args.quick else 64)


if __name__ == "__main__":
    main()
