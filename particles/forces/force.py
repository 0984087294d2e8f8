"""The Force base class: what every force of the library is, and the contract it keeps.

A force is a small object with one method::

    force.add_to(F, x, v, t, m)    # F += this force, F shape (n, d)

where ``x`` and ``v`` are positions and velocities (shape (n, d)), ``t`` the
time and ``m`` the masses (shape (n,)). The particle system sums all forces in
one place (:meth:`particles.ParticleSystem.total_force`). Calling a force,
``force(x, v, t, m)``, returns its contribution alone, which is handy for
testing and plotting it. The contract every force keeps (it does not modify
its inputs, conservative forces are minus the gradient of their
``potential_energy``, internal forces conserve momentum) is tested for every
subclass in ``tests/library/forces/test_force_contract.py``.
"""

import numpy as np

from .._checks import as_float_array, finite_real

__all__ = ["Force"]


class Force:
    """Base class: subclasses implement :meth:`add_to`.

    Attributes
    ----------
    uses_velocity, uses_time : bool
        Whether the force depends on the velocities and on the time. Both
        default to True (always safe); a force that depends on positions
        only sets them False, which lets :meth:`particles.ParticleSystem.run`
        reuse the force at the end of a velocity-Verlet step as the force at
        the start of the next one instead of computing it again.
    """

    uses_velocity = True
    uses_time = True
    _compiled_role = None

    def add_to(self, F, x, v, t, m):
        """Add this force into `F` (shape (n, d), newtons), in place."""
        raise NotImplementedError

    @property
    def compiled_role(self):
        """What the compiled step (:mod:`particles.massspring.compiled_step`) does with this force, or None (it calls ``add_to``).

        ``"springs"`` and ``"bending"``: computed in the step's block pass;
        ``"gravity"``, ``"damping"`` and ``"wind"``: added in the update of
        each particle; ``"clamp"``: a compiled kernel of its own. A class
        declares its role in ``_compiled_role``; the role holds only
        while ``add_to`` is that class's own, so that a subclass with another
        force law is added by its own ``add_to`` (None: the step calls it).
        """
        for cls in type(self).__mro__:  # a loop over the few classes of the force's lineage
            if "_compiled_role" in cls.__dict__:
                return cls._compiled_role if type(self).add_to is cls.add_to else None
        return None

    def __call__(self, x, v=None, t=0.0, m=1.0):
        """This force alone, for positions `x` and velocities `v`.

        Parameters
        ----------
        x : array_like, shape (n, d)
            Positions, in metres.
        v : array_like, shape (n, d), optional
            Velocities, in m/s (default zero).
        t : float
            Time, in seconds.
        m : float or array_like, shape (n,)
            Masses, in kg, > 0.

        Returns
        -------
        ndarray, shape (n, d)
            The force on each particle, in newtons.
        """
        x = as_float_array(x, "x", ndim=2)
        v = np.zeros_like(x) if v is None else as_float_array(v, "v", shape=x.shape)
        m = as_float_array(m, "m", ndim=(0, 1))
        if m.ndim == 1 and m.shape != (len(x),):
            raise ValueError(f"m must be a number or have shape ({len(x)},), got shape {m.shape}")
        if np.any(m <= 0):
            raise ValueError("m must be positive: every mass must be > 0 kg")
        m = np.broadcast_to(m, (len(x),))
        t = finite_real(t, "t", "seconds")
        F = np.zeros_like(x)
        self.add_to(F, x, v, t, m)
        return F

    def __repr__(self):
        fields = ", ".join(f"{k}={v!r}" for k, v in vars(self).items() if not k.startswith("_"))
        return f"{type(self).__name__}({fields})"
