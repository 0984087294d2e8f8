"""Fingerprints of compiled code: the library's forbidden functions recognised by what runs, honest code never."""

import inspect
import re
import textwrap
import types

import numpy as np
import pytest

import particles.integrators.steppers as steppers
from particles.course.reading.forbidden import forbidden_code
from particles.course.worker import codeprints
from particles.course.worker.codeprints import LibraryPrints, fingerprint, library_prints

FORBIDDEN = ("particles.integrators.euler", "particles.integrators.midpoint", "particles.integrators.rk4",
             "particles.forces.Gravity", "particles.studies.order.fit_order")


def _functions(source, name=None, **extra):
    """The functions a piece of source defines (compiled from a string, as an exec of a copy would)."""
    namespace = {"__name__": "copy", **extra}
    exec(compile(textwrap.dedent(source), "<copy>", "exec"), namespace)
    return namespace if name is None else namespace[name]


def _steppers_copy(edit=lambda text: text):
    """The library's steppers module, run again from its source (possibly edited): a dict of new functions."""
    text = edit(inspect.getsource(steppers))
    return _functions(text, __package__="particles.integrators", __name__="particles.integrators.steppers")


@pytest.fixture(scope="module")
def prints():
    return library_prints(FORBIDDEN)


def test_fingerprint_ignores_names_texts_and_lines():
    """Renamed function, arguments, locals and helpers, another docstring or message: the same fingerprint."""
    a = _functions('''
        def step(f, X, t, h):
            """One Euler step."""
            X_new = X + h * evaluate(f, X, t)
            if X_new.shape != X.shape:
                raise ValueError("bad shape")
            return X_new
    ''', "step", evaluate=None)
    b = _functions('''


        def my_step(rhs, state, time, dt):
            nxt = state + dt * ev(rhs, state, time)
            if nxt.shape != state.shape:
                raise ValueError("the shapes differ")
            return nxt
    ''', "my_step", ev=None)
    assert fingerprint(a.__code__) == fingerprint(b.__code__)


@pytest.mark.parametrize("other", [
    "def step(f, X, t, h):\n    return X + 0.5 * h * f(X, t)",     # another constant
    "def step(f, X, t, h):\n    return X - h * f(X, t)",           # another operation
    "def step(f, X, t, h):\n    return X + h * f(X, t + h)",       # another argument
    "def step(f, X, h, t):\n    return X + h * f(X, t)",           # the arguments in another order
])
def test_fingerprint_tells_different_code_apart(other):
    """A different constant, operation, argument or argument order gives another fingerprint."""
    base = _functions("def step(f, X, t, h):\n    return X + h * f(X, t)", "step")
    assert fingerprint(base.__code__) != fingerprint(_functions(other, "step").__code__)


def test_fingerprint_refuses_what_is_not_code():
    """Anything but a code object is a TypeError naming what it got."""
    with pytest.raises(TypeError, match="code must be a code object, got function"):
        fingerprint(lambda: 0)


@pytest.mark.parametrize("variant", ["as_is", "renamed", "new_docstrings", "renamed_locals"])
def test_a_rerun_copy_of_the_library_is_recognised(prints, variant):
    """The steppers' source run again (renamed, docstrings rewritten, locals renamed) is the library's euler."""
    edits = {
        "as_is": lambda text: text,
        "renamed": lambda text: re.sub(r"\beuler\b", "my_step", text),
        "new_docstrings": lambda text: text.replace('"""Explicit (forward) Euler step', '"""Mine, all mine'),
        "renamed_locals": lambda text: text.replace("X_m", "halfway").replace("k1", "slope_1"),
    }
    copy = _steppers_copy(edits[variant])
    euler = copy["my_step" if variant == "renamed" else "euler"]
    assert euler is not steppers.euler
    assert prints.match(codeprints.describe(euler.__code__)) == ("particles.integrators.euler",
                                                                 "particles.integrators.euler")
    assert prints.match(codeprints.describe(copy["rk4"].__code__))[0] == "particles.integrators.rk4"


def test_an_edited_copy_of_a_long_function_is_recognised(prints):
    """A line added to the library's rk4 (a long function): still the library's rk4, by its shared shingles."""
    copy = _steppers_copy(lambda text: text.replace("    k4 = evaluate(f, X + h * k3, t + h)\n",
                                                    "    k4 = evaluate(f, X + h * k3, t + h)\n    unused = k4 * 0\n"))
    record = codeprints.describe(copy["rk4"].__code__)
    assert record["fp"] != codeprints.describe(steppers.rk4.__code__)["fp"]
    assert prints.match(record) == ("particles.integrators.rk4", "particles.integrators.rk4")


def test_a_class_method_copy_names_the_class(prints):
    """A copy of a forbidden class's method is reported as that method of the library's class."""
    import particles.forces.fields as fields

    source = inspect.getsource(fields.Gravity).replace("class Gravity", "class Pull")
    namespace = dict(vars(fields))
    exec(compile(source, "<copy>", "exec"), namespace)
    record = codeprints.describe(namespace["Pull"].add_to.__code__)
    assert prints.match(record) == ("particles.forces.Gravity.add_to", "particles.forces.Gravity")


@pytest.mark.parametrize("source", [
    "def euler_step(f, X, t, h):\n    return X + h * f(X, t)",
    # the library's name, the library's shape
    "def euler(f, X, t, h):\n    X = np.asarray(X, float)\n    return X + h * np.asarray(f(X, t))",
    "def midpoint_step(f, X, t, h):\n    X_m = X + 0.5 * h * f(X, t)\n    return X + h * f(X_m, t + 0.5 * h)",
    "def rk4_step(f, X, t, h):\n    k1 = f(X, t)\n    k2 = f(X + 0.5 * h * k1, t + 0.5 * h)\n"
    "    k3 = f(X + 0.5 * h * k2, t + 0.5 * h)\n    k4 = f(X + h * k3, t + h)\n"
    "    return X + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)",
    "def fit_order(h, e):\n    slope, _ = np.polyfit(np.log(h), np.log(e), 1)\n    return slope",
])
def test_honest_code_is_not_the_library(prints, source):
    """A student's own steps and fit, even named like the library's functions, are nobody's but theirs."""
    function = _functions(source, source.split("(")[0][4:], np=np)
    for code in codeprints.nested(function.__code__):
        assert prints.match(codeprints.describe(code)) is None


def test_short_library_code_is_never_matched():
    """Library code of fewer than MIN_TOKENS tokens is left out: an honest student writes the same."""
    tiny = _functions("def n(self):\n    return len(self.X)", "n")
    assert codeprints.describe(tiny.__code__)["size"] < codeprints.MIN_TOKENS
    assert len(LibraryPrints([("tiny.n", "tiny", tiny.__code__)])) == 0


def test_forbidden_code_lists_functions_methods_and_modules():
    """A function gives its code, a class each method, a module each function it defines; constants nothing."""
    found = forbidden_code(["particles.integrators.euler", "particles.forces.Gravity", "particles.studies.order",
                            "particles.studies.stability.THEORY_OMEGA_H"])
    labels = {label for label, _, _ in found}
    assert "particles.integrators.euler" in labels and "particles.forces.Gravity.add_to" in labels
    assert "particles.studies.order.fit_order" in labels
    assert not any("THEORY_OMEGA_H" in label for label in labels)
    assert all(isinstance(code, types.CodeType) for _, _, code in found)
