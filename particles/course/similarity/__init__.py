"""``particles similarity``: submitted functions structurally equal to the library, a master or a classmate.

Modules:

* :mod:`~particles.course.similarity.compare`: the report: candidates, scores, the tables;
* :mod:`~particles.course.similarity.fingerprint`: normalized syntax trees of functions, hashed, and
  the score of two.
"""
