"""Reading a submitted notebook: which of its statements run in the grader, and what they use.

Modules:

* :mod:`~particles.course.reading.submission`: a notebook's cells -> the statements that run
  (:class:`SubmissionCode`);
* :mod:`~particles.course.reading.magics`: a cell as the Python that Jupyter runs (IPython's
  transformer);
* :mod:`~particles.course.reading.scopes`: where the names of a statement resolve (a function's
  local or the notebook's global);
* :mod:`~particles.course.reading.selection`: the rule: which top-level statements run, by what they
  define and read;
* :mod:`~particles.course.reading.provided`: the code cells the course provides in an exercise (a
  submission that keeps one unchanged is not blamed for it);
* :mod:`~particles.course.reading.forbidden`: which library names a submission's functions use;
* :mod:`~particles.course.reading.ipython_shim`: ``get_ipython()`` in the worker, for the magics.
"""
