"""Static equilibria (particles.implicit.statics.relax) against the elastic catenary, and relax's stopping rule.

The reference is an extensible cable hanging under its own weight between
two pins at the same height (Irvine, *Cable Structures*, 1981, ch. 1),
written here from the equations, independently of the library: a cable of
unstretched length ``L0``, weight ``w`` per unstretched length and axial
stiffness ``EA``, pinned ``span`` apart. With ``s`` the unstretched arc
length, the horizontal tension ``H`` is constant, the vertical one
``V(s) = w (s - L0 / 2)`` (zero at the lowest point), the tension
``T = sqrt(H^2 + V^2)`` stretches the cable by ``T / EA`` (Hooke), so
``dx/ds = (1 + T/EA) H/T`` and ``dz/ds = (1 + T/EA) V/T``, which integrate to

    x(s) = H s / EA + (H / w) (asinh(V(s) / H) - asinh(V(0) / H))
    z(s) = (T(s) - T(0)) / w + (w / EA) (s^2 / 2 - L0 s / 2)

and ``H`` solves ``x(L0) = span``. A string of ``n`` nodes (physical
scaling: masses lumped at the nodes, ``k = EA / L0``) and a cloth pinned
along two opposite edges (each row such a string) converge to it at
second order in the node spacing.

Also: relax's methods on a stiff chain, a cloth and a drooping hair, and a
system already at rest.
"""

import numpy as np
import pytest
import scipy.optimize

from particles.errors import ConvergenceError
from particles.implicit import relax
from particles.implicit.statics import ROUNDOFF
from particles.massspring import cloth, string

G = 9.81  # m/s^2
SIZES = (21, 41, 81, 161, 321)  # nodes along the cable: the spacing halves from one to the next


def elastic_catenary(s, L0, span, w, EA):
    """Positions (x, z) at unstretched arc lengths `s` of an elastic catenary pinned at (0, 0) and (span, 0).

    Parameters
    ----------
    s : ndarray, shape (k,)
        Unstretched arc lengths from the left pin, in [0, L0] (m).
    L0, span : float
        Unstretched length and distance between the pins (m), ``span < L0 (1 + ...)``.
    w : float
        Weight per unstretched length (N/m).
    EA : float
        Axial stiffness (N).

    Returns
    -------
    ndarray, shape (k, 2)
        ``(x, z)`` in metres, ``z`` up.
    """
    def V(u):
        return w * (u - L0 / 2)

    def x(u, H):
        return H * u / EA + (H / w) * (np.arcsinh(V(u) / H) - np.arcsinh(V(0.0) / H))

    H = scipy.optimize.brentq(lambda H: x(L0, H) - span, 1e-9 * w * L0, EA * span / L0 + w * L0, xtol=1e-15,
                              rtol=4 * np.finfo(float).eps)
    T0, T = np.hypot(H, V(0.0)), np.hypot(H, V(s))
    return np.stack([x(s, H), (T - T0) / w + (w / EA) * (s**2 / 2 - L0 * s / 2)], axis=1)


def _orders(errors):
    """Observed orders of convergence between successive halvings of the spacing."""
    errors = np.asarray(errors)
    return np.log2(errors[:-1] / errors[1:])


def _relaxed_string(n, EA, d=2, tol=1e-8):
    """A physical string of n nodes, 1 m over a 0.8 m span, relaxed; and its error against the catenary (m)."""
    s = string(n, 1.0, pin="both", span=0.8, d=d, scaling="physical", linear_density=0.2, stretch_modulus=EA)
    steps = relax(s, tol=tol)
    ref = elastic_catenary(np.linspace(0.0, 1.0, n), 1.0, 0.8, 0.2 * G, EA)
    exact = np.zeros((n, d))
    exact[:, 0], exact[:, -1] = ref[:, 0] - 0.4, ref[:, 1]
    return s, steps, np.abs(s.X[:, 0] - exact).max()


@pytest.mark.parametrize("EA, d, sizes", [(1e5, 2, SIZES[:-1]), (20.0, 2, SIZES), (20.0, 3, SIZES)],
                         ids=["stiff 2D", "soft 2D", "soft 3D"])
def test_relaxed_strings_converge_to_the_elastic_catenary_at_second_order(EA, d, sizes):
    """Strings of 21 to 321 nodes, EA = 20 N (strain 10%) and 1e5 N (strain 2e-5): order 2 to the catenary.

    The stiff string stops at 161 nodes: at 321 its springs' round-off
    (``k = 3.2e7`` N/m, the floor ``16 eps k |x|`` of the stopping rule, 6e-6
    of a node's weight) is as large as the discretization error (1e-6 m).
    """
    errors = [_relaxed_string(n, EA, d)[2] for n in sizes]
    assert errors[-1] < 1e-5
    np.testing.assert_allclose(_orders(errors), 2.0, atol=0.1)


def _relaxed_cloth(nx, ny=3, Y=100.0, rho=0.2):
    """A cloth of nx x ny nodes pinned along its left and right edges, 1 m wide squeezed to 0.8 m, relaxed.

    Shear and flexion moduli are negligible (1e-9 Y), so each row is a string
    of stiffness ``Y w_j dy`` and weight ``rho g w_j dy`` per unit length:
    the rows hang as the catenary of ``EA = Y``, ``w = rho g`` per unit width.
    """
    idx = np.arange(nx * ny).reshape(ny, nx)
    c = cloth(nx, ny, 1.0, 0.1, plane="horizontal", pins=[int(p) for p in idx[:, [0, -1]].ravel()],
              scaling="physical", areal_density=rho, stretch_modulus=Y, shear_modulus=1e-9 * Y,
              flexion_modulus=1e-9 * Y)
    X = c.state()
    X[:, 0, 0] *= 0.8  # the straight start, every row compressed by 20%
    c.set_state(X)
    steps = relax(c)
    ref = elastic_catenary(np.linspace(0.0, 1.0, nx), 1.0, 0.8, rho * G, Y)
    exact = np.zeros((ny, nx, 3))
    exact[..., 0], exact[..., 2] = ref[:, 0], ref[:, 1]
    exact[..., 1] = np.linspace(0.0, 0.1, ny)[:, None]
    return c, steps, np.abs(c.X[:, 0] - exact.reshape(-1, 3)).max()


def test_relaxed_cloths_converge_to_the_elastic_catenary_at_second_order():
    """Cloths of 21 to 321 nodes along the sag (3 rows), pinned along two edges: order 2 to the catenary."""
    errors = [_relaxed_cloth(nx)[2] for nx in SIZES]
    assert errors[-1] < 1e-5
    np.testing.assert_allclose(_orders(errors), 2.0, atol=0.1)


def _balance(system):
    """Net force and load (the weight) on each free particle (N), and the round-off floor of the stopping rule."""
    free = np.setdiff1d(np.arange(system.n), system.pinned)
    F = np.linalg.norm(system.total_force(system.X, system.t)[free], axis=1)
    k_max = max(s.k.max() for s in system.springs.values())
    return F, system.m[free] * G, ROUNDOFF * k_max * np.abs(system.X[:, 0]).max()


def test_a_compressed_straight_start_is_not_returned_as_the_equilibrium():
    """Issue 24: 161 nodes, EA = 1e5 N, tol = 1e-6: steps are taken and every node's weight is balanced to 1e-6."""
    s = string(161, 1.0, pin="both", span=0.8, scaling="physical", linear_density=0.2, stretch_modulus=1e5)
    F, w, floor = _balance(s)
    assert np.all(F >= 0.999 * w)  # at the start every node carries its whole weight unbalanced
    steps = relax(s, tol=1e-6)
    F, w, floor = _balance(s)
    assert steps > 0
    assert np.all(F <= np.maximum(1e-6 * w, floor)) and floor < 1e-5 * w.min()
    ref = elastic_catenary(np.array([0.5]), 1.0, 0.8, 0.2 * G, 1e5)
    assert s.X[80, 0, 1] == pytest.approx(ref[0, 1], abs=1e-5)  # the sag of the catenary, 0.265 m


@pytest.mark.parametrize("tol", [1e-4, 1e-6, 1e-8])
def test_the_net_force_is_small_against_each_particles_load(tol):
    """After relax(tol), every free node's net force is below tol times its weight (or the round-off floor)."""
    s, steps, _ = _relaxed_string(41, 1e5, tol=tol)
    F, w, floor = _balance(s)
    assert np.all(F <= np.maximum(tol * w, floor))


def test_wind_is_a_load_like_the_weight_and_weightless_systems_reach_round_off():
    """A wind of g down instead of gravity: the same equilibrium in as many steps; with no load, round-off."""
    heavy = cloth(8, 8, pins="top edge", scaling="physical")
    windy = cloth(8, 8, pins="top edge", scaling="physical", gravity=0.0, wind=[0.0, 0.0, -G])
    assert relax(windy) == relax(heavy) > 0
    np.testing.assert_allclose(windy.X, heavy.X, rtol=0, atol=1e-12)
    weightless = cloth(8, 8, pins="top edge", scaling="physical", gravity=0.0)
    X = weightless.state()
    X[:, 0, 2] *= 1.2  # stretched: only the springs act
    weightless.set_state(X)
    assert relax(weightless) > 0
    F, _, floor = _balance(weightless)
    assert np.all(F <= floor)


def test_relax_that_fails_names_the_largest_net_force_and_its_load():
    """Too few steps: ConvergenceError with the largest net force and the load it should balance."""
    s = string(41, 1.0, pin="both", span=0.8, scaling="physical", stretch_modulus=1e5)
    with pytest.raises(ConvergenceError, match=r"within 2 steps \(largest net force .* N on a particle of load"):
        relax(s, max_steps=2)


@pytest.mark.parametrize("pin", ["top", "both"])
def test_relax_converges_on_a_stiff_chain_with_its_defaults(pin):
    """Issue 13: an 81-node chain with EA = 1e5 N relaxes with the default tol (each node's weight sets it)."""
    s = string(81, 1.0, pin=pin, span=0.8 if pin == "both" else None, scaling="physical", linear_density=0.2,
               stretch_modulus=1e5)
    relax(s)
    tension = s.springs["structural"].k * (s.springs["structural"].lengths(s.X[:, 0]) - 1.0 / 80)
    free = np.setdiff1d(np.arange(s.n), s.pinned)
    assert np.abs(s.total_force(s.X, 0.0)[free]).max() <= 1e-8 * tension.max()
    np.testing.assert_allclose(s.reaction_forces().sum(axis=0), [0.0, 0.2 * 9.81], rtol=1e-7, atol=1e-8)
    if pin == "top":  # each spring carries the weight below it
        below = s.m[::-1].cumsum()[::-1][1:] * 9.81
        np.testing.assert_allclose(tension, below, rtol=1e-6)


def test_relax_finds_rest_and_rejects_bad_method():
    """relax() brings a pinned cloth to rest (net forces ~ 0) and names the allowed methods otherwise."""
    c = cloth(6, 6, pins="top edge", scaling="physical")
    relax(c)
    F = c.total_force(c.X, 0.0)
    free = np.setdiff1d(np.arange(c.n), c.pinned)
    assert np.abs(F[free]).max() < 1e-8 * c.m.max() * 9.81 * 10
    with pytest.raises(ValueError, match="method must be 'auto', 'implicit' or 'newton'"):
        relax(c, method="euler")


def test_relax_newton_finds_a_large_droop():
    """Newton relaxation settles a soft hair with stiff segments that droops far beyond linear beam theory."""
    from particles.massspring import hair

    mu, L, EI = 0.05, 0.3, 0.002
    h = hair(6, L, scaling="physical", linear_density=mu, stretch_modulus=1e3, bending_modulus=EI)
    relax(h, method="newton")
    F = h.total_force(h.X, 0.0)
    assert np.abs(F[2:]).max() < 1e-9  # the free particles are at rest
    droop = -h.X[-1, 0, 1]
    assert 0.2 * L < droop < mu * 9.81 * L**4 / (8 * EI)  # large, and below the linear prediction
    assert np.linalg.norm(h.X[-1, 0] - h.X[0, 0]) <= L * 1.001  # the hair does not get longer


def test_relax_returns_at_once_from_an_equilibrium():
    """Relaxing a system that is already at rest in equilibrium takes no step (no ConvergenceError)."""
    s = string(10, 1.0)
    relax(s)
    x = s.X[:, 0].copy()
    assert relax(s) == 0
    np.testing.assert_array_equal(s.X[:, 0], x)
