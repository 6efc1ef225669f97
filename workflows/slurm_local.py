"""A one-node SLURM on this machine, for the tests and for trying the launcher.

    python workflows/slurm_local.py          # start it; prints SLURM_CONF; Ctrl-C stops it

Installs Debian's ``slurm-wlm`` and ``munge`` with apt when they are missing
(as root), writes ``slurm.conf`` (one node with this machine's CPUs,
``proctrack/linuxproc``, ``task/none``, ``select/cons_tres``) and a munge
key into a temporary folder, starts ``munged``, ``slurmctld`` and ``slurmd``
in the foreground as child processes, and stops them by their PIDs. Client
commands (``sbatch``, ``squeue``, ``scancel``, ``sinfo``) find this cluster
through ``SLURM_CONF``. The daemons use free ports chosen at start, so the
cluster does not clash with another one on the machine; SLURM has no option
to bind its daemons to one address, so they listen on every interface,
with munge authenticating every message.

From Python::

    with LocalSlurm() as slurm:     # raises SlurmUnavailable with the reason
        subprocess.run(["sinfo"], env=slurm.env)
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PACKAGES = ("slurm-wlm", "munge")
DAEMONS = ("munged", "slurmctld", "slurmd")
COMMANDS = ("sbatch", "squeue", "scancel", "sinfo")
PARTITION = "debug"
START_SECONDS = 60
STOP_SECONDS = 15

CONF = """\
ClusterName=dlasweep
SlurmctldHost={host}(127.0.0.1)
SlurmctldPort={ctld_port}
SlurmdPort={slurmd_port}
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={munge_socket}
SlurmUser=root
SlurmdUser=root
StateSaveLocation={root}/state
SlurmdSpoolDir={root}/spool
SlurmctldPidFile={root}/slurmctld.pid
SlurmdPidFile={root}/slurmd.pid
SlurmctldLogFile={root}/slurmctld.log
SlurmdLogFile={root}/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc={root}/jobcomp.txt
MpiDefault=none
ReturnToService=2
MailProg=/bin/true
KillWait=5
MinJobAge=600
NodeName={host} NodeAddr=127.0.0.1 CPUs={cpus} RealMemory={memory_mb} State=UNKNOWN
PartitionName={partition} Nodes={host} Default=YES MaxTime=INFINITE State=UP
"""
"""``slurm.conf``: ``JobCompType=jobcomp/filetxt`` logs every ended job (``ended_jobs``),
since there is no accounting database for ``sacct``; ``MinJobAge`` keeps ended jobs
in ``squeue --states=all`` for ten minutes."""


class SlurmUnavailable(RuntimeError):
    """SLURM cannot be started here; the message says why, in one line."""


def unavailable_reason() -> str | None:
    """Why a one-node SLURM cannot be started here (None: it can), without installing anything."""
    if not sys.platform.startswith("linux"):
        return f"SLURM needs Linux, this is {sys.platform}"
    if os.geteuid() != 0:
        return "starting SLURM's daemons needs root"
    if _missing() and shutil.which("apt-get") is None:
        return f"{', '.join(_missing())} not installed and no apt-get to install {' '.join(PACKAGES)}"
    return None


def _missing() -> list:
    return [name for name in (*DAEMONS, *COMMANDS) if _which(name) is None]


def _which(name) -> str | None:
    # The daemons live in /usr/sbin, which a user's PATH may lack.
    return shutil.which(name) or shutil.which(name, path="/usr/sbin:/sbin")


def install():
    """Install ``slurm-wlm`` and ``munge`` with apt when a command of theirs is missing."""
    if not _missing():
        return
    if unavailable_reason():
        raise SlurmUnavailable(unavailable_reason())
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    for command in (["apt-get", "update", "-q"],
                    ["apt-get", "install", "-y", "-q", "--no-install-recommends", *PACKAGES]):
        done = subprocess.run(command, check=False, env=env, capture_output=True, text=True)
        if done.returncode:
            raise SlurmUnavailable(f"{' '.join(command)} failed: {_last_line(done.stderr or done.stdout)}")
    if _missing():
        raise SlurmUnavailable(f"{', '.join(_missing())} still missing after installing {' '.join(PACKAGES)}")


class LocalSlurm:
    """A one-node SLURM in a temporary folder, started and stopped as a context manager.

    Parameters
    ----------
    cpus : int, optional
        CPUs of the node (default: this machine's).
    root : path, optional
        Folder for the configuration, keys, state and logs (default: a new
        temporary folder, removed at the end).

    Attributes
    ----------
    env : dict
        ``os.environ`` with ``SLURM_CONF`` pointing to this cluster.
    partition, cpus : str, int
        The one partition and its CPUs.
    """

    def __init__(self, cpus=None, root=None):
        self.cpus = cpus or os.cpu_count() or 1
        self.partition = PARTITION
        self._given_root = root
        self.root = None
        self.env = None
        self._daemons = {}

    def __enter__(self):
        self.start()
        return self

    def __exit__(self, *exc):
        self.stop()

    def start(self):
        """Install when needed, write the configuration, start the daemons, wait for an idle node."""
        reason = unavailable_reason()
        if reason:
            raise SlurmUnavailable(reason)
        install()
        self.root = Path(self._given_root or tempfile.mkdtemp(prefix="dlasweep-slurm-")).resolve()
        try:
            self._start()
        except BaseException:
            self.stop()
            raise

    def _start(self):
        root = self.root
        for folder in ("state", "spool", "munge"):
            (root / folder).mkdir(parents=True, exist_ok=True)
        os.chmod(root, 0o755)  # munged refuses a socket folder that others may write
        key = root / "munge" / "munge.key"
        key.write_bytes(os.urandom(1024))
        os.chmod(key, 0o400)
        munge_socket = root / "munge" / "munge.socket"
        host = socket.gethostname().split(".")[0]
        conf = root / "slurm.conf"
        conf.write_text(CONF.format(host=host, root=root, munge_socket=munge_socket, cpus=self.cpus,
                                    memory_mb=_memory_mb(), partition=self.partition,
                                    ctld_port=_free_port(), slurmd_port=_free_port()))
        self.env = dict(os.environ, SLURM_CONF=str(conf))

        self._launch("munged", [_which("munged"), "--foreground", "--force", f"--socket={munge_socket}",
                                f"--key-file={key}", f"--pid-file={root}/munge/munged.pid",
                                f"--log-file={root}/munge/munged.log", f"--seed-file={root}/munge/seed"])
        self._wait(lambda: munge_socket.exists(), "munged", root / "munge" / "munged.log")
        self._launch("slurmctld", [_which("slurmctld"), "-D", "-i", "-f", str(conf)])
        self._launch("slurmd", [_which("slurmd"), "-D", "-N", host, "-f", str(conf)])
        self._wait(self._idle, "slurmd", root / "slurmd.log")

    def _launch(self, name, command):
        with open(self.root / f"{name}.out", "ab") as log:
            # A session of its own: a Ctrl-C meant for the caller does not reach the daemons.
            self._daemons[name] = subprocess.Popen(command, env=self.env, stdin=subprocess.DEVNULL,
                                                   stdout=log, stderr=subprocess.STDOUT,
                                                   start_new_session=True)

    def _wait(self, ready, name, log: Path):
        deadline = time.monotonic() + START_SECONDS
        while not ready():
            dead = [n for n, p in self._daemons.items() if p.poll() is not None]
            if dead or time.monotonic() > deadline:
                why = f"{dead[0]} exited" if dead else f"{name} not ready after {START_SECONDS} s"
                tail = log.read_text(errors="replace") if log.exists() else ""
                raise SlurmUnavailable(f"{why}: {_last_line(tail)} (logs in {self.root})")
            time.sleep(0.2)

    def _idle(self) -> bool:
        state = self.run("sinfo", "--noheader", "--format=%t", check=False)
        return state.returncode == 0 and state.stdout.split() == ["idle"]

    def run(self, *command, check=True) -> subprocess.CompletedProcess:
        """Run a SLURM client command (``squeue``, ``scancel``, ...) against this cluster."""
        return subprocess.run([_which(command[0]) or command[0], *command[1:]], env=self.env,
                              capture_output=True, text=True, check=check, timeout=30)

    def jobs(self, states="all") -> dict:
        """Job id -> state of the jobs ``squeue`` knows (ended ones for ``MinJobAge``)."""
        listed = self.run("squeue", "--noheader", f"--states={states}", "--format=%i %T")
        return dict(line.split() for line in listed.stdout.splitlines())

    def ended_jobs(self) -> list:
        """One dict per ended job, from the job completion log (``JobId``, ``JobState``, ...)."""
        log = self.root / "jobcomp.txt"
        lines = log.read_text().splitlines() if log.exists() else []
        return [dict(field.split("=", 1) for field in line.split() if "=" in field) for line in lines]

    def stop(self):
        """Cancel every job, then stop the daemons by their PIDs; remove a temporary folder."""
        if "slurmd" in self._daemons and self._daemons["slurmd"].poll() is None:
            self.run("scancel", "--full", *self.jobs("pending,running,completing"), check=False)
            deadline = time.monotonic() + STOP_SECONDS
            while self.jobs("pending,running,completing") and time.monotonic() < deadline:
                time.sleep(0.3)
        for name in reversed(DAEMONS):
            process = self._daemons.pop(name, None)
            if process is None:
                continue
            process.send_signal(signal.SIGTERM)
            try:
                process.wait(STOP_SECONDS)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        if self._given_root is None and self.root is not None:
            shutil.rmtree(self.root, ignore_errors=True)


def _memory_mb() -> int:
    # Below the total: slurmd drains a node that has less memory than slurm.conf claims.
    with open("/proc/meminfo") as info:
        total_kb = int(next(line for line in info if line.startswith("MemTotal")).split()[1])
    return int(total_kb / 1024 * 0.9)


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _last_line(text) -> str:
    lines = [line for line in text.splitlines() if line.strip()]
    return lines[-1].strip() if lines else "no output"


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cpus", type=int, help="CPUs of the node (default: this machine's)")
    parser.add_argument("--dir", type=Path, help="folder for configuration, state and logs (default: temporary)")
    args = parser.parse_args(argv)
    if args.cpus is not None and args.cpus < 1:
        print(f"slurm_local.py: --cpus: {args.cpus} is below 1", file=sys.stderr)
        return 2
    # Stop the daemons on SIGTERM as on Ctrl-C, also where SIGINT came in ignored (a shell's `&`).
    signal.signal(signal.SIGINT, _interrupt)
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        with LocalSlurm(cpus=args.cpus, root=args.dir) as slurm:
            print(f"one-node SLURM running: partition {slurm.partition}, {slurm.cpus} CPUs, files in {slurm.root}\n"
                  f"in another shell: export SLURM_CONF={slurm.env['SLURM_CONF']}\n"
                  f"Ctrl-C stops it", flush=True)
            while all(p.poll() is None for p in slurm._daemons.values()):
                time.sleep(1)
            print("slurm_local.py: a daemon exited; stopping", file=sys.stderr)
            return 1
    except SlurmUnavailable as err:
        print(f"slurm_local.py: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("slurm_local.py: stopped", file=sys.stderr)
        return 0


if __name__ == "__main__":
    raise SystemExit(main())
