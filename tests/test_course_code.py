"""Which statements of a submission run in the grader, and which library names they use."""

from particles.course.code import SubmissionCode

FORBIDDEN = ["particles.integrators.euler", "particles.integrators.INTEGRATORS", "particles.integrators.integrate"]


def _code(*sources):
    return SubmissionCode.from_cells([(f"code cell {k}", s) for k, s in enumerate(sources, start=1)])


def test_only_definitions_imports_and_constants_run():
    """Imports, defs, classes and constant assignments run; calls, loops, plots and magics do not."""
    code = _code("%matplotlib inline\nimport numpy as np\nh = 0.1; X0 = np.array([1.0, 0.0])",
                 "t, X = simulate(X0)\nE = X[:, 0] ** 2\nfor k in range(10):\n    print(k)\nplt.plot(t, X)",
                 "@np.vectorize\ndef sq(x):\n    return x * x\nclass A:\n    pass",
                 "%%time\nslow()")
    assert [c.source for c in code.chunks] == ["import numpy as np", "h = 0.1", "X0 = np.array([1.0, 0.0])",
                                               "@np.vectorize\ndef sq(x):\n    return x * x", "class A:\n    pass"]
    reasons = {s.text.split()[0]: s.reason for s in code.skipped}
    assert "computed by a call" in reasons["t,"] and "did not compute" in reasons["E"]
    assert reasons["for"] == "a top-level loop" and reasons["%%time"] == "a cell magic"
    assert code.chunks[3].line == 1 and code.chunks[4].line == 4


def test_syntax_errors_are_recorded_not_raised():
    """A cell with a syntax error is reported and skipped; the other cells still run."""
    code = _code("def f(:\n    pass", "def g():\n    return 1")
    assert code.syntax_errors == [("code cell 1", "line 1: invalid syntax")]
    assert "g" in code.defines() and "f" not in code.defines()


def test_forbidden_uses_through_aliases_helpers_and_getattr():
    """Forbidden names are found through import aliases, package re-exports, helpers and getattr."""
    code = _code("import particles.integrators as I\nfrom particles import INTEGRATORS as T\nimport particles",
                 "def a(f, X, t, h):\n    return I.euler(f, X, t, h)",
                 "def b(f, X, t, h):\n    return helper(f, X, t, h)\ndef helper(f, X, t, h):\n    return T['euler'](f, X, t, h)",
                 "def c(f, X0):\n    return particles.integrate(f, X0, 0, 1, 0.1)",
                 "def d(f, X, t, h):\n    return getattr(I, 'euler')(f, X, t, h)",
                 "def clean(X):\n    return X.copy()")
    assert code.forbidden_uses("a", FORBIDDEN) == [("particles.integrators.euler", ["a"])]
    assert code.forbidden_uses("b", FORBIDDEN) == [("particles.integrators.INTEGRATORS", ["b", "helper"])]
    assert code.forbidden_uses("c", FORBIDDEN) == [("particles.integrators.integrate", ["c"])]
    assert code.forbidden_uses("d", FORBIDDEN)[0][0] == "particles.integrators.euler"
    assert code.forbidden_uses("clean", FORBIDDEN) == []


def test_parameters_and_skipped_assignments():
    """Parameter names come from the last def; a name bound only by a skipped call is explained."""
    code = _code("def step(f, X, t, h):\n    return X", "stepper = make()")
    assert code.parameters("step") == ["f", "X", "t", "h"]
    assert code.skipped_assignment("stepper").text == "stepper = make()"


def test_a_cell_source_that_is_not_text_makes_the_notebook_unreadable(tmp_path):
    """A code cell whose source holds numbers, or cells that are not a list, is an unreadable notebook (ValueError)."""
    import json

    import pytest

    from particles.course.code import notebook_cells

    cases = {"numbers": {"cells": [{"cell_type": "code", "source": [1, 2]}]},
             "a_dict": {"cells": [{"cell_type": "code", "source": {"a": 1}}]},
             "cells_dict": {"cells": {"a": 1}}}
    for name, notebook in cases.items():
        (tmp_path / f"{name}.ipynb").write_text(json.dumps(notebook))
    with pytest.raises(ValueError, match=r"the source of code cell 1 holds a list with an item of type int, not text"):
        notebook_cells(tmp_path / "numbers.ipynb")
    with pytest.raises(ValueError, match=r"the source of code cell 1 holds a value of type dict, not text"):
        notebook_cells(tmp_path / "a_dict.ipynb")
    with pytest.raises(ValueError, match=r"its cells are a dict, not a list"):
        notebook_cells(tmp_path / "cells_dict.ipynb")


def test_a_null_byte_is_a_syntax_error_without_line_none():
    """A null byte in a cell is reported as that cell's syntax error, with no 'line None'."""
    code = _code("def f():\n    return 1\x00\n", "def g():\n    return 1")
    assert len(code.syntax_errors) == 1 and code.syntax_errors[0][0] == "code cell 1"
    assert "null bytes" in code.syntax_errors[0][1] and "None" not in code.syntax_errors[0][1]
    assert "g" in code.defines()
