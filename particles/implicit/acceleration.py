"""Accelerations of a fixed-point iteration ``u <- G(u)``: Anderson's mixing and Chebyshev's semi-iteration.

:class:`particles.implicit.Prefactored` mixes its local/global iterates with one of them. Each is an
object with ``propose(u, image)`` (the next iterate from the current one and the plain image ``G(u)``)
and ``restart(u)`` (called when the solver's safeguard rejected a proposal and took the plain image).

References
----------
.. [1] Y. Peng, B. Deng, J. Zhang, F. Geng, W. Qin and L. Liu, "Anderson
   acceleration for geometry optimization and physics simulation", ACM
   Transactions on Graphics 37(4), 2018.
.. [2] H. Wang, "A Chebyshev semi-iterative approach for accelerating
   projective and position-based dynamics", ACM Transactions on Graphics
   34(6), 2015.
"""

import numpy as np

__all__ = ["Anderson", "Chebyshev"]


def _least_squares(RRt, Rb):
    """argmin |R^T c - b| for a few rows R (m, N), from its normal equations' ``R R^T`` and ``R b``."""
    try:
        return np.linalg.solve(RRt + 1e-14 * np.trace(RRt) * np.eye(len(RRt)), Rb)
    except np.linalg.LinAlgError:  # exactly dependent rows
        return np.linalg.lstsq(RRt, Rb, rcond=None)[0]


class Chebyshev:
    """Wang's Chebyshev semi-iterative mixing of local/global iterates, for a spectral radius estimate `rho`.

    After `delay` plain iterations, ``u' = w (G(u) - u_prev) + u_prev`` with ``w_1 = 2 / (2 - rho^2)``,
    ``w_{k+1} = 4 / (4 - rho^2 w_k)`` (Wang 2015, eq. 8 with gamma = 1). For a linear ``G`` whose
    iteration matrix has real eigenvalues within ``[-rho, rho]`` the error falls like a Chebyshev
    polynomial's, ``(rho / (1 + sqrt(1 - rho^2)))^k`` instead of ``rho^k``.

    Parameters
    ----------
    rho : float
        An estimate of the plain iteration's spectral radius, in [0, 1).
    delay : int
        Plain iterations before the mixing starts (and after every restart).
    """

    def __init__(self, rho, delay=3):
        self.rho2, self.delay = rho * rho, delay
        self.restart(None)

    def restart(self, u):
        self.previous, self.run, self.w = u, 0, 1.0

    def propose(self, u, image):
        """The next iterate from the current `u` and the plain local/global image ``G(u)``."""
        previous, self.previous = self.previous, u
        self.run += 1
        if self.run <= self.delay or previous is None:
            return image
        self.w = 2.0 / (2.0 - self.rho2) if self.w == 1.0 else 4.0 / (4.0 - self.rho2 * self.w)  # w_1, w_k+1
        return self.w * (image - previous) + previous


class Anderson:
    """Anderson mixing over the `depth` most recent iterates (Peng et al. 2018).

    The differences of the images ``G(u)`` and of the steps ``G(u) - u`` between iterations are kept as
    the rows of ``dG`` and ``dF`` (a ring: their order does not matter), with the Gram matrix of ``dF``
    updated one row at a time, so an iteration costs ``2 depth`` products of length ``N``, not ``depth^2``.
    The mixed iterate is ``G(u) - dG^T gamma``, ``gamma`` minimizing ``|G(u) - u - dF^T gamma|``.

    Parameters
    ----------
    depth : int
        How many previous iterates the mixing uses, >= 1.
    size : int
        The number of unknowns (``u.size``).
    """

    def __init__(self, depth, size):
        self.dG, self.dF = np.empty((depth, size)), np.empty((depth, size))
        self.gram = np.zeros((depth, depth))
        self.last, self.kept = None, 0

    def restart(self, u):
        self.kept = 0  # forget the differences; the last image stays the origin of the next one

    def propose(self, u, image):
        """The next iterate from the current `u` and the plain local/global image ``G(u)``."""
        f = (image - u).ravel()
        candidate = image
        if self.last is not None:
            depth = len(self.dG)
            row = self.kept % depth
            np.subtract(image.ravel(), self.last[0], out=self.dG[row])
            np.subtract(f, self.last[1], out=self.dF[row])
            self.kept += 1
            rows = min(self.kept, depth)
            self.gram[row, :rows] = self.gram[:rows, row] = self.dF[:rows] @ self.dF[row]
            gamma = _least_squares(self.gram[:rows, :rows], self.dF[:rows] @ f)
            candidate = (image.ravel() - gamma @ self.dG[:rows]).reshape(u.shape)
        self.last = (image.ravel(), f)
        return candidate
