"""ODE steppers for dX/dt = f(X, t).

Every stepper has the same signature::

    X_new = step(f, X, t, h)

and never modifies ``X``, which must be finite (inf or NaN raise ValueError;
:func:`integrate` turns a state that blows up into
:class:`~particles.SimulationDiverged`). ``f(X, t)`` returns an array of the
same shape as ``X``. The generic steppers (:func:`euler`, :func:`midpoint`, :func:`trapezoid`,
:func:`rk4`, :func:`implicit_euler`) accept any array shape, so they work on a
scalar ODE, on the circle field ``f = (-y, x)`` and on a particle system alike.
:func:`symplectic_euler` and :func:`verlet` need the second-order layout
``X.shape == (n, 2, d)`` where ``X[:, 0]`` are positions and ``X[:, 1]``
velocities, and ``f`` of the form ``(v, a(x, v, t))``.

Each stepper carries ``.order``, its order of global accuracy: halving ``h``
divides the error at a fixed end time by about ``2**order``, and ``.fsal``
("first same as last"): True when its last evaluation of ``f`` is at the
positions the next step starts from (:func:`verlet`). For forces that depend
on the positions only, that evaluation *is* the next step's first one, and
:meth:`particles.ParticleSystem.run` reuses it (one force evaluation per
step instead of two); the stepper itself keeps the generic signature.

References
----------
.. [1] A. Witkin and D. Baraff, "Physically Based Modeling: Principles and
   Practice", SIGGRAPH 1997 course notes, section "Differential equation basics".
.. [2] E. Hairer, C. Lubich and G. Wanner, *Geometric Numerical Integration*,
   2nd ed., Springer, 2006, sections I.1 and VI.3 (symplectic Euler, Verlet).
"""

import math

import numpy as np

from .._checks import count, nonnegative_number
from ..errors import ConvergenceError
from .common import check_arguments, evaluate, split_state, stepper

__all__ = [
    "euler",
    "midpoint",
    "trapezoid",
    "rk4",
    "symplectic_euler",
    "verlet",
    "implicit_euler",
    "INTEGRATORS",
]


@stepper(order=1)
def euler(f, X, t, h):
    """Explicit (forward) Euler step: ``X + h f(X, t)``.

    Parameters
    ----------
    f : callable
        Right-hand side ``f(X, t) -> ndarray`` of the same shape as ``X``.
    X : ndarray, any shape
        State at time `t`. Not modified.
    t : float
        Time, in seconds.
    h : float
        Time step, in seconds, > 0.

    Returns
    -------
    ndarray, shape of `X`
        State at ``t + h``.

    Raises
    ------
    ValueError
        When `X` is not an array of finite real numbers, `t` not a finite
        real number, or `h` not a positive finite number. Every stepper makes
        these checks, so that a NaN never passes silently from step to step.

    Notes
    -----
    First order. On the undamped oscillator ``x'' = -w**2 x`` it is unstable for
    every ``h > 0``: each step multiplies the amplitude by ``sqrt(1 + (w h)**2)``.
    Stable for a decaying mode ``x' = -lambda x`` only when ``h < 2 / lambda``.

    Examples
    --------
    >>> import numpy as np
    >>> euler(lambda X, t: -X, np.array([1.0]), 0.0, 0.1)
    array([0.9])
    """
    X, h = check_arguments(X, t, h)
    return X + h * evaluate(f, X, t)


@stepper(order=2)
def midpoint(f, X, t, h):
    """Explicit midpoint step: half an Euler step, evaluate there, full step.

    ``X_m = X + h/2 f(X, t)``, then ``X_new = X + h f(X_m, t + h/2)``.

    Parameters and return value as for :func:`euler`.

    Notes
    -----
    Second order, two evaluations of ``f`` per step. On the undamped oscillator
    the amplitude grows by ``sqrt(1 + (w h)**4 / 4)`` per step: slowly unstable.
    """
    X, h = check_arguments(X, t, h)
    X_m = X + 0.5 * h * evaluate(f, X, t)
    return X + h * evaluate(f, X_m, t + 0.5 * h)


@stepper(order=2)
def trapezoid(f, X, t, h):
    """Explicit trapezoid (Heun) step: Euler step, evaluate there, average.

    ``f_0 = f(X, t)``, ``f_1 = f(X + h f_0, t + h)``, ``X_new = X + h (f_0 + f_1) / 2``.

    Parameters and return value as for :func:`euler`.

    Notes
    -----
    Second order, two evaluations of ``f`` per step. For linear problems it
    gives the same result as :func:`midpoint`.
    """
    X, h = check_arguments(X, t, h)
    f_0 = evaluate(f, X, t)
    f_1 = evaluate(f, X + h * f_0, t + h)
    return X + 0.5 * h * (f_0 + f_1)


@stepper(order=4)
def rk4(f, X, t, h):
    """Classical fourth-order Runge-Kutta step.

    ``k1 = f(X, t)``, ``k2 = f(X + h/2 k1, t + h/2)``, ``k3 = f(X + h/2 k2, t + h/2)``,
    ``k4 = f(X + h k3, t + h)``, ``X_new = X + h (k1 + 2 k2 + 2 k3 + k4) / 6``.

    Parameters and return value as for :func:`euler`.

    Notes
    -----
    Fourth order, four evaluations of ``f`` per step. On the undamped oscillator
    it is stable for ``w h <= 2 sqrt(2) ~ 2.83`` (with slow amplitude decay below
    that limit).
    """
    X, h = check_arguments(X, t, h)
    k1 = evaluate(f, X, t)
    k2 = evaluate(f, X + 0.5 * h * k1, t + 0.5 * h)
    k3 = evaluate(f, X + 0.5 * h * k2, t + 0.5 * h)
    k4 = evaluate(f, X + h * k3, t + h)
    return X + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


@stepper(order=1, second_order_layout=True)
def symplectic_euler(f, X, t, h):
    """Symplectic (semi-implicit) Euler step: new velocity first, then position.

    ``v_new = v + h a(x, v, t)``, then ``x_new = x + h v_new``.

    Parameters
    ----------
    f : callable
        ``f(X, t)`` of the second-order form ``(v, a)``; only its acceleration
        part ``f(X, t)[:, 1]`` is used.
    X : ndarray, shape (n, 2, d)
        ``X[:, 0]`` positions (m), ``X[:, 1]`` velocities (m/s). Not modified.
    t, h : float
        Time and time step, in seconds.

    Returns
    -------
    ndarray, shape (n, 2, d)

    Notes
    -----
    First order, one evaluation of ``f`` per step, symplectic for forces that
    depend on position only: on the undamped oscillator it is stable for
    ``w h < 2`` and the energy error stays bounded (it oscillates, it does not
    drift) over arbitrarily long runs [2]_.

    When `f` is the ``derivative`` of an object with a method
    ``fused_symplectic_euler(X, t, h)`` (a :class:`~particles.ParticleSystem`)
    and that method returns a state, the step is that state: the same method
    in one compiled pass when the system's springs run compiled
    (:func:`particles.backends.compiled_step`), equal to this code to
    rounding.
    """
    X, h = check_arguments(X, t, h)
    fused = _compiled_step(f)  # a system's step in one compiled pass (particles.backends), or None
    if fused is not None and (X_new := fused(X, t, h)) is not None:
        return X_new
    x, v = split_state(X)
    a = evaluate(f, X, t)[:, 1]
    X_new = np.empty_like(X)
    X_new[:, 1] = v + h * a
    X_new[:, 0] = x + h * X_new[:, 1]
    return X_new


def _compiled_step(f, name="fused_symplectic_euler"):
    """The method `name` of `f`'s owner when `f` is a bound ``derivative`` method, else None."""
    owner = getattr(f, "__self__", None) if getattr(f, "__name__", None) == "derivative" else None
    return getattr(owner, name, None)


def _symplectic_euler_steps(f, X, times, limit):
    """Symplectic Euler from ``times[0]`` to ``times[-1]`` in one compiled call; None when it does not apply.

    :func:`particles.integrators.integrate` calls it (as ``symplectic_euler.steps``) for the steps
    between two recorded states when nothing runs between the steps: `f` must be a system's
    ``derivative`` whose ``fused_symplectic_euler_steps`` applies (see
    :meth:`particles.backends.compiled.CompiledStep.symplectic_euler_steps`). Each step is the one
    :func:`symplectic_euler` takes, to the bit, and the divergence guard (``max|X| <= limit``,
    finite) runs after each step inside the call.

    Returns
    -------
    (ndarray, int, float) or None
        The last state that passed the guard, the number of steps that passed, and the size
        ``max|X|`` of the last state computed.
    """
    many = _compiled_step(f, "fused_symplectic_euler_steps")
    if many is None:
        return None
    X, _ = check_arguments(X, times[0], times[1] - times[0])
    return many(X, times, limit)


symplectic_euler.steps = _symplectic_euler_steps


@stepper(order=2, second_order_layout=True, fsal=True)
def verlet(f, X, t, h):
    """Velocity Verlet step (kick, drift, kick).

    ``v_half = v + h/2 a(x, v, t)``, ``x_new = x + h v_half``,
    ``v_new = v_half + h/2 a(x_new, v*, t + h)``.

    Parameters and return value as for :func:`symplectic_euler`.

    Notes
    -----
    Second order, two evaluations of ``f`` per step, symplectic and
    time-reversible for position-only forces: on the undamped oscillator it is
    stable for ``w h < 2`` with bounded energy error [2]_. The second
    evaluation is at the new positions, where the next step starts
    (``verlet.fsal`` is True): a particle system whose forces depend on the
    positions only reuses it, so that a run costs one force evaluation per
    step (see :meth:`particles.ParticleSystem.run`).

    When the force depends on velocity (damping, drag) the final kick needs a
    velocity at ``t + h`` before it is known. We use the Euler predictor
    ``v* = v + h a(x, v, t)``, which keeps the method second order; for
    position-only forces ``v*`` is never used and the method is the classical
    velocity Verlet.
    """
    X, h = check_arguments(X, t, h)
    x, v = split_state(X)
    a = evaluate(f, X, t)[:, 1]
    v_half = v + 0.5 * h * a
    X_pred = np.empty_like(X)
    X_pred[:, 0] = x + h * v_half
    X_pred[:, 1] = v + h * a
    a_new = evaluate(f, X_pred, t + h)[:, 1]
    X_new = np.empty_like(X)
    X_new[:, 0] = X_pred[:, 0]
    X_new[:, 1] = v_half + 0.5 * h * a_new
    return X_new


# Without an analytic Jacobian, states up to this size get a dense finite-
# difference Jacobian (one evaluation of f per component); larger ones are
# solved matrix-free by GMRES.
_DENSE_FD_MAX = 200


def _jacobian_operator(f, Y, t, fY):
    """Matrix-free J v ~ (f(Y + eps v) - f(Y)) / eps, as a LinearOperator."""
    import scipy.sparse.linalg
    shape, N = Y.shape, Y.size
    scale = 1.0 + np.linalg.norm(Y.ravel(), np.inf)

    def matvec(u):
        u = np.asarray(u, dtype=float).ravel()
        norm = np.linalg.norm(u, np.inf)
        if norm == 0.0:
            return np.zeros(N)
        eps = math.sqrt(np.finfo(float).eps) * scale / norm
        return (evaluate(f, Y + eps * u.reshape(shape), t) - fY).ravel() / eps

    return scipy.sparse.linalg.LinearOperator((N, N), matvec=matvec, dtype=float)


@stepper(order=1, explicit=False)
def implicit_euler(f, X, t, h, jac=None, tol=1e-10, max_iter=50):
    """Implicit (backward) Euler step, solved by Newton's method.

    Finds ``Y`` with ``Y = X + h f(Y, t + h)``. Newton's method on
    ``G(Y) = Y - X - h f(Y, t + h)`` repeats ``(I - h J) dY = -G(Y)``, ``Y += dY``
    with ``J = df/dX`` at the current ``Y``, starting from ``Y = X``.

    Parameters
    ----------
    f : callable
        Right-hand side ``f(X, t)``, same shape as ``X``.
    X : ndarray, any shape
        State at time `t`. Not modified.
    t, h : float
        Time and time step, in seconds (``h > 0``).
    jac : callable, optional
        ``jac(X, t)`` returning the Jacobian ``df/dX`` of the flattened state,
        shape ``(X.size, X.size)``, as a dense array (or nested lists) or a
        ``scipy.sparse`` matrix. Without it, the Jacobian is estimated by finite differences:
        as a dense matrix (one evaluation of ``f`` per state component) for
        states of up to 200 numbers, and matrix-free inside GMRES for larger
        ones (one evaluation per Krylov iteration). Give `jac` for large systems.
    tol : float
        Relative tolerance, >= 0: Newton stops when the residual
        ``Y - X - h f(Y, t + h)`` or the last update is below
        ``tol * max(max|X|, max|Y|)``.
    max_iter : int
        Largest number of Newton iterations, >= 1.

    Returns
    -------
    ndarray, shape of `X`

    Raises
    ------
    ConvergenceError
        When Newton's method does not converge in `max_iter` iterations, or
        (matrix-free) when GMRES, within its budget of about ``2 X.size``
        evaluations of ``f`` for one Newton iteration, does not even reduce
        the linear residual to 0.9 of ``|G|`` (no usable Newton step).
    ValueError
        For a non-finite `X` or `t`, ``h <= 0``, ``tol < 0``, a `max_iter`
        that is not an integer >= 1, or a `jac` of the wrong shape.

    Notes
    -----
    First order and A-stable: stable for every ``h > 0`` on any decaying or
    oscillating linear system. The price is numerical damping: on the undamped
    oscillator each step multiplies the amplitude by ``1 / sqrt(1 + (w h)**2)``.
    For a linear ``f`` with an exact `jac`, one Newton iteration solves the step.

    Matrix-free, the Newton iterations are inexact [3]_: GMRES solves the
    k-th one only to the relative residual ``eta_k`` (the forcing term),
    with ``eta_0 = 0.5`` and Eisenstat and Walker's choice 2,
    ``eta_k = 0.9 (|G_k| / |G_k-1|)^2`` (safeguarded by ``0.9 eta_k-1^2`` and
    capped at 0.9): loose while Newton is far from the solution, tight
    only as it converges, and never below what the step's tolerance needs
    (``tol`` scaled by ``|G_k|``) or below ``1e-7``, the noise of a
    finite-difference product ``(f(Y + e u) - f(Y)) / e``. A GMRES run that
    ends short of ``eta_k`` but below 0.9 still gives an inexact Newton
    step, and is taken. On a 300-unknown heat equation a step then costs 15,
    44 and 167 evaluations of ``f`` at ``h = 1e-4, 1e-3, 1e-2`` (``h`` times
    the largest eigenvalue: 36, 360, 3600); solving every linear system to
    ``1e-8``, below the noise, spent the whole budget at each iteration
    (3200 to 4000 evaluations, where a dense finite-difference Jacobian
    needs 301 per iteration).

    References
    ----------
    .. [3] S. C. Eisenstat and H. F. Walker, "Choosing the forcing terms in an
       inexact Newton method", SIAM J. Sci. Comput. 17(1), 1996.
    """
    X, h = check_arguments(X, t, h)
    tol = nonnegative_number(tol, "tol")
    max_iter = count(max_iter, "max_iter", least=1)
    if jac is not None and not callable(jac):
        raise ValueError(f"jac must be a function jac(X, t) returning df/dX, got {type(jac).__name__}")
    t_new = t + h
    Y = X.copy()
    dY = np.full(X.size, np.inf)
    eta, norm_old = 0.5, None  # the forcing term of the matrix-free (GMRES) solves
    for iteration in range(max_iter + 1):
        fY = evaluate(f, Y, t_new)
        G = (Y - X - h * fY).ravel()
        small = tol * max(np.max(np.abs(X), initial=0.0), np.max(np.abs(Y), initial=0.0))
        if np.max(np.abs(G), initial=0.0) <= small or np.max(np.abs(dY)) <= small:
            return Y
        if iteration == max_iter:
            break
        norm = float(np.linalg.norm(G))
        if norm_old is not None:  # Eisenstat and Walker's choice 2 (gamma = 0.9, alpha = 2), safeguarded
            guard = 0.9 * eta**2
            eta = min(max(0.9 * (norm / norm_old) ** 2, guard if guard > 0.1 else 0.0), 0.9)
        eta = max(eta, 0.5 * small / norm, 1e-7)  # no solving beyond the step's tolerance or the noise
        norm_old = norm
        dY = _newton_update(f, Y, t_new, h, fY, G, jac, eta)
        Y = Y + dY.reshape(X.shape)
        if not np.all(np.isfinite(Y)):
            break
    raise ConvergenceError(
        f"implicit_euler: Newton's method did not converge in {max_iter} iterations "
        f"at t = {t:.6g} s with h = {h:.6g} s (last update max|dY| = "
        f"{np.max(np.abs(dY)):.3g}). Reduce h, or pass an exact jacobian as jac=."
    )


def _newton_update(f, Y, t, h, fY, G, jac, eta=1e-8):
    """Solve ``(I - h J) dY = -G`` with J = df/dX at (Y, t); matrix-free to the relative residual `eta`."""
    import scipy.sparse.linalg
    N = Y.size
    if jac is not None:
        J = jac(Y, t)
        if not scipy.sparse.issparse(J):
            try:
                J = np.asarray(J, dtype=float)  # a nested list, a matrix...
            except (TypeError, ValueError):
                raise ValueError(
                    f"jac(X, t) must return a ({N}, {N}) array of real numbers or a scipy.sparse "
                    f"matrix, got {type(J).__name__}"
                ) from None
        if J.shape != (N, N):
            raise ValueError(f"jac(X, t) must return a ({N}, {N}) matrix, got shape {J.shape}")
        if scipy.sparse.issparse(J):
            A = scipy.sparse.identity(N, format="csc") - h * J.tocsc()
            return scipy.sparse.linalg.spsolve(A, -G)
        return np.linalg.solve(np.eye(N) - h * J, -G)
    if N <= _DENSE_FD_MAX:
        J = _dense_jacobian(f, Y, t, fY)
        return np.linalg.solve(np.eye(N) - h * J, -G)
    J = _jacobian_operator(f, Y, t, fY)
    A = scipy.sparse.linalg.LinearOperator((N, N), matvec=lambda u: u - h * J.matvec(u), dtype=float)
    restart = min(N, 50)
    budget = -(-2 * N // restart)  # restart cycles: at most about 2 N evaluations of f
    dY, info = scipy.sparse.linalg.gmres(A, -G, rtol=eta, atol=0.0, restart=restart, maxiter=budget)
    if info == 0 and np.all(np.isfinite(dY)):
        return dY
    # short of eta: still an inexact Newton step if the linear residual fell below 0.9 |G|
    reached = np.linalg.norm(A.matvec(dY) + G) / np.linalg.norm(G) if np.all(np.isfinite(dY)) else np.inf
    if reached <= 0.9:
        return dY
    raise ConvergenceError(
        f"implicit_euler: GMRES did not reach the relative residual {eta:.3g} within {budget * restart} "
        f"matrix-free iterations (reached {reached:.3g}, no usable Newton step) at t = {t:.6g} s with "
        f"h = {h:.6g} s: the linear systems are too stiff for finite differences without a "
        "preconditioner. Pass the Jacobian as jac=, or reduce h."
    )


def _dense_jacobian(f, Y, t, fY):
    """Forward-difference Jacobian, one evaluation of f per state component."""
    y = Y.ravel()
    eps = math.sqrt(np.finfo(float).eps) * (1.0 + np.abs(y))
    J = np.empty((y.size, y.size))
    for c in range(y.size):  # a loop over Jacobian columns: f is a black box
        y_c = y.copy()
        y_c[c] += eps[c]
        J[:, c] = (evaluate(f, y_c.reshape(Y.shape), t) - fY).ravel() / eps[c]
    return J


INTEGRATORS = {
    "euler": euler,
    "midpoint": midpoint,
    "trapezoid": trapezoid,
    "rk4": rk4,
    "symplectic_euler": symplectic_euler,
    "verlet": verlet,
    "implicit_euler": implicit_euler,
}
"""Stepper by name, in teaching order."""


