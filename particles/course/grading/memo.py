"""Reference results computed once per grading session: the decorator :func:`memoized`.

One pytest session of the grader grades a batch of notebooks (see
:mod:`particles.course.grading.session`). The public tests ask every notebook the
same questions, and the hidden tests ask the same ones of every notebook graded
with the same seed, so a reference that a test computes from its own inputs (a
measured stability limit, the global errors of the reference stepper, a relaxed
cloth) comes out the same for each notebook. ``@memoized`` on such a function
computes it once per distinct arguments and gives every caller its own deep copy,
so that no test can change what the next one receives.

Only the grader's own inputs belong in the arguments: a function of what a
student's code returned is computed anew for every notebook anyway.

>>> calls = []
>>> @memoized
... def square(x):
...     calls.append(x)
...     return [x * x]
>>> square(3), square(3), calls
([9], [9], [3])
>>> square(3) is square(3)
False
"""

import copy
import functools
import pickle
from collections import OrderedDict

__all__ = ["memoized"]

SIZE = 512
"""Results kept per function; the least recently used one goes first."""


def memoized(function):
    """Decorate a pure function of the grader's inputs: each result is computed once per session.

    Parameters
    ----------
    function : callable
        A function whose result depends only on its arguments. The arguments must
        pickle (numbers, strings, tuples, lists, dicts, NumPy arrays): they are compared by
        their pickled bytes, so ``1`` and ``1.0`` are two keys.

    Returns
    -------
    callable
        The same function, returning a deep copy of the result it computed the first
        time it was called with equal arguments (at most :data:`SIZE` results kept).
        An exception is not remembered: the next call computes again. ``.cache_clear()``
        forgets every result.

    Raises
    ------
    TypeError
        When called with an argument that does not pickle (a lambda, an open file),
        naming the function.
    """
    results = OrderedDict()

    @functools.wraps(function)
    def remembered(*args, **kwargs):
        try:
            key = pickle.dumps((args, sorted(kwargs.items())), protocol=pickle.HIGHEST_PROTOCOL)
        except (pickle.PicklingError, TypeError, AttributeError) as error:
            raise TypeError(f"{function.__qualname__} is memoized, so its arguments must pickle: {error}") from None
        if key in results:
            results.move_to_end(key)
        else:
            results[key] = function(*args, **kwargs)
            if len(results) > SIZE:
                results.popitem(last=False)
        return copy.deepcopy(results[key])

    remembered.cache_clear = results.clear
    return remembered
