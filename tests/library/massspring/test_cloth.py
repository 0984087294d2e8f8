"""Cloth (particles.massspring.cloth): spring sets, pins, physical masses and stiffnesses, sag, damping, wind."""

import numpy as np
import pytest

from particles.implicit import relax
from particles.massspring import cloth, cloth_masses, cloth_springs, cloth_stiffness

g = 9.81


def test_cloth_spring_sets():
    """Structural, shear and flexion springs join the grid neighbours the slide names."""
    nx, ny = 5, 4
    pairs = cloth_springs(nx, ny)
    counts = {k: len(v) for k, v in pairs.items()}
    assert counts == {"structural": ny * (nx - 1) + (ny - 1) * nx, "shear": 2 * (nx - 1) * (ny - 1),
                      "flexion": ny * (nx - 2) + (ny - 2) * nx}
    c = cloth(nx, ny, width=0.4, height=0.3)
    x = c.X[:, 0]
    np.testing.assert_allclose(c.springs["structural"].rest_length, np.r_[[0.1] * 16, [0.1] * 15])
    shear = c.springs["shear"]
    np.testing.assert_allclose(np.linalg.norm(x[shear.i] - x[shear.j], axis=1), np.hypot(0.1, 0.1))
    flex = c.springs["flexion"]
    assert set(np.abs(flex.i - flex.j)) == {2, 2 * nx}
    assert c.grid_shape == (ny, nx)


def test_cloth_pins_by_name_and_index():
    """Pins by point name, by index or a mix; unknown names and out-of-range indices are refused."""
    c = cloth(6, 5, pins="top corners")
    assert c.pinned.tolist() == [0, 5]
    assert cloth(6, 5, pins=["top left", 29]).pinned.tolist() == [0, 29]
    assert cloth(6, 5, pins="top edge").pinned.tolist() == list(range(6))
    assert len(cloth(6, 5, pins=None).pinned) == 0
    with pytest.raises(ValueError, match="unknown pin name 'top centre'"):
        cloth(6, 5, pins="top centre")
    with pytest.raises(ValueError, match=r"pins must be particle indices in \[0, 30\)"):
        cloth(6, 5, pins=[30])


def test_physical_cloth_masses_and_stiffness():
    """Masses add up to density x area; on square cells k equals the modulus (interior)."""
    m = cloth_masses(9, 5, 2.0, 1.0, 0.3)
    assert m.sum() == pytest.approx(0.6)
    k = cloth_stiffness(9, 9, 1.0, 1.0, {"structural": 50.0, "shear": 10.0, "flexion": 4.0})
    assert k["structural"].max() == pytest.approx(50.0) and k["structural"].min() == pytest.approx(25.0)
    np.testing.assert_allclose(k["shear"], 10.0 / 4)
    # uniform strain: each family stores the continuum energy Y e^2 / 2 x area
    for kind, Y in (("structural", 50.0), ("flexion", 4.0)):
        c = cloth(9, 7, width=2.0, height=1.5, scaling="physical", stretch_modulus=50.0, flexion_modulus=4.0)
        springs = c.springs[kind]
        along_x = np.abs(springs.i - springs.j) < 3
        e = 0.01
        energy = 0.5 * np.sum(springs.k[along_x] * (e * springs.rest_length[along_x]) ** 2)
        assert energy == pytest.approx(0.5 * Y * e**2 * 2.0 * 1.5)


def test_naive_defaults_equal_physical_at_reference_resolution():
    """Naive defaults equal the physical interior mass and stiffnesses at the 8 x 8 reference grid."""
    naive, physical = cloth(8, 8, scaling="naive"), cloth(8, 8, scaling="physical")
    interior = np.arange(64).reshape(8, 8)[1:-1, 1:-1].ravel()
    np.testing.assert_allclose(naive.m[interior], physical.m[interior])
    for kind in ("structural", "shear", "flexion"):
        assert naive.springs[kind].k[0] == pytest.approx(physical.springs[kind].k.max())


def cloth_sag(n, scaling, pins="top edge"):
    c = cloth(n, n, scaling=scaling, pins=pins)
    relax(c, h=0.2)
    return -c.X[:, 0, 2].min() - 1.0, c


def test_physical_scaling_sag_agrees_across_resolutions_naive_does_not():
    """Static sag of a cloth hanging from its top edge at 8, 16, 32 particles per side."""
    physical = [cloth_sag(n, "physical")[0] for n in (8, 16, 32)]
    naive = [cloth_sag(n, "naive")[0] for n in (8, 16, 32)]
    assert max(physical) / min(physical) - 1 < 0.03
    assert naive[2] / naive[0] > 5


def test_point_pins_concentrate_strain_under_refinement():
    """Two pinned corners are point loads: their strain keeps growing as the grid is refined."""
    strains = [cloth_sag(n, "physical", pins="top corners")[1].max_strain() for n in (8, 16, 32)]
    assert strains[0] < strains[1] < strains[2]
    assert strains[2] > 2 * strains[0]


def test_cloth_damping_and_wind_options():
    """Damping is per unit mass (physical) or per particle (naive); wind adds its force; pins carry weight and wind."""
    rng = np.random.default_rng(3)
    for scaling, per_mass in (("physical", True), ("naive", False)):
        c = cloth(5, 5, damping=0.3, gravity=0.0, scaling=scaling)
        X = c.state()
        X[:, 1] = rng.normal(size=(c.n, 3))
        free = np.setdiff1d(np.arange(c.n), c.pinned)
        springs_only = cloth(5, 5, damping=0.0, gravity=0.0, scaling=scaling).total_force(X, 0.0)
        drag = c.total_force(X, 0.0) - springs_only
        expected = -0.3 * (c.m[:, None] if per_mass else 1.0) * X[:, 1]
        np.testing.assert_allclose(drag[free], expected[free], atol=1e-12)
    c = cloth(5, 5, damping=0.3, wind=[1.0, 0.0, 0.0], scaling="physical")
    F = c.total_force(c.state(), 0.0)
    weight = c.m[:, None] * np.array([0.0, 0.0, -g])
    np.testing.assert_allclose(F[c.pinned], (weight + c.m[:, None] * [1.0, 0.0, 0.0])[c.pinned], atol=1e-12)
