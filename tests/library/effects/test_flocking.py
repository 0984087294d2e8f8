"""Boids: the three rules against a brute-force reference, limits, and the measured flock behaviour."""

import numpy as np
import pytest

from particles import ParticleSystem
from particles.effects import Boids, Containment, Flock, polarization, spread


def random_flock(n=200, box=10.0, seed=0):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.0, box, (n, 2))
    angle = rng.uniform(0.0, 2 * np.pi, n)
    return x, np.stack([np.cos(angle), np.sin(angle)], axis=1)


def brute_force(rules, x, v):
    """The rules written with all pairs, one boid at a time: the O(n^2) reference."""
    a = np.zeros_like(x)
    for i in range(len(x)):
        r = x - x[i]
        dist = np.linalg.norm(r, axis=1)
        seen = (dist < rules.radius) & (dist > 0)
        if rules.view_angle < np.pi:
            cos = r @ v[i] / np.maximum(dist * np.linalg.norm(v[i]), 1e-300)
            seen &= cos >= np.cos(rules.view_angle)
        if not seen.any():
            continue
        close = seen & (dist < rules.separation_radius)
        a[i] += rules.cohesion * (x[seen].mean(axis=0) - x[i])
        a[i] += rules.alignment * (v[seen].mean(axis=0) - v[i])
        a[i] -= rules.separation * np.sum(r[close] / dist[close, None] ** 2, axis=0)
        norm = np.linalg.norm(a[i])
        if norm > rules.max_force:
            a[i] *= rules.max_force / norm
    return a


@pytest.mark.parametrize("view_angle", [np.pi, 2.0])
@pytest.mark.parametrize("d", [2, 3])
def test_rules_match_brute_force(view_angle, d):
    """Bucket-grid neighbours give the same steering as testing every pair, with and without a view angle."""
    rng = np.random.default_rng(d)
    x = rng.uniform(0, 4, (150, d))
    v = rng.normal(size=(150, d))
    rules = Boids(1.0, separation=0.3, alignment=0.7, cohesion=0.4, view_angle=view_angle, max_force=5.0)
    np.testing.assert_allclose(rules.accelerations(x, v), brute_force(rules, x, v), atol=1e-12)


def test_view_angle_hides_boids_behind():
    """A boid flying away from a neighbour does not see it; the neighbour, looking at it, does."""
    x = np.array([[0.0, 0.0], [1.0, 0.0]])
    v = np.array([[1.0, 0.0], [1.0, 0.0]])  # boid 1 leads, boid 0 follows
    rules = Boids(2.0, separation=0.0, alignment=0.0, cohesion=1.0, view_angle=np.pi / 2)
    a = rules.accelerations(x, v)
    np.testing.assert_allclose(a, [[1.0, 0.0], [0.0, 0.0]])


def test_each_rule_points_the_right_way():
    """Separation pushes apart, cohesion pulls to the centre, alignment turns towards the mean heading."""
    x = np.array([[0.0, 0.0], [0.2, 0.0]])
    v = np.array([[0.0, 1.0], [1.0, 0.0]])
    sep = Boids(1.0, separation=1.0, alignment=0.0, cohesion=0.0).accelerations(x, v)
    assert sep[0, 0] < 0 < sep[1, 0]
    coh = Boids(1.0, separation=0.0, alignment=0.0, cohesion=1.0).accelerations(x, v)
    np.testing.assert_allclose(coh, [[0.2, 0.0], [-0.2, 0.0]])
    ali = Boids(1.0, separation=0.0, alignment=1.0, cohesion=0.0).accelerations(x, v)
    np.testing.assert_allclose(ali, [[1.0, -1.0], [-1.0, 1.0]])


def test_speed_and_steering_limits():
    """Speeds stay within [min_speed, max_speed] and no steering exceeds max_force."""
    x, v = random_flock(100, box=3.0)
    rules = Boids(1.0, separation=1.0, alignment=1.0, cohesion=1.0, max_force=0.5)
    assert np.linalg.norm(rules.accelerations(x, 3 * v), axis=1).max() <= 0.5 + 1e-12
    flock = Flock(x, 3 * v, rules, min_speed=0.5, max_speed=1.5)
    t, X = flock.run(2.0, 0.05, every=10)
    speed = np.linalg.norm(X[:, :, 1], axis=2)
    assert speed.min() >= 0.5 - 1e-12 and speed.max() <= 1.5 + 1e-12


def test_polarization_rises_above_0_9_with_alignment():
    """From random headings (polarization about 0.1) a flock with alignment on flies one way (> 0.9)."""
    x, v = random_flock()
    rules = Boids(3.0, separation=0.1, alignment=2.0, cohesion=0.5, max_force=3.0)
    flock = Flock(x, v, rules, min_speed=0.5, max_speed=2.0)
    t, X = flock.run(15.0, 0.05, every=100)
    p = [polarization(Xk[:, 1]) for Xk in X]
    assert p[0] < 0.2
    assert p[-1] > 0.9  # measured 0.99


def test_without_alignment_headings_stay_disordered():
    """The control: with alignment off, the same start stays far from ordered."""
    x, v = random_flock()
    flock = Flock(x, v, Boids(3.0, separation=0.1, alignment=0.0, cohesion=0.5, max_force=3.0),
                  min_speed=0.5, max_speed=2.0)
    t, X = flock.run(15.0, 0.05, every=300)
    assert polarization(X[-1, :, 1]) < 0.5


def test_cohesion_keeps_the_flock_together():
    """With cohesion the spread stays bounded; without it the same flock disperses."""
    x, v = random_flock()
    spreads = {}
    for cohesion in (0.5, 0.0):
        rules = Boids(3.0, separation=0.1, alignment=2.0, cohesion=cohesion, max_force=3.0)
        t, X = Flock(x, v, rules, min_speed=0.5, max_speed=2.0).run(15.0, 0.05, every=20)
        spreads[cohesion] = [spread(Xk[:, 0]) for Xk in X]
    assert max(spreads[0.5]) < 1.2 * spreads[0.5][0]  # measured: 4.2 m at the start, never above
    assert spreads[0.0][-1] > 2 * spreads[0.5][-1]


def test_containment_turns_boids_back():
    """Containment pushes inward near the walls and does nothing in the middle."""
    wall = Containment([0.0, 0.0], [10.0, 10.0], margin=1.0, strength=2.0)
    F = wall(np.array([[0.5, 5.0], [5.0, 5.0], [10.5, 9.5]]), m=np.array([1.0, 1.0, 2.0]))
    np.testing.assert_allclose(F, [[1.0, 0.0], [0.0, 0.0], [-6.0, -2.0]])


def test_boids_is_a_force_for_any_system():
    """Boids plugs into ParticleSystem: F = m a."""
    x, v = random_flock(30, box=2.0)
    rules = Boids(1.0)
    ps = ParticleSystem(x, v=v, m=2.0, forces=[rules])
    np.testing.assert_allclose(ps.total_force(ps.X, 0.0), 2.0 * rules.accelerations(x, v))


def test_polarization_and_spread_values():
    """polarization is 1 for a parallel flock, 0 for opposite pairs; spread is the radius of gyration."""
    assert polarization([[1.0, 0.0], [3.0, 0.0]]) == pytest.approx(1.0)
    assert polarization([[1.0, 0.0], [-1.0, 0.0]]) == pytest.approx(0.0)
    assert spread([[1.0, 0.0], [-1.0, 0.0]]) == pytest.approx(1.0)


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: Boids(-1.0), "radius must be a positive"),
        (lambda: Boids(1.0, alignment=-1.0), "alignment must be a finite number >= 0"),
        (lambda: Boids(1.0, view_angle=4.0), r"view_angle must lie in \[0, pi\]"),
        (lambda: Flock([[0.0, 0.0]], [[1.0, 0.0]], Boids(1.0), min_speed=2.0, max_speed=1.0),
         "max_speed must be >= min_speed"),
        (lambda: Flock([[0.0, 0.0]], [[1.0, 0.0]], "boids"), "rules must be a Boids object"),
        (lambda: Containment([0.0, 0.0], [0.0, 1.0]), "hi must exceed lo"),
        (lambda: Boids(1.0).accelerations(np.zeros((3, 2)), np.zeros((2, 2))), r"v must have shape \(3, 2\)"),
        (lambda: Boids(1.0).accelerations(np.zeros(3), np.zeros(3)), "x must have 2 dimensions"),
    ],
)
def test_bad_input(make, match):
    """Mistakes raise ValueError naming the argument."""
    with pytest.raises(ValueError, match=match):
        make()


def test_inputs_are_not_modified():
    """Steering and running a flock leave the caller's arrays as they were."""
    x, v = random_flock(50, box=3.0)
    x.setflags(write=False)
    v.setflags(write=False)
    Boids(1.0).accelerations(x, v)
    Flock(x, 5 * v, Boids(1.0), max_speed=2.0).run(0.5, 0.05)


def test_a_blow_up_raises_simulation_diverged():
    """Boids that overflow raise SimulationDiverged naming the step, the time and the cause, not NaNs."""
    from particles import SimulationDiverged

    flock = Flock([[0.0, 0.0], [0.0, 1e-7]], [[0.0, 0.0], [0.0, 0.0]], Boids(1.0, separation=1e300))
    with pytest.raises(SimulationDiverged, match=r"step 1 \(t = 0 s\).*separation") as info:
        flock.step(0.1)
    assert info.value.step == 1
    np.testing.assert_array_equal(flock.system.X[:, 0], [[0.0, 0.0], [0.0, 1e-7]])  # the state is kept


def test_diverged_counts_the_steps():
    """Two boids closing in at 2 m/s blow up on the step that brings them within R_s, step 14 at t = 1.3 s."""
    from particles import SimulationDiverged

    rules = Boids(1.0, separation=1e308, alignment=0.0, cohesion=0.0)  # R_s = 0.5 m, reached after 1.3 s
    flock = Flock([[0.0, 0.0], [3.0, 0.0]], [[1.0, 0.0], [-1.0, 0.0]], rules)
    with pytest.raises(SimulationDiverged, match=r"step 14 \(t = 1\.3 s\)") as info:
        flock.run(5.0, 0.1)
    assert info.value.step == 14 and info.value.t == pytest.approx(1.3)
    assert np.all(np.isfinite(flock.system.X)) and flock.t == pytest.approx(1.3)


@pytest.mark.parametrize("view_angle", [np.pi, 2.0])
def test_boids_in_a_periodic_world_see_through_the_walls(view_angle):
    """With box=L the rules equal the brute force on minimum-image differences, for unwrapped positions."""
    from particles.md import minimum_image

    L = 10.0
    x, v = random_flock(60, box=L, seed=4)
    rules = Boids(radius=2.0, separation=0.5, alignment=1.0, cohesion=0.3, view_angle=view_angle, box=L)
    moved = x + np.random.default_rng(5).integers(-2, 3, size=x.shape) * L  # whole boxes away
    a = rules.accelerations(moved, v)
    ref = np.zeros_like(x)
    for i in range(len(x)):  # the brute force, seen from each boid with the minimum image
        y = x[i] + minimum_image(x - x[i], L)
        ref[i] = brute_force(Boids(radius=2.0, separation=0.5, alignment=1.0, cohesion=0.3,
                                   view_angle=view_angle), y, v)[i]
    np.testing.assert_allclose(a, ref, atol=1e-10)
    with pytest.raises(ValueError, match=r"box must be at least 2 x radius = 4 m"):
        Boids(radius=2.0, box=3.0)
