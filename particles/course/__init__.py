"""The course machinery: release exercises from masters, grade submissions in isolated workers.

Modules, in the order the data flows:

* :mod:`~particles.course.release`: ``solutions/`` masters -> ``exercises/``, the student bundle;
* :mod:`~particles.course.code`: which statements of a notebook run;
* :mod:`~particles.course.forbidden`: which library names a submission's functions use;
* :mod:`~particles.course.protocol`: JSON plus NumPy arrays between processes, never pickle;
* :mod:`~particles.course.worker`: the process that runs a submission;
* :mod:`~particles.course.sandbox`: its walls (audit hook, tripwires, resource limits);
* :mod:`~particles.course.process`: the worker seen from the grader (start, deadline, kill);
* :mod:`~particles.course.runner`: the tests' handle on a submission (``student.call(...)``);
* :mod:`~particles.course.registry`: test problems passed to student code by name;
* :mod:`~particles.course.expect`: the checks tests use, with one-line reasons;
* :mod:`~particles.course.plugin`: the pytest plugin (points, hidden tests, seeds);
* :mod:`~particles.course.grading`: the driver, ``particles grade``;
* :mod:`~particles.course.reports`: results.json, gradebook CSV, Markdown feedback;
* :mod:`~particles.course.gradescope`: the Gradescope autograder bundle;
* :mod:`~particles.course.check`: ``particles.check(...)`` from a student's notebook.
"""
