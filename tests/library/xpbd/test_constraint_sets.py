"""The constraint sets (particles.xpbd.constraint_sets): isometric bending, constraint damping, bad input."""

import numpy as np
import pytest

from particles.implicit import relax
from particles.massspring import hair, string
from particles.xpbd import XPBD, Attachment, Distance, IsometricBending


def test_isometric_bending_holds_a_hair_like_the_bending_force():
    """A clamped hair with isometric bending of compliance 1/kb droops as the spring hair with Bending kb."""
    h = hair(12, kb=0.002, k=2000.0)
    springs = hair(12, kb=0.002, k=2000.0)
    relax(springs, h=0.05)
    solver = XPBD.from_system(h, substeps=20)
    X = h.state()
    for _ in range(240):
        X = solver(None, X, 0.0, 1 / 60)
        X[:, 1] *= 0.7
    droop, droop_springs = -X[-1, 0, 1], -springs.X[-1, 0, 1]
    assert droop > 0.01 and abs(droop / droop_springs - 1.0) < 0.05


def test_straight_bending_at_rest_stays_at_rest():
    """A straight hair without gravity under isometric bending stays at rest (no chatter at theta = 0)."""
    h = hair(8, gravity=0.0)
    solver = XPBD.from_system(h, iterations=5)
    t, X = h.run(1.0, 1 / 60, method=solver)
    assert np.abs(X[-1] - X[0]).max() < 1e-15


def test_xpbd_damping_removes_relative_motion():
    """Constraint damping kd (Macklin et al. eq. 26) takes energy out of a bouncing string; kd = 0 keeps more."""
    energies = []
    for kd in (0.0, 0.5):
        c = string(10, k=50.0, kd=kd)
        c.run(1.0, 1 / 60, method=XPBD.from_system(c, substeps=10))
        energies.append(c.kinetic_energy() + c.potential_energy())
    assert energies[1] < energies[0]


@pytest.mark.parametrize("make, name", [
    (lambda: Distance([[0, 1]], 1.0, compliance=-1.0), "compliance"),
    (lambda: Distance([[0, 1]], 1.0, stiffness=1.5), "stiffness"),
    (lambda: Distance([[0, 1]], 1.0, damping=-0.1), "damping"),
    (lambda: Distance([[0, 0]], 1.0), "indices"),
    (lambda: Distance([[0, 1, 2]], 1.0), "indices"),
    (lambda: Distance([[0, 1]]), "rest_length"),
    (lambda: Distance([[0, 1], [1, 2]], 1.0, groups=[[0, 1]]), "groups"),
    (lambda: Distance([[0, 1], [1, 2]], 1.0, groups=[[0]]), "groups"),
    (lambda: IsometricBending([[0, 1, 2]], rest_lengths=[[1.0, 0.0]]), "rest_lengths"),
    (lambda: Attachment([0, 1], [[0.0, 0.0]]), "targets"),
])
def test_bad_input_names_the_argument(make, name):
    """Bad arguments raise ValueError naming the argument."""
    with pytest.raises(ValueError, match=name):
        make()
