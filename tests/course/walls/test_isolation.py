"""The operating system's walls around a worker hold on their own: hostile code with the audit hook off.

Each attack is a function of a hostile submission that tries one route out of
the worker and returns what it got; the worker runs it with its audit hook
switched off (``audit_hook=False``), so only the operating system's layers
(namespaces, a uid of its own, Landlock, limits; see
:mod:`particles.course.walls.isolation`) stand in the way. Each plan below is one
layer (or one combination) alone; every route must fail under each.
"""

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from particles.course.walls import isolation
from particles.course.reading.submission import SubmissionCode
from particles.course.worker.runner import Submission

ROOT = Path(__file__).resolve().parents[3]
MASTER = ROOT / "solutions" / "00_warmup.ipynb"
LIBRARY = ROOT / "particles"
FOUND = isolation.probe()

PLANS = {
    "namespaces alone": ("namespaces,no-uid,no-landlock", FOUND["namespaces"], "bubblewrap cannot run here"),
    "landlock alone": ("no-namespaces,no-uid,landlock", FOUND["landlock"] >= 1, "the kernel has no Landlock"),
    "all layers": ("namespaces,uid,landlock", FOUND["namespaces"] and FOUND["root"], "needs namespaces and root"),
}

ATTACKS = r'''
import os, sys, glob, signal, socket, subprocess

def read_file(path):
    """Read a file by its path."""
    try:
        with open(path, "rb") as handle:
            return handle.read(200)
    except Exception as error:
        return repr(error)

def read_with_dir_fd(path):
    """Open '/' and read `path` relative to it (the route the audit hook resolved wrongly)."""
    out = []
    for flags in (os.O_RDONLY, os.O_PATH):
        try:
            fd = os.open("/", flags)
            handle = os.open(path.lstrip("/"), os.O_RDONLY, dir_fd=fd)
            out.append(os.read(handle, 200))
        except Exception as error:
            out.append(repr(error))
    return out

def run_program(path):
    """Start /bin/cat and a second Python (no audit hook there either) on `path`."""
    out = []
    for command in (["/bin/cat", path], [sys.executable, "-c", f"print(open({path!r}).read(200))"]):
        try:
            out.append(subprocess.run(command, capture_output=True, timeout=10).stdout)
        except Exception as error:
            out.append(repr(error))
    try:
        import _posixsubprocess
        out.append("fork_exec " + str(_posixsubprocess.__name__))
    except Exception as error:
        out.append(repr(error))
    return out

def list_folder(path):
    """List a folder."""
    try:
        return sorted(os.listdir(path))
    except Exception as error:
        return repr(error)

def read_process(pid):
    """Read another process's environment and memory maps."""
    out = []
    for name in ("environ", "maps", "cmdline"):
        try:
            with open(f"/proc/{pid}/{name}", "rb") as handle:
                out.append(handle.read(4000))
        except Exception as error:
            out.append(repr(error))
    return out

def scan_environments(marker):
    """Look for `marker` in the environment of every process it can see."""
    found = []
    for path in glob.glob("/proc/[0-9]*/environ"):
        try:
            with open(path, "rb") as handle:
                if marker.encode() in handle.read():
                    found.append(path)
        except Exception:
            pass
    return found

def write_file(path, text):
    """Append `text` to a file (a library module, a planted .pyc, the grader's records)."""
    try:
        with open(path, "a") as handle:
            handle.write(text)
        return "written"
    except Exception as error:
        return repr(error)

def kill(pid):
    """Send SIGKILL to `pid`."""
    try:
        os.kill(pid, signal.SIGKILL)
        return "sent"
    except Exception as error:
        return repr(error)

def kill_everything():
    """kill(-1): every process it may signal."""
    try:
        os.kill(-1, signal.SIGKILL)
        return "sent"
    except Exception as error:
        return repr(error)

def connect(port):
    """Open a TCP connection to the grader's machine."""
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=2) as conn:
            return conn.recv(100)
    except Exception as error:
        return repr(error)

def who():
    """Its uid and effective capabilities."""
    with open("/proc/self/status") as status:
        caps = [line.split()[1] for line in status if line.startswith("CapEff:")]
    return [os.getuid(), int(caps[0], 16) if caps else -1]

def raise_limits():
    """Raise its own memory limit again."""
    import resource
    try:
        resource.setrlimit(resource.RLIMIT_AS, (resource.RLIM_INFINITY, resource.RLIM_INFINITY))
        return "raised"
    except Exception as error:
        return repr(error)

def leave_a_process(marker):
    """Start a detached process that should outlive the worker."""
    try:
        subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)", marker], start_new_session=True,
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        return "started"
    except Exception as error:
        return repr(error)
'''


def _plan(option):
    return isolation.Plan.from_option(option)


@pytest.fixture(scope="module", params=sorted(PLANS))
def hostile(request, tmp_path_factory):
    """One worker per plan, running the attacks with its audit hook off."""
    option, available, why = PLANS[request.param]
    if not available:
        pytest.skip(why)
    code = SubmissionCode.from_cells([("code cell 1", ATTACKS)])
    scratch = tmp_path_factory.mktemp("hostile")
    with Submission(code, isolation=_plan(option), audit_hook=False, scratch=scratch, time_limit=20) as sub:
        sub.name = request.param
        yield sub


@pytest.fixture(scope="module")
def secrets_on_disk(tmp_path_factory):
    """A private folder like the driver's (batch file, records) and a world-readable course-like file."""
    private = tmp_path_factory.mktemp("grader-private")
    os.chmod(private, 0o700)
    (private / "batch.json").write_text('{"seed": "SECRET-SEED-1234"}')
    public = tmp_path_factory.mktemp("course")
    os.chmod(public, 0o755)
    (public / "master.ipynb").write_text("SECRET-MASTER-5678")
    os.chmod(public / "master.ipynb", 0o644)
    return {"private": private / "batch.json", "public": public / "master.ipynb"}


def _text(value):
    return repr(value)


def test_worker_reports_its_layers(hostile):
    """The worker says which walls it had, and the audit hook was really off."""
    layers = hostile.layers if hostile.layers else (hostile.call("who") and hostile.layers)
    assert layers["audit_hook"] is False
    option = PLANS[hostile.name][0]
    assert layers["namespaces"] is ("no-namespaces" not in option)
    if "no-landlock" not in option:
        assert layers["landlock"] >= 1


def test_cannot_read_course_files(hostile, secrets_on_disk):
    """Neither the master notebook nor a world-readable file outside the allow-list can be read."""
    for path in (MASTER, secrets_on_disk["public"]):
        got = _text(hostile.call("read_file", str(path)))
        assert "cells" not in got and "SECRET" not in got, got


def test_cannot_read_private_files(hostile, secrets_on_disk):
    """The driver's private batch file (every hidden seed) cannot be read, by path or with a dir_fd of /."""
    got = _text(hostile.call("read_file", str(secrets_on_disk["private"])))
    assert "SECRET" not in got, got
    got = _text(hostile.call("read_with_dir_fd", str(MASTER))) + _text(
        hostile.call("read_with_dir_fd", str(secrets_on_disk["private"])))
    assert "cells" not in got and "SECRET" not in got, got


def test_programs_it_starts_are_walled_in_too(hostile, secrets_on_disk):
    """/bin/cat and a second Python started by the submission read nothing either."""
    for path in (MASTER, secrets_on_disk["private"]):
        got = _text(hostile.call("run_program", str(path)))
        assert "cells" not in got and "SECRET" not in got, got


def test_cannot_list_the_course_or_the_batch(hostile, secrets_on_disk):
    """The course folder and the driver's private folder cannot be listed."""
    for folder in (ROOT, secrets_on_disk["private"].parent):
        got = hostile.call("list_folder", str(folder))
        assert not isinstance(got, list) or not ({"solutions", "tests", "batch.json"} & set(got)), got


def test_cannot_read_the_grader_process(hostile, monkeypatch):
    """The grading process's environment and memory maps are out of reach, and no process shows its marker."""
    monkeypatch.setenv("PARTICLES_TEST_MARKER", "MARKER-9876")  # only in os.environ: look for it in /proc
    got = hostile.call("read_process", os.getpid())
    assert all(not isinstance(part, bytes) for part in got), got
    assert hostile.call("scan_environments", "PARTICLES_TEST_MARKER") == []


def test_library_cannot_be_changed(hostile):
    """A library module cannot be appended to, nor a .pyc planted in its __pycache__; the checksum agrees."""
    before = isolation.library_checksum()
    assert "written" not in _text(hostile.call("write_file", str(LIBRARY / "course" / "expect.py"), "\n# pwned\n"))
    pyc = LIBRARY / "course" / "__pycache__" / "expect.cpython-311.pyc"
    assert "written" not in _text(hostile.call("write_file", str(pyc), "pwned"))
    assert isolation.library_changes(before) == []


def test_cannot_write_outside_its_folder(hostile, secrets_on_disk, tmp_path):
    """The grader's records and any folder but its own scratch are read-only to it."""
    assert "written" not in _text(hostile.call("write_file", str(secrets_on_disk["private"]), "forged"))
    target = tmp_path / "results.json"
    os.chmod(tmp_path, 0o777)
    assert "written" not in _text(hostile.call("write_file", str(target), "forged"))
    assert not target.exists()


def test_cannot_signal_the_grader(hostile):
    """SIGKILL to a process of the grader's (a child it started) is refused or cannot reach it."""
    victim = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        if hostile.name == "landlock alone" and FOUND["landlock"] < 6:
            pytest.skip("Landlock scopes signals from ABI 6 on")
        hostile.call("kill", victim.pid)
        time.sleep(0.2)
        assert victim.poll() is None, "the grader's process was killed"
    finally:
        victim.kill()
        victim.wait()


def test_kill_everything_stays_inside(hostile):
    """kill(-1) from the worker kills nothing outside it (run where the uid or the PID namespace contain it)."""
    if hostile.name == "landlock alone":
        pytest.skip("as root without namespaces, only Landlock's signal scope would hold: not risked here")
    victim = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        try:
            hostile.call("kill_everything")
        except AssertionError:
            pass  # the worker may have killed itself
        time.sleep(0.2)
        assert victim.poll() is None
    finally:
        victim.kill()
        victim.wait()


def test_no_network(hostile):
    """A TCP server of the grader's machine cannot be reached."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(1)
    port = server.getsockname()[1]
    try:
        got = hostile.call("connect", port)
        assert not isinstance(got, bytes), got
    finally:
        server.close()


def test_not_root_and_no_way_back(hostile):
    """The worker has no capabilities (a uid of its own where possible) and cannot raise its limits."""
    uid, caps = hostile.call("who")
    assert caps == 0
    if hostile.layers.get("uid"):
        assert uid == hostile.layers["uid"] != 0
    assert "raised" not in _text(hostile.call("raise_limits"))


def test_no_process_outlives_the_worker(hostile):
    """A detached process started by the submission is gone once its worker is killed."""
    marker = f"particles-leftover-{os.getpid()}-{hostile.name.replace(' ', '-')}"
    hostile.call("leave_a_process", marker)
    hostile.worker.kill()
    time.sleep(0.3)
    left = []
    for path in Path("/proc").glob("[0-9]*/cmdline"):
        try:
            if marker.encode() in path.read_bytes():
                left.append(path)
        except OSError:
            pass
    for path in left:  # do not leave them to the rest of the suite
        try:
            os.kill(int(path.parent.name), signal.SIGKILL)
        except (OSError, ValueError):
            pass
    assert left == []


def test_strict_refuses_without_namespaces(monkeypatch):
    """--isolation strict refuses to grade when the namespace sandbox cannot start; auto says why not."""
    monkeypatch.setattr(isolation, "probe", lambda: dict(FOUND, namespaces=False, namespaces_why="no bwrap (test)"))
    with pytest.raises(isolation.IsolationUnavailable, match="no bwrap"):
        isolation.plan("strict")
    assert isolation.plan("auto").namespaces is False
    with pytest.raises(ValueError, match="isolation must be one of"):
        isolation.plan("loose")


def test_describe_names_every_layer():
    """The one-line description names what was active and what was not."""
    text = isolation.describe({"namespaces": True, "uid": 1900000001, "landlock": 7, "no_new_privs": True,
                               "rlimits": True, "audit_hook": True})
    assert "namespaces" in text and "uid 1900000001" in text and "Landlock ABI 7" in text
    assert "no namespaces" in isolation.describe({"namespaces": False, "landlock": 0, "audit_hook": False})


def test_library_changes_names_a_planted_file(tmp_path):
    """The checksum names a changed module and a planted .pyc, and ignores a .pyc Python wrote itself."""
    package = tmp_path / "pkg"
    (package / "__pycache__").mkdir(parents=True)
    (package / "mod.py").write_text("x = 1\n")
    before = isolation.library_checksum(package)
    import py_compile

    py_compile.compile(str(package / "mod.py"), cfile=str(package / "__pycache__" / "mod.cpython-311.pyc"))
    assert isolation.library_changes(before, package) == []
    (package / "__pycache__" / "evil.cpython-311.pyc").write_bytes(b"\x00" * 20)
    assert isolation.library_changes(before, package) == ["__pycache__/evil.cpython-311.pyc"]
    (package / "mod.py").write_text("x = 2\n")
    assert isolation.library_changes(before, package)[0] == "mod.py"  # sources first, then bytecode
