"""Springs as constraints: the distance and bending constraints of a mass-spring system's springs.

:func:`constraints_from_system` turns each spring set of a
:class:`~particles.massspring.MassSpringSystem` into a distance constraint
set of compliance ``1 / k`` (converged XPBD then has the springs' elastic
energy), a :class:`~particles.forces.Bending` force into isometric bending
and a :class:`~particles.forces.Clamp` into an isometric clamp;
:meth:`particles.xpbd.XPBD.from_system` builds a solver with them.
"""

import numpy as np

from ..forces import Bending, Clamp
from .constraint_sets import Distance, IsometricBending, IsometricClamp

__all__ = ["constraints_from_system"]


def constraints_from_system(system, kinds=None, bending=True):
    """Distance (and bending) constraints equivalent to a mass-spring system's springs.

    Each spring of stiffness ``k`` and damping ``kd`` becomes a distance
    constraint of compliance ``1 / k`` and damping ``kd``, so that converged
    XPBD has the same elastic energy as the springs; a
    :class:`~particles.forces.Bending` force of joint stiffness ``kb``
    becomes isometric bending of compliance ``1 / kb``, and a
    :class:`~particles.forces.Clamp` an :class:`IsometricClamp`.

    Parameters
    ----------
    system : MassSpringSystem
        A string, hair or cloth from :mod:`particles.massspring`.
    kinds : sequence of str, optional
        Spring kinds to convert (default: all of the system's).
    bending : bool
        Convert the system's Bending and Clamp forces too.

    Returns
    -------
    constraints : list of Distance, IsometricBending and IsometricClamp
    converted : list
        The force objects of the system that the constraints replace (a
        solver built with :meth:`XPBD.from_system` leaves them out).
    """
    if not hasattr(system, "springs"):
        raise ValueError("system must be a MassSpringSystem (with labelled spring sets)")
    kinds = list(system.springs) if kinds is None else list(kinds)
    unknown = [k for k in kinds if k not in system.springs]
    if unknown:
        raise ValueError(f"kinds {unknown} are not spring kinds of the system; it has {list(system.springs)}")
    constraints, converted = [], []
    for kind in kinds:  # a loop over the few spring kinds
        s = system.springs[kind]
        constraints.append(Distance(s.indices, s.rest_length, compliance=1.0 / s.k, damping=s.kd, kind=kind))
        converted.append(s)
    if bending:
        for force in system.other_forces():  # a loop over the few force objects
            if isinstance(force, Bending):
                if np.any(np.abs(force.rest_angle) > 1e-12):
                    raise ValueError("isometric bending needs straight rest shapes (rest_angle 0); this "
                                     "system's Bending force has curved ones")
                triples = np.stack([force.i, force.j, force.l], axis=1)
                compliance = np.divide(1.0, force.kb, out=np.full(len(force.kb), np.inf), where=force.kb > 0)
                keep = np.isfinite(compliance)
                constraints.append(IsometricBending(triples[keep], x=system.X[:, 0], compliance=compliance[keep],
                                                    kind="bending"))
                converted.append(force)
            elif isinstance(force, Clamp):
                x = system.X[:, 0]
                keep = force.kb > 0
                L0 = np.linalg.norm(x[force.j] - x[force.i], axis=1)[keep]
                constraints.append(IsometricClamp(np.stack([force.i, force.j], axis=1)[keep], force.direction[keep],
                                                  L0, compliance=1.0 / force.kb[keep], kind="clamp"))
                converted.append(force)
    return constraints, converted
