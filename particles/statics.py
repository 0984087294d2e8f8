"""Static equilibrium of mass-spring systems: where the net force on every free particle vanishes.

:func:`relax` finds it by pseudo time stepping with the implicit solver of
:mod:`particles.implicit` (large cloths), or by Newton's method on all forces
with a continuation (small systems with bending, such as a hair).
"""

import numpy as np

from .errors import ConvergenceError
from .fields import Damping, Gravity, Wind
from .baraffwitkin import BaraffWitkin

__all__ = ["relax"]


def relax(system, h=0.05, tol=1e-8, max_steps=2000, method="auto"):
    """Static equilibrium of a mass-spring system: positions where the net force vanishes.

    Parameters
    ----------
    system : MassSpringSystem
        Relaxed in place: its state becomes the equilibrium, at rest.
    h : float
        Pseudo time step of the ``"implicit"`` method (larger is closer to
        plain Newton), and the first of the growing pseudo time steps of the
        ``"newton"`` method's continuation.
    tol : float
        Relative force tolerance: stop when the largest net force on a free
        particle is below ``tol`` times the force scale, the largest of the
        net force at the start, the largest force any one force object
        applies there (so that a system already at equilibrium returns at
        once) and the largest tension ``k |L - L0|`` any spring carries at
        the current positions (at an equilibrium the springs' forces on a
        particle balance: their net is small, their tensions are not, and
        the round-off of the net force follows the tensions). Never below
        the round-off of the spring forces, ``16 eps max(k) max|x|``.
        ``"newton"``: at most ``max(tol, 1e-6)`` times the scale, the floor
        set by its finite-difference Jacobian.
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
        Steps (``"implicit"``) or force evaluations (``"newton"``) used.

    Raises
    ------
    particles.ConvergenceError
        When no equilibrium is found.
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
    # the force scale: the larger of the net force at the start and the largest force any one force
    # applies (at an equilibrium the net force is ~0 but gravity and the springs are not)
    scale = max(np.max(np.abs(system.total_force(X, system.t)[free]), initial=0.0), 1e-300)
    for force in system.forces:  # a loop over the few force objects
        F_one = np.zeros_like(X[:, 0])
        force.add_to(F_one, X[:, 0], X[:, 1], system.t, system.m)
        scale = max(scale, np.max(np.abs(F_one[free]), initial=0.0))
    springs = list(system.springs.values())
    k_max = max((float(s.k.max(initial=0.0)) for s in springs), default=0.0)  # a loop over spring sets

    def threshold(x):
        """tol times the force scale with the springs' tensions at x, or the round-off floor (N)."""
        tension = max((float(np.max(s.k * np.abs(s.lengths(x) - s.rest_length), initial=0.0)) for s in springs),
                      default=0.0)  # a loop over the few spring sets
        return max(tol * max(scale, tension), 16 * np.finfo(float).eps * k_max * np.max(np.abs(x), initial=0.0))

    if method == "newton":
        mass = np.repeat(system.m[free], system.d)

        def net_force(y):
            X[free, 0] = y.reshape(-1, system.d)
            return system.total_force(X, system.t)[free].ravel() / scale

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
        # finite-difference Jacobians limit the attainable residual to about 1e-8
        residual = np.max(np.abs(net_force(y))) * scale
        X[free, 0] = y.reshape(-1, system.d)
        if not sol.success or residual > max(threshold(X[:, 0]), max(tol, 1e-6) * scale):
            raise ConvergenceError(f"relax: Newton found no static equilibrium ({sol.message})")
        system.set_state(X)
        return int(evaluations)
    # one linearized backward-Euler solve per pseudo step: Newton's method on F(x) = 0, regularized
    solver = BaraffWitkin(system, linear_solver="direct", newton_iterations=1, energy_check=False)
    residual = np.inf
    for step in range(max_steps + 1):
        X[:, 1] = 0.0
        residual = np.max(np.abs(system.total_force(X, system.t)[free]), initial=0.0)
        if residual <= threshold(X[:, 0]):
            system.set_state(X)
            return step
        X = solver.step(X, system.t, h)
        if not np.all(np.isfinite(X)):
            break
    raise ConvergenceError(f"relax: no static equilibrium within {max_steps} steps "
                           f"(largest net force {residual:.3g} N)")
