"""Strings and hair (particles.massspring.strands): structure, statics (catenary, cantilever), scaling."""

import numpy as np
import pytest
from scipy.optimize import fsolve

from particles.implicit import relax
from particles.massspring import hair, string

g = 9.81


def chain_statics(m, k, L0, A, B):
    """Static shape of a chain of point masses on springs hung between pins A and B (2D).

    Independent of the simulator: each segment carries a tension vector (H, V_s);
    H is the same in every segment and V grows by each mass's weight (the chain
    slopes down from A, V < 0, then up); a segment's length is L0 + tension / k.
    H and the first V are found so that the chain ends at B. Returns positions,
    shape (n, 2).
    """
    weights = m[1:-1] * g

    def shape(p):
        H, V0 = p
        V = V0 + np.concatenate([[0.0], np.cumsum(weights)])  # vertical tension component per segment
        T = np.hypot(H, V)
        seg = (L0 + T / k)[:, None] * np.stack([H / T, V / T], axis=1)
        return A + np.concatenate([[[0.0, 0.0]], np.cumsum(seg, axis=0)])

    H, V0 = fsolve(lambda p: shape(p)[-1] - B, [m.sum() * g, -m.sum() * g / 2], xtol=1e-14)
    return shape((H, V0))


def test_string_structure_and_errors():
    """A string's springs, rest lengths and pins; bad pins, counts and scalings are named in the error."""
    s = string(10, 2.0)
    assert s.n == 10 and list(s.springs) == ["structural"]
    np.testing.assert_allclose(s.springs["structural"].rest_length, 2.0 / 9)
    assert s.pinned.tolist() == [0]
    assert string(10, pin="both").pinned.tolist() == [0, 9]
    with pytest.raises(ValueError, match="pin must be 'top', 'root', 'both' or 'none'"):
        string(10, pin="middle")
    with pytest.raises(ValueError, match="n must be an integer >= 2"):
        string(1)
    with pytest.raises(ValueError, match="scaling must be 'naive' or 'physical'"):
        string(5, scaling="exact")


def test_hanging_string_from_one_pin_matches_statics_and_reaction_is_weight():
    """Each spring stretches by the weight below it / k; the pin carries the whole weight."""
    n, k, m = 12, 40.0, 0.02
    s = string(n, 1.0, k=k, mass=m)
    relax(s, tol=1e-12)
    depth = -s.X[:, 0, 1]
    L0 = 1.0 / (n - 1)
    below = m * g * np.arange(n - 1, 0, -1)  # weight below each spring
    np.testing.assert_allclose(depth, np.concatenate([[0.0], np.cumsum(L0 + below / k)]), rtol=1e-9, atol=1e-12)
    assert s.X[-1, 0, 1] < -1.0  # longer than its rest length: a rubber band
    np.testing.assert_allclose(s.reaction_forces(), [[0.0, n * m * g]], rtol=1e-9)


@pytest.mark.parametrize("scaling", ["naive", "physical"])
def test_string_between_two_pins_settles_to_static_shape(scaling):
    """The relaxed string equals the elastic-catenary statics of the discrete chain."""
    s = string(15, 1.0, pin="both", span=0.8, scaling=scaling, k=30.0, mass=0.01,
               linear_density=0.1, stretch_modulus=5.0)
    relax(s, tol=1e-12)
    x = s.X[:, 0]
    k = s.springs["structural"].k[0]
    expected = chain_statics(s.m, k, 1.0 / 14, x[0], x[-1])
    np.testing.assert_allclose(x, expected, atol=1e-8)
    R = s.reaction_forces()
    np.testing.assert_allclose(R.sum(axis=0), [0.0, s.m.sum() * g], rtol=1e-8)  # pins carry the weight


def test_physical_string_converges_to_continuous_catenary():
    """Refining a physical string converges to the continuous elastic catenary (n -> inf)."""
    def sag(n):
        s = string(n, 1.0, pin="both", span=0.8, scaling="physical", linear_density=0.1, stretch_modulus=5.0)
        x = chain_statics(s.m, s.springs["structural"].k[0], 1.0 / (n - 1), np.array([-0.4, 0.0]),
                          np.array([0.4, 0.0]))
        return -x[:, 1].min()

    limit = sag(1601)
    errors = [abs(sag(n) - limit) for n in (11, 21, 41)]
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 0.01 * limit


def test_naive_string_changes_with_resolution():
    """Fixed per-particle mass and stiffness: a finer string is heavier and softer."""
    sags = []
    for n in (10, 20, 40):
        s = string(n, 1.0, pin="both", span=0.8, mass=0.01, k=30.0)
        relax(s)
        sags.append(-s.X[:, 0, 1].min())
    assert sags[2] > 1.5 * sags[0]


def test_physical_masses_and_stiffness_of_string():
    """Physical string: masses add up to density x length (half at the ends), k = EA / L0."""
    s = string(11, 2.0, scaling="physical", linear_density=0.3, stretch_modulus=8.0)
    assert s.m.sum() == pytest.approx(0.6)
    assert s.m[0] == pytest.approx(s.m[1] / 2)
    np.testing.assert_allclose(s.springs["structural"].k, 8.0 / 0.2)


def cantilever_ratios(ns, pin, EI=0.2, mu=0.05, L=0.3):
    """Relaxed tip deflection over beam theory's q L^4 / (8 EI) for hairs of ns particles (a test helper)."""
    ratios = []
    for n in ns:
        h = hair(n, L, pin=pin, scaling="physical", linear_density=mu, bending_modulus=EI, stretch_modulus=1e4)
        relax(h)
        ratios.append(-h.X[-1, 0, 1] / (mu * g * L**4 / (8 * EI)))
    return np.array(ratios)


def test_hair_droops_like_a_cantilever():
    """Issue 13: the clamped hair's tip deflection converges at second order to q L^4 / (8 EI); stiffer droops less."""
    ns = (11, 21, 41)
    errors = np.abs(cantilever_ratios(ns, "root") - 1)
    orders = np.log2(errors[:-1] / errors[1:])  # the spacing halves from one to the next
    assert np.all(orders > 1.8), orders
    assert errors[0] < 0.015 and errors[2] < 1e-3
    # small deflections: twice as stiff, half the droop (the same ratio to q L^4 / (8 EI))
    assert cantilever_ratios([21], "root", EI=0.4)[0] == pytest.approx(cantilever_ratios([21], "root")[0], rel=0.01)


def test_two_pinned_root_particles_clamp_half_a_segment_in():
    """pin="pair" (the first segment held) droops ((n - 2) / (n - 1))^2 of beam theory: a first-order error."""
    ns = np.array([11, 21, 41])
    np.testing.assert_allclose(cantilever_ratios(ns, "pair"), ((ns - 2) / (ns - 1)) ** 2, rtol=2e-4)


def test_hair_root_clamp_structure():
    """The default clamp pins the root only and holds the first segment along the hair's direction."""
    from particles.forces import Clamp

    h = hair(6, 0.3, direction=[0.0, -1.0])
    assert h.pinned.tolist() == [0]
    clamps = [f for f in h.other_forces() if isinstance(f, Clamp)]
    assert len(clamps) == 1 and clamps[0].i.tolist() == [0] and clamps[0].j.tolist() == [1]
    np.testing.assert_allclose(clamps[0].direction, [[0.0, -1.0]])
    np.testing.assert_allclose(clamps[0].kb, 2 * 0.002)  # twice a joint's kb: the mirrored ghost node
    assert hair(6, 0.3, pin="pair").pinned.tolist() == [0, 1]
    assert not any(isinstance(f, Clamp) for f in hair(6, 0.3, pin="pair").other_forces())
    with pytest.raises(ValueError, match="pin must be 'root', 'pair', 'top' or 'none', got 'both'"):
        hair(6, 0.3, pin="both")
