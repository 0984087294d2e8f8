"""Is the installed library the one the run started with? A checksum before, a comparison after.

A submission that got out of its worker could change a library module or
plant a ``.pyc`` in its ``__pycache__`` so that a later session (another
student's) or the next grading run imports it. The driver takes
:func:`library_checksum` before its first worker and compares it with
:func:`library_changes` at the end; a difference fails the run loudly.
"""

import errno
import hashlib
import os
from pathlib import Path

__all__ = ["library_checksum", "library_changes"]


def library_checksum(package=None):
    """SHA-256 of every file of the installed ``particles`` package (sources, data and bytecode).

    Taken by the driver at the start of a grading run and compared at its end
    with :func:`library_changes`: a submission that changed a module or
    planted a ``.pyc`` would show there.

    Parameters
    ----------
    package : path, optional
        The package folder (default: the one this module belongs to).

    Returns
    -------
    dict
        Path relative to `package` -> hex digest of its contents.
    """
    package = Path(package) if package is not None else Path(__file__).resolve().parents[2]
    files = {}
    for path in sorted(package.rglob("*")):
        if path.is_file() or path.is_symlink():
            try:
                data = os.readlink(path).encode() if path.is_symlink() else path.read_bytes()
            except OSError as error:
                data = f"<unreadable: {errno.errorcode.get(error.errno, error.errno)}>".encode()
            files[str(path.relative_to(package))] = hashlib.sha256(data).hexdigest()
    return files


def _honest_bytecode(pyc):
    """Whether `pyc` is exactly what compiling its source gives (a cache Python itself wrote)."""
    import importlib.util
    import marshal

    pyc = Path(pyc)
    name = pyc.name.split(".")[0] + ".py"
    source = pyc.parent.parent / name
    try:
        data, text, stat = pyc.read_bytes(), source.read_bytes(), source.stat()
    except OSError:
        return False
    if len(data) < 16 or data[:4] != importlib.util.MAGIC_NUMBER:
        return False
    flags = int.from_bytes(data[4:8], "little")
    if flags == 0:  # timestamp pyc: Python loads it only if the source's mtime and size match
        if (int.from_bytes(data[8:12], "little") != (int(stat.st_mtime) & 0xFFFFFFFF)
                or int.from_bytes(data[12:16], "little") != (stat.st_size & 0xFFFFFFFF)):
            return True  # stale: Python ignores it and compiles the source
    try:
        return marshal.loads(data[16:]) == compile(text, str(source), "exec", dont_inherit=True)
    except Exception:
        return False


def library_changes(before, package=None):
    """Files of the package that changed since `before` (a :func:`library_checksum`), worst first.

    A bytecode file that Python rewrote from an unchanged source (a module
    imported for the first time) is not a change; any other new, missing or
    different file is.

    Returns
    -------
    list of str
        Relative paths, empty when the library is as it was.
    """
    package = Path(package) if package is not None else Path(__file__).resolve().parents[2]
    after = library_checksum(package)
    changed = []
    for name in sorted(set(before) | set(after)):
        if before.get(name) == after.get(name):
            continue
        if name.endswith(".pyc") and name in after and "__pycache__" in Path(name).parts:
            source = str(Path(name).parent.parent / (Path(name).name.split(".")[0] + ".py"))
            if before.get(source) == after.get(source) and _honest_bytecode(package / name):
                continue
        changed.append(name)
    return sorted(changed, key=lambda n: (n.endswith(".pyc"), n))
