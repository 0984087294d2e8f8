"""Births and deaths: particles added to and removed from a system, their attributes kept aligned.

:class:`Population` is a base class of :class:`~particles.system.ParticleSystem`: its methods change the
number of particles (emitters add, lifetimes remove) and keep the masses, pins and per-particle
attributes (birth time, colour...) aligned with the state. Forces that cache per-particle data are told
through their ``reset()``.
"""

import numpy as np

from ._checks import as_float_array

__all__ = ["Population"]


class Population:
    """Particles that come and go (a base class of :class:`~particles.system.ParticleSystem`).

    It uses the system's ``X``, ``m``, ``pinned``, ``forces``, ``attributes``, ``_fill`` and ``_changes``.
    """

    def define_attribute(self, name, fill=0.0, shape=(), dtype=float):
        """Create a per-particle attribute, kept aligned when particles come and go.

        Parameters
        ----------
        name : str
            Key in :attr:`attributes`.
        fill : scalar or array_like of shape `shape`
            Value of existing particles, and of new particles added without it.
        shape : tuple of int
            Shape of the value per particle (``()`` for a number, ``(3,)`` for
            an RGB colour).
        dtype : data-type

        Returns
        -------
        ndarray, shape (n,) + shape
            The new attribute array (also ``self.attributes[name]``).
        """
        if not isinstance(name, str) or not name:
            raise ValueError(f"name must be a non-empty string, got {name!r}")
        if name in self.attributes:
            raise ValueError(f"name {name!r} is already an attribute of this system")
        shape = tuple(int(k) for k in np.atleast_1d(shape)) if shape != () else ()
        try:
            fill = np.broadcast_to(np.asarray(fill, dtype=dtype), shape).copy()
        except ValueError:
            raise ValueError(f"fill must have shape {shape}, got {np.shape(fill)}") from None
        self._fill[name] = fill
        self.attributes[name] = np.broadcast_to(fill, (self.n,) + shape).copy()
        return self.attributes[name]

    def add_particles(self, x, v=None, m=1.0, **attributes):
        """Append particles to the system (emitters use this); returns their indices.

        Parameters
        ----------
        x : array_like, shape (k, d)
            Positions of the new particles, in metres.
        v : array_like, shape (k, d), optional
            Velocities, in m/s (default zero).
        m : float or array_like, shape (k,)
            Masses, in kg, > 0.
        **attributes : array_like, shape (k,) + attribute shape, or one value
            Values of attributes made with :meth:`define_attribute`; missing
            ones get that attribute's `fill`.

        Returns
        -------
        ndarray of int, shape (k,)
            Indices of the new particles (the last `k`). New particles are not pinned.

        Notes
        -----
        The state stays in Fortran order (see the class Notes). Forces that
        cache per-particle data (a neighbour list) are told through their
        ``reset()`` method when they have one.
        """
        x = as_float_array(x, "x", shape=(None, self.d))
        k = len(x)
        v = np.zeros_like(x) if v is None else as_float_array(v, "v", shape=(k, self.d))
        m = as_float_array(m, "m", ndim=(0, 1))
        m = np.broadcast_to(m, (k,)) if m.ndim == 0 else m
        if m.shape != (k,):
            raise ValueError(f"m must be a number or have shape ({k},), got shape {m.shape}")
        if np.any(m <= 0):
            raise ValueError("m must be positive: every mass must be > 0 kg")
        unknown = sorted(set(attributes) - set(self.attributes))
        if unknown:
            raise ValueError(
                f"unknown attributes {unknown}; create them first with define_attribute "
                f"(known: {sorted(self.attributes)})"
            )
        new = {}
        for name, values in self.attributes.items():
            value = attributes.get(name, self._fill[name])
            try:
                new[name] = np.broadcast_to(np.asarray(value, dtype=values.dtype), (k,) + values.shape[1:])
            except ValueError:
                raise ValueError(
                    f"attribute {name!r} must have shape {(k,) + values.shape[1:]}, got {np.shape(value)}"
                ) from None
        start = self.n
        X_new = np.empty((k, 2, self.d))
        X_new[:, 0], X_new[:, 1] = x, v
        self.X = np.asfortranarray(np.concatenate([self.X, X_new]))
        self.m = np.concatenate([self.m, m])
        for name, values in new.items():
            self.attributes[name] = np.concatenate([self.attributes[name], values])
        self._forces_changed()
        return np.arange(start, start + k)

    def remove_particles(self, which):
        """Remove particles, keeping masses, pins and attributes aligned.

        Parameters
        ----------
        which : array_like of bool, shape (n,), or of int
            A mask of the particles to remove, or their indices.

        Returns
        -------
        keep : ndarray of int, shape (n_left,)
            Old indices of the particles that remain, in order: particle
            ``keep[i]`` is now particle ``i``.

        Notes
        -----
        Forces that store particle indices (springs) are not renumbered:
        remove particles only from systems whose forces act on each particle
        alone or find their pairs anew (gravity, fields, Lennard-Jones, boids).
        """
        which = np.asarray(which)
        if which.dtype == bool:
            if which.shape != (self.n,):
                raise ValueError(f"which as a boolean mask must have shape ({self.n},), got {which.shape}")
            gone = which
        else:
            if which.size and (which.ndim != 1 or not np.issubdtype(which.dtype, np.integer)):
                raise ValueError(f"which must be particle indices or a boolean mask, got {which!r}")
            if np.any((which < -self.n) | (which >= self.n)):
                raise ValueError(f"which indices must lie in [0, {self.n}), got {which.tolist()}")
            gone = np.zeros(self.n, dtype=bool)
            gone[which.astype(int) % max(self.n, 1)] = True
        keep = np.flatnonzero(~gone)
        if len(keep) == self.n:
            return keep
        self.X = np.asfortranarray(self.X[keep])
        self.m = self.m[keep]
        for name in self.attributes:
            self.attributes[name] = self.attributes[name][keep]
        new_index = np.cumsum(~gone) - 1  # old index -> new index, for the survivors
        self.pinned = new_index[self.pinned[~gone[self.pinned]]]
        self._forces_changed()
        return keep

    def _forces_changed(self):
        """Tell forces with cached per-particle data that the particles changed."""
        self._changes += 1
        for force in self.forces:
            reset = getattr(force, "reset", None)
            if callable(reset):
                reset()
