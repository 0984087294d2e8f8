"""What the grader decides on its corpora, written down to compare two versions of the grader.

A change to how grading runs (its stages, its record, where batches run) must not change what it
decides. This script grades, through the command line and with fixed seeds:

* the hostile corpus of exercise 00 (``corpus.py``),
* the exercise corpora (``cases_NN_topic.py``),
* the scripted term of ``tests/course/test_term.py`` (deadline, times file, extension, malformed and
  doubled notebooks), then the same term with ``--resume`` and with ``--student``,

and writes one JSON file of everything a student or an instructor reads: each command's exit status
and output, the gradebook, every record (score, per-test verdict and message, notes, late decision)
and every feedback file, with what differs from run to run (timings, temporary paths, sandbox
descriptions, signatures) taken out. Two such files are then compared::

    python -m tests.course.grader.snapshot before.json            # on the old commit
    python -m tests.course.grader.snapshot after.json             # on the new one
    python -m tests.course.grader.snapshot --compare before.json after.json

The comparison prints every difference and exits 1 when there is one.
"""

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
HERE = Path(__file__).resolve().parent

# fields of a record that differ between two runs of the same grading
_VOLATILE = {"seconds", "sandbox", "isolation", "notebook", "worker", "graded_at", "run", "resumed"}
_TIMING = re.compile(r"\(\d+(\.\d+)? s\)|\d+(\.\d+)? s\b|in \d+(\.\d+)?s")
# in any text: the uid a worker ran as (drawn per run), the library's digest (changes with any commit), where
# an endless loop happened to be when it was stopped, and a clock's time (a file's modification time: the
# instructor's times are whole seconds)
_IDS = [(re.compile(r"\buid\b(\W{1,3})\d+"), r"uid\g<1>0"), (re.compile(r"library=[\w.+-]+"), "library=V"),
        (re.compile(r"(did not finish within T s) at code cell \d+, line \d+, in \w+"), r"\1 at PLACE"),
        (re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d+[+-]\d\d:\d\d"), "CLOCK")]


def _clean(text, tmp):
    text = text.replace(str(tmp), "TMP").replace(str(ROOT), "ROOT")
    return _TIMING.sub("T s", text)


def _ids(text):
    for pattern, replacement in _IDS:
        text = pattern.sub(replacement, text)
    return text


def _record(path, tmp):
    data = json.loads(path.read_text())
    for name in _VOLATILE:
        data.pop(name, None)
    for test in data.get("tests", []):
        test.pop("seconds", None)
    return json.loads(_clean(json.dumps(data, sort_keys=True), tmp))


def _records(out, tmp):
    """The current records of the course record of `out`, as ``records/<student>__<exercise>.json`` entries (the
    layout of the grader before the course record, so that the two can be compared)."""
    from particles.course.term.database import DATABASE, TermRecord

    if not (Path(out) / DATABASE).exists():
        return {}
    with TermRecord(out) as term:
        current = term.current()
    found = {}
    for (student, exercise), record in current.items():
        data = record.to_dict()
        data.pop("options", None)
        for name in _VOLATILE:
            data.pop(name, None)
        for test in data.get("tests", []):
            test.pop("seconds", None)
        found[f"records/{student}__{exercise}.json"] = json.loads(_clean(json.dumps(data, sort_keys=True), tmp))
    return found


def _outputs(out, tmp):
    """Everything a grading run wrote in `out` that a student or an instructor reads."""
    found = _records(out, tmp)
    for path in sorted(Path(out).rglob("*")):
        name = str(path.relative_to(out))
        if not path.is_file() or name.startswith(("logs/", "course.sqlite")) or name.endswith((".html", ".png")):
            continue  # logs hold timings; the HTML feedback is the Markdown one drawn (its figures' bytes vary)
        if name.startswith("records/"):
            found[name] = _record(path, tmp)
            found[name].pop("options", None)
        elif name.endswith("results.json"):
            data = json.loads(path.read_text())
            data.pop("execution_time", None)
            found[name] = json.loads(_clean(json.dumps(data, sort_keys=True), tmp))
        else:
            found[name] = _clean(path.read_text(errors="replace"), tmp)
    return found


def _grade(args, out, tmp):
    command = [sys.executable, "-m", "particles", "grade", *map(str, args), "--root", str(ROOT)]
    done = subprocess.run(command, capture_output=True, text=True, cwd=tmp)
    lines = sorted(_clean(line, tmp) for line in (done.stdout + done.stderr).splitlines() if line.strip())
    return {"status": done.returncode, "output": lines, "files": _outputs(out, tmp) if out else {}}


def _term(tmp):
    sys.path.insert(0, str(ROOT))
    from tests.course import test_term

    subs = test_term._hand_in(tmp)
    out = tmp / "term-out"
    common = ["--exercise", test_term.EXERCISE, "--course", tmp / "course.toml", "--times", tmp / "times.csv",
              "--seed", "7", "--jobs", "2", "--out", out]
    first = _grade([subs, *common], out, tmp)
    resumed = _grade([subs, *common, "--resume"], out, tmp)
    (subs / "dee" / f"{test_term.EXERCISE}.ipynb").write_text(json.dumps(test_term._notebooks()[0]))
    regraded = _grade([subs, *common, "--student", "dee"], out, tmp)
    return {"term": first, "term --resume": resumed, "term --student": regraded}


def snapshot(jobs=2):
    """Grade the corpora and the term; returns the snapshot (a JSON-able dict)."""
    sys.path.insert(0, str(HERE))
    import corpus
    import exercise_corpus

    with tempfile.TemporaryDirectory(prefix="particles-snapshot-") as name:
        tmp = Path(name).resolve()
        corpus.write_corpus(tmp / "hostile")
        exercise_corpus.write_corpora(tmp / "exercises")
        runs = {
            "hostile": _grade([tmp / "hostile", "--out", tmp / "hostile-out", "--jobs", jobs, "--seed", 20240611,
                               "--time-limit", 2.0], tmp / "hostile-out", tmp),
            "exercises": _grade([tmp / "exercises", "--out", tmp / "exercises-out", "--jobs", jobs, "--seed",
                                 20261201, "--time-limit", 10.0], tmp / "exercises-out", tmp),
        }
        runs.update(_term(tmp))
    return runs


def differences(before, after, where=""):
    """Every place where two snapshots differ, one line each."""
    if isinstance(before, dict) and isinstance(after, dict):
        lines = []
        for key in sorted(set(before) | set(after)):
            if key not in after:
                lines.append(f"{where}/{key}: only before")
            elif key not in before:
                lines.append(f"{where}/{key}: only after")
            else:
                lines += differences(before[key], after[key], f"{where}/{key}")
        return lines
    if isinstance(before, list) and isinstance(after, list) and len(before) == len(after):
        return [line for k, (a, b) in enumerate(zip(before, after)) for line in differences(a, b, f"{where}[{k}]")]
    return [] if before == after else [f"{where}: {before!r:.300} != {after!r:.300}"]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("files", nargs="+", metavar="FILE")
    parser.add_argument("--compare", action="store_true", help="compare two snapshot files")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args(argv)
    if args.compare:
        before, after = (json.loads(_ids(Path(f).read_text())) for f in args.files)
        lines = differences(before, after)
        for line in lines:
            print(line)
        counted = sum(len(run["files"]) for run in after.values())
        print(f"{len(lines)} difference(s) in {len(after)} runs, {counted} files compared")
        return 1 if lines else 0
    os.environ.setdefault("PYTHONHASHSEED", "0")
    Path(args.files[0]).write_text(json.dumps(snapshot(args.jobs), indent=1, sort_keys=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
