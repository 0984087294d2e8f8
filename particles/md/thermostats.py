"""Thermostats: steppers that hold a particle system at a temperature.

Velocity Verlet conserves the energy: it samples the microcanonical (NVE)
ensemble. To compare with tables measured at a fixed temperature ``T``
(the canonical, NVT, ensemble) the system must exchange energy with a heat
bath. Two thermostats, both steppers ``step(f, X, t, h)`` that compose with
:meth:`particles.ParticleSystem.run` like any other:

* :class:`Berendsen`: after each step of an inner stepper (Verlet), scale
  all velocities by ``lambda = sqrt(1 + (h / tau) (T / T_now - 1))`` [1]_: the
  kinetic temperature relaxes to ``T`` in about ``tau``; ``tau <= h`` is plain
  velocity rescaling to ``T`` at every step. Deterministic, fast and robust
  from far out of equilibrium (melting a lattice), but it suppresses the
  fluctuations of the kinetic energy: it does *not* sample the canonical
  ensemble. Use it to equilibrate.
* :class:`Langevin`: each particle also feels a friction ``-gamma m v`` and a
  random force whose strength is fixed by the fluctuation-dissipation
  theorem. Integrated by the BAOAB splitting of Leimkuhler and Matthews [2]_
  (half kick B, half drift A, exact friction-and-noise update O, half drift,
  half kick), it samples the canonical ensemble, with configurational
  averages (energy, pressure) accurate to ``O(h^2)`` and very small
  constants even at the largest stable steps. The random numbers come from
  a seeded generator, so a run is reproducible. Use it to sample.

Why not Nose-Hoover? It is deterministic and canonical too, but it adds a
variable (the bath's momentum) that the state ``X = (x, v)`` has no room
for, and for small or stiff systems it can fail to be ergodic (the chain
version fixes that at the price of more variables). Langevin needs no extra
state, each particle is thermostatted locally, and it is never non-ergodic.

Both steppers end where the next step starts (``fsal``): with forces that
depend on the positions only, :meth:`particles.ParticleSystem.run` evaluates
the forces once per step.

References
----------
.. [1] H. J. C. Berendsen, J. P. M. Postma, W. F. van Gunsteren, A. DiNola and
   J. R. Haak, "Molecular dynamics with coupling to an external bath",
   J. Chem. Phys. 81, 3684-3690, 1984.
.. [2] B. Leimkuhler and C. Matthews, "Rational construction of stochastic
   numerical methods for molecular sampling", Applied Mathematics Research
   eXpress 2013(1), 34-56, 2013 (BAOAB).
"""

import numpy as np

from .._checks import as_float_array, count, method_name, nonnegative_number, positive_number
from ..integrators.common import check_arguments, evaluate, split_state
from ..integrators.steppers import INTEGRATORS

__all__ = ["kinetic_temperature", "Berendsen", "Langevin"]


def _masses(m, n):
    """Masses of shape (n,) from a number or an array of shape (n,), all > 0."""
    m = as_float_array(m, "m", ndim=(0, 1))
    if m.ndim == 1 and m.shape != (n,):
        raise ValueError(f"m must be a number or have shape ({n},), got shape {m.shape}")
    if np.any(m <= 0):
        raise ValueError("m must be positive: every mass must be > 0 kg")
    return np.broadcast_to(m, (n,))


def kinetic_temperature(v, m=1.0, dof=None, k_B=1.0):
    """Instantaneous temperature ``T = sum(m v^2) / (dof k_B)`` of the velocities `v`.

    Parameters
    ----------
    v : array_like, shape (n, d)
        Velocities, in m/s.
    m : float or array_like, shape (n,)
        Masses, in kg.
    dof : int, optional
        Degrees of freedom (default ``d (n - 1)``: the motion of the centre
        of mass, conserved by pair forces, is not thermal; ``d n`` for a
        single particle).
    k_B : float
        Boltzmann's constant in the model's units (1 in reduced units,
        1.380649e-23 J/K in SI).

    Returns
    -------
    float
        The temperature, in kelvin (or in units of ``epsilon / k_B``).

    Examples
    --------
    >>> kinetic_temperature([[1.0, 0.0], [-1.0, 0.0]])     # sum m v^2 = 2, dof = 2
    1.0
    """
    v = as_float_array(v, "v", ndim=2)
    n, d = v.shape
    m = _masses(m, n)
    dof = (d * max(n - 1, 1) if n > 1 else d) if dof is None else count(dof, "dof", least=1)
    return float(np.sum(m * np.einsum("ij,ij->i", v, v))) / (dof * positive_number(k_B, "k_B"))


class Berendsen:
    """Berendsen's weak coupling: an inner step, then all velocities scaled towards `T`.

    ``lambda^2 = 1 + c (T / T_now - 1)`` with ``c = min(h / tau, 1)`` and
    ``T_now`` the kinetic temperature after the inner step.

    Parameters
    ----------
    T : float
        Target temperature, > 0 (kelvin, or ``epsilon / k_B`` in reduced units).
    tau : float
        Relaxation time, in seconds, > 0; ``tau <= h`` rescales to exactly
        `T` at every step. About 100 steps is usual for equilibration.
    m : float or array_like, shape (n,)
        Masses, in kg (for the kinetic temperature).
    step : str or callable
        The inner stepper (default ``"verlet"``).
    dof : int, optional
        Degrees of freedom, as in :func:`kinetic_temperature`.
    k_B : float
        Boltzmann's constant in the model's units.

    Attributes
    ----------
    order, second_order_layout, fsal
        Those of the inner stepper (the rescaling changes velocities only).

    Raises
    ------
    ValueError
        When `T` or `tau` is not a positive finite number, or `step` unknown.

    Notes
    -----
    A system at rest (``T_now = 0``) cannot be scaled and stays at rest:
    give it velocities first. The rescaling keeps the total momentum if it
    is zero, not otherwise. It does not sample the canonical ensemble (the
    kinetic energy hardly fluctuates): use it to equilibrate, and
    :class:`Langevin` to sample.

    Examples
    --------
    >>> import numpy as np
    >>> from particles import ParticleSystem
    >>> ps = ParticleSystem([[0.0, 0.0], [5.0, 0.0]], v=[[1.0, 0.0], [-1.0, 0.0]])
    >>> _ = ps.run(0.1, h=0.01, method=Berendsen(T=4.0, tau=0.01))
    >>> round(kinetic_temperature(ps.X[:, 1]), 12)
    4.0
    """

    explicit = True

    def __init__(self, T, tau, m=1.0, step="verlet", dof=None, k_B=1.0):
        self.T = positive_number(T, "T", "kelvin")
        self.tau = positive_number(tau, "tau", "seconds")
        self.m = as_float_array(m, "m", ndim=(0, 1))
        self.step = method_name(step, INTEGRATORS, "step")
        self.dof = None if dof is None else count(dof, "dof", least=1)
        self.k_B = positive_number(k_B, "k_B")
        for attr in ("order", "second_order_layout", "fsal"):
            setattr(self, attr, getattr(self.step, attr, False))
        self.__name__ = f"berendsen({getattr(self.step, '__name__', type(self.step).__name__)})"

    def __call__(self, f, X, t, h, **options):
        X_new = self.step(f, X, t, h, **options)
        v = X_new[:, 1]
        T_now = kinetic_temperature(v, self.m, self.dof, self.k_B) if np.isfinite(v).all() else np.nan
        if T_now > 0:
            c = min(h / self.tau, 1.0)
            X_new[:, 1] *= np.sqrt(max(1.0 + c * (self.T / T_now - 1.0), 0.0))
        return X_new


class Langevin:
    """Langevin dynamics at temperature `T` by the BAOAB splitting: a thermostat that samples NVT.

    ``dv = a(x) dt - gamma v dt + sqrt(2 gamma k_B T / m) dW``, one step:

    * B: ``v += h/2 a(x)``;  A: ``x += h/2 v``;
    * O: ``v = c1 v + sqrt((1 - c1^2) k_B T / m) xi``, ``c1 = exp(-gamma h)``,
      ``xi`` standard normal (the exact solution of friction plus noise);
    * A: ``x += h/2 v``;  B: ``v += h/2 a(x_new)``.

    Parameters
    ----------
    T : float
        Temperature, > 0 (kelvin, or ``epsilon / k_B`` in reduced units).
    gamma : float
        Friction rate, in 1/s, >= 0 (0: velocity Verlet, no thermostat).
        About 1 / (a few hundred steps) perturbs the dynamics little and
        still thermalizes in ``1 / gamma``.
    m : float or array_like, shape (n,)
        Masses, in kg (the noise on a particle is ``sqrt(k_B T / m)``).
    seed : int or numpy.random.Generator, optional
        Seed of the random numbers: the same seed gives the same run.
    k_B : float
        Boltzmann's constant in the model's units.
    pinned : array_like of int, optional
        Particles left out of friction and noise (pass the system's
        :attr:`~particles.ParticleSystem.pinned`).

    Attributes
    ----------
    order : int
        2 (weak order: averages converge like ``h^2``).
    fsal : bool
        True: the last force is at the positions where the next step starts.
    rng : numpy.random.Generator
        The generator, advanced by every step.

    Raises
    ------
    ValueError
        When `T` is not a positive finite number, `gamma` negative, or `m`
        not positive (at the first step when its shape does not fit).

    Notes
    -----
    Forces that depend on the velocity are evaluated with the velocity at
    hand (the kick's start); the method is built for position-only forces.

    Examples
    --------
    >>> import numpy as np
    >>> from particles import ParticleSystem
    >>> gas = ParticleSystem(np.zeros((2000, 3)))
    >>> _ = gas.run(5.0, h=0.01, method=Langevin(T=2.0, gamma=5.0, seed=1))
    >>> round(kinetic_temperature(gas.X[:, 1], dof=3 * 2000), 1)
    2.0
    """

    order = 2
    explicit = True
    second_order_layout = True
    fsal = True
    __name__ = "langevin"

    def __init__(self, T, gamma, m=1.0, seed=None, k_B=1.0, pinned=()):
        self.T = positive_number(T, "T", "kelvin")
        self.gamma = nonnegative_number(gamma, "gamma", "1/s")
        self.m = as_float_array(m, "m", ndim=(0, 1))
        if np.any(self.m <= 0):
            raise ValueError("m must be positive: every mass must be > 0 kg")
        self.k_B = positive_number(k_B, "k_B")
        self.rng = np.random.default_rng(seed)
        self.pinned = np.asarray(pinned, dtype=np.int64).reshape(-1)

    def __call__(self, f, X, t, h):
        X, h = check_arguments(X, t, h)
        x, v = split_state(X)
        n, d = x.shape
        c1 = np.full(n, np.exp(-self.gamma * h))  # velocity kept by the friction over h
        sigma = np.sqrt(self.k_B * self.T / _masses(self.m, n))  # thermal speed per coordinate, m/s
        c1[self.pinned], sigma[self.pinned] = 1.0, 0.0
        scale = np.sqrt(1.0 - c1 * c1) * sigma
        a = evaluate(f, X, t)[:, 1]
        X_new = np.empty_like(X)
        x_new, v_new = X_new[:, 0], X_new[:, 1]
        np.multiply(a, 0.5 * h, out=v_new)
        v_new += v  # B
        np.multiply(v_new, 0.5 * h, out=x_new)
        x_new += x  # A
        xi = self.rng.standard_normal((d, n))
        for k in range(d):  # a loop over the d coordinates: O, the exact friction and noise update
            v_new[:, k] *= c1
            v_new[:, k] += scale * xi[k]
        x_new += 0.5 * h * v_new  # A
        a_new = evaluate(f, X_new, t + h)[:, 1]
        v_new += 0.5 * h * a_new  # B
        return X_new
