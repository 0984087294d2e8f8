"""Small timing helpers shared by the benchmark scripts."""

import time


def best_time(fn, repeat=3, min_time=0.2):
    """Best wall time of `fn()` in seconds over `repeat` runs (each at least once).

    Taking the minimum filters out noise from other processes on a shared
    machine; compare ratios measured in the same run, not absolute times.
    """
    best = float("inf")
    spent = 0.0
    runs = 0
    while runs < repeat or (spent < min_time and runs < 50):
        t0 = time.perf_counter()
        fn()
        dt = time.perf_counter() - t0
        best = min(best, dt)
        spent += dt
        runs += 1
    return best
