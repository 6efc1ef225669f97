"""``dlasweep slurm`` (dlasweep/sweep/slurm.py): its options without SLURM, then on a real one-node SLURM
(workflows/slurm_local.py).

The SLURM tests start the daemons once for the module (installing the packages
with apt where needed, as root) and skip, saying why, where that cannot be done.
Everything dask listens on is 127.0.0.1 (``--interface lo``). The launcher runs as
the installed ``dlasweep`` command in a process of its own, its stderr not a
terminal, so it writes progress lines.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import xarray as xr

import dlasweep as dla
from conftest import ROOT, science
from dlasweep.sweep import slurm as launcher
from dlasweep.sweep.spec import load_spec, parse_spec
from test_sweep import SLOW_SPEC, finished_clusters, wait_for


def _workflow(name):
    """A script of workflows/ as a module."""
    spec = importlib.util.spec_from_file_location(f"workflows_{name}", ROOT / "workflows" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


slurm_local = _workflow("slurm_local")

DLASWEEP = Path(sys.executable).with_name("dlasweep")
"""The installed command, beside this Python (a venv's bin/)."""

QUICK = ROOT / "dlasweep" / "sweep" / "specs" / "quick.toml"
TASKS = 8
"""SLOW_SPEC's dask tasks: eight clusters of 3e5, each worth more than one task's TASK_SECONDS."""

INTERRUPTED = "finished tasks are kept, continue with --resume"


# Without SLURM: options, wall time, the job script.

@pytest.mark.parametrize("text, seconds", [("90", 5400), ("1:30", 90), ("02:00:00", 7200), ("1-12", 129600),
                                           ("1-00:30", 88200), ("1-0:0:10", 86410), ("99:99:99", 362439)])
def test_walltime_reads_slurms_formats(text, seconds):
    """As SLURM's own ``time_str2secs`` reads them: it adds the fields up without bounding minutes or
    seconds to 59, so that 99:99:99 is 99 hours, 99 minutes and 99 seconds."""
    assert launcher.walltime_seconds(text) == seconds


@pytest.mark.parametrize("text", ["", "abc", "1:2:3:4", "-5", "1-", "2h"])
def test_walltime_refuses_other_text(text):
    with pytest.raises(launcher.OptionError, match="^walltime"):
        launcher.walltime_seconds(text)


def test_lifetime_ends_every_worker_before_its_walltime():
    assert launcher.lifetime(7200) == (6480, 360)  # 108 min, staggered by 6 min: out by 114 min of 120
    assert launcher.lifetime(600) == (510, 30)
    for walltime in range(launcher.MIN_WALLTIME, 3 * 86400, 97):
        life, stagger = launcher.lifetime(walltime)
        assert life - stagger > 0
        assert life + stagger <= walltime - max(launcher.RETIRE_SECONDS, walltime // 20)
    with pytest.raises(launcher.OptionError, match="too short"):
        launcher.lifetime(launcher.MIN_WALLTIME - 1)


@pytest.mark.parametrize("wanted, arrived, planned, busy, hold", [
    (0, 0, 0, False, 0),   # no work yet: no job (a refused sweep submits nothing)
    (10, 0, 0, True, 1),   # work for ten: one job first
    (10, 0, 1, True, 1),   # it waits in the queue: no second one, and it is not cancelled
    (10, 1, 1, True, 2),   # it runs: one more may wait
    (0, 1, 2, True, 2),    # dask wants fewer before task durations are known: the waiting job stays
    (0, 2, 2, True, 1),    # the work is done: idle workers may go, one stays
    (3, 0, 2, True, 2),    # both workers lost (scancel): both replaced
])
def test_jobs_to_hold_keeps_one_job_waiting_and_cancels_none(wanted, arrived, planned, busy, hold):
    assert launcher.jobs_to_hold(wanted, arrived, planned, busy) == hold


def test_help_lists_the_command_and_every_option(run_cli):
    status, out, _ = run_cli("--help")
    assert status == 0 and "slurm     run a sweep spec on SLURM" in out
    status, out, _ = run_cli("slurm", "--help")
    assert status == 0 and "pip install 'dlasweep[slurm]'" in out
    for field in dataclasses.fields(launcher.Options):
        assert f"--{field.name.replace('_', '-')} " in out


def test_dry_run_prints_the_job_script_and_starts_nothing(tmp_path, monkeypatch, run_cli):
    from distributed import Scheduler

    def no_scheduler(*args, **kwargs):
        raise AssertionError("a dry run started a scheduler")

    monkeypatch.setattr(Scheduler, "__init__", no_scheduler)
    monkeypatch.chdir(tmp_path)
    handler = signal.getsignal(signal.SIGINT)
    status, script, err = run_cli("slurm", QUICK, "--dry-run", "--cores", "4", "--memory", "3GB",
                                  "--walltime", "10:00", "--interface", "lo", "--sbatch=--qos=short",
                                  "--partition", "big", "--account", "dla", "--death-timeout", "30",
                                  "--local-directory", "/scratch/me", "--prologue", "module load gcc")
    assert status == 0 and err == ""
    assert signal.getsignal(signal.SIGINT) is handler  # dask-jobqueue's sys.exit() handler undone
    for line in ("#SBATCH -J dlasweep", "#SBATCH --cpus-per-task=4", "#SBATCH --mem=3G", "#SBATCH -t 10:00",
                 "#SBATCH -p big", "#SBATCH -A dla", "#SBATCH --qos=short",
                 f"#SBATCH --output={tmp_path.resolve()}/slurm-logs/slurm-%j.out"):
        assert line + "\n" in script
    assert "\nmodule load gcc\n" in script
    command = script.strip().splitlines()[-1]
    assert command.startswith(f"{sys.executable} -m distributed.cli.dask_worker tcp://127.0.0.1:PORT ")
    # One worker of four threads; it retires 8.5 +- 0.5 min into a 10 min job.
    for option in ("--nthreads 4", "--lifetime 510s --lifetime-stagger 30s", "--interface lo",
                   "--death-timeout 30", "--local-directory /scratch/me"):
        assert f" {option}" in command
    assert "--nworkers" not in command
    assert not any(tmp_path.iterdir())  # not even the log folder


@pytest.mark.parametrize("argv, message", [
    (["--walltime", "2h"], "dlasweep slurm: --walltime 2h: expected SLURM's format"),
    (["--walltime", "2"], "dlasweep slurm: --walltime: 120 s is too short"),
    (["--cores", "0"], "dlasweep slurm: --cores: 0 is below 1"),
    (["--max-jobs", "0"], "dlasweep slurm: --max-jobs: 0 is below 1"),
    (["--log-every", "0"], "dlasweep slurm: --log-every: 0 is below 1"),
    (["--death-timeout", "0"], "dlasweep slurm: --death-timeout: 0 is not positive"),
    (["--memory", "lots"], "dlasweep slurm: --memory lots: expected an amount like 16GB"),
    (["--interface", "nosuch0"], "dlasweep slurm: --interface nosuch0: no such network interface here"),
    (["--python", "/no/python"], "dlasweep slurm: --python /no/python: not an executable file"),
    (["-o", "out.txt"], "dlasweep slurm: -o out.txt: expected a file ending in .nc"),
    (["-o", "no/such/out.nc"], "dlasweep slurm: -o no/such/out.nc: folder no/such does not exist"),
    (["--frobnicate"], "dlasweep slurm: unrecognized arguments: --frobnicate"),
])
def test_bad_options_exit_2_with_one_line(argv, message, tmp_path, monkeypatch, run_cli):
    monkeypatch.chdir(tmp_path)
    status, out, err = run_cli("slurm", QUICK, "--dry-run", *argv)
    assert status == 2 and out == ""
    assert err.startswith(message) and err.count("\n") == 1, err
    assert not any(tmp_path.iterdir())


def test_a_bad_spec_exits_2(tmp_path, run_cli):
    spec = tmp_path / "bad.toml"
    spec.write_text("[grid]\nn_particles = [100]\nseeds = -1\n")
    status, _, err = run_cli("slurm", spec, "--dry-run")
    assert status == 2 and err.startswith("dlasweep slurm: ") and "seeds" in err and err.count("\n") == 1


def test_without_dask_jobqueue_one_line_names_the_extra(tmp_path):
    """The installed command, its import of dask_jobqueue made to fail (as where the extra is missing)."""
    site = tmp_path / "site"
    site.mkdir()
    (site / "sitecustomize.py").write_text("import sys\nsys.modules['dask_jobqueue'] = None  # import fails\n")
    run = tmp_path / "run"
    run.mkdir()
    done = subprocess.run([DLASWEEP, "slurm", QUICK, "--dry-run"], capture_output=True, text=True, cwd=run,
                          env=dict(os.environ, PYTHONPATH=site), timeout=120)
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr == "dlasweep slurm: needs dask-jobqueue: pip install 'dlasweep[slurm]'\n"
    assert not any(run.iterdir())


def test_slurm_is_not_started_without_root(monkeypatch):
    monkeypatch.setattr(os, "geteuid", lambda: 1000)
    assert slurm_local.unavailable_reason() == "starting SLURM's daemons needs root"
    with pytest.raises(slurm_local.SlurmUnavailable, match="needs root"):
        slurm_local.LocalSlurm().start()


# On a real one-node SLURM.

@pytest.fixture(scope="module")
def slurm():
    pytest.importorskip("dask_jobqueue", reason="the launcher needs dask-jobqueue: pip install 'dlasweep[slurm]'")
    reason = slurm_local.unavailable_reason()
    if reason:
        pytest.skip(f"no one-node SLURM here: {reason}")
    try:
        slurm_local.install()
    except slurm_local.SlurmUnavailable as err:
        # A mirror outage must not block the rest of the suite; the reason is shown.
        pytest.skip(f"no one-node SLURM here: {err}")
    with slurm_local.LocalSlurm() as cluster:
        yield cluster


@pytest.fixture
def queue(slurm):
    """The cluster, its queue emptied after the test."""
    yield slurm
    left = slurm.jobs("pending,running")
    if left:
        slurm.run("scancel", *left, check=False)


@pytest.fixture(scope="module")
def quick_reference():
    return science(dla.run_sweep(load_spec(QUICK)))


@pytest.fixture(scope="module")
def slow_reference():
    return science(dla.run_sweep(parse_spec(SLOW_SPEC)))


class Launcher:
    """``dlasweep slurm`` as a process of its own, its stdout and stderr in a file."""

    def __init__(self, slurm, folder: Path, spec, *options, name="launcher", path=None):
        self.out = folder / "out.nc"
        self.log = folder / f"{name}.log"
        env = dict(slurm.env)
        if path:
            env["PATH"] = f"{path}{os.pathsep}{env['PATH']}"
        argv = [DLASWEEP, "slurm", spec, "-o", self.out, "--cores", slurm.cpus,
                "--memory", "1GB", "--walltime", "10:00", "--interface", "lo", "--log-every", "1",
                "--log-dir", folder / "slurm-logs", *options]
        with open(self.log, "wb") as log:
            self.process = subprocess.Popen([str(a) for a in argv], stdout=log, stderr=subprocess.STDOUT,
                                            env=env, cwd=folder)

    def text(self) -> str:
        return self.log.read_text()

    def submitted(self) -> list:
        return re.findall(r"job (\d+) submitted", self.text())

    def finished_tasks(self) -> int:
        return len(re.findall(r"\d+ tasks finished", self.text()))

    def wait(self, timeout=180) -> int:
        try:
            return self.process.wait(timeout)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
            raise AssertionError(f"the launcher did not finish in {timeout} s:\n{self.text()}") from None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()


def held_jobs(slurm, ids) -> dict:
    """Of the given jobs, those SLURM still holds (pending or running), with their states."""
    return {job: state for job, state in slurm.jobs("pending,running").items() if job in ids}


def blocker(slurm, folder) -> str:
    """A job that takes every CPU of the node, so that the launcher's jobs wait."""
    done = slurm.run("sbatch", "--parsable", f"--cpus-per-task={slurm.cpus}", f"--chdir={folder}",
                     "--output=/dev/null", "--wrap=sleep 600")
    job = done.stdout.strip()
    wait_for(lambda: slurm.jobs("running").get(job) == "RUNNING", "the blocking job to run")
    return job


@pytest.mark.slow
def test_the_quick_spec_on_slurm_equals_the_embedded_run(queue, tmp_path, quick_reference):
    with Launcher(queue, tmp_path, QUICK) as run:
        assert run.wait() == 0, run.text()
    log = run.text()
    assert "out.nc: 16 clusters in" in log
    # Progress off a terminal: a line per finished task (--log-every 1), job and worker changes.
    assert run.finished_tasks() >= 1 and "tasks finished, 1 workers" in log
    assert re.search(r"scheduler tcp://127\.0\.0\.1:\d+, dashboard http://127\.0\.0\.1:\d+", log)
    assert re.search(r"worker SLURMCluster-0 started: tcp://127\.0\.0\.1:\d+, \d+ threads", log)
    assert not held_jobs(queue, run.submitted()), log
    first = run.submitted()[0]
    assert (tmp_path / "slurm-logs" / f"slurm-{first}.out").exists()
    with dla.open_sweep(run.out) as ds:
        xr.testing.assert_identical(science(ds), quick_reference)


@pytest.mark.slow
def test_a_cancelled_worker_job_is_replaced_and_the_sweep_finishes(queue, tmp_path, slow_reference):
    spec = tmp_path / "slow.toml"
    spec.write_text(SLOW_SPEC)
    with Launcher(queue, tmp_path, spec, "--max-jobs", "1", "--cores", "1") as run:  # one core: see the Ctrl-C test
        wait_for(lambda: run.finished_tasks() >= 1, "a first finished task", timeout=120)
        before = run.finished_tasks()
        queue.run("scancel", run.submitted()[0])
        assert run.wait() == 0, run.text()
    log = run.text()
    assert before < TASKS, f"the sweep ended before the scancel:\n{log}"
    # The same worker comes back in a new job.
    assert len(run.submitted()) >= 2 and log.count("worker SLURMCluster-0 started") >= 2, log
    assert not held_jobs(queue, run.submitted()), log
    with dla.open_sweep(run.out) as ds:
        xr.testing.assert_identical(science(ds), slow_reference)


@pytest.mark.slow
def test_a_queue_wait_submits_one_job_and_cancels_none(queue, tmp_path, quick_reference):
    block = blocker(queue, tmp_path)
    with Launcher(queue, tmp_path, QUICK, "--max-jobs", "10") as run:
        wait_for(lambda: run.submitted(), "a first job", timeout=60)
        time.sleep(10)  # churn was a cancel and a resubmission every 3 s
        waiting = run.submitted()
        assert len(waiting) == 1 and held_jobs(queue, waiting) == {waiting[0]: "PENDING"}, run.text()
        assert "scancel" not in run.text()
        queue.run("scancel", block)
        assert run.wait() == 0, run.text()
    assert not held_jobs(queue, run.submitted())
    with dla.open_sweep(run.out) as ds:
        xr.testing.assert_identical(science(ds), quick_reference)


@pytest.mark.slow
def test_sigterm_in_a_queue_wait_exits_143_and_cancels_the_waiting_job(queue, tmp_path):
    blocker(queue, tmp_path)
    with Launcher(queue, tmp_path, QUICK) as run:
        wait_for(lambda: run.submitted(), "a first job", timeout=60)
        run.process.send_signal(signal.SIGTERM)
        assert run.wait(60) == 143, run.text()
    log = run.text()
    assert f"interrupted (SIGTERM); {INTERRUPTED}" in log
    assert not held_jobs(queue, run.submitted()), log


@pytest.mark.slow
def test_ctrl_c_mid_sweep_exits_130_keeps_finished_tasks_and_resume_completes(queue, tmp_path, slow_reference):
    spec = tmp_path / "slow.toml"
    spec.write_text(SLOW_SPEC)
    # One core: the seven clusters after the first take about 10 s, not 5; with two, on CI's loaded
    # 2 cores, the Ctrl-C once landed after the sweep had ended.
    with Launcher(queue, tmp_path, spec, "--cores", "1") as run:
        wait_for(lambda: finished_clusters(run.out), "a first saved cluster", timeout=120)
        run.process.send_signal(signal.SIGINT)
        sent = time.strftime("%H:%M:%S")  # beside the log's times, should the sweep have ended first
        assert run.wait(60) == 130, run.text()
    assert f"interrupted (SIGINT); {INTERRUPTED}" in run.text()
    assert not held_jobs(queue, run.submitted()), run.text()
    kept = len(finished_clusters(run.out))
    assert 1 <= kept < TASKS, f"SIGINT sent at {sent}\n{run.text()}"

    with Launcher(queue, tmp_path, spec, "--resume", name="resumed") as resumed:
        assert resumed.wait() == 0, resumed.text()
    # Only what was missing is computed (one cluster per task).
    assert re.search(rf"tasks finished: {TASKS - kept}, failed: 0", resumed.text()), resumed.text()
    with dla.open_sweep(run.out) as ds:
        xr.testing.assert_identical(science(ds), slow_reference)


@pytest.mark.parametrize("argv, message", [
    (["--cores", "99"], "--cores 99: partition debug has at most {cpus} CPUs per node"),
    (["--partition", "nosuch"], "--partition nosuch: no such partition (sinfo)"),
    (["--memory", "100TB"], "--memory 100TB: partition debug has at most"),
    (["--sbatch=--constraint=nosuch"], "sbatch refuses the job: allocation failure: Invalid feature specification"),
])
def test_options_beyond_the_partition_exit_2_and_submit_nothing(argv, message, queue, tmp_path):
    before = queue.jobs()
    with Launcher(queue, tmp_path, QUICK, *argv) as run:
        assert run.wait(60) == 2
    line = run.text()
    assert line.startswith(f"dlasweep slurm: {message.format(cpus=queue.cpus)}") and line.count("\n") == 1, line
    assert queue.jobs() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["launcher.log"]


@pytest.mark.slow
def test_a_failing_sbatch_stops_the_launcher_with_exit_1(queue, tmp_path):
    """sbatch that passes the up-front ``--test-only`` check, then fails (a full queue, a lost controller)."""
    shim = tmp_path / "bin"
    shim.mkdir()
    (shim / "sbatch").write_text(f"""#!/bin/sh
case "$1" in --test-only) exec {queue.run("which", "sbatch").stdout.strip()} "$@";; esac
echo "sbatch: error: Batch job submission failed: simulated" >&2
exit 1
""")
    (shim / "sbatch").chmod(0o755)
    with Launcher(queue, tmp_path, QUICK, path=shim) as run:
        assert run.wait(60) == 1, run.text()
    assert "stopped: submitting a job failed: sbatch: error: Batch job submission failed: simulated" in run.text()
    assert "jobs submitted: 0" in run.text()
