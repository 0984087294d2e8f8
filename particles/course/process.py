"""The worker process seen from the grader: start it, talk to it, kill it.

:class:`Worker` starts ``python -c BOOTSTRAP`` (see :mod:`particles.course.worker`)
in a new session (so that killing its process group also ends anything it
started), with a clean environment: its scratch folder as home and temporary
folder, one BLAS thread, Matplotlib's Agg backend, and ``PYTHONPATH`` set to
the library the grader itself uses. Every request waits for its reply with a
deadline; a worker that misses it is killed.
"""

import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from .protocol import ProtocolError, read_frame, write_frame
from .worker import BOOTSTRAP

__all__ = ["Worker", "WorkerDied", "WorkerTimeout", "library_parent"]


class WorkerTimeout(RuntimeError):
    """The worker did not answer in time and was killed."""


class WorkerDied(RuntimeError):
    """The worker process ended while the grader waited for an answer."""

    def __init__(self, returncode):
        self.returncode = returncode
        super().__init__(f"worker ended with exit status {returncode}")


_MPL_CACHE = None


def _matplotlib_cache():
    """A grader-owned folder with Matplotlib's font list, built once by a trusted process.

    Without it every worker would rebuild the font cache in its fresh scratch
    folder, which takes seconds. Workers get a copy, never the folder itself,
    so one submission cannot tamper with another's.
    """
    global _MPL_CACHE
    if _MPL_CACHE is None:
        folder = Path(tempfile.gettempdir()) / f"particles-grader-mplcache-{os.getuid()}"
        if not list(folder.glob("fontlist*.json")):
            folder.mkdir(parents=True, exist_ok=True)
            env = dict(os.environ, MPLCONFIGDIR=str(folder), MPLBACKEND="Agg")
            try:
                subprocess.run([sys.executable, "-c", "import matplotlib.font_manager"], env=env,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=120)
            except (OSError, subprocess.TimeoutExpired):
                pass
        _MPL_CACHE = sorted(folder.glob("fontlist*.json"))
    return _MPL_CACHE


def library_parent():
    """The folder holding the ``particles`` package that the grader itself uses."""
    return str(Path(__file__).resolve().parents[2])


class Worker:
    """One worker process (see :mod:`particles.course.worker`).

    Parameters
    ----------
    scratch : path
        Its working directory, the only place it may write.
    config : dict
        Sent as the first frame: limits, private paths (``deny``) and
        forbidden names (``forbidden``: dotted name -> reason).
    python : str
        The Python interpreter (default: the grader's).
    """

    def __init__(self, scratch, config, python=None, start_timeout=30.0):
        self.scratch = Path(scratch)
        self.scratch.mkdir(parents=True, exist_ok=True)
        (self.scratch / ".matplotlib").mkdir(exist_ok=True)
        for font_list in _matplotlib_cache():
            shutil.copyfile(font_list, self.scratch / ".matplotlib" / font_list.name)
        self.config = dict(config, scratch=str(self.scratch))
        env = {
            "PATH": os.environ.get("PATH", os.defpath), "HOME": str(self.scratch), "TMPDIR": str(self.scratch),
            "MPLCONFIGDIR": str(self.scratch / ".matplotlib"), "MPLBACKEND": "Agg", "LANG": "C.UTF-8",
            "PYTHONDONTWRITEBYTECODE": "1", "PYTHONPATH": library_parent(), "PYTHONNOUSERSITE": "1",
            "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
        }
        self.process = subprocess.Popen(
            [python or sys.executable, "-c", BOOTSTRAP, str(self.scratch / "stdout.txt")],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
            cwd=self.scratch, env=env, start_new_session=True,
        )
        self._out = self.process.stdout.fileno()
        try:
            self.request(self.config, start_timeout, send=True)
        except BaseException:
            self.kill()
            raise

    @property
    def alive(self):
        return self.process.poll() is None

    def _read_exactly(self, n, deadline):
        chunks, remaining = [], n
        while remaining:
            left = deadline - time.monotonic()
            if left <= 0:
                raise WorkerTimeout
            ready, _, _ = select.select([self._out], [], [], left)
            if not ready:
                raise WorkerTimeout
            chunk = os.read(self._out, min(remaining, 1 << 20))
            if not chunk:
                raise EOFError
            chunks.append(chunk)
            remaining -= len(chunk)
        return b"".join(chunks)

    def request(self, message, timeout, send=True):
        """Send `message` and wait at most `timeout` seconds for the reply.

        Raises
        ------
        WorkerTimeout
            No complete reply in time; the worker has been killed.
        WorkerDied
            The worker ended; its exit status is attached.
        ProtocolError
            The reply was malformed or too large; the worker has been killed.
        """
        deadline = time.monotonic() + timeout
        try:
            if send:
                write_frame(self.process.stdin.fileno(), message)
            return read_frame(lambda n: self._read_exactly(n, deadline))
        except WorkerTimeout:
            self.kill()
            raise
        except (EOFError, BrokenPipeError):
            self.kill()
            raise WorkerDied(self.process.returncode) from None
        except ProtocolError:
            self.kill()
            raise

    def kill(self):
        """End the worker and everything it started (its process group)."""
        if self.process.poll() is None:
            try:
                os.killpg(self.process.pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                self.process.kill()
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            pass
        for stream in (self.process.stdin, self.process.stdout):
            try:
                stream.close()
            except OSError:
                pass

    def close(self):
        """Ask the worker to exit, and make sure it does."""
        if self.alive:
            try:
                write_frame(self.process.stdin.fileno(), {"op": "exit"})
                self.process.wait(timeout=2)
            except (OSError, subprocess.TimeoutExpired):
                pass
        self.kill()
