"""Forces: formulas, symmetries, momentum, potentials, and bucket grid == all pairs."""

import numpy as np
import pytest

from particles import ParticleSystem
from particles.forces import (
    Attractor,
    Damping,
    Field,
    Gravity,
    LennardJones,
    NBodyGravity,
    Vortex,
    Wind,
    scatter_pair_forces,
)


def numerical_gradient(energy, x, eps=1e-6):
    """Central-difference gradient of a scalar function of positions (test helper)."""
    grad = np.zeros_like(x)
    for idx in np.ndindex(x.shape):
        e = np.zeros_like(x)
        e[idx] = eps
        grad[idx] = (energy(x + e) - energy(x - e)) / (2 * eps)
    return grad


def test_gravity_is_mass_proportional_and_can_point_up():
    """Gravity is m g for each particle, and an upward g lifts (smoke)."""
    x = np.zeros((3, 2))
    m = np.array([1.0, 2.0, 0.5])
    np.testing.assert_allclose(Gravity([0, -9.81])(x, m=m), np.outer(m, [0, -9.81]))
    assert np.all(Gravity([0, 0.3])(x, m=m)[:, 1] > 0)  # smoke rises


def test_gravity_dimension_mismatch_is_reported():
    """A 3D g on 2D particles is refused, naming both dimensions."""
    with pytest.raises(ValueError, match="g has 3 components but the particles live in 2 dimensions"):
        Gravity([0, 0, -9.81])(np.zeros((1, 2)))


def test_damping_opposes_velocity():
    """Damping is -d v, and a negative d is refused by name."""
    v = np.array([[1.0, -2.0], [0.0, 3.0]])
    np.testing.assert_allclose(Damping(0.4)(np.zeros((2, 2)), v), -0.4 * v)
    with pytest.raises(ValueError, match="d must be a finite number >= 0"):
        Damping(-1.0)


def test_wind_constant_and_gusting():
    """Calm wind is uniform; gusts vary with time and along the wind."""
    x = np.array([[0.0, 0.0], [0.25, 0.0]])
    calm = Wind([2.0, 0.0])
    np.testing.assert_allclose(calm(x, t=3.0), [[2.0, 0.0]] * 2)
    gusty = Wind([2.0, 0.0], gust=0.5, period=1.0, wavelength=1.0)
    F0, F1 = gusty(x, t=0.0), gusty(x, t=0.25)
    np.testing.assert_allclose(F0[:, 1], 0.0)
    np.testing.assert_allclose(F0[:, 0], 2.0 * (1 + 0.5 * np.sin(-2 * np.pi * x[:, 0])))
    assert not np.allclose(F0, F1)
    assert F1[1, 0] == pytest.approx(2.0)  # gust front: phase 0 at x = 0.25, t = 0.25


def test_attractor_formula_repulser_and_potential():
    """The softened attractor's force follows its formula, a negative strength repels, and F = -grad U."""
    x = np.array([[1.0, 0.0], [0.0, -2.0], [3.0, 4.0]])
    a = Attractor([0.0, 0.0], strength=2.0, softening=0.5)
    F = a(x)
    r = -x
    r2 = np.sum(r**2, axis=1) + 0.25
    np.testing.assert_allclose(F, 2.0 * r / (r2**1.5)[:, None])
    np.testing.assert_allclose(Attractor([0, 0], -2.0, softening=0.5)(x), -F)  # negative repels
    grad = numerical_gradient(lambda y: a.potential_energy(y, None), x)
    np.testing.assert_allclose(F, -grad, rtol=1e-6, atol=1e-9)


def test_attractor_moving_center():
    """A centre given as a function of time moves with t."""
    a = Attractor(lambda t: [t, 0.0], strength=1.0)
    x = np.array([[1.0, 0.0]])
    assert a(x, t=0.0)[0, 0] < 0 < a(x, t=2.0)[0, 0]


def test_vortex_2d_is_tangential_counterclockwise():
    """A 2D vortex pushes tangentially, counterclockwise, with the core-softened magnitude."""
    rng = np.random.default_rng(1)
    x = rng.normal(size=(50, 2))
    F = Vortex([0.0, 0.0], strength=1.5, core=0.2)(x)
    np.testing.assert_allclose(np.sum(F * x, axis=1), 0.0, atol=1e-12)  # no radial part
    assert np.all(x[:, 0] * F[:, 1] - x[:, 1] * F[:, 0] > 0)  # positive torque about z
    r = np.linalg.norm(x, axis=1)
    np.testing.assert_allclose(np.linalg.norm(F, axis=1), 1.5 * r / (r**2 + 0.04))


def test_vortex_3d_about_axis():
    """In 3D the swirl is perpendicular to the axis and to the radius."""
    rng = np.random.default_rng(2)
    axis = np.array([1.0, 1.0, 0.0])
    x = rng.normal(size=(40, 3))
    c = np.array([0.5, 0.0, 1.0])
    F = Vortex(c, strength=2.0, axis=axis)(x)
    np.testing.assert_allclose(F @ axis, 0.0, atol=1e-12)
    np.testing.assert_allclose(np.sum(F * (x - c), axis=1), 0.0, atol=1e-12)
    with pytest.raises(ValueError, match="axis must be a non-zero vector"):
        Vortex(c, 1.0, axis=[0, 0, 0])


def test_field_calls_user_function_and_checks_shape():
    """A Field calls the user's fn(x, t), and a wrong shape or a non-function is refused by name."""
    fn = Field(lambda x, t: np.sin(t) * x)
    x = np.array([[1.0, 2.0]])
    np.testing.assert_allclose(fn(x, t=0.5), np.sin(0.5) * x)
    with pytest.raises(ValueError, match=r"fn\(x, t\) must return shape \(1, 2\), got \(2,\)"):
        Field(lambda x, t: np.zeros(2))(x)
    with pytest.raises(ValueError, match="fn must be a function"):
        Field(3.0)


def test_scatter_pair_forces_equal_and_opposite_with_repeats():
    """Repeated indices accumulate (unlike F[i] += f) and the total is zero."""
    F = np.zeros((3, 2))
    i, j = np.array([0, 0, 1]), np.array([1, 2, 2])
    f = np.array([[1.0, 0.0], [0.0, 2.0], [3.0, 3.0]])
    scatter_pair_forces(F, i, j, f)
    np.testing.assert_allclose(F, [[1.0, 2.0], [2.0, 3.0], [-3.0, -5.0]])
    np.testing.assert_allclose(F.sum(axis=0), 0.0)


# -- N-body ------------------------------------------------------------------


def test_nbody_two_bodies_inverse_square():
    """|F| = G m1 m2 / r^2 along the line joining the bodies, equal and opposite."""
    x = np.array([[0.0, 0.0, 0.0], [3.0, 4.0, 0.0]])
    m = np.array([2.0, 5.0])
    F = NBodyGravity(G=1.5)(x, m=m)
    np.testing.assert_allclose(F[0], 1.5 * 2 * 5 / 25 * np.array([0.6, 0.8, 0.0]))
    np.testing.assert_allclose(F[1], -F[0])


def test_nbody_momentum_and_potential():
    """Total force zero to round-off; force is minus the gradient of the potential."""
    rng = np.random.default_rng(4)
    x = rng.normal(size=(60, 3))
    m = rng.uniform(0.5, 2.0, 60)
    nb = NBodyGravity(G=1.0, softening=0.05)
    F = nb(x, m=m)
    assert np.abs(F.sum(axis=0)).max() < 1e-12 * np.abs(F).max() * 60
    grad = numerical_gradient(lambda y: nb.potential_energy(y, m), x, eps=1e-6)
    np.testing.assert_allclose(F, -grad, rtol=1e-5, atol=1e-6)


def test_nbody_blocks_match_direct_sum():
    """The blocked computation equals a direct double sum (many blocks for large n)."""
    rng = np.random.default_rng(5)
    x = rng.normal(size=(1200, 2))
    m = rng.uniform(1, 2, 1200)
    F = NBodyGravity(softening=0.1)(x, m=m)
    k = 17
    r = x - x[k]
    r2 = np.sum(r**2, axis=1) + 0.01
    r2[k] = np.inf
    np.testing.assert_allclose(F[k], (m[k] * m / r2**1.5) @ r, rtol=1e-10)


def test_two_body_orbit_conserves_energy():
    """A circular two-body orbit with Verlet keeps its energy within 1e-4."""
    G, M = 1.0, 1.0
    x = np.array([[0.0, 0.0], [1.0, 0.0]])
    v = np.array([[0.0, 0.0], [0.0, 1.0]])
    ps = ParticleSystem(x, v=v, m=[M, 1e-6], forces=[NBodyGravity(G)])
    E0 = ps.kinetic_energy() + ps.potential_energy()
    ps.run(2 * np.pi, 0.005, method="verlet")
    assert abs(ps.kinetic_energy() + ps.potential_energy() - E0) < 1e-4 * abs(E0)
    np.testing.assert_allclose(ps.X[1, 0], [1.0, 0.0], atol=1e-2)  # back after one period


# -- Lennard-Jones -----------------------------------------------------------


def test_lennard_jones_formula_and_zero_crossing():
    """f(r) = k1/r^m - k2/r^n; the 12-6 force vanishes at r = 2^(1/6) sigma."""
    lj = LennardJones.from_epsilon_sigma(epsilon=2.0, sigma=1.5)
    assert (lj.k1, lj.k2, lj.m, lj.n) == (48 * 2 * 1.5**12, 24 * 2 * 1.5**6, 13, 7)
    r0 = 2 ** (1 / 6) * 1.5
    assert lj.magnitude(r0) == pytest.approx(0.0, abs=1e-12)
    assert lj.magnitude(0.9 * r0) > 0 > lj.magnitude(1.1 * r0)
    x = np.array([[0.0, 0.0], [1.2, 0.0]])
    F = lj(x)
    np.testing.assert_allclose(F[0], [-lj.magnitude(1.2), 0.0])
    np.testing.assert_allclose(F[1], -F[0])
    assert np.all(lj(np.array([[0.0, 0.0], [3.76, 0.0]])) == 0.0)  # beyond 2.5 sigma


def test_lennard_jones_general_exponents():
    """Non-integer exponents use the same formula."""
    lj = LennardJones(k1=2.0, k2=1.0, m=9.5, n=4.5, cutoff=3.0)
    F = lj(np.array([[0.0, 0.0, 0.0], [0.0, 1.3, 0.0]]))
    assert F[1, 1] == pytest.approx(2.0 / 1.3**9.5 - 1.0 / 1.3**4.5)


def random_liquid(n, d, density, seed):
    rng = np.random.default_rng(seed)
    side = (n / density) ** (1 / d)
    # jittered lattice: no overlapping particles, as in a liquid
    k = int(np.ceil(n ** (1 / d)))
    grid = np.stack(np.meshgrid(*[np.arange(k)] * d, indexing="ij"), -1).reshape(-1, d)[:n]
    return (grid + 0.5 + rng.uniform(-0.1, 0.1, (n, d))) * side / k


@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_lennard_jones_cells_equal_all_pairs(d, seed):
    """Bucket grid and all pairs agree to 1e-10 on random liquids."""
    x = random_liquid(700, d, 0.8, seed)
    F_cells = LennardJones.from_epsilon_sigma(neighbors="cells")(x)
    F_all = LennardJones.from_epsilon_sigma(neighbors="all")(x)
    assert np.abs(F_all).max() > 1.0
    np.testing.assert_allclose(F_cells, F_all, rtol=0, atol=1e-10)


def test_lennard_jones_cells_on_cell_boundaries_and_beyond_grid():
    """Particles exactly on cell faces, at the cutoff, and far outside the grid bulk."""
    cut = 2.5
    cell = cut / 2
    # a lattice with spacing exactly the cell size: every particle on a cell boundary
    g = np.arange(6) * cell
    x = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    # pairs at exactly the cutoff, just inside it, and a far-away cluster (outliers)
    extra = np.array([[0.0, 0.0, 20.0], [0.0, 0.0, 20.0 + cut], [0.0, 0.0, 30.0],
                      [0.0, cut * (1 - 1e-12), 30.0], [1e4, 1e4, 1e4], [1e4 + 1.1, 1e4, 1e4]])
    x = np.concatenate([x, extra])
    lj = dict(k1=1.0, k2=1.0, m=13, n=7, cutoff=cut)
    F_all = LennardJones(**lj, neighbors="all")(x)
    for k in (1, 2, 3):
        F_cells = LennardJones(**lj, neighbors="cells", cells_per_cutoff=k, skin=0.0)(x)
        np.testing.assert_allclose(F_cells, F_all, rtol=0, atol=1e-10)
    assert np.all(F_all[-6:-4] == 0.0)  # exactly at the cutoff: no force
    assert F_all[-3, 1] != 0.0 and np.all(F_all[-2:, 0] != 0)


def test_lennard_jones_momentum_conserved():
    """The Lennard-Jones forces of a liquid sum to zero."""
    x = random_liquid(500, 3, 0.8, 7)
    F = LennardJones.from_epsilon_sigma()(x)
    assert np.abs(F.sum(axis=0)).max() < 1e-10


def test_lennard_jones_force_is_minus_gradient_of_potential():
    """The Lennard-Jones force is minus the finite-difference gradient of its potential energy."""
    x = random_liquid(40, 2, 0.6, 3)
    lj = LennardJones.from_epsilon_sigma()
    grad = numerical_gradient(lambda y: lj.potential_energy(y), x, eps=1e-7)
    np.testing.assert_allclose(lj(x), -grad, rtol=1e-5, atol=1e-5)


def test_verlet_list_reused_and_still_exact():
    """With a skin, small moves reuse the pair list; forces stay equal to all pairs."""
    rng = np.random.default_rng(9)
    x = random_liquid(400, 2, 0.8, 9)
    lj = LennardJones.from_epsilon_sigma(skin=0.4)
    ref = LennardJones.from_epsilon_sigma(neighbors="all")
    for step in range(10):
        np.testing.assert_allclose(lj(x), ref(x), atol=1e-10)
        x = x + rng.uniform(-0.02, 0.02, x.shape)
    assert lj.neighbor_list.builds == 1  # total motion < skin/2: never rebuilt
    x = x + rng.uniform(-0.5, 0.5, x.shape)
    np.testing.assert_allclose(lj(x), ref(x), atol=1e-10)
    assert lj.neighbor_list.builds == 2


def test_lennard_jones_bad_parameters():
    """Bad exponents, neighbour searches and cutoffs are refused by name."""
    with pytest.raises(ValueError, match="exponents must satisfy m > n > 1"):
        LennardJones(1.0, 1.0, 6, 12, 2.5)
    with pytest.raises(ValueError, match="neighbors must be 'cells' or 'all'"):
        LennardJones(1.0, 1.0, 13, 7, 2.5, neighbors="grid")
    with pytest.raises(ValueError, match="cutoff must be a positive finite number"):
        LennardJones(1.0, 1.0, 13, 7, -1.0)


def test_forces_do_not_modify_inputs():
    """x and v are read, never written."""
    rng = np.random.default_rng(0)
    x, v = rng.normal(size=(30, 3)), rng.normal(size=(30, 3))
    x.setflags(write=False)
    v.setflags(write=False)
    for force in [Gravity([0, 0, -1]), Damping(1.0), Wind([1, 0, 0], gust=0.3), Attractor([0, 0, 0], 1.0),
                  Vortex([0, 0, 0], 1.0), NBodyGravity(softening=0.1), LennardJones.from_epsilon_sigma()]:
        force(x, v, 0.5)


@pytest.mark.parametrize("method", ["verlet", "rk4", "midpoint", "trapezoid", "euler"])
@pytest.mark.parametrize("d", [2, 3])
def test_lennard_jones_overlap_raises_simulation_diverged(method, d):
    """Two particles 1e-25 apart: inf positions mid-step reach the divergence check (not the grid's ValueError)."""
    from particles import SimulationDiverged

    x = np.zeros((2, d))
    x[1] = 1e-25
    ps = ParticleSystem(x, forces=[LennardJones.from_epsilon_sigma()])
    with np.errstate(all="ignore"):
        with pytest.raises(SimulationDiverged, match=rf"diverged at step 1 \(t = 0 s\).*'{method}'") as info:
            ps.run(0.1, 0.01, method=method)
    assert info.value.step == 1 and info.value.t == 0.0
    np.testing.assert_array_equal(ps.X[:, 0], x)  # the system is left as it was


def test_force_call_checks_masses():
    """force(x, m=...) refuses masses <= 0 and masses of the wrong length, naming m."""
    x = np.zeros((2, 2))
    for m in (-1.0, 0.0, [1.0, -2.0]):
        with pytest.raises(ValueError, match="m must be positive"):
            Gravity([0, -9.81])(x, m=m)
    with pytest.raises(ValueError, match=r"m must be a number or have shape \(2,\), got shape \(3,\)"):
        Gravity([0, -9.81])(x, m=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="t must be a finite real number"):
        Gravity([0, -9.81])(x, t=np.nan)
    np.testing.assert_allclose(Gravity([0, -9.81])(x, m=[1.0, 2.0]), [[0, -9.81], [0, -19.62]])


def test_lennard_jones_documented_helpers():
    """magnitude vanishes at 2^(1/6) sigma; pair_potential is -epsilon there and 0 beyond the cutoff."""
    lj = LennardJones.from_epsilon_sigma(epsilon=2.0, sigma=0.5)
    r_min = 2 ** (1 / 6) * 0.5
    assert abs(lj.magnitude(r_min)) < 1e-9 and lj.magnitude(0.9 * r_min) > 0 > lj.magnitude(1.1 * r_min)
    shift = 4 * 2.0 * ((0.5 / 1.25) ** 12 - (0.5 / 1.25) ** 6)  # U at the default cutoff 2.5 sigma
    assert lj.pair_potential(r_min) == pytest.approx(-2.0 - shift)
    assert lj.pair_potential(np.array([1.25, 3.0])).tolist() == [0.0, 0.0]


# -- Lennard-Jones in a periodic box: minimum image, virial, tail corrections --


def periodic_liquid(cells, density, jitter, seed):
    """An FCC lattice at `density` in its box, each particle moved by up to `jitter` (test helper)."""
    from particles.md import fcc_lattice

    x, box = fcc_lattice(cells, density)
    return x + np.random.default_rng(seed).uniform(-jitter, jitter, x.shape), box


@pytest.mark.parametrize("cells_per_cutoff", [1, 2, 3])
def test_periodic_lennard_jones_cells_equal_all_pairs(cells_per_cutoff):
    """In a box, the bucket grid with a skin gives the minimum-image all-pairs forces and virial."""
    x, box = periodic_liquid((4, 5, 6), 0.86, 0.2, 0)
    x[::7] += 3 * box  # some particles far outside: positions need not be wrapped
    lj = LennardJones.from_epsilon_sigma(cutoff=2.5, skin=0.3, box=box, cells_per_cutoff=cells_per_cutoff)
    ref = LennardJones.from_epsilon_sigma(cutoff=2.5, neighbors="all", box=box)
    F, F_ref = lj(x), ref(x)
    assert np.abs(F_ref).max() > 1.0
    np.testing.assert_allclose(F, F_ref, rtol=0, atol=1e-10)
    assert lj.last_virial == pytest.approx(ref.last_virial, rel=1e-12)
    assert lj.virial(x) == pytest.approx(ref.last_virial, rel=1e-12)
    assert np.abs(F.sum(axis=0)).max() < 1e-10  # pair forces: momentum conserved


def test_periodic_lennard_jones_is_invariant_under_whole_box_shifts():
    """Moving particles by whole box lengths changes no force and no energy."""
    x, box = periodic_liquid(3, 0.8, 0.15, 1)
    lj = LennardJones.from_epsilon_sigma(cutoff=2.5, skin=0.0, box=box)
    F, U = lj(x), lj.potential_energy(x)
    shift = np.random.default_rng(2).integers(-3, 4, size=x.shape) * box
    np.testing.assert_allclose(lj(x + shift), F, atol=1e-10)
    assert lj.potential_energy(x + shift) == pytest.approx(U, rel=1e-12)


def test_periodic_force_is_minus_gradient_and_virial_is_minus_volume_derivative():
    """F = -grad U (truncated U) and W = -dU/dlambda when positions and box scale by lambda."""
    x, box = periodic_liquid(2, 0.7, 0.2, 3)  # 32 particles in a box of 3.6
    lj = LennardJones.from_epsilon_sigma(cutoff=1.7, skin=0.0, box=box)
    grad = numerical_gradient(lambda y: lj.potential_energy(y, shift=False), x, eps=1e-6)
    np.testing.assert_allclose(lj(x), -grad, rtol=1e-6, atol=1e-6)

    def energy(lam):
        scaled = LennardJones.from_epsilon_sigma(cutoff=1.7, skin=0.0, box=lam * box)
        return scaled.potential_energy(lam * x, shift=False)

    dU = (energy(1 + 1e-6) - energy(1 - 1e-6)) / 2e-6  # no pair crosses the cutoff in between
    assert lj.virial(x) == pytest.approx(-dU, rel=1e-6)


def test_truncated_and_shifted_energies_differ_by_the_shift_per_pair():
    """U_truncated - U_shifted = (pairs within the cutoff) U(r_c)."""
    x, box = periodic_liquid(4, 0.86, 0.2, 4)
    lj = LennardJones.from_epsilon_sigma(cutoff=2.5, box=box)
    from particles.neighbors import cell_pairs

    pairs = len(cell_pairs(x, 2.5, box=box)[0])
    U_rc = 4 * (2.5**-12 - 2.5**-6)
    difference = lj.potential_energy(x, shift=False) - lj.potential_energy(x)
    assert difference == pytest.approx(pairs * U_rc, rel=1e-9)
    assert lj.pair_potential(1.5, shift=False) == pytest.approx(4 * (1.5**-12 - 1.5**-6))
    assert lj.pair_potential(2.6, shift=False) == 0.0


@pytest.mark.parametrize("d", [2, 3])
def test_tail_corrections_equal_the_integrals_beyond_the_cutoff(d):
    """u_tail and p_tail match numerical integrals of U and r f(r) beyond r_c (g = 1), in 2D and 3D."""
    from scipy.integrate import quad

    lj = LennardJones(k1=2.0, k2=1.5, m=13, n=7, cutoff=2.2)
    rho, S = 0.7, {2: 2 * np.pi, 3: 4 * np.pi}[d]
    U = lambda r: 2.0 / (12 * r**12) - 1.5 / (6 * r**6)  # f = -dU/dr, untruncated
    u_num = 0.5 * rho * S * quad(lambda r: U(r) * r ** (d - 1), 2.2, np.inf)[0]
    p_num = rho**2 / (2 * d) * S * quad(lambda r: r * lj.magnitude(r) * r ** (d - 1), 2.2, np.inf)[0]
    u_tail, p_tail = lj.tail_corrections(rho, d=d)
    assert u_tail == pytest.approx(u_num, rel=1e-8)
    assert p_tail == pytest.approx(p_num, rel=1e-8)
    nist = LennardJones.from_epsilon_sigma(cutoff=3.0).tail_corrections(0.86)
    assert nist == pytest.approx((8 / 3 * np.pi * 0.86 * (3.0**-9 / 3 - 3.0**-3),
                                  16 / 3 * np.pi * 0.86**2 * (2 / 3 * 3.0**-9 - 3.0**-3)), rel=1e-12)


def test_tail_corrections_and_box_refuse_bad_input_by_name():
    """density <= 0, d not 2 or 3, diverging tails and a box below 2 (cutoff + skin) raise ValueError."""
    lj = LennardJones.from_epsilon_sigma(cutoff=3.0)
    with pytest.raises(ValueError, match="density must be a positive finite number"):
        lj.tail_corrections(0.0)
    with pytest.raises(ValueError, match="d must be 2 or 3"):
        lj.tail_corrections(0.5, d=1)
    with pytest.raises(ValueError, match="tail integrals diverge"):
        LennardJones(1.0, 1.0, 6, 3.5, 2.5).tail_corrections(0.5)
    with pytest.raises(ValueError, match=r"box must be at least 2 x \(cutoff \+ skin\) = 6.6 m"):
        LennardJones.from_epsilon_sigma(cutoff=3.0, skin=0.3, box=6.5)
    with pytest.raises(ValueError, match="box must hold positive finite side lengths"):
        LennardJones.from_epsilon_sigma(box=[10.0, -10.0, 10.0])


def test_force_pass_in_chunks_equals_one_pass(monkeypatch):
    """The force pass over chunks of pairs gives the forces and virial of a single pass."""
    import particles.forces.lennardjones as lennardjones

    x, box = periodic_liquid(5, 0.86, 0.2, 5)
    F_one = LennardJones.from_epsilon_sigma(cutoff=3.0, box=box)(x)
    lj = LennardJones.from_epsilon_sigma(cutoff=3.0, box=box)
    monkeypatch.setattr(lennardjones, "_PAIR_CHUNK", 1000)  # many chunks (the 2 n floor: 1000 pairs each)
    np.testing.assert_allclose(lj(x), F_one, rtol=0, atol=1e-10)
    assert lj.last_virial == pytest.approx(lj.virial(x), rel=1e-12)


def test_position_only_forces_say_so():
    """Forces that ignore velocity and time declare it (the run may reuse them); damping does not."""
    lj = LennardJones.from_epsilon_sigma()
    assert not lj.uses_velocity and not lj.uses_time
    assert not Gravity([0, -1]).uses_velocity and not NBodyGravity().uses_time
    assert Damping(1.0).uses_velocity and not Damping(1.0).uses_time
    assert Wind([1, 0], gust=0.5).uses_time and not Wind([1, 0]).uses_time
    assert Attractor(lambda t: [t, 0.0], 1.0).uses_time and not Attractor([0, 0], 1.0).uses_time
    assert not Field(lambda x, t: x).uses_velocity and Field(lambda x, t: x).uses_time
