"""Results: the records of a run and everything made from them.

Modules:

* :mod:`~particles.course.results.records`: typed records: one per test, per session, per
  submission;
* :mod:`~particles.course.results.signing`: signed session records: the driver knows they are the
  session's own;
* :mod:`~particles.course.results.reports`: Gradescope ``results.json``, the gradebook CSV, Markdown
  and HTML feedback, and all of them written into a grading run's folder (``write_outputs``);
* :mod:`~particles.course.results.gradescope`: ``particles gradescope-bundle``: the autograder zip
  Gradescope runs (written questions listed for its manual grading);
* :mod:`~particles.course.results.review`: ``particles review``: one page per written question with every
  student's answer side by side, and the rubric to fill in;
* :mod:`~particles.course.results.markup`: students' Markdown as safe HTML (no markup of theirs survives);
* :mod:`~particles.course.results.shown`: what students read of a record: no folder of the instructor's;
* :mod:`~particles.course.results.rubric`: rubrics (CSV) of the written answers, checked and merged into
  the records (``particles grade --rubric``);
* :mod:`~particles.course.results.lms`: ``particles export``: the grades as Canvas's and Moodle's
  gradebook import CSVs, students matched through a roster;
* :mod:`~particles.course.results.returned`: ``particles export --canvas-feedback/--moodle-feedback``: the
  feedback zips Canvas and Moodle read back as each student's feedback files;
* :mod:`~particles.course.results.importers`: how Canvas's and Moodle's importers read a file (PHP's
  ``fgetcsv`` escapes, identifiers PHP calls empty, Canvas's number converter and matching order).
"""
