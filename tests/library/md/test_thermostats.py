"""Thermostats: Berendsen's rescaling reaches its temperature, Langevin (BAOAB) samples NVT."""

import numpy as np
import pytest

from particles import ParticleSystem
from particles.forces import Field
from particles.integrators import verlet
from particles.md import Berendsen, Langevin, kinetic_temperature


class Spring:
    """Position-only spring to the origin, F = -k x, counting its evaluations (test helper)."""

    uses_velocity = False
    uses_time = False

    def __init__(self, k=1.0):
        self.k, self.calls = k, 0

    def add_to(self, F, x, v, t, m):
        self.calls += 1
        F -= self.k * x


def test_kinetic_temperature_counts_degrees_of_freedom():
    """T = sum m v^2 / (dof k_B), with d (n - 1) degrees of freedom by default."""
    v = np.array([[1.0, 2.0], [-1.0, 0.0], [0.0, -2.0]])
    assert kinetic_temperature(v) == pytest.approx(10.0 / 4)
    assert kinetic_temperature(v, m=[1.0, 2.0, 1.0], dof=6, k_B=2.0) == pytest.approx(11.0 / 12)


def test_berendsen_relaxes_to_its_temperature_in_about_tau():
    """T_now approaches T like exp(-t/tau) under pure rescaling; tau <= h rescales exactly every step."""
    rng = np.random.default_rng(0)
    x = rng.uniform(-5, 5, size=(200, 3))
    v = rng.normal(size=x.shape)
    v -= v.mean(axis=0)
    T0 = kinetic_temperature(v)
    ps = ParticleSystem(x, v=v)  # free particles: only the thermostat changes T
    t, X = ps.run(0.5, 0.001, method=Berendsen(T=2 * T0, tau=0.25), every=50)
    T = np.array([kinetic_temperature(Xk[:, 1]) for Xk in X])
    np.testing.assert_allclose(T, 2 * T0 - T0 * np.exp(-t / 0.25), rtol=2e-3)
    ps.run(0.51, 0.01, method=Berendsen(T=0.3, tau=0.001))
    assert kinetic_temperature(ps.X[:, 1]) == pytest.approx(0.3, rel=1e-12)


def test_berendsen_keeps_the_inner_stepper_and_reuses_its_forces():
    """Berendsen around Verlet: order 2, fsal, one force evaluation per step with position-only forces."""
    step = Berendsen(T=1.0, tau=0.1)
    assert step.order == 2 and step.fsal and step.second_order_layout
    spring = Spring()
    ps = ParticleSystem([[1.0, 0.0], [0.0, 1.0]], v=[[0.0, 1.0], [1.0, 0.0]], forces=[spring])
    ps.run(1.0, 0.01, method=step)
    assert spring.calls == 101


def test_langevin_samples_the_canonical_ensemble_of_an_oscillator():
    """Harmonic springs at T: <x^2> = k_B T / k and <v^2> = k_B T / m per coordinate (BAOAB, long run)."""
    T, k, m = 0.7, 4.0, 2.0
    spring = Spring(k)
    ps = ParticleSystem(np.zeros((400, 2)), m=m, forces=[spring])
    ps.run(5.0, 0.05, method=Langevin(T, gamma=1.0, m=m, seed=1))  # equilibrate
    t, X = ps.run(ps.t + 60.0, 0.05, method=Langevin(T, gamma=1.0, m=m, seed=2), every=10)
    assert spring.calls == 100 + 1 + 1200 + 1  # once per step in each run
    x2, v2 = np.mean(X[1:, :, 0] ** 2), np.mean(X[1:, :, 1] ** 2)
    assert x2 == pytest.approx(T / k, rel=0.03)  # BAOAB: exact for the oscillator's positions
    assert v2 == pytest.approx(T / m * (1 - (0.05**2 * k / m) / 4), rel=0.03)


def test_langevin_is_reproducible_with_a_seed_and_leaves_pins_alone():
    """The same seed gives the same run; a pinned particle feels no noise; gamma = 0 is velocity Verlet."""
    x = np.array([[1.0, 0.0], [0.0, 1.0], [2.0, 2.0]])
    runs = []
    for _ in range(2):
        ps = ParticleSystem(x, forces=[Field(lambda y, t: -y)], pinned=[2])
        runs.append(ps.run(1.0, 0.01, method=Langevin(1.0, 2.0, seed=7, pinned=ps.pinned))[1])
    np.testing.assert_array_equal(runs[0], runs[1])
    np.testing.assert_array_equal(runs[0][:, 2, 0], np.broadcast_to([2.0, 2.0], (101, 2)))
    assert np.all(runs[0][:, 2, 1] == 0.0)
    X0 = np.array([[[1.0, 0.0], [0.3, -0.2]]])
    f = lambda X, t: np.stack([X[:, 1], -X[:, 0]], axis=1)  # noqa: E731 (the oscillator's derivative)
    no_friction = Langevin(1.0, 0.0, seed=0)
    np.testing.assert_allclose(no_friction(f, X0, 0.0, 0.1), verlet(f, X0, 0.0, 0.1), atol=1e-15)


@pytest.mark.parametrize("make, match", [
    (lambda: Langevin(T=0.0, gamma=1.0), "T must be a positive finite number"),
    (lambda: Langevin(T=-1.0, gamma=1.0), "T must be a positive finite number"),
    (lambda: Langevin(T=1.0, gamma=-0.5), "gamma must be a finite number >= 0"),
    (lambda: Langevin(T=1.0, gamma=1.0, m=[1.0, 0.0]), "m must be positive"),
    (lambda: Berendsen(T=0.0, tau=1.0), "T must be a positive finite number"),
    (lambda: Berendsen(T=1.0, tau=0.0), "tau must be a positive finite number"),
    (lambda: Berendsen(T=1.0, tau=1.0, step="leapfrog"), "unknown step 'leapfrog'"),
])
def test_thermostats_refuse_bad_parameters_by_name(make, match):
    """Temperatures <= 0, negative friction, masses <= 0, tau <= 0, unknown steppers raise ValueError."""
    with pytest.raises(ValueError, match=match):
        make()
