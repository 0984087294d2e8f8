"""Stiffness and the time step: how large can ``h`` be before a simulation blows up?

A spring of stiffness ``k`` holding a mass ``m`` oscillates at ``omega =
sqrt(k / m)``. For the undamped oscillator each explicit stepper multiplies
the state by a fixed matrix per step, so it is stable exactly when the
eigenvalues of that matrix stay within the unit circle:

=================  =====================================================
explicit Euler     never (amplitude x sqrt(1 + (omega h)^2) per step)
midpoint, Heun     never (amplitude x sqrt(1 + (omega h)^4 / 4) per step)
symplectic Euler   omega h <= 2
velocity Verlet    omega h <= 2
RK4                omega h <= 2 sqrt(2) ~ 2.83
implicit Euler     any h (amplitude x 1 / sqrt(1 + (omega h)^2): damping)
=================  =====================================================

So the largest stable step falls like ``1 / sqrt(k)``: stiff springs need
small steps. The functions here *measure* these limits by simulation
(bisection on a blow-up test), to compare with the table.
"""

import time

import numpy as np

from .._checks import as_float_array, count, method_name, positive_number
from ..integrators.steppers import INTEGRATORS
from .order import fit_order

__all__ = [
    "THEORY_OMEGA_H",
    "theory_max_step",
    "oscillator",
    "blows_up",
    "max_stable_step",
    "chain_max_stable_step",
    "stability_study",
    "damping_factor",
    "cost_study",
    "plot_stability",
]

THEORY_OMEGA_H = {
    "euler": 0.0,
    "midpoint": 0.0,
    "trapezoid": 0.0,
    "symplectic_euler": 2.0,
    "verlet": 2.0,
    "rk4": 2.0 * np.sqrt(2.0),
    "implicit_euler": np.inf,
}
"""Largest stable ``omega h`` of each stepper on the undamped oscillator."""


def _omega(k, m):
    """``sqrt(k / m)`` (rad/s) after checking both are positive."""
    return np.sqrt(positive_number(k, "k", "N/m") / positive_number(m, "m", "kg"))


def theory_max_step(method, k, m):
    """Theoretical largest stable step ``(omega h)_max / omega`` of a stepper on the undamped oscillator.

    Parameters
    ----------
    method : str
        A key of :data:`THEORY_OMEGA_H` (the steppers of
        :data:`particles.integrators.INTEGRATORS`).
    k : float
        Spring stiffness, in N/m (> 0).
    m : float
        Mass, in kg (> 0).

    Returns
    -------
    float
        The largest stable step, in seconds: 0 for the steppers that are never
        stable (explicit Euler, midpoint, Heun), ``inf`` for implicit Euler.

    Examples
    --------
    >>> round(float(theory_max_step("verlet", 100.0, 1.0)), 6)
    0.2
    """
    omega_h = method_name(method, THEORY_OMEGA_H)
    if callable(omega_h):
        raise ValueError(f"method must be a stepper's name, got {method!r}")
    return omega_h / _omega(k, m)


def oscillator(k, m):
    """Right-hand side ``f(X, t)`` of ``m x'' = -k x``, for states in the layout (1, 2, 1).

    Parameters
    ----------
    k : float
        Spring stiffness, in N/m (> 0).
    m : float
        Mass, in kg (> 0).

    Returns
    -------
    callable
        ``f(X, t)`` returning ``dX/dt`` with the shape of `X`, (p, 2, 1): any
        number ``p`` of independent oscillators, position in m, velocity in m/s.
    """
    w2 = _omega(k, m) ** 2

    def f(X, t):
        return np.stack([X[:, 1], -w2 * X[:, 0]], axis=1)

    return f


def blows_up(method, k, m, h, steps=1000, growth=1e3):
    """Blow-up test: does the amplitude grow more than `growth`-fold within `steps` steps?

    Starts at ``x = 1, v = 0`` and watches the energy ``v^2 + omega^2 x^2``. A
    stepper that is stable for this ``h`` keeps it bounded (or lets it decay);
    an unstable one makes it grow geometrically. The threshold must be large:
    near its limit a stable symplectic Euler lets the energy oscillate by a
    factor ``2 / (2 - omega h)`` without blowing up.

    Parameters
    ----------
    method : str or callable
        A key of :data:`particles.integrators.INTEGRATORS`, or a stepper
        ``step(f, X, t, h)``.
    k : float
        Spring stiffness, in N/m (> 0).
    m : float
        Mass, in kg (> 0).
    h : float
        Time step, in seconds (> 0).
    steps : int
        Number of steps of the test (>= 1).
    growth : float
        Amplitude factor counted as a blow-up (> 1).

    Returns
    -------
    bool
        True if the amplitude exceeded `growth` times its start (or became
        inf/NaN) within `steps` steps.
    """
    step = method_name(method, INTEGRATORS)
    f = oscillator(k, m)
    h = positive_number(h, "h", "s")
    steps = count(steps, "steps", 1)
    growth = positive_number(growth, "growth")
    if growth <= 1:
        raise ValueError(f"growth must be > 1, got {growth!r}")
    X = np.array([[[1.0], [0.0]]])
    w2 = k / m
    E0 = w2
    limit = growth**2 * E0
    with np.errstate(over="ignore", invalid="ignore"):
        for n in range(steps):  # a loop over time steps
            X = step(f, X, n * h, h)
            E = X[0, 1, 0] ** 2 + w2 * X[0, 0, 0] ** 2
            if not E <= limit:
                return True
    return False


def max_stable_step(method, k, m, steps=1000, rtol=2e-3, h_range=None):
    """Largest step that passes :func:`blows_up`, by bisection.

    Parameters
    ----------
    method : str or callable
        A key of :data:`particles.integrators.INTEGRATORS`, or a stepper.
    k, m : float
        Stiffness (N/m) and mass (kg), both > 0.
    steps : int
        Length of each blow-up test. Methods that are unstable for every ``h``
        (explicit Euler, midpoint) seem to have a limit that shrinks as tests
        get longer.
    rtol : float
        Relative precision of the bisection.
    h_range : (float, float), optional
        Bracket (default: half to twice the theoretical limit, or ``1e-6 / omega``
        to ``10 / omega`` when there is none).

    Returns
    -------
    float
        The largest stable step in seconds; ``inf`` if the whole bracket is
        stable, 0 if even its lower end blows up.
    """
    method_name(method, INTEGRATORS)
    omega = _omega(k, m)
    steps = count(steps, "steps", 1)
    rtol = positive_number(rtol, "rtol")
    guess = THEORY_OMEGA_H.get(method, 0.0)
    if h_range is not None:
        lo, hi = _bracket(h_range)
    elif 0 < guess < np.inf:
        lo, hi = 0.5 * guess / omega, 2.0 * guess / omega
    else:
        lo, hi = 1e-6 / omega, 10.0 / omega
    if not blows_up(method, k, m, hi, steps):
        return np.inf
    if blows_up(method, k, m, lo, steps):
        return 0.0
    while hi - lo > rtol * lo:  # bisection on a geometric scale
        mid = np.sqrt(lo * hi)
        if blows_up(method, k, m, mid, steps):
            hi = mid
        else:
            lo = mid
    return lo


def _bracket(h_range):
    """``(lo, hi)`` of a bisection, two steps in seconds with ``0 < lo < hi``."""
    try:
        lo, hi = h_range
    except (TypeError, ValueError):
        raise ValueError(f"h_range must be a pair (lo, hi) of steps in seconds, got {h_range!r}") from None
    lo, hi = positive_number(lo, "h_range[0]", "s"), positive_number(hi, "h_range[1]", "s")
    if not lo < hi:
        raise ValueError(f"h_range must have lo < hi, got {h_range!r}")
    return lo, hi


def chain_max_stable_step(method, n, k, m, steps=1000, rtol=2e-3):
    """Largest stable step for a chain of `n` masses between two walls (springs ``k``).

    The chain's fastest mode has ``omega_max = 2 sqrt(k / m) sin(n pi / (2 (n + 1)))``,
    approaching twice the single spring's frequency: a chain needs about half
    the step of one spring. Measured with the same blow-up test on the
    stiffest mode's initial shape.

    Parameters
    ----------
    method : str or callable
        A key of :data:`particles.integrators.INTEGRATORS`, or a stepper.
    n : int
        Number of masses (>= 1); the chain has ``n + 1`` springs.
    k : float
        Stiffness of every spring, in N/m (> 0).
    m : float
        Mass of every particle, in kg (> 0).
    steps : int
        Length of each blow-up test (>= 1).
    rtol : float
        Relative precision of the bisection (> 0).

    Returns
    -------
    float
        The largest stable step in seconds (``inf`` if ``10 / sqrt(k / m)`` is
        stable, 0 if even ``1e-6 / sqrt(k / m)`` blows up).
    """
    step = method_name(method, INTEGRATORS)
    n = count(n, "n", 1)
    _omega(k, m)
    steps = count(steps, "steps", 1)
    rtol = positive_number(rtol, "rtol")
    j = np.arange(1, n + 1)
    shape = np.sin(n * np.pi * j / (n + 1))  # the fastest normal mode

    def f(X, t):
        x = X[:, 0, 0]
        left = np.concatenate([[0.0], x[:-1]])
        right = np.concatenate([x[1:], [0.0]])
        a = k / m * (left - 2 * x + right)
        return np.stack([X[:, 1], a[:, None]], axis=1)

    def unstable(h):
        X = np.zeros((n, 2, 1))
        X[:, 0, 0] = shape
        E0 = np.sum(shape**2) * 4 * k / m
        with np.errstate(over="ignore", invalid="ignore"):
            for s in range(steps):  # a loop over time steps
                X = step(f, X, s * h, h)
                x = X[:, 0, 0]
                E = np.sum(X[:, 1, 0] ** 2) + k / m * (np.sum(np.diff(x) ** 2) + x[0] ** 2 + x[-1] ** 2)
                if not E <= 1e6 * E0:
                    return True
        return False

    omega = np.sqrt(k / m)
    lo, hi = 1e-6 / omega, 10.0 / omega
    if not unstable(hi):
        return np.inf
    if unstable(lo):
        return 0.0
    while hi - lo > rtol * lo:
        mid = np.sqrt(lo * hi)
        lo, hi = (lo, mid) if unstable(mid) else (mid, hi)
    return lo


def stability_study(ks=(1.0, 100.0, 1e4, 1e6), m=1.0,
                    methods=("euler", "symplectic_euler", "verlet", "rk4"), steps=1000):
    """Measured largest stable step against stiffness, with theory and fitted slopes.

    Returns
    -------
    dict
        ``"k"`` (ndarray), ``"h_max"`` (dict method -> ndarray, measured),
        ``"theory"`` (dict method -> ndarray), ``"slope"`` (dict method ->
        fitted slope of log h_max against log k, expected -1/2), ``"m"``.
    """
    ks = np.asarray(ks, dtype=float)
    h_max = {meth: np.array([max_stable_step(meth, k, m, steps) for k in ks]) for meth in methods}
    slope = {meth: fit_order(ks, h) if np.all((h > 0) & np.isfinite(h)) else np.nan for meth, h in h_max.items()}
    theory = {meth: np.array([theory_max_step(meth, k, m) for k in ks]) for meth in methods}
    return {"k": ks, "m": m, "h_max": h_max, "theory": theory, "slope": slope, "steps": steps}


def damping_factor(omega_h, steps=50):
    """Measured amplitude factor per step of implicit Euler on the undamped oscillator.

    Parameters
    ----------
    omega_h : float or array_like, shape (r,)
        Values of ``omega h`` (dimensionless, > 0).
    steps : int
        Steps simulated (>= 1); the factor is the geometric mean per step.

    Returns
    -------
    ndarray, shape (r,)
        Amplitude ratio per step, to compare with ``1 / sqrt(1 + (omega h)^2)``
        (a scalar `omega_h` gives shape (1,)).
    """
    wh = np.atleast_1d(as_float_array(omega_h, "omega_h", ndim=(0, 1)))
    if wh.size == 0 or not np.all(wh > 0):
        raise ValueError(f"omega_h must be > 0 (and not empty), got {np.asarray(omega_h).tolist()!r}")
    steps = count(steps, "steps", 1)
    # all oscillators at once, omega = wh, h = 1 (only the product matters)
    w2 = wh[:, None] ** 2

    def f(X, t):
        return np.stack([X[:, 1], -w2 * X[:, 0]], axis=1)

    X = np.zeros((len(wh), 2, 1))
    X[:, 0, 0] = 1.0
    step = INTEGRATORS["implicit_euler"]
    jac = _oscillator_jacobian(wh)
    for n in range(steps):  # a loop over time steps
        X = step(f, X, float(n), 1.0, jac=jac)
    amplitude = np.hypot(X[:, 0, 0], X[:, 1, 0] / wh)
    return amplitude ** (1.0 / steps)


def _oscillator_jacobian(wh):
    """Sparse Jacobian of the stacked oscillators, for the flattened (n, 2, 1) state."""
    import scipy.sparse

    n = len(wh)
    rows = np.concatenate([2 * np.arange(n), 2 * np.arange(n) + 1])
    cols = np.concatenate([2 * np.arange(n) + 1, 2 * np.arange(n)])
    vals = np.concatenate([np.ones(n), -(wh**2)])
    J = scipy.sparse.csr_matrix((vals, (rows, cols)), shape=(2 * n, 2 * n))
    return lambda X, t: J


def cost_study(ks=(1e2, 1e4, 1e6, 1e8), m=1.0, methods=("symplectic_euler", "rk4", "implicit_euler"),
               T=1.0, implicit_step=0.01):
    """Cost of simulating `T` seconds of a spring at each method's largest stable step.

    Explicit methods run at 90% of their theoretical limit; implicit Euler at
    `implicit_step` whatever the stiffness. Cost is counted in right-hand-side
    evaluations (1 per step for symplectic Euler, 4 for RK4, about 3 for
    implicit Euler's Newton iterations on a linear problem) and measured in
    wall-clock seconds.

    Returns
    -------
    list of dict
        One row per (k, method): ``k``, ``method``, ``h``, ``steps``,
        ``evaluations``, ``seconds``.
    """
    from ..integrators.loop import integrate

    rows = []
    for k in ks:
        for method in methods:
            h = implicit_step if method == "implicit_euler" else 0.9 * theory_max_step(method, k, m)
            count = [0]
            f0 = oscillator(k, m)

            def f(X, t):
                count[0] += 1
                return f0(X, t)

            options = {"jac": _oscillator_jacobian(np.array([np.sqrt(k / m)]))} if method == "implicit_euler" else {}
            start = time.perf_counter()
            t, _ = integrate(f, [[[1.0], [0.0]]], 0.0, T, h, method=method, every=10**9, **options)
            rows.append({"k": k, "method": method, "h": h, "steps": int(np.ceil(T / h - 1e-9)),
                         "evaluations": count[0], "seconds": time.perf_counter() - start})
    return rows


def plot_stability(study, ax=None):
    """Log-log plot of measured (markers) and theoretical (lines) largest stable steps against k.

    Parameters
    ----------
    study : dict
        As returned by :func:`stability_study`.
    ax : matplotlib.axes.Axes, optional
        Where to draw (default: a new 6 x 4.5 inch figure).

    Returns
    -------
    matplotlib.figure.Figure
        The figure of `ax`: h (s) against k (N/m), one colour per stepper.
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 4.5))
    for i, (meth, h) in enumerate(study["h_max"].items()):
        color = f"C{i}"
        ok = (h > 0) & np.isfinite(h)
        label = f"{meth} (slope {study['slope'][meth]:.2f})" if ok.all() else f"{meth} (measured)"
        ax.loglog(study["k"][ok], h[ok], "osD^v"[i % 5], color=color, label=label, mfc="none" if i % 2 else color)
        theory = study["theory"][meth]
        if np.all((theory > 0) & np.isfinite(theory)):
            ax.loglog(study["k"], theory, "-", color=color, lw=1)
    ax.set_xlabel("spring stiffness k (N/m)")
    ax.set_ylabel("largest stable time step h (s)")
    ax.set_title(f"Stability limit, m = {study['m']} kg ({study['steps']}-step blow-up test)")
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    return ax.figure
