"""Corpora of wrong and alternative submissions for the exercises 01 onwards.

Each exercise ``NN_topic`` has a module ``tests/grader/cases_NN_topic.py`` that
defines

* ``EXERCISE = "NN_topic"``;
* ``REJECTED``: case name -> ``{"replace": {function: code}, "append": [code],
  "fails": {test: piece of its reason}, "passes": [tests]}``, at least two
  per exercise, each losing the points it should with a message that says
  what is wrong;
* ``CORRECT`` (optional): case name -> a case that must score full marks.

A case starts from the master notebook ``solutions/NN_topic.ipynb`` and
replaces the code cell that defines each named function (``replace``), or
appends code cells (``append``). The 00_warmup corpus (``corpus.py``) is the
larger one that tests the grader's defences; these test the exercises.
"""

import importlib
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent


def case_modules():
    """The ``cases_NN_topic`` modules of this folder, in exercise order."""
    names = sorted(p.stem for p in HERE.glob("cases_*.py"))
    return [importlib.import_module(name) for name in names]


def _source(cell):
    source = cell["source"]
    return "".join(source) if isinstance(source, list) else source


def build(exercise, case):
    """The notebook (a dict) of `case` for `exercise`, made from its master."""
    notebook = json.loads((ROOT / "solutions" / f"{exercise}.ipynb").read_text())
    for name, code in case.get("replace", {}).items():
        for cell in notebook["cells"]:
            if cell["cell_type"] == "code" and f"def {name}(" in _source(cell):
                cell["source"] = code.strip("\n")
                break
        else:
            raise KeyError(f"no code cell of {exercise} defines {name}")
    for code in case.get("append", []):
        notebook["cells"].append({"cell_type": "code", "metadata": {}, "source": code, "outputs": [],
                                  "execution_count": None, "id": f"extra-{len(notebook['cells'])}"})
    notebook["metadata"]["particles"] = {"exercise": exercise}
    return notebook


def write_corpora(folder, modules=None):
    """Write every case as ``folder/<exercise>__<case>/<exercise>.ipynb``, plus each master and stub.

    Returns
    -------
    dict
        student name -> (exercise, case name), with case names ``"master"``
        and ``"released_stub"`` for the two reference notebooks.
    """
    folder = Path(folder)
    students = {}
    for module in modules or case_modules():
        exercise = module.EXERCISE
        cases = dict(module.REJECTED, **getattr(module, "CORRECT", {}))
        texts = {name: json.dumps(build(exercise, case), indent=1) for name, case in cases.items()}
        texts["master"] = (ROOT / "solutions" / f"{exercise}.ipynb").read_text()
        texts["released_stub"] = (ROOT / "exercises" / f"{exercise}.ipynb").read_text()
        for name, text in texts.items():
            student = f"{exercise}__{name}"
            (folder / student).mkdir(parents=True, exist_ok=True)
            (folder / student / f"{exercise}.ipynb").write_text(text)
            students[student] = (exercise, name)
    return students
