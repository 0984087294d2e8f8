"""Discretization dependence: is a finer cloth the same cloth?

The same 1 m x 1 m cloth, hanging from its top edge, is built at several
resolutions with ``scaling="naive"`` (per-particle mass and per-spring
stiffness fixed, calibrated at the coarsest grid) and ``scaling="physical"``
(mass from density and area, stiffness from modulus and rest length; see
:mod:`particles.massspring`). Measured at each resolution:

* the static sag (drop of the lowest point below its rest position);
* the period of the cloth's vertical bounce when released unstretched;
* the largest stable step of symplectic Euler, ``2 / omega_max``.

With physical scaling the first two converge; the stable step shrinks in
proportion to the grid spacing (2D cloth: ``k`` stays the same while
``m ~ dx^2``, so ``omega_max ~ 1 / dx``). With naive constants the cloth gets
heavier and softer as it is refined.
"""

import numpy as np

from .._checks import count, positive_number
from ..implicit.statics import relax
from ..massspring.cloth import cloth
from .order import fit_order

__all__ = ["hanging_cloth", "static_sag", "bounce_period", "discretization_study", "plot_discretization"]


def hanging_cloth(n, scaling, reference=8, **material):
    """The study's cloth: n x n particles hanging from the top edge, no damping.

    Parameters
    ----------
    n : int
        Particles per side (>= 3) of the 1 m x 1 m sheet.
    scaling : {"naive", "physical"}
        How masses and stiffnesses follow the resolution (see
        :func:`particles.massspring.cloth`).
    reference : int
        Resolution at which the naive constants are calibrated (>= 3).
    **material
        Other keywords of :func:`particles.massspring.cloth` (``areal_density``
        in kg/m^2, ``stretch_modulus`` in N/m, ...).

    Returns
    -------
    MassSpringSystem
        The flat cloth at rest in the vertical plane, its top row pinned.
    """
    n = count(n, "n", 3)
    return cloth(n, n, scaling=scaling, pins="top edge", reference=reference, **material)


def static_sag(system):
    """Drop (m) of the lowest particle below its position in the unstretched cloth, at equilibrium.

    Parameters
    ----------
    system : MassSpringSystem
        A hanging cloth, flat and at rest (as made by :func:`hanging_cloth`);
        it is relaxed to its equilibrium in place.

    Returns
    -------
    float
        The sag, in metres (> 0 for a cloth hanging under gravity).
    """
    z0 = system.X[:, 0, 2].min()
    relax(system, h=0.2)
    return float(z0 - system.X[:, 0, 2].min())


def bounce_period(system, periods=2, safety=0.5):
    """Period (s) of the vertical bounce of a cloth released unstretched, by simulation.

    Symplectic Euler at `safety` times its stability limit; the period is the
    mean time between successive highest points of the centre of mass.

    Parameters
    ----------
    system : MassSpringSystem
        A hanging cloth, flat and at rest; it is advanced in place.
    periods : int
        Number of periods to average over (>= 1).
    safety : float
        Time step as a fraction of ``system.max_stable_step()`` (0 < safety <= 1).

    Returns
    -------
    float
        The period in seconds, or NaN if fewer than two highest points were
        seen within ``20 / sqrt(g)`` seconds.
    """
    periods = count(periods, "periods", 1)
    safety = positive_number(safety, "safety")
    if safety > 1:
        raise ValueError(f"safety must be in (0, 1], got {safety!r}")
    h = safety * system.max_stable_step()
    g = 9.81
    z = []
    # simulate in chunks until enough maxima of the centre of mass are seen
    while True:
        t, X = system.run(system.t + 0.25, h, method="symplectic_euler")
        z.extend((X[1:, :, 0, 2] @ system.m) / system.m.sum())
        zc = np.array(z)
        peaks = np.flatnonzero((zc[1:-1] > zc[:-2]) & (zc[1:-1] >= zc[2:])) + 1
        if len(peaks) >= periods + 1 or system.t > 20.0 / np.sqrt(g):
            break
    if len(peaks) < 2:
        return np.nan
    return float(np.mean(np.diff(peaks)) * h)


def discretization_study(resolutions=(8, 16, 32), reference=8):
    """Sag, bounce period and stable step at each resolution, for both scalings.

    Returns
    -------
    dict
        ``"n"``, ``"spacing"`` (m); for each of ``"naive"`` and ``"physical"``:
        dict with ``"sag"``, ``"period"``, ``"h_max"`` arrays, and
        ``"h_exponent"``: fitted exponent ``p`` in ``h_max ~ spacing^p``.
    """
    n = np.asarray(resolutions)
    out = {"n": n, "spacing": 1.0 / (n - 1)}
    for scaling in ("naive", "physical"):
        sag, period, h_max = [], [], []
        for res in n:
            sag.append(static_sag(hanging_cloth(res, scaling, reference)))
            c = hanging_cloth(res, scaling, reference)
            h_max.append(c.max_stable_step())
            period.append(bounce_period(c))
        h_max = np.array(h_max)
        out[scaling] = {"sag": np.array(sag), "period": np.array(period), "h_max": h_max,
                        "h_exponent": fit_order(out["spacing"], h_max)}
    return out


def plot_discretization(study):
    """Three panels against the number of particles per side: sag, period, stable step.

    Parameters
    ----------
    study : dict
        As returned by :func:`discretization_study`.

    Returns
    -------
    matplotlib.figure.Figure
        The static sag (mm) and the bounce period (s) against the particles per
        side, and the largest stable step (s) against the grid spacing (m), log-log.
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    labels = {"naive": "naive constants", "physical": "physical scaling"}
    for scaling, style in (("naive", "o-"), ("physical", "s-")):
        data = study[scaling]
        axes[0].plot(study["n"], 1000 * data["sag"], style, label=labels[scaling])
        axes[1].plot(study["n"], data["period"], style, label=labels[scaling])
        axes[2].loglog(study["spacing"], data["h_max"], style,
                       label=f"{labels[scaling]} (h ~ dx^{data['h_exponent']:.2f})")
    axes[0].set_ylabel("static sag (mm)")
    axes[1].set_ylabel("bounce period (s)")
    axes[2].set_ylabel("largest stable step of symplectic Euler (s)")
    axes[2].set_xlabel("grid spacing dx (m)")
    from matplotlib.ticker import NullFormatter

    axes[2].xaxis.set_minor_formatter(NullFormatter())
    axes[2].yaxis.set_minor_formatter(NullFormatter())
    for ax in axes[:2]:
        ax.set_xlabel("particles per side")
        ax.set_xticks(study["n"])
    for ax in axes:
        ax.legend(fontsize=8)
        ax.grid(True, alpha=0.3)
    fig.suptitle("The same 1 m cloth at several resolutions")
    fig.tight_layout()
    return fig
