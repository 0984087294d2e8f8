"""The plan of a grading run: the notebooks to grade, cut into batches, each notebook's seed drawn.

A batch is one pytest session (:mod:`particles.course.grading.session`), of one exercise. Seeds are
drawn here, before any batch is run: a batch run twice (a lost one retried, on another machine) grades
its notebooks with the same hidden parameters.
"""

import itertools
import math
import secrets
from dataclasses import dataclass

__all__ = ["Batch", "batches", "plan_batches"]


@dataclass(frozen=True)
class Batch:
    """Notebooks of one exercise graded in one session, with their seeds.

    Parameters
    ----------
    number : int
        The batch's place in the run (its log is ``logs/batch<number>-<exercise>.log``).
    units : tuple of Unit
        The notebooks (:class:`~particles.course.grading.discovery.Unit`), all of one exercise.
    seeds : tuple of int
        One per unit.
    """

    number: int
    units: tuple
    seeds: tuple

    def __post_init__(self):
        if not self.units or len(self.units) != len(self.seeds):
            raise ValueError(f"a batch needs one seed per notebook, got {len(self.units)} notebooks "
                             f"and {len(self.seeds)} seeds")
        if len({u.exercise for u in self.units}) != 1:
            raise ValueError("a batch must hold notebooks of one exercise")

    @property
    def exercise(self):
        """The exercise of every notebook of the batch."""
        return self.units[0].exercise

    def singles(self):
        """The batch cut into batches of one notebook each (same number, same seeds)."""
        return [Batch(self.number, (unit,), (seed,)) for unit, seed in zip(self.units, self.seeds)]


def batches(units, jobs, largest=20):
    """Split units into batches of one exercise for `jobs` processes: large first, smaller towards the end.

    Each batch is one pytest session, whose start-up (about 1 s of CPU) and reference results are paid
    once, so a batch should be large; but the last batches decide when the run ends, so they should be
    small. Guided self-scheduling does both: each batch takes about a ``2 * jobs``-th of the notebooks not
    yet batched (at most `largest`, never across exercises). A corpus of 95 notebooks over six exercises
    on two jobs makes 14 batches instead of 36 (six per exercise); one exercise of 17 makes 6 (5, 3, 3, 2, 2, 2).

    Returns
    -------
    list of list of Unit
        The units, in their order, cut into batches.
    """
    by_exercise = {}
    for unit in units:
        by_exercise.setdefault(unit.exercise, []).append(unit)
    out, left = [], len(units)
    for group in by_exercise.values():
        sizes, rest = [], len(group)
        while rest:
            size = min(largest, rest, max(2, math.ceil(left / (2 * max(jobs, 1)))))
            if rest - size == 1:  # no batch of one left behind: take it too, or leave two
                size = rest if rest <= largest else size - 1
            sizes.append(size)
            rest, left = rest - size, left - size
        starts = list(itertools.accumulate(sorted(sizes, reverse=True), initial=0))  # a tail that grew goes first
        out += [group[a:b] for a, b in zip(starts[:-1], starts[1:])]
    return out


def plan_batches(units, jobs, seed=None):
    """The batches of a run, each notebook's seed drawn now.

    Parameters
    ----------
    units : list of Unit
        The notebooks to grade (none rejected).
    jobs : int
        Sessions run at the same time.
    seed : int, optional
        The seed of every notebook (default: a new random one each).

    Returns
    -------
    list of Batch
    """
    planned = []
    for number, group in enumerate(batches(units, jobs)):
        seeds = tuple(seed if seed is not None else secrets.randbelow(2**31) for _ in group)
        planned.append(Batch(number, tuple(group), seeds))
    return planned
