"""The worker: the process that runs a submission, and the grader's handle on it.

Modules:

* :mod:`~particles.course.worker.main`: the worker process itself (``python -c BOOTSTRAP``): loads
  the code, answers calls;
* :mod:`~particles.course.worker.process`: the worker seen from the grader: start it, its deadline,
  kill it;
* :mod:`~particles.course.worker.protocol`: JSON plus NumPy arrays between the processes, never
  pickle;
* :mod:`~particles.course.worker.runner`: the tests' handle on a submission (``student.call(...)``),
  failures as one-line reasons;
* :mod:`~particles.course.worker.registry`: test problems and functions passed to student code by
  name; counted ones evaluated (and counted) by the grader;
* :mod:`~particles.course.worker.codeprints`: fingerprints of compiled code, to recognise the library's
  forbidden functions however a submission ran them;
* :mod:`~particles.course.worker.codewatch`: in the worker, the code a call could run besides the
  notebook's own (what it reaches, what starts running during it).
"""
