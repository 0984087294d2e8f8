"""The walls around a worker: the operating system's first, the Python-level ones second.

Modules:

* :mod:`~particles.course.walls.isolation`: the operating system's walls: namespaces (bubblewrap), a
  uid of its own, Landlock, limits; which layers a machine allows;
* :mod:`~particles.course.walls.syscalls`: the Linux system calls behind them (Landlock, prctl,
  uids, capabilities, orphans);
* :mod:`~particles.course.walls.audit`: the Python-level walls: the audit hook, the tripwires on
  forbidden names, resource limits;
* :mod:`~particles.course.walls.integrity`: the library's checksum, before and after a run;
* :mod:`~particles.course.walls.limits`: a worker's limits with their defaults and units, checked in
  one place.
"""
