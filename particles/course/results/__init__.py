"""Results: the records of a run and everything made from them.

Modules:

* :mod:`~particles.course.results.records`: typed records: one per test, per session, per
  submission;
* :mod:`~particles.course.results.store`: the records on disk as they are made (``--resume``);
* :mod:`~particles.course.results.signing`: signed session records: the driver knows they are the
  session's own;
* :mod:`~particles.course.results.reports`: Gradescope ``results.json``, the gradebook CSV, Markdown
  and HTML feedback;
* :mod:`~particles.course.results.gradescope`: ``particles gradescope-bundle``: the autograder zip
  Gradescope runs.
* :mod:`~particles.course.results.lms`: ``particles export``: the grades as Canvas's and Moodle's
  gradebook import CSVs, students matched through a roster.
"""
