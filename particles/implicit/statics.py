"""Static equilibrium of mass-spring systems: where the net force on every free particle vanishes.

:func:`relax` finds it by pseudo time stepping with the implicit solver of
:mod:`particles.implicit` (large cloths), or by Newton's method on all forces
with a continuation (small systems with bending, such as a hair). It stops
when the net force on every free particle is small against the loads that
particle must balance (its weight, the wind on it): an equilibrium is a
balance of loads, and a start whose loads are not balanced is never returned
as one, however large the tensions of its springs.
"""

import numpy as np

from ..errors import ConvergenceError
from ..forces.fields import Damping, Gravity, Wind
from ..forces import Bending, Clamp
from .baraffwitkin import BaraffWitkin

__all__ = ["relax"]

# the round-off of a spring's force: its stiffness times the rounding of the positions it joins, with room
# for the dozen springs that meet at a cloth's particle
ROUNDOFF = 16 * np.finfo(float).eps


def _force_scale(system, X, free):
    """The force scale of Newton's equations: the largest net force at X or force of any one force object (N)."""
    scale = max(np.max(np.abs(system.total_force(X, system.t)[free]), initial=0.0), 1e-300)
    for force in system.forces:  # a loop over the few force objects
        F_one = np.zeros_like(X[:, 0])
        force.add_to(F_one, X[:, 0], X[:, 1], system.t, system.m)
        scale = max(scale, np.max(np.abs(F_one[free]), initial=0.0))
    return scale


def relax(system, h=0.05, tol=1e-8, max_steps=2000, method="auto"):
    """Static equilibrium of a mass-spring system: positions where the net force on every free particle vanishes.

    Parameters
    ----------
    system : MassSpringSystem
        Relaxed in place: its state becomes the equilibrium, at rest.
    h : float
        Pseudo time step of the ``"implicit"`` method (larger is closer to
        plain Newton), and the first of the growing pseudo time steps of the
        ``"newton"`` method's continuation.
    tol : float
        Relative force tolerance, against the loads (see Notes): stop when
        ``|F_p| <= tol w_p`` on every free particle ``p``.
    max_steps : int
        Largest number of pseudo time steps.
    method : {"auto", "implicit", "newton"}
        ``"implicit"`` repeats backward-Euler steps (:class:`~particles.implicit.BaraffWitkin`)
        from rest, i.e. Newton's method on ``F(x) = 0`` regularized by
        ``M / h^2``; it handles large cloths but treats forces other than
        springs and damping explicitly. ``"newton"`` calls
        ``scipy.optimize.root`` (Powell's hybrid method, finite-difference
        Jacobian) on all forces, for small systems such as a hair with
        bending. ``"auto"`` picks ``"newton"`` when the system has forces
        beyond springs, gravity, damping and wind, else ``"implicit"``.

    Returns
    -------
    int
        Steps (``"implicit"``) or force evaluations (``"newton"``) used; 0
        when the start is already an equilibrium.

    Raises
    ------
    particles.ConvergenceError
        When no equilibrium is found.

    Notes
    -----
    **The stopping rule.** At rest, a free particle ``p`` is in equilibrium
    when its internal forces (springs, :class:`~particles.forces.Bending`,
    :class:`~particles.forces.Clamp`) balance its loads, the forces of all
    the other force objects (gravity, wind, fields; damping is zero at
    rest). Its load is ``w_p = sum_f |F_f(p)|`` over those external forces,
    at the current positions: ``m_p |g|`` for a cloth or a string. ``relax``
    stops when, for every free particle,

        ``|F_p| <= max(tol w_p, 16 eps max(k) max|x|)``,

    ``F_p`` the net force. The second term is the round-off of the spring
    forces (a spring of stiffness ``k`` between positions rounded to ``eps
    |x|``), below which no net force can be computed; it only counts for
    loads below about ``1e-7 k |x|`` (weightless particles, stiff springs).
    The tensions of the springs do not enter: they are large at an
    equilibrium and at a start that is not one alike (a string compressed
    between its pins, whose every node carries its weight unbalanced).
    ``"newton"`` accepts ``max(tol, 1e-6) w_p``, the floor set by its
    finite-difference Jacobian.

    Examples
    --------
    A string of 21 nodes pinned at both ends, 1 m long over a 0.8 m span,
    starts straight and compressed; relaxed, every node's weight is balanced:

    >>> import numpy as np
    >>> from particles.massspring import string
    >>> s = string(21, 1.0, pin="both", span=0.8, scaling="physical", stretch_modulus=1e5)
    >>> relax(s, tol=1e-6) > 0
    True
    >>> F, w = s.total_force(s.X, 0.0)[1:-1], s.m[1:-1] * 9.81
    >>> bool(np.all(np.linalg.norm(F, axis=1) <= 1e-6 * w))
    True
    """
    import scipy.optimize

    if method == "auto":
        simple = all(isinstance(f, (Gravity, Damping, Wind)) for f in system.other_forces())
        method = "implicit" if simple else "newton"
    if method not in ("implicit", "newton"):
        raise ValueError(f"method must be 'auto', 'implicit' or 'newton', got {method!r}")
    free = np.setdiff1d(np.arange(system.n), system.pinned)
    X = system.X.copy(order="K")
    X[:, 1] = 0.0
    scale = _force_scale(system, X, free)
    internal = {id(s) for s in system.springs.values()}
    external = [f for f in system.forces if id(f) not in internal and not isinstance(f, (Bending, Clamp))]
    k_max = max((float(s.k.max(initial=0.0)) for s in system.springs.values()), default=0.0)

    def loads(x):
        """``w_p``, the sum of the external forces' magnitudes on each free particle at rest at x (N), shape (f,)."""
        w, F_one, at_rest = np.zeros(system.n), np.zeros_like(x), np.zeros_like(x)
        for force in external:  # a loop over the few external force objects
            F_one[:] = 0.0
            force.add_to(F_one, x, at_rest, system.t, system.m)
            w += np.sqrt(np.einsum("pa,pa->p", F_one, F_one))
        return w[free]

    def balanced(F, x, relative):
        """Whether the net force F (n, d) is within `relative` times the load on every free particle (or round-off)."""
        residual = np.sqrt(np.einsum("pa,pa->p", F[free], F[free]))
        floor = ROUNDOFF * k_max * np.max(np.abs(x), initial=0.0)
        return bool(np.all(residual <= np.maximum(relative * loads(x), floor))), residual

    def worst(residual, x):
        """The largest net force and the load where it acts, for an error message."""
        if not len(residual):
            return "no free particle"
        p = int(np.argmax(residual))
        return f"largest net force {residual[p]:.3g} N on a particle of load {loads(x)[p]:.3g} N"

    if method == "newton":
        mass = np.repeat(system.m[free], system.d)

        def net_force(y):
            X[free, 0] = y.reshape(-1, system.d)
            return system.total_force(X, system.t)[free].ravel() / scale

        if balanced(system.total_force(X, system.t), X[:, 0], tol)[0]:
            system.set_state(X)
            return 0
        # continuation: backward-Euler-like steps from rest with growing pseudo
        # time steps guide Newton to the equilibrium nearest the start, then a
        # plain solve of F(x) = 0. A pseudo step whose solve fails is not
        # taken: it is retried at half the length (large rotations of stiff
        # springs defeat Newton when the step is too long).
        y, evaluations = X[free, 0].ravel().copy(), 0
        tau, longest = h, h * 2.0**11
        for _ in range(max_steps):  # a loop over pseudo time steps
            start = y.copy()
            sol = scipy.optimize.root(lambda z: net_force(z) - mass * (z - start) / (tau * tau * scale),
                                      start, method="hybr", tol=1e-12)
            evaluations += sol.nfev
            if sol.success:
                y = sol.x
                if tau == np.inf:
                    break
                tau = np.inf if tau >= longest else 2.0 * tau
            elif tau == np.inf:
                tau = longest  # not close enough for a plain solve: more pseudo steps first
            elif tau > 1e-6 * h:
                tau /= 2.0
            else:
                break
        X[free, 0] = y.reshape(-1, system.d)
        # finite-difference Jacobians limit the attainable residual to about 1e-8 of the force scale
        ok, residual = balanced(system.total_force(X, system.t), X[:, 0], max(tol, 1e-6))
        if not sol.success or not ok:
            raise ConvergenceError(f"relax: Newton found no static equilibrium ({sol.message}; "
                                   f"{worst(residual, X[:, 0])})")
        system.set_state(X)
        return int(evaluations)
    # one linearized backward-Euler solve per pseudo step: Newton's method on F(x) = 0, regularized
    solver = BaraffWitkin(system, linear_solver="direct", newton_iterations=1, energy_check=False)
    residual = np.full(len(free), np.inf)
    for step in range(max_steps + 1):  # a loop over pseudo time steps
        X[:, 1] = 0.0
        ok, residual = balanced(system.total_force(X, system.t), X[:, 0], tol)
        if ok:
            system.set_state(X)
            return step
        X = solver.step(X, system.t, h)
        if not np.all(np.isfinite(X)):
            break
    raise ConvergenceError(f"relax: no static equilibrium within {max_steps} steps ({worst(residual, X[:, 0])})")
