"""N-body gravity: every particle attracts every other, ``|F_ij| = G m_i m_j / r^2``.

References
----------
.. [1] A. Witkin, "Particle System Dynamics", in *Physically Based Modeling:
   Principles and Practice*, SIGGRAPH 1997 course notes (n-ary forces).
.. [2] S. J. Aarseth, *Gravitational N-Body Simulations*, Cambridge University
   Press, 2003, section 2.2 (Plummer softening).
"""

import numpy as np

from .._checks import nonnegative_number, positive_number
from ..backends import check_backend, compiled
from .force import Force
from .pairs import gravitational_pull

__all__ = ["NBodyGravity"]


class NBodyGravity(Force):
    """Mutual gravitation of all pairs: ``|F_ij| = G m_i m_j / r^2``.

    ``F_i = sum_j G m_i m_j (x_j - x_i) / (|x_j - x_i|^2 + eps^2)^(3/2)``

    Parameters
    ----------
    G : float
        Gravitational constant in the model's units (``6.674e-11`` m^3/(kg s^2)
        in SI; 1 in most demos).
    softening : float
        ``eps``, in metres, >= 0. Plummer softening: removes the singularity
        when two particles pass close; 0 gives the exact inverse-square law.
    backend : {None, "auto", "numpy", "numba"}, optional
        This NumPy code or the same law in a compiled double loop, one thread
        per particle (:mod:`particles.forces.kernels`; None: the global
        choice, see :mod:`particles.backends`).

    Notes
    -----
    O(n^2) time, computed in blocks of rows so memory stays O(n). Pairs are
    antisymmetric term by term, so the total force is zero to round-off. The
    law of one pair is :func:`particles.forces.pairs.gravitational_pull`.

    Open space only: gravity reaches every copy of a periodic box, so the
    minimum image (one copy per pair, as for :class:`LennardJones`) would
    be wrong, and a periodic sum needs Ewald or particle-mesh methods.
    """

    uses_velocity = False
    uses_time = False

    def __init__(self, G=1.0, softening=0.0, backend=None):
        self._backend = check_backend(backend)
        self.G = positive_number(G, "G")
        self.softening = nonnegative_number(softening, "softening", "metres")

    def add_to(self, F, x, v, t, m):
        n = len(x)
        if compiled(self._backend, n):  # the same law, compiled (particles.forces.kernels)
            from .kernels import nbody_forces  # noqa: PLC0415  (imports numba)
            nbody_forces(F, x, np.broadcast_to(m, (n,)), self.G, self.softening)
            return
        xt = np.ascontiguousarray(x.T)  # (d, n): one row per coordinate
        block = max(1, 1_000_000 // max(n, 1))
        for a in range(0, n, block):  # a loop over blocks of rows
            b = min(n, a + block)
            r = xt[:, None, :] - xt[:, a:b, None]  # (d, block, n): x_j - x_i
            r2 = np.einsum("kij,kij->ij", r, r)
            r2[np.arange(b - a), np.arange(a, b)] = np.inf  # no self-force
            w = gravitational_pull(self.G, m[a:b, None], m[None, :], r2, self.softening**2)
            F[a:b] += np.einsum("ij,kij->ik", w, r)

    def potential_energy(self, x, m, t=0.0):
        """``-sum_{i<j} G m_i m_j / sqrt(r^2 + eps^2)``, in joules."""
        i, j = np.triu_indices(len(x), k=1)
        r2 = np.sum((x[i] - x[j]) ** 2, axis=1) + self.softening**2
        return -self.G * float(np.sum(m[i] * m[j] / np.sqrt(r2)))
