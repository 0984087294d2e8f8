"""The ``particles`` command line: one module per verb, its parser and its command together.

Modules:

* ``__main__.py``: ``python -m particles.cli``;
* ``common.py``: what several verbs share (the course folder option);
* ``tour.py``: ``particles tour``, the course tour;
* ``demo.py``: ``particles demo``, a particle-effect animation;
* ``study.py``: ``particles study``, a measured study's figure and table;
* ``warm.py``: ``particles warm``, the numba kernels compiled ahead of use;
* ``site.py``: ``particles site``, the lectures as a static course site;
* ``check.py``: ``particles check``, an exercise's public tests on a saved notebook;
* ``release.py``: ``particles release``, the exercises generated from their masters;
* ``grade.py``: ``particles grade``, the autograder;
* ``grade_worker.py``: ``particles grade-worker``, grading workers joining a Dask cluster;
* ``review.py``: ``particles review``, the written answers' pages and rubrics;
* ``new_exercise.py``: ``particles new-exercise``, a template master and test module;
* ``export.py``: ``particles export``, the grades and the feedback zips for Canvas and Moodle;
* ``record.py``: ``particles record``, the term's record: its runs, a student's history, a result retired;
* ``gradescope_bundle.py``: ``particles gradescope-bundle``, the Gradescope autograder zip;
* ``similarity.py``: ``particles similarity``, submitted functions equal to others.

Each verb module has ``register(commands)``, which adds its parser to the ``argparse`` sub-parsers
`commands` with the function that runs it; a verb imports what it runs only when it runs (``particles
--help`` loads no grader). A command returns the exit status: 0 done, 1 done with something to look at,
2 nothing done (a bad argument or input, said on stderr).
"""

import argparse
import sys

from . import (check, demo, export, grade, grade_worker, gradescope_bundle, new_exercise, record, release, review,
               similarity, site, study, tour, warm)

__all__ = ["main", "build_parser", "VERBS"]

VERBS = (tour, demo, study, warm, site, check, release, grade, grade_worker, review, new_exercise, export, record,
         gradescope_bundle, similarity)
"""The verbs' modules, in the order ``particles --help`` lists them."""


def build_parser():
    """The parser of the ``particles`` command: every verb of :data:`VERBS` registered."""
    parser = argparse.ArgumentParser(
        prog="particles",
        description="Particle systems and mass-spring simulation: the course package's tools.",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for verb in VERBS:
        verb.register(commands)
    return parser


def main(argv=None):
    """Entry point of the ``particles`` console script."""
    args = build_parser().parse_args(argv)
    return args.run(args)


if __name__ == "__main__":
    sys.exit(main())
