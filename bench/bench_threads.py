"""numba's thread pools on this machine: what a parallel loop costs to start, and what two threads gain.

The compiled kernels (:mod:`particles.backends`) run their long loops on numba's threads, and a step
is many short parallel loops: one per step of a cloth (a fraction of a millisecond each), one per
colour group of an XPBD substep (17 per substep on a 128^2 cloth, tens of microseconds each). The
thread pool then matters as much as the kernels. :mod:`particles.backends.compile` picks GNU OpenMP
with a bounded spin (``GOMP_SPINCOUNT=10000``) unless the user chose a layer; this script measures
that choice against numba's work queue and against OpenMP's default spin, each in its own process
(a process keeps the layer it started with):

* ``start``: an empty parallel loop of two iterations, on two threads (us);
* ``loop 1t``, ``loop 2t``: a parallel loop of two chunks of about 0.1 ms of arithmetic each, on one
  thread and on two (us): on two, it should take half the time;
* ``xpbd alone``: a 128^2 XPBD substep (:func:`particles.xpbd.kernels.substep`, damped
  springs, every colour group in parallel), ms;
* ``xpbd shared``: the same, while a second process runs the same substeps on its own two threads:
  two processes on two cores, as a test suite run with two workers, or a class's kernels on a
  shared server (ms, the slower of the two processes).

Times are the best of many calls. Read them side by side: the machine is shared and its speed
changes from minute to minute.

Run:  python bench/bench_threads.py
"""

import json
import os
import subprocess
import sys
import time


CONFIGURATIONS = {  # name: the environment of the process
    "workqueue": {"NUMBA_THREADING_LAYER": "workqueue"},
    "omp, default spin": {"NUMBA_THREADING_LAYER": "omp", "GOMP_SPINCOUNT": ""},
    "omp, GOMP_SPINCOUNT=10000 (the library's)": {},
}

PROBE = r"""
import json, math, sys, time
import numpy as np
import particles.backends.compile  # its choice of layer, unless the environment has one
import numba
from numba import prange

@numba.njit(parallel=True)
def chunks(a, reps):
    for c in prange(2):
        s = 0.0
        for r in range(reps):
            s += math.sqrt(r + c)
        a[c] = s

def best(fn, calls):
    out = float("inf")
    for _ in range(calls):
        t = time.perf_counter(); fn(); out = min(out, time.perf_counter() - t)
    return out

a = np.zeros(2)
chunks(a, 1)
result = {"layer": None}
numba.set_num_threads(2)
result["start"] = 1e6 * best(lambda: chunks(a, 1), 200)
for threads in (1, 2):
    numba.set_num_threads(threads)
    result[f"loop {threads}t"] = 1e6 * best(lambda: chunks(a, 40000), 100)
numba.set_num_threads(2)
result["layer"] = numba.threading_layer()
sys.path.insert(0, sys.argv[1])
from bench_constraints import substep_cases
from particles.backends import compile as kernels
from particles.xpbd import XPBD
kernels.PARALLEL_MIN = 0  # every colour group in parallel
c, X = substep_cases(128)["damped springs, gravity"]
solver = XPBD.from_system(c, substeps=10, iterations=1, backend="numba")
solver(None, X, 0.0, 1 / 60)
print("ready", flush=True)
sys.stdin.readline()  # both processes start their timing together
result["xpbd"] = 1e3 * best(lambda: solver(None, X, 0.0, 1 / 60), 20) / 10
print(json.dumps(result), flush=True)
"""


def probe(env, copies):
    """Run `copies` probe processes with `env` at once; their results."""
    here = os.path.dirname(os.path.abspath(__file__))
    environment = {k: v for k, v in os.environ.items() if k not in ("NUMBA_THREADING_LAYER", "GOMP_SPINCOUNT")}
    environment.update({k: v for k, v in env.items() if v})
    procs = [subprocess.Popen([sys.executable, "-c", PROBE, here], env=environment, stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True) for _ in range(copies)]
    for p in procs:  # a loop over the few processes: wait until each has compiled and warmed up
        assert p.stdout.readline().strip() == "ready"
    for p in procs:
        p.stdin.write("go\n")
        p.stdin.flush()
    results = [json.loads(p.stdout.readline()) for p in procs]
    for p in procs:
        p.wait()
    return results


def main():
    print(f"load average before: {os.getloadavg()[0]:.2f}; {os.cpu_count()} cores")
    print(f"{'configuration':>42} {'layer':>10} {'start us':>9} {'loop 1t':>8} {'loop 2t':>8} {'2t gain':>8} "
          f"{'xpbd alone':>11} {'xpbd shared':>12}")
    start = time.perf_counter()
    for name, env in CONFIGURATIONS.items():
        alone = probe(env, 1)[0]
        shared = max(r["xpbd"] for r in probe(env, 2))
        print(f"{name:>42} {alone['layer']:>10} {alone['start']:>9.1f} {alone['loop 1t']:>8.1f} "
              f"{alone['loop 2t']:>8.1f} {alone['loop 1t'] / alone['loop 2t']:>7.2f}x {alone['xpbd']:>11.2f} "
              f"{shared:>12.2f}")
    print(f"load average after: {os.getloadavg()[0]:.2f}; {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
