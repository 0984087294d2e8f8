"""The term's record: who is in the course, what each run graded, and every grade and why.

Modules:

* :mod:`~particles.course.term.identity`: every name matched to a student in one place (names, aliases,
  identifiers);
* :mod:`~particles.course.term.roster`: the roster file: the course's students, their LMS identifiers and
  aliases;
* :mod:`~particles.course.term.database`: the course record, one SQLite database per output folder
  (students, runs, submissions, results and their history, written grades, extensions, overrides);
* :mod:`~particles.course.term.recorder`: the course record as the record stage of a grading run;
* :mod:`~particles.course.term.legacy`: a ``records/`` folder of an older grader, imported once.
"""
