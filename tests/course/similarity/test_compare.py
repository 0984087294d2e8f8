"""`particles similarity`: submitted functions structurally equal to the library, a master or a classmate."""

import csv
import inspect
import json
import re
import sys
import textwrap
from pathlib import Path

import pytest

import particles.integrators
import particles.massspring
from particles.cli import main
from particles.course.similarity.compare import fingerprint, library_functions, score, similarity

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "bench"))  # the synthetic class, and notebooks made from a master, are the bench's

from synthetic_class import cell_source, notebook, write_synthetic  # noqa: E402

EX01, EX00 = "01_integrator_order", "00_warmup"


def write(folder, student, exercise, **case):
    """Write `student`'s notebook as folder/student/exercise.ipynb."""
    (folder / student).mkdir(parents=True, exist_ok=True)
    (folder / student / f"{exercise}.ipynb").write_text(json.dumps(notebook(exercise, **case), indent=1))


def renamed(obj, names):
    """The source of a library function with its decorators removed and identifiers renamed."""
    text = textwrap.dedent(inspect.getsource(obj))
    text = re.sub(r"^@.*\n", "", text, flags=re.M)
    pattern = r"\b(" + "|".join(map(re.escape, names)) + r")\b(?![\"'])"  # not the f of f"..."
    return re.sub(pattern, lambda m: names[m.group(1)], text)


STEP_NAMES = {"f": "rhs", "X": "state", "t": "time", "h": "dt", "X_m": "half", "dX": "slope",
              "check_arguments": "check_inputs", "evaluate": "slope_of", "midpoint": "midpoint_step"}
STEP_IMPORTS = ("import math\nimport numpy as np\n"
                "from particles._checks import as_float_array, finite_real, positive_number\n")


def copied_midpoint(extra_line=""):
    """A midpoint_step cell that pastes the library's midpoint and its two helpers under new names."""
    common = particles.integrators.common
    helpers = renamed(common.check_arguments, STEP_NAMES) + renamed(common.evaluate, STEP_NAMES)
    step = renamed(particles.integrators.midpoint, STEP_NAMES)
    if extra_line:
        step = step.replace("    state, dt = check_inputs", f"    {extra_line}\n    state, dt = check_inputs")
    return STEP_IMPORTS + helpers + "\n" + step


def pairs_of(report, owner):
    """(function of `owner`, what it matches, score, match) for every reported pair with `owner` in it."""
    out = []
    for p in report.pairs:
        for a, b in ((p.a, p.b), (p.b, p.a)):
            if a.owner == owner:
                out.append((a.name, f"{b.owner}: {b.name}", round(p.score, 3), p.match))
    return out


def test_renamed_copy_of_library_midpoint_is_identical(tmp_path):
    """The library's midpoint and its helpers pasted with every name changed are reported identical to them."""
    write(tmp_path, "ada", EX01, replace={"midpoint_step": copied_midpoint()})
    report = similarity([tmp_path], root=ROOT)
    found = pairs_of(report, "ada")
    assert ("midpoint_step", "library: particles.integrators.steppers.midpoint", 1.0, "identical") in found
    # the renaming also changed the error messages ('state must be finite'): the same structure, other constants
    assert ("check_inputs", "library: particles.integrators.common.check_arguments", 1.0,
            "identical up to constants") in found
    assert ("slope_of", "library: particles.integrators.common.evaluate", 1.0, "identical up to constants") in found
    where = next(p for p in report.pairs if p.b.name == "particles.integrators.steppers.midpoint" or
                 p.a.name == "particles.integrators.steppers.midpoint")
    lib, student = sorted((where.a, where.b), key=lambda f: f.kind)
    assert lib.path == "particles/integrators/steppers.py" and lib.line == inspect.getsourcelines(
        particles.integrators.midpoint)[1] + 1  # below the decorator
    assert student.path == f"ada/{EX01}.ipynb" and student.cell == "code cell 3" and student.role == "asked"


def test_renamed_copy_of_the_string_builder_is_identical(tmp_path):
    """particles.massspring.string (from particles.massspring.strands) pasted, names changed, helpers imported: identical."""
    # keyword arguments (m=m, springs=[springs], pinned=pinned) keep their names: they are the callee's API
    names = {"string": "make_chain", "n": "count", "length": "L", "x": "pos", "i": "idx", "direction": "u"}
    cell = ("import numpy as np\nfrom particles.massspring import MassSpringSystem\n"
            "from particles.massspring.strands import _chain, _chain_parameters\n"
            "from particles.massspring.model import common_forces\n"
            "from particles.forces import Springs\n\n"
            + renamed(particles.massspring.string, names)
            + "\n\ndef run(f, X0, t0, h, n_steps):\n    system = make_chain(3)\n    return system.X, n_steps\n")
    write(tmp_path, "ada", EX00, replace={"run": cell})
    found = pairs_of(similarity([tmp_path], root=ROOT), "ada")
    assert ("make_chain", "library: particles.massspring.strands.string", 1.0, "identical") in found


def test_two_students_with_the_same_code_under_other_names(tmp_path):
    """Two students' functions that differ only in names, comments and docstrings are reported identical."""
    ada = '''
    def observed_order(h, errors):
        """Slope by least squares."""
        logh = np.log(np.asarray(h, dtype=float))
        loge = np.log(np.asarray(errors, dtype=float))
        A = np.vstack([logh, np.ones_like(logh)]).T
        slope, intercept = np.linalg.lstsq(A, loge, rcond=None)[0]
        return float(slope)
    '''
    bob = '''
    import numpy
    from numpy.linalg import lstsq
    def observed_order(step_sizes, errs):
        # fit a line through the log-log points
        x = numpy.log(numpy.asarray(step_sizes, dtype=float))
        y = numpy.log(numpy.asarray(errs, dtype=float))
        M = numpy.vstack([x, numpy.ones_like(x)]).T   # design matrix
        p, c = lstsq(M, y, rcond=None)[0]
        return float(p)
    '''
    write(tmp_path, "ada", EX01, replace={"observed_order": ada})
    write(tmp_path, "bob", EX01, replace={"observed_order": bob})
    report = similarity([tmp_path], root=ROOT)
    assert ("observed_order", "bob: observed_order", 1.0, "identical") in pairs_of(report, "ada")
    cluster = next(c for c in report.clusters if c.members[0].name == "observed_order")
    assert cluster.students == ["ada", "bob"] and cluster.score == 1.0
    assert not [m for m in cluster.members if m.kind != "student"]  # not the master's way


def test_independent_rewrite_is_not_flagged_against_the_library(tmp_path):
    """A midpoint and an rk4 written another way (a tableau loop, inline slopes) match no library function."""
    rk4 = '''
    def rk4_step(f, X, t, h):
        """RK4 from its Butcher tableau."""
        a = [[], [0.5], [0.0, 0.5], [0.0, 0.0, 1.0]]
        b, c = [1 / 6, 1 / 3, 1 / 3, 1 / 6], [0.0, 0.5, 0.5, 1.0]
        k = []
        for i in range(4):
            Xi = X + h * sum(aij * kj for aij, kj in zip(a[i], k))
            k.append(f(Xi, t + c[i] * h))
        return X + h * sum(bi * ki for bi, ki in zip(b, k))
    '''
    midpoint = '''
    def midpoint_step(f, X, t, h):
        half = h / 2
        return X + h * f(X + half * f(X, t), t + half)
    '''
    write(tmp_path, "cyd", EX01, replace={"rk4_step": rk4, "midpoint_step": midpoint})
    report = similarity([tmp_path], root=ROOT, threshold=0.6)
    found = pairs_of(report, "cyd")
    assert not [p for p in found if p[0] in ("rk4_step", "midpoint_step")], found
    library = fingerprint(inspect.getsource(particles.integrators.steppers), "rk4")
    ours = fingerprint("import numpy as np\n" + textwrap.dedent(rk4))
    assert score(library, ours) < 0.5


def test_near_copy_with_one_extra_line_scores_above_threshold(tmp_path):
    """The pasted midpoint with one extra line is 'similar' to the library's, above 0.8 but below 1."""
    write(tmp_path, "dan", EX01, replace={"midpoint_step": copied_midpoint("assert dt > 0, 'dt must be positive'")})
    report = similarity([tmp_path], root=ROOT)
    (hit,) = [p for p in pairs_of(report, "dan")
              if p[:2] == ("midpoint_step", "library: particles.integrators.steppers.midpoint")]
    assert hit[3] == "similar" and 0.8 <= hit[2] < 1.0
    assert hit[2] == pytest.approx(2 * 36 / (36 + 41), abs=1e-3)  # 36 nodes plus the 5 of the assert
    assert not [p for p in pairs_of(similarity([tmp_path], root=ROOT, threshold=0.95), "dan")
                if p[0] == "midpoint_step"]


def test_trivially_short_functions_are_not_flagged(tmp_path):
    """Two identical one-line Euler steps (9 nodes) are ignored and listed as short, unless min_nodes allows them."""
    euler = "def euler_step(f, X, t, h):\n    return X + h * f(X, t)  # the master's way\n"
    for student in ("ada", "bob"):
        write(tmp_path, student, EX00, replace={"euler_step": euler})
    report = similarity([tmp_path], root=ROOT)
    assert not [p for p in report.pairs if p.a.name == "euler_step" or p.b.name == "euler_step"]
    assert report.short[f"{EX00} euler_step"] == 2
    assert fingerprint(euler).size == 9
    loose = similarity([tmp_path], root=ROOT, min_nodes=5)
    assert ("euler_step", "bob: euler_step", 1.0, "identical") in pairs_of(loose, "ada")


def test_released_stub_and_given_code_are_not_compared(tmp_path):
    """Stubs left unwritten and functions the stub hands out (midpoint_wrong_time) are never reported."""
    for student in ("ada", "bob"):
        (tmp_path / student).mkdir()
        stub = json.loads((ROOT / "exercises" / f"{EX01}.ipynb").read_text())
        cell = next(c for c in stub["cells"] if "def measured_order(" in cell_source(c))
        cell["source"] = ("def measured_order(method, f, X0, t0, t1, exact, n_steps):\n"
                          "    return midpoint_wrong_time(f, X0, t0, t1)\n")
        (tmp_path / student / f"{EX01}.ipynb").write_text(json.dumps(stub))
    report = similarity([tmp_path], root=ROOT, min_nodes=0)
    assert [(p.a.label, p.b.label, p.match) for p in report.pairs] == [
        ("ada: measured_order", "bob: measured_order", "identical")]
    assert report.unwritten[f"{EX01} rk4_step"] == 2 and report.compared == 2


def test_normalization_rules():
    """Module aliases resolve, names and docstrings go, argument order and attributes stay, constants are a level."""
    a = fingerprint("import numpy as np\ndef f(x, y):\n    '''Doc.'''\n    z = np.sqrt(x) - y\n    return z.T")
    b = fingerprint("from numpy import sqrt\ndef g(p, q):\n    r = sqrt(p) - q  # comment\n    return r.T")
    swapped = fingerprint("import numpy as np\ndef f(x, y):\n    z = np.sqrt(y) - x\n    return z.T")
    other_attr = fingerprint("import numpy as np\ndef f(x, y):\n    z = np.sqrt(x) - y\n    return z.real")
    other_module = fingerprint("import math as np\ndef f(x, y):\n    z = np.sqrt(x) - y\n    return z.T")
    assert a.exact == b.exact and a.tokens == b.tokens
    assert len({a.structure, swapped.structure, other_attr.structure, other_module.structure}) == 4
    c1 = fingerprint("def f(x):\n    return 2.0 * x + 1")
    c2 = fingerprint("def f(x):\n    return 3.5 * x + 7")
    assert c1.structure == c2.structure and c1.exact != c2.exact and score(c1, c2) == 1.0
    assert "N:<self>" in fingerprint("def fact(n):\n    return 1 if n < 2 else n * fact(n - 1)").tokens


def test_cli_prints_a_table_and_writes_csv_and_markdown(tmp_path, capsys):
    """`particles similarity DIR --out` exits 0, prints the pairs and writes similarity.csv and similarity.md."""
    write(tmp_path / "subs", "ada", EX01, replace={"midpoint_step": copied_midpoint()})
    write(tmp_path / "subs", "bob", EX01, replace={"midpoint_step": copied_midpoint("assert dt > 0")})
    code = main(["similarity", str(tmp_path / "subs"), "--out", str(tmp_path / "out"), "--root", str(ROOT)])
    assert code == 0
    out = capsys.readouterr().out
    assert "2 submissions" in out and "particles.integrators.steppers.midpoint" in out and "identical" in out
    rows = list(csv.DictReader(open(tmp_path / "out" / "similarity.csv")))
    assert {"cluster", "score", "match", "owner_a", "function_a", "line_a", "owner_b", "function_b"} <= set(rows[0])
    assert any({r["owner_a"], r["owner_b"]} == {"ada", "library"} and r["score"] == "1.000" for r in rows)
    assert any({r["owner_a"], r["owner_b"]} == {"ada", "bob"} and r["match"] == "similar" for r in rows)
    text = (tmp_path / "out" / "similarity.md").read_text()
    assert text.startswith("# Similarity report") and "## Cluster 1" in text
    # an unreadable notebook and a cell that does not parse are listed, and the report still goes out
    (tmp_path / "subs" / "eve").mkdir()
    (tmp_path / "subs" / "eve" / f"{EX01}.ipynb").write_text("{not json")
    write(tmp_path / "subs", "fay", EX01, replace={"rk4_step": "def rk4_step(f, X, t, h):\n    return X +"})
    assert main(["similarity", str(tmp_path / "subs"), "--root", str(ROOT)]) == 0
    captured = capsys.readouterr()
    assert "not compared: " in captured.err and "is not a readable Jupyter notebook" in captured.err
    assert "code cell 5 has a syntax error" in captured.err and "3 submissions" in captured.out
    # nothing to report is still a report: exit 0
    assert main(["similarity", str(tmp_path / "subs"), "--exercise", EX00, "--root", str(ROOT)]) == 0


@pytest.mark.parametrize("argv, message", [
    (["similarity", "MISSING"], "DIR"),
    (["similarity", ".", "--threshold", "1.5"], "threshold must be a number from 0 to 1, got 1.5"),
    (["similarity", ".", "--threshold", "-0.1"], "threshold"),
    (["similarity", ".", "--exercise", "99_none"], "unknown exercise '99_none'"),
    (["similarity", ".", "--min-nodes", "-1"], "min_nodes"),
])
def test_cli_bad_arguments_exit_2(tmp_path, capsys, argv, message):
    """A missing folder, a threshold outside [0, 1], an unknown exercise: exit 2 with a message naming it."""
    argv = [str(tmp_path / a) if a in ("MISSING", ".") else a for a in argv]
    assert main([*argv, "--root", str(ROOT)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("particles similarity: ") and message in err


def test_cli_threshold_must_be_a_number(capsys):
    """--threshold abc is rejected by the parser (exit 2) naming the option."""
    with pytest.raises(SystemExit) as stop:
        main(["similarity", ".", "--threshold", "abc"])
    assert stop.value.code == 2 and "--threshold" in capsys.readouterr().err


def test_planted_copies_are_found_among_many_distinct_submissions(tmp_path):
    """In a synthetic class of 60 submissions, the planted copies (renamed, or with an extra line) are clustered."""
    planted = write_synthetic(tmp_path, n=60, copies=6)
    report = similarity([tmp_path], root=ROOT)
    assert report.submissions == 60 and report.compared > 400
    together = {(a.owner, b.owner, a.name) for c in report.clusters for a in c.members for b in c.members}
    for copier, source in planted:
        found = {name for a, b, name in together if (a, b) == (copier, source)}
        assert len(found) >= 8, (copier, source, found)  # of the 9 asked functions; short ones are ignored


def test_library_functions_that_only_delegate_are_no_references():
    """A library function whose body is ``return g(...)`` is not compared; one with more to it is."""
    names = {f.name for f in library_functions()}
    assert "particles.collisions.candidates.candidates_touching" not in names  # return candidates_in_boxes(...)
    assert "particles.collisions.candidates.candidates_in_boxes" in names and "particles.integrators.steppers.midpoint" in names
