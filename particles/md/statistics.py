"""Averages of a simulation's time series, with an honest error bar.

Successive samples of a molecular-dynamics run are correlated: the energy at
one step is almost the energy of the step before. The naive standard error
``std / sqrt(N)`` then underestimates the uncertainty, by the square root of
the number of steps over which the samples stay correlated. **Block
averages** fix that [1]_: cut the series into ``B`` consecutive blocks, each
much longer than the correlation time; the block means are then nearly
independent, and the standard error of the mean is

    ``SE = std(block means) / sqrt(B)``   (``std`` with ``B - 1`` in the denominator).

:func:`blocking` shows the standard error against the block length: it
grows while blocks are shorter than the correlation time and levels off at
the true error once they are longer, which is how to choose `blocks`.

References
----------
.. [1] H. Flyvbjerg and H. G. Petersen, "Error estimates on averages of
   correlated data", J. Chem. Phys. 91, 461-466, 1989.
"""

from collections import namedtuple

import numpy as np

from .._checks import as_float_array, count

__all__ = ["Estimate", "block_average", "blocking"]

Estimate = namedtuple("Estimate", "mean error")
Estimate.__doc__ = """A mean and its standard error (same unit as the samples)."""


def block_average(samples, blocks=10):
    """Mean of a correlated time series and its standard error from block means.

    Parameters
    ----------
    samples : array_like, shape (N,)
        The series, in time order (e.g. the potential energy at every 10th
        step), any unit.
    blocks : int
        Number of blocks ``B``, >= 2 and at most ``N``. The first
        ``N mod B`` samples are dropped so that blocks are equally long
        (early samples are the least equilibrated).

    Returns
    -------
    Estimate
        ``(mean, error)``: the mean of the samples used, and
        ``std(block means, ddof=1) / sqrt(B)``, in the unit of `samples`.

    Raises
    ------
    ValueError
        For samples that are not a finite 1-d series, or `blocks` not an
        integer in ``[2, N]``.

    Examples
    --------
    >>> block_average([1.0, 3.0, 2.0, 4.0], blocks=2)     # block means 2 and 3
    Estimate(mean=2.5, error=0.5)
    """
    a = as_float_array(samples, "samples", ndim=1)
    B = count(blocks, "blocks", least=2)
    if B > len(a):
        raise ValueError(f"blocks must be at most the number of samples, {len(a)}, got {B}")
    length = len(a) // B
    means = a[len(a) - B * length:].reshape(B, length).mean(axis=1)
    return Estimate(float(means.mean()), float(means.std(ddof=1) / np.sqrt(B)))


def blocking(samples, min_blocks=4):
    """Standard error of the mean against the block length, doubling it each time.

    Parameters
    ----------
    samples : array_like, shape (N,)
        The series, in time order.
    min_blocks : int
        Stop when fewer blocks than this would remain (>= 2).

    Returns
    -------
    lengths : ndarray of int, shape (k,)
        Block lengths 1, 2, 4, ..., in samples.
    errors : ndarray, shape (k,)
        The standard error of the mean from blocks of that length (the
        first is the naive ``std / sqrt(N)``). It levels off once blocks
        are longer than the correlation time.
    """
    a = as_float_array(samples, "samples", ndim=1)
    least = count(min_blocks, "min_blocks", least=2)
    lengths, errors = [], []
    length = 1
    while len(a) // length >= least:
        lengths.append(length)
        errors.append(block_average(a, len(a) // length).error)
        length *= 2
    return np.array(lengths, dtype=np.int64), np.array(errors)
