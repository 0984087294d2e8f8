"""A synthetic class of many distinct submissions with planted copies, made from a master.

``bench_similarity.py`` times ``particles similarity`` on it, and the similarity tests
(``tests/course/similarity/test_compare.py``) check that the planted copies are found and build their
small cases with :func:`notebook`.
"""

import ast
import copy
import json
import random
import textwrap
from _corpus import ROOT, cell_source
EX02 = "02_stiffness"


def notebook(exercise, replace=None, append=()):
    """The master of `exercise` with the code cell defining each function in `replace` replaced."""
    nb = json.loads((ROOT / "solutions" / f"{exercise}.ipynb").read_text())
    for name, code in (replace or {}).items():
        cell = next(c for c in nb["cells"] if c["cell_type"] == "code" and f"def {name}(" in cell_source(c))
        cell["source"] = textwrap.dedent(code).strip("\n")
    for k, code in enumerate(append):
        nb["cells"].append({"cell_type": "code", "metadata": {}, "source": textwrap.dedent(code), "outputs": [],
                            "execution_count": None, "id": f"extra-{k}"})
    nb["metadata"]["particles"] = {"exercise": exercise}
    return nb


class _Rename(ast.NodeTransformer):
    def __init__(self, names):
        self.names = names

    def visit_Name(self, node):
        node.id = self.names.get(node.id, node.id)
        return node

    def visit_arg(self, node):
        node.arg = self.names.get(node.arg, node.arg)
        return node


def _variant(func, rng, kind):
    """A student's version of master function `func` (an ast.FunctionDef): renamed, mutated or rewritten."""
    func = copy.deepcopy(func)
    params = [a.arg for a in func.args.args]
    bound = sorted({n.id for n in ast.walk(func) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)})
    suffix = rng.choice(["_", "1", "_s", "x", "_v"])
    func = _Rename({n: n + suffix for n in params + bound}).visit(func)
    params = [a.arg for a in func.args.args]
    body = func.body[1:] if isinstance(func.body[0], ast.Expr) else func.body
    if kind == "mutated":
        for _ in range(rng.randint(1, 3)):
            p, q, c = rng.choice(params), rng.choice(params), round(rng.uniform(0.1, 9.0), 2)
            extra = rng.choice([f"assert {p} is not None", f"tmp_{len(body)} = np.asarray({p}, dtype=float)",
                                f"{p} = {c} * {p}", f"print({p}, {q})", f"w_{len(body)} = np.sum({p}) + {c}",
                                f"if {p} is None:\n    return None"])
            body.insert(rng.randrange(len(body)), ast.parse(extra).body[0])
        for node in ast.walk(ast.Module(body, [])):
            if isinstance(node, ast.Constant) and isinstance(node.value, float) and rng.random() < 0.3:
                node.value = round(node.value * rng.uniform(0.5, 2.0), 3)
    elif kind == "rewritten":
        body = []
        for j in range(rng.randint(3, 7)):
            p, q, c = rng.choice(params), rng.choice(params), rng.randint(1, 9)
            body.append(ast.parse(rng.choice([
                f"a{j} = np.zeros({c}) + {p}", f"for i{j} in range({c}):\n    {p} = {p} + i{j} * {q}",
                f"b{j} = [{p} for _ in range({c})]", f"if {p} > {q}:\n    {p}, {q} = {q}, {p}",
                f"c{j} = np.maximum({p}, {q}) ** {c}", f"while {p} < {c}:\n    {p} = {p} * 2",
                f"d{j} = {{'{p}': {q}, 'n': {c}}}", f"e{j} = np.linalg.norm(np.atleast_1d({p}))"])).body[0])
        body.append(ast.parse(f"return {rng.choice(params)}").body[0])
    func.body = func.body[:1] + body if isinstance(func.body[0], ast.Expr) else body
    return ast.unparse(func)


def write_synthetic(folder, n=300, exercise=EX02, seed=0, copies=10):
    """Write `n` submissions of `exercise`: a third close to the master, the rest mutated or rewritten.

    The first `copies` students copy every asked function of the student `n // 2 + k` (renamed; every other
    one with an extra line). Returns the planted pairs ``(copier, source)``.
    """
    rng = random.Random(seed)
    master = notebook(exercise)
    code = {}
    for cell in master["cells"]:
        if cell["cell_type"] == "code" and "### BEGIN SOLUTION" in cell_source(cell):
            func = next(s for s in ast.parse(cell_source(cell)).body if isinstance(s, ast.FunctionDef))
            code[func.name] = func
    students = {}
    for k in range(n):
        students[k] = {name: _variant(func, rng, rng.choices(["renamed", "mutated", "rewritten"], [3, 5, 2])[0])
                       for name, func in code.items()}
    planted = []
    for k in range(copies):
        source = n // 2 + k
        for name, text in students[source].items():
            copied = _variant(ast.parse(text).body[0], rng, "renamed")
            if k % 2:
                lines = copied.split("\n")
                lines.insert(len(lines) - 1, "    assert True, 'checked'")  # one extra line before the last
                copied = "\n".join(lines)
            students[k][name] = copied
        planted.append((f"student{k:03d}", f"student{source:03d}"))
    folder.mkdir(parents=True, exist_ok=True)
    for k, functions in students.items():
        (folder / f"student{k:03d}").mkdir()
        (folder / f"student{k:03d}" / f"{exercise}.ipynb").write_text(json.dumps(notebook(exercise, replace=functions)))
    return planted
