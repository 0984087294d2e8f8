"""PBD's iteration-corrected stiffness (particles.xpbd.stiffness) and PBD(corrected=True)."""

import numpy as np
import pytest

from particles import ParticleSystem
from particles.forces import Gravity
from particles.massspring import string
from particles.xpbd import PBD, Distance, iteration_corrected

G = 9.81


def test_n_corrected_iterations_remove_what_one_iteration_of_k_removes():
    """(1 - k')^n = 1 - k for every k and n; k' = k at one iteration; 0 and 1 are kept; k' falls with n."""
    k = np.linspace(0.0, 1.0, 11)
    for n in (1, 2, 7, 50):
        np.testing.assert_allclose((1 - iteration_corrected(k, n)) ** n, 1 - k, atol=1e-15)
    np.testing.assert_array_equal(iteration_corrected(k, 1), k)
    assert iteration_corrected(0.3, 10) < iteration_corrected(0.3, 2) < 0.3
    assert isinstance(iteration_corrected(0.3, 4), float)


def hanging_particle(k, iterations, corrected, h=1 / 60, T=6.0):
    """Stretch (m) of a 1 kg particle at rest under gravity on one PBD constraint of rest length 1 m."""
    ps = ParticleSystem([[0.0, 0.0], [0.0, -1.0]], m=1.0, forces=[Gravity([0.0, -G])], pinned=[0])
    solver = PBD([Distance([[0, 1]], 1.0, stiffness=k)], ps.m, ps.pinned, iterations=iterations,
                 corrected=corrected, forces=ps.forces)
    for _ in range(round(T / h)):  # a loop over steps, with a strong damping to reach rest
        X = solver(None, ps.X, 0.0, h)
        X[:, 1] *= 0.8
        ps.set_state(X)
    return -ps.X[1, 0, 1] - 1.0


def test_one_constraint_no_longer_depends_on_the_iterations():
    """A particle on one PBD constraint rests at e = (1 - k)(e + g h^2), i.e. e = (1 - k) g h^2 / k, after one
    iteration of k; corrected, 10 and 50 iterations rest at the same stretch, uncorrected far less."""
    k, h = 0.2, 1 / 60
    expected = (1 - k) * G * h**2 / k
    assert hanging_particle(k, 1, False) == pytest.approx(expected, rel=1e-9)
    for n in (10, 50):
        assert hanging_particle(k, n, True) == pytest.approx(expected, rel=1e-9)
        assert hanging_particle(k, n, False) < 0.1 * expected


def test_the_correction_narrows_a_strings_iteration_dependence():
    """On a hanging string (constraints sharing particles) the correction holds only roughly: 1 and 10 corrected
    iterations stretch it within a factor 2, where the same k uncorrected differs by a factor 10."""
    def mean_strain(iterations, corrected):
        c = string(10, k=50.0, damping=0.05)
        solver = PBD.from_system(c, iterations=iterations, corrected=corrected).set_stiffness(0.5)
        c.run(2.0, 1 / 60, method=solver)
        return c.strain().mean()

    assert mean_strain(1, False) / mean_strain(10, False) > 8
    assert mean_strain(1, True) / mean_strain(10, True) < 2


def test_the_constraints_keep_their_stiffness_and_bad_input_is_refused():
    """corrected=True leaves the sets' stiffness as given; stiffnesses outside [0, 1] and iteration counts
    below 1 are refused by name."""
    c = Distance([[0, 1]], 1.0, stiffness=0.4)
    PBD([c], [1.0, 1.0], [0], iterations=5, corrected=True)
    np.testing.assert_array_equal(c.stiffness, [0.4])
    with pytest.raises(ValueError, match="k must hold PBD stiffnesses in \\[0, 1\\]"):
        iteration_corrected(1.5, 3)
    with pytest.raises(ValueError, match="iterations"):
        iteration_corrected(0.5, 0)
