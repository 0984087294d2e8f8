"""The run stage on a Dask cluster: batches graded by other processes or machines (``--scheduler``).

:class:`ClusterRunner` is a :class:`~particles.course.grading.run.Runner` beside the local pool. Dask's
``distributed`` schedules, moves the data and watches the workers; nothing of a scheduler, a queue or a
worker protocol is ours. ``local:N`` starts an embedded ``LocalCluster`` of N worker processes (one thread
each, bound to 127.0.0.1, no dashboard, TLS with a key made for the run); a ``tcp://`` or ``tls://``
address, or a scheduler file, joins a running cluster, whose workers are
:class:`~particles.course.grading.cluster_worker.GraderWorker` s (``particles grade-worker``). Off this
machine the scheduler must be a ``tls://`` address with the certificates in Dask's settings: Dask pickles
its messages, and student code runs on the workers.

Each batch becomes a task of plain data (:mod:`~particles.course.grading.cluster_tasks`) asking for the
grading resource, so only grading workers take it, one at a time each; the runner sends one per grading
worker and keeps the others, in the plan's order, until one is free. Delivery is at least once and
records exactly once:

* a result is read once, checked against its task, and released, so that Dask does not compute it again
  when the worker holding it dies; a second delivery of a notebook (same student, exercise, digest and
  seed: a batch sent again after a loss that was graded after all) is dropped, never handed on twice;
* a task lost with its worker comes back as a lost :class:`~particles.course.grading.run.Outcome`:
  :func:`~particles.course.grading.run.run_all` sends it again, then notebook by notebook, then records it
  as not graded yet (the embedded scheduler lets Dask try a task once, ``allowed-failures: 0``, so that
  those bounded retries are the run's; a cluster's own scheduler may try it more often first);
* a task a worker refused (other tests, library or course files, weaker walls) stops the run with
  :class:`~particles.course.grading.cluster_tasks.TaskRefused` naming the worker: it is not sent again.

:meth:`ClusterRunner.close` with ``cancel`` (Ctrl-C, an error) cancels every task not finished; the
embedded cluster ends with the run, and its workers' sessions with them.
"""

import collections
import functools
import ipaddress
import json
import logging
import socket
import sys
import time
import uuid
from pathlib import Path

import dask
from distributed import Client, LocalCluster, Nanny, as_completed
from distributed.scheduler import KilledWorker
from distributed.security import Security

from .cluster_tasks import RESOURCE, ClusterError, course_digest, delivery_keys, make_task, read_result
from .cluster_worker import ISOLATION_VARIABLE, GraderWorker, grade_task
from .run import Outcome
from .versions import library_digest, tests_version

__all__ = ["ClusterRunner", "scheduler_address", "check_address", "is_loopback", "WAIT"]

WAIT = 120.0
"""Seconds a run waits for a first grading worker to join a running cluster's scheduler."""

QUIET = {"distributed.admin.tick.interval": "500ms", "distributed.admin.system-monitor.interval": "5s",
         "distributed.admin.system-monitor.gil.enabled": False, "distributed.scheduler.work-stealing": False,
         "distributed.scheduler.allowed-failures": 0, "distributed.worker.profile.enabled": False,
         "distributed.worker.memory.monitor-interval": "1s"}
"""Dask's settings of the embedded cluster: its processes wait for grading sessions, so they check their event
loops, the machine and their memory seldom, sample no profile, steal no work (the runner keeps the queue)
and let a task be tried once (a lost one comes back to the run, which sends it again)."""

with dask.config.set(QUIET):
    WORKER_CONFIG = dask.config.merge(dask.config.config)
"""The whole of Dask's settings a nanny gives the workers it starts, also when it starts one again."""


def is_loopback(host):
    """Whether `host` (a name or an address) is this machine's loopback (every address it resolves to)."""
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        pass
    try:
        found = {info[4][0] for info in socket.getaddrinfo(host, None)}
    except OSError:
        return False
    return bool(found) and all(ipaddress.ip_address(a.split("%")[0]).is_loopback for a in found)


def scheduler_address(scheduler=None, scheduler_file=None):
    """The scheduler's address: `scheduler`, or the ``address`` of Dask's scheduler file."""
    if scheduler_file is None:
        return scheduler
    try:
        return str(json.loads(Path(scheduler_file).read_text())["address"])
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise ClusterError(f"cannot read the scheduler's address from {scheduler_file} ({error})") from None


def check_address(address, certificates):
    """Refuse a scheduler off this machine without TLS and certificates.

    Parameters
    ----------
    address : str
        ``tcp://host:port`` or ``tls://host:port``.
    certificates : dict
        What TLS needs, name -> file (None when missing): the CA file, this side's certificate and key.

    Raises
    ------
    ClusterError
        On another protocol, or off loopback without ``tls://`` and every certificate.
    """
    scheme, _, rest = address.partition("://")
    if scheme not in ("tcp", "tls") or not rest:
        raise ClusterError(f"the scheduler's address must be tcp://HOST:PORT or tls://HOST:PORT, got {address!r}")
    host = rest.rsplit(":", 1)[0] if rest.count(":") == 1 or rest.startswith("[") else rest
    if is_loopback(host):
        return
    if scheme != "tls":
        raise ClusterError(f"the scheduler {address} is not on this machine: a cluster's messages are pickled and "
                           "carry the submissions, so it must use TLS with certificates (a tls:// address)")
    missing = [name for name, path in certificates.items() if not path]
    if missing:
        raise ClusterError(f"the scheduler {address} uses TLS but this side has no {', '.join(missing)}: set them "
                           "in Dask's settings (distributed.comm.tls) or on the command line")


def _reason(error):
    """The innermost cause of a failed start: the grading worker's own refusal."""
    while error.__cause__ is not None:
        error = error.__cause__
    return str(error)


class ClusterRunner:
    """Batches graded on a Dask cluster.

    Parameters
    ----------
    scheduler : str, optional
        ``local:N`` (an embedded cluster of N worker processes), ``tcp://HOST:PORT`` or ``tls://HOST:PORT``.
    scheduler_file : path, optional
        Dask's scheduler file (instead of `scheduler`).
    root : path
        The course folder (an embedded cluster's workers grade with it).
    isolation : {"auto", "strict"}
        The walls an embedded cluster's workers check for when they start.
    say : callable, optional
        Called with one line for each lost batch (default: printed on stderr).
    wait : float
        Seconds to wait for a grading worker of a running cluster.

    Attributes
    ----------
    slots : int
        Batches graded at the same time (the embedded workers, or the grading workers found); reading it
        starts or joins the cluster.
    """

    def __init__(self, scheduler=None, scheduler_file=None, root=None, isolation="auto", say=None, wait=WAIT):
        self.scheduler, self.scheduler_file, self.root, self.isolation = scheduler, scheduler_file, root, isolation
        self.say = say or (lambda line: print(line, file=sys.stderr, flush=True))
        self.wait = wait
        self.local = int(scheduler.split(":", 1)[1]) if scheduler and scheduler.startswith("local:") else None
        self.cluster = self.client = self.queue = None
        self.pending, self.delivered, self.versions, self.graders, self.counted = {}, set(), {}, 0, 0.0
        self.waiting = collections.deque()

    @property
    def slots(self):
        self._connect()
        return self.local or self.graders

    def _connect(self):
        if self.client is not None:
            return
        if self.local is not None:
            self._start_local()
        else:
            self._join()
        self.queue = as_completed()
        self.library = library_digest()

    def _start_local(self):
        env = {"PARTICLES_COURSE_ROOT": str(self.root), ISOLATION_VARIABLE: self.isolation}
        # TLS on loopback too, with a key made for this run: no other process of this machine (another user, a
        # submission that got out of its walls) can reach the scheduler or its workers, which run as this user
        security = Security.temporary()
        try:
            with dask.config.set(QUIET):
                self.cluster = LocalCluster(n_workers=self.local, threads_per_worker=1, processes=True,
                                            host="127.0.0.1", protocol="tls://", security=security,
                                            dashboard_address=None, env=env, silence_logs=logging.CRITICAL,
                                            worker_class=functools.partial(Nanny, worker_class=GraderWorker,
                                                                           config=WORKER_CONFIG),
                                            scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})  # health only
        except Exception as error:  # a worker that refused to join: say why, not Dask's "failed to start"
            raise ClusterError(f"the grading workers of {self.scheduler} did not start: {_reason(error)}") from None
        self.client = Client(self.cluster, security=security)

    def _join(self):
        address = scheduler_address(self.scheduler, self.scheduler_file)
        security = Security()
        check_address(address, {"CA file": security.tls_ca_file, "certificate": security.tls_client_cert,
                                "key": security.tls_client_key})
        try:
            self.client = Client(address, security=security if address.startswith("tls://") else None)
        except (OSError, TimeoutError) as error:
            raise ClusterError(f"cannot reach the scheduler at {address} ({error})") from None
        deadline, others = time.monotonic() + self.wait, self._count()
        while not self.graders and time.monotonic() < deadline:
            time.sleep(0.5)
            others = self._count()
        if not self.graders:
            self.client.close()
            self.client = None
            raise ClusterError(f"no grading worker joined the scheduler at {address} within {self.wait:g} s (it has "
                               f"{others} other worker(s)); start them with: particles grade-worker {address}")

    def _count(self):
        """Count the scheduler's grading workers (:attr:`graders`); returns how many workers it has in all."""
        workers = list(self.client.scheduler_info()["workers"].values())
        self.graders = sum(1 for w in workers if RESOURCE in (w.get("resources") or {}))
        self.counted = time.monotonic()
        return len(workers)

    def _capacity(self):
        """Tasks the cluster is given at once: one per grading worker (a running cluster's counted again, at most
        every few seconds, as workers join or leave), at least one."""
        if self.local is not None:
            return self.local
        if time.monotonic() - self.counted > 2.0:
            self._count()
        return max(1, self.graders)

    def _versions(self, root, exercise):
        if exercise not in self.versions:
            self.versions[exercise] = {"tests": tests_version(root, exercise, self.library), "library": self.library,
                                       "course": course_digest(root, exercise)}
        return self.versions[exercise]

    def submit(self, batch, settings):
        self._connect()
        self.waiting.append((batch, settings))
        self._feed()

    def _feed(self):
        """Send waiting batches, in their order, while a grading worker is free for each.

        The run keeps the queue: Dask would place every task on a worker when it is sent, before knowing how
        long any takes, and the large batches the plan puts first could end up last on a busy worker.
        """
        while self.waiting and len(self.pending) < self._capacity():
            batch, settings = self.waiting.popleft()
            task = make_task(batch, settings, self._versions(settings.root, batch.exercise))
            key = f"grade-{batch.exercise}-{batch.number}-{uuid.uuid4().hex}"  # a task sent again is a new one
            future = self.client.submit(grade_task, task, key=key, resources={RESOURCE: 1}, pure=False, retries=0)
            self.pending[future.key] = (future, batch, task, settings)
            self.queue.add(future)

    def completed(self):
        while self.pending or self.waiting:
            self._feed()
            future = next(self.queue)
            entry = self.pending.pop(future.key, None)
            if entry is None:  # the same future again (a result computed twice): delivered already
                continue
            _, batch, task, settings = entry
            try:
                outcome = self._outcome(future, batch, task, settings)
            finally:
                future.release()  # read once: Dask must not compute it again if the worker holding it dies
            if outcome is not None:
                yield outcome

    def _outcome(self, future, batch, task, settings):
        """The :class:`Outcome` of a finished task (None: every record of it was delivered before)."""
        if future.status == "finished":
            records, logs = read_result(task, future.result())
            if settings.logs is not None:
                for name, text in logs.items():
                    if Path(name).name == name and name.endswith(".log"):
                        (settings.logs / name).write_text(text)
            keys = delivery_keys(task)
            fresh = [record for record, key in zip(records, keys) if key not in self.delivered]
            self.delivered.update(keys)
            if len(fresh) < len(records):
                self.say(f"particles grade: {len(records) - len(fresh)} notebook(s) of batch {batch.number} of "
                         f"{batch.exercise} delivered again; their first records are kept")
            return Outcome(batch, results=fresh) if fresh else None
        error = future.exception() if future.status == "error" else None
        if isinstance(error, ClusterError):
            raise type(error)(str(error)) from None
        if error is not None and not isinstance(error, KilledWorker):
            raise error  # a fault of the grader, as a local run raises it
        last = getattr(getattr(error, "last_worker", None), "address", "unknown")
        why = (f"the worker grading it died ({last})" if error is not None
               else f"the cluster dropped it ({future.status})")
        self.say(f"particles grade: batch {batch.number} of {batch.exercise} ({len(batch.units)} notebook(s)) "
                 f"was lost: {why}")
        return Outcome(batch, lost=why)

    def close(self, cancel=False):
        if self.client is None:
            return
        if cancel and self.pending:
            self.client.cancel([future for future, *_ in self.pending.values()], force=True)
        self.pending.clear()
        self.waiting.clear()
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()
        self.client = self.cluster = self.queue = None
