"""Lennard-Jones forces: bucket grid ("cells") vs all pairs, in a periodic liquid.

A 3D Lennard-Jones liquid in a periodic box at reduced density rho sigma^3 =
0.86 (an FCC lattice melted at T* = 3, then cooled to T* = 0.85), cutoff 2.5
sigma, for N = 1k, 4k, 16k, 64k particles; the box is 4 x (10, 5, 5), (10, 10,
10), (20, 20, 10) and (20, 20, 40) FCC cells, so the number of pairs grows
exactly like N. For each N:

* all      one force evaluation testing all N^2 pairs (minimum image; the O(N^2) reference);
* search   the bucket-grid pair search alone;
* kdtree   scipy.spatial.cKDTree pair search in the same periodic box, a compiled reference point;
* fresh    bucket-grid search plus force pass (no reuse), one evaluation;
* pass     the force pass alone over a ready pair list;
* step     cost per step of a velocity-Verlet run with a Verlet list (skin 0.3 sigma,
           rebuilt only when needed), the force evaluated once per step (evals/step).

Run:  python bench/bench_lennard_jones.py [--quick]
"""

import argparse
import os
import sys
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _timing import best_time  # noqa: E402

from particles import ParticleSystem  # noqa: E402
from particles.forces import LennardJones  # noqa: E402
from particles.md import fcc_lattice, maxwell_boltzmann  # noqa: E402
from particles.neighbors import cell_pairs  # noqa: E402
from particles.md import wrap  # noqa: E402
from particles.md import Berendsen  # noqa: E402

CELLS = {1000: (10, 5, 5), 4000: (10, 10, 10), 16000: (20, 20, 10), 64000: (20, 20, 40)}


def liquid(n, density=0.86, seed=0):
    """A periodic Lennard-Jones liquid of n particles: an FCC lattice melted at T* = 3, then held at 0.85.

    0.4 time units at T* = 3 melt the lattice, 0.2 more at T* = 0.85 (velocities
    rescaled every step) cool it. Returns positions (n, 3) folded into the
    box, velocities (n, 3) and the box (3,).
    """
    x, box = fcc_lattice(CELLS[n], density)
    melt = ParticleSystem(x, v=maxwell_boltzmann(n, 3.0, seed=seed),
                          forces=[LennardJones.from_epsilon_sigma(skin=0.3, box=box)])
    melt.run(0.4, 0.005, method=Berendsen(3.0, tau=0.005))
    melt.run(0.6, 0.005, method=Berendsen(0.85, tau=0.005))
    return wrap(melt.X[:, 0], box), melt.state()[:, 1], box


class Counter:
    """A force that adds nothing and counts its evaluations (position-only, like Lennard-Jones)."""

    uses_velocity = False
    uses_time = False

    def __init__(self):
        self.calls = 0

    def add_to(self, F, x, v, t, m):
        self.calls += 1


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="only 1k and 4k particles")
    args = parser.parse_args(argv)
    sizes = [1000, 4000] if args.quick else [1000, 4000, 16000, 64000]
    all_limit = 16000  # all pairs at 64k would take minutes

    load = os.getloadavg()[0]
    print(__doc__.split("\n\n")[1].replace("\n", " "))
    header = (f"{'N':>6} {'pairs':>9} {'all':>9} {'search':>8} {'kdtree':>8} {'fresh':>8} {'pass':>8} "
              f"{'step':>8} {'all/fresh':>9} {'evals/step':>10} {'rebuilds':>9}")
    print("\ntimes in ms (best of several runs)")
    print(header)
    print("-" * len(header))
    results = {}
    for n in sizes:
        x, v, box = liquid(n)
        lj_all = LennardJones.from_epsilon_sigma(neighbors="all", box=box)
        lj_fresh = LennardJones.from_epsilon_sigma(skin=0.0, box=box)
        F_ref = lj_fresh(x)
        t_all = None
        if n <= all_limit:
            t_all = best_time(lambda: lj_all(x), repeat=1)
            assert np.allclose(lj_all(x), F_ref, atol=1e-9)
        t_search = best_time(lambda: cell_pairs(x, 2.5, box=box))
        t_kd = best_time(lambda: cKDTree(x, boxsize=box).query_pairs(2.5, output_type="ndarray"))

        def fresh():
            lj_fresh.neighbor_list.reset()  # forget the pair list: search again
            return lj_fresh(x)

        t_fresh = best_time(fresh)
        lj_reuse = LennardJones.from_epsilon_sigma(skin=0.3, box=box)
        lj_reuse(x)  # build the list once
        t_pass = best_time(lambda: lj_reuse(x), repeat=5)
        # a short run: velocity Verlet, h = 0.005, velocities at T* = 0.85
        lj_run, count = LennardJones.from_epsilon_sigma(skin=0.3, box=box), Counter()
        ps = ParticleSystem(x, v=v, forces=[lj_run, count])
        steps = 40
        t_run = best_time(lambda: ps.run(ps.t + steps * 0.005, 0.005, method="verlet", every=steps), repeat=2)
        runs = count.calls / (steps + 1)  # best_time may run it more than once
        t_step = t_run / steps
        pairs = len(cell_pairs(x, 2.5, box=box)[0])
        results[n] = pairs, t_fresh, t_pass, t_step
        ratio = f"{t_all / t_fresh:9.1f}" if t_all else f"{'-':>9}"
        all_ms = f"{1e3 * t_all:9.1f}" if t_all else f"{'(skip)':>9}"
        print(f"{n:>6} {pairs:>9} {all_ms} {1e3 * t_search:8.1f} {1e3 * t_kd:8.1f} {1e3 * t_fresh:8.1f} "
              f"{1e3 * t_pass:8.1f} {1e3 * t_step:8.1f} {ratio} {count.calls / (runs * steps):>10.3f} "
              f"{lj_run.neighbor_list.builds:>5}/{int(runs) * steps}")
    print()
    ns = sorted(results)
    for a, b in zip(ns, ns[1:]):
        (pa, fa, qa, sa), (pb, fb, qb, sb) = results[a], results[b]
        print(f"cost growth {a:>6} -> {b:>6} particles (x{b / a:.0f}, pairs x{pb / pa:.2f}): "
              f"search plus forces x{fb / fa:.2f}, force pass x{qb / qa:.2f}, Verlet step x{sb / sa:.2f}")
    print(f"load average before: {load:.2f}, after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
