"""Run a sweep on dask: batches of clusters as tasks, each batch saved as it arrives.

Every cluster task (``task.measure_task``) grows one (swept params, size,
seed) cluster from its own random stream, so results do not depend on how
many workers there are, in which order tasks finish, or how they are
batched. A dask task runs a batch of consecutive cluster tasks worth about
``TASK_SECONDS`` (``_batch_size``), so that small clusters do not pay dask's
and the part files' overhead one by one.

Each finished batch goes at once to the parts folder ``OUT.parts``
(``parts``), which a resumed run reads back; a changed spec, or a second
run on the same output, is refused there. The stored clusters' positions go
into the file's per-particle variables while the sweep runs, each as soon
as every cluster before it has finished (``OUT.parts/particles.nc``,
``store.ParticleWriter``), so memory holds a few parts at a time and the
compression overlaps the growth. At the end the dataset is assembled from
the parts in one pass without the positions, written into that file, and
the file renamed to OUT. What a task does on a worker is ``task``'s.
This is the only module that knows dask.

Precision on demand (``[run] target_ci``): the seeds of the spec are a first
batch. After each batch the dataset is assembled and its headline D
measured (``analysis.headline``); while the 95% CI half-width of the headline D at
the largest count is above the target for some configuration (NaN counts as
above) and fewer than ``max_seeds`` seeds are grown, every configuration
gets more seeds, replicates n..m-1 (``_more_seeds`` says how many). Replicate
j is the same task in every batch, so a batch grows only new replicates, the
result equals a fixed sweep with the final count, and a resumed run replays
the same batches from its parts. The dataset records the achieved
half-widths and why the sweep stopped (``store.record_stop``).
"""

from __future__ import annotations

import contextlib
import functools
import gc
import importlib
import itertools
import json
import logging
import math
import os
import sys
import threading
import uuid
import warnings
from pathlib import Path

import numpy as np
from tqdm import tqdm

from . import schema, store
from .analysis import headline
from .fit import growth_counts
from .grow import STOP, compiled
from .parts import PARTICLES, Parts, parts_folder
from .paths import writable
from .progress import Lines
from .spec import Spec, load_spec
from .task import error_result, measure_tasks, sweep_scales

TASK_SECONDS = 0.25
"""Work given to one dask task: its overhead (scheduling, a part file: milliseconds)
becomes small, while a kill loses little and the threads share the end of a sweep."""

SECONDS_PER_PARTICLE = 3e-6
"""Growing and measuring a 2D lattice cluster, per particle of its largest count
(about linear from 10^3 to 10^5 particles; other models take longer)."""

SWITCH_INTERVAL = 0.0005
"""Seconds a thread may hold the GIL while another waits, in the embedded cluster
(Python's default: 0.005). Measured on 10,000 lattice clusters of 10^3 on 2
threads, whole sweep: 0.005 s 15.1-15.4 s; 0.001 s 14.4-14.5; 0.0005 s 14.1-15.1;
0.0002 s 14.2-14.3."""

TARGET_REACHED, CAP_REACHED, TASKS_FAILED = "target_ci reached", "max_seeds reached", "tasks failed"
"""Why a target sweep stopped (its ``stop_reason``); failed tasks stop it so that
``--resume`` retries them rather than seeds being added around them."""


def run_sweep(spec, client=None, out=None, resume=False, workers=None, progress=None,
              scheduler_file=None, announce=None):
    """Grow and measure every cluster of a spec.

    Parameters
    ----------
    spec : Spec or path
        A spec from ``load_spec``, or the path of one.
    client : distributed.Client or str, optional
        A connected client, or a scheduler address. Default: an embedded
        ``LocalCluster``: one in-process worker with a thread per core.
    out : path, optional
        The netCDF file to write; its ``.parts`` folder keeps finished tasks
        until the file is complete. Without it, results stay in memory.
    resume : bool
        Reuse the parts of an interrupted run of the same spec.
    workers : int, optional
        Threads of the embedded cluster, i.e. tasks run at once (default:
        ``[run] workers``, else the usable cores).
    progress : bool, optional
        Show a progress bar on stderr (True), or nothing (False). Default: a
        bar on a terminal, else a line each 10% of the clusters or 10 s
        (``progress.Lines``), for a log.
    scheduler_file : path, optional
        Connect to the scheduler described in this file.
    announce : str, optional
        A line for stderr once the first task is about to run (connected):
        the plan (``plan.Plan``).

    Returns
    -------
    xarray.Dataset
        Opened from ``out`` when given. Failed tasks (status ``error``) are
        listed in its ``failed_tasks`` attribute, and a warning names them.
        A target sweep's dataset has as many seeds as it grew, and its stop
        record (``store.record_stop``).

    Raises
    ------
    ResumeError
        When ``out``'s parts folder is from another spec, exists without
        ``resume``, or is locked by a running sweep; nothing is computed then.
    OSError
        When ``out`` cannot be written (``paths.writable``); nothing is computed then.
    """
    if not isinstance(spec, Spec):
        spec = load_spec(spec)
    if out is not None:
        writable(out)
    lines = progress is None and not sys.stderr.isatty()
    if progress is None:
        progress = sys.stderr.isatty()
    # Tasks the sweep may run at most: the embedded cluster needs no more threads.
    most = math.prod(spec.shape[:-1]) * (spec.max_seeds or len(spec.seeds))
    with parts_folder(spec, out, resume) as parts, contextlib.ExitStack() as session:
        batch, dask_client, stream = spec, None, None
        while True:
            tasks = list(batch.tasks())  # listed once a batch: 15 s for 1e7 clusters (``spec.MAX_TASKS``)
            todo = [t for t in tasks if not parts.finished(t.key)]
            if out is not None:  # the batch's clusters go into the file as they finish
                stream = _Stream(batch, tasks, parts, todo)
                session.callback(stream.writer.discard)
            if todo:
                if dask_client is None:
                    if progress and client is None and scheduler_file is None and _compiles(spec):
                        print(f"{spec.name}: compiling kernels (once)", file=sys.stderr)
                    dask_client = session.enter_context(_connected(client, scheduler_file, workers or spec.workers, most,
                                                                   functools.partial(_load_kernels, spec)))
                    if announce:
                        print(announce, file=sys.stderr, flush=True)
                    session.enter_context(_collector_eased())
                bar = (Lines(batch.n_tasks, batch.n_tasks - len(todo), spec.name) if lines else
                       tqdm(total=batch.n_tasks, initial=batch.n_tasks - len(todo), unit="cluster",
                            desc=spec.name, disable=not progress, file=sys.stderr))
                with bar:
                    _compute(dask_client, batch, todo, parts, bar, stream)
            ds, failed = _assemble(batch, tasks, parts)
            if spec.target_ci is not None:
                half_width = _ci_half_width(ds)
                more, reason = _more_seeds(spec, len(batch.seeds), half_width.values, failed)
                if more:
                    batch = spec.with_seeds(more)
                    if stream is not None:  # the cluster order changes: the next batch writes them again
                        stream.writer.discard()
                    continue
                ds = store.record_stop(ds, half_width, spec.target_ci, spec.max_seeds, reason)
            # The clusters go from the parts into the file (or memory) one part at a time.
            if out is None:
                ds = store.with_clusters(ds, _clusters(batch, tasks, parts))
            else:
                stream.feed()
                stream.writer.finish(ds, out)
                ds = store.open_sweep(out)
            break
        parts.done = not failed
    if failed:
        warnings.warn(f"{len(failed)} of {spec.n_tasks} tasks failed: "
                      + "; ".join(f"{k}: {m}" for k, m in failed), RuntimeWarning, stacklevel=2)
    return ds


def _ci_half_width(ds):
    """Half-width of the 95% CI of the headline D at the largest count, per configuration.

    NaN where there is no interval (too few seeds or too small clusters).
    """
    top = headline(ds)
    return ((top["D_ci_hi"] - top["D_ci_lo"]) / 2).reset_coords(drop=True)


def _more_seeds(spec, n, half_width, failed):
    """Seeds the next batch should bring the sweep to, or ``None`` and why it stops.

    The CI half-width of a mean over n seeds falls as 1/sqrt(n), so a
    configuration at half-width w needs about ``n * (w / target_ci)**2``
    seeds; 10% more covers the noise of w, so that one more batch usually
    suffices (bootstrap intervals from few seeds are, if anything, too
    narrow, so the estimate errs towards too few seeds, not too many). A
    configuration without an interval yet (NaN) asks for twice n. The worst
    configuration sets the batch, which is at least one first batch (so the
    workers get a batch worth distributing) and at most ``max_seeds``.

    Parameters
    ----------
    spec : Spec
        A target sweep's spec (``target_ci`` set).
    n : int
        Seeds grown so far.
    half_width : ndarray
        CI half-width of every configuration after n seeds.
    failed : sequence
        Failed tasks of the batch: they stop the sweep.

    Returns
    -------
    (int, None) or (None, str)
        The new seed count, or the stop reason.
    """
    if failed:
        return None, TASKS_FAILED
    unmet = ~(half_width <= spec.target_ci)  # NaN compares False: unmet
    if not unmet.any():
        return None, TARGET_REACHED
    if n >= spec.max_seeds:
        return None, CAP_REACHED
    wanted = np.where(np.isnan(half_width), 2 * n, np.ceil(1.1 * n * (half_width / spec.target_ci) ** 2))
    return min(spec.max_seeds, max(n + len(spec.seeds), int(wanted[unmet].max()))), None


def _compiles(spec) -> bool:
    """Whether the first tasks compile kernels: numba's cache lacks a growth kernel the spec needs."""
    return not all(compiled(model, dim, task.params["walkers"])
                   for (model, dim, _), task in _first_task_of_each_kernel(spec).items())


def _first_task_of_each_kernel(spec) -> dict:
    """(model name, dimension, lockstep walkers) -> the first task of the spec that grows it: each is a kernel of
    its own."""
    first = {}
    for task in spec.tasks(replicates=1):
        first.setdefault((task.params["model"], task.params["dim"], task.params["walkers"] > 1), task)
    return first


def _batch_size(spec, n_todo, threads) -> int:
    """Cluster tasks per dask task: about ``TASK_SECONDS`` of work, yet at least 4 dask tasks per thread."""
    per_cluster = SECONDS_PER_PARTICLE * spec.counts[-1]
    return max(1, min(int(TASK_SECONDS / per_cluster), n_todo // (4 * threads)))


def _batches(todo, size, threads):
    """``todo`` in consecutive slices of ``size`` tasks, near the end of at most what is left
    / (2 x threads) (guided scheduling), so that the threads finish together."""
    start = 0
    while start < len(todo):
        n = max(1, min(size, (len(todo) - start) // (2 * threads)))
        yield todo[start:start + n]
        start += n


def _load_kernels(spec):
    """Grow and measure a cluster of a few particles of each model and dimension swept.

    The kernels its tasks call load (or compile) here, once, while the
    embedded cluster starts, not in each of its threads at once, one
    waiting for the other under numba's lock. So does dask.array, which
    xarray imports when it builds the dataset: imported while the tasks
    ran, it held the GIL they need between kernels.
    """
    first = list(_first_task_of_each_kernel(spec).values())
    counts = np.array([min(spec.counts[0], 10)])
    measure_tasks(first, counts, sweep_scales(spec), spec.root_seed, [False] * len(first))
    with contextlib.suppress(ImportError):
        importlib.import_module("dask.array")


COLLECT_EVERY = 20_000
"""Allocations between the garbage collector's young collections while a sweep runs (Python's default: 700).

Measured on 10^4 clusters of 10^3 (``gc.callbacks``): 790 young, 72 middle and
6 full collections took 0.47-0.51 s, all holding the GIL; at 20,000, 257, 22
and 2 took 0.22-0.24 s."""


@contextlib.contextmanager
def _collector_eased():
    """Collect garbage less often while the tasks run; as before afterwards, also after a failure.

    What the imports, kernels and cluster made (about 200,000 objects)
    outlives the sweep, so it is frozen out of the full collections, which
    scanned it at about 70 ms each; young collections run every
    ``COLLECT_EVERY`` allocations (a threshold of 0, no automatic
    collection, is kept).
    """
    thresholds = gc.get_threshold()
    gc.freeze()
    gc.set_threshold(max(COLLECT_EVERY, thresholds[0]) if thresholds[0] else 0, *thresholds[1:])
    try:
        yield
    finally:
        gc.set_threshold(*thresholds)
        gc.unfreeze()


@contextlib.contextmanager
def _connected(client, scheduler_file, workers, n_tasks, load):
    """A client: the one given, one for an address or scheduler file, or an embedded cluster.

    ``load`` is called in a thread while the embedded cluster starts (the kernels, ``_load_kernels``).
    """
    # distributed loads here, not with the module: ``dlasweep grow`` and ``info`` never need it
    import dask
    from distributed import Client, LocalCluster

    if isinstance(client, Client):
        yield client
        return
    if client is not None or scheduler_file is not None:
        with Client(scheduler_address(client, scheduler_file)) as connected:
            yield connected
        return
    threads = embedded_threads(workers, n_tasks)
    # The kernels release the GIL, so one in-process worker with a thread per
    # core runs them in parallel, starts in milliseconds instead of a second
    # per spawned process, and loads the compiled kernels once, not per process.
    # Its worker shares this process: no memory limit to watch (memory_limit=0),
    # and no statistical profiler sampling the threads every 10 ms under the GIL.
    interval = sys.getswitchinterval()
    # A thread back from a kernel waits for the GIL until its holder (the
    # event loop, another thread's Python) lets go or the interval ends.
    sys.setswitchinterval(SWITCH_INTERVAL)
    loading = threading.Thread(target=load, name="dlasweep-load", daemon=True)
    loading.start()
    try:
        with (dask.config.set({"distributed.worker.profile.enabled": False}),
              LocalCluster(n_workers=1, threads_per_worker=threads, processes=False, memory_limit=0,
                           dashboard_address=":0", silence_logs=logging.CRITICAL) as cluster,
              Client(cluster) as embedded):
            loading.join()
            try:
                yield embedded
            except BaseException:
                STOP.set()  # closing joins the worker's threads: their growths give up first
                raise
    finally:
        STOP.clear()
        sys.setswitchinterval(interval)


def scheduler_address(address=None, scheduler_file=None) -> str:
    """A scheduler's address, as given or read from its scheduler file, checked for its form (not reached).

    Raises
    ------
    ValueError
        One line: what is wrong with the address or the file (the caller names the option).
    """
    from distributed.comm.addressing import parse_address, parse_host_port
    from distributed.comm.registry import backends

    if scheduler_file is not None:
        try:
            info = json.loads(Path(scheduler_file).read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, ValueError) as err:
            raise ValueError(f"not a dask scheduler file ({type(err).__name__}: {err})") from None
        address = info.get("address") if isinstance(info, dict) else None
        if not isinstance(address, str):
            raise ValueError('not a dask scheduler file (no "address" string)')
    try:
        scheme, location = parse_address(address)
        if scheme not in backends:
            raise ValueError(f"unknown protocol {scheme!r} (known: {', '.join(backends)})")
        if scheme in ("tcp", "tls"):
            host, port = parse_host_port(location)
            if not host or not 0 < port < 65536:
                raise ValueError("expected HOST:PORT, the port in [1, 65535]")
        if scheme == "inproc":  # a scheduler in this process (an embedding program's, a test's)
            fields = location.split("/")
            if len(fields) != 3 or not fields[1].isdigit():
                raise ValueError("expected inproc://HOST/PID/N")
            if int(fields[1]) != os.getpid():
                raise ValueError(f"names a scheduler inside process {fields[1]}, not this one")
    except (ValueError, TypeError) as err:
        raise ValueError(f"{address!r} is not a scheduler address ({err})") from None
    return address


def embedded_threads(workers, n_tasks=None) -> int:
    """Threads of the embedded cluster: ``workers`` (default: the usable cores), at most one a task."""
    return min(workers or _usable_cores(), n_tasks or math.inf)


def _usable_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def _compute(client, spec, todo, parts, bar, stream=None):
    """Submit batches of tasks in a bounded window, save each batch as one part as it arrives, and
    ``stream`` the clusters it completes."""
    from distributed import as_completed

    counts = np.asarray(spec.counts, np.int64)
    scales = sweep_scales(spec)
    threads = max(1, sum(client.nthreads().values()))  # an adaptive cluster may start with none
    window = max(100, 4 * threads)
    pending = _batches(todo, _batch_size(spec, len(todo), threads), threads)
    # Unique per run: a key shared with an earlier run's lingering future would return its result.
    tag = uuid.uuid4().hex[:12]
    batch_of = {}

    def submit(batch):
        future = client.submit(measure_tasks, batch, counts, scales, spec.root_seed, list(map(spec.stores, batch)),
                               key=f"{batch[0].key}+{len(batch)}-{tag}", pure=False)
        batch_of[future.key] = batch
        return future

    running = as_completed([submit(t) for t in itertools.islice(pending, window)],
                           with_results=True, raise_errors=False)
    for future, results in running:
        batch = batch_of.pop(future.key)
        if not isinstance(results, list):
            # Dask gave up on it (its workers kept dying: KilledWorker: a (type, error, traceback)) or it
            # was cancelled. Not the status: a result gathered before its worker died reads "lost" (dask
            # computes it again for this future), yet the results in hand are whole.
            message = f"{type(results[1]).__name__}: {results[1]}" if isinstance(results, tuple) else "task cancelled"
            results = [error_result(counts, len(scales), task.params["dim"], message) for task in batch]
        finished = {task.key: result for task, result in zip(batch, results)}
        parts.write(finished)
        if stream is not None:
            stream.feed(finished)
        future.release()
        bar.update(len(batch))
        for batch in itertools.islice(pending, 1):
            running.add(submit(batch))


def _assemble(spec, tasks, parts):
    """The dataset from the parts of ``tasks`` (``spec.tasks()``), in one pass, clusters aside (``_clusters``)."""
    scales = sweep_scales(spec)
    history = growth_counts(spec.counts)
    grid = (*spec.shape[:-1], len(spec.counts), spec.shape[-1])
    shapes = {"box_count": (*grid, len(scales)), "radius_gyration_history": (*spec.shape, len(history))}
    science = {name: schema.blank(name, shapes.get(name, grid)) for name in (*schema.SCIENCE, "wall_time")}
    table = parts.table((t.key for t in tasks), (*science, "points.shape", "error"))
    for name, values in science.items():
        # The tasks are the grid's points in C order; but for the history, a
        # task's values run along n_particles, which comes before seed.
        each = table[name].reshape(*spec.shape, *table[name].shape[1:])
        values[...] = each if name == "radius_gyration_history" else np.moveaxis(each, len(spec.shape) - 1,
                                                                                   len(spec.shape))
    stores = [spec.stores(task) for task in tasks]
    sizes = [int(shape[0]) for shape in itertools.compress(table["points.shape"], stores)]
    failed = [(task.key, str(error)) for task, error in zip(tasks, table["error"]) if str(error)]

    # Keep scales up to the first at which every cluster fits in one box.
    fits = (science["box_count"] <= 1).reshape(-1, len(scales)).all(axis=0)
    top = int(np.argmax(fits)) if fits.any() else len(scales) - 1
    science["box_count"] = science["box_count"][..., : top + 1]
    stored = list(itertools.compress(tasks, stores))
    return store.to_dataset(spec, stored, scales[: top + 1], history, science, sizes, failed), failed


class _Stream:
    """A spec's stored clusters written into its file (``store.ParticleWriter``, in the parts
    folder until the end) in cluster order, each once it and all before it have finished."""

    def __init__(self, spec, tasks, parts, todo):
        self.parts, self.next, self.pending = parts, 0, {task.key for task in todo}
        self.keys = [task.key for task in tasks if spec.stores(task)]
        columns = schema.ragged_columns([t.params["model"] for t in tasks], [t.params["dim"] for t in tasks])
        self.writer = store.ParticleWriter(parts.path / PARTICLES, columns)

    def feed(self, done=None):
        """Write the clusters that come next in order and are no longer pending (``todo`` but not in ``done``,
        results by task key, just written to the parts: those are written from memory, not read back).

        A cluster that failed in this run is written too (it has no points); one
        that failed in an earlier run is pending until it is computed again.
        """
        done = done or {}
        self.pending.difference_update(done)
        ready = list(itertools.takewhile(lambda key: key not in self.pending,
                                         itertools.islice(self.keys, self.next, None)))
        read = self.parts.results([key for key in ready if key not in done], Parts.PER_PARTICLE, release=True)
        for key in ready:
            result = done[key] if key in done else next(read)
            self.writer.add(*(result[name] for name in Parts.PER_PARTICLE))
        self.parts.release([key for key in ready if key in done])
        self.next += len(ready)


def _clusters(spec, tasks, parts):
    """Points, diffusion times and parents of each stored cluster of ``tasks``, in order, read one part at a time."""
    stored = (t.key for t in tasks if spec.stores(t))
    for result in parts.results(stored, Parts.PER_PARTICLE):
        yield tuple(result[name] for name in Parts.PER_PARTICLE)
