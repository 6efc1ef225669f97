"""The worker's task: grow one cluster of a sweep and measure it at every count.

What runs on a dask worker (``runner`` submits ``measure_tasks``): the
cluster grows once, to the largest count, from its own random stream
``SeedSequence(root_seed, spawn_key=grid indices)``, and each count's
measures come from its prefix. A task never raises: a failure is an ``error`` result
carrying its message, so that one bad cluster does not end a sweep.
"""

from __future__ import annotations

import itertools

import numpy as np

from ..data import schema
from ..growth.cluster import grow, grow_many
from ..measures import shape
from ..measures.boxes import default_scales
from ..measures.harmonic import KEY as HARMONIC_KEY
from ..measures.harmonic import harmonic_measure
from ..params import Status, one_line
from ..stats.fit import growth_counts
from ..stats.multifractal import multifractal_spectrum
from .spec import Spec


def sweep_scales(spec: Spec) -> np.ndarray:
    """Box sides every task measures: up to an extent no cluster can exceed.

    A bounded cluster (and its line seed) fits its box; an unbounded,
    connected one of n particles spans at most n (+ a seed block). The
    axis is trimmed to the clusters after the sweep.
    """
    return default_scales(max(size or spec.counts[-1] for size in spec.sizes) + 2)


def measure_tasks(tasks, counts, scales, root_seed, stored, walkers=0) -> list:
    """``measure_task`` for each of a batch of tasks; runs on a worker as one dask task.

    ``stored``: per task, whether its positions are kept (``Spec.stores``);
    ``walkers``: those fired at each cluster for its harmonic measure (``Spec.harmonic_walkers``, 0: none).
    Each run of tasks with the same parameters grows in one compiled call
    (``grow_many``); if that raises, each of its tasks grows alone, so that
    only the clusters that fail are marked failed.
    """
    history = growth_counts(counts)
    results = []
    for _, run in itertools.groupby(zip(tasks, stored), key=lambda pair: pair[0].params):
        run = list(run)
        try:
            clusters = grow_many(counts[-1], [_stream(root_seed, task) for task, _ in run], checkpoints=counts,
                                 **run[0][0].params)
        except Exception:  # noqa: BLE001 (each task then grows alone and records its own error)
            clusters = [None] * len(run)
        results += [measure_task(task, counts, scales, root_seed, keep, history, cluster, walkers)
                    for (task, keep), cluster in zip(run, clusters)]
    return results


def measure_task(task, counts, scales, root_seed, stored, history, cluster=None, walkers=0) -> dict:
    """Grow one cluster (unless ``cluster`` is the one grown) and measure every count; runs on a worker.

    Its Rg along the growth is kept at ``history`` (``growth_counts(counts)``,
    computed once per batch); its positions and diffusion times only when
    ``stored`` (else empty). With ``walkers``, the harmonic measure of the
    cluster at each count is sampled with that many walkers (``harmonic``).
    Never raises: a failure is returned as an ``error``
    result with its message.
    """
    try:
        if cluster is None:
            cluster = grow(counts[-1], _stream(root_seed, task), checkpoints=counts, **task.params)
        points = cluster.points
        reached = np.asarray(counts) <= len(points)
        prefix = np.minimum(counts, len(points))
        lattice = cluster.params["model"] == "lattice"
        measures = shape.cluster_measures(points, prefix, history, lattice=lattice, scales=scales)
        if walkers:
            measures.update(harmonic(cluster, walkers, harmonic_seed(root_seed, task), counts))
        return {
            **measures,
            "n_grown": prefix.astype(np.int64),
            "status": np.where(reached, Status.ok, Status[cluster.status]).astype(np.int8),
            "wall_time": np.where(np.isnan(cluster.times), cluster.seconds, cluster.times),
            "walk_steps": _prefix_sums(cluster.steps, prefix),
            "points": points if stored else points[:0],
            "diffusion_time": cluster.steps if stored else cluster.steps[:0],
            "parent": np.asarray(cluster.parents if stored else cluster.parents[:0], np.int32),
            "error": np.array(""),
        }
    except Exception as err:
        return error_result(counts, len(scales), task.params["dim"], f"{type(err).__name__}: {err}", walkers)


def harmonic(cluster, walkers, seed, counts) -> dict:
    """The harmonic measurement of a grown cluster: the ``schema.HARMONIC`` variables of one task.

    ``walkers`` walkers from ``seed`` are fired (``measures.harmonic.harmonic_measure``) at the cluster
    as it was at each of ``counts`` it reached (its first particles: the cluster then) and as grown:
    the Renyi entropies at ``schema.HARMONIC_Q`` of each count's measure, of all the walkers and of
    the first half, whose growth with the cluster gives D(q) by size (``stats.multifractal.size_scaling``);
    and of the cluster as grown, its box spectrum D(q) with standard errors and ok flags (its jackknife
    drawn from the same seed) and the deposition depth. Every count's walkers come from the same seed.
    """
    q = schema.HARMONIC_Q
    entropy, half = (np.full((len(counts), len(q)), np.nan) for _ in range(2))
    for k, m in enumerate([*(m for m in counts if m < cluster.n), cluster.n]):
        measure = harmonic_measure(cluster.prefix(m), walkers, seed)
        if k < len(counts) and counts[k] == m:
            entropy[k], half[k] = measure.renyi_entropies(q), measure.renyi_entropies(q, first=walkers // 2)
    spectrum = multifractal_spectrum(measure, q=q, seed=seed)
    depth, spread = measure.depth
    return {"harmonic_D": spectrum.D.astype(np.float64), "harmonic_D_stderr": spectrum.stderr.astype(np.float64),
            "harmonic_D_ok": spectrum.ok.astype(np.int8), "harmonic_entropy": entropy,
            "harmonic_entropy_half": half, "harmonic_depth": np.float64(depth),
            "harmonic_depth_spread": np.float64(spread)}


def harmonic_seed(root_seed, task) -> int:
    """The seed of a task's harmonic measurement: 63 bits drawn from ``SeedSequence(root_seed, spawn_key=(grid
    indices..., harmonic.KEY))``, a child of the task's stream that its growth never draws (its children, if
    any, are numbered from 0), so that the walkers are the same for the task in any batch or worker."""
    state = np.random.SeedSequence(root_seed, spawn_key=(*task.spawn_key, HARMONIC_KEY)).generate_state(1, np.uint64)
    return int(state[0] >> np.uint64(1))


def _prefix_sums(steps, prefix) -> np.ndarray:
    """The sums of ``steps[:m]`` for each m of ``prefix`` (ascending), in int64: a sum per stretch, not a
    cumulative sum of every particle (8 bytes a particle)."""
    stretches = [steps[a:b].sum(dtype=np.int64) for a, b in zip(np.r_[0, prefix[:-1]], prefix)]
    return np.cumsum(np.array(stretches, np.int64))


def _stream(root_seed, task) -> np.random.SeedSequence:
    """The task's random stream: from the root seed and its grid indices."""
    return np.random.SeedSequence(root_seed, spawn_key=task.spawn_key)


def error_result(counts, n_scales, dim, message, walkers=0) -> dict:
    """The result recorded for a task that raised (or whose worker kept dying); with ``walkers``, its
    harmonic variables too, missing (so that every result of a sweep has the same variables)."""
    n_counts = len(counts)
    shapes = {"box_count": (n_counts, n_scales), "radius_gyration_history": len(growth_counts(counts))}
    result = {name: schema.blank(name, shapes.get(name, n_counts)) for name in (*schema.SCIENCE, "wall_time")}
    if walkers:
        dims = {"n_particles": n_counts, "q": len(schema.HARMONIC_Q)}
        result.update({name: schema.blank(name, tuple(dims[d] for d in schema.SCHEMA[name].dims if d in dims))
                       for name in schema.HARMONIC})
    result["status"][:] = Status.error
    return {**result, "points": np.zeros((0, dim)), "diffusion_time": schema.blank("diffusion_time", 0),
            "parent": schema.blank("parent", 0), "error": np.array(one_line(message))}
