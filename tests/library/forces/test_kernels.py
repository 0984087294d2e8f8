"""The forces' compiled passes (particles.forces.kernels) on problems larger than the force contract's.

A 40^2 cloth, an 864-particle Lennard-Jones liquid in and out of a box,
N-body, a long chain's bending agree with NumPy to 1e-12 and give the same
bits on one thread, on two, and serially.
"""

import numpy as np
import pytest

from particles import backends
from particles.forces import Bending, LennardJones, NBodyGravity
from particles.forces.springs import joint_factor
from particles.massspring import cloth
from particles.md import fcc_lattice
from particles.xpbd import XPBD

from ..backends.helpers import _close, assert_same_bits, needs_numba, on_thread_counts


def _cloth_state(n, seed=0):
    c = cloth(n, n, kd=0.05)
    X = c.state()
    rng = np.random.default_rng(seed)
    X[:, 0] += rng.normal(scale=0.05 / n, size=X[:, 0].shape)
    X[:, 1] = rng.normal(scale=0.1, size=X[:, 1].shape)
    return c, X


@needs_numba
def test_a_cloth_step_agrees_and_is_the_same_every_time():
    """A 40^2 cloth (4.6k damped springs): the derivative agrees to 1e-12, repeated calls give the same bits."""
    c, X = _cloth_state(40)
    with backends.using("numpy"):
        reference = c.derivative(X, 0.0)
    with backends.using("numba"):
        first = c.derivative(X, 0.0)
        np.testing.assert_array_equal(c.derivative(X, 0.0), first)
    _close(reference, first)


def _liquid(cells=(6, 6, 6), seed=1):
    x, box = fcc_lattice(cells, 0.86)
    return x + np.random.default_rng(seed).uniform(-0.1, 0.1, x.shape), box


@needs_numba
@pytest.mark.parametrize("periodic", [True, False], ids=["periodic", "open"])
def test_lennard_jones_on_a_liquid_agrees_with_numpy(periodic):
    """864 particles at rho* = 0.86 (about 34k listed pairs): forces to 1e-12, the virial to 1e-12."""
    x, box = _liquid()
    out = {}
    for backend in ("numpy", "numba"):
        lj = LennardJones.from_epsilon_sigma(skin=0.3, box=box if periodic else None, backend=backend)
        out[backend] = lj(x), lj.last_virial
    _close(out["numpy"][0], out["numba"][0])
    assert out["numba"][1] == pytest.approx(out["numpy"][1], rel=1e-12)


@needs_numba
def test_lennard_jones_follows_its_list_when_particles_move():
    """Across list rebuilds (particles moving, unwrapped positions leaving the box) both backends agree."""
    x, box = _liquid(seed=3)
    lj = {b: LennardJones.from_epsilon_sigma(skin=0.2, box=box, backend=b) for b in ("numpy", "numba")}
    rng = np.random.default_rng(4)
    for _ in range(4):  # a loop over moves: some reuse the list, some rebuild it
        x = x + rng.normal(scale=0.06, size=x.shape) + np.array([0.5, 0.0, 0.0]) * box
        _close(lj["numpy"](x), lj["numba"](x))
    assert lj["numba"].neighbor_list.builds == lj["numpy"].neighbor_list.builds > 1


@needs_numba
@pytest.mark.parametrize("d", [2, 3])
def test_nbody_and_bending_agree_with_numpy(d):
    """N-body gravity (300 particles) and a long chain's bending agree to 1e-12."""
    rng = np.random.default_rng(5)
    x, m = rng.normal(size=(300, d)), rng.uniform(0.5, 2.0, 300)
    triples = np.stack([np.arange(298), np.arange(1, 299), np.arange(2, 300)], axis=1)
    kb = rng.uniform(0.5, 1.0, 298)
    for make in (lambda b: NBodyGravity(G=2.0, softening=0.05, backend=b),
                 lambda b: Bending(triples, kb=kb, rest_angle=0.2, backend=b)):
        _close(make("numpy")(x, m=m), make("numba")(x, m=m))


@needs_numba
def test_bending_agrees_on_both_forms_of_the_joint_factor():
    """A chain straight at rest, some joints bent by less than 29 degrees (the series) and some by more (acos),
    and a chain with a rest angle (acos only): the kernel's branch chooses the form NumPy selects, to 1e-13."""
    rng = np.random.default_rng(8)
    s = np.linspace(0.0, 3.0, 400)
    bend = rng.choice([1e-7, 1e-3, 0.2, 0.8], size=400)  # turning per link, in radians
    angle = np.cumsum(bend * rng.choice([-1.0, 1.0], size=400))
    x = np.stack([np.cumsum(np.cos(angle)), np.cumsum(np.sin(angle)), 0.01 * s], axis=1)
    triples = np.stack([np.arange(398), np.arange(1, 399), np.arange(2, 400)], axis=1)
    for rest in (0.0, 0.3):
        numpy_F = Bending(triples, kb=1.0, rest_angle=rest, backend="numpy")(x)
        np.testing.assert_allclose(Bending(triples, kb=1.0, rest_angle=rest, backend="numba")(x), numpy_F,
                                   rtol=1e-13, atol=1e-13 * np.abs(numpy_F).max())
    import numba  # noqa: PLC0415  (the law alone, compiled as the kernels compile it: the same form, to the last bits)

    from particles.forces import kernels  # noqa: F401, PLC0415  (registers the kernels' form of joint_factor)
    compiled = numba.njit(lambda c, theta0: joint_factor(c, theta0, 1.0))
    c = np.cos(np.array([1e-7, 1e-5, 1e-3, 0.1, 0.5, 0.6, 2.0]))
    for rest in (0.0, 0.3):
        np.testing.assert_allclose([compiled(ci, rest) for ci in c], joint_factor(c, rest, 1.0), rtol=5e-16, atol=0)


@needs_numba
def test_results_do_not_depend_on_the_number_of_threads(monkeypatch):
    """Springs, bending, Lennard-Jones, N-body and XPBD: the same bits on one thread, on two, and serial.

    (For springs the serial form is a one-pass scatter, the parallel one forces per spring then a gather.)
    """
    from particles.forces import kernels

    c, X = _cloth_state(32)
    x, box = _liquid()
    rng = np.random.default_rng(7)
    xn, m = rng.normal(size=(200, 3)), rng.uniform(0.5, 2.0, 200)
    chain = np.stack([np.arange(198), np.arange(1, 199), np.arange(2, 200)], axis=1)
    monkeypatch.setattr(kernels, "SPRING_THREADS", 1)  # springs too: the two-pass form, then one pass

    def run():
        with backends.using("numba"):
            lj = LennardJones.from_epsilon_sigma(skin=0.3, box=box)
            xpbd = XPBD.from_system(_cloth_state(32)[0], substeps=2)
            return [c.derivative(X, 0.0), lj(x), np.array(lj.last_virial), xpbd(None, X, 0.0, 0.01),
                    NBodyGravity()(xn, m=m), Bending(chain, kb=0.5)(xn)]

    assert_same_bits(on_thread_counts(monkeypatch, run))
