"""Particle effects and flocks: emitters, their distributions, colours, and Reynolds' boids.

* :mod:`particles.effects.emitters`: :class:`Emitter` and :class:`ParticleEmitter`, particles born with
  lifetimes;
* :mod:`particles.effects.distributions`: where and how fast they are born (:class:`Point`, :class:`Disk`,
  :class:`Cone`...);
* :mod:`particles.effects.colours`: colour ramps, tints and palettes (no Matplotlib needed);
* :mod:`particles.effects.effect`: :class:`ParticleEffect`, emitters, forces and colliders run together, with
  child effects;
* :mod:`particles.effects.flocking`: :class:`Boids` and :class:`Flock`, Reynolds' flocking rules.
"""

from .colours import TAB10, hsv_to_rgb, palette, to_rgb
from .effect import ColorRamp, ParticleEffect, Snapshot
from .emitters import Births, Cone, Disk, Emitter, ParticleEmitter, Point, SphereSurface, vary
from .flocking import Boids, Containment, Flock, polarization, spread

__all__ = ["ColorRamp", "Snapshot", "ParticleEffect", "Point", "Disk", "SphereSurface", "Cone", "Births", "Emitter",
           "ParticleEmitter", "vary", "to_rgb", "hsv_to_rgb", "palette", "TAB10", "Boids", "Containment", "Flock",
           "polarization", "spread"]
