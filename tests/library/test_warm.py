"""particles.warm: the kernels compiled ahead of use, and its errors."""

import pytest

from particles.cli import main

from .backends.helpers import needs_numba


@needs_numba
def test_a_part_compiles_the_parallel_and_the_serial_copy_of_its_kernels():
    """After the "pairs" part, Lennard-Jones and N-body have machine code for both copies, in this process."""
    from particles.forces import kernels
    from particles.warm import warm

    lines = []
    seconds = warm(parts=["pairs"], report=lines.append)
    assert seconds > 0 and len(lines) == 1 and lines[0].startswith("pairs: ")
    for kernel in (kernels.lennard_jones_blocks, kernels.nbody_pulls):
        assert kernel.signatures and kernel.serial.signatures, kernel.py_func.__name__


@needs_numba
def test_the_cloth_collisions_part_runs_every_self_collision_kernel(monkeypatch):
    """The folded sheet of the "cloth collisions" part reaches the stages a sheet on a ball does not: the proximity
    iterations and the continuous test's searches over a few moving vertices, box against box (without them, a
    first run of bench_cloth_fold compiled these in its timed steps: a 5 s step)."""
    from particles.backends import using
    from particles.collisions import compiled_stages as cloth
    from particles.warm import _folded_sheet

    met = set()

    def pick(kernel, size):
        met.add(kernel.py_func.__name__)
        return kernel.serial

    monkeypatch.setattr(cloth, "pick", pick)
    with using("numba"):
        _folded_sheet()
    assert {"box_candidates", "subset_pairs", "kept_pairs", "proximity_rows", "proximity_impulses",
            "first_contact_pairs", "key_rows"} <= met


@needs_numba
def test_parts_in_other_processes_report_each_part_once():
    """With two jobs each part runs in a process of the pool and is reported once."""
    from particles.warm import warm

    lines = []
    warm(parts=["implicit", "pairs"], jobs=2, report=lines.append)
    assert sorted(line.split(":")[0] for line in lines) == ["implicit", "pairs"]


@needs_numba
@pytest.mark.parametrize("options, message", [
    (dict(parts=["springs"]), r"parts must be among \['explicit step'.*got \['springs'\]"),
    (dict(jobs=0), "jobs must be a positive integer, got 0"),
    (dict(jobs=1.5), "jobs must be a positive integer, got 1.5"),
])
def test_bad_options_are_named(options, message):
    """An unknown part or a number of jobs that is not a positive integer is a ValueError naming it."""
    from particles.warm import warm

    with pytest.raises(ValueError, match=message):
        warm(**options)


def test_cli_refuses_bad_jobs_with_status_2(capsys):
    """``particles warm --jobs 0`` prints the reason and exits with status 2, compiling nothing."""
    assert main(["warm", "--jobs", "0"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("particles warm: ") and ("jobs must be a positive integer" in err or "numba" in err)
