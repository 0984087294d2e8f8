"""Similarity report on a synthetic class: 300 submissions of 02_stiffness (9 asked functions each).

The class is made by ``synthetic_class.py``'s ``write_synthetic``: about a
third of the functions are the master's with renamed variables, half are
mutated (one to three inserted statements, changed constants), a fifth are
rewritten from random statements, and ten students copy every function of
another (renamed, every other one with an extra line). The script times
``particles.course.similarity.compare.similarity`` (library parsed once, cached, as
in one CLI run), splits reading from comparing, counts the work of each
stage, checks that the planted copies are clustered, and compares with the
naive baseline: difflib on every pair of distinct structures, estimated from
a random sample of pairs.

Run: .venv/bin/python bench/bench_similarity.py [--n 300] [--repeat 2]
"""

import argparse
import difflib
import os
import random
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import best_time  # noqa: E402
from particles.course.similarity import compare as S  # noqa: E402
from synthetic_class import write_synthetic  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=300, help="number of submissions (default 300)")
    parser.add_argument("--repeat", type=int, default=2, help="timed runs, best kept (default 2)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "subs"
        planted = write_synthetic(folder, n=args.n, copies=min(10, args.n // 4))
        load = os.getloadavg()[0]
        t0 = time.perf_counter()
        S.library_functions()
        library = time.perf_counter() - t0
        reports = []
        wall = best_time(lambda: reports.append(S.similarity([folder], root=ROOT)), repeat=args.repeat, min_time=0)
        report = reports[-1]
    st = report.stats
    together = {(a.owner, b.owner) for c in report.clusters for a in c.members for b in c.members}
    found = sum((copier, source) in together for copier, source in planted)

    groups = {}
    for c in report.clusters:
        for m in c.members:
            groups.setdefault(m.structure, m.tokens)
    rng = random.Random(0)
    tokens = list(groups.values())
    sample = [(rng.choice(tokens), rng.choice(tokens)) for _ in range(2000)]
    t0 = time.perf_counter()
    for a, b in sample:
        difflib.SequenceMatcher(None, a, b, autojunk=False).ratio()
    per_pair = (time.perf_counter() - t0) / len(sample)
    all_pairs = st["structures"] * (st["structures"] - 1) / 2

    print(f"{args.n} submissions of 02_stiffness, best of {args.repeat} runs; load average before: {load:.2f}, "
          f"after: {os.getloadavg()[0]:.2f}")
    print(f"  {'stage':<44}{'count':>10}{'seconds':>10}")
    print(f"  {'library parsed and normalized (once)':<44}{report.references['library']:>10}{library:>10.2f}")
    print(f"  {'notebooks read, functions normalized':<44}{st['functions']:>10}{st['read_seconds']:>10.2f}")
    print(f"  {'distinct structures (dict buckets)':<44}{st['structures']:>10}")
    print(f"  {'candidate pairs (MinHash bands)':<44}{st['candidates']:>10}")
    print(f"  {'pairs scored by difflib':<44}{st['scored']:>10}")
    print(f"  {'similar links':<44}{st['links']:>10}")
    print(f"  {'clusters, reported pairs':<44}{len(report.clusters):>5}{len(report.pairs):>5}"
          f"{wall - st['read_seconds']:>10.2f}")
    print(f"  {'total similarity()':<44}{'':>10}{wall:>10.2f}")
    print(f"planted copies clustered with their source: {found} / {len(planted)}")
    print(f"naive baseline, difflib on all {all_pairs:.0f} pairs of distinct structures: "
          f"~{all_pairs * per_pair:.0f} s ({per_pair * 1e6:.0f} us a pair, from {len(sample)} random pairs)")


if __name__ == "__main__":
    main()
