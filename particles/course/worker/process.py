"""The worker process seen from the grader: start it, talk to it, kill it.

:class:`Worker` starts ``python -c BOOTSTRAP`` (see :mod:`particles.course.worker.main`)
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

from ..walls import isolation as walls
from .protocol import ProtocolError, read_frame, write_frame
from .main import BOOTSTRAP, UID_VARIABLE

__all__ = ["Worker", "WorkerDied", "WorkerTimeout", "library_parent"]


class WorkerTimeout(RuntimeError):
    """The worker did not answer in time and was killed."""


class WorkerDied(RuntimeError):
    """The worker process ended while the grader waited for an answer."""

    def __init__(self, returncode):
        self.returncode = returncode
        super().__init__(f"worker ended with exit status {returncode}")


_LIVE = set()  # pids of the workers this process has running (never taken for orphans)

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
    return str(Path(__file__).resolve().parents[3])


class Worker:
    """One worker process (see :mod:`particles.course.worker.main`).

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

    def __init__(self, scratch, config, python=None, start_timeout=30.0, isolation=None):
        self.scratch = Path(scratch)
        self.scratch.mkdir(parents=True, exist_ok=True)
        (self.scratch / ".matplotlib").mkdir(exist_ok=True)
        for font_list in _matplotlib_cache():
            shutil.copyfile(font_list, self.scratch / ".matplotlib" / font_list.name)
        self.plan = isolation if isolation is not None else walls.plan("auto")
        self.evaluate = None  # set by the caller: answers the worker's {"op": "evaluate"} frames
        self.lease = walls.UidLease() if self.plan.separate_uid else None
        self.layers = {}
        library = Path(library_parent()) / "particles"
        self.config = dict(config, scratch=str(self.scratch), namespaces=self.plan.namespaces,
                           landlock=self.plan.landlock, read=walls.read_paths(library),
                           uid=None if self.lease is None else self.lease.uid,
                           nproc=walls.NPROC if self.lease is not None else 1)
        if self.lease is not None:  # its folder is its own, and no one else's
            for path in [self.scratch, *self.scratch.rglob("*")]:
                os.chown(path, self.lease.uid, self.lease.uid)
            os.chmod(self.scratch, 0o700)
        env = {
            "PATH": os.environ.get("PATH", os.defpath), "HOME": str(self.scratch), "TMPDIR": str(self.scratch),
            "MPLCONFIGDIR": str(self.scratch / ".matplotlib"), "MPLBACKEND": "Agg", "LANG": "C.UTF-8",
            "PYTHONDONTWRITEBYTECODE": "1", "PYTHONPATH": library_parent(), "PYTHONNOUSERSITE": "1",
            "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
            "NUMBA_DISABLE_JIT": "1",  # the NumPy reference (particles.backends): no compiler, no cache
        }
        if self.lease is not None:
            env[UID_VARIABLE] = str(self.lease.uid)
        # without a PID namespace or a uid of its own, what the worker leaves behind is adopted by the grader
        self.reaps = not self.plan.namespaces and self.lease is None and walls.become_subreaper()
        command = [python or sys.executable, "-c", BOOTSTRAP, str(self.scratch / "stdout.txt")]
        if self.plan.namespaces:
            command = walls.bwrap_command(self.plan.bwrap, self.scratch, library, root=self.lease is not None
                                          or os.geteuid() == 0) + command
        try:
            self.process = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                            stderr=None if os.environ.get("PARTICLES_WORKER_STDERR") else subprocess.DEVNULL, cwd=self.scratch, env=env,
                                            start_new_session=True)
        except BaseException:
            self._release()
            raise
        _LIVE.add(self.process.pid)
        self._out = self.process.stdout.fileno()
        try:
            reply = self.request(self.config, start_timeout, send=True)
        except BaseException:
            self.kill()
            raise
        self.layers = dict(reply.get("layers") or {}) if isinstance(reply, dict) else {}

    @property
    def returncode(self):
        """The worker's exit status as Python reports it (-N: killed by signal N), also through bubblewrap.

        bubblewrap ends with status 128 + N when the process it runs is
        killed by signal N.
        """
        code = self.process.returncode
        if self.plan.namespaces and code is not None and 128 < code < 128 + 65:
            return -(code - 128)
        return code

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
            while True:
                reply = read_frame(lambda n: self._read_exactly(n, deadline))
                if not (isinstance(reply, dict) and reply.get("op") == "evaluate"):
                    return reply
                # the student's code calls a function the grader evaluates (and counts): answer, keep waiting
                answer = self.evaluate(reply) if self.evaluate is not None else {"ok": False, "error": "not expected"}
                write_frame(self.process.stdin.fileno(), answer, strict=False)
        except WorkerTimeout:
            self.kill()
            raise
        except (EOFError, BrokenPipeError):
            self.kill()
            raise WorkerDied(self.returncode) from None
        except ProtocolError:
            self.kill()
            raise

    def _release(self):
        if self.lease is not None:  # kills every process of its uid, wherever it went
            self.lease.release()
            self.lease = None

    def kill(self):
        """End the worker and everything it started.

        Its process group; with namespaces the whole sandbox (its PID
        namespace ends with its first process); with a uid of its own every
        process of that uid, also those that left the process group.
        """
        if self.process.poll() is None:
            try:
                os.killpg(self.process.pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                self.process.kill()
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            pass
        _LIVE.discard(self.process.pid)
        if self.reaps:
            walls.kill_orphans(keep=_LIVE)
        self._release()
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
