"""``particles grade-worker ADDRESS``: grading workers joining a Dask cluster (:mod:`particles.course.grading.cluster`).

The machine checks itself first (:func:`particles.course.grading.cluster_worker.check_in`: its course
folder, its walls, the digests of its library and tests) and says what it found; under ``--isolation
strict`` a machine without the namespace sandbox refuses to join, naming what it lacks (exit status 2).
Then it becomes Dask's own ``dask worker`` with the grading worker class, one thread per process, no
dashboard: the same as::

    PARTICLES_COURSE_ROOT=COURSE PARTICLES_GRADER_ISOLATION=strict dask worker ADDRESS --nworkers N \\
        --nthreads 1 --no-dashboard --worker-class particles.course.grading.cluster_worker.GraderWorker
"""

import os
import sys

from .common import add_root, course_root


def command(args, address, loopback):
    """The ``dask worker`` command line of the arguments."""
    where = ["--scheduler-file", args.scheduler_file] if args.scheduler_file else [address]
    line = [sys.executable, "-m", "distributed.cli.dask_worker", *where, "--nworkers", str(args.nworkers),
            "--nthreads", "1", "--no-dashboard",
            "--worker-class", "particles.course.grading.cluster_worker.GraderWorker"]
    line += ["--host", "127.0.0.1"] if loopback else []
    line += ["--name", args.name] if args.name else []
    for flag, value in (("--tls-ca-file", args.tls_ca_file), ("--tls-cert", args.tls_cert),
                        ("--tls-key", args.tls_key)):
        line += [flag, value] if value else []
    return line


def run(args):
    if not args.address and not args.scheduler_file:
        print("particles grade-worker: give the scheduler's ADDRESS or --scheduler-file", file=sys.stderr)
        return 2
    try:
        from ..course.grading.cluster import check_address, is_loopback, scheduler_address
        from ..course.grading.cluster_worker import check_in
    except ImportError as error:
        print(f"particles grade-worker: needs Dask's distributed (pip install 'particles[cluster]'): {error}",
              file=sys.stderr)
        return 2
    from ..course.grading.cluster_tasks import ClusterError
    from ..course.walls.isolation import IsolationUnavailable

    from distributed.security import Security

    config = Security()  # Dask's settings (distributed.comm.tls), where the flags do not say
    if args.nworkers < 1:
        print(f"particles grade-worker: --nworkers must be at least 1, got {args.nworkers}", file=sys.stderr)
        return 2
    try:
        address = scheduler_address(args.address, args.scheduler_file)
        check_address(address, {"--tls-ca-file": args.tls_ca_file or config.tls_ca_file,
                                "--tls-cert": args.tls_cert or config.tls_worker_cert,
                                "--tls-key": args.tls_key or config.tls_worker_key})
        grader = check_in(course_root(args), args.isolation)
    except (ValueError, IsolationUnavailable, ClusterError) as error:
        print(f"particles grade-worker: refusing to join: {error}", file=sys.stderr)
        return 2
    plan = grader.plan
    print(f"particles grade-worker: {grader.host} joins {address} with {args.nworkers} worker(s); course "
          f"{grader.root}, library {grader.library}", flush=True)
    print(f"  walls ({grader.mode}): {plan.to_option()}" + (f" ({plan.why})" if plan.why else ""), flush=True)
    for exercise, version in grader.tests.items():
        print(f"  {exercise}: {version}", flush=True)
    host = address.partition("://")[2].rsplit(":", 1)[0]
    env = dict(os.environ, PARTICLES_COURSE_ROOT=str(grader.root), PARTICLES_GRADER_ISOLATION=grader.mode)
    line = command(args, address, is_loopback(host))
    os.execve(line[0], line, env)  # Dask's worker from here on: its nanny restarts a worker that died


def register(commands):
    verb = commands.add_parser("grade-worker", help="join a Dask cluster as grading workers (particles grade "
                                                    "--scheduler ADDRESS)")
    verb.add_argument("address", nargs="?", metavar="ADDRESS",
                      help="the scheduler's tcp://HOST:PORT (this machine only) or tls://HOST:PORT")
    verb.add_argument("--scheduler-file", metavar="FILE", help="the scheduler's file (dask scheduler --scheduler-file)")
    verb.add_argument("--nworkers", type=int, default=os.cpu_count() or 1,
                      help="worker processes, each grading one batch at a time (default: one per core)")
    verb.add_argument("--name", help="the workers' name (numbered when there are several)")
    add_root(verb)
    verb.add_argument("--isolation", choices=["auto", "strict"], default="auto",
                      help="auto: the strongest sandbox this machine allows (default); strict: refuse to join "
                           "without the namespace sandbox")
    verb.add_argument("--tls-ca-file", metavar="FILE", help="the cluster's CA certificate (PEM), for tls://")
    verb.add_argument("--tls-cert", metavar="FILE", help="this worker's certificate (PEM), for tls://")
    verb.add_argument("--tls-key", metavar="FILE", help="this worker's private key (PEM), for tls://")
    verb.set_defaults(run=run)
