"""What collisions, emitters and boids cost, and how the cost grows with the number of particles.

* collisions  one step of particles in a box with a round obstacle: the
              quick fix ("project") against finding the crossing time on the
              step's path ("backtrack"), same particles, same step;
* effect      one step of a fountain at steady state (births, motion,
              ground collisions, deaths), with the number of live particles
              set by the emission rate: the cost should grow like n;
* boids       the steering rules with neighbours from the bucket grid against
              the same rules with all n (n - 1) pairs.

Run:  python bench/bench_effects.py
"""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _timing import best_time  # noqa: E402

from particles import ParticleSystem  # noqa: E402
from particles.collisions import Box, Collider, Plane, Sphere  # noqa: E402
from particles.effects import ParticleEffect  # noqa: E402
from particles.effects import Cone, Disk, Emitter  # noqa: E402
from particles.effects import Boids  # noqa: E402
from particles.forces import Gravity, pair_differences  # noqa: E402
from particles.neighbors import all_pairs  # noqa: E402


def collisions(n, h=0.005):
    """Seconds per collide() call with each method, for n particles moving at ~3 m/s in a 2 m box."""
    rng = np.random.default_rng(0)
    scene = Box([-1, -1, -1], [1, 1, 1], container=True) | Sphere([0, 0, 0], 0.4)
    x = rng.uniform(-0.95, 0.95, (2 * n, 3))
    x = x[scene.H(x) > 0][:n]
    ps = ParticleSystem(x, v=rng.normal(0.0, 3.0, x.shape), forces=[Gravity([0, 0, -9.81])])
    X_old = ps.state()
    ps.step(h, method="verlet")
    times = {}
    for method in ("project", "backtrack"):
        collider = Collider(scene, restitution=0.8, method=method)
        times[method] = best_time(lambda: collider.collide(X_old, ps.X, 0.0, h))
    return times


def effect_step(rate, h=0.01):
    """Seconds per step of a fountain at steady state, and its number of live particles."""
    nozzle = Emitter(rate, Disk([0, 0, 0.05], 0.05), Cone([0, 0, 1], 4.0, 0.3, angle=0.3), lifetime=(1.5, 0.3))
    fountain = ParticleEffect(3, [nozzle], forces=[Gravity([0, 0, -9.81])], seed=0,
                              collider=Collider(Plane([0, 0, 0], [0, 0, 1]), restitution=0.3))
    fountain.run(2.0, h)  # fill up to the steady state
    return best_time(lambda: fountain.step(h)), fountain.n


def boids_all_pairs(rules, x, v):
    """The same rules with every pair: the O(n^2) reference neighbour search."""
    i, j = all_pairs(x, rules.radius)
    obs, nb = np.concatenate([i, j]), np.concatenate([j, i])
    r = pair_differences(x, nb, obs)
    n, d = x.shape
    count = np.bincount(obs, minlength=n)
    inv = np.divide(1.0, count, out=np.zeros(n), where=count > 0)
    return np.stack([rules.cohesion * np.bincount(obs, r[k], minlength=n) * inv for k in range(d)], axis=1)


def main():
    print(__doc__.split("\n\n")[1])
    print(f"\n{'N':>7} {'project (ms)':>13} {'backtrack (ms)':>15} {'ratio':>6}")
    for n in (1000, 4000, 16000):
        t = collisions(n)
        print(f"{n:>7} {1e3 * t['project']:>13.2f} {1e3 * t['backtrack']:>15.2f} {t['backtrack'] / t['project']:>6.1f}")

    print(f"\n{'rate (1/s)':>10} {'live N':>7} {'step (ms)':>10} {'us per particle':>16}")
    for rate in (1000, 4000, 16000):
        seconds, n = effect_step(rate)  # (the first size also pays for warming up caches)
        print(f"{rate:>10} {n:>7} {1e3 * seconds:>10.2f} {1e6 * seconds / n:>16.2f}")

    print(f"\n{'N':>7} {'bucket grid (ms)':>17} {'all pairs (ms)':>15} {'ratio':>6}")
    for n in (1000, 2000, 4000):
        rng = np.random.default_rng(0)
        side = np.sqrt(n / 2.0)  # 2 boids per square metre
        x, v = rng.uniform(0, side, (n, 2)), rng.normal(size=(n, 2))
        rules = Boids(1.5)
        t_grid = best_time(lambda: rules.accelerations(x, v))
        t_all = best_time(lambda: boids_all_pairs(rules, x, v), repeat=1)
        print(f"{n:>7} {1e3 * t_grid:>17.1f} {1e3 * t_all:>15.1f} {t_all / t_grid:>6.1f}")


if __name__ == "__main__":
    main()
