"""The cloths of the implicit solvers' tests (issue 13's stiff cloth among them), and their energy."""

import numpy as np

from particles.massspring import cloth


def stiff_naive_cloth(**options):
    """A 16 x 16 cloth with naive constants (5000 N/m per structural spring): symplectic Euler needs h < 1e-3 s."""
    return cloth(16, 16, k_structural=5000.0, k_shear=1250.0, k_flexion=500.0, **options)


def energy(c, X):
    """The total energy (kinetic + potential) of system `c` in state `X`."""
    return c.kinetic_energy(X) + c.potential_energy(X)


def readme_cloth(n, **options):
    """The README's stiff cloth (5000 N/m, physical scaling), n x n, lying flat, held by its top corners."""
    return cloth(n, n, scaling="physical", areal_density=0.2, stretch_modulus=5000.0, plane="horizontal", **options)


def largest_rise(E):
    """The largest energy gain over any stretch of a run, max over k of E[k] - min(E[:k + 1])."""
    E = np.asarray(E)
    return float(np.max(E - np.minimum.accumulate(E)))


def small_cloth():
    """A soft 5 x 5 cloth, 0.4 m square, lying flat: cheap enough for a fine reference run."""
    return cloth(5, 5, width=0.4, height=0.4, mass=0.01, k_structural=20.0, k_shear=5.0, k_flexion=2.0,
                 plane="horizontal")
