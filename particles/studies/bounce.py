"""The bouncing-ball study: restitution and the two fixes of the overshooting problem, measured.

A ball dropped from height ``H0`` on the floor ``y = 0`` under gravity:

* with restitution ``eps`` each bounce reaches ``eps^2`` of the previous
  height (the speed at impact is ``sqrt(2 g H)`` and is scaled by ``eps``);
* with ``eps = 1`` the height should stay ``H0`` forever.

``"backtrack"`` reproduces both to round-off with an exact stepper
(velocity Verlet or RK4 under constant gravity); ``"project"`` moves the
ball up to the floor at each bounce and so adds ``m g d`` of energy, where
``d`` (up to ``|v| h``) is how far it had sunk in: the ball climbs.
The functions return data; :func:`plot_bounce_study` draws the lecture's
figure.
"""

import numpy as np

from .._checks import nonnegative_number, positive_number
from ..collisions.collider import Collider
from ..collisions.surfaces import Plane
from ..forces.fields import Gravity
from ..system import ParticleSystem

__all__ = ["bounce_heights", "bounce_study", "plot_bounce_study", "format_bounce_table"]

G = 9.81


def bounce_heights(method="backtrack", restitution=1.0, bounces=20, h=0.01, stepper="verlet", height=1.0):
    """Heights of the successive arcs of a ball dropped on a floor.

    Parameters
    ----------
    method : {"backtrack", "project"}
    restitution : float
        ``eps`` in [0, 1].
    bounces : int
        Number of bounces to simulate (about).
    h : float
        Time step, in seconds.
    stepper : str
        ODE stepper.
    height : float
        Drop height ``H0``, in metres.

    Returns
    -------
    heights : ndarray, shape (k,)
        Top of each arc, ``y + v_y^2 / (2 g)`` at the states between two
        contacts (exact on a ballistic arc), starting with the drop height.
    contacts : Contacts
    """
    restitution = nonnegative_number(restitution, "restitution")
    h = positive_number(h, "h", "seconds")
    height = positive_number(height, "height", "metres")
    ball = ParticleSystem([[0.0, height]], forces=[Gravity([0.0, -G])])
    floor = Collider(Plane([0.0, 0.0], [0.0, 1.0]), restitution=restitution, method=method)
    flight = 2 * np.sqrt(2 * height / G)  # time between the first two bounces
    t_end = flight * (0.5 + sum(max(restitution, 0.05) ** k for k in range(1, bounces + 1)))
    t, X, contacts = floor.run(ball, 1.3 * t_end if method == "project" else t_end, h, method=stepper)
    top = X[:, 0, 0, 1] + X[:, 0, 1, 1] ** 2 / (2 * G)
    edges = np.concatenate([[-np.inf], contacts.time, [np.inf]])  # the formula holds on part of an arc too
    arcs = [(t > a) & (t < b) for a, b in zip(edges[:-1], edges[1:])]
    return np.array([top[arc].mean() for arc in arcs if arc.any()])[:bounces + 1], contacts


def bounce_study(restitutions=(1.0, 0.8), methods=("backtrack", "project"), bounces=20, h=0.01):
    """Heights per bounce for each method and restitution, with the summary figures.

    Returns
    -------
    dict
        ``"heights"``: dict ``(method, eps)`` -> ndarray, in metres;
        ``"drift"``: dict ``(method, eps)`` -> largest relative error of the
        heights against ``H0 eps^(2k)`` over the bounces; ``"ratio"``: dict
        ``(method, eps)`` -> ``(min, max)`` of the successive height ratios
        ``H_k / H_(k-1)`` (``eps^2`` for every bounce when the response is
        exact); ``"h"``: the time step, in seconds.
    """
    heights, drift, ratio = {}, {}, {}
    for method in methods:  # a loop over the cases of the study
        for eps in restitutions:
            hk, _ = bounce_heights(method, eps, bounces if eps == 1 else 6, h)
            expected = eps ** (2 * np.arange(len(hk)))
            heights[method, eps] = hk
            drift[method, eps] = float(np.max(np.abs(hk / expected - 1.0)))
            r = hk[1:] / hk[:-1]
            ratio[method, eps] = (float(r.min()), float(r.max()))
    return {"heights": heights, "drift": drift, "ratio": ratio, "h": h}


def format_bounce_table(study):
    """The study as a text table, one line per case.

    Parameters
    ----------
    study : dict
        As returned by :func:`bounce_study`.

    Returns
    -------
    str
        Columns: method, ``eps``, number of bounces, the largest relative
        error ``|H_k / (H0 eps^(2k)) - 1|`` and the range (min to max) of the
        successive height ratios ``H_k / H_(k-1)``, to compare with ``eps^2``.
    """
    error, ratio = "max |H_k / (H0 eps^2k) - 1|", "H_k / H_k-1, min to max"
    header = f"{'method':<10}{'eps':>5}{'bounces':>9}{error:>30}{ratio:>26}"
    lines = [header, "-" * len(header)]
    for (method, eps), d in study["drift"].items():
        lo, hi = study["ratio"][method, eps]
        lines.append(f"{method:<10}{eps:>5.2f}{len(study['heights'][method, eps]) - 1:>9d}{d:>30.2e}"
                     f"{f'{lo:.4f} to {hi:.4f}':>26}")
    return "\n".join(lines)


def plot_bounce_study(study, ax=None):
    """Bounce height against bounce number, exact law dashed; returns the figure."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 4.5))
    for (method, eps), hk in study["heights"].items():
        k = np.arange(len(hk))
        ax.plot(k, hk, "o-" if method == "backtrack" else "s-", ms=3, label=f"{method}, eps = {eps:g}")
        ax.plot(k, eps ** (2 * k), "k--", lw=0.8)
    from matplotlib.ticker import MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("bounce k")
    ax.set_ylabel("height of arc k (m)")
    ax.set_title(f"Dropped ball, h = {study['h']} s (dashed: eps^(2k))")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return ax.figure
