"""The hanging curtain of the lecture, with and without Provot's constraint.

A square cloth held by its two top corners falls from the horizontal under
gravity. With soft springs, the springs near the corners stretch far beyond
what real cloth allows ("excessive deformation after 200 iterations");
Provot's constraint keeps every structural and shear spring within 10%.
"""

import numpy as np

from .._checks import count, positive_number
from ..constraints import ProvotConstraint
from ..integrators.steppers import symplectic_euler
from ..massspring.cloth import cloth

__all__ = ["curtain", "provot_study", "plot_provot"]


def curtain(n=12, k=30.0):
    """The slide's curtain: n x n particles, 1 m square, soft springs, two pinned corners.

    Parameters
    ----------
    n : int
        Particles per side (>= 3).
    k : float
        Structural stiffness, in N/m (> 0); shear springs get ``k / 4`` and
        flexion springs ``k / 10``.

    Returns
    -------
    MassSpringSystem
        The cloth lying flat in the horizontal plane, at rest, held by its two
        top corners, with gravity and a light damping.
    """
    n = count(n, "n", 3)
    k = positive_number(k, "k", "N/m")
    return cloth(n, n, plane="horizontal", pins="top corners", k_structural=k, k_shear=k / 4,
                 k_flexion=k / 10, damping=0.002)


def provot_study(n=12, k=30.0, steps=200, h=0.005, max_strain=0.1, every=5):
    """Simulate the curtain for `steps` steps with and without the constraint.

    Parameters
    ----------
    n : int
        Particles per side (>= 3).
    k : float
        Structural stiffness, in N/m (> 0).
    steps : int
        Number of time steps of each run (>= 1).
    h : float
        Time step of symplectic Euler, in seconds (> 0).
    max_strain : float
        Largest relative elongation the constraint allows (> 0; 0.1 is 10%).
    every : int
        Record one state every `every` steps (>= 1).

    Returns
    -------
    dict
        ``"t"`` (recorded times), ``"strain"`` (dict ``"free"``/``"provot"`` ->
        largest structural strain at each recorded time), ``"X"`` (dict ->
        recorded states, shape (K, n^2, 2, 3)), ``"iterations"`` (projection
        passes per step), ``"tol"``, ``"max_strain"``, ``"system"`` (a curtain,
        for its springs and grid).
    """
    n, k = count(n, "n", 3), positive_number(k, "k", "N/m")
    steps, every = count(steps, "steps", 1), count(every, "every", 1)
    h = positive_number(h, "h", "s")
    max_strain = positive_number(max_strain, "max_strain")
    out = {"strain": {}, "X": {}, "max_strain": max_strain}
    for label in ("free", "provot"):
        c = curtain(n, k)
        step = symplectic_euler
        if label == "provot":
            provot = ProvotConstraint.from_system(c, max_strain=max_strain)
            step = provot.stepper(symplectic_euler)
        t, X = c.run(steps * h, h, method=step, every=every)
        out["t"] = t
        out["X"][label] = X
        out["strain"][label] = np.array([c.max_strain(Xk, "structural") for Xk in X])
    out["iterations"] = np.array([r.iterations for r in provot.history])
    out["tol"] = provot.tol
    out["system"] = c
    return out


def plot_provot(study):
    """Largest strain against time for both runs, and the final shapes side by side.

    Parameters
    ----------
    study : dict
        As returned by :func:`provot_study`.

    Returns
    -------
    matplotlib.figure.Figure
        Three panels: the largest strain (%) against time (s), and the final
        wireframes (m) without and with the constraint.
    """
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(12, 4))
    ax = fig.add_subplot(1, 3, 1)
    for label, strain in study["strain"].items():
        ax.plot(study["t"], 100 * strain, label="soft springs" if label == "free" else "with Provot's constraint")
    ax.axhline(100 * study["max_strain"], color="grey", ls=":", label="10% limit")
    ax.set_xlabel("time t (s)")
    ax.set_ylabel("largest spring strain (%)")
    ax.legend(fontsize=8)
    c = study["system"]
    ny, nx = c.grid_shape
    for i, label in enumerate(("free", "provot")):
        ax3 = fig.add_subplot(1, 3, 2 + i, projection="3d")
        x = study["X"][label][-1, :, 0].reshape(ny, nx, 3)
        ax3.plot_wireframe(x[..., 0], x[..., 1], x[..., 2], color="C0" if label == "free" else "C1", lw=0.6)
        ax3.set_title(f"{'soft springs' if label == 'free' else 'with Provot'}: t = {study['t'][-1]:.2f} s")
        ax3.set_xlim(-0.2, 1.2)
        ax3.set_ylim(-0.7, 0.7)
        ax3.set_zlim(-2.0, 0.2)
        ax3.set_xlabel("x (m)")
        ax3.set_zlabel("z (m)")
    fig.tight_layout()
    return fig
