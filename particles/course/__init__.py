"""The course machinery: release exercises from masters, grade submissions in isolated workers.

Packages, in the order the data flows (each ``__init__`` docstring maps its modules):

* :mod:`~particles.course.release`: ``solutions/`` masters -> ``exercises/`` with one answer slot per
  question, the student bundle, new exercises, the course site;
* :mod:`~particles.course.reading`: which statements of a submitted notebook run, read as Jupyter
  reads them, and which library names they use;
* :mod:`~particles.course.worker`: the process that runs a submission, the protocol to it (plain data,
  never pickle) and the tests' handle on it (``student.call(...)``);
* :mod:`~particles.course.walls`: the walls around that process: the operating system's (namespaces,
  a uid of its own, Landlock, limits) and the Python-level ones (audit hook, tripwires);
* :mod:`~particles.course.grading`: ``particles grade`` (the driver), the pytest plugin, which
  notebooks are graded, the checks tests use and whose fault a failure is;
* :mod:`~particles.course.results`: typed records and their signatures, the reports (gradebook, feedback,
  Gradescope ``results.json``), the LMS files and the Gradescope bundle;
* :mod:`~particles.course.term`: the term's record (one SQLite database per output folder), the roster and
  every name matched to a student;
* :mod:`~particles.course.similarity`: ``particles similarity``, structurally equal solutions.

Modules at this level: :mod:`~particles.course.check` (``particles.check(...)`` from a student's
notebook) and :mod:`~particles.course.paths` (where the course's folders are).
"""
