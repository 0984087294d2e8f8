"""Grading on an embedded Dask cluster (--scheduler local:2) against this machine's pool (--jobs 2).

Both grade the same corpus with the same seed; the cluster's time includes its start-up (two worker
processes, each checking its walls and digests before it joins), sending each batch's notebooks as a task
and its records back. The overhead per notebook is the difference of the two times over the notebooks.

The corpus is made from the course's own masters, without the tests' corpora: for each exercise the master,
its released stub, and the master with one solution cell left undone (released alone), each ``--copies``
times under other student names: about 16 notebooks per exercise with ``--copies 2``, like the exercise
corpora of ``tests/course/grader``. The machine is shared: the settings are interleaved, in turns of
alternating order, and the best of ``--repeat`` runs of each is kept.

Run: .venv/bin/python bench/bench_cluster.py [--copies 2] [--repeat 2] [--exercise 00_warmup]
"""

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

from _corpus import ROOT, write_corpus


def main():
    # imported here, not at the top: the embedded cluster's worker processes import this module again
    from particles.course.grading.driver import grade
    from particles.course.paths import exercise_names

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--copies", type=int, default=2, help="copies of each variant (default 2)")
    parser.add_argument("--repeat", type=int, default=2, help="runs of each setting, interleaved (default 2)")
    parser.add_argument("--exercise", action="append", help="only this exercise (repeatable; default all)")
    args = parser.parse_args()
    exercises = args.exercise or exercise_names(ROOT)
    settings = {"--jobs 2": {"jobs": 2}, "--scheduler local:2": {"scheduler": "local:2"}}
    with tempfile.TemporaryDirectory() as tmp:
        n = write_corpus(Path(tmp) / "subs", exercises, args.copies)
        print(f"{n} notebooks of {len(exercises)} exercise(s), best of {args.repeat} interleaved runs; load average "
              f"before: {os.getloadavg()[0]:.2f}", flush=True)
        best = {name: float("inf") for name in settings}
        for run in range(args.repeat):  # interleaved, every other run in the other order: load that rises or
            order = list(settings.items())  # falls during a run hits both settings alike
            for name, options in order if run % 2 == 0 else order[::-1]:
                start = time.perf_counter()
                summary = grade([Path(tmp) / "subs"], None, seed=1, time_limit=10.0, root=ROOT, **options)
                seconds = time.perf_counter() - start
                best[name] = min(best[name], seconds)
                assert len(summary["students"]) == n, "every notebook graded"
                print(f"  run {run + 1}, {name}: {seconds:.1f} s", flush=True)
    local, cluster = best["--jobs 2"], best["--scheduler local:2"]
    print(f"{'setting':<24}{'wall s':>10}{'per notebook':>14}")
    for name, seconds in best.items():
        print(f"{name:<24}{seconds:>10.1f}{seconds / n:>13.3f}s")
    overhead = cluster - local
    print(f"overhead of the cluster (start-up included): {overhead:.1f} s, {overhead / n:.3f} s per notebook, "
          f"{100 * overhead / local:.1f}% of the grading time")
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    print(json.dumps({"notebooks": n, "jobs2": round(local, 2), "local2": round(cluster, 2)}))


if __name__ == "__main__":
    main()
