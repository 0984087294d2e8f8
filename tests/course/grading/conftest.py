"""Fixtures of the cluster tests (test_cluster.py, test_cluster_worker.py): a small corpus, and its records graded
on this machine's pool, which every cluster run must give."""

import pytest

from .helpers import ROOT, SEED, write_corpus


@pytest.fixture(scope="module")
def subs(tmp_path_factory):
    """Four notebooks of 00_warmup (:func:`helpers.write_corpus`)."""
    return write_corpus(tmp_path_factory.mktemp("cluster") / "subs")


@pytest.fixture(scope="module")
def local_run(subs, tmp_path_factory):
    """The corpus graded on this machine's pool, --jobs 2: the records and gradebook a cluster run must give."""
    from particles.course.grading.driver import grade

    out = tmp_path_factory.mktemp("local") / "out"
    grade([subs], out, jobs=2, seed=SEED, root=ROOT)
    return out
