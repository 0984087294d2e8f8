"""Molecular dynamics: a periodic box, thermostats, a liquid's initial state, and error bars.

* :mod:`particles.md.periodic`: periodic boxes: the minimum image, wrapping;
* :mod:`particles.md.thermostats`: :class:`Berendsen` and :class:`Langevin`, and the kinetic temperature;
* :mod:`particles.md.liquids`: an fcc lattice and Maxwell-Boltzmann velocities;
* :mod:`particles.md.statistics`: block averages of correlated samples (:func:`blocking`).
"""

from .liquids import fcc_lattice, maxwell_boltzmann
from .periodic import box_option, check_box, minimum_image, volume, wrap
from .statistics import Estimate, block_average, blocking
from .thermostats import Berendsen, Langevin, kinetic_temperature

__all__ = ["check_box", "box_option", "wrap", "minimum_image", "volume", "kinetic_temperature", "Berendsen",
           "Langevin", "fcc_lattice", "maxwell_boltzmann", "Estimate", "block_average", "blocking"]
