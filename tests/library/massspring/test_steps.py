"""Several compiled symplectic Euler steps in one call (integrate's batches through a stepper's ``steps``).

A mass-spring system's run without hooks takes its steps up to each recorded
state in one compiled call (:meth:`particles.massspring.SymplecticEulerStep.steps`,
:meth:`particles.massspring.compiled_step.CompiledStep.symplectic_euler_steps`),
with the divergence guard inside the call. These tests check that the
states are those of the steps taken one at a time, to the bit, on every
force the compiled step covers (time-dependent gusts included), on any
number of threads; that a run falls back to one step at a time where a
force needs Python between the steps; and that a diverging run is stopped
at the same step, with the same report, as the NumPy run.
"""

import numpy as np
import pytest

from particles import backends
from particles.massspring import compiled_step as compiled
from particles.errors import SimulationDiverged
from particles.forces import Damping, Wind
from particles.integrators import step_times
from particles.massspring import cloth, hair, string

from ..backends.helpers import _close, assert_same_bits, needs_numba, on_thread_counts
from ..backends.helpers import shaken as _shaken

pytestmark = needs_numba

H = 1e-4  # s


def _gusty():
    system = cloth(10, 10, kd=0.01, scaling="physical", bending_modulus=1e-3)
    system.forces += [Wind([0.3, 0.1, 0.0], gust=0.5, period=0.001, wavelength=0.3), Damping(rate=0.3)]
    return system


SYSTEMS = {
    "cloth, three damped sets": lambda: cloth(12, 12, kd=0.05),
    "cloth, bending, gusts with a period of 10 steps, damping": _gusty,
    "string in 2D, pinned at both ends": lambda: string(30, pin="both", span=0.8, scaling="physical", damping=0.2),
    "hair with its clamp (one step at a time)": lambda: hair(25, kd=0.001, damping=0.05),
}


def _one_at_a_time(system, T, h):
    """The states of the system's symplectic Euler called step by step (the compiled step of one step), at every step."""
    times = step_times(system.t, T, h)
    X = system.state()
    states = [X]
    step = system.stepper("symplectic_euler")
    with backends.using("numba"):
        for k in range(1, len(times)):  # a loop over the steps
            X = step(system.derivative, X, times[k - 1], times[k] - times[k - 1])
            states.append(X)
    return np.array(states)


@pytest.mark.parametrize("name", SYSTEMS)
def test_steps_in_one_call_are_the_steps_one_at_a_time(name, monkeypatch):
    """Records every 7th of 30 steps: the same bits as the stepper called 30 times; one call per record."""
    calls = []
    original = compiled.CompiledStep.symplectic_euler_steps

    def spy(self, X, times, limit):
        result = original(self, X, times, limit)
        calls.append((len(times) - 1, result is not None))
        return result

    monkeypatch.setattr(compiled.CompiledStep, "symplectic_euler_steps", spy)
    system = _shaken(SYSTEMS[name]())
    expected = _one_at_a_time(system, 30 * H, H)
    given = system.state()
    with backends.using("numba"):
        t, X = system.run(30 * H, H, method="symplectic_euler", every=7)
    np.testing.assert_array_equal(X, expected[[0, 7, 14, 21, 28, 30]])
    if "clamp" in name:  # the clamp is computed by Python before each step: the steps cannot run in one call
        assert calls == [(7, False)]
    else:
        assert calls == [(7, True), (7, True), (7, True), (7, True), (2, True)]
    system.set_state(given, 0.0)
    with backends.using("numpy"):
        _close(system.run(30 * H, H, method="symplectic_euler", every=7)[1], X)


def test_the_given_state_is_not_modified_and_the_end_state_is_fortran():
    """A run of 20 steps in one call from a Fortran-ordered state: X0 unchanged, the system's end state in F order."""
    system = _shaken(cloth(9, 9, kd=0.05))
    X0 = system.X
    kept = X0.copy()
    with backends.using("numba"):
        system.run(20 * H, H, method="symplectic_euler", every=20)
    np.testing.assert_array_equal(X0, kept)
    assert system.X.flags.f_contiguous and not np.shares_memory(system.X, X0)


def test_the_same_bits_on_one_thread_and_on_two(monkeypatch):
    """Blocks of 50 particles, 12 steps in one call: one thread, two, and the serial kernel agree to the bit."""
    monkeypatch.setattr(compiled, "STEP_BLOCK", 50)
    system = _shaken(_gusty())
    X0 = system.state()

    def run():
        system.set_state(X0, 0.0)
        with backends.using("numba"):
            return [system.run(12 * H, H, method="symplectic_euler", every=12)[1]]

    assert_same_bits(on_thread_counts(monkeypatch, run))


@pytest.mark.parametrize("blowup", [1e12, None], ids=["growth limit", "inf or NaN only"])
def test_a_diverging_run_stops_at_the_numpy_run_s_step(blowup):
    """h far above the stability limit, 500 steps in one call: SimulationDiverged at NumPy's step, same cause."""
    errors = {}
    for backend in ("numpy", "numba"):
        system = _shaken(cloth(8, 8, kd=0.0, k_structural=1e4))
        with backends.using(backend), pytest.raises(SimulationDiverged) as caught:
            system.run(500 * 0.01, 0.01, method="symplectic_euler", every=500, blowup=blowup)
        errors[backend] = str(caught.value)
        assert system.t == 0.0  # the system keeps its state: the run did not happen
    assert errors["numba"] == errors["numpy"]
    assert ("The state became inf or NaN" in errors["numba"]) == (blowup is None)
