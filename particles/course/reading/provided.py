"""The code cells the course provides in an exercise, which a submission may keep unchanged.

The grader trusts those cells (they may use what the exercise forbids, and their errors are not the
student's) when a submission keeps them as they are; :func:`provided_cells` lists them from the
exercise's master, or from its released notebook when the master is not there.
"""

from pathlib import Path

from ..release.answers import BEGIN, STUB_LINE
from .submission import notebook_cells

__all__ = ["provided_cells"]


def provided_cells(root, exercise):
    """Sources of the code cells the course provides in `exercise`: those without a solution block.

    Read from the master ``solutions/NN_topic.ipynb`` when there is one (its
    instructor-only cells included: they are the course's too, when a master
    is checked), else from the released ``exercises/NN_topic.ipynb``
    (code cells without the release's stub line, :data:`~particles.course.release.answers.STUB_LINE`). The grader lets
    these cells, when a submission keeps them unchanged, use what the exercise
    forbids, and does not count their errors as the student's
    (:meth:`~particles.course.reading.submission.SubmissionCode.from_cells`).

    Read as JSON, like the submission
    (:func:`~particles.course.reading.submission.notebook_cells`): every grading
    session reads it for each notebook, and nbformat's import and schema check
    took 0.2 s of the session's 1 s start.

    Returns
    -------
    list of str
        Empty when neither notebook exists or can be read.
    """
    root = Path(root)
    master_path, released_path = root / "solutions" / f"{exercise}.ipynb", root / "exercises" / f"{exercise}.ipynb"
    try:
        if master_path.exists():
            return [source for _, source in notebook_cells(master_path) if BEGIN not in source]
        if released_path.exists():
            return [source for _, source in notebook_cells(released_path) if STUB_LINE not in source]
    except ValueError:
        return []
    return []
