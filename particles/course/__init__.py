"""The course machinery: release exercises from masters, grade submissions in isolated workers.

Modules, in the order the data flows:

* :mod:`~particles.course.release`: ``solutions/`` masters -> ``exercises/``, the student bundle;
* :mod:`~particles.course.code`: which statements of a notebook run (with
  :mod:`~particles.course.magics`: cells read as IPython reads them,
  :mod:`~particles.course.scopes`: which names a statement reads as globals,
  :mod:`~particles.course.selection`: the rule, and
  :mod:`~particles.course.ipython_shim`: ``get_ipython()`` in the worker);
* :mod:`~particles.course.forbidden`: which library names a submission's functions use;
* :mod:`~particles.course.protocol`: JSON plus NumPy arrays between processes, never pickle;
* :mod:`~particles.course.worker`: the process that runs a submission;
* :mod:`~particles.course.isolation`: its operating-system walls (namespaces, a uid of its own,
  Landlock, limits), with :mod:`~particles.course.kernel` (the system calls) and
  :mod:`~particles.course.integrity` (the library's checksum);
* :mod:`~particles.course.sandbox`: its Python-level walls (audit hook, tripwires, resource limits);
* :mod:`~particles.course.process`: the worker seen from the grader (start, deadline, kill);
* :mod:`~particles.course.runner`: the tests' handle on a submission (``student.call(...)``);
* :mod:`~particles.course.registry`: test problems passed to student code by name;
* :mod:`~particles.course.expect`: the checks tests use, with one-line reasons;
* :mod:`~particles.course.plugin`: the pytest plugin (points, hidden tests, seeds);
* :mod:`~particles.course.discovery`: which notebooks are graded, as which student and exercise;
* :mod:`~particles.course.signing`: the signed records of a pytest session;
* :mod:`~particles.course.grading`: the driver, ``particles grade``;
* :mod:`~particles.course.store`: the records on disk as they are made (``--resume``);
* :mod:`~particles.course.reports`: results.json, gradebook CSV, Markdown feedback;
* :mod:`~particles.course.gradescope`: the Gradescope autograder bundle;
* :mod:`~particles.course.check`: ``particles.check(...)`` from a student's notebook;
* :mod:`~particles.course.similarity`: ``particles similarity``, structurally equal solutions.
"""
