"""Implicit surfaces, collision response, and the two fixes of the overshooting problem."""

import numpy as np
import pytest

from particles import ParticleSystem
from particles.collisions import (Box, Collider, Complement, Intersection, Plane, Sphere, Union,
                                  respond)
from particles.crossing import first_crossing, hermite
from particles.forces import Gravity

g = 9.81

SURFACES_3D = {
    "plane": Plane([0.0, 0.0, 0.5], [1.0, 2.0, 3.0]),
    "sphere": Sphere([0.1, -0.2, 0.3], 0.8),
    "container sphere": Sphere([0.1, -0.2, 0.3], 0.8, container=True),
    "box": Box([-1.0, -0.5, -0.25], [1.0, 0.5, 0.75]),
    "container box": Box([-1.0, -0.5, -0.25], [1.0, 0.5, 0.75], container=True),
    "union": Sphere([0.0, 0.0, 0.0], 0.7) | Box([0.3, -0.3, -0.3], [1.2, 0.3, 0.3]),
    "intersection": Sphere([0.0, 0.0, 0.0], 1.0) & Plane([0.2, 0.0, 0.0], [-1.0, 0.0, 0.0]),
    "complement": ~Box([-0.5, -0.5, -0.5], [0.5, 0.5, 0.5]),
}
SURFACES_2D = {
    "plane": Plane([0.0, 0.0], [0.0, 1.0]),
    "sphere": Sphere([0.5, 0.0], 1.0),
    "container box": Box([-1.0, -1.0], [1.0, 2.0], container=True),
    "union": Sphere([0.0, 0.0], 0.5) | Sphere([0.6, 0.0], 0.4),
}
ALL = [(f"3d {k}", s) for k, s in SURFACES_3D.items()] + [(f"2d {k}", s) for k, s in SURFACES_2D.items()]
PRIMITIVES = [(k, s) for k, s in ALL if not any(w in k for w in ("union", "intersection", "complement"))]


def random_points(surface, n=400, seed=0):
    return np.random.default_rng(seed).uniform(-1.5, 1.5, (n, surface.d))


@pytest.mark.parametrize(
    "surface, inside, outside, on",
    [
        (Plane([0, 0, 0], [0, 0, 1]), [0, 0, -1], [3, 4, 0.1], [5, -2, 0]),
        (Sphere([1, 1], 2.0), [1.5, 1.0], [4.0, 1.0], [3.0, 1.0]),
        (Sphere([1, 1], 2.0, container=True), [4.0, 1.0], [1.5, 1.0], [1.0, 3.0]),
        (Box([0, 0, 0], [1, 2, 3]), [0.5, 1.0, 2.9], [0.5, 1.0, 3.1], [1.0, 1.0, 1.0]),
        (Box([0, 0], [1, 2], container=True), [1.5, 1.0], [0.5, 1.0], [0.0, 0.5]),
        (Sphere([0, 0], 1.0) | Sphere([2, 0], 1.0), [2.5, 0.0], [1.0, 0.5], [3.0, 0.0]),
        (Sphere([0, 0], 1.0) & Sphere([1, 0], 1.0), [0.5, 0.0], [-0.5, 0.0], [0.0, 0.0]),
        (~Sphere([0, 0], 1.0), [0.0, 2.0], [0.0, 0.5], [1.0, 0.0]),
    ],
)
def test_sign_of_H(surface, inside, outside, on):
    """H < 0 inside the solid, > 0 in free space, 0 on the surface."""
    assert surface.H(inside) < 0 and surface.inside(inside)
    assert surface.H(outside) > 0 and not surface.inside(outside)
    assert surface.H(on) == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("name, surface", ALL)
def test_gradient_matches_finite_differences(name, surface):
    """grad H agrees with central differences wherever H is smooth (kinks are rare)."""
    x = random_points(surface)
    grad = surface.gradient(x)
    delta = 1e-6
    fd, kink = np.empty_like(x), np.zeros(len(x), dtype=bool)
    H0 = surface.H(x)
    for a in range(surface.d):
        e = np.zeros(surface.d)
        e[a] = delta
        Hp, Hm = surface.H(x + e), surface.H(x - e)
        fd[:, a] = (Hp - Hm) / (2 * delta)
        kink |= np.abs(Hp + Hm - 2 * H0) > 1e-9  # a kink within delta (curvature alone gives ~1e-12)
    assert kink.mean() < 0.02
    np.testing.assert_allclose(grad[~kink], fd[~kink], atol=1e-6)
    normal = surface.normal(x)
    np.testing.assert_allclose(np.linalg.norm(normal, axis=1), 1.0)


@pytest.mark.parametrize("name, surface", PRIMITIVES)
def test_closest_point_of_primitives_is_on_surface_and_nearest(name, surface):
    """The closest point has H = 0 and lies at distance |H(x)| along the normal (exact signed distance)."""
    x = random_points(surface, seed=1)
    p = surface.closest_point(x)
    np.testing.assert_allclose(surface.H(p), 0.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(p - x, axis=1), np.abs(surface.H(x)), atol=1e-12)
    away = np.abs(surface.H(x)) > 1e-3  # x - p is along the normal at x
    np.testing.assert_allclose((x - p)[away], surface.H(x)[away, None] * surface.normal(x)[away], atol=1e-12)


def test_closest_point_on_sphere_against_brute_force():
    """Against a dense sampling of the sphere, no surface point is closer than the one returned."""
    rng = np.random.default_rng(2)
    ball = Sphere([0.2, 0.0, -0.1], 0.9)
    u = rng.normal(size=(20000, 3))
    samples = ball.center + ball.radius * u / np.linalg.norm(u, axis=1)[:, None]
    x = rng.uniform(-2, 2, (50, 3))
    brute = np.min(np.linalg.norm(x[:, None] - samples[None], axis=2), axis=1)
    ours = np.linalg.norm(ball.closest_point(x) - x, axis=1)
    assert np.all(ours <= brute + 1e-12)
    assert np.all(brute - ours < 0.03)  # the sampling is dense enough to come close


@pytest.mark.parametrize("name, surface", [(k, s) for k, s in ALL if k not in dict(PRIMITIVES)])
def test_closest_point_of_combinations(name, surface):
    """Combinations: the closest point is on the combined surface; outside a union it is the nearest."""
    x = random_points(surface, seed=3)
    p = surface.closest_point(x)
    np.testing.assert_allclose(surface.H(p), 0.0, atol=1e-9)
    if isinstance(surface, Union):
        out = surface.H(x) > 0  # outside, min of signed distances is the exact distance
        np.testing.assert_allclose(np.linalg.norm(p - x, axis=1)[out], surface.H(x)[out], atol=1e-12)


def test_operators_build_combinations():
    """a | b, a & b and ~a build Union, Intersection and Complement; unions flatten."""
    a, b, c = Sphere([0, 0], 1.0), Sphere([1, 0], 1.0), Plane([0, 0], [0, 1])
    assert isinstance(a | b, Union) and isinstance(a & b, Intersection) and isinstance(~a, Complement)
    assert len(((a | b) | c).parts) == 3
    x = random_points(a)
    np.testing.assert_allclose((~a).H(x), Sphere([0, 0], 1.0, container=True).H(x))
    np.testing.assert_allclose((~a).gradient(x), Sphere([0, 0], 1.0, container=True).gradient(x))


def test_crossing_of_segments_is_exact():
    """Segment against plane and sphere: the entry fraction matches the analytic intersection."""
    plane = Plane([0, 0, 0], [0, 0, 1])
    x0 = np.array([[0, 0, 3.0], [1, 1, 1.0], [0, 0, -1.0]])
    x1 = np.array([[0, 0, -1.0], [2, 1, 0.5], [0, 0, -2.0]])
    np.testing.assert_allclose(plane.crossing(x0, x1), [0.75, 1.0, 0.0], atol=1e-12)
    ball = Sphere([0, 0, 0], 1.0)
    s = ball.crossing([[-3.0, 0.5, 0.0]], [[3.0, 0.5, 0.0]])
    assert s[0] * 6.0 - 3.0 == pytest.approx(-np.sqrt(0.75), abs=1e-12)


def test_first_crossing_finds_the_first_of_two_entries():
    """A path that enters, leaves and re-enters a thin slab gets its first entry, not a later one."""
    slab = Box([0.2, -1.0], [0.3, 1.0])
    x0, x1 = np.array([[0.0, 0.0]]), np.array([[1.0, 0.0]])
    s, s_in = first_crossing(slab, lambda k, s: x0[k] + s[:, None] * (x1[k] - x0[k]), 1, samples=16)
    assert s[0] == pytest.approx(0.2, abs=1e-12) and s_in[0] >= s[0]


def test_hermite_reproduces_constant_acceleration():
    """The cubic Hermite path of a ballistic step is the exact parabola, positions and velocities."""
    x0, v0, a, h = np.array([[0.0, 2.0]]), np.array([[1.0, 3.0]]), np.array([0.0, -g]), 0.1
    x1, v1 = x0 + v0 * h + 0.5 * a * h**2, v0 + a * h
    s = np.array([0.37])
    x, v = hermite(x0, v0, x1, v1, h, s)
    tau = 0.37 * h
    np.testing.assert_allclose(x, x0 + v0 * tau + 0.5 * a * tau**2, atol=1e-15)
    np.testing.assert_allclose(v, v0 + a * tau, atol=1e-14)


def test_response_reflects_normal_and_keeps_tangential():
    """v <- v_t - eps v_n; impulse per unit mass -(1 + eps) v_n; separating particles unchanged."""
    v = np.array([[2.0, -3.0], [1.0, 4.0]])
    n = np.array([[0.0, 1.0], [0.0, 1.0]])
    v_new, dv_n, dv_t = respond(v, n, restitution=0.6)
    np.testing.assert_allclose(v_new, [[2.0, 1.8], [1.0, 4.0]])
    np.testing.assert_allclose(dv_n, [[0.0, 4.8], [0.0, 0.0]])
    np.testing.assert_array_equal(dv_t, 0.0)


def test_coulomb_friction_slows_but_never_reverses():
    """Friction removes mu (1 + eps) |v_n| of tangential speed, and stops a slow slide dead."""
    n = np.array([[0.0, 1.0], [0.0, 1.0]])
    v = np.array([[5.0, -2.0], [0.5, -2.0]])
    v_new, dv_n, dv_t = respond(v, n, restitution=0.5, friction=0.4)
    np.testing.assert_allclose(v_new, [[5.0 - 0.4 * 1.5 * 2.0, 1.0], [0.0, 1.0]])
    assert np.all(np.abs(dv_t[:, 0]) <= 0.4 * np.abs(dv_n[:, 1]) + 1e-15)


def drop_ball(method, restitution, n_bounces, h=0.01, stepper="verlet", height=1.0, longer=1.0, apex=False):
    """Bounce heights of a ball dropped on the floor y = 0, one per arc between contacts.

    The largest sampled y, or with `apex` the top of the parabola through the
    sampled states, ``y + v_y^2 / (2 g)`` (exact on a ballistic arc, and free
    of the sampling error that matters for low bounces).
    """
    ps = ParticleSystem([[0.0, height]], forces=[Gravity([0.0, -g])])
    floor = Collider(Plane([0.0, 0.0], [0.0, 1.0]), restitution=restitution, method=method)
    t_end = (n_bounces + 0.5) * 2 * np.sqrt(2 * height / g) * longer
    t, X, contacts = floor.run(ps, t_end, h, method=stepper)
    y = X[:, 0, 0, 1] + (X[:, 0, 1, 1] ** 2 / (2 * g) if apex else 0.0)
    edges = np.concatenate([[-1.0], contacts.time])
    arcs = [(t > a) & (t < b) for a, b in zip(edges[:-1], edges[1:])]
    return np.array([y[arc].max() for arc in arcs if arc.any()]), contacts


@pytest.mark.parametrize("stepper", ["verlet", "rk4"])
def test_elastic_bounce_keeps_its_height_with_backtracking(stepper):
    """eps = 1 and backtracking: 20 bounces, every height within 1% of the drop height."""
    heights, contacts = drop_ball("backtrack", 1.0, 20, stepper=stepper)
    assert len(contacts) >= 20
    np.testing.assert_allclose(heights[:21], 1.0, rtol=0.01)
    np.testing.assert_allclose(contacts.time[0], np.sqrt(2 / g), rtol=1e-9)  # the exact impact time


@pytest.mark.parametrize("stepper", ["verlet", "rk4"])
def test_contacts_count_bounces_without_round_off_contacts(stepper):
    """Issue 13: an elastic ball logs one contact per bounce, every one with an impulse (none after round-off)."""
    heights, contacts = drop_ball("backtrack", 1.0, 20, stepper=stepper)
    assert len(contacts) == 20 and len(np.unique(contacts.time)) == 20
    assert np.all(contacts.impulse[:, 1] > 0)


def test_resting_and_leaving_particles_are_not_logged():
    """A dead-stopped ball logs its one impact; a particle inside by round-off and leaving logs nothing."""
    _, contacts = drop_ball("backtrack", 0.0, 3)
    assert len(contacts) == 1 and contacts.impulse[0, 1] > 0
    floor = Plane([0.0, 0.0], [0.0, 1.0])
    X_old = np.array([[[0.0, -1e-18], [0.0, 1.0]]])  # on the floor by round-off, moving up
    X_new = np.array([[[0.0, -1e-18], [0.0, 1.0]]])
    for method in ("backtrack", "project"):
        X, contacts = Collider(floor, method=method).collide(X_old, X_new, 0.0, 0.01)
        assert len(contacts) == 0 and X[0, 0, 1] >= 0.0
    X_deep = np.array([[[0.0, -0.1], [0.0, 1.0]]])  # a real penetration is still reported, even when leaving
    X, contacts = Collider(floor, method="project").collide(X_deep, X_deep, 0.0, 0.01)
    assert len(contacts) == 1 and X[0, 0, 1] == 0.0


@pytest.mark.parametrize("eps", [0.8, 0.5])
def test_heights_shrink_by_restitution_squared(eps):
    """With eps < 1 each bounce reaches eps^2 of the previous height (within 1%)."""
    heights, _ = drop_ball("backtrack", eps, 6 if eps > 0.6 else 4, h=0.02, apex=True)
    ratios = heights[1:5] / heights[:4]
    np.testing.assert_allclose(ratios, eps**2, rtol=0.01)


def test_projection_visibly_changes_the_energy():
    """The quick fix: moving the ball up to the floor and reflecting adds height at every bounce."""
    heights, _ = drop_ball("project", 1.0, 20, longer=1.3)
    assert heights[20] > 1.1  # more than 10% higher after 20 bounces (measured: 1.43 at h = 0.01 s)
    assert np.all(np.diff(heights[:21]) >= -1e-9)


@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("method", ["backtrack", "project"])
def test_no_particle_ends_a_step_inside_a_solid(d, method):
    """Fast particles in a box with obstacles (corners, a union, a hole): H >= 0 after every step."""
    rng = np.random.default_rng(d)
    scene = (Box(-np.ones(d), np.ones(d), container=True) | Sphere(np.zeros(d), 0.4)
             | (Box(-0.9 * np.ones(d), np.r_[-0.5, -0.5, 0.9][:d]) & ~Sphere(-0.7 * np.ones(d), 0.2)))
    x = rng.uniform(-0.95, 0.95, (600, d))
    x = x[scene.H(x) > 0]
    ps = ParticleSystem(x, v=rng.normal(0.0, 5.0, x.shape), forces=[Gravity(np.r_[np.zeros(d - 1), -g])])
    collider = Collider(scene, restitution=0.7, friction=0.2, method=method)
    for _ in range(30):
        X_old = ps.state()
        ps.step(0.01, method="verlet")
        X, _ = collider.collide(X_old, ps.X, ps.t - 0.01, 0.01)
        ps.X = np.asfortranarray(X)
        assert scene.H(X[:, 0]).min() >= -1e-12


def test_backtracking_catches_a_particle_crossing_a_thin_wall():
    """A particle that would pass through a thin wall within one step is stopped by backtracking only."""
    wall = Box([0.45, -1.0], [0.55, 1.0])
    X_old = np.array([[[0.0, 0.0], [100.0, 0.0]]])
    X_new = np.array([[[1.0, 0.0], [100.0, 0.0]]])  # 1 m in a 0.01 s step, straight through
    X, contacts = Collider(wall, method="backtrack", samples=16).collide(X_old, X_new, 0.0, 0.01)
    np.testing.assert_allclose(X[0], [[-0.1, 0.0], [-100.0, 0.0]], atol=1e-9)
    np.testing.assert_allclose(contacts.time, [0.0045])
    np.testing.assert_allclose(contacts.normal, [[-1.0, 0.0]])
    X, contacts = Collider(wall, method="project").collide(X_old, X_new, 0.0, 0.01)
    assert len(contacts) == 0 and X[0, 0, 0] == 1.0


def test_corner_of_a_container_reflects_both_components():
    """Diagonally into a box corner with eps = 1: both velocity components reverse, no energy lost."""
    box = Box([0.0, 0.0], [1.0, 1.0], container=True)
    X_old = np.array([[[0.9, 0.9], [2.0, 2.0]]])
    X_new = np.array([[[1.1, 1.1], [2.0, 2.0]]])
    X, contacts = Collider(box).collide(X_old, X_new, 0.0, 0.1)
    np.testing.assert_allclose(X[0, 1], [-2.0, -2.0])
    np.testing.assert_allclose(X[0, 0], [0.9, 0.9], atol=1e-9)
    assert box.H(X[:, 0]).min() >= 0


def test_impulses_are_the_momentum_change():
    """The reported impulses add up to m (v_after - v_before) of a single bounce, friction included."""
    m = 2.5
    X_old = np.array([[[0.0, 0.05], [3.0, -2.0]]])
    X_new = np.array([[[0.3, -0.15], [3.0, -2.0]]])
    X, contacts = Collider(Plane([0, 0], [0, 1]), restitution=0.5, friction=0.3).collide(X_old, X_new, 0.0, 0.1, m=m)
    assert len(contacts) == 1
    np.testing.assert_allclose(contacts.impulse, [[0.0, m * 1.5 * 2.0]])
    np.testing.assert_allclose(contacts.total_impulse(), m * (X[0, 1] - X_old[0, 1]))
    np.testing.assert_allclose(contacts.point, [[0.075, 0.0]], atol=1e-12)


def test_pinned_particles_and_inputs_are_untouched():
    """Pinned particles keep their state even inside the solid; X_old and X_new are not modified."""
    X_old = np.array([[[0.0, 0.1], [0.0, -1.0]], [[1.0, 0.1], [0.0, -1.0]]])
    X_new = np.array([[[0.0, -0.1], [0.0, -1.0]], [[1.0, -0.1], [0.0, -1.0]]])
    before = (X_old.copy(), X_new.copy())
    for method in ("backtrack", "project"):
        X, contacts = Collider(Plane([0, 0], [0, 1]), method=method).collide(X_old, X_new, 0.0, 0.2, pinned=[1])
        np.testing.assert_array_equal(X[1], X_new[1])
        assert X[0, 0, 1] >= 0 and contacts.index.tolist() == [0]
    np.testing.assert_array_equal(X_old, before[0])
    np.testing.assert_array_equal(X_new, before[1])


def test_resolve_projects_a_state():
    """resolve() moves particles inside onto the surface and reflects their velocities."""
    collider = Collider(Sphere([0, 0], 1.0), restitution=0.0)
    x, v, contacts = collider.resolve([[0.5, 0.0], [2.0, 0.0]], [[-1.0, 1.0], [0, 0]])
    np.testing.assert_allclose(x, [[1.0, 0.0], [2.0, 0.0]])
    np.testing.assert_allclose(v, [[0.0, 1.0], [0.0, 0.0]])
    assert contacts.index.tolist() == [0]


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: Sphere([0, 0], -1.0), "radius must be a positive"),
        (lambda: Plane([0, 0], [0, 0]), "normal must be a non-zero vector"),
        (lambda: Box([0, 0], [1, -1]), "hi must exceed lo"),
        (lambda: Sphere([0, 0], 1.0) | Sphere([0, 0, 0], 1.0), "same dimension"),
        (lambda: Collider(Plane([0, 0], [0, 1]), restitution=1.5), r"restitution must lie in \[0, 1\]"),
        (lambda: Collider(Plane([0, 0], [0, 1]), friction=-1), "friction must be a finite number >= 0"),
        (lambda: Collider(Plane([0, 0], [0, 1]), method="bounce"), "unknown method 'bounce'"),
        (lambda: Collider("floor"), "surface must be a Surface"),
        (lambda: Sphere([0, 0], 1.0).H([[0.0, 0.0, 0.0]]), r"x must have shape \(n, 2\)"),
        (lambda: Collider(Plane([0, 0], [0, 1])).collide(np.zeros((3, 2, 3)), np.zeros((3, 2, 3)), 0, 0.1),
         r"X_old must have shape \(n, 2, 2\)"),
        (lambda: Collider(Plane([0, 0], [0, 1])).collide(np.zeros((3, 2, 2)), np.zeros((3, 2, 2)), 0, 0.0),
         "h must be a positive finite number"),
        (lambda: Collider(Plane([0, 0], [0, 1])).collide(np.zeros((3, 2, 2)), np.zeros((3, 2, 2)), 0, 0.1, pinned=[5]),
         r"pinned indices must lie in \[0, 3\)"),
        (lambda: respond([[1.0, -1.0]], [[0.0, 2.0]]), r"n must be unit normals .* got \|n\| = 2"),
        (lambda: respond([[1.0, -1.0]], [[0.0, 0.0]]), r"n must be unit normals .* got \|n\| = 0"),
        (lambda: Collider(Plane([0, 0], [0, 1])).collide(np.zeros((3, 2, 2)), np.zeros((3, 2, 2)), 0, 0.1,
                                                          m=[1.0, 2.0]), r"m must be a number or have shape \(3,\)"),
        (lambda: Collider(Plane([0, 0], [0, 1])).collide(np.zeros((3, 2, 2)), np.zeros((3, 2, 2)), 0, 0.1, m=-1.0),
         "m must be positive"),
        (lambda: Collider(Plane([0, 0], [0, 1])).resolve(np.zeros((3, 2)), np.zeros((3, 2)), m=[1.0, 0.0, 1.0]),
         "m must be positive"),
        (lambda: Collider(Plane([0, 0], [0, 1])).resolve(np.zeros((3, 2)), np.zeros((3, 2)), m=np.ones((3, 1))),
         r"m must be a number or have shape \(3,\)"),
    ],
)
def test_bad_input(make, match):
    """Mistakes raise ValueError naming the argument."""
    with pytest.raises(ValueError, match=match):
        make()


def test_run_reports_divergence():
    """Collider.run raises SimulationDiverged (not NaNs) when the stepper blows up."""
    from particles import SimulationDiverged
    from particles.forces import Field

    ps = ParticleSystem([[1.0, 1.0]], forces=[Field(lambda x, t: [-1e12, 0.0] * x)])  # along the floor
    with pytest.raises(SimulationDiverged, match="diverged at step"):
        Collider(Plane([0.0, 0.0], [0.0, 1.0])).run(ps, 10.0, 0.1, method="euler")


def test_bounce_study_table():
    """The lecture's bounce study: backtracking follows eps^(2k) to round-off, projection does not."""
    from particles.studies.bounce import bounce_study, format_bounce_table

    study = bounce_study(restitutions=(1.0,), bounces=5, h=0.02)
    assert study["drift"]["backtrack", 1.0] < 1e-9
    assert study["drift"]["project", 1.0] > 0.05
    assert "backtrack  1.00        5" in format_bounce_table(study)


def test_bounce_table_prints_the_height_ratios():
    """The table prints the min-max of H_k / H_(k-1): eps^2 = 0.64 for backtracking, 0.65 to 0.70 for projection."""
    from particles.studies.bounce import bounce_study, format_bounce_table

    study = bounce_study(restitutions=(0.8,), h=0.01)
    lo, hi = study["ratio"]["backtrack", 0.8]
    assert lo == pytest.approx(0.64, abs=1e-12) and hi == pytest.approx(0.64, abs=1e-12)
    lo, hi = study["ratio"]["project", 0.8]
    assert 0.645 < lo < 0.66 and 0.695 < hi < 0.705  # measured 0.6540 and 0.7013
    lines = format_bounce_table(study).splitlines()
    assert "H_k / H_k-1" in lines[0]
    assert lines[2].startswith("backtrack  0.80        6") and lines[2].endswith("0.6400 to 0.6400")
    assert lines[3].startswith("project    0.80        6") and lines[3].endswith(f"{lo:.4f} to {hi:.4f}")
    assert len({len(line) for line in lines}) == 1  # the columns line up


@pytest.mark.parametrize("method", ["backtrack", "project"])
@pytest.mark.parametrize("mu", [0.0, 0.2, 0.8])
def test_block_on_a_slope_follows_coulomb_friction(method, mu):
    """A particle resting on a 20 degree slope slides by g (sin - mu cos) t^2 / 2, or sticks."""
    from particles import ParticleSystem
    from particles.forces import Gravity

    angle = np.radians(20.0)
    slope = Plane([0.0, 0.0, 0.0], [0.0, -np.sin(angle), np.cos(angle)])
    ps = ParticleSystem([[0.0, 0.0, 0.0]], forces=[Gravity([0.0, 0.0, -9.81])])
    collider = Collider(slope, restitution=0.0, friction=mu, method=method)
    ps.run(0.5, 0.002, method=collider.stepper("verlet", m=ps.m))
    travel = ps.X[0, 0] @ np.array([0.0, -np.cos(angle), -np.sin(angle)])
    expected = 0.5 * 9.81 * max(0.0, np.sin(angle) - mu * np.cos(angle)) * 0.5**2
    # backtracking handles the contact within the step; projection creeps by about h g t per second
    assert travel == pytest.approx(expected, abs=1e-9 if method == "backtrack" else 0.005)
