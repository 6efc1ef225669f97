"""Run a sweep spec on SLURM: dask-jobqueue worker jobs that come and go.

    pip install 'dlasweep[slurm]'
    python workflows/slurm.py workflows/quick.toml -o results/quick.nc \\
        --partition normal --account myproject --cores 16 --memory 32GB --walltime 02:00:00

``--dry-run`` prints the SLURM job script and stops, without starting anything.

The dask scheduler runs in this process (run it on a login node or in a
small job of its own); the sweep is ``dlasweep sweep --scheduler ADDRESS``,
with its checks, messages and exit status. Each SLURM job runs one dask
worker with ``--cores`` threads: the kernels release the GIL, and dask
notices when a one-worker job ends (``scancel``, preemption, the end of its
wall time) and submits a replacement (after its lost-worker timeout, 15 s
by default). Jobs are added as tasks wait, one at a time: at most one job
waits in the queue, and a waiting job is not cancelled to be resubmitted
(it would lose its place; see ``jobs_to_hold``). Once the sweep has work,
one job is kept. A worker retires before its wall time runs out
(lifetime and stagger derived from ``--walltime``), so SLURM never cuts a
task off; dask runs it elsewhere. Each finished task is saved as it
arrives, so an interrupted run continues with ``--resume``. On any exit
(the end, an error, Ctrl-C, SIGTERM) every job this launcher submitted is
cancelled.

Lines on stderr say when a job is submitted, starts, ends or is cancelled,
and (when stderr is not a terminal) every ``--log-every`` finished tasks.
"""

from __future__ import annotations

import _thread
import argparse
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

MIN_WALLTIME = 180
"""Seconds: a worker's start, some work, and its retirement must fit in one job."""

RETIRE_SECONDS = 60
"""At least this long between a worker's latest retirement and the end of its wall time."""

JOB_NAME = "dlasweep"


class UsageError(ValueError):
    """A bad option; the message names it."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        raise UsageError(message)


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="slurm.py", allow_abbrev=False, description=__doc__.split("\n\n")[0])
    parser.add_argument("spec", type=Path, help="sweep spec (TOML)")
    parser.add_argument("-o", "--output", type=Path, help="netCDF file (default: SPEC's name with .nc, here)")
    parser.add_argument("--resume", action="store_true", help="continue an interrupted run of this spec")
    job = parser.add_argument_group("each worker job")
    job.add_argument("--partition", "--queue", dest="partition", help="SLURM partition (default: the default one)")
    job.add_argument("--account", help="SLURM account")
    job.add_argument("--cores", type=int, default=8, help="CPUs of a job: one dask worker with this many threads "
                                                          "(default 8)")
    job.add_argument("--memory", default="16GB", help="memory of a job (default 16GB)")
    job.add_argument("--walltime", default="02:00:00", help="wall time of a job, in SLURM's format "
                                                            "(default 02:00:00); workers retire before it ends")
    job.add_argument("--max-jobs", type=int, default=10, help="most jobs at once (default 10)")
    job.add_argument("--sbatch", action="append", default=[], metavar="OPTION",
                     help="extra #SBATCH line, e.g. --sbatch '--qos=short' (repeatable)")
    job.add_argument("--python", default=sys.executable,
                     help="Python that runs the workers (default: this one, by absolute path)")
    job.add_argument("--prologue", action="append", default=[], metavar="LINE",
                     help="shell line run before the worker starts (repeatable)")
    job.add_argument("--log-dir", type=Path, default=Path("slurm-logs"),
                     help="folder for the jobs' slurm-<id>.out (default slurm-logs)")
    job.add_argument("--local-directory", metavar="DIR",
                     help="worker scratch folder (default: dask's, in the job's temporary folder)")
    job.add_argument("--death-timeout", type=float, default=60,
                     help="seconds a worker waits for a lost scheduler before it exits (default 60)")
    net = parser.add_argument_group("network")
    net.add_argument("--interface", help="network interface of the scheduler and the workers, e.g. ib0 or lo")
    net.add_argument("--scheduler-host", metavar="ADDRESS",
                     help="address the scheduler listens on (default: --interface's, else the host name's)")
    parser.add_argument("--log-every", type=int, default=10, metavar="N",
                        help="when stderr is not a terminal, a line per N finished tasks (default 10)")
    parser.add_argument("--dry-run", action="store_true", help="print the job script and stop")
    return parser


def walltime_seconds(text: str) -> int:
    """Seconds in a SLURM time: ``M``, ``M:S``, ``H:M:S``, ``D-H``, ``D-H:M``, ``D-H:M:S``."""
    days, dash, clock = text.partition("-")
    if not dash:
        days, clock = "0", text
    fields = clock.split(":")
    if not (days.isdigit() and all(f.isdigit() for f in fields) and len(fields) <= 3):
        raise UsageError(f"--walltime {text}: expected SLURM's format, e.g. 02:00:00, 90 or 1-12:00:00")
    if dash:  # D-H, D-H:M, D-H:M:S
        hours, minutes, seconds = (fields + ["0", "0"])[:3]
    else:  # M, M:S, H:M:S
        hours, minutes, seconds = (["0", *fields, "0"] if len(fields) < 3 else fields)[:3]
    return ((int(days) * 24 + int(hours)) * 60 + int(minutes)) * 60 + int(seconds)


def lifetime(walltime: int) -> tuple[int, int]:
    """A worker's lifetime and stagger (seconds): it retires in [lifetime - stagger, lifetime + stagger],
    at least ``RETIRE_SECONDS`` (and a twentieth of the wall time) before SLURM ends its job."""
    if walltime < MIN_WALLTIME:
        raise UsageError(f"--walltime: {walltime} s is too short; a worker needs at least "
                         f"{MIN_WALLTIME} s to start, work and retire")
    stagger = walltime // 20
    return walltime - stagger - max(RETIRE_SECONDS, walltime // 20), stagger


def _check(args):
    """Refuse bad options before anything starts."""
    for name in ("cores", "max_jobs", "log_every"):
        if getattr(args, name) < 1:
            raise UsageError(f"--{name.replace('_', '-')}: {getattr(args, name)} is below 1")
    if args.death_timeout <= 0:
        raise UsageError(f"--death-timeout: {args.death_timeout:g} is not positive")
    from dask.utils import parse_bytes

    try:
        parse_bytes(args.memory)
    except ValueError:
        raise UsageError(f"--memory {args.memory}: expected an amount like 16GB") from None
    lifetime(walltime_seconds(args.walltime))
    if not os.access(args.python, os.X_OK):
        raise UsageError(f"--python {args.python}: not an executable file")
    if args.interface:
        import psutil

        have = psutil.net_if_addrs()
        if args.interface not in have:
            raise UsageError(f"--interface {args.interface}: no such network interface here "
                             f"(there are: {', '.join(sorted(have))})")
    if args.scheduler_host:
        try:
            socket.getaddrinfo(args.scheduler_host, None)
        except OSError:
            raise UsageError(f"--scheduler-host {args.scheduler_host}: unknown host") from None


def _check_partition(args):
    """Check the partition, ``--cores`` and ``--memory`` against what ``sinfo`` says it offers."""
    from dask.utils import parse_bytes

    try:
        listed = subprocess.run(["sinfo", "--noheader", "--format=%P %c %m"], check=False,
                                capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired) as err:
        raise UsageError(f"sinfo: cannot ask SLURM for its partitions ({err})") from None
    if listed.returncode:
        raise UsageError(f"sinfo failed: {_last_line(listed.stderr)}")
    cpus, memory_mb = {}, {}
    for line in listed.stdout.splitlines():
        name, node_cpus, node_mb = line.split()
        default, name = name.endswith("*"), name.rstrip("*")
        if name == args.partition or (args.partition is None and default):
            # A partition of several kinds of node is listed once per kind; "+" marks a range.
            cpus[name] = max(cpus.get(name, 0), int(node_cpus.rstrip("+")))
            memory_mb[name] = max(memory_mb.get(name, 0), int(node_mb.rstrip("+")))
    partition = args.partition or next(iter(cpus), None)
    if partition not in cpus:
        raise UsageError(f"--partition {args.partition}: no such partition (sinfo)" if args.partition
                         else "--partition: SLURM has no default partition; name one")
    if args.cores > cpus[partition]:
        raise UsageError(f"--cores {args.cores}: partition {partition} has at most {cpus[partition]} "
                         f"CPUs per node")
    if parse_bytes(args.memory) > memory_mb[partition] * 2**20:
        raise UsageError(f"--memory {args.memory}: partition {partition} has at most "
                         f"{memory_mb[partition]} MB per node")


def _check_job(script: str):
    """Ask SLURM whether it would take the job script (``sbatch --test-only``: nothing is submitted)."""
    with tempfile.NamedTemporaryFile("w", suffix=".sh") as file:
        file.write(script)
        file.flush()
        tried = subprocess.run(["sbatch", "--test-only", file.name], check=False, capture_output=True,
                               text=True, timeout=30)
    if tried.returncode:
        raise UsageError(f"sbatch refuses the job: {_last_line(tried.stderr)}")


def _last_line(text: str) -> str:
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[-1] if lines else "no message"


def _scheduler_host(args) -> str | None:
    """The address the scheduler listens on: given, the interface's, or dask's default (None)."""
    if args.scheduler_host or not args.interface:
        return args.scheduler_host
    import psutil

    for address in psutil.net_if_addrs()[args.interface]:
        if address.family == socket.AF_INET:
            return address.address
    raise UsageError(f"--interface {args.interface}: has no IPv4 address")


def job_options(args) -> dict:
    """The keywords of a dask-jobqueue SLURM job: one worker of ``--cores`` threads."""
    life, stagger = lifetime(walltime_seconds(args.walltime))
    return {
        "cores": args.cores,
        "processes": 1,
        "memory": args.memory,
        "walltime": args.walltime,
        "queue": args.partition,
        "account": args.account,
        "python": args.python,
        "job_name": JOB_NAME,
        "job_extra_directives": [f"--output={args.log_dir.resolve()}/slurm-%j.out", *args.sbatch],
        "job_script_prologue": args.prologue,
        "local_directory": args.local_directory,
        "death_timeout": args.death_timeout,
        "interface": args.interface,
        "worker_extra_args": ["--lifetime", f"{life}s", "--lifetime-stagger", f"{stagger}s"],
    }


def jobs_to_hold(wanted: int, arrived: int, planned: int, busy: bool) -> int:
    """How many worker jobs to hold, given how many dask wants, how many have arrived (their worker
    connected) and how many are planned (submitted or being replaced).

    At most one job more than have arrived, so that at most one waits in the queue; never fewer
    than planned while one waits, so that a waiting job keeps its place instead of being cancelled
    and resubmitted; at least one once the sweep has had work (``busy``).
    """
    hold = max(min(wanted, arrived + 1), int(busy))
    return max(hold, planned) if planned > arrived else hold


class _Log:
    """Progress lines on stderr, and what the launcher needs to know of its jobs."""

    def __init__(self, every, on_terminal):
        self.every = every
        self.task_lines = not on_terminal  # on a terminal the sweep shows its own progress bar
        self.finished = self.failed = 0
        self.submitted = []
        self.sbatch_error = None
        self.signal = None

    def interrupted(self, signum, frame):
        self.signal = signum
        raise KeyboardInterrupt

    def line(self, text):
        print(f"slurm.py {time.strftime('%H:%M:%S')} {text}", file=sys.stderr, flush=True)

    def task_done(self, ok, workers):
        if ok:
            self.finished += 1
        else:
            self.failed += 1
        done = self.finished + self.failed
        if self.task_lines and done % self.every == 0:
            failed = f" ({self.failed} failed)" if self.failed else ""
            self.line(f"{done} tasks finished{failed}, {workers} workers")


def _slurm_classes(log: _Log):
    """A SLURM job class that logs and records its job, a scheduler plugin that logs workers and
    tasks, and the adaptive policy (built here: dask-jobqueue is imported only when needed)."""
    from dask_jobqueue.slurm import SLURMJob
    from distributed.core import Status
    from distributed.deploy.adaptive import Adaptive
    from distributed.diagnostics.plugin import SchedulerPlugin

    class LoggedJob(SLURMJob):
        async def start(self):
            try:
                await super().start()
            except Exception as err:
                self.status = Status.failed  # so that the cluster can close
                if log.sbatch_error is None:
                    log.sbatch_error = _last_line(str(err))
                    _thread.interrupt_main()  # the sweep waits in the main thread: stop it
                raise
            log.submitted.append(self.job_id)
            log.line(f"job {self.job_id} submitted (worker {self.name})")

        async def close(self):
            if self.job_id:
                log.line(f"job {self.job_id}: scancel (worker {self.name})")
            await super().close()

    class Progress(SchedulerPlugin):
        name = "dlasweep-slurm-progress"

        def __init__(self):
            self.names = {}

        def add_worker(self, scheduler, worker):
            state = scheduler.workers[worker]
            self.names[worker] = state.name
            log.line(f"worker {state.name} started: {worker}, {state.nthreads} threads")

        def remove_worker(self, scheduler, worker, **kwargs):
            log.line(f"worker {self.names.pop(worker, worker)} left, its job ended")

        def transition(self, key, start, finish, *args, **kwargs):
            if finish in ("memory", "erred"):
                log.task_done(finish == "memory", len(self.names))

    class OneJobWaiting(Adaptive):
        """dask's adaptive scaling, its target passed through ``jobs_to_hold``."""

        busy = False

        async def target(self):
            wanted = await super().target()
            self.busy = self.busy or wanted > 0
            return jobs_to_hold(wanted, len(self.observed), len(self.plan), self.busy)

    return LoggedJob, Progress, OneJobWaiting


def _cancel_left(log: _Log):
    """Cancel every job this launcher submitted that SLURM still holds."""
    if not log.submitted:
        return
    queued = subprocess.run(["squeue", "--noheader", "--format=%i", "--states=pending,running,configuring",
                             f"--jobs={','.join(log.submitted)}"], check=False, capture_output=True, text=True)
    left = queued.stdout.split()
    if left:
        subprocess.run(["scancel", *left], check=False, capture_output=True)
        log.line(f"cancelled jobs left in the queue: {' '.join(left)}")


def main(argv=None) -> int:
    """Run the launcher; return the exit status (2: bad option, 130/143: Ctrl-C/SIGTERM)."""
    try:
        args = _parser().parse_args(None if argv is None else [str(a) for a in argv])
        _check(args)
        from dlasweep.spec import SpecError, load_spec
        from dlasweep.store import one_line

        try:
            load_spec(args.spec)
        except SpecError as err:
            raise UsageError(one_line(err)) from None
        if not args.dry_run:
            _check_partition(args)
        handler = signal.getsignal(signal.SIGINT)
        import dask_jobqueue  # noqa: F401
        # Its import replaces the SIGINT handler with sys.exit(), which turns Ctrl-C into a quiet exit 0.
        signal.signal(signal.SIGINT, handler)
        host = _scheduler_host(args)
    except UsageError as err:
        print(f"slurm.py: {err}", file=sys.stderr)
        return 2
    except ImportError:
        print("slurm.py: needs dask-jobqueue: pip install 'dlasweep[slurm]'", file=sys.stderr)
        return 2
    log = _Log(args.log_every, on_terminal=sys.stderr.isatty())
    LoggedJob, Progress, OneJobWaiting = _slurm_classes(log)
    address = f"tcp://{host or socket.gethostname()}:PORT"
    script = LoggedJob(scheduler=address, name=f"{JOB_NAME}-worker", **job_options(args)).job_script()
    if args.dry_run:
        print(script)
        return 0
    try:
        _check_job(script)
    except UsageError as err:
        print(f"slurm.py: {err}", file=sys.stderr)
        return 2
    # Ctrl-C and SIGTERM raise KeyboardInterrupt: the sweep then says how to resume, jobs are cancelled.
    handlers = {signum: signal.signal(signum, log.interrupted) for signum in (signal.SIGINT, signal.SIGTERM)}

    from dask_jobqueue import SLURMCluster

    from dlasweep.cli import main as dlasweep_main

    status = 1
    try:
        args.log_dir.mkdir(parents=True, exist_ok=True)
        scheduler = {"plugins": [Progress()], "dashboard_address": f"{host or ''}:0"}
        if host:
            scheduler["host"] = host
        with SLURMCluster(job_cls=LoggedJob, scheduler_options=scheduler, **job_options(args)) as cluster:
            log.line(f"scheduler {cluster.scheduler_address}, dashboard {cluster.dashboard_link}, "
                     f"jobs of {args.cores} cores, at most {args.max_jobs}")
            cluster.adapt(Adaptive=OneJobWaiting, minimum_jobs=0, maximum_jobs=args.max_jobs)
            sweep = ["sweep", args.spec, "--scheduler", cluster.scheduler_address]
            if args.output:
                sweep += ["-o", args.output]
            if args.resume:
                sweep.append("--resume")
            status = dlasweep_main(sweep)
    except KeyboardInterrupt:
        pass  # the status is the signal's
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # cancel the jobs even if Ctrl-C is pressed again
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        _cancel_left(log)
        if log.sbatch_error:
            log.line(f"stopped: submitting a job failed: {log.sbatch_error}")
        elif log.signal:
            log.line(f"interrupted ({signal.Signals(log.signal).name}); finished tasks are kept, "
                     f"continue with --resume")
        log.line(f"jobs submitted: {len(log.submitted)}, tasks finished: {log.finished}, failed: {log.failed}")
        for signum, handler in handlers.items():
            signal.signal(signum, handler)
    if log.sbatch_error:
        return 1
    return 128 + log.signal if log.signal else status


if __name__ == "__main__":
    raise SystemExit(main())
