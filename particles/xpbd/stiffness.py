"""PBD's stiffness corrected for the iteration count (Müller et al. 2007, section 3.3).

A PBD projection with stiffness ``k`` in [0, 1] removes the share ``k`` of a
constraint's violation; ``n`` iterations on one constraint leave
``(1 - k)^n`` of it, so the same ``k`` gives a stiffer material the more
iterations the solver takes. Müller et al. scale the stiffness to::

    k' = 1 - (1 - k)^(1/n)

so that ``n`` iterations of ``k'`` leave ``(1 - k')^n = 1 - k`` of the
violation, what one iteration of ``k`` leaves: for one constraint, the
iteration count no longer changes the result. On a mesh, where constraints
share particles, the correction holds only approximately (lecture 8 measures
it), and it leaves PBD's two other flaws alone: the stiffness still has no
unit, and the step still scales the effective stiffness like ``m / h^2``.
:class:`particles.xpbd.PBD` applies it with ``corrected=True``.

References
----------
.. [1] M. Müller, B. Heidelberger, M. Hennix and J. Ratcliff, "Position based
   dynamics", Journal of Visual Communication and Image Representation 18(2),
   2007, 109-118, section 3.3 (constraint projection, the stiffness ``k``).
"""

import numpy as np

from .._checks import as_float_array, count

__all__ = ["iteration_corrected"]


def iteration_corrected(k, iterations):
    """The PBD stiffness that, applied `iterations` times, removes what `k` removes once: ``1 - (1 - k)^(1/n)``.

    Parameters
    ----------
    k : float or array_like
        PBD stiffnesses in [0, 1] (dimensionless).
    iterations : int
        Iterations per substep ``n`` (>= 1).

    Returns
    -------
    float or ndarray
        ``k'`` in [0, 1], of the shape of `k`; ``k' = k`` for one iteration,
        ``k' = 1`` where ``k = 1`` (a constraint solved fully stays solved fully).

    Raises
    ------
    ValueError
        When a stiffness lies outside [0, 1] or `iterations` is not a whole
        number >= 1.

    Examples
    --------
    >>> round(float(iteration_corrected(0.5, 2)), 6)      # two steps of 0.2929 leave (1 - 0.2929)^2 = 0.5
    0.292893
    >>> float(iteration_corrected(0.5, 1)), float(iteration_corrected(1.0, 50))
    (0.5, 1.0)
    """
    n = count(iterations, "iterations", 1)
    k_arr = as_float_array(k, "k")
    if np.any((k_arr < 0) | (k_arr > 1)):
        raise ValueError(f"k must hold PBD stiffnesses in [0, 1], got {k!r}")
    corrected = k_arr.copy() if n == 1 else 1.0 - (1.0 - k_arr) ** (1.0 / n)
    return float(corrected) if corrected.ndim == 0 else corrected
