"""The corpus the grading benches grade, made from the course's own masters (never the tests' corpora).

For each exercise: the master, its released stub, and the master with one solution cell left undone
(released alone, so that only that cell is a stub): a correct notebook, one that fails every test
quickly, and the partial ones between. ``bench_cluster.py`` and ``bench_grading.py`` import it.
"""

import copy
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def cell_source(cell):
    """The text of a notebook cell, whether stored as one string or as lines."""
    return "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]


def variants(exercise):
    """name -> notebook: the master, the stub, and the master with each solution cell left undone."""
    from particles.course.release.answers import BEGIN, END
    from particles.course.release.notebooks import read_master, release_notebook

    master = read_master(ROOT / "solutions" / f"{exercise}.ipynb")
    found = {"master": master, "stub": release_notebook(master, exercise)}
    marked = [k for k, c in enumerate(master.cells) if c.cell_type == "code" and BEGIN in cell_source(c)]
    for k in marked:  # only cell k keeps its markers: released, it alone becomes a stub
        one = copy.deepcopy(master)
        for j in marked:
            if j != k:
                lines = cell_source(one.cells[j]).split("\n")
                one.cells[j].source = "\n".join(line for line in lines if line.strip() not in (BEGIN, END))
        found[f"undone{k}"] = release_notebook(one, exercise)
    return found


def write_corpus(folder, exercises, copies):
    """The corpus as ``folder/<student>/<exercise>.ipynb``; returns how many notebooks."""
    import nbformat

    count = 0
    for exercise in exercises:
        for name, notebook in variants(exercise).items():
            for k in range(copies):
                student = folder / f"{exercise}-{name}-{k}"
                student.mkdir(parents=True)
                nbformat.write(notebook, student / f"{exercise}.ipynb")
                count += 1
    return count
