"""Grading: the driver, the pytest plugin and what the tests use to judge.

Modules:

* :mod:`~particles.course.grading.driver`: ``particles grade``: the grading run, its stages strung
  together;
* :mod:`~particles.course.grading.options`: the options of a run, one typed object checked once;
* :mod:`~particles.course.grading.plan`: the batches of a run and each notebook's seed;
* :mod:`~particles.course.grading.run`: where batches are graded (a runner: this machine's cores), a
  lost batch retried;
* :mod:`~particles.course.grading.cluster`: the runner on a Dask cluster (``--scheduler``): an embedded
  ``LocalCluster`` or a running scheduler, each result delivered once;
* :mod:`~particles.course.grading.cluster_worker`: a cluster's grading worker: its checks before it joins,
  and the task it grades;
* :mod:`~particles.course.grading.cluster_tasks`: a cluster's tasks and results as plain data, checked on
  both sides;
* :mod:`~particles.course.grading.session`: one pytest session grading a batch; its signed records
  read back;
* :mod:`~particles.course.grading.record`: each result decided, saved (a recorder: the records
  folder) and reported as it arrives;
* :mod:`~particles.course.grading.report`: the gradebook, feedback and Gradescope file at the end of
  a run;
* :mod:`~particles.course.grading.plugin`: the pytest plugin: points, hidden tests, seeds, records
  of a session;
* :mod:`~particles.course.grading.discovery`: which notebooks are graded, as which student and
  exercise; written answers;
* :mod:`~particles.course.grading.intake`: what is let in: notebooks checked within limits, zips
  opened safely;
* :mod:`~particles.course.grading.expect`: the checks tests use, each failing with a one-line
  reason;
* :mod:`~particles.course.grading.memo`: reference results the tests compute once per session, not
  once per notebook;
* :mod:`~particles.course.grading.blame`: whose fault a failure is: the judged function or a failing
  helper of it;
* :mod:`~particles.course.grading.figures`: figures in the feedback: the student's curve beside the
  reference's.
* :mod:`~particles.course.grading.deadlines`: the course file (``course.toml``): deadlines, the late
  policy, extensions (their names checked); the late penalty of a record;
* :mod:`~particles.course.grading.times`: when each notebook was submitted, never guessed;
* :mod:`~particles.course.grading.versions`: which version of the tests graded a record (a digest of
  the exercise's tests and the library).
"""
