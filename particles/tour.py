"""The course tour run by ``make demo``: figures, animations and tables into one folder.

Each part is a function that computes data and a separate step that draws it,
so that tests and lectures can call the same functions without a window.
"""

import time
from pathlib import Path

import numpy as np

from . import demos, forces, render
from .neighbors import all_pairs, cell_pairs
from .system import ParticleSystem

__all__ = ["force_field_scene", "lennard_jones_costs", "run_tour"]


def force_field_scene(n=300, t_end=6.0, h=0.01, every=10, seed=0):
    """Particles released from a disk into a vortex, an attractor, gravity and damping.

    Returns
    -------
    t : ndarray, shape (K,)
    X : ndarray, shape (K, n, 2, 2)
    """
    rng = np.random.default_rng(seed)
    r = np.sqrt(rng.random(n)) * 0.5
    angle = rng.random(n) * 2 * np.pi
    x = np.stack([r * np.cos(angle) - 1.5, r * np.sin(angle) + 1.0], axis=1)
    system = ParticleSystem(
        x, m=1.0,
        forces=[
            forces.Gravity([0.0, -0.2]),
            forces.Vortex([0.0, 0.0], strength=2.0, core=0.3),
            forces.Attractor([0.0, 0.0], strength=3.0, softening=0.6),
            forces.Damping(1.0),
        ],
    )
    return system.run(t_end, h, method="rk4", every=every)


def lennard_jones_costs(sizes=(250, 500, 1000, 2000), density=0.8, cutoff=2.5, seed=0):
    """Seconds to find the interacting pairs of a 2D Lennard-Jones liquid, all pairs vs cells.

    Returns a list of dicts with keys ``n``, ``pairs``, ``all_s``, ``cells_s``.
    """
    rows = []
    rng = np.random.default_rng(seed)
    for n in sizes:
        side = np.sqrt(n / density)
        x = rng.random((n, 2)) * side
        t0 = time.perf_counter()
        i, _ = all_pairs(x, cutoff)
        t1 = time.perf_counter()
        cell_pairs(x, cutoff)
        t2 = time.perf_counter()
        rows.append({"n": n, "pairs": len(i), "all_s": t1 - t0, "cells_s": t2 - t1})
    return rows


def run_tour(out="out", log=print):
    """Run every part of the tour, write its files into `out`, print a summary.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    start = time.perf_counter()

    from .studies.report import write_study, write_table

    log("1. Integrator order: global error at t = 5 s against the step size (particles study order)")
    written += write_study("order", out, log=lambda line: log("   " + line))

    log("\n2. A particle system in a force field (vortex + attractor + gravity + damping)")
    t, X = force_field_scene()
    anim = render.animate(X[:, :, 0], times=t, velocities=X[:, :, 1], blur=0.05,
                          limits=[(-2.5, 2.5), (-2.5, 2.5)], title="force field", figsize=(4, 4))
    written.append(render.save_gif(anim, out / "force_field.gif", fps=10))
    log(f"   {X.shape[1]} particles, {len(t)} frames, rk4 with h = 0.01 s")

    log("\n3. Lennard-Jones neighbour search, all pairs O(N^2) vs bucket grid O(N)")
    rows = lennard_jones_costs()
    log(f"   {'N':>6} {'pairs':>8} {'all (ms)':>10} {'cells (ms)':>11} {'ratio':>7}")
    for r in rows:
        log(f"   {r['n']:>6} {r['pairs']:>8} {1e3 * r['all_s']:>10.1f} {1e3 * r['cells_s']:>11.1f} "
            f"{r['all_s'] / r['cells_s']:>7.1f}")
    written.append(write_table(out, "lennard_jones_costs", rows))

    log("\n4. Stiffness, Provot's constraint, discretization (particles study NAME)")
    for name in ("stability", "provot", "discretization"):
        written += write_study(name, out, log=lambda line: log("   " + line))

    log("\n5. Collisions: a dropped ball, backtracking vs projection (particles study bounce)")
    written += write_study("bounce", out, log=lambda line: log("   " + line))

    log("\n6. Particle effects: emitters, lifetimes, collisions, hierarchies, flocks")
    log("   short previews at 5 frames/s; full length: particles demo all")
    for name, demo in demos.DEMOS.items():  # a loop over the registered demos
        t0 = time.perf_counter()
        data, paths = demos.write_demo(name, out, **demo.preview)
        info = ", ".join(f"{k} {v}" for k, v in data.info.items())
        log(f"   {name:<10} {len(data):>4} frames  {info}  ({time.perf_counter() - t0:.1f} s)")
        written.extend(paths)

    log(f"\nWrote {len(written)} files to {out}/ in {time.perf_counter() - start:.1f} s:")
    for path in written:
        log(f"   {path}")
    return written
