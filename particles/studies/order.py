"""Order of convergence: global error against step size on problems with exact solutions.

Halving ``h`` divides the error of a method of order ``p`` by about ``2^p``;
on a log-log plot of error against ``h`` the points fall on a line of slope
``p``, which :func:`fit_order` measures.
"""

import numpy as np

from .._checks import as_float_array
from ..integrators.loop import integrate
from ..integrators.steppers import INTEGRATORS
from ..problems import Problem, get_problem

__all__ = ["fit_order", "global_error", "convergence_study", "plot_convergence", "format_table"]


def fit_order(h, error):
    """Observed order of convergence: the slope of ``log(error)`` against ``log(h)``.

    Fits ``error ~ C h^p`` by least squares in log-log coordinates.

    Parameters
    ----------
    h : array_like, shape (k,)
        Step sizes, > 0, at least two distinct values.
    error : array_like, shape (k,)
        Errors, > 0.

    Returns
    -------
    p : float
        The fitted order.

    Examples
    --------
    >>> round(fit_order([0.1, 0.05, 0.025], [1e-2, 2.5e-3, 6.25e-4]), 6)
    2.0
    """
    h = as_float_array(h, "h", ndim=1)
    error = as_float_array(error, "error", shape=h.shape)
    if len(h) < 2 or len(np.unique(h)) < 2:
        raise ValueError("h must hold at least two different step sizes")
    if np.any(h <= 0) or np.any(error <= 0):
        raise ValueError("h and error must be > 0 to be fitted in log-log coordinates")
    slope, _ = np.polyfit(np.log(h), np.log(error), 1)
    return float(slope)


def global_error(problem, method, n_steps):
    """Max-norm error at ``problem.t1`` after `n_steps` equal steps of `method`.

    Parameters
    ----------
    problem : particles.problems.Problem
        An initial value problem with its exact solution.
    method : str
        A key of :data:`particles.integrators.INTEGRATORS`.
    n_steps : int
        Number of equal steps from ``problem.t0`` to ``problem.t1``.

    Returns
    -------
    float
        ``max |X_N - X(t1)|`` over all components, in the units of the state.
    """
    h = (problem.t1 - problem.t0) / n_steps
    _, X = integrate(problem.f, problem.X0, problem.t0, problem.t1, h, method=method, every=n_steps)
    return problem.error(X[-1])


def convergence_study(problem="harmonic_oscillator", methods=None, n_steps=None):
    """Global error against step size for several steppers, and fitted orders.

    Parameters
    ----------
    problem : str or Problem
        A :class:`particles.problems.Problem` or a name from
        :data:`particles.problems.PROBLEMS`.
    methods : sequence of str, optional
        Stepper names (default: every stepper that applies to the problem;
        the symplectic ones need a second-order problem).
    n_steps : sequence of int, optional
        Numbers of steps over ``[t0, t1]`` (default 64, 128, ..., 1024).

    Returns
    -------
    dict
        ``"h"`` (ndarray, shape (k,)), ``"error"`` (dict method -> ndarray,
        shape (k,)), ``"order"`` (dict method -> fitted order),
        ``"expected"`` (dict method -> ``step.order``), ``"problem"`` (name).
    """
    if not isinstance(problem, Problem):
        problem = get_problem(problem)
    if methods is None:
        methods = [
            name for name, step in INTEGRATORS.items()
            if problem.second_order or not step.second_order_layout
        ]
    n_steps = np.array([64, 128, 256, 512, 1024] if n_steps is None else n_steps)
    h = (problem.t1 - problem.t0) / n_steps
    errors = {m: np.array([global_error(problem, m, int(k)) for k in n_steps]) for m in methods}
    return {
        "problem": problem.name,
        "h": h,
        "error": errors,
        "order": {m: fit_order(h, e) for m, e in errors.items()},
        "expected": {m: INTEGRATORS[m].order for m in methods},
    }


def format_table(study):
    """A plain-text table of a :func:`convergence_study`: method, expected and observed order.

    Parameters
    ----------
    study : dict
        As returned by :func:`convergence_study`.

    Returns
    -------
    str
        One line per method, with the error at the smallest step.
    """
    lines = [f"{'method':<18}{'expected':>9}{'observed':>10}   error at smallest h",
             "-" * 60]
    for m, p in study["order"].items():
        lines.append(f"{m:<18}{study['expected'][m]:>9d}{p:>10.2f}   {study['error'][m][-1]:.2e}")
    return "\n".join(lines)


# One look per stepper. Pairs that give (nearly) the same errors -- midpoint and
# trapezoid are identical on linear problems, implicit and explicit Euler differ
# little -- get a small filled marker on a solid line against a large open
# marker on a dashed line, so that neither hides the other.
_STYLES = {
    "euler": dict(marker="o", linestyle="-", markersize=4),
    "implicit_euler": dict(marker="s", linestyle="--", markersize=9, fillstyle="none"),
    "midpoint": dict(marker="^", linestyle="-", markersize=4),
    "trapezoid": dict(marker="D", linestyle="--", markersize=9, fillstyle="none"),
    "rk4": dict(marker="v", linestyle="-.", markersize=6),
    "symplectic_euler": dict(marker="x", linestyle=":", markersize=8),
    "verlet": dict(marker="P", linestyle=(0, (5, 1, 1, 1)), markersize=7),
}
_FALLBACK_MARKERS = ["*", "h", "<", ">", "p", "X"]
_FALLBACK_LINES = ["-", "--", "-.", ":"]


def _style(method, k):
    """Marker and line style of `method`, the k-th line of the plot."""
    if method in _STYLES:
        return dict(_STYLES[method])
    return dict(marker=_FALLBACK_MARKERS[k % len(_FALLBACK_MARKERS)],
                linestyle=_FALLBACK_LINES[k % len(_FALLBACK_LINES)], markersize=7)


def plot_convergence(study, ax=None):
    """Log-log plot of global error against step size, one line per method.

    Every method gets its own marker and line style, so that methods with
    (nearly) equal errors stay visible on top of each other; the step-size
    axis is labelled at each step size of the study.

    Parameters
    ----------
    study : dict
        The result of :func:`convergence_study`.
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter, NullLocator

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 4.5))

    h = np.asarray(study["h"], dtype=float)
    for k, (m, e) in enumerate(study["error"].items()):
        ax.loglog(h, e, label=f"{m} (slope {study['order'][m]:.2f})", **_style(m, k))
    # a study spans about one decade of h: one labelled tick per step size
    ax.xaxis.set_major_locator(FixedLocator(np.sort(h)))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:.3g}"))
    ax.xaxis.set_minor_locator(NullLocator())
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("time step h (s)")
    ax.set_ylabel("global error at t1")
    ax.set_title(f"Convergence on the {study['problem'].replace('_', ' ')}")
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    return ax.figure
