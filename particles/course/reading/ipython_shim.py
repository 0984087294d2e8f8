"""A stand-in for IPython's ``get_ipython()`` in the worker, for code read as Jupyter runs it.

The grader reads cells with IPython's transformer (:mod:`particles.course.reading.magics`),
so ``%timeit -o f()`` in a kept statement or inside a function becomes
``get_ipython().run_line_magic('timeit', '-o f()')``. The worker has no IPython
(it starts with NumPy only), so its namespace gets ``get_ipython`` from here:

* ``run_line_magic``: ``time stmt`` runs the statement in the notebook's
  namespace and returns its value; ``timeit [-o] stmt`` runs it once, in a
  namespace of its own as IPython does, and with ``-o`` returns a
  :class:`TimeitResult` (``best``, ``average``, ``worst``, ``stdev`` in
  seconds); ``prun stmt`` runs it; every other line magic (``matplotlib``,
  ``load_ext``, ``autoreload``, ``config``, ``pip``, ...) does nothing and
  returns None;
* ``run_cell_magic``: ``time``, ``capture`` and ``prun`` run the body once in
  the notebook's namespace (``%%capture out`` binds ``out``, with what was
  printed); ``timeit`` runs it once in a namespace of its own; ``writefile``
  writes a file in the working folder only (a plain file name); every other
  cell magic does nothing;
* ``system`` and ``getoutput`` (``!cmd``, ``x = !cmd``) run nothing and return
  None and an empty list.

It gives a submission no power it does not have already: it runs code with
``exec`` in the submission's own namespace, opens files with :func:`open`
under the worker's audit hook, and never starts a process.
"""

import contextlib
import io
import os
import re
import sys
import time

__all__ = ["Shell", "TimeitResult", "get_ipython_for"]


class TimeitResult:
    """What ``%timeit -o`` returns: times of one run, in seconds (the grader runs the statement once)."""

    def __init__(self, seconds, compile_time=0.0):
        self.loops, self.repeat = 1, 1
        self.all_runs = [seconds]
        self.timings = [seconds]
        self.best = self.worst = self.average = seconds
        self.stdev = 0.0
        self.compile_time = compile_time

    def __repr__(self):
        return f"<TimeitResult : {self.best:.3g} s per loop (1 run, 1 loop)>"


class _Output(list):
    """What ``x = !cmd`` returns: IPython's list of output lines (``.s``, ``.n``, ``.l``), here empty."""

    s = property(lambda self: " ".join(self))
    n = property(lambda self: "\n".join(self))
    l = property(lambda self: list(self))  # noqa: E741  (IPython's name)


class _Captured:
    """What ``%%capture out`` binds to ``out``: the text the cell printed."""

    def __init__(self, stdout, stderr):
        self.stdout, self.stderr, self.outputs = stdout, stderr, []

    def show(self):
        """Print what was captured."""
        print(self.stdout, end="")

    __call__ = show


def _options(line, with_value):
    """``(options, rest)`` of a magic's line, read like getopt: leading ``-x`` flags, the value of those in
    `with_value` (``-n 10`` or ``-n10``), and the rest of the line as it was written."""
    options, rest = {}, line
    while True:
        match = re.match(r"\s*-(\S+)", rest)
        if match is None:
            return options, rest.strip()
        flags, rest = match.group(1), rest[match.end():]
        for k, flag in enumerate(flags):
            if flag in with_value:
                value = flags[k + 1:]
                if not value:
                    word = re.match(r"\s*(\S*)", rest)
                    value, rest = word.group(1), rest[word.end():]
                options[flag] = value
                break
            options[flag] = True


class Shell:
    """The object ``get_ipython()`` returns in the worker.

    Parameters
    ----------
    namespace : dict
        The submission's namespace, in which statements and cells run.
    """

    def __init__(self, namespace):
        self.user_ns = namespace

    def _run(self, source, local=None):
        """Run `source` with the notebook's globals and `local` names: an expression's value, or None."""
        source = source.strip()
        if not source:
            return None
        try:
            code = compile(source, "<magic>", "eval")
        except SyntaxError:
            exec(compile(source, "<magic>", "exec"), self.user_ns, local)
            return None
        return eval(code, self.user_ns, local)

    def run_line_magic(self, name, line, _stack_depth=1):
        """Answer ``%name line`` (see the module docstring).

        As in IPython, ``time`` and ``timeit`` inside a function see its local variables.
        """
        caller = sys._getframe(_stack_depth).f_locals
        local = None if caller is self.user_ns else caller
        if name == "time":
            return self._run(line, local)
        if name == "prun":
            self._run(_options(line, {"s", "l", "T", "D"})[1], local)
            return None
        if name == "timeit":
            options, statement = _options(line, {"n", "r", "p"})
            start = time.perf_counter()
            self._run(statement, dict(local or {}))  # names it binds stay its own, as in IPython
            return TimeitResult(time.perf_counter() - start) if "o" in options else None
        return None

    def run_cell_magic(self, name, line, cell):
        """Answer a ``%%name line`` cell with body `cell`, plain Python (see the module docstring).

        The grader's reading of the notebook unpacks ``%%time``, ``%%capture`` and
        ``%%prun`` cells itself (:mod:`particles.course.reading.submission`); this answers the calls
        that code makes on its own.
        """
        if name in ("time", "prun"):
            exec(compile(cell, "<magic>", "exec"), self.user_ns)
        elif name == "capture":
            out, err = io.StringIO(), io.StringIO()
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                exec(compile(cell, "<magic>", "exec"), self.user_ns)
            target = line.split()[-1] if line.split() and not line.split()[-1].startswith("-") else None
            if target and target.isidentifier():
                self.user_ns[target] = _Captured(out.getvalue(), err.getvalue())
        elif name == "timeit":
            setup = _options(line, {"n", "r", "p"})[1]
            exec(compile(setup + "\n" + cell, "<magic>", "exec"), self.user_ns, {})  # its own names, as in IPython
        elif name in ("writefile", "file"):
            options, path = _options(line, set())
            path = path.strip()
            if path and os.path.basename(path) == path and path not in (".", ".."):
                with open(path, "a" if "a" in options else "w", encoding="utf-8") as handle:
                    handle.write(cell)
        return None

    def magic(self, line):
        """The old spelling ``get_ipython().magic("name line")``."""
        name, _, rest = line.lstrip("%").partition(" ")
        return self.run_line_magic(name, rest, _stack_depth=2)

    def system(self, command):
        """``!command``: the grader runs no shell command."""
        return None

    def getoutput(self, command, split=True):
        """``x = !command``: no command runs, the output is empty."""
        return _Output()


def get_ipython_for(namespace):
    """A ``get_ipython`` function for the worker's `namespace`, always returning the same :class:`Shell`."""
    shell = Shell(namespace)

    def get_ipython():
        """The grader's stand-in for IPython's shell (see :mod:`particles.course.reading.ipython_shim`)."""
        return shell

    return get_ipython
