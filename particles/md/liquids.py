"""Starting a simple liquid: particles on a lattice, velocities at a temperature.

A molecular-dynamics run of a liquid starts from a state nobody knows. The
usual way in: put the particles on a face-centred cubic (FCC) lattice at the
wanted density (no two of them overlap, so the Lennard-Jones forces stay
moderate), draw Maxwell-Boltzmann velocities at the wanted temperature, and
let a thermostat melt and equilibrate the lattice
(:mod:`particles.md.thermostats`) before measuring anything.

An FCC cell of side ``a`` holds 4 particles, at ``(0, 0, 0)``,
``(1/2, 1/2, 0)``, ``(1/2, 0, 1/2)`` and ``(0, 1/2, 1/2)`` times ``a``; ``c``
cells along each axis give ``N = 4 c^3`` particles (500 for ``c = 5``, the
size of the NIST reference runs) in a periodic box of side ``c a`` with
``a = (4 / rho)^(1/3)``.

References
----------
.. [1] M. P. Allen and D. J. Tildesley, *Computer Simulation of Liquids*,
   2nd ed., Oxford University Press, 2017, section 5.6 (starting up).
"""

import numpy as np

from .._checks import as_float_array, positive_number
from .thermostats import kinetic_temperature

__all__ = ["fcc_lattice", "maxwell_boltzmann"]

_FCC_BASIS = np.array([[0.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.5, 0.0, 0.5], [0.0, 0.5, 0.5]])


def fcc_lattice(cells, density):
    """Positions of a face-centred cubic lattice filling a periodic box at a number density.

    Parameters
    ----------
    cells : int or sequence of 3 ints
        FCC cells along each axis (each >= 1).
    density : float
        Number density ``rho = N / V``, in particles per m^3 (``rho sigma^3``
        in reduced units), > 0.

    Returns
    -------
    x : ndarray, shape (4 prod(cells), 3)
        Positions, in metres, inside ``[0, L)`` (offset by a quarter of the
        spacing from the faces).
    box : ndarray, shape (3,)
        Side lengths ``L`` of the periodic box, in metres.

    Examples
    --------
    >>> x, box = fcc_lattice(5, density=0.86)
    >>> len(x), round(float(box[0]), 4), round(len(x) / float(np.prod(box)), 12)
    (500, 8.3462, 0.86)
    """
    c = np.broadcast_to(np.asarray(cells), (3,))
    if not np.issubdtype(c.dtype, np.integer) or np.any(c < 1):
        raise ValueError(f"cells must be a positive integer or 3 of them, got {cells!r}")
    a = (4.0 / positive_number(density, "density", "particles per m^3")) ** (1.0 / 3.0)
    corner = np.stack(np.meshgrid(*[np.arange(k) for k in c], indexing="ij"), axis=-1).reshape(-1, 1, 3)
    x = (corner + _FCC_BASIS + 0.25).reshape(-1, 3) * a
    return x, c * a


def maxwell_boltzmann(n, T, m=1.0, d=3, seed=None, k_B=1.0):
    """Random velocities at temperature `T`, with zero total momentum.

    Each component is drawn from the normal distribution of variance
    ``k_B T / m``; the centre-of-mass velocity is removed and the velocities
    are scaled so that the kinetic temperature
    (:func:`particles.md.thermostats.kinetic_temperature`, ``d (n - 1)``
    degrees of freedom) is exactly `T`.

    Parameters
    ----------
    n : int
        Number of particles, >= 2.
    T : float
        Temperature, > 0 (kelvin, or ``epsilon / k_B``).
    m : float or array_like, shape (n,)
        Masses, in kg.
    d : int
        Dimension of space.
    seed : int or numpy.random.Generator, optional
        Seed of the random numbers.
    k_B : float
        Boltzmann's constant in the model's units.

    Returns
    -------
    ndarray, shape (n, d)
        Velocities, in m/s.

    Examples
    --------
    >>> v = maxwell_boltzmann(500, T=0.85, seed=1)
    >>> round(kinetic_temperature(v), 12), bool(abs(v.sum(axis=0)).max() < 1e-12)
    (0.85, True)
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 2:
        raise ValueError(f"n must be an integer >= 2, got {n!r}")
    T = positive_number(T, "T", "kelvin")
    m = np.broadcast_to(as_float_array(m, "m", ndim=(0, 1)), (n,))
    if np.any(m <= 0):
        raise ValueError("m must be positive: every mass must be > 0 kg")
    rng = np.random.default_rng(seed)
    v = rng.standard_normal((n, d)) * np.sqrt(k_B * T / m)[:, None]
    v -= (m @ v) / m.sum()  # no motion of the centre of mass
    return v * np.sqrt(T / kinetic_temperature(v, m, k_B=k_B))
