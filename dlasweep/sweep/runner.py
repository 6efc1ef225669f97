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
``netcdf.ParticleWriter``), so memory holds a few parts at a time and the
compression overlaps the growth. At the end the dataset is assembled from
the parts in one pass without the positions, written into that file, and
the file renamed to OUT. What a task does on a worker is ``task``'s; the
dask session it runs on is ``session``'s.

With ``[run] target_ci``, the sweep grows batch after batch of seeds as
``precision.Precision`` decides; the dataset records the achieved
half-widths and why the sweep stopped (``netcdf.record_stop``).
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import math
import sys
import uuid
import warnings

import numpy as np
from tqdm import tqdm

from ..data import netcdf, schema
from ..data.paths import writable
from ..growth.cluster import compiled
from ..stats.fit import growth_counts
from .parts import PARTICLES, Parts, parts_folder
from .precision import Precision
from .precompile import first_task_of_each_kernel, load_kernels
from .progress import Lines, compiling
from .session import collector_eased, connected
from .spec import Spec, load_spec
from .task import error_result, measure_tasks, sweep_scales

TASK_SECONDS = 0.25
"""Work given to one dask task: its overhead (scheduling, a part file: milliseconds)
becomes small, while a kill loses little and the threads share the end of a sweep."""

SECONDS_PER_PARTICLE = 3e-6
"""Growing and measuring a 2D lattice cluster, per particle of its largest count
(about linear from 10^3 to 10^5 particles; other models take longer)."""

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
        record (``netcdf.record_stop``).

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
        precision, dask_client, stream = Precision(spec), None, None
        batch = precision.ask()
        while True:
            tasks = list(batch.tasks())  # listed once a batch, as listing is slow at ``spec.MAX_TASKS``
            todo = [t for t in tasks if not parts.finished(t.key)]
            if out is not None:  # the batch's clusters go into the file as they finish
                stream = _Stream(batch, tasks, parts, todo)
                session.callback(stream.writer.discard)
            if todo:
                if dask_client is None:
                    cold = (progress or lines) and client is None and scheduler_file is None and _cold_kernels(spec)
                    if cold:  # on a terminal and in a log: what compiles, and for about how long
                        print(f"{spec.name}: {compiling(cold)}", file=sys.stderr, flush=True)
                    dask_client = session.enter_context(connected(client, scheduler_file, workers or spec.workers, most,
                                                                  functools.partial(load_kernels, spec)))
                    if announce:
                        print(announce, file=sys.stderr, flush=True)
                    session.enter_context(collector_eased())
                bar = (Lines(batch.n_tasks, batch.n_tasks - len(todo), spec.name) if lines else
                       tqdm(total=batch.n_tasks, initial=batch.n_tasks - len(todo), unit="cluster",
                            desc=spec.name, disable=not progress, file=sys.stderr))
                with bar:
                    _compute(dask_client, batch, todo, parts, bar, stream)
            ds, failed = _assemble(batch, tasks, parts)
            done = batch
            batch = precision.tell(ds, failed)
            if batch is not None:
                if stream is not None:  # the cluster order changes: the next batch writes them again
                    stream.writer.discard()
                continue
            if spec.target_ci is not None:
                ds = netcdf.record_stop(ds, precision.half_width, spec.target_ci, spec.max_seeds, precision.reason)
            # The clusters go from the parts into the file (or memory) one part at a time.
            if out is None:
                ds = netcdf.with_clusters(ds, _clusters(done, tasks, parts))
            else:
                stream.feed()
                stream.writer.finish(ds, out)
                ds = netcdf.open_sweep(out)
            break
        parts.done = not failed
    if failed:
        warnings.warn(f"{len(failed)} of {spec.n_tasks} tasks failed: "
                      + "; ".join(f"{k}: {m}" for k, m in failed), RuntimeWarning, stacklevel=2)
    return ds


def _cold_kernels(spec) -> list:
    """The growth kernels the spec needs that numba's cache lacks (``growth.cluster.kernel_of``): the first
    tasks compile them."""
    return [kernel for kernel, task in first_task_of_each_kernel(spec).items() if not compiled(task.params)]


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
                               spec.harmonic_walkers, key=f"{batch[0].key}+{len(batch)}-{tag}", pure=False)
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
            results = [error_result(counts, len(scales), task.params["dim"], message, spec.harmonic_walkers)
                       for task in batch]
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
    if spec.harmonic_walkers:  # on (<axes>..., size, [n_particles,] seed[, q])
        science.update({name: schema.blank(name, _harmonic_shape(name, spec.shape, grid)) for name in schema.HARMONIC})
    table = parts.table((t.key for t in tasks), (*science, "points.shape", "error"))
    for name, values in science.items():
        # The tasks are the grid's points in C order; but for the history and the harmonic measurement, a
        # task's values do not run along n_particles, which comes before seed.
        each = table[name].reshape(*spec.shape, *table[name].shape[1:])
        once = name == "radius_gyration_history" or (name in schema.HARMONIC and not _at_every_count(name))
        values[...] = each if once else np.moveaxis(each, len(spec.shape) - 1, len(spec.shape))
    stores = [spec.stores(task) for task in tasks]
    sizes = [int(shape[0]) for shape in itertools.compress(table["points.shape"], stores)]
    failed = [(task.key, str(error)) for task, error in zip(tasks, table["error"]) if str(error)]

    # Keep scales up to the first at which every cluster fits in one box.
    fits = (science["box_count"] <= 1).reshape(-1, len(scales)).all(axis=0)
    top = int(np.argmax(fits)) if fits.any() else len(scales) - 1
    science["box_count"] = science["box_count"][..., : top + 1]
    stored = list(itertools.compress(tasks, stores))
    return netcdf.to_dataset(spec, stored, scales[: top + 1], history, science, sizes, failed), failed


def _at_every_count(name) -> bool:
    """Whether a harmonic variable is sampled at every count (on ``n_particles``), not once per cluster."""
    return "n_particles" in schema.SCHEMA[name].dims


def _harmonic_shape(name, shape, grid) -> tuple:
    """The shape of harmonic variable ``name`` in a sweep of task grid ``shape`` (seed last) and science grid
    ``grid`` (n_particles before seed): on the science grid when sampled at every count, else once per
    cluster; then q, when it has it."""
    q = (len(schema.HARMONIC_Q),) if "q" in schema.SCHEMA[name].dims else ()
    return (*(grid if _at_every_count(name) else shape), *q)


class _Stream:
    """A spec's stored clusters written into its file (``netcdf.ParticleWriter``, in the parts
    folder until the end) in cluster order, each once it and all before it have finished."""

    def __init__(self, spec, tasks, parts, todo):
        self.parts, self.next, self.pending = parts, 0, {task.key for task in todo}
        self.keys = [task.key for task in tasks if spec.stores(task)]
        columns = schema.ragged_columns([t.params["model"] for t in tasks], [t.params["dim"] for t in tasks])
        self.writer = netcdf.ParticleWriter(parts.path / PARTICLES, columns)

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
