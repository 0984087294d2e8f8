"""The kernel's calls behind the worker's walls: Landlock, prctl, uids, capabilities, orphans.

Small wrappers over Linux system calls (through :mod:`ctypes`), used by
:mod:`particles.course.walls.isolation` (the grader's side) and by the worker
before it runs any student code. Each returns whether it took effect, and
does nothing (returns False or 0) where the kernel lacks it.

References
----------
.. [1] Landlock: unprivileged access control, Linux kernel documentation,
   ``Documentation/userspace-api/landlock.rst``.
.. [2] prctl(2), capabilities(7), setresuid(2), Linux man-pages.
"""

import os
import signal
import sys
from pathlib import Path

__all__ = ["protect_this_process", "no_new_privs", "landlock_abi", "apply_landlock", "drop_privileges",
           "drop_capabilities", "become_subreaper", "kill_orphans", "die_with_parent",
           "PARENT_VARIABLE"]

_PR_SET_DUMPABLE, _PR_SET_NO_NEW_PRIVS = 4, 38
_SYS_CREATE_RULESET, _SYS_ADD_RULE, _SYS_RESTRICT_SELF = 444, 445, 446  # the same on every architecture
_FS = {"execute": 1 << 0, "write_file": 1 << 1, "read_file": 1 << 2, "read_dir": 1 << 3,
       "remove_dir": 1 << 4, "remove_file": 1 << 5, "make_char": 1 << 6, "make_dir": 1 << 7,
       "make_reg": 1 << 8, "make_sock": 1 << 9, "make_fifo": 1 << 10, "make_block": 1 << 11,
       "make_sym": 1 << 12, "refer": 1 << 13, "truncate": 1 << 14, "ioctl_dev": 1 << 15}
_FS_BY_ABI = {1: (1 << 13) - 1, 2: (1 << 14) - 1, 3: (1 << 15) - 1, 4: (1 << 15) - 1, 5: (1 << 16) - 1}
_FILE_RIGHTS = _FS["execute"] | _FS["write_file"] | _FS["read_file"] | _FS["truncate"] | _FS["ioctl_dev"]


def _libc():
    import ctypes

    return ctypes, ctypes.CDLL(None, use_errno=True)


def _prctl(option, value):
    if not sys.platform.startswith("linux"):
        return False
    try:
        ctypes, libc = _libc()
        return libc.prctl(option, ctypes.c_ulong(value), ctypes.c_ulong(0), ctypes.c_ulong(0),
                          ctypes.c_ulong(0)) == 0
    except (OSError, AttributeError):
        return False


def protect_this_process():
    """Turn off ``PR_SET_DUMPABLE`` for the grader's own process: no ptrace, no ``/proc/PID/mem``, no environ.

    Returns True when the kernel accepted it (Linux).
    """
    return _prctl(_PR_SET_DUMPABLE, 0)


def no_new_privs():
    """``PR_SET_NO_NEW_PRIVS`` for this process and its children; True when set."""
    return _prctl(_PR_SET_NO_NEW_PRIVS, 1)


def landlock_abi():
    """The kernel's Landlock ABI version (0: not available)."""
    if not sys.platform.startswith("linux"):
        return 0
    try:
        ctypes, libc = _libc()
        abi = libc.syscall(ctypes.c_long(_SYS_CREATE_RULESET), None, ctypes.c_size_t(0), ctypes.c_uint32(1))
        return max(int(abi), 0)
    except (OSError, AttributeError):
        return 0


def apply_landlock(read, write):
    """Restrict this process (and its children) with Landlock: read `read`, read and write `write`.

    Parameters
    ----------
    read : sequence of path
        Files and folders (with everything under them) that may be read and
        executed.
    write : sequence of path
        Folders that may also be written (files made, removed, truncated).

    Returns
    -------
    int
        The ABI that was applied (0: Landlock is not available and nothing
        was restricted). With ABI 4+ TCP ``bind``/``connect`` is denied, with
        ABI 6+ signals to processes outside the domain and abstract Unix
        sockets are too.

    Notes
    -----
    Needs ``PR_SET_NO_NEW_PRIVS`` (set here) unless the process has
    ``CAP_SYS_ADMIN``. A path that does not exist is skipped.
    """
    abi = landlock_abi()
    if abi < 1:
        return 0
    ctypes, libc = _libc()
    handled_fs = _FS_BY_ABI.get(abi, (1 << 16) - 1)

    class RulesetAttr(ctypes.Structure):
        _fields_ = [("fs", ctypes.c_uint64), ("net", ctypes.c_uint64), ("scoped", ctypes.c_uint64)]

    class PathBeneath(ctypes.Structure):
        _pack_ = 1
        _fields_ = [("allowed", ctypes.c_uint64), ("parent_fd", ctypes.c_int32)]

    attr = RulesetAttr(handled_fs, 3 if abi >= 4 else 0, 3 if abi >= 6 else 0)
    size = 8 if abi < 4 else (16 if abi < 6 else 24)
    ruleset = libc.syscall(ctypes.c_long(_SYS_CREATE_RULESET), ctypes.byref(attr), ctypes.c_size_t(size),
                           ctypes.c_uint32(0))
    if ruleset < 0:
        return 0
    try:
        read_rights = _FS["execute"] | _FS["read_file"] | _FS["read_dir"]
        rules = [(p, read_rights) for p in read] + [(p, handled_fs) for p in write]
        for path, rights in rules:
            try:
                fd = os.open(path, os.O_PATH | os.O_CLOEXEC)
            except OSError:
                continue
            try:
                if not os.path.isdir(path):
                    rights &= _FILE_RIGHTS
                rule = PathBeneath(rights & handled_fs, fd)
                if libc.syscall(ctypes.c_long(_SYS_ADD_RULE), ctypes.c_int(ruleset), ctypes.c_int(1),
                                ctypes.byref(rule), ctypes.c_uint32(0)) != 0:
                    raise OSError(ctypes.get_errno(), f"landlock_add_rule failed for {path}")
            finally:
                os.close(fd)
        no_new_privs()
        if libc.syscall(ctypes.c_long(_SYS_RESTRICT_SELF), ctypes.c_int(ruleset), ctypes.c_uint32(0)) != 0:
            raise OSError(ctypes.get_errno(), "landlock_restrict_self failed")
    finally:
        os.close(ruleset)
    return abi


def drop_privileges(uid):
    """Become `uid` (and a group of the same number), with no supplementary groups; True when done.

    Only a process running as root can; the change is for good (real, effective
    and saved ids), and every capability goes with it.
    """
    if uid is None or not hasattr(os, "setresuid") or os.geteuid() != 0:
        return False
    os.setgroups([])
    os.setresgid(uid, uid, uid)
    os.setresuid(uid, uid, uid)
    return os.getuid() == uid and os.geteuid() == uid


def drop_capabilities():
    """Give up every capability for good (bounding set emptied, then capset to zero); True when done.

    For a worker that must keep uid 0 (the grader is root and no other uid can
    run Python here): without capabilities root is an ordinary uid that owns
    some files, and Landlock decides which of them it may open.
    """
    if not sys.platform.startswith("linux"):
        return False
    try:
        ctypes, libc = _libc()
        for cap in range(64):  # the bounding set, one capability at a time (PR_CAPBSET_DROP)
            libc.prctl(24, ctypes.c_ulong(cap), ctypes.c_ulong(0), ctypes.c_ulong(0), ctypes.c_ulong(0))

        class Header(ctypes.Structure):
            _fields_ = [("version", ctypes.c_uint32), ("pid", ctypes.c_int)]

        class Data(ctypes.Structure):
            _fields_ = [("effective", ctypes.c_uint32), ("permitted", ctypes.c_uint32),
                        ("inheritable", ctypes.c_uint32)]

        header, data = Header(0x20080522, 0), (Data * 2)()  # _LINUX_CAPABILITY_VERSION_3
        if libc.capset(ctypes.byref(header), data) != 0:
            return False
        with open("/proc/self/status") as status:
            effective = [line.split()[1] for line in status if line.startswith("CapEff:")]
        return bool(effective) and int(effective[0], 16) == 0
    except (OSError, AttributeError, ValueError):
        return False


_PR_SET_CHILD_SUBREAPER = 36
_PR_SET_PDEATHSIG = 1

PARENT_VARIABLE = "PARTICLES_GRADER_PARENT"
"""Environment variable of a grading session naming the pid of the process that started it
(:func:`die_with_parent`)."""


def die_with_parent(parent):
    """Have the kernel kill this process (SIGKILL) when its parent ends (Linux); True when set.

    A grading session dies with the process that started it (the driver, or a cluster's worker killed
    mid-batch), and a worker with its session: no orphan keeps grading. The kernel clears the setting when
    the process changes its uid, so a worker sets it after that.

    Parameters
    ----------
    parent : int
        The pid the caller knows as its parent: when this process already has another one (the parent
        ended before the call), it ends now.
    """
    if not _prctl(_PR_SET_PDEATHSIG, signal.SIGKILL):
        return False
    if os.getppid() != parent:
        os.kill(os.getpid(), signal.SIGKILL)
    return True


def become_subreaper():
    """Make this process the reaper of its orphaned descendants (Linux); True when set.

    Without namespaces or a uid of its own, a worker's process that left its
    session (``setsid``) would be adopted by init and outlive the worker; with
    this, it is adopted by the grader, which kills it (:func:`kill_orphans`).
    """
    return _prctl(_PR_SET_CHILD_SUBREAPER, 1)


def kill_orphans(keep=()):
    """SIGKILL (and reap) this process's children that are outside its session, except the pids in `keep`.

    Such children are what workers left behind and this process adopted as
    their subreaper: the grader starts its own helpers in its own session,
    and its workers (whose pids are in `keep`) in sessions of their own.

    Returns
    -------
    list of int
        The pids killed.
    """
    if not sys.platform.startswith("linux"):
        return []
    mine, killed = os.getsid(0), []
    for _ in range(3):  # an orphan of an orphan is adopted only once its parent is dead
        children = set()
        for task in Path(f"/proc/{os.getpid()}/task").glob("*/children"):
            try:
                children.update(int(p) for p in task.read_text().split())
            except (OSError, ValueError):
                pass
        found = []
        for pid in sorted(children - set(keep) - set(killed)):
            try:
                if os.getsid(pid) != mine:
                    os.kill(pid, signal.SIGKILL)
                    found.append(pid)
            except OSError:
                pass
        for pid in found:
            try:
                os.waitpid(pid, 0)
            except ChildProcessError:
                pass
        killed += found
        if not found:
            break
    return killed
