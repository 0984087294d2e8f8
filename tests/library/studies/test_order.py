"""Convergence orders of the steppers (particles.studies.order): the convergence plot."""

import numpy as np

from particles.integrators import INTEGRATORS

ALL = list(INTEGRATORS)


def test_convergence_plot_lines_are_distinguishable_and_h_axis_labelled():
    """Every method has its own marker and line style; the h axis labels every step size."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from particles.studies import convergence_study, plot_convergence

    study = convergence_study("harmonic_oscillator", n_steps=[16, 32, 64, 128])
    fig = plot_convergence(study)
    try:
        ax = fig.axes[0]
        fig.canvas.draw()
        lines = ax.get_lines()
        assert len(lines) == len(ALL)
        looks = {(ln.get_marker(), str(ln.get_linestyle()), ln.get_markersize(), ln.get_fillstyle()) for ln in lines}
        assert len(looks) == len(lines)
        by_name = {ln.get_label().split()[0]: ln for ln in lines}
        for a, b in [("midpoint", "trapezoid"), ("euler", "implicit_euler")]:
            la, lb = by_name[a], by_name[b]
            assert la.get_marker() != lb.get_marker() and la.get_linestyle() != lb.get_linestyle()
            assert la.get_markersize() < lb.get_markersize() and lb.get_fillstyle() == "none"
        labels = [t.get_text() for t in ax.get_xticklabels() if t.get_text()]
        assert len(labels) == 4
        np.testing.assert_allclose(sorted(float(s) for s in labels), np.sort(study["h"]), rtol=1e-2)
    finally:
        plt.close(fig)
