"""Emitters, lifetimes, colours by age and hierarchical particle systems."""

import numpy as np
import pytest

from particles import ParticleSystem
from particles.collisions import Collider, Plane
from particles.effects import ColorRamp, Cone, Disk, Emitter, ParticleEffect, ParticleEmitter, Point, SphereSurface
from particles.forces import Gravity

g = np.array([0.0, -9.81])


def irregular_steps(n=400, seed=0):
    """Step sizes from 0.1 ms to 0.1 s, with some far smaller and some far larger."""
    rng = np.random.default_rng(seed)
    h = 10 ** rng.uniform(-4, -1, n)
    h[::37] = 1e-7
    h[::53] = 0.7
    return h


@pytest.mark.parametrize("rate", [37.3, 10.0, 1000.0, 0.4])
def test_counts_are_exact_over_irregular_steps(rate):
    """After every step of an irregular sequence the total is floor(rate t): no drift."""
    emitter, rng, t = Emitter(rate, Point([0.0, 0.0])), np.random.default_rng(1), 0.0
    for h in irregular_steps():
        births = emitter.emit(t, t + h, rng)
        t += h
        assert emitter.count == np.floor(rate * t + 1e-9)
        assert np.all((births.t > t - h - 1e-12) & (births.t <= t + 1e-12))
    assert emitter.t_last == pytest.approx(emitter.count / rate)


def test_an_emitter_that_started_earlier_makes_nobody_before_the_first_step():
    """start < t0: counting goes on from start, but only particles born after t0 are created."""
    emitter = Emitter(10.0, Point([0.0, 0.0]), start=-1.05)
    births = emitter.emit(0.0, 0.1, np.random.default_rng(0))
    np.testing.assert_allclose(births.t, [0.05])
    assert emitter.count == 11


def test_the_slides_reset_rule_runs_slow():
    """Setting t_last = t loses the fractions: 10 particles/s in steps of 0.15 s gives 6.7/s."""
    exact, reset = Emitter(10.0, Point([0, 0])), Emitter(10.0, Point([0, 0]), carry=False)
    rng = np.random.default_rng(0)
    for k in range(60):  # 9 seconds
        for emitter in (exact, reset):
            emitter.emit(0.15 * k, 0.15 * (k + 1), rng)
    assert exact.count == 90
    assert reset.count == 60


def test_births_are_staggered_over_the_step():
    """Ten particles made in one step are born 1/rate apart, the last at the end of the step."""
    births = Emitter(100.0, Point([0.0, 0.0])).emit(0.0, 0.1, np.random.default_rng(0))
    np.testing.assert_allclose(births.t, np.arange(1, 11) / 100.0)


def test_newborns_are_advanced_by_their_partial_time():
    """Particle born at t_b is, at the end of the step, at v tau + g tau^2 / 2 with tau = t - t_b."""
    jet = Emitter(100.0, Point([0.0, 0.0]), Cone([1.0, 0.0], 2.0))
    effect = ParticleEffect(2, [jet], forces=[Gravity(g)])
    effect.step(0.1)
    tau = 0.1 - effect.system.attributes["birth"]
    np.testing.assert_allclose(effect.system.X[:, 0, 0], 2.0 * tau, atol=1e-15)
    np.testing.assert_allclose(effect.system.X[:, 0, 1], 0.5 * g[1] * tau**2, atol=1e-15)
    np.testing.assert_allclose(effect.system.X[:, 1, 1], g[1] * tau, atol=1e-15)
    np.testing.assert_allclose(effect.age(), tau)


def test_moving_emitter_spreads_births_along_its_path():
    """An emitter moving along x = t leaves each particle where it was at that particle's birth."""
    path = Point(lambda t: np.stack([t, np.zeros_like(t)], axis=-1))
    effect = ParticleEffect(2, [Emitter(50.0, path)])
    effect.run(1.0, h=0.25)  # four big steps, still a continuous trail
    birth = effect.system.attributes["birth"]
    np.testing.assert_allclose(effect.system.X[:, 0, 0], birth, atol=1e-12)
    np.testing.assert_allclose(np.sort(birth), np.arange(1, 51) / 50.0)


def test_moving_emitter_can_hand_on_its_velocity():
    """inherit=1 adds the emitter's velocity: particles ride along with the moving source."""
    path = Point(lambda t: np.stack([2.0 * t, np.zeros_like(t)], axis=-1))
    effect = ParticleEffect(2, [Emitter(50.0, path, Cone([0.0, 1.0], 1.0), inherit=1.0)])
    effect.run(1.0, h=0.25)
    np.testing.assert_allclose(effect.system.X[:, 1], [[2.0, 1.0]] * 50, atol=1e-8)
    np.testing.assert_allclose(effect.system.X[:, 0, 0], 2.0, atol=1e-8)  # all at the emitter now


def test_disk_positions():
    """Disk: inside the radius, in the plane across its normal, uniform per unit area."""
    rng = np.random.default_rng(0)
    t = np.zeros(20000)
    x2 = Disk([1.0, 2.0], 0.5).sample(rng, t)
    r2 = np.sum((x2 - [1.0, 2.0]) ** 2, axis=1)
    assert r2.max() <= 0.25 and np.mean(r2) == pytest.approx(0.125, rel=0.02)
    normal = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    x3 = Disk([0.0, 0.0, 1.0], 2.0, normal=normal).sample(rng, t)
    np.testing.assert_allclose((x3 - [0.0, 0.0, 1.0]) @ normal, 0.0, atol=1e-12)
    assert np.linalg.norm(x3 - [0, 0, 1.0], axis=1).max() <= 2.0


@pytest.mark.parametrize("d", [2, 3])
def test_sphere_surface_positions(d):
    """SphereSurface: on the sphere; with a polar band, at angles from the pole inside the band."""
    rng = np.random.default_rng(d)
    c = np.arange(d, dtype=float)
    x = SphereSurface(c, 1.5).sample(rng, np.zeros(5000))
    np.testing.assert_allclose(np.linalg.norm(x - c, axis=1), 1.5)
    assert np.linalg.norm(np.mean(x - c, axis=0)) < 0.06  # uniform: no side preferred
    band = SphereSurface(c, 1.5, polar=(0.5, 0.7), pole=np.eye(d)[0]).sample(rng, np.zeros(5000))
    angle = np.arccos(np.clip((band - c) @ np.eye(d)[0] / 1.5, -1, 1))
    assert angle.min() >= 0.5 - 1e-9 and angle.max() <= 0.7 + 1e-9


def test_expanding_ring():
    """A polar band that is a function of time: later births lie further from the pole."""
    ring = SphereSurface([0, 0, 0], 1.0, polar=lambda t: (t, t + 0.01))
    t = np.array([0.2, 0.2, 0.9, 0.9])
    x = ring.sample(np.random.default_rng(0), t)
    angle = np.arccos(x[:, 2])
    assert np.all((angle >= t - 1e-9) & (angle <= t + 0.01 + 1e-9))


@pytest.mark.parametrize("d", [2, 3])
def test_cone_velocities(d):
    """Cone: directions within the half-angle of the axis, speeds mean +- spread (Reeves)."""
    rng = np.random.default_rng(0)
    axis = np.ones(d) / np.sqrt(d)
    v = Cone(axis * 3, speed=4.0, spread=1.0, angle=0.3).sample(rng, 20000)
    speed = np.linalg.norm(v, axis=1)
    assert speed.min() >= 3.0 - 1e-12 and speed.max() <= 5.0 + 1e-12
    assert speed.mean() == pytest.approx(4.0, rel=0.01)
    cos = v @ axis / speed
    assert cos.min() >= np.cos(0.3) - 1e-12
    everywhere = Cone(axis, 1.0, angle=np.pi).sample(rng, 20000)
    assert np.linalg.norm(everywhere.mean(axis=0)) < 0.03  # an explosion: no direction preferred


def test_reeves_stochastic_count():
    """rate + rand * spread per step: counts vary within the bounds and average to the rate."""
    emitter, rng = Emitter(100.0, Point([0, 0]), rate_spread=50.0), np.random.default_rng(3)
    counts = [len(emitter.emit(0.02 * k, 0.02 * (k + 1), rng)) for k in range(2000)]
    assert min(counts) >= 0 and max(counts) <= 4  # (100 +- 50) x 0.02 = 1..3, +-1 for fractions
    assert len(set(counts)) >= 3
    assert np.mean(counts) == pytest.approx(2.0, rel=0.03)


def test_lifetimes_remove_old_particles():
    """With a fixed lifetime L, no particle is older than L and rate x L of them are alive."""
    effect = ParticleEffect(2, [Emitter(40.0, Point([0, 0]), Cone([0, 1], 1.0), lifetime=0.5)])
    frames = effect.run(3.0, h=0.01, every=10)
    assert all(s.age.max(initial=0) <= 0.5 + 1e-12 for s in frames)
    assert [len(s) for s in frames[-5:]] == [20] * 5  # rate x L: a particle lives [t_b, t_b + L)
    np.testing.assert_allclose(np.sort(frames[-1].age), np.arange(20) / 40.0, atol=1e-9)


def test_random_lifetimes():
    """Random lifetimes lie in mean +- spread; particles die when older than their own lifetime."""
    effect = ParticleEffect(2, [Emitter(200.0, Point([0, 0]), lifetime=(1.0, 0.5))], seed=4)
    effect.run(2.0, h=0.02)
    life = effect.system.attributes["lifetime"]
    assert life.min() >= 0.5 and life.max() <= 1.5 and np.ptp(life) > 0.8
    assert np.all(effect.age() <= life)
    assert len(life) == pytest.approx(200.0 * 1.0, rel=0.15)  # rate x mean lifetime


def test_particles_leaving_bounds_are_removed():
    """With bounds, particles outside the box are removed at the end of the step."""
    jet = Emitter(100.0, Point([0.0, 0.0]), Cone([1.0, 0.0], 1.0))
    effect = ParticleEffect(2, [jet], bounds=([-1.0, -1.0], [0.5, 1.0]))
    effect.run(2.0, h=0.01)
    assert effect.system.X[:, 0, 0].max() <= 0.5
    assert len(effect.system.X) == 51  # born in the last 0.5 s, both ends included (x = 0 and 0.5)


def test_colour_and_transparency_by_age():
    """ColorRamp interpolates colour and alpha over the relative age; tints multiply the colour."""
    ramp = ColorRamp(["yellow", "red", "black"], alphas=[1.0, 0.5, 0.0])
    np.testing.assert_allclose(ramp(np.array([0.0, 0.5, 1.0, 2.0])),
                               [[1, 1, 0, 1], [1, 0, 0, 0.5], [0, 0, 0, 0], [0, 0, 0, 0]])
    emitter = Emitter(10.0, Point([0, 0]), lifetime=1.0, tint="tab:blue")
    effect = ParticleEffect(2, [emitter], color=ColorRamp(["white"], alphas=[1.0, 0.0]))
    effect.run(1.0, h=0.05)
    rgba, age = effect.colors(), effect.age()
    np.testing.assert_allclose(rgba[:, 3], 1.0 - age)  # old particles fade
    from matplotlib.colors import to_rgb
    np.testing.assert_allclose(rgba[:, :3], [to_rgb("tab:blue")] * len(age))


def test_collider_keeps_newborns_out_of_solids():
    """An emitter below the floor of an effect with a collider: no particle is ever inside."""
    floor = Plane([0.0, 0.0], [0.0, 1.0])
    spray = Emitter(200.0, Disk([0.0, 0.05], 0.2), Cone([0.0, -1.0], 3.0, angle=1.0), lifetime=2.0)
    effect = ParticleEffect(2, [spray], forces=[Gravity(g)], collider=Collider(floor, restitution=0.3))
    for s in effect.run(1.0, h=0.02):
        assert floor.H(s.x).min(initial=0.0) >= -1e-12


def fireworks(shell_rate=5.0, stop=1.0, trail_rate=20.0, burst=10):
    shells = ParticleEffect(2, [Emitter(shell_rate, Point([0, 0]), Cone([0, 1], 8.0), lifetime=0.8, stop=stop,
                                        tint="random")], forces=[Gravity(g)], name="shells", seed=1)
    sparks = shells.add_child(ParticleEffect(2, name="sparks", seed=2))
    sparks.add_emitter(ParticleEmitter(shells, rate=trail_rate, lifetime=100.0, tint="parent"))
    sparks.add_emitter(ParticleEmitter(shells, count=burst, when="death", velocity=Cone([0, 1], 2.0, angle=np.pi),
                                       lifetime=100.0, tint="parent"))
    return shells, sparks


def test_hierarchical_counts_are_exact():
    """Parents emitted at R for T, each emitting r per second while alive and a burst at death."""
    shells, sparks = fireworks()
    steps = iter(np.tile(irregular_steps(300, seed=5) / 10, 5))
    while shells.t < 3.0:
        shells.step(next(steps))
    source = sparks.system.attributes["emitter"]
    assert shells.emitters[0].count == 5  # floor(R T)
    assert np.sum(source == 0) == 5 * 16  # floor(r L) each
    assert np.sum(source == 1) == 5 * 10  # one burst each
    assert sparks.system.attributes["tint"].std(axis=0).sum() > 0  # each shell's sparks have its colour


def test_children_start_where_their_parent_was():
    """A burst starts where its parent died, at the parent's death time, even within a step."""
    shell = Emitter(5.0, Point([0, 0]), Cone([0, 1], 8.0), lifetime=0.8, stop=0.2)  # one shell, born at 0.2 s
    shells = ParticleEffect(2, [shell], forces=[Gravity(g)], method="verlet")
    sparks = shells.add_child(ParticleEffect(2))
    sparks.add_emitter(ParticleEmitter(shells, count=30, when="death", lifetime=10.0))
    shells.run(1.1, h=0.03)  # the death at 1.0 s falls inside the step (0.99, 1.02]
    np.testing.assert_allclose(sparks.system.attributes["birth"], 1.0)
    y_death = 8.0 * 0.8 + 0.5 * g[1] * 0.8**2
    np.testing.assert_allclose(sparks.system.X[:, 0], [[0.0, y_death]] * 30, atol=3e-3)  # O(h^2) back-extrapolation
    assert shells.n == 0


def test_genesis_ring_of_secondary_systems():
    """Reeves' Genesis effect: secondary systems on a sphere's surface, each spraying away from it."""
    planet = np.zeros(3)
    ring = SphereSurface(planet, 1.0, polar=lambda t: (0.3 * t, 0.3 * t + 0.05))
    systems = ParticleEffect(3, [Emitter(40.0, ring, lifetime=0.5)], name="systems", seed=0)
    fire = systems.add_child(ParticleEffect(3, name="fire", seed=1))
    fire.add_emitter(ParticleEmitter(systems, rate=30.0, velocity=Cone([0, 0, 1], 1.0, angle=0.3), axis=planet,
                                     lifetime=0.2))
    systems.run(2.0, h=0.05)
    assert systems.emitters[0].count == 80  # floor(40 x 2) secondary systems made
    np.testing.assert_allclose(np.linalg.norm(systems.system.X[:, 0], axis=1), 1.0)  # on the surface
    x, v = fire.system.X[:, 0], fire.system.X[:, 1]
    outward = np.sum(v * (x - v * fire.age()[:, None]), axis=1) / np.linalg.norm(v, axis=1)
    assert np.all(outward >= np.cos(0.3) - 1e-9)  # each jet points away from the planet
    alive = systems.n
    assert alive == 20  # rate x lifetime


def test_emitters_attached_to_a_plain_particle_system():
    """Each particle of an ordinary ParticleSystem can be an emitter (a comet and its tail)."""
    comets = ParticleSystem([[0.0, 0.0], [5.0, 0.0], [0.0, 5.0]], v=[[1.0, 0.0]] * 3)
    tails = ParticleEffect(2, [ParticleEmitter(comets, rate=10.0, lifetime=100.0)])
    for k in range(20):
        comets.step(0.05)
        tails.step(0.05)
    assert tails.n == 3 * 10
    assert np.all(tails.system.X[:, 0, 0] <= comets.X[:, 0, 0].max())


def test_three_generations():
    """A child of a child: grandchildren bursts from the death of every child."""
    shells, sparks = fireworks(trail_rate=1e-9)
    sparks.emitters[1].lifetime = (0.1, 0.0)
    crackle = sparks.add_child(ParticleEffect(2, name="crackle"))
    crackle.add_emitter(ParticleEmitter(sparks, count=2, when="death", lifetime=10.0))
    shells.run(2.0, h=0.01)
    assert crackle.n == 2 * 5 * 10


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: Emitter(-1.0, Point([0, 0])), "rate must be a finite number >= 0"),
        (lambda: Emitter(10.0, Point([0, 0]), rate_spread=20.0), "rate spread must not exceed its mean"),
        (lambda: Emitter(10.0, [0, 0]), "shape must be a Point, Disk or SphereSurface"),
        (lambda: Emitter(10.0, Point([0, 0]), lifetime=(1.0, 2.0)), "lifetime spread must not exceed"),
        (lambda: Emitter(10.0, Point([0, 0]), Cone([0, 0, 1], 1.0)), "velocity has 3 components"),
        (lambda: Emitter(10.0, Point([0, 0]), start=2.0, stop=1.0), "stop must be later than start"),
        (lambda: Cone([0, 0], 1.0), "direction must be a non-zero vector"),
        (lambda: Cone([0, 1], 1.0, angle=4.0), r"angle must lie in \[0, pi\]"),
        (lambda: SphereSurface([0, 0, 0], 1.0, polar=(1.0, 0.5)), "polar must be"),
        (lambda: ParticleEmitter(ParticleSystem([[0.0, 0.0]]), count=3, when="death"), "needs a source with lifetimes"),
        (lambda: ParticleEmitter(ParticleSystem([[0.0, 0.0]])), "rate .* is needed"),
        (lambda: ParticleEffect(4), "d must be 2 or 3"),
        (lambda: ParticleEffect(2, [Emitter(1.0, Point([0, 0, 0]))]), "another dimension"),
        (lambda: ParticleEffect(2, color="red"), "color must be a ColorRamp"),
        (lambda: ColorRamp(["nocolour"]), "colors must be a list of Matplotlib colours"),
        (lambda: ParticleEffect(2).step(-0.1), "h must be a positive finite number"),
        (lambda: Emitter(10.0, Point([0, 0])).emit(0.0, np.nan, np.random.default_rng(0)), "t1 must be finite"),
        (lambda: Emitter(10.0, Point([0, 0])).emit(-np.inf, 1.0, np.random.default_rng(0)), "t0 must be finite"),
        (lambda: Emitter(10.0, Point([0, 0])).emit(1.0, 0.5, np.random.default_rng(0)), "t1 must not be earlier"),
        (lambda: ParticleEmitter(ParticleSystem([[0.0, 0.0]]), rate=1.0).emit(0.0, np.inf, np.random.default_rng(0)),
         "t1 must be finite"),
        (lambda: ParticleEmitter("x", rate=1), "source must be a ParticleSystem or a ParticleEffect, got str"),
        (lambda: Emitter(10.0, Point([0, 0]), tint="nocolour"), "tint must be a Matplotlib colour"),
        (lambda: ParticleEmitter(ParticleSystem([[0.0, 0.0]]), rate=1.0, tint=(1.0, 2.0)),
         "tint must be a Matplotlib colour"),
    ],
)
def test_bad_input(make, match):
    """Mistakes raise ValueError naming the argument."""
    with pytest.raises(ValueError, match=match):
        make()


def test_diverged_reports_the_step_it_happened_in():
    """A force that turns infinite at t = 0.45 s stops the run at step 6 (t = 0.5 s), not 'step 0'."""
    from particles import SimulationDiverged
    from particles.forces import Field

    burst = Field(lambda x, t: np.where(t >= 0.45, np.inf, 0.0) * np.ones_like(x))
    jet = Emitter(100.0, Point([0.0, 0.0]), Cone([1.0, 0.0], 1.0), stop=0.2)
    effect = ParticleEffect(2, [jet], forces=[burst], name="jet")
    with pytest.raises(SimulationDiverged, match=r"step 6 \(t = 0\.5 s\).*'jet'") as info:
        effect.run(1.0, h=0.1)
    assert info.value.step == 6
