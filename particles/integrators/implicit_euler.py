"""Implicit (backward) Euler for any ODE: Newton's method, with a dense or a matrix-free (GMRES) Jacobian.

:func:`implicit_euler` has the signature of every stepper, ``step(f, X, t, h)``, and works on any array
shape; it is the one stepper of :data:`particles.integrators.INTEGRATORS` that solves an equation at each
step, which is why it has a module of its own. The mass-spring solvers built on the same idea, with the
springs' own Jacobians, are in :mod:`particles.implicit`.

References
----------
.. [1] A. Witkin and D. Baraff, "Physically Based Modeling: Principles and
   Practice", SIGGRAPH 1997 course notes, section "Implicit methods".
"""

import math

import numpy as np

from .._checks import count, nonnegative_number
from ..errors import ConvergenceError
from .common import check_arguments, evaluate, stepper

__all__ = ["implicit_euler"]


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

    Matrix-free, the Newton iterations are inexact [2]_: GMRES solves the
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
    .. [2] S. C. Eisenstat and H. F. Walker, "Choosing the forcing terms in an
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
