"""Cloth self-collision (particles.collisions.selfcollision): pushes, impulses, exclusions, two sheets."""

import numpy as np
import pytest

from particles.collisions import Collider, Plane, SelfCollision
from particles.constraints import ProvotConstraint
from particles.integrators import symplectic_euler
from particles.massspring import MassSpringSystem, cloth
from particles.neighbors import all_pairs
from particles.forces import Springs

DX = 0.05  # grid spacing of the test sheets, m
THICKNESS = 0.8 * DX  # > DX / sqrt(2): no particle fits through the centre of a cell


def _far_apart(n=2, d=3):
    """Rest positions 1 m apart along x: no pair is a rest neighbour."""
    x = np.zeros((n, d))
    x[:, 0] = np.arange(n)
    return x


def test_two_particles_pushed_to_thickness_centre_of_mass_kept():
    """Overlapping pair ends exactly `thickness` apart, mass centre and momentum unchanged, approach stopped."""
    m = np.array([1.0, 3.0])
    sc = SelfCollision(0.1, _far_apart(), m=m)
    x = np.array([[0.0, 0.0, 0.0], [0.03, 0.04, 0.0]])  # 5 cm apart along (0.6, 0.8, 0)
    v = np.array([[2.0, 1.0, 0.5], [-1.0, 0.0, 0.5]])
    res = sc.resolve(x, v)
    assert res.pairs == 1 and res.converged and res.iterations == 1
    assert np.linalg.norm(res.x[1] - res.x[0]) == pytest.approx(0.1, rel=1e-12)
    assert res.min_distance >= 0.1 * (1 - 1e-12)  # inf, or the pair itself within round-off
    np.testing.assert_allclose(m @ res.x, m @ x, atol=1e-15)
    np.testing.assert_allclose(m @ res.v, m @ v, atol=1e-14)
    # the light particle moves 3/4 of the 5 cm overlap, the heavy one 1/4
    n = np.array([0.6, 0.8, 0.0])
    np.testing.assert_allclose(res.x[0], x[0] - 0.75 * 0.05 * n, atol=1e-15)
    # inelastic: no relative normal velocity left; tangential relative velocity kept
    dv_old, dv_new = v[1] - v[0], res.v[1] - res.v[0]
    assert dv_new @ n == pytest.approx(0.0, abs=1e-14)
    np.testing.assert_allclose(dv_new - (dv_new @ n) * n, dv_old - (dv_old @ n) * n, atol=1e-14)


def test_restitution_reverses_and_friction_slows_the_relative_velocity():
    """eps = 1 reverses the relative normal velocity; friction mu removes mu times the normal change from the tangential one."""
    x = np.array([[0.0, 0.0], [0.05, 0.0]])
    v = np.array([[1.0, 0.0], [-1.0, 1.0]])  # approach at 2 m/s along x, slide at 1 m/s along y
    elastic = SelfCollision(0.1, _far_apart(d=2), restitution=1.0).resolve(x, v)
    assert elastic.v[1, 0] - elastic.v[0, 0] == pytest.approx(2.0)
    assert elastic.v[1, 1] - elastic.v[0, 1] == pytest.approx(1.0)
    rough = SelfCollision(0.1, _far_apart(d=2), friction=0.25).resolve(x, v)
    assert rough.v[1, 0] - rough.v[0, 0] == pytest.approx(0.0, abs=1e-14)
    assert rough.v[1, 1] - rough.v[0, 1] == pytest.approx(1.0 - 0.25 * 2.0)
    sticky = SelfCollision(0.1, _far_apart(d=2), friction=5.0).resolve(x, v)
    assert sticky.v[1, 1] - sticky.v[0, 1] == pytest.approx(0.0, abs=1e-14)  # stops, never reverses


def test_separating_pair_is_pushed_but_keeps_its_velocities():
    """A close pair already moving apart is moved to the thickness, its velocities untouched."""
    x = np.array([[0.0, 0.0], [0.05, 0.0]])
    v = np.array([[-1.0, 0.3], [1.0, 0.0]])
    res = SelfCollision(0.1, _far_apart(d=2)).resolve(x, v)
    assert res.x[1, 0] - res.x[0, 0] == pytest.approx(0.1)
    np.testing.assert_array_equal(res.v, v)


def test_pinned_particle_does_not_move():
    """Against a pinned particle, the free one takes the whole push and the whole impulse."""
    sc = SelfCollision(0.1, _far_apart(), pinned=[0])
    x = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.02]])
    v = np.array([[0.0, 0.0, 0.0], [0.5, 0.0, -3.0]])
    res = sc.resolve(x, v)
    np.testing.assert_array_equal(res.x[0], x[0])
    np.testing.assert_array_equal(res.v[0], 0.0)
    np.testing.assert_allclose(res.x[1], [0.0, 0.0, 0.1])
    np.testing.assert_allclose(res.v[1], [0.5, 0.0, 0.0])
    both = SelfCollision(0.1, _far_apart(), pinned=[0, 1]).resolve(x, v)
    np.testing.assert_array_equal(both.x, x)


def test_coincident_particles_separate_along_their_rest_direction():
    """Two particles at the same point are pushed apart along the line joining them at rest."""
    rest = np.array([[0.0, 0.0], [0.0, 1.0]])
    res = SelfCollision(0.1, rest).resolve(np.zeros((2, 2)), np.zeros((2, 2)))
    np.testing.assert_allclose(res.x, [[0.0, -0.05], [0.0, 0.05]])


def test_rest_neighbours_and_excluded_pairs_never_repel():
    """A cloth shrunk until its springs are shorter than the thickness is left alone; an excluded pair too."""
    sheet = cloth(6, 6, 5 * DX, 5 * DX, plane="horizontal", pins=None)
    sc = SelfCollision.from_system(sheet, THICKNESS)
    x = 0.6 * sheet.X[:, 0]  # structural 0.6 dx and shear 0.85 dx apart; flexion 1.2 dx
    assert np.sum(np.linalg.norm(x[1:] - x[:-1], axis=1) < THICKNESS) > 0  # neighbours do overlap
    res = sc.resolve(x, np.ones_like(x))
    assert res.pairs == 0 and res.iterations == 0
    np.testing.assert_array_equal(res.x, x)
    np.testing.assert_array_equal(res.v, 1.0)
    i, j = np.triu_indices(sheet.n, 1)
    L = np.linalg.norm(sheet.X[i, 0] - sheet.X[j, 0], axis=1)
    springs = {(min(a, b), max(a, b)) for a, b in sheet.spring_indices().tolist()}
    expected = (L < 2 * THICKNESS) | np.array([(a, b) in springs for a, b in zip(i, j)])
    np.testing.assert_array_equal(sc.is_neighbour(i, j), expected)
    np.testing.assert_array_equal(sc.is_neighbour(j, i), expected)
    far = SelfCollision(0.1, _far_apart(3), exclude=[[0, 2]])
    x3 = np.array([[0.0, 0.0, 0.0], [5.0, 0.0, 0.0], [0.01, 0.0, 0.0]])
    np.testing.assert_array_equal(far.resolve(x3, np.zeros((3, 3))).x, x3)


def test_grid_search_agrees_with_all_pairs():
    """The bucket-grid pair search returns exactly the pairs of the all-pairs test, exclusions applied."""
    rng = np.random.default_rng(3)
    rest = rng.uniform(0.0, 1.0, (400, 3))
    sc = SelfCollision(0.08, rest, rest_distance=0.1)
    x = rng.uniform(0.0, 0.6, (400, 3))
    grid = sc.close_pairs(x)
    brute = sc.close_pairs(x, search="all")
    assert len(grid[0]) > 100
    np.testing.assert_array_equal(grid[0], brute[0])
    np.testing.assert_array_equal(grid[1], brute[1])
    i, j = all_pairs(x, 0.08)
    near_at_rest = np.linalg.norm(rest[i] - rest[j], axis=1) < 0.1
    assert len(grid[0]) == np.sum(~near_at_rest) and np.sum(near_at_rest) > 0


def _sheets(bottom, top, pins_bottom, top_offset):
    """One system made of two horizontal sheets (nx, width) of spacing DX, the second above the first."""
    a = cloth(bottom, bottom, (bottom - 1) * DX, (bottom - 1) * DX, plane="horizontal", pins=pins_bottom,
              damping=0.002)
    b = cloth(top, top, (top - 1) * DX, (top - 1) * DX, plane="horizontal", pins=None, origin=top_offset,
              damping=0.002)
    springs = [Springs(np.concatenate([s.indices, b.springs[kind].indices + a.n]),
                       np.concatenate([s.rest_length, b.springs[kind].rest_length]),
                       k=np.concatenate([s.k, b.springs[kind].k]), kind=kind) for kind, s in a.springs.items()]
    system = MassSpringSystem(np.concatenate([a.X[:, 0], b.X[:, 0]]), m=np.concatenate([a.m, b.m]),
                              springs=springs, forces=a.other_forces(), pinned=a.pinned)
    return system, a.n


def _closest_non_neighbours(sc, X):
    """Smallest distance of a non-neighbour pair in each recorded state (inf when none is within 2 thicknesses)."""
    out = []
    for x in X[:, :, 0]:  # a loop over recorded states
        i, j = all_pairs(x, 2 * sc.thickness)
        keep = ~sc.is_neighbour(i, j)
        r = np.linalg.norm(x[i[keep]] - x[j[keep]], axis=1)
        out.append(r.min(initial=np.inf))
    return np.array(out)


def _hammock():
    """A 6 x 6 sheet, offset by half a cell, falls 10 cm into a 10 x 10 sheet held by its corners."""
    off = (9 - 5) * DX / 2 + DX / 2
    return _sheets(10, 6, "corners", (off, off, 0.1))


def _height_above_lower_sheet(X, n):
    """z of each upper particle minus z of the lower particle closest to it in x-y, in the last state."""
    x = X[-1, :, 0]
    lower, upper = x[:n], x[n:]
    d2 = np.sum((upper[:, None, :2] - lower[None, :, :2]) ** 2, axis=-1)
    return upper[:, 2] - lower[np.argmin(d2, axis=1), 2]


def test_sheet_falling_into_a_hammock_stays_on_top_with_self_collision():
    """With the wrapper (around Provot's), every non-neighbour pair stays >= thickness (1 - tol) apart at every step."""
    system, n = _hammock()
    sc = SelfCollision.from_system(system, THICKNESS)
    step = sc.stepper(ProvotConstraint.from_system(system).stepper(symplectic_euler))
    assert step.order == symplectic_euler.order and "self_collision" in step.__name__
    t, X = system.run(0.8, 1e-3, method=step)
    closest = _closest_non_neighbours(sc, X)
    assert closest.min() >= THICKNESS * (1 - sc.tol) - 1e-12
    assert len(sc.history) == len(t) - 1 and all(r.converged for r in sc.history)
    assert max(r.pairs for r in sc.history) > 10  # the sheets did meet
    assert _height_above_lower_sheet(X, n).min() > 0.25 * THICKNESS


def test_sheet_falling_into_a_hammock_passes_through_without_self_collision():
    """Without the wrapper the top sheet falls through the hammock: the z order swaps."""
    system, n = _hammock()
    sc = SelfCollision.from_system(system, THICKNESS)  # only to measure
    t, X = system.run(0.8, 1e-3, method=ProvotConstraint.from_system(system).stepper(symplectic_euler))
    assert _closest_non_neighbours(sc, X).min() < 0.75 * THICKNESS
    assert _height_above_lower_sheet(X, n).max() < 0  # every upper particle is now below the lower sheet
    assert X[-1, n:, 0, 2].max() < X[-1, :n, 0, 2].min()


def test_two_sheets_on_a_floor_stay_stacked_with_collider_last():
    """Composed with Collider.stepper, the upper sheet rests on the lower one instead of lying in the floor plane.

    The floor projection after the push can undo part of it (a lower particle pushed into the
    floor is moved back up): pairs keep >= 0.98 thickness here, measured 0.989.
    """
    for use in (True, False):  # a loop over with and without self-collision
        system, n = _sheets(8, 8, None, (DX / 2, DX / 2, 0.1))
        system.X[:, 0, 2] += 0.02
        sc = SelfCollision.from_system(system, THICKNESS)
        floor = Collider(Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]), restitution=0.0, friction=0.3, method="project")
        inner = sc.stepper(symplectic_euler) if use else symplectic_euler
        t, X = system.run(0.5, 1e-3, method=floor.stepper(inner, m=system.m, pinned=system.pinned), every=5)
        top = X[-1, n:, 0, 2]
        if use:
            assert _closest_non_neighbours(sc, X).min() >= 0.98 * THICKNESS
            # resting in the hollows of the lower sheet: sqrt(thickness^2 - dx^2 / 2) above it
            assert top.mean() == pytest.approx(np.sqrt(THICKNESS**2 - DX**2 / 2), rel=0.1)
        else:
            np.testing.assert_allclose(top, 0.0, atol=1e-12)


def test_a_blow_up_is_reported_by_the_run():
    """A diverging step goes through the wrapper unchanged, so the run raises SimulationDiverged."""
    from particles import SimulationDiverged

    sheet = cloth(5, 5, 0.2, 0.2, plane="horizontal", pins=None, k_structural=1e6)
    step = SelfCollision.from_system(sheet, 0.04).stepper(symplectic_euler)
    sheet.X[0, 0, 2] += 0.01
    with pytest.raises(SimulationDiverged):
        sheet.run(1.0, 0.01, method=step)


def test_inputs_not_modified():
    """resolve returns corrected copies and leaves the arrays it was given alone."""
    x = np.array([[0.0, 0.0], [0.05, 0.0]])
    v = np.array([[1.0, 0.0], [-1.0, 0.0]])
    x0, v0 = x.copy(), v.copy()
    SelfCollision(0.1, _far_apart(d=2)).resolve(x, v)
    np.testing.assert_array_equal(x, x0)
    np.testing.assert_array_equal(v, v0)


@pytest.mark.parametrize("kwargs, name", [
    ({"thickness": -0.1}, "thickness"),
    ({"thickness": 0.0}, "thickness"),
    ({"rest_distance": 0.05}, "rest_distance"),
    ({"iterations": 0}, "iterations"),
    ({"tol": 1.0}, "tol"),
    ({"restitution": 1.5}, "restitution"),
    ({"friction": -1.0}, "friction"),
    ({"m": [1.0, 2.0, 3.0]}, "m"),
    ({"pinned": [5]}, "pinned"),
    ({"exclude": [[0, 7]]}, "exclude"),
    ({"x_rest": [0.0, 1.0]}, "x_rest"),
])
def test_bad_arguments_name_the_argument(kwargs, name):
    """Bad constructor arguments raise ValueError naming the argument."""
    args = {"thickness": 0.1, "x_rest": _far_apart()}
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        SelfCollision(**args)


def test_bad_positions_name_the_argument():
    """resolve and close_pairs check the shape of x and v and the search name."""
    sc = SelfCollision(0.1, _far_apart())
    with pytest.raises(ValueError, match="x must have shape"):
        sc.resolve(np.zeros((3, 3)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="v must have shape"):
        sc.resolve(np.zeros((2, 3)), np.zeros((2, 2)))
    with pytest.raises(ValueError, match="i and j"):
        sc.is_neighbour([0], [2])
    with pytest.raises(ValueError, match="search"):
        sc.close_pairs(np.zeros((2, 3)), search="octree")
