"""ParticleSystem: the derivative, pins and their reaction, running, errors."""

import numpy as np
import pytest

from particles import ParticleSystem, SimulationDiverged
from particles.forces import Damping, Field, Gravity, NBodyGravity

g = np.array([0.0, -9.81])


def test_derivative_is_velocity_and_acceleration():
    """f(X, t) = (v, F/m) particle by particle, as on the slide."""
    x = [[0.0, 0.0], [1.0, 2.0], [3.0, -1.0]]
    v = [[1.0, 0.0], [0.0, 2.0], [-1.0, 1.0]]
    m = [1.0, 2.0, 4.0]
    ps = ParticleSystem(x, v=v, m=m, forces=[Gravity(g), Damping(0.5)])
    dX = ps.derivative(ps.state(), 0.0)
    np.testing.assert_allclose(dX[:, 0], v)
    F = np.array(m)[:, None] * g - 0.5 * np.array(v)
    np.testing.assert_allclose(dX[:, 1], F / np.array(m)[:, None])


def test_state_layout_and_copy():
    """state() is (n, 2, d), positions then velocities, and a copy."""
    ps = ParticleSystem([[1.0, 2.0, 3.0]], v=[[4.0, 5.0, 6.0]])
    X = ps.state()
    assert X.shape == (1, 2, 3) and ps.n == 1 and ps.d == 3
    np.testing.assert_array_equal(X.ravel(), [1, 2, 3, 4, 5, 6])  # the slide's stacked vector
    X[:] = 0
    assert ps.X[0, 0, 0] == 1.0


def test_projectile_exact_with_rk4():
    """Under gravity alone RK4 is exact (the solution is a quadratic)."""
    ps = ParticleSystem([[0.0, 10.0]], v=[[2.0, 3.0]], forces=[Gravity(g)])
    t, X = ps.run(1.3, 0.1, method="rk4")
    np.testing.assert_allclose(X[:, 0, 0, 0], 2.0 * t, atol=1e-12)
    np.testing.assert_allclose(X[:, 0, 0, 1], 10.0 + 3.0 * t + 0.5 * g[1] * t**2, atol=1e-12)
    assert ps.t == pytest.approx(1.3)


def test_damping_decays_velocity_exponentially():
    """F = -d v gives v(t) = v0 exp(-d t / m)."""
    ps = ParticleSystem([[0.0, 0.0]], v=[[1.0, -2.0]], m=2.0, forces=[Damping(3.0)])
    t, X = ps.run(2.0, 0.01, method="rk4")
    np.testing.assert_allclose(X[:, 0, 1], np.outer(np.exp(-1.5 * t), [1.0, -2.0]), rtol=1e-8)


def test_pinned_particles_do_not_move_and_reaction_balances():
    """A pinned particle keeps its place; the pin's force is minus all other forces."""
    spring = Field(lambda x, t: -10.0 * (x - [0.0, 1.0]))
    ps = ParticleSystem([[0.0, 0.0], [1.0, 1.0]], m=[2.0, 1.0], forces=[Gravity(g), spring], pinned=[0])
    t, X = ps.run(1.0, 0.01)
    np.testing.assert_array_equal(X[:, 0, 0], [[0.0, 0.0]] * len(t))
    np.testing.assert_array_equal(X[:, 0, 1], 0.0)
    assert np.ptp(X[:, 1, 0, 0]) > 0.1  # the free one moves
    R = ps.reaction_forces(X[0], 0.0)
    expected = -(2.0 * g - 10.0 * (np.array([0.0, 0.0]) - [0.0, 1.0]))
    np.testing.assert_allclose(R, [expected])


def test_hanging_mass_pin_carries_the_weight():
    """Inverse dynamics: a mass on a pin feels m g; the pin pushes back with -m g."""
    ps = ParticleSystem([[0.0, 0.0], [5.0, 5.0]], m=[3.0, 1.0], forces=[Gravity(g)], pinned=np.array([True, False]))
    np.testing.assert_allclose(ps.reaction_forces(), [-3.0 * g])
    assert ps.pinned.tolist() == [0]


def test_momentum_conserved_by_internal_forces():
    """With only pairwise forces, total momentum stays constant during a run."""
    rng = np.random.default_rng(0)
    ps = ParticleSystem(rng.normal(size=(20, 3)), v=rng.normal(size=(20, 3)), m=rng.uniform(1, 2, 20),
                        forces=[NBodyGravity(G=0.1, softening=0.1)])
    p0 = ps.momentum()
    ps.run(1.0, 0.01, method="verlet")
    np.testing.assert_allclose(ps.momentum(), p0, atol=1e-12)


def test_run_every_and_step():
    """run(..., every=k) records every k-th state; step() advances by h."""
    ps = ParticleSystem([[0.0, 0.0]], v=[[1.0, 0.0]])
    t, X = ps.run(1.0, 0.1, every=5)
    np.testing.assert_allclose(t, [0.0, 0.5, 1.0])
    assert X.shape == (3, 1, 2, 2)
    X1 = ps.step(0.25, method="euler")
    assert ps.t == pytest.approx(1.25)
    np.testing.assert_allclose(X1[0, 0], [1.25, 0.0])


def test_energy_bookkeeping_under_gravity():
    """Kinetic plus potential energy is conserved along an exact projectile path."""
    ps = ParticleSystem([[0.0, 0.0], [1.0, 5.0]], v=[[1.0, 4.0], [0.0, 0.0]], m=[1.0, 3.0], forces=[Gravity(g)])
    E0 = ps.kinetic_energy() + ps.potential_energy()
    ps.run(0.8, 0.05, method="rk4")
    assert ps.kinetic_energy() + ps.potential_energy() == pytest.approx(E0, rel=1e-12)


def test_divergence_in_run_names_step_and_leaves_system_unchanged():
    """A stiff field with a large step raises SimulationDiverged; the state is kept."""
    stiff = Field(lambda x, t: -1e6 * x)
    ps = ParticleSystem([[1.0, 0.0]], forces=[stiff])
    with pytest.raises(SimulationDiverged, match=r"diverged at step \d+ \(t = .*stability limit"):
        ps.run(10.0, 0.01, method="euler")
    np.testing.assert_array_equal(ps.X[0, 0], [1.0, 0.0])
    assert ps.t == 0.0


def test_derivative_does_not_modify_state():
    """derivative and reaction_forces never write into the state (a read-only X works)."""
    ps = ParticleSystem([[0.0, 1.0]], v=[[1.0, 0.0]], forces=[Gravity(g), Damping(1.0)])
    X = ps.state()
    X.setflags(write=False)
    ps.derivative(X, 0.0)
    ps.reaction_forces(X, 0.0)


def test_user_arrays_are_not_aliased():
    """The system copies the positions it is given; later runs do not touch them."""
    x = np.array([[0.0, 1.0]])
    ps = ParticleSystem(x, forces=[Gravity(g)])
    ps.run(1.0, 0.1)
    assert x.tolist() == [[0.0, 1.0]]


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(x=[1.0, 2.0]), "x must have 2 dimensions"),
        (dict(x=[[1.0, 2.0, 3.0, 4.0]]), r"x must have shape \(n, 2\) or \(n, 3\)"),
        (dict(x=[[np.nan, 0.0]]), "x must be finite"),
        (dict(v=[[0.0, 0.0, 0.0]]), r"v must have shape \(1, 2\)"),
        (dict(m=0.0), "m must be positive"),
        (dict(m=[-1.0]), "m must be positive"),
        (dict(m=[1.0, 2.0]), r"m must be a number or have shape \(1,\)"),
        (dict(pinned=[3]), r"pinned indices must lie in \[0, 1\)"),
        (dict(pinned=[0], v=[[1.0, 0.0]]), "v of pinned particles must be zero"),
        (dict(pinned=[0.5]), "pinned must be a list of particle indices"),
        (dict(forces=[lambda x: x]), "forces must be Force objects"),
    ],
)
def test_bad_input(kwargs, match):
    """Each mistake raises a ValueError naming the argument."""
    args = dict(x=[[0.0, 0.0]])
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        ParticleSystem(**args)


def test_state_of_wrong_shape_is_rejected():
    """A state of the wrong shape is refused with the expected shape."""
    ps = ParticleSystem([[0.0, 0.0]])
    with pytest.raises(ValueError, match=r"X must have shape \(1, 2, 2\)"):
        ps.derivative(np.zeros((2, 2, 2)), 0.0)


def test_unknown_method_in_run():
    """run refuses an unknown method by name."""
    ps = ParticleSystem([[0.0, 0.0]])
    with pytest.raises(ValueError, match="unknown method 'leapfrog'"):
        ps.run(1.0, 0.1, method="leapfrog")


def test_add_particles_keeps_state_fortran_ordered_and_attributes_aligned():
    """add_particles appends state, masses and attribute values; the state stays in Fortran order."""
    ps = ParticleSystem([[0.0, 0.0], [1.0, 0.0]], m=[1.0, 2.0])
    birth = ps.define_attribute("birth", fill=-1.0)
    assert birth.tolist() == [-1.0, -1.0]
    ps.define_attribute("rgb", fill=[1.0, 1.0, 1.0], shape=(3,))
    new = ps.add_particles([[5.0, 5.0], [6.0, 6.0]], v=[[1.0, 0.0], [0.0, 1.0]], m=3.0, birth=[0.5, 0.7])
    assert new.tolist() == [2, 3] and ps.n == 4
    assert ps.X.flags.f_contiguous
    np.testing.assert_array_equal(ps.m, [1.0, 2.0, 3.0, 3.0])
    np.testing.assert_array_equal(ps.attributes["birth"], [-1.0, -1.0, 0.5, 0.7])
    assert ps.attributes["rgb"].shape == (4, 3)
    np.testing.assert_array_equal(ps.X[3], [[6.0, 6.0], [0.0, 1.0]])


def test_remove_particles_remaps_pins_and_attributes():
    """remove_particles drops rows everywhere and renumbers the pinned particles that remain."""
    ps = ParticleSystem(np.arange(10.0).reshape(5, 2), m=[1.0, 2.0, 3.0, 4.0, 5.0], pinned=[1, 4])
    ps.define_attribute("tag", fill=0, dtype=int)
    ps.attributes["tag"][:] = [10, 11, 12, 13, 14]
    keep = ps.remove_particles(np.array([True, True, False, False, False]))
    assert keep.tolist() == [2, 3, 4] and ps.n == 3 and ps.X.flags.f_contiguous
    assert ps.pinned.tolist() == [2]
    np.testing.assert_array_equal(ps.m, [3.0, 4.0, 5.0])
    np.testing.assert_array_equal(ps.attributes["tag"], [12, 13, 14])
    ps.remove_particles([0])
    np.testing.assert_array_equal(ps.X[:, 0, 0], [6.0, 8.0])
    ps.remove_particles(np.ones(2, dtype=bool))
    t, X = ps.run(0.1, 0.05)  # an empty system still runs
    assert X.shape == (3, 0, 2, 2)


def test_pair_forces_stay_right_when_particles_come_and_go():
    """Lennard-Jones (with its cached pair list) gives the exact forces after removing and adding."""
    from particles.forces import LennardJones

    lj = LennardJones.from_epsilon_sigma(skin=0.5)
    x = np.array([[0.0, 0.0], [1.1, 0.0], [5.0, 0.0]])
    ps = ParticleSystem(x, forces=[lj])
    ps.total_force(ps.X, 0.0)
    ps.remove_particles([1])
    ps.add_particles([[5.5, 0.0]])  # same count, other particles
    F = ps.total_force(ps.X, 0.0)
    np.testing.assert_allclose(F, lj(ps.X[:, 0]))
    assert abs(F[1, 0]) > 0


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda ps: ps.add_particles([[0.0, 0.0, 0.0]]), r"x must have shape \(any, 2\)"),
        (lambda ps: ps.add_particles([[0.0, 0.0]], m=-1.0), "m must be positive"),
        (lambda ps: ps.add_particles([[0.0, 0.0]], age=[1.0]), "unknown attributes \\['age'\\]"),
        (lambda ps: ps.remove_particles([7]), r"which indices must lie in \[0, 1\)"),
        (lambda ps: ps.remove_particles([True, False]), r"which as a boolean mask must have shape \(1,\)"),
        (lambda ps: ps.define_attribute("", 0.0), "name must be a non-empty string"),
    ],
)
def test_bad_population_changes(call, match):
    """Adding or removing particles wrongly raises a ValueError naming the argument."""
    ps = ParticleSystem([[0.0, 0.0]])
    with pytest.raises(ValueError, match=match):
        call(ps)


def test_run_to_an_earlier_time_names_t_end():
    """run(t_end) before the current time says t_end (not integrate's t1) and the current t."""
    ps = ParticleSystem([[0.0, 0.0]], t=2.0)
    with pytest.raises(ValueError, match=r"t_end must be >= the current time t = 2.0 s of the system, got 1.0"):
        ps.run(1.0, 0.1)
    for bad in ("later", np.nan, np.inf, None):
        with pytest.raises(ValueError, match="t_end must be a finite real number"):
            ps.run(bad, 0.1)
    assert ps.t == 2.0


@pytest.mark.parametrize("t", [np.nan, np.inf, "a", None, [0.0]])
def test_initial_time_must_be_a_finite_number(t):
    """ParticleSystem(t=...) refuses NaN, inf and non-numbers, naming t."""
    with pytest.raises(ValueError, match="t must be a finite real number"):
        ParticleSystem([[0.0, 0.0]], t=t)


def test_initial_time_accepts_numpy_scalars():
    """A NumPy time (as from a time array) is accepted and stored as a float."""
    ps = ParticleSystem([[0.0, 0.0]], t=np.float32(0.5))
    assert ps.t == 0.5 and type(ps.t) is float


def test_a_single_force_needs_no_list():
    """forces=Gravity(g) works like forces=[Gravity(g)]; a non-list non-force is a ValueError."""
    one = ParticleSystem([[0.0, 1.0]], forces=Gravity(g))
    listed = ParticleSystem([[0.0, 1.0]], forces=[Gravity(g)])
    assert len(one.forces) == 1
    np.testing.assert_array_equal(one.run(1.0, 0.1)[1], listed.run(1.0, 0.1)[1])
    with pytest.raises(ValueError, match="forces must be a list of Force objects .*got int"):
        ParticleSystem([[0.0, 0.0]], forces=3)
    with pytest.raises(ValueError, match="forces must be a list of Force objects, got the string 'gravity'"):
        ParticleSystem([[0.0, 0.0]], forces="gravity")


def test_run_blowup_option_lets_true_growth_through():
    """x'' = x grows like cosh t: over 30 s the default rule stops it, blowup=None gives cosh(30)."""
    repel = Field(lambda x, t: x)
    ps = ParticleSystem([[1.0, 0.0]], forces=[repel])
    with pytest.raises(SimulationDiverged, match=r"grew too much.*blowup=None"):
        ps.run(30.0, 0.01)
    assert ps.t == 0.0
    t, X = ps.run(30.0, 0.01, blowup=None)
    assert X[-1, 0, 0, 0] == pytest.approx(np.cosh(30.0), rel=1e-7)
    assert ps.t == 30.0
    step = ParticleSystem([[1.0, 0.0]], forces=[repel]).step(0.1, blowup=None)
    assert step[0, 0, 0] == pytest.approx(np.cosh(0.1), rel=1e-8)


def test_energy_and_momentum_of_a_given_state():
    """kinetic_energy, momentum and potential_energy use the state passed, else the current one."""
    ps = ParticleSystem([[0.0, 2.0], [1.0, 0.0]], v=[[3.0, 0.0], [0.0, -1.0]], m=[2.0, 1.0], forces=[Gravity(g)])
    assert ps.kinetic_energy() == pytest.approx(0.5 * 2.0 * 9.0 + 0.5 * 1.0)
    np.testing.assert_allclose(ps.momentum(), [6.0, -1.0])
    assert ps.potential_energy() == pytest.approx(2.0 * 9.81 * 2.0)
    X = np.zeros((2, 2, 2))
    assert ps.kinetic_energy(X) == 0.0 and ps.potential_energy(X) == 0.0
    np.testing.assert_array_equal(ps.momentum(X), [0.0, 0.0])


def test_runs_name_t_end_when_it_is_before_the_current_time():
    """ParticleSystem, Flock and ParticleEffect runs all say `t_end`, not the internal t1, when it lies in the past."""
    from particles.effects import Boids, Flock, ParticleEffect

    ps = ParticleSystem([[0.0, 0.0]], t=1.0)
    with pytest.raises(ValueError, match=r"t_end must be >= the current time t = 1.0 s of the system, got 0.5"):
        ps.run(0.5, 0.1)
    flock = Flock(np.zeros((3, 2)) + np.arange(3)[:, None], np.ones((3, 2)), Boids(1.0))
    with pytest.raises(ValueError, match="t_end must be >= the current time t = 0.0 s of the flock"):
        flock.run(-1.0, 0.1)
    with pytest.raises(ValueError, match="t_end must be >= the current time t = 0.0 s of the effect"):
        ParticleEffect(d=2).run(-1.0, 0.1)


# -- force reuse: one force evaluation per velocity-Verlet step ---------------


class CountingForce:
    """A position-only force that counts its evaluations (test helper): a spring to the origin."""

    uses_velocity = False
    uses_time = False

    def __init__(self):
        self.calls = 0

    def add_to(self, F, x, v, t, m):
        self.calls += 1
        F -= x


def lennard_jones_box(seed=0):
    """64 particles of a jittered lattice in a periodic box with Lennard-Jones forces (test helper)."""
    from particles.forces import LennardJones

    rng = np.random.default_rng(seed)
    g = np.arange(4) * 2.0
    x = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3) + rng.uniform(-0.1, 0.1, (64, 3))
    return x, rng.normal(size=x.shape), LennardJones.from_epsilon_sigma(box=8.0)


def test_verlet_run_evaluates_forces_once_per_step():
    """N verlet steps of position-only forces cost N + 1 force evaluations, not 2 N."""
    from particles.integrators import verlet

    x, v, lj = lennard_jones_box()
    count = CountingForce()
    ps = ParticleSystem(x, v=v, forces=[lj, count])
    t, X = ps.run(0.5, 0.005, method="verlet")
    assert len(t) - 1 == 100 and count.calls == 101
    assert verlet.fsal and verlet.order == 2
    ps.step(0.005, method="verlet")  # a single step: its start force is not known
    assert count.calls == 103


def test_reused_forces_give_the_same_trajectory_to_the_last_bit():
    """The run with force reuse equals the plain stepper loop (2 evaluations per step) bit for bit."""
    from particles import integrate

    x, v, lj = lennard_jones_box(1)
    v[3] = 0.0
    ps = ParticleSystem(x, v=v, forces=[lj, CountingForce()], pinned=[3])
    t, X = ps.run(0.4, 0.004, method="verlet", every=5)
    ref = ParticleSystem(x, v=v, forces=[lj, CountingForce()], pinned=[3])
    lj.reset()
    t_ref, X_ref = integrate(ref.derivative, ref.X, 0.0, 0.4, 0.004, method="verlet", every=5)
    assert ref.forces[1].calls == 2 * 100 and ps.forces[1].calls == 101
    np.testing.assert_array_equal(X, X_ref)
    np.testing.assert_array_equal(X[:, 3, 0], np.broadcast_to(x[3], X[:, 3, 0].shape))  # the pin holds


def test_velocity_dependent_or_other_steppers_are_not_reused():
    """With damping in the forces, or with RK4, every stage is evaluated (no stale force is reused)."""
    count = CountingForce()
    ps = ParticleSystem([[1.0, 0.0]], forces=[count, Damping(0.5)])
    ps.run(0.1, 0.01, method="verlet")
    assert count.calls == 20
    ps = ParticleSystem([[1.0, 0.0]], forces=[CountingForce()])
    ps.run(0.1, 0.01, method="rk4")
    assert ps.forces[0].calls == 40


def test_time_dependent_forces_are_reused_only_at_the_same_time():
    """A force of position and time is recomputed whenever the time differs, so results stay exact."""
    from particles import integrate

    field = Field(lambda x, t: -x * (1.0 + np.sin(3 * t)))
    ps = ParticleSystem([[1.0, 0.0], [0.0, 2.0]], v=[[0.0, 1.0], [1.0, 0.0]], forces=[field])
    t, X = ps.run(1.0, 0.01, method="verlet")
    ref = ParticleSystem([[1.0, 0.0], [0.0, 2.0]], v=[[0.0, 1.0], [1.0, 0.0]], forces=[field])
    _, X_ref = integrate(ref.derivative, ref.X, 0.0, 1.0, 0.01, method="verlet")
    np.testing.assert_array_equal(X, X_ref)


# -- the one loop: hooks between steps, records, solver objects --------------------------------------------


def test_a_hook_between_steps_sees_each_step_end_and_may_add_and_remove_particles():
    """between_steps is called once per step with the system at the step's end; births and deaths take effect."""
    ps = ParticleSystem([[0.0, 0.0]], v=[[1.0, 0.0]])
    seen = []

    def hook(system, t0):
        seen.append((t0, system.t, system.n))
        system.add_particles([[0.0, 1.0]], v=[[0.0, 0.0]])
        if system.n > 3:
            system.remove_particles([0])

    t, counts = ps.run(0.5, 0.1, method="euler", between_steps=hook, record=lambda system: system.n)
    assert [round(s[1], 12) for s in seen] == [0.1, 0.2, 0.3, 0.4, 0.5]
    assert [s[0] for s in seen[1:]] == [s[1] for s in seen[:-1]]  # each step starts where the last ended
    assert counts == [1, 2, 3, 3, 3, 3] and ps.n == 3 and ps.t == 0.5
    np.testing.assert_allclose(ps.X[:, 0, 1], 1.0)  # the first particle, moving along x, was removed


def test_a_hook_that_changes_the_count_needs_record():
    """Recording states of changing size without record= says what to do."""
    ps = ParticleSystem([[0.0, 0.0]])
    with pytest.raises(ValueError, match="particles born or removed.*record="):
        ps.run(0.3, 0.1, between_steps=lambda system, t0: system.add_particles([[1.0, 1.0]]))
    with pytest.raises(ValueError, match="between_steps must be a function"):
        ps.run(1.0, 0.1, between_steps=[42])


def test_hooks_and_records_leave_the_trajectory_unchanged():
    """A run with a hook that only watches gives the states of a plain run, bit for bit, recorded either way."""
    make = lambda: ParticleSystem([[0.0, 1.0], [1.0, 0.0]], v=[[0.3, 0.0], [0.0, -0.2]],  # noqa: E731
                                  forces=[NBodyGravity(G=1.0, softening=0.1)])
    t, X = make().run(2.0, 0.01, method="verlet", every=7)
    ps, calls = make(), []
    t2, X2 = ps.run(2.0, 0.01, method="verlet", every=7, between_steps=[lambda s, t0: calls.append(t0)])
    t3, X3 = make().run(2.0, 0.01, method="verlet", every=7, record=lambda system: system.state())
    np.testing.assert_array_equal(t, t2)
    np.testing.assert_array_equal(X, X2)
    np.testing.assert_array_equal(X, np.stack(X3))
    assert len(calls) == 200


def test_with_hooks_a_divergence_keeps_the_last_finite_state():
    """The hooks have seen (and may have changed) the system, so a blow-up leaves it at the failing step's start."""
    stiff = Field(lambda x, t: -1e6 * x)
    ps = ParticleSystem([[1.0, 0.0]], forces=[stiff])
    with pytest.raises(SimulationDiverged) as info:
        ps.run(10.0, 0.01, method="euler", between_steps=lambda system, t0: None)
    assert ps.t == pytest.approx(info.value.t) and np.all(np.isfinite(ps.X)) and ps.t > 0


def test_set_state_replaces_the_state_of_the_same_particles():
    """set_state copies a new state and time in; another shape, NaNs or moving pins are refused."""
    ps = ParticleSystem([[0.0, 0.0], [1.0, 0.0]], pinned=[0])
    X = np.zeros((2, 2, 2))
    X[1, 0] = [2.0, 3.0]
    ps.set_state(X, t=1.5)
    X[1, 0] = 0.0
    np.testing.assert_array_equal(ps.X[1, 0], [2.0, 3.0])
    assert ps.t == 1.5 and ps.X.flags.f_contiguous
    for bad, match in ((np.zeros((3, 2, 2)), "X must have shape"), (np.full((2, 2, 2), np.nan), "finite"),
                       (np.ones((2, 2, 2)), "v of pinned particles must be zero")):
        with pytest.raises(ValueError, match=match):
            ps.set_state(bad)


def test_run_accepts_solver_objects_and_refuses_another_systems():
    """A solver object (step(X, t, h), order) runs in the loop; one built for another system is refused."""
    from particles.integrators import Solver

    class ExactDrift(Solver):
        """x' = x + h v: exact for free particles."""
        order = 99

        def step(self, X, t, h):
            X_new = np.array(X, order="F")
            X_new[:, 0] += h * X[:, 1]
            return X_new

    ps = ParticleSystem([[0.0, 0.0]], v=[[1.0, 2.0]])
    t, X = ps.run(1.0, 0.25, method=ExactDrift(ps))
    np.testing.assert_allclose(X[-1, 0, 0], [1.0, 2.0])
    ps.step(0.5, method=ExactDrift(ps))
    np.testing.assert_allclose(ps.X[0, 0], [1.5, 3.0])
    with pytest.raises(ValueError, match="ExactDrift built for another system"):
        ps.run(2.0, 0.25, method=ExactDrift(ParticleSystem([[0.0, 0.0]])))


def test_a_tiny_step_is_one_step():
    """step(h) lands on t + h in one step even when h is far below the round-off of t."""
    ps = ParticleSystem([[0.0, 0.0]], v=[[1.0, 0.0]], t=1.0)
    ps.step(1e-8, method="euler")
    assert ps.t == 1.0 + 1e-8


def test_a_stepper_object_with_a_step_attribute_stays_a_stepper():
    """A thermostat wrapping Verlet (callable, with a .step attribute) is a stepper; a Solver is a solver."""
    from particles.integrators import Solver, as_stepper, is_solver
    from particles.md import Berendsen

    thermostat = Berendsen(T=1.0, tau=0.1, step="verlet")
    assert not is_solver(thermostat) and as_stepper(thermostat) is thermostat
    solver = Solver(ParticleSystem([[0.0, 0.0]]))
    assert is_solver(solver) and as_stepper(solver).solver is solver
