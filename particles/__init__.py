"""particles: a course package for particle systems and mass-spring simulation.

The reference library follows the lecture's animation loop, and has one
time loop, :meth:`ParticleSystem.run`: a state ``X`` of shape ``(n, 2, d)``
(positions and velocities), forces that add into a force array, and ODE
steppers ``step(f, X, t, h)`` or solver objects ``solver.step(X, t, h)``.
One package per area of the lecture, each ``__init__`` docstring its map:

* :mod:`particles.integrators`: steppers, solver forms, the time loop;
* :mod:`particles.forces`: gravity, damping, fields, springs and bending, pair forces, N-body, Lennard-Jones;
* :mod:`particles.massspring`: strings, hair and cloth builders, and their compiled step;
* :mod:`particles.implicit`: implicit solvers of stiff springs (Baraff-Witkin, prefactored), statics;
* :mod:`particles.constraints`: Provot's strain limit, rigid rods;
* :mod:`particles.xpbd`: position-based dynamics;
* :mod:`particles.collisions`: surfaces, the particle collider, cloth meshes and their collisions;
* :mod:`particles.effects`: emitters, particle effects, colours, flocks;
* :mod:`particles.md`: molecular dynamics in a periodic box;
* :mod:`particles.explore`: explorations of a parameter with a slider;
* :mod:`particles.backends`: the switch between the NumPy reference and the compiled kernels (each package keeps
  its own ``kernels.py``); :mod:`particles.demos`, :mod:`particles.studies`: demos and studies;
* :mod:`particles.course`: release and grading of the exercises.

The root keeps what every area shares: :mod:`particles.system` (:class:`ParticleSystem`, births and deaths
in :mod:`particles.population`), :mod:`particles.neighbors` (bucket grid), :mod:`particles.problems`,
:mod:`particles.errors`, the command line (:mod:`particles.cli`, :mod:`particles.tour`, :mod:`particles.warm`)
and drawing (:mod:`particles.render`, imported on demand because it loads
Matplotlib's pyplot). ``CONTRIBUTING.md`` says where to make a change and describes the data flow of a step.

>>> import particles
>>> from particles.forces import Gravity, Damping
>>> ps = particles.ParticleSystem([[0.0, 0.0]], v=[[1.0, 1.0]], forces=[Gravity([0, -9.81])])
>>> t, X = ps.run(0.5, h=0.01, method="verlet")
"""

from . import collisions, constraints, effects, forces, implicit, integrators, massspring, md, neighbors, xpbd
from .collisions import ClothCollisions, Collider
from .effects import Flock, ParticleEffect
from .errors import ConvergenceError, SimulationDiverged
from .integrators import INTEGRATORS, integrate
from .system import ParticleSystem


def check(exercise, notebook=None, *, time_limit=None, root=None):
    """Run the public tests of an exercise on your code and show what to fix.

    Put ``particles.check("03_provot")`` in the last cell of an exercise
    notebook and run it after your own cells. The public tests are the
    autograder's tests with fixed, readable inputs; the autograder adds hidden
    tests with random inputs, so a pass here is necessary, not sufficient.

    What is checked: by default the code you ran in this kernel, in the order
    you ran it (you need not save). With ``notebook="03_provot.ipynb"``, the
    saved file, which is exactly what you hand in. Your code runs in a
    separate process under the autograder's rules: using a library function
    that the exercise asks you to write raises ``PermissionError`` (the cells
    the course gives you may use it), and a call that takes longer than
    `time_limit` seconds is stopped.

    What you see: one line per test, PASS or FAIL with what to fix; the
    functions still raising ``NotImplementedError`` ("Not implemented yet:");
    your written answers counted in the saved notebook ("Written answers: 1 of
    3 filled in; not written yet: questions 2, 3"; save to update; they are
    graded by your instructor); tests marked as stretch goals, which score
    nothing. If the tests cannot run at all (pytest missing), you get an
    error that says how to fix it, never a pass.

    Parameters
    ----------
    exercise : str
        The notebook's name without ``.ipynb``, e.g. ``"00_warmup"``.
    notebook : str or path, optional
        Check this saved notebook instead of the code run in this kernel
        (required outside Jupyter).
    time_limit : float, optional
        Seconds each call of your functions may take (default: the exercise's).
    root : str or path, optional
        The course folder (default: found from the current folder).

    Returns
    -------
    CheckResult
        Shown as a table in the notebook; ``.passed``, ``.score``,
        ``.max_score``, ``.unwritten`` (functions not implemented yet),
        ``.written_answers``.

    Raises
    ------
    ValueError
        An unknown exercise, or no notebook outside Jupyter.
    particles.course.check.CheckError
        The tests could not run; the message says what to do.
    """
    from .course.check import check as _check

    return _check(exercise, notebook, time_limit=time_limit, root=root)


__version__ = "0.1.0"

__all__ = [
    "ParticleSystem",
    "INTEGRATORS",
    "integrate",
    "SimulationDiverged",
    "ConvergenceError",
    "Collider",
    "ClothCollisions",
    "ParticleEffect",
    "Flock",
    "check",
    "collisions",
    "constraints",
    "effects",
    "forces",
    "implicit",
    "integrators",
    "massspring",
    "md",
    "neighbors",
    "springs",
    "xpbd",
]
