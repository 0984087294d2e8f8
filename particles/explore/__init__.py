"""Explorations: a simulation run for each value of a parameter, and a slider that shows them.

* :mod:`particles.explore.exploration`: :class:`Exploration` and the simulations it runs (damped spring,
  bouncing ball, curtain);
* :mod:`particles.explore.drop`: :func:`cloth_drop`, a cloth dropped on a ball on the floor with every
  stage of the cloth collisions (lecture 9);
* :mod:`particles.explore.figures`: their figures, and the slider player of pre-rendered images (the only
  drawing here).
"""

from .drop import cloth_drop
from .exploration import STATIC, Exploration, bouncing_ball, curtain_time_step, damped_spring, provot_passes
from .figures import (figure_png, plot_bounces, plot_cloth_drop, plot_damped_spring, plot_provot_passes,
                      plot_time_step, slider_player)

__all__ = ["Exploration", "STATIC", "damped_spring", "bouncing_ball", "curtain_time_step", "provot_passes",
           "cloth_drop", "figure_png", "slider_player", "plot_damped_spring", "plot_bounces", "plot_time_step",
           "plot_provot_passes", "plot_cloth_drop"]
