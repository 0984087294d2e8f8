"""Release: what the course hands out, made from the instructors' masters.

Modules:

* :mod:`~particles.course.release.notebooks`: ``solutions/`` masters -> ``exercises/`` (solution
  blocks become stubs), the student bundle;
* :mod:`~particles.course.release.answers`: written answers: one slot per question, counted as a
  reader would count them;
* :mod:`~particles.course.release.newexercise`: ``particles new-exercise NN_topic``: a new exercise
  from a template that already passes;
* :mod:`~particles.course.release.site`: ``particles site``: the lectures executed and rendered as a
  static, offline site.
"""
