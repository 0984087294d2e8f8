"""Lennard-Jones forces: bucket grid ("cells") vs all pairs, at liquid density.

A 3D Lennard-Jones liquid at reduced density rho sigma^3 = 0.8 with cutoff
2.5 sigma, for N = 1k, 4k, 16k, 64k particles. For each N:

* all      one force evaluation testing all N^2 pairs (the O(N^2) reference);
* search   the bucket-grid pair search alone;
* kdtree   scipy.spatial.cKDTree pair search, a compiled reference point;
* fresh    bucket-grid search plus force pass (no reuse), one evaluation;
* pass     the force pass alone over a ready pair list;
* step     amortized cost per force evaluation during a short velocity-Verlet
           run with a Verlet list (skin 0.3 sigma), rebuilt only when needed.

Run:  python bench/bench_lennard_jones.py [--quick]
"""

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _timing import best_time  # noqa: E402

from particles import ParticleSystem  # noqa: E402
from particles.forces import LennardJones  # noqa: E402
from particles.neighbors import cell_pairs  # noqa: E402


def liquid(n, density=0.8, seed=0):
    """Jittered cubic lattice at the given number density (sigma = 1)."""
    rng = np.random.default_rng(seed)
    k = int(np.ceil(n ** (1 / 3)))
    side = (n / density) ** (1 / 3)
    grid = np.stack(np.meshgrid(*[np.arange(k)] * 3, indexing="ij"), -1).reshape(-1, 3)[:n]
    return (grid + 0.5 + rng.uniform(-0.1, 0.1, (n, 3))) * side / k


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="only 1k and 4k particles")
    args = parser.parse_args(argv)
    sizes = [1000, 4000] if args.quick else [1000, 4000, 16000, 64000]
    all_limit = 16000  # all pairs at 64k would take minutes

    print(__doc__.split("\n\n")[1].replace("\n", " "))
    header = f"{'N':>6} {'pairs':>9} {'all':>9} {'search':>8} {'kdtree':>8} {'fresh':>8} {'pass':>8} {'step':>8} {'all/fresh':>9} {'rebuilds':>9}"
    print("\ntimes in ms per force evaluation (best of several runs)")
    print(header)
    print("-" * len(header))
    results = {}
    for n in sizes:
        x = liquid(n)
        lj_all = LennardJones.from_epsilon_sigma(neighbors="all")
        lj_fresh = LennardJones.from_epsilon_sigma(skin=0.0)
        F_ref = lj_fresh(x)
        t_all = None
        if n <= all_limit:
            t_all = best_time(lambda: lj_all(x), repeat=1)
            assert np.allclose(lj_all(x), F_ref, atol=1e-9)
        t_search = best_time(lambda: cell_pairs(x, 2.5))
        t_kd = best_time(lambda: cKDTree(x).query_pairs(2.5, output_type="ndarray"))
        def fresh():
            lj_fresh.neighbor_list.reset()  # forget the pair list: search again
            return lj_fresh(x)

        t_fresh = best_time(fresh)
        lj_reuse = LennardJones.from_epsilon_sigma(skin=0.3)
        lj_reuse(x)  # build the list once
        t_pass = best_time(lambda: lj_reuse(x))
        # a short run: velocity Verlet, h = 0.005, velocities at temperature ~1
        rng = np.random.default_rng(1)
        v = rng.normal(size=x.shape)
        v -= v.mean(axis=0)
        lj_run = LennardJones.from_epsilon_sigma(skin=0.3)
        ps = ParticleSystem(x, v=v, forces=[lj_run])
        steps = 40
        t_run = best_time(lambda: ps.run(ps.t + steps * 0.005, 0.005, method="verlet", every=steps), repeat=1)
        t_step = t_run / (2 * steps)  # two force evaluations per Verlet step
        i, _ = cell_pairs(x, 2.5)
        results[n] = t_fresh
        ratio = f"{t_all / t_fresh:9.1f}" if t_all else f"{'-':>9}"
        all_ms = f"{1e3 * t_all:9.1f}" if t_all else f"{'(skip)':>9}"
        print(f"{n:>6} {len(i):>9} {all_ms} {1e3 * t_search:8.1f} {1e3 * t_kd:8.1f} {1e3 * t_fresh:8.1f} "
              f"{1e3 * t_pass:8.1f} {1e3 * t_step:8.1f} {ratio} {lj_run.neighbor_list.builds:>5}/{2 * steps}")
    print()
    ns = sorted(results)
    for a, b in zip(ns, ns[1:]):
        print(f"cells cost growth {a:>6} -> {b:>6} particles (x{b / a:.0f}): x{results[b] / results[a]:.2f}")


if __name__ == "__main__":
    main()
