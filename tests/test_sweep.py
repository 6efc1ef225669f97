"""Sweeps: results equal direct growth, do not depend on workers, survive interruption."""

import contextlib
import errno
import functools
import gc
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import dask
import numpy as np
import pytest
import xarray as xr
from distributed import Client, LocalCluster

import dlasweep as dla
from conftest import TINY_SPEC, Interrupt, files_under, finished_clusters, interrupt_after, progress_lines, science
from dlasweep.data import netcdf as store
from dlasweep.data import ragged, schema
from dlasweep.measures import boxes
from dlasweep.measures import shape as measure
from dlasweep.sweep import progress, session
from dlasweep.sweep import runner as sweep
from dlasweep.sweep import task as worker
from dlasweep.sweep.parts import Parts, ResumeError
from dlasweep.sweep.spec import parse_spec


def test_clusters_and_measures_equal_direct_growth(reference):
    spec = parse_spec(TINY_SPEC)
    for k, task in enumerate(spec.tasks()):
        seed = np.random.SeedSequence(spec.root_seed, spawn_key=task.spawn_key)
        cluster = dla.grow(max(spec.counts), seed, **task.params)
        np.testing.assert_array_equal(ragged.cluster_points(reference, k), cluster.points)
        np.testing.assert_array_equal(ragged.cluster_parents(reference, k), cluster.parents)
        cell = reference.isel(dict(zip(["stickiness", "size", "seed"], task.index)))
        for j, n in enumerate(spec.counts):
            m = min(n, cluster.n)
            at = cell.isel(n_particles=j)
            assert int(at["n_grown"]) == m
            assert int(at["walk_steps"]) == cluster.steps[:m].sum()
            assert float(at["radius_gyration"]) == measure.radius_of_gyration(cluster.points)[m - 1]
            np.testing.assert_equal(float(at["anisotropy"]), measure.anisotropy(cluster.points, [m])[0])
            _, counts = boxes.box_counts(cluster.points[:m], scales=reference["scale"].values)
            np.testing.assert_array_equal(at["box_count"].values, counts)
            ok = schema.STATUS_FLAGS[int(at["status"])] == "ok"
            assert ok == (m == n) and (ok or cluster.status != "ok")


def test_scale_axis_is_trimmed_to_the_clusters(reference):
    scales = reference["scale"].values
    assert scales[0] == 1.0 and np.all(np.diff(scales) > 0)
    top = reference["box_count"].isel(scale=-1)
    assert (top == 1).all() and not (reference["box_count"].isel(scale=-2) == 1).all()


def test_one_worker_gives_the_same_results(reference):
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=":0") as lc:
        with Client(lc) as client:
            alone = dla.run_sweep(parse_spec(TINY_SPEC), client=client)
    xr.testing.assert_identical(science(alone), science(reference))


def record_writes(monkeypatch):
    """The keys of the clusters saved, in order."""
    written = []
    real_write = Parts.write
    monkeypatch.setattr(Parts, "write",
                        lambda self, results: (written.extend(results), real_write(self, results)))
    return written


def batches_of(monkeypatch, size):
    """Make every dask task a batch of ``size`` clusters (the last one: what is left)."""
    monkeypatch.setattr(sweep, "_batches",
                        lambda todo, _, threads: (todo[i:i + size] for i in range(0, len(todo), size)))


def test_the_batch_size_follows_the_counts():
    def size(counts, seeds):
        spec = parse_spec(f"[grid]\nn_particles = {counts}\nseeds = {seeds}\n")
        return sweep._batch_size(spec, seeds, 2)

    # About TASK_SECONDS of work per dask task, and at least four of them per thread.
    assert (size([100, 1000], 1000), size([1000, 10000], 64), size([10000, 100000], 32)) == (83, 8, 1)
    assert size([100, 1000], 40) == 5 and size([10], 7) == 1


def test_batches_shrink_near_the_end_so_that_the_threads_finish_together():
    todo = list(range(1000))
    batches = list(sweep._batches(todo, 83, 2))
    sizes = [len(b) for b in batches]
    assert sum(batches, []) == todo and sizes[:8] == [83] * 8 and sizes[-1] == 1
    assert all(a >= b for a, b in zip(sizes, sizes[1:]))
    # each batch at most what is left over 2 x threads, once that is below the size
    left = np.cumsum(sizes[::-1])[::-1]
    assert all(n <= max(1, min(83, rest // 4)) for n, rest in zip(sizes, left))
    assert [len(b) for b in sweep._batches(list(range(5)), 8, 1)] == [2, 1, 1, 1]


def test_batches_give_the_same_results(reference, dask_client, monkeypatch):
    parts = []
    real_write = Parts.write
    monkeypatch.setattr(Parts, "write",
                        lambda self, results: (parts.append(len(results)), real_write(self, results)))
    batches_of(monkeypatch, 5)
    ds = dla.run_sweep(parse_spec(TINY_SPEC), client=dask_client)
    assert sorted(parts) == [2, 5, 5]
    xr.testing.assert_identical(science(ds), science(reference))


@pytest.mark.parametrize("before, after", [(1, 1), (3, 2)])
def test_resume_computes_only_what_is_missing(before, after, tmp_path, dask_client, reference, monkeypatch):
    out = tmp_path / "tiny.nc"
    spec = parse_spec(TINY_SPEC)
    batches_of(monkeypatch, before)
    first = interrupt_after(monkeypatch, 5)
    with pytest.raises(Interrupt):
        dla.run_sweep(spec, client=dask_client, out=out)
    assert not out.exists() and sorted(finished_clusters(out)) == sorted(first)
    assert len(first) == 5 - 5 % before
    monkeypatch.undo()
    with pytest.raises(ResumeError, match="--resume"):
        dla.run_sweep(spec, client=dask_client, out=out)
    batches_of(monkeypatch, after)
    second = record_writes(monkeypatch)
    resumed = dla.run_sweep(spec, client=dask_client, out=out, resume=True)
    assert sorted(first + second) == sorted(t.key for t in spec.tasks())
    xr.testing.assert_identical(science(resumed), science(reference))
    assert not out.with_name("tiny.nc.parts").exists()
    resumed.close()


@pytest.mark.parametrize("size", [1, 5])
def test_a_raising_task_is_recorded_and_retried_on_resume(size, tmp_path, dask_client, reference, monkeypatch,
                                                          replicate_1_fails):
    out = tmp_path / "tiny.nc"
    batches_of(monkeypatch, size)  # 5: failed and finished clusters share parts
    with pytest.warns(RuntimeWarning, match="4 of 12 tasks failed"):
        ds = dla.run_sweep(parse_spec(TINY_SPEC), client=dask_client, out=out)
    error = schema.STATUS_FLAGS.index("error")
    assert (ds["status"].sel(seed=1) == error).all() and (ds["status"].sel(seed=[0, 2]) != error).all()
    assert "task-0-0-1: RuntimeError: simulated failure" in ds.attrs["failed_tasks"]
    assert ds["cluster_particles"].values.reshape(2, 2, 3)[..., 1].sum() == 0
    ds.close()
    monkeypatch.undo()
    batches_of(monkeypatch, size)
    retried = record_writes(monkeypatch)
    healed = dla.run_sweep(parse_spec(TINY_SPEC), client=dask_client, out=out, resume=True)
    assert sorted(retried) == ["task-0-0-1", "task-0-1-1", "task-1-0-1", "task-1-1-1"]
    xr.testing.assert_identical(science(healed), science(reference))
    healed.close()


class _Lost:
    """A future whose worker died after its result was gathered: dask marks it "lost" and computes it again."""
    status = "lost"

    def __init__(self, future):
        self.key, self.release = future.key, future.release


def test_a_result_gathered_before_its_worker_died_is_kept(tmp_path, dask_client, reference, monkeypatch):
    import distributed

    class losing(distributed.as_completed):
        def __next__(self):
            future, results = super().__next__()
            return _Lost(future), results

    monkeypatch.setattr(distributed, "as_completed", losing)
    ds = dla.run_sweep(parse_spec(TINY_SPEC), client=dask_client, out=tmp_path / "t.nc")
    assert "failed_tasks" not in ds.attrs
    xr.testing.assert_identical(science(ds), science(reference))
    ds.close()


def test_clusters_go_into_the_file_while_the_sweep_runs(tmp_path, dask_client, monkeypatch, reference):
    # Chunks of 16 values, tasks of one cluster: each finished cluster fills chunks at once.
    monkeypatch.setattr(store, "PARTICLE_CHUNK", 16)
    batches_of(monkeypatch, 1)
    written, feed = [], sweep._Stream.feed

    def fed(self, done=()):
        feed(self, done)
        written.append(self.writer.written)

    monkeypatch.setattr(sweep._Stream, "feed", fed)
    ds = dla.run_sweep(parse_spec(TINY_SPEC), client=dask_client, out=tmp_path / "t.nc")
    assert len(written) == 13 and written == sorted(written) and written[5] > 0
    xr.testing.assert_identical(science(ds), science(reference))
    ds.close()
    assert files_under(tmp_path) == {Path("t.nc")}


def test_a_sweep_lists_its_tasks_once(tmp_path, dask_client, monkeypatch, reference):
    """The grid is listed once, not once each for the work to do, the file's stream, the dataset, its stored
    clusters and the clusters read back: 15 s a listing at ``spec.MAX_TASKS`` clusters."""
    from dlasweep.sweep.spec import Spec

    listings, tasks = [], Spec.tasks

    def listed(self, replicates=None):
        listings.extend([self.name] if replicates is None else [])
        return tasks(self, replicates)

    monkeypatch.setattr(Spec, "tasks", listed)
    for out in (tmp_path / "t.nc", None):
        listings.clear()
        ds = dla.run_sweep(parse_spec(TINY_SPEC), client=dask_client, out=out)
        assert len(listings) == 1
        xr.testing.assert_identical(science(ds), science(reference))
        ds.close()


def test_the_embedded_cluster_shortens_the_switch_interval_and_restores_it(monkeypatch):
    before, during = sys.getswitchinterval(), []
    growth_counts = worker.growth_counts

    def counted(counts):  # called by each task, in the worker's thread (a module global: not pickled)
        during.append(sys.getswitchinterval())
        return growth_counts(counts)

    monkeypatch.setattr(worker, "growth_counts", counted)
    dla.run_sweep(parse_spec("[grid]\nn_particles = [5]\nseeds = 2\n"), workers=1)
    assert session.SWITCH_INTERVAL in during and sys.getswitchinterval() == before != session.SWITCH_INTERVAL


def test_the_embedded_cluster_has_its_kernels_loaded_before_the_first_task(monkeypatch):
    threads = []
    growth_counts = worker.growth_counts

    def recorded(counts):  # called once by each batch of tasks (a module global: not pickled)
        threads.append(threading.current_thread().name)
        return growth_counts(counts)

    monkeypatch.setattr(worker, "growth_counts", recorded)
    ds = dla.run_sweep(parse_spec("[grid]\nn_particles = [5, 50]\nseeds = 3\n"), workers=1)
    assert threads[0] == "dlasweep-load" and "dlasweep-load" not in threads[1:] and len(threads) > 1
    assert (ds["n_grown"].values == [[5] * 3, [50] * 3]).all()


def test_submission_is_batched(dask_client, monkeypatch):
    """The client holds a bounded window of tasks, however many the sweep has."""
    spec = parse_spec("[grid]\nn_particles = [1]\nseeds = 250\n")
    batches_of(monkeypatch, 1)
    in_flight, peak = [0], [0]
    real_submit, real_write = dask_client.submit, Parts.write

    def submit(*args, **kwargs):
        in_flight[0] += 1
        peak[0] = max(peak[0], in_flight[0])
        return real_submit(*args, **kwargs)

    def write(self, results):
        in_flight[0] -= 1
        real_write(self, results)

    monkeypatch.setattr(dask_client, "submit", submit)
    monkeypatch.setattr(Parts, "write", write)
    ds = dla.run_sweep(spec, client=dask_client)
    assert peak[0] == 100 and ds.sizes["cluster"] == 250 and (ds["n_grown"] == 1).all()


def test_early_stops_keep_their_status(dask_client):
    spec = parse_spec(TINY_SPEC.replace("dim = 2", "dim = 2\nmax_steps = 300"))
    ds = dla.run_sweep(spec, client=dask_client)
    for k, task in enumerate(spec.tasks()):
        cluster = dla.grow(max(spec.counts), np.random.SeedSequence(spec.root_seed, spawn_key=task.spawn_key),
                           **task.params)
        final = ds.isel({**dict(zip(["stickiness", "size", "seed"], task.index)), "n_particles": -1})
        assert schema.STATUS_FLAGS[int(final["status"])] == cluster.status
        assert int(final["n_grown"]) == int(ds["cluster_particles"][k]) == cluster.n
        # a count never reached is given the whole growth's seconds, which are at least those to any count
        seconds = ds["wall_time"].isel(dict(zip(["stickiness", "size", "seed"], task.index))).values
        assert (seconds > 0).all() and (np.diff(seconds) >= 0).all()
    assert (ds["status"] == schema.STATUS_FLAGS.index("step_limit")).any()


def test_an_unreachable_scheduler_leaves_nothing(tmp_path):
    with (dask.config.set({"distributed.comm.timeouts.connect": "1s"}),
          pytest.raises(OSError, match="tcp://127.0.0.1:1")):
        dla.run_sweep(parse_spec(TINY_SPEC), client="tcp://127.0.0.1:1", out=tmp_path / "x.nc")
    assert files_under(tmp_path) == set()


def test_a_full_disk_exits_1_keeping_the_parts_and_resume_completes(run_cli, write_spec, tmp_path, dask_cluster,
                                                                      reference, monkeypatch):
    out, address = tmp_path / "tiny.nc", dask_cluster.scheduler_address
    real_write = Parts.write

    def write(self, results):
        if len(finished_clusters(out)) == 5:
            raise OSError(errno.ENOSPC, "No space left on device")
        real_write(self, results)

    monkeypatch.setattr(Parts, "write", write)
    status, _, err = run_cli("sweep", write_spec(), "-o", out, "--scheduler", address)
    assert status == 1 and err.strip().splitlines()[1:] == [  # after the plan
        "dlasweep sweep: failed: OSError: [Errno 28] No space left on device"]
    assert len(finished_clusters(out)) == 5 and not out.exists()
    monkeypatch.undo()
    status, _, err = run_cli("sweep", write_spec(), "-o", out, "--resume", "--scheduler", address)
    assert status == 0, err
    with dla.open_sweep(out) as ds:
        xr.testing.assert_identical(science(ds), science(reference))
    assert not Path(f"{out}.parts").exists()


def test_each_model_and_dimension_swept_is_a_kernel_of_its_own():
    """The kernels are compiled per dimension (``dlasweep._jit``) and apart for lockstep walkers
    (``kernels.model.lockstep_flag``), and off the lattice for Gaussian steps (``kernels.model.gaussian_flag``):
    each (model, dim, lockstep, gaussian) swept is loaded (``precompile.load_kernels``) and looked up in the cache
    (``_cold_kernels``) on its own."""
    spec = parse_spec("name = 'dims'\n[grid]\nn_particles = [5]\nseeds = 2\nsize = [40]\n"
                      "[model]\nmodel = ['lattice', 'offlattice']\ndim = [2, 3]\nwalkers = [1, 3, 5]\n")
    kernels = sweep.first_task_of_each_kernel(spec)
    assert sorted(kernels) == [(model, dim, lockstep, False) for model in ("lattice", "offlattice")
                               for dim in (2, 3) for lockstep in (False, True)]
    assert all((task.params["model"], task.params["dim"], task.params["walkers"] > 1, False) == key
               for key, task in kernels.items())
    stepped = parse_spec("name = 'steps'\n[grid]\nn_particles = [5]\nseeds = 2\n"
                         "[model]\nmodel = 'offlattice'\nstep = [0.0, 0.5, 1.0]\n")
    assert sorted(sweep.first_task_of_each_kernel(stepped)) == [("offlattice", 2, False, gaussian)
                                                                 for gaussian in (False, True)]


def test_a_spec_of_lockstep_walkers_compiles_when_only_one_walkers_kernel_is_cached(monkeypatch):
    monkeypatch.setattr(sweep, "compiled", lambda params: params["walkers"] == 1)
    one = parse_spec("name = 'one'\n[grid]\nn_particles = [5]\nseeds = 1\nsize = [40]\n[model]\nwalkers = [1]\n")
    many = parse_spec("name = 'many'\n[grid]\nn_particles = [5]\nseeds = 1\nsize = [40]\n[model]\nwalkers = [1, 3]\n")
    assert sweep._cold_kernels(one) == [] and sweep._cold_kernels(many) == [("lattice", 2, True, False)]


def test_a_cold_kernel_cache_is_announced_on_a_terminal(tmp_path, monkeypatch, capsys):
    spec = parse_spec(TINY_SPEC)
    code = ("import sys, dlasweep.sweep.runner as s, dlasweep.sweep.spec as p; "
            "print(bool(s._cold_kernels(p.parse_spec(sys.argv[1]))))")
    cold = subprocess.run([sys.executable, "-c", code, TINY_SPEC], capture_output=True, text=True, check=True,
                          env={**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)})
    dla.grow(20, 0, model="lattice")  # compiles into the cache, if it is not there yet
    assert cold.stdout == "True\n" and not sweep._cold_kernels(spec)
    cold_kernels = [("lattice", 2, False, False), ("lattice", 3, True, False)]
    monkeypatch.setattr(sweep, "_cold_kernels", lambda spec: cold_kernels)
    dla.run_sweep(parse_spec("name = 'cold'\n[grid]\nn_particles = [5]\nseeds = 1\n"), progress=True)
    notice = "compiling the lattice 2D and lattice 3D lockstep kernels, once: one to two minutes each\n"
    assert capsys.readouterr().err.startswith(f"cold: {notice}")
    monkeypatch.setattr(sys.stderr, "isatty", lambda: False)  # a log: the sweep's lines, the notice first
    dla.run_sweep(parse_spec("name = 'logged'\n[grid]\nn_particles = [5]\nseeds = 1\n"))
    assert capsys.readouterr().err.startswith(f"logged: {notice}")


# Real processes: an external scheduler and workers, kill -9, resume.

BIN = Path(sys.executable).parent
SLOW_SPEC = """\
name = "slow"
[grid]
n_particles = [1000, 300000]
seeds = 8
[run]
root_seed = 5
"""
"""Eight clusters of about 1.3 s each: after a test sees the first one finished, the sweep still has
seconds to run (on 2 threads), so a kill or a Ctrl-C then lands mid-sweep. With clusters of 1e5 (0.4 s)
the whole sweep once finished before the signal arrived on a loaded CI machine."""


def spawn(*argv, log):
    """Start a command in a session of its own (so that killpg reaches all its processes)."""
    with open(log, "wb") as output:
        return subprocess.Popen([str(a) for a in argv], stdout=output, stderr=subprocess.STDOUT,
                                start_new_session=True, cwd=log.parent)


def wait_for(condition, what, timeout=60.0):
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise TimeoutError(f"waited {timeout} s for {what}")
        time.sleep(0.05)


def start_worker(scheduler_file, log):
    worker = spawn(BIN / "dask", "worker", "--scheduler-file", scheduler_file, "--nthreads", "1",
                   "--host", "127.0.0.1", "--no-dashboard", log=log)
    wait_for(lambda: b"Registered to" in log.read_bytes(), "a worker to register")
    return worker


@pytest.fixture(scope="module")
def external_scheduler(tmp_path_factory):
    """A real ``dask scheduler`` and one ``dask worker`` process on 127.0.0.1; yields the scheduler file."""
    folder = tmp_path_factory.mktemp("external")
    scheduler_file = folder / "scheduler.json"
    processes = [spawn(BIN / "dask", "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                       "--scheduler-file", scheduler_file, log=folder / "scheduler.log")]
    try:
        wait_for(scheduler_file.exists, "the scheduler file")
        processes.append(start_worker(scheduler_file, folder / "worker.log"))
        yield scheduler_file
    finally:
        for process in processes:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(process.pid, signal.SIGKILL)
            process.wait()


@pytest.fixture(scope="module")
def slow_reference(dask_client):
    return science(dla.run_sweep(parse_spec(SLOW_SPEC), client=dask_client))


@pytest.fixture
def slow_spec(tmp_path):
    path = tmp_path / "slow.toml"
    path.write_text(SLOW_SPEC)
    return path


@pytest.mark.slow
def test_a_killed_worker_loses_nothing(external_scheduler, slow_spec, slow_reference, tmp_path):
    extra = start_worker(external_scheduler, tmp_path / "extra-worker.log")
    out = tmp_path / "slow.nc"
    run = spawn(BIN / "dlasweep", "sweep", slow_spec, "-o", out, "--scheduler-file", external_scheduler,
                log=tmp_path / "sweep.log")
    try:
        wait_for(lambda: finished_clusters(out), "a first finished task")
        os.killpg(extra.pid, signal.SIGKILL)
        assert run.wait(timeout=120) == 0, (tmp_path / "sweep.log").read_text()
    finally:
        for process in (extra, run):
            with contextlib.suppress(ProcessLookupError):
                os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    with dla.open_sweep(out) as ds:
        xr.testing.assert_identical(science(ds), slow_reference)


@pytest.mark.slow
def test_resume_after_kill_9(external_scheduler, slow_spec, slow_reference, tmp_path, run_cli):
    out = tmp_path / "slow.nc"
    run = spawn(BIN / "dlasweep", "sweep", slow_spec, "-o", out, "--scheduler-file", external_scheduler,
                log=tmp_path / "sweep.log")
    try:
        wait_for(lambda: len(finished_clusters(out)) >= 2, "two finished tasks")
    finally:
        os.killpg(run.pid, signal.SIGKILL)
        run.wait()
    assert 2 <= len(finished_clusters(out)) < 8 and not out.exists()
    address = json.loads(external_scheduler.read_text())["address"]
    status, _, err = run_cli("sweep", slow_spec, "-o", out, "--resume", "--scheduler", address)
    assert status == 0, err
    with dla.open_sweep(out) as ds:
        xr.testing.assert_identical(science(ds), slow_reference)
    assert not Path(f"{out}.parts").exists()


@pytest.mark.parametrize("fails", [False, True])
def test_the_collector_is_eased_while_tasks_run_and_as_before_after(tmp_path, monkeypatch, dask_client, fails):
    # gc.freeze() and a higher young threshold while the tasks run (the objects of the imports and the
    # cluster's start are not scanned in each full collection); as before when the sweep ends, also when it
    # fails (a full disk).
    frozen, grow_many, thresholds = [], worker.grow_many, gc.get_threshold()

    def watched(*args, **kwargs):
        frozen.append((gc.get_freeze_count(), gc.get_threshold()[0]))
        return grow_many(*args, **kwargs)

    def full(self, results):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(worker, "grow_many", watched)
    if fails:
        monkeypatch.setattr(Parts, "write", full)
    with pytest.raises(OSError) if fails else contextlib.nullcontext():
        dla.run_sweep(parse_spec(TINY_SPEC), client=dask_client, out=tmp_path / "t.nc")
    # A failed sweep's tasks may still run on a shared cluster after it returns: its first batch ran frozen.
    during = frozen[:1] if fails else frozen
    assert during and all(count > 0 and young == session.COLLECT_EVERY for count, young in during)
    assert gc.get_freeze_count() == 0 and gc.get_threshold() == thresholds


def test_a_collector_switched_off_stays_off_during_a_sweep():
    # gc.set_threshold(0) (no automatic collection) is the user's choice: the sweep does not turn it on.
    thresholds = gc.get_threshold()
    gc.set_threshold(0, *thresholds[1:])
    try:
        with session.collector_eased():
            assert gc.get_threshold()[0] == 0 and gc.get_freeze_count() > 0
        assert gc.get_threshold()[0] == 0
    finally:
        gc.set_threshold(*thresholds)


@pytest.mark.parametrize("on_terminal", [False, True])
def test_a_sweep_off_a_terminal_prints_progress_lines(on_terminal, tmp_path, dask_client, monkeypatch, capsys):
    monkeypatch.setattr(sweep, "Lines", functools.partial(progress.Lines, gap=0))  # the tiny sweep takes a second
    monkeypatch.setattr(sys.stderr, "isatty", lambda: on_terminal)
    batches_of(monkeypatch, 3)
    dla.run_sweep(parse_spec(TINY_SPEC), client=dask_client, out=tmp_path / "tiny.nc").close()
    shown = progress_lines(capsys.readouterr().err)
    assert shown == ([] if on_terminal else [3, 6, 9, 12])
