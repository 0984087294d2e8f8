"""Autograder tests of exercise 00_warmup: Euler's step, gravity plus damping, the loop.

Public tests use fixed inputs a student can reason about; hidden tests draw
random shapes and parameters from the grading seed (fixture ``rng``), so that
hard-coded answers fail, and never print them (their messages give errors and
indices, ``show_values=False``). Every expected value comes from the reference
library, computed here in the grader, never in the student's process. A wrong
result is compared with the typical mistakes (``hints``): a midpoint step, the
slope taken at t + h, X returned unstepped, the damping's sign, the masses
left out, a trajectory whose first record is not X0, ...
"""

import numpy as np
import pytest

import particles
from particles.course.grading.expect import expect_array
from particles.course.worker.registry import remote
from particles.course.worker.runner import GradingFailure, describe_value
from particles.forces import Damping, Gravity
from particles.integrators import euler, midpoint

EXERCISE = "00_warmup"
FORBIDDEN = {
    "particles.integrators.euler": "it is the Euler step you are asked to write",
    "particles.integrators.INTEGRATORS": "it holds the library's own steppers; write the step yourself",
    "particles.integrators.integrate": "it is the loop you are asked to write",
    "particles.forces.Gravity": "compute m g yourself",
    "particles.forces.Damping": "compute -d v yourself",
    "particles.system.ParticleSystem": "it computes the forces and runs the loop for you",
}


def _reference_force(x, v, m, g, d):
    return Gravity(g)(x, v, 0.0, m) + Damping(d)(x, v, 0.0, m)


def _random_state(rng, n, d):
    return rng.normal(size=(n, 2, d))


def _euler_hints(f, X, t, h):
    """Typical wrong answers for one Euler step: label -> the state they give."""
    slope = f(X, t)
    return {
        "a midpoint step": midpoint(f, X, t, h),
        "an Euler step with f evaluated at t + h instead of t (the slope of an Euler step is f(X, t), at the "
        "start of the step)": X + h * f(X, t + h),
        "X itself: the step X + h f(X, t) is missing": X,
        "zeros, not the new state X + h f(X, t)": np.zeros_like(X),
        "h f(X, t) alone, without X": h * slope,
    }


def _force_hints(v, m, g, d):
    """Typical wrong total forces: label -> the forces they give."""
    gravity, drag = np.asarray(m, dtype=float)[:, None] * g, -d * v
    return {
        "m g + d v: the damping has the wrong sign (the drag -d v opposes the velocity)": gravity - drag,
        "g - d v, gravity without the masses (the weight of particle i is m_i g)": g + drag,
        "m (g - d v): the drag multiplied by the mass (it is -d v, whatever the mass)": gravity + m[:, None] * drag,
        "m g alone: the damping -d v is missing": gravity,
        "-d v alone: gravity m g is missing": drag,
        "the total force summed over all particles (sum(axis=0)); return one force per particle, shape (n, dim)":
            (gravity + drag).sum(axis=0),
    }


# -- euler_step --------------------------------------------------------------------------------


@pytest.mark.points(1)
def test_euler_step_circle(student):
    """euler_step takes one step on the circle field f = (-y, x) from (1, 0)."""
    f, X = remote("circle"), np.array([1.0, 0.0])
    got = student.call("euler_step", f, X, 0.0, 0.1)
    expect_array(got, euler(f, X, 0.0, 0.1), "euler_step(f, X=[1, 0], t=0, h=0.1) on the circle field",
                 hints=_euler_hints(f, X, 0.0, 0.1))


@pytest.mark.points(1)
def test_euler_step_oscillator(student):
    """euler_step advances a particle state (1, 2, 1) of the harmonic oscillator."""
    f = remote("harmonic_oscillator", omega=2.0)
    X = np.array([[[1.0], [0.5]]])
    got = student.call("euler_step", f, X, 0.0, 0.05)
    expect_array(got, euler(f, X, 0.0, 0.05), "euler_step(f, X, t=0, h=0.05) on the oscillator with omega = 2",
                 hints=_euler_hints(f, X, 0.0, 0.05))


@pytest.mark.points(1)
def test_euler_step_leaves_X_unchanged(student):
    """euler_step returns a new array holding the step, without modifying X or calling f more than once."""
    f = remote("harmonic_oscillator", omega=1.0, counted=True)  # the grader evaluates f, and counts
    X = np.array([[[1.0], [0.0]], [[0.0], [1.0]]])
    got = student.call("euler_step", f, X, 0.0, 0.1, check_inputs=True)
    expect_array(got, euler(f, X, 0.0, 0.1), "euler_step(f, X of shape (2, 2, 1), t=0, h=0.1) on the oscillator "
                 "with omega = 1", hints=_euler_hints(f, X, 0.0, 0.1))
    if student.calls_of(0) != 1:
        raise GradingFailure(f"euler_step evaluated f {student.calls_of(0)} times in one step; Euler's method "
                             "uses exactly one evaluation, f(X, t)")


@pytest.mark.points(2)
@pytest.mark.hidden
def test_euler_step_random(student, rng):
    """euler_step matches the reference on random states, times and steps of a driven oscillator."""
    for _ in range(3):
        n, d = int(rng.integers(1, 6)), int(rng.integers(1, 4))
        omega, h, t = rng.uniform(0.5, 3.0), rng.uniform(0.001, 0.2), rng.uniform(0.0, 10.0)
        f = remote("forced_oscillator", omega=omega, amplitude=rng.uniform(0.5, 2.0), frequency=omega + 1.3)
        X = _random_state(rng, n, d)
        expect_array(student.call("euler_step", f, X, t, h), euler(f, X, t, h),
                     f"euler_step(f, X of shape {X.shape}, t, h) on a driven oscillator (random t, h and X)",
                     hints=_euler_hints(f, X, t, h), show_values=False)


# -- total_force -------------------------------------------------------------------------------


@pytest.mark.points(1)
def test_total_force_three_particles(student):
    """total_force adds m g and -d v for three particles in 2D."""
    x = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    v = np.array([[1.0, 0.0], [0.0, -2.0], [0.5, 0.5]])
    m, g, d = np.array([1.0, 2.0, 0.5]), np.array([0.0, -9.81]), 0.3
    got = student.call("total_force", x, v, m, g, d)
    expect_array(got, _reference_force(x, v, m, g, d), "total_force(x, v, m=[1, 2, 0.5], g=[0, -9.81], d=0.3)",
                 hints=_force_hints(v, m, g, d))


@pytest.mark.points(2)
@pytest.mark.hidden
def test_total_force_random(student, rng):
    """total_force matches the reference for random particles in 2D and 3D, without changing its inputs."""
    for dim in (2, 3):
        n = int(rng.integers(5, 50))
        x, v = rng.normal(size=(n, dim)), rng.normal(size=(n, dim))
        m, g, d = rng.uniform(0.1, 3.0, n), rng.normal(size=dim), rng.uniform(0.0, 2.0)
        got = student.call("total_force", x, v, m, g, d, check_inputs=True)
        expect_array(got, _reference_force(x, v, m, g, d), f"total_force for {n} random particles in {dim}D",
                     hints=_force_hints(v, m, g, d), show_values=False)


# -- run ---------------------------------------------------------------------------------------


def _reference_run(f, X0, t0, h, n):
    return particles.integrate(f, X0, t0, t0 + n * h, h, method="euler")


def _loop(f, X0, t0, h, n, time_shift=0.0, restart=False):
    """A wrong Euler loop: each step given t_k + `time_shift`, or each step taken from X0 (`restart`)."""
    X = [np.asarray(X0, dtype=float)]
    for k in range(n):
        X.append(euler(f, X0 if restart else X[-1], t0 + k * h + time_shift, h))
    return np.array(X)


def _first_record(X0):
    """A pattern: the trajectory's first record is not X0."""
    def wrong(X):
        return X.ndim >= 1 and len(X) > 0 and X[0].shape == np.shape(X0) and not np.allclose(X[0], X0, rtol=1e-9)
    return wrong


def _run_hints(f, X0, t0, h, n):
    """Typical wrong trajectories of run: label -> the states (or a pattern)."""
    longer = _reference_run(f, X0, t0, h, n + 1)[1]
    return {
        "the states one step ahead, X[k] after k + 1 steps: your first record is not X0 (the trajectory must start "
        "with the initial state, X[0] = X0)": longer[1:],
        "the states of a loop that passes t + h to each step instead of t[k] (the step from t[k] is "
        "euler_step(f, X[k], t[k], h))": _loop(f, X0, t0, h, n, time_shift=h),
        "one step from X0 in every record: each step must start from the previous state X[k], not from X0":
            _loop(f, X0, t0, h, n, restart=True),
        "X0 in every record: the state never advances (look at the loop, and at euler_step)":
            np.broadcast_to(np.asarray(X0, dtype=float), longer[1:].shape),
        "your first record is not X0: the trajectory must start with the initial state (X[0] = X0)": _first_record(X0),
    }


def _check_run(got, f, X0, t0, h, n, call, reveal=True):
    if not isinstance(got, tuple) or len(got) != 2:
        kind = describe_value(got) if not isinstance(got, tuple) else f"a tuple of {len(got)} values"
        raise GradingFailure(f"{call} returned {kind}, expected the tuple (t, X)")
    t_ref, X_ref = _reference_run(f, X0, t0, h, n)
    records = "n_steps steps make n_steps + 1 records, t0 and X0 included"
    longer = _reference_run(f, X0, t0, h, n + 1)
    expect_array(got[0], t_ref, f"the times t of {call}", rtol=1e-9, show_values=reveal, hints={
        f"the times without the last one: your loop takes one step too few ({records})": t_ref[:-1],
        f"the times of n_steps + 1 steps: your loop takes one step too many ({records}; a loop over all n_steps "
        "+ 1 times takes one step from the last one too)": longer[0],
        f"the times after each step, without t0: {records}": t_ref[1:],
        "times that start at t0 + h instead of t0": t_ref + h,
        "times that start at 0 instead of t0": t_ref - t0,
    })
    expect_array(got[1], X_ref, f"the states X of {call}", rtol=1e-9, show_values=reveal,
                 hints=dict({f"the states without the last one: your loop takes one step too few ({records})":
                             X_ref[:-1],
                             f"the states of n_steps + 1 steps: your loop takes one step too many ({records}; a "
                             "loop over all n_steps + 1 times takes one step from the last one too)": longer[1],
                             f"the states after each step, without X0: {records}": X_ref[1:]},
                            **_run_hints(f, X0, t0, h, n)))


@pytest.mark.points(1)
def test_run_circle(student):
    """run takes 10 Euler steps on the circle field and records all 11 states."""
    f, X0 = remote("circle"), np.array([1.0, 0.0])
    _check_run(student.call("run", f, X0, 0.0, 0.1, 10), f, X0, 0.0, 0.1, 10,
               "run(f, X0=[1, 0], t0=0, h=0.1, n_steps=10) on the circle field")


@pytest.mark.points(2)
@pytest.mark.hidden
def test_run_random(student, rng):
    """run matches the reference loop on a driven oscillator with random start, time and step."""
    n, d, steps = int(rng.integers(1, 4)), int(rng.integers(1, 3)), int(rng.integers(20, 60))
    omega = rng.uniform(0.5, 3.0)
    f = remote("forced_oscillator", omega=omega, amplitude=1.0, frequency=omega + 0.7)
    X0, t0, h = _random_state(rng, n, d), rng.uniform(0.0, 5.0), rng.uniform(0.005, 0.05)
    _check_run(student.call("run", f, X0, t0, h, steps, check_inputs=True), f, X0, t0, h, steps,
               f"run(f, X0 of shape {X0.shape}, t0, h, n_steps) on a driven oscillator (random X0, t0, h and "
               "n_steps)", reveal=False)
