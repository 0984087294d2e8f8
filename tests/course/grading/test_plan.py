"""The plan of a run: batches of one exercise, large first, every notebook once; seeds drawn before any run."""

from pathlib import Path

import pytest

from particles.course.grading import plan
from particles.course.grading.discovery import Unit


@pytest.mark.parametrize("jobs", [1, 2, 4])
@pytest.mark.parametrize("sizes", [[15, 20, 17, 17, 14, 12], [17], [300], [1], [2, 1, 3], [21], [41, 3]])
def test_batches_cover_every_notebook_once_large_first_one_exercise_each(sizes, jobs):
    """Batches keep the notebooks' order, one exercise each, at most 20; none of one beside a larger one of its
    exercise; one exercise's batches never grow; and a run of many notebooks over several exercises takes
    fewer sessions than six per exercise (each session costs about 1 s to start)."""
    units = [Unit(f"s{e}_{k}", f"{e:02d}_topic", Path(f"s{e}_{k}.ipynb"))
             for e, n in enumerate(sizes) for k in range(n)]
    batches = plan.batches(units, jobs)
    assert [u for b in batches for u in b] == units
    assert all(0 < len(b) <= 20 and len({u.exercise for u in b}) == 1 for b in batches)
    for exercise in {u.exercise for u in units}:
        mine = [len(b) for b in batches if b[0].exercise == exercise]
        assert mine == [1] or 1 not in mine, mine
    if len(sizes) == 1:  # one exercise: sizes never grow, so the run ends on small batches
        assert all(a >= b for a, b in zip(map(len, batches), map(len, batches[1:])))
    if len(units) >= 60:
        assert len(batches) >= 2 * jobs
    if len(sizes) > 1 and len(units) >= 60:
        assert len(batches) < 6 * len(sizes)


def _units(n, exercise="00_warmup"):
    return [Unit(f"s{k}", exercise, Path(f"s{k}.ipynb")) for k in range(n)]


def test_seeds_are_drawn_when_the_run_is_planned():
    """Every notebook's seed is in its batch before anything runs: the given seed everywhere, else a new one each
    (so a batch run again, elsewhere, grades with the same hidden parameters)."""
    fixed = plan.plan_batches(_units(7), jobs=2, seed=42)
    assert [u for b in fixed for u in b.units] == _units(7) and {s for b in fixed for s in b.seeds} == {42}
    assert [b.number for b in fixed] == list(range(len(fixed)))
    drawn = plan.plan_batches(_units(40), jobs=2)
    seeds = [s for b in drawn for s in b.seeds]
    assert len(seeds) == 40 and len(set(seeds)) > 30 and all(0 <= s < 2**31 for s in seeds)


def test_a_batch_holds_one_exercise_with_a_seed_per_notebook_and_cuts_into_singles():
    """A batch refuses mixed exercises or a missing seed, naming the problem; singles keep number and seeds."""
    with pytest.raises(ValueError, match="one exercise"):
        plan.Batch(0, (*_units(1), *_units(1, "01_integrator_order")), (1, 2))
    with pytest.raises(ValueError, match="one seed per notebook, got 2 notebooks and 1 seeds"):
        plan.Batch(0, tuple(_units(2)), (1,))
    batch = plan.Batch(3, tuple(_units(3)), (5, 6, 7))
    assert batch.exercise == "00_warmup"
    assert [(b.number, b.units[0].student, b.seeds) for b in batch.singles()] == [(3, "s0", (5,)), (3, "s1", (6,)),
                                                                                   (3, "s2", (7,))]
