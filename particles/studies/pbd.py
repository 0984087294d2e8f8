"""Constraints instead of springs, measured: PBD and XPBD on the cloths of lecture 7.

* :func:`stiffness_study`: the *effective stiffness* of a constrained
  curtain (lecture 7's curtain: 12 x 12 particles, 1 m, structural springs
  ``k``, shear ``k / 4``, flexion ``k / 10``, here hung by its whole top edge so
  that it stays in its plane and comes to rest quickly): the structural
  stiffness of the spring curtain that sags as much at rest. It is read from
  a table of relaxed spring curtains (:func:`spring_sags`), and the
  constrained curtain's sag from a run that starts at the spring curtain's
  equilibrium and is helped to settle (:func:`settled_sag`). XPBD
  with compliance ``1 / k`` keeps ``k`` whatever the iterations and the step;
  PBD, with the stiffness that matches ``k`` for one particle at one setting,
  does not.
* :func:`swing`: lecture 7's stiff cloth (10 x 10, 5000 N/m) released
  horizontally for 1 s, with any stepper: energy, kinetic energy, largest
  strain, wall time. :func:`small_steps_study` splits a fixed budget of sweeps
  per frame into substeps and iterations (Macklin et al. 2019).
"""

import time

import numpy as np

from .._checks import count, positive_number
from ..implicit.statics import relax
from ..massspring.cloth import cloth
from ..xpbd.solver import PBD, XPBD

__all__ = ["curtain", "spring_sags", "effective_stiffness", "settled_sag", "pbd_stiffness", "stiffness_study",
           "stiff_cloth", "swing", "small_steps_study", "SAG_TABLE"]

SAG_TABLE = 30.0 * 2.0 ** np.arange(-3, 7)
"""Structural stiffnesses (N/m) of the spring curtains whose sags :func:`effective_stiffness` interpolates."""

SETTLE = 0.2
"""Share of the velocity removed every 1/60 s while a curtain settles (changes nothing at rest)."""


def curtain(k=30.0, n=12, plane="vertical", pins="top corners"):
    """Lecture 7's curtain: n x n particles, 1 m square, two pinned top corners, shear k/4, flexion k/10.

    Parameters
    ----------
    k : float
        Structural stiffness, in N/m (> 0).
    n : int
        Particles per side (>= 3).
    plane : {"vertical", "horizontal"}
        Hanging flat (the stiffness study) or released from the horizontal
        (the slide's curtain).
    pins : str
        Pinned points (see :func:`particles.massspring.cloth`): the two top
        corners, or the whole ``"top edge"`` (the stiffness study).

    Returns
    -------
    MassSpringSystem
        Naive scaling: every particle 4.08 g (0.2 kg/m^2 at 8 x 8), gravity, no damping.
    """
    k = positive_number(k, "k", "N/m")
    return cloth(count(n, "n", 3), n, plane=plane, pins=pins, k_structural=k, k_shear=k / 4, k_flexion=k / 10)


def _sag(system, X=None):
    """Depth of the lowest particle below the pins, in metres."""
    x = system.X[:, 0] if X is None else X[:, 0]
    return float(system.X[system.pinned, 0, 2].max() - x[:, 2].min())


def spring_sags(ks=SAG_TABLE, n=12, pins="top edge"):
    """Static sags of spring curtains of several stiffnesses (relaxed with :func:`particles.implicit.relax`).

    Parameters
    ----------
    ks : array_like, shape (K,)
        Structural stiffnesses, in N/m, increasing.
    n : int
        Particles per side.
    pins : str
        As for :func:`curtain`.

    Returns
    -------
    ks, sags : ndarray, shape (K,)
        The stiffnesses and the depth (m) of the lowest particle below the pins.
    """
    ks = np.asarray(ks, dtype=float)
    if ks.ndim != 1 or len(ks) < 2 or np.any(np.diff(ks) <= 0) or ks[0] <= 0:
        raise ValueError(f"ks must be at least two increasing stiffnesses > 0 (N/m), got {ks!r}")
    sags = []
    for k in ks:  # a loop over the few stiffnesses of the table
        c = curtain(k, n, pins=pins)
        relax(c, h=0.2)
        sags.append(_sag(c))
    return ks, np.array(sags)


def effective_stiffness(sag, table):
    """The structural stiffness of the spring curtain with this sag, by log-log interpolation in `table`.

    Parameters
    ----------
    sag : float
        Measured sag, in metres.
    table : (ndarray, ndarray)
        ``(ks, sags)`` from :func:`spring_sags`.

    Returns
    -------
    float
        The stiffness, in N/m.

    Raises
    ------
    ValueError
        When the sag lies outside the table (the curtain is softer or stiffer
        than every spring curtain in it).
    """
    ks, sags = table
    if not sags[-1] <= sag <= sags[0]:
        stiffer = sag < sags[-1]
        raise ValueError(f"sag {sag:.6g} m lies outside the table ({sags[-1]:.6g} to {sags[0]:.6g} m): the "
                         f"curtain is {'stiffer' if stiffer else 'softer'} than {ks[-1 if stiffer else 0]:g} N/m")
    return float(np.exp(np.interp(-np.log(sag), -np.log(sags), np.log(ks))))


def settled_sag(solver, start, h=1 / 60, T=2.0, tol=1e-4):
    """Sag of a curtain run by `solver` from the state `start` until it rests.

    Every 1/60 s of simulated time the velocities lose :data:`SETTLE` of
    themselves, so that the curtain comes to rest quickly; at rest (the fixed
    point of the solver's step) that changes nothing. The run stops when no
    particle moves faster than `tol`, or after `T`.

    Parameters
    ----------
    solver : callable
        A stepper bound to a curtain (e.g. ``XPBD.from_system(curtain())``).
    start : MassSpringSystem
        The curtain whose state the run starts from (not modified).
    h : float
        Time step, in seconds.
    T : float
        Longest simulated time, in seconds.
    tol : float
        Speed (m/s) below which the curtain counts as at rest.

    Returns
    -------
    float
        The depth of the lowest particle below the pins, in metres.
    """
    h = positive_number(h, "h", "seconds")
    X = start.state()
    keep = (1.0 - SETTLE) ** (60.0 * h)
    for _ in range(max(1, round(positive_number(T, "T", "seconds") / h))):  # a loop over time steps
        X = solver(None, X, 0.0, h)
        X[:, 1] *= keep
        if np.abs(X[:, 1]).max() < tol:
            break
    return _sag(start, X)


def pbd_stiffness(k, m, hs):
    """PBD stiffness that gives one particle of mass `m` on a spring `k` the same sag at one iteration.

    One PBD iteration per substep ``hs`` leaves a hanging particle at the
    stretch ``e`` where ``e = (1 - s)(e + g hs^2)``, i.e. an effective stiffness
    ``(m / hs^2) s / (1 - s)``; equal to `k` for ``s = k hs^2 / (m + k hs^2)``.

    Parameters
    ----------
    k : float or ndarray
        Spring stiffness, N/m.
    m : float
        Particle mass, kg.
    hs : float
        Substep, s.

    Returns
    -------
    float or ndarray
        The stiffness in [0, 1).
    """
    return k * hs**2 / (m + k * hs**2)


def _pbd(c, k, hs, **options):
    """A PBD solver for curtain c whose stiffness matches springs k, k/4, k/10 at one iteration of hs.

    ``corrected=True`` among the options scales it for the iteration count (:class:`~particles.xpbd.PBD`).
    """
    solver = PBD.from_system(c, **options)
    for s in solver.constraints:  # a loop over the three spring kinds
        s.stiffness[:] = pbd_stiffness({"structural": k, "shear": k / 4, "flexion": k / 10}[s.kind], c.m[0], hs)
    return PBD(solver.constraints, c.m, c.pinned, forces=solver.forces, **options)


def stiffness_study(iterations=(1, 10, 50), steps=(1 / 30, 1 / 60, 1 / 120, 1 / 240), substeps=5, k=30.0,
                    h=1 / 60, n=12, corrected=False):
    """Effective stiffness of the constrained curtain against iterations and against the time step.

    Parameters
    ----------
    iterations : sequence of int
        Iteration counts, at the step `h` with `substeps`.
    steps : sequence of float
        Time steps (s), at one iteration and `substeps`.
    substeps : int
        Substeps per step.
    k : float
        The springs the constraints stand for (N/m): XPBD's compliance is
        ``1 / k`` (``4 / k``, ``10 / k``); PBD's stiffness matches `k` for one
        particle at one iteration of ``h / substeps``.
    h : float
        Time step of the iteration sweep, in seconds.
    n : int
        Particles per side.
    corrected : bool
        Also sweep the iterations with PBD's iteration-corrected stiffness
        (``"pbd_corrected"`` in ``"by_iterations"``, Müller et al.'s section 3.3).

    Returns
    -------
    dict
        ``"k"``, ``"iterations"``, ``"steps"``, ``"substeps"``, ``"h"``;
        ``"by_iterations"`` and ``"by_step"``: dicts ``"xpbd"``/``"pbd"`` ->
        effective stiffnesses (N/m), one per entry (and ``"pbd_corrected"`` in
        ``"by_iterations"`` with `corrected`); ``"spring_sag"``: the springs'
        sag (m); ``"table"``: ``(ks, sags)``.
    """
    k = positive_number(k, "k", "N/m")
    substeps = count(substeps, "substeps", 1)
    h = positive_number(h, "h", "seconds")
    table = spring_sags(k * SAG_TABLE / 30.0, n)
    start = curtain(k, n, pins="top edge")
    relax(start, h=0.2)
    out = {"k": k, "iterations": list(iterations), "steps": list(steps), "substeps": substeps, "h": h,
           "table": table, "spring_sag": _sag(start), "by_iterations": {}, "by_step": {}}
    for name in ("xpbd", "pbd"):
        def make(it, step, c=curtain(k, n, pins="top edge")):
            options = dict(substeps=substeps, iterations=it)
            return XPBD.from_system(c, **options) if name == "xpbd" else _pbd(c, k, h / substeps, **options)
        out["by_iterations"][name] = [effective_stiffness(settled_sag(make(count(i, "iterations", 1), h), start, h),
                                                          table) for i in iterations]
        out["by_step"][name] = [effective_stiffness(settled_sag(make(1, s), start, s), table) for s in steps]
    if corrected:
        c = curtain(k, n, pins="top edge")
        solvers = [_pbd(c, k, h / substeps, substeps=substeps, iterations=count(i, "iterations", 1), corrected=True)
                   for i in iterations]
        out["by_iterations"]["pbd_corrected"] = [effective_stiffness(settled_sag(s, start, h), table) for s in solvers]
    return out


def stiff_cloth(n=10, k=5000.0, plane="horizontal"):
    """Lecture 7's stiff cloth: n x n, 1 m, top corners pinned, springs k, k/4, k/10 (N/m), no damping."""
    return curtain(k, n, plane)


def swing(make_method, h, T=1.0, system=None, every=None):
    """Run the stiff cloth released horizontally (or `system`) and measure energy, strain and wall time.

    Parameters
    ----------
    make_method : callable
        ``make_method(system) -> stepper`` (a name of a stepper, a solver...).
    h : float
        Time step, in seconds.
    T : float
        Simulated time, in seconds.
    system : MassSpringSystem, optional
        Default :func:`stiff_cloth`.
    every : int, optional
        Record every `every` steps (default: about 60 records per second).

    Returns
    -------
    dict
        ``"t"`` (s), ``"E"`` (kinetic + spring + gravity energy, J), ``"K"``
        (kinetic energy, J), ``"strain"`` (largest structural strain of each
        record), ``"wall"`` (s of the run), ``"X"`` (records), ``"system"``.
    """
    system = stiff_cloth() if system is None else system
    method = make_method(system)
    every = max(1, round(1 / 60 / h)) if every is None else every
    start = time.perf_counter()
    t, X = system.run(T, h, method=method, every=every)
    wall = time.perf_counter() - start
    K = np.array([system.kinetic_energy(x) for x in X])
    E = K + np.array([system.potential_energy(x) for x in X])
    strain = np.array([system.max_strain(x, "structural") for x in X])
    return {"t": t, "E": E, "K": K, "strain": strain, "wall": wall, "X": X, "system": system, "method": method}


def small_steps_study(budget=20, h=1 / 60, T=1.0, n=10, k=5000.0, substeps=None):
    """XPBD on the stiff cloth with ``substeps x iterations = budget`` sweeps per step.

    Parameters
    ----------
    budget : int
        Sweeps per time step.
    substeps : sequence of int, optional
        The substep counts to try, each dividing `budget` (default: all its divisors).
    h, T : float
        Time step and simulated time, in seconds.
    n : int
        Particles per side.
    k : float
        Structural stiffness, in N/m (compliance ``1 / k``).

    Returns
    -------
    dict
        ``"splits"``: list of ``(substeps, iterations)``; ``"runs"``: one
        :func:`swing` result per split.
    """
    budget = count(budget, "budget", 1)
    substeps = [s for s in range(1, budget + 1) if budget % s == 0] if substeps is None else list(substeps)
    if any(count(s, "substeps", 1) > budget or budget % s for s in substeps):
        raise ValueError(f"substeps must divide budget = {budget}, got {substeps}")
    splits = [(s, budget // s) for s in substeps]
    runs = [swing(lambda c, s=s, i=i: XPBD.from_system(c, substeps=s, iterations=i), h, T, stiff_cloth(n, k))
            for s, i in splits]
    return {"splits": splits, "runs": runs}
