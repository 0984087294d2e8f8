"""The Lennard-Jones liquid of the NIST Standard Reference Simulation Website, reproduced with the library.

NIST's Monte Carlo reference for the 12-6 potential truncated at 3 sigma with
analytic long-range (tail) corrections, N = 500 at T* = 0.85, rho* = 0.86
(https://mmlapps.nist.gov/srs/LJ_PURE/mc.htm): U/N = -6.0305 (standard error
0.00238) and p* = 1.2660 (0.0136). We run molecular dynamics instead of Monte
Carlo: the same N in a periodic box, melted from an FCC lattice with
Berendsen's thermostat, then sampled at constant temperature with Langevin
(BAOAB), force reuse and a Verlet list, and compare both means within three
combined standard errors (ours from block averages, and NIST's).

Notes on what is compared: the force is truncated at 3 sigma, so molecular
dynamics samples the ensemble of the *shifted* potential while NIST's Monte
Carlo samples the truncated one; reweighting our frames by
``exp(-U(r_c) dN_pairs / T)`` moves U/N by less than 0.001, a tenth of our
error bar. The samples stay correlated for long: most of the correlation
of U and p is lost within 0.1 time units, but a tail of 10-20% lasts a few
time units (energy flows in and out through the thermostat only, and the
liquid rearranges slowly), so the blocks are 4 time units long. Runs of 20
time units with other seeds scattered by about 0.01 in U/N around NIST's value.
"""

import numpy as np
import pytest

from particles import ParticleSystem
from particles.forces import LennardJones
from particles.md import Berendsen, Langevin, block_average, fcc_lattice, kinetic_temperature, maxwell_boltzmann

NIST = {"T": 0.85, "rho": 0.86, "U/N": (-6.0305, 0.00238), "p": (1.2660, 0.0136)}


def test_fcc_lattice_and_maxwell_boltzmann_start():
    """500 particles at rho = 0.86, 12 neighbours a / sqrt(2) apart; velocities at exactly T, no drift."""
    from particles.neighbors import cell_pairs

    x, box = fcc_lattice(5, 0.86)
    assert x.shape == (500, 3) and len(x) / np.prod(box) == pytest.approx(0.86)
    a = box[0] / 5
    i, j = cell_pairs(x, 0.75 * a, box=box)
    assert len(i) == 500 * 12 // 2  # 12 nearest neighbours each, through the walls too
    v = maxwell_boltzmann(500, 0.85, seed=3)
    assert kinetic_temperature(v) == pytest.approx(0.85, rel=1e-12)
    assert np.abs(v.sum(axis=0)).max() < 1e-12
    with pytest.raises(ValueError, match="cells must be a positive integer"):
        fcc_lattice(0, 0.86)
    with pytest.raises(ValueError, match="density must be a positive finite number"):
        fcc_lattice(3, -1.0)


def test_nist_lennard_jones_state_point():
    """U/N and p at T* = 0.85, rho* = 0.86 (r_c = 3, tail-corrected) match NIST within 3 combined SE."""
    T, N, h = NIST["T"], 500, 0.005
    x, box = fcc_lattice(5, NIST["rho"])
    V = float(np.prod(box))
    lj = LennardJones.from_epsilon_sigma(cutoff=3.0, skin=0.4, box=box)
    ps = ParticleSystem(x, v=maxwell_boltzmann(N, 3.0, seed=2026), forces=[lj])
    ps.run(0.5, h, method=Berendsen(3.0, tau=0.05))  # melt the lattice
    ps.run(ps.t + 2.0, h, method=Berendsen(T, tau=0.1))  # cool to T
    ps.run(ps.t + 1.0, h, method=Langevin(T, gamma=1.0, seed=2027))  # equilibrate in the canonical ensemble
    t, X = ps.run(ps.t + 40.0, h, method=Langevin(T, gamma=1.0, seed=2028), every=20)

    u_tail, p_tail = lj.tail_corrections(N / V)
    U, W = [], []
    for Xk in X[1:]:  # 400 samples, 0.1 time units apart
        U.append(lj.potential_energy(Xk[:, 0], shift=False) / N + u_tail)
        W.append(lj.virial(Xk[:, 0]))
    p = N / V * T + np.array(W) / (3 * V) + p_tail
    Tk = [kinetic_temperature(Xk[:, 1], dof=3 * N) for Xk in X[1:]]

    # 10 blocks of 4 time units: the blocking estimate of the error is still growing at 2 time units
    for name, series, sharp in (("U/N", U, 0.01), ("p", p, 0.05)):
        ours = block_average(series, blocks=10)
        ref, ref_error = NIST[name]
        allowed = 3 * np.hypot(ours.error, ref_error)
        assert abs(ours.mean - ref) <= allowed, f"{name}: {ours.mean:.4f} +- {ours.error:.4f}, NIST {ref}"
        assert ours.error < sharp  # sharp enough to see a missing tail correction (0.27 and 0.46)
    T_run = block_average(Tk, blocks=10)
    assert abs(T_run.mean - T) <= 3 * T_run.error + 0.005  # Langevin holds T (up to BAOAB's O(h^2))
