"""What vectorization buys: the slide's loop in pure Python vs the library.

The same particle system (gravity, damping and an attractor, explicit Euler,
100 steps) is simulated twice:

* loop        the lecture's pseudocode written with Python loops: a Particle
              object per particle, each force adding into p.f, then an Euler
              update particle by particle;
* vectorized  particles.ParticleSystem with NumPy arrays.

Both give the same trajectory (checked); the table prints the ratio.

Run:  python bench/bench_vectorization.py
"""

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _timing import best_time  # noqa: E402

from particles import ParticleSystem  # noqa: E402
from particles.forces import Attractor, Damping, Gravity  # noqa: E402

G = (0.0, -9.81)
D = 0.2
CENTER, STRENGTH, SOFT = (0.0, 0.0), 5.0, 0.1


class Particle:
    """The slide's particle: position, velocity, mass and a force accumulator."""

    def __init__(self, x, v, m):
        self.x, self.v, self.m = list(x), list(v), m
        self.f = [0.0, 0.0]


def compute_forces(particles):
    for p in particles:  # the naive baseline: one particle at a time
        p.f = [p.m * G[0], p.m * G[1]]                       # gravity
        p.f[0] -= D * p.v[0]                                 # damping
        p.f[1] -= D * p.v[1]
        rx, ry = CENTER[0] - p.x[0], CENTER[1] - p.x[1]      # attractor
        r2 = rx * rx + ry * ry + SOFT * SOFT
        s = STRENGTH / (r2 * math.sqrt(r2))
        p.f[0] += s * rx
        p.f[1] += s * ry


def euler_loop(particles, h, steps):
    for _ in range(steps):
        compute_forces(particles)
        for p in particles:
            ax, ay = p.f[0] / p.m, p.f[1] / p.m
            p.x[0] += h * p.v[0]
            p.x[1] += h * p.v[1]
            p.v[0] += h * ax
            p.v[1] += h * ay
    return particles


def main():
    print(__doc__.split("\n\n")[1])
    h, steps = 0.001, 100
    print(f"\n{'N':>6} {'loop (ms)':>10} {'vectorized (ms)':>16} {'speed-up':>9}")
    for n in (100, 1000, 10000):
        rng = np.random.default_rng(0)
        x0, v0, m = rng.normal(size=(n, 2)), rng.normal(size=(n, 2)), rng.uniform(1, 2, n)

        def loop():
            return euler_loop([Particle(x0[k], v0[k], m[k]) for k in range(n)], h, steps)

        def vectorized():
            ps = ParticleSystem(x0, v=v0, m=m, forces=[Gravity(G), Damping(D), Attractor(CENTER, STRENGTH, SOFT)])
            ps.run(steps * h, h, method="euler", every=steps)
            return ps

        ps, particles = vectorized(), loop()
        assert np.allclose(ps.X[:, 0], [p.x for p in particles], rtol=1e-10, atol=1e-12)
        t_loop = best_time(loop, repeat=1 if n > 1000 else 3)
        t_vec = best_time(vectorized)
        print(f"{n:>6} {1e3 * t_loop:>10.1f} {1e3 * t_vec:>16.1f} {t_loop / t_vec:>8.0f}x")


if __name__ == "__main__":
    main()
