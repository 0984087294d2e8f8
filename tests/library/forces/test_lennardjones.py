"""Lennard-Jones (particles.forces.lennardjones): the formula, bucket grid == all pairs, the periodic box."""

import numpy as np
import pytest

from particles import ParticleSystem
from particles.forces import LennardJones

from .helpers import numerical_gradient


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
