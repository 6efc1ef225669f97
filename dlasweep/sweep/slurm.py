"""Work on SLURM: a dask scheduler in this process, its workers SLURM jobs (dask-jobqueue) that come and go.

Each job runs one dask worker with ``Options.cores`` threads: the kernels
release the GIL, and dask notices when a one-worker job ends (``scancel``,
preemption, the end of its wall time) and submits a replacement (after its
lost-worker timeout). Jobs are added as tasks wait, one at
a time: at most one job waits in the queue, and a waiting job is not
cancelled to be resubmitted (it would lose its place; see ``jobs_to_hold``).
Once the work has started, one job is kept. A worker retires before its
wall time runs out (``lifetime``), so SLURM never cuts a task off; dask runs
it elsewhere. On any exit (the end, an error, Ctrl-C, SIGTERM) every job
submitted is cancelled.

dask-jobqueue (the ``slurm`` extra) is imported only when a job is built.
"""

from __future__ import annotations

import _thread
import dataclasses
import os
import signal
import socket
import subprocess
import sys
import tempfile
from pathlib import Path

MIN_WALLTIME = 180
"""Seconds: a worker's start, some work, and its retirement must fit in one job."""

RETIRE_SECONDS = 60
"""At least this long between a worker's latest retirement and the end of its wall time."""

JOB_NAME = "dlasweep"

NEEDS_EXTRA = "needs dask-jobqueue: pip install 'dlasweep[slurm]'"


class SlurmError(ValueError):
    """The launcher cannot start: SLURM refuses, or dask-jobqueue is missing. One line."""


class OptionError(SlurmError):
    """A bad option; the message starts with its name (a field of ``Options``)."""


@dataclasses.dataclass(frozen=True)
class Options:
    """What each worker job asks SLURM for, how the workers reach the scheduler, and how often to log.

    Attributes
    ----------
    partition, account : str or None
        SLURM partition (None: the default one) and account.
    cores : int
        CPUs of a job: one dask worker with this many threads.
    memory, walltime : str
        A job's memory (``16GB``) and wall time, in SLURM's format.
    max_jobs : int
        Most jobs at once.
    sbatch, prologue : tuple of str
        Extra ``#SBATCH`` options; shell lines run before the worker starts.
    python : str
        Python that runs the workers (default: this one, by absolute path).
    log_dir : Path
        Folder of the jobs' ``slurm-<id>.out``.
    local_directory : str or None
        Workers' scratch folder (None: dask's).
    death_timeout : float
        Seconds a worker waits for a lost scheduler before it exits.
    interface, scheduler_host : str or None
        Network interface of the scheduler and the workers; address the scheduler listens on.
    log_every : int
        A line per this many finished tasks (when task lines are asked for).
    """

    partition: str | None = None
    account: str | None = None
    cores: int = 8
    memory: str = "16GB"
    walltime: str = "02:00:00"
    max_jobs: int = 10
    sbatch: tuple = ()
    python: str = sys.executable
    prologue: tuple = ()
    log_dir: Path = Path("slurm-logs")
    local_directory: str | None = None
    death_timeout: float = 60
    interface: str | None = None
    scheduler_host: str | None = None
    log_every: int = 10


def walltime_seconds(text: str) -> int:
    """Seconds in a SLURM time: ``M``, ``M:S``, ``H:M:S``, ``D-H``, ``D-H:M``, ``D-H:M:S``."""
    days, dash, clock = text.partition("-")
    if not dash:
        days, clock = "0", text
    fields = clock.split(":")
    if not (days.isdigit() and all(f.isdigit() for f in fields) and len(fields) <= 3):
        raise OptionError(f"walltime {text}: expected SLURM's format, e.g. 02:00:00, 90 or 1-12:00:00")
    if dash:  # D-H, D-H:M, D-H:M:S
        hours, minutes, seconds = (fields + ["0", "0"])[:3]
    else:  # M, M:S, H:M:S
        hours, minutes, seconds = (["0", *fields, "0"] if len(fields) < 3 else fields)[:3]
    return ((int(days) * 24 + int(hours)) * 60 + int(minutes)) * 60 + int(seconds)


def lifetime(walltime: int) -> tuple[int, int]:
    """A worker's lifetime and stagger (seconds): it retires in [lifetime - stagger, lifetime + stagger],
    at least ``RETIRE_SECONDS`` (and a twentieth of the wall time) before SLURM ends its job."""
    if walltime < MIN_WALLTIME:
        raise OptionError(f"walltime: {walltime} s is too short; a worker needs at least "
                          f"{MIN_WALLTIME} s to start, work and retire")
    stagger = walltime // 20
    return walltime - stagger - max(RETIRE_SECONDS, walltime // 20), stagger


def jobs_to_hold(wanted: int, arrived: int, planned: int, busy: bool) -> int:
    """How many worker jobs to hold, given how many dask wants, how many have arrived (their worker
    connected) and how many are planned (submitted or being replaced).

    At most one job more than have arrived, so that at most one waits in the queue; never fewer
    than planned while one waits, so that a waiting job keeps its place instead of being cancelled
    and resubmitted; at least one once the work has started (``busy``).
    """
    hold = max(min(wanted, arrived + 1), int(busy))
    return max(hold, planned) if planned > arrived else hold


def prepare(options: Options, ask_slurm=True) -> str:
    """Check everything before anything starts; return the job script.

    Parameters
    ----------
    options : Options
    ask_slurm : bool
        Also check the partition, ``cores`` and ``memory`` against ``sinfo``, and
        the job script with ``sbatch --test-only`` (nothing is submitted).

    Raises
    ------
    SlurmError
        dask-jobqueue is missing, or SLURM refuses; ``OptionError`` names a bad option.
    """
    _import_jobqueue()
    _check(options)
    if ask_slurm:
        _check_partition(options)
    from dask_jobqueue.slurm import SLURMJob

    address = f"tcp://{_scheduler_host(options) or socket.gethostname()}:PORT"
    script = SLURMJob(scheduler=address, name=f"{JOB_NAME}-worker", **job_options(options)).job_script()
    if ask_slurm:
        _check_job(script)
    return script


def _import_jobqueue():
    """Import dask-jobqueue, keeping this process's Ctrl-C handler."""
    handler = signal.getsignal(signal.SIGINT)
    try:
        import dask_jobqueue  # noqa: F401
    except ImportError:
        raise SlurmError(NEEDS_EXTRA) from None
    # Its import replaces the SIGINT handler with sys.exit(), which turns Ctrl-C into a quiet exit 0.
    signal.signal(signal.SIGINT, handler)


def _check(options: Options):
    """Refuse bad options without asking SLURM."""
    for name in ("cores", "max_jobs", "log_every"):
        if getattr(options, name) < 1:
            raise OptionError(f"{name}: {getattr(options, name)} is below 1")
    if options.death_timeout <= 0:
        raise OptionError(f"death_timeout: {options.death_timeout:g} is not positive")
    from dask.utils import parse_bytes

    try:
        parse_bytes(options.memory)
    except ValueError:
        raise OptionError(f"memory {options.memory}: expected an amount like 16GB") from None
    lifetime(walltime_seconds(options.walltime))
    if not os.access(options.python, os.X_OK):
        raise OptionError(f"python {options.python}: not an executable file")
    if options.interface:
        import psutil

        have = psutil.net_if_addrs()
        if options.interface not in have:
            raise OptionError(f"interface {options.interface}: no such network interface here "
                              f"(there are: {', '.join(sorted(have))})")
    if options.scheduler_host:
        try:
            socket.getaddrinfo(options.scheduler_host, None)
        except OSError:
            raise OptionError(f"scheduler_host {options.scheduler_host}: unknown host") from None


def _check_partition(options: Options):
    """Check the partition, ``cores`` and ``memory`` against what ``sinfo`` says it offers."""
    from dask.utils import parse_bytes

    try:
        listed = subprocess.run(["sinfo", "--noheader", "--format=%P %c %m"], check=False,
                                capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired) as err:
        raise SlurmError(f"sinfo: cannot ask SLURM for its partitions ({err})") from None
    if listed.returncode:
        raise SlurmError(f"sinfo failed: {_last_line(listed.stderr)}")
    cpus, memory_mb = {}, {}
    for line in listed.stdout.splitlines():
        name, node_cpus, node_mb = line.split()
        default, name = name.endswith("*"), name.rstrip("*")
        if name == options.partition or (options.partition is None and default):
            # A partition of several kinds of node is listed once per kind; "+" marks a range.
            cpus[name] = max(cpus.get(name, 0), int(node_cpus.rstrip("+")))
            memory_mb[name] = max(memory_mb.get(name, 0), int(node_mb.rstrip("+")))
    partition = options.partition or next(iter(cpus), None)
    if partition not in cpus:
        raise OptionError(f"partition {options.partition}: no such partition (sinfo)" if options.partition
                          else "partition: SLURM has no default partition; name one")
    if options.cores > cpus[partition]:
        raise OptionError(f"cores {options.cores}: partition {partition} has at most {cpus[partition]} "
                          f"CPUs per node")
    if parse_bytes(options.memory) > memory_mb[partition] * 2**20:
        raise OptionError(f"memory {options.memory}: partition {partition} has at most "
                          f"{memory_mb[partition]} MB per node")


def _check_job(script: str):
    """Ask SLURM whether it would take the job script (``sbatch --test-only``: nothing is submitted)."""
    with tempfile.NamedTemporaryFile("w", suffix=".sh") as file:
        file.write(script)
        file.flush()
        tried = subprocess.run(["sbatch", "--test-only", file.name], check=False, capture_output=True,
                               text=True, timeout=30)
    if tried.returncode:
        raise SlurmError(f"sbatch refuses the job: {_last_line(tried.stderr)}")


def _last_line(text: str) -> str:
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[-1] if lines else "no message"


def _scheduler_host(options: Options) -> str | None:
    """The address the scheduler listens on: given, the interface's, or dask's default (None)."""
    if options.scheduler_host or not options.interface:
        return options.scheduler_host
    import psutil

    for address in psutil.net_if_addrs()[options.interface]:
        if address.family == socket.AF_INET:
            return address.address
    raise OptionError(f"interface {options.interface}: has no IPv4 address")


def job_options(options: Options) -> dict:
    """The keywords of a dask-jobqueue SLURM job: one worker of ``cores`` threads."""
    life, stagger = lifetime(walltime_seconds(options.walltime))
    return {
        "cores": options.cores,
        "processes": 1,
        "memory": options.memory,
        "walltime": options.walltime,
        "queue": options.partition,
        "account": options.account,
        "python": options.python,
        "job_name": JOB_NAME,
        "job_extra_directives": [f"--output={Path(options.log_dir).resolve()}/slurm-%j.out", *options.sbatch],
        "job_script_prologue": list(options.prologue),
        "local_directory": options.local_directory,
        "death_timeout": options.death_timeout,
        "interface": options.interface,
        "worker_extra_args": ["--lifetime", f"{life}s", "--lifetime-stagger", f"{stagger}s"],
    }


def launch(options: Options, work, echo, task_lines=True) -> int:
    """Start the scheduler and its SLURM jobs, run ``work(address)``, cancel every job left.

    Call ``prepare`` first. Ctrl-C and SIGTERM stop ``work`` (as KeyboardInterrupt) and are
    answered here: what ``work`` finished stays, and the jobs are cancelled.

    Parameters
    ----------
    options : Options
    work : callable
        ``work(scheduler_address) -> exit status``, e.g. a sweep on that scheduler.
    echo : callable
        Takes each progress line: a job submitted, started, ended or cancelled, and
        (``task_lines``) every ``options.log_every`` finished tasks.
    task_lines : bool
        Log finished tasks (off where the work shows a progress bar of its own).

    Returns
    -------
    int
        ``work``'s status; 1 when submitting a job failed; 128 + the signal's number
        (130 Ctrl-C, 143 SIGTERM) when interrupted.
    """
    log = _Log(options.log_every, task_lines, echo)
    LoggedJob, Progress, OneJobWaiting = _slurm_classes(log)
    host = _scheduler_host(options)
    # Ctrl-C and SIGTERM raise KeyboardInterrupt: the work stops, its finished tasks kept.
    handlers = {signum: signal.signal(signum, log.interrupted) for signum in (signal.SIGINT, signal.SIGTERM)}

    from dask_jobqueue import SLURMCluster

    status = 1
    try:
        Path(options.log_dir).mkdir(parents=True, exist_ok=True)
        scheduler = {"plugins": [Progress()], "dashboard_address": f"{host or ''}:0"}
        if host:
            scheduler["host"] = host
        with SLURMCluster(job_cls=LoggedJob, scheduler_options=scheduler, **job_options(options)) as cluster:
            echo(f"scheduler {cluster.scheduler_address}, dashboard {cluster.dashboard_link}, "
                 f"jobs of {options.cores} cores, at most {options.max_jobs}")
            cluster.adapt(Adaptive=OneJobWaiting, minimum_jobs=0, maximum_jobs=options.max_jobs)
            status = work(cluster.scheduler_address)
    except KeyboardInterrupt:
        pass  # the status is the signal's, or the failed submission's
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # cancel the jobs even if Ctrl-C is pressed again
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        _cancel_left(log)
        if log.sbatch_error:
            echo(f"stopped: submitting a job failed: {log.sbatch_error}")
        elif log.signal:
            echo(f"interrupted ({signal.Signals(log.signal).name}); finished tasks are kept, "
                 f"continue with --resume")
        echo(f"jobs submitted: {len(log.submitted)}, tasks finished: {log.finished}, failed: {log.failed}")
        for signum, handler in handlers.items():
            signal.signal(signum, handler)
    if log.sbatch_error:
        return 1
    return 128 + log.signal if log.signal else status


class _Log:
    """Progress lines, and what the launcher needs to know of its jobs."""

    def __init__(self, every, task_lines, echo):
        self.every = every
        self.task_lines = task_lines
        self.line = echo
        self.finished = self.failed = 0
        self.submitted = []
        self.sbatch_error = None
        self.signal = None

    def interrupted(self, signum, frame):
        self.signal = signum
        raise KeyboardInterrupt

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
                    _thread.interrupt_main()  # the work waits in the main thread: stop it
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
