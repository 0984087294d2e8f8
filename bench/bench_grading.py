"""Grading throughput: 50 submissions with --jobs 1 and with --jobs 2, and the cost of the OS walls.

Submissions of one exercise are graded in batches: one pytest process per
batch (its start-up and the reference library are paid once per batch), and
one worker process per submission inside it. ``grade`` splits the notebooks
into batches of one exercise, at most 20, each about a ``2 * jobs``-th of the
notebooks not yet batched (guided self-scheduling: large batches first, small
ones at the end), so the batches are independent and two jobs on a 2-core
machine should approach a 2x speed-up. The 50 notebooks are made from the
course's master (``_corpus.py``): the master, its stub and the master with one
solution cell left undone, in turn (no timeouts, which would measure sleeping
rather than grading).

The machine is shared: the script interleaves the settings, keeps the best
of each, and prints the CPU time of the graders so that a low speed-up caused
by load elsewhere can be told from one caused by the grader. The first run of
a machine also fills the grader's private bytecode cache (the sessions'
``PYTHONPYCACHEPREFIX``): use ``--repeat 2`` or more.

The third setting grades with the Python-level walls alone (no namespaces, no
uid of its own, no Landlock: the grader as it was before the operating
system's layers), the baseline of the per-submission cost.

With ``--corpora``, it grades instead each exercise's corpus of ``_corpus.py``
(the master, the stub and each solution cell left undone, twice under other
names: about 16 notebooks each, ``--jobs 2``), with the output folder
(feedback files, their figures drawn by the driver) and without it, and
prints the seconds per notebook of each exercise and what the outputs add.

Run: .venv/bin/python bench/bench_grading.py [--n 50] [--repeat 2] [--corpora]
"""

import argparse
import itertools
import os
import resource
import tempfile
import time
from pathlib import Path

from _corpus import ROOT, variants, write_corpus
from particles.course.walls import isolation
from particles.course.grading.driver import grade

WARMUP = "00_warmup"


def make_submissions(folder, n):
    """`n` notebooks of 00_warmup as folder/studentNNN_00_warmup.ipynb: the master, the stub and each undone cell
    in turn."""
    import nbformat  # noqa: PLC0415

    for k, notebook in zip(range(n), itertools.cycle(variants(WARMUP).values())):
        nbformat.write(notebook, folder / f"student{k:03d}_{WARMUP}.ipynb")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=50, help="number of submissions (default 50)")
    parser.add_argument("--repeat", type=int, default=2, help="runs of each setting, interleaved (default 2)")
    parser.add_argument("--corpora", action="store_true",
                        help="grade each exercise's corpus instead, with and without the feedback files")
    args = parser.parse_args()
    if args.corpora:
        return corpora(args.repeat)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "subs"
        folder.mkdir()
        make_submissions(folder, args.n)
        walls = isolation.plan("auto")
        baseline = isolation.Plan.from_option("no-namespaces,no-uid,no-landlock")
        settings = {"OS walls, --jobs 1": (1, walls), "OS walls, --jobs 2": (2, walls),
                    "Python walls only, --jobs 1": (1, baseline)}
        wall, cpu = {name: [] for name in settings}, {name: [] for name in settings}
        layers = {}
        load = os.getloadavg()[0]
        for run in range(args.repeat):  # interleaved, so that a burst of load elsewhere hits every setting
            for name, (jobs, plan) in settings.items():
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                start = time.perf_counter()
                summary = grade([folder], Path(tmp) / f"out{len(wall[name])}-{jobs}-{run}-{plan.namespaces}",
                                jobs=jobs, seed=1, time_limit=2.0, root=ROOT, isolation=plan)
                wall[name].append(time.perf_counter() - start)
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
                cpu[name].append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
                assert len(summary["students"]) == args.n
                layers.setdefault(name, summary_layers(summary))
        print(f"{args.n} submissions of 00_warmup, best of {args.repeat} runs; load average before: {load:.2f}, "
              f"after: {os.getloadavg()[0]:.2f}")
        print(f"OS walls: {isolation.describe(layers['OS walls, --jobs 1'])}")
        print("(CPU s counts the pytest sessions and the workers they waited for; a worker inside"
              " bubblewrap is reaped in its PID namespace, so its CPU time is not in the count)")
        print(f"{'setting':<30}{'wall s':>10}{'per submission':>16}{'CPU s':>10}")
        for name in settings:
            best = min(wall[name])
            print(f"{name:<30}{best:>10.1f}{best / args.n:>15.2f}s{min(cpu[name]):>10.1f}")
        one, two, python = (min(wall[name]) for name in settings)
        print(f"speed-up of --jobs 2 over --jobs 1: x{one / two:.2f}")
        print(f"per-submission cost of the OS walls over the Python walls alone: x{one / python:.2f}")


def corpora(repeat):
    """Seconds per notebook of each exercise's corpus, --jobs 2, with the output folder and without."""
    from particles.course.grading import figures  # noqa: PLC0415  (its cache of drawn figures, cleared per run)
    from particles.course.paths import exercise_names  # noqa: PLC0415

    settings = ("with feedback files", "verdicts only")
    print(f"each exercise's corpus, --jobs 2, best of {repeat} interleaved runs; load average before: "
          f"{os.getloadavg()[0]:.2f}")
    print(f"{'exercise':<22}{'notebooks':>10}" + "".join(f"{name + ', s':>24}" for name in settings)
          + f"{'per notebook':>14}{'outputs add':>13}")
    with tempfile.TemporaryDirectory() as tmp:
        for exercise in exercise_names(ROOT):  # a loop over the exercises
            folder = Path(tmp) / exercise
            n = write_corpus(folder, [exercise], copies=2)
            best = {name: float("inf") for name in settings}
            for run in range(repeat):  # interleaved, so that a burst of load elsewhere hits both settings
                for name in settings:
                    out = Path(tmp) / f"out-{exercise}-{run}" if name == settings[0] else None
                    figures.clear_cache()  # the figures of an earlier run (same seed, same figures) are drawn again
                    start = time.perf_counter()
                    summary = grade([folder], out, jobs=2, seed=1, time_limit=10.0, root=ROOT)
                    best[name] = min(best[name], time.perf_counter() - start)
                    assert len(summary["students"]) == n
            full, verdicts = (best[name] for name in settings)
            print(f"{exercise:<22}{n:>10}{full:>24.1f}{verdicts:>24.1f}{full / n:>13.2f}s"
                  f"{100 * (full / verdicts - 1):>12.0f}%")
    print(f"load average after: {os.getloadavg()[0]:.2f}")


def summary_layers(summary):
    """The walls of the first graded notebook of a run."""
    for results in summary["students"].values():
        return results[0].get("isolation", {})
    return {}


if __name__ == "__main__":
    main()
