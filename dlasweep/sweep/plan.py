"""What a sweep will take, before it starts: clusters, particles, memory and disk.

Pure computation from a spec (``plan``) and the room there is (``room``);
``check`` refuses, naming the spec's key, a sweep that cannot fit. The
figures are estimates from the stored types and the kernels' benchmarked use,
rounded up: a sweep may take less, it should not take much more.
"""

from __future__ import annotations

import math
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..data import schema
from ..params import counted
from ..stats.fit import growth_counts
from .spec import Spec, SpecError
from .task import sweep_scales

KERNEL_BYTES = {("lattice", 2): 23, ("offlattice", 2): 33, ("lattice", 3): 31, ("offlattice", 3): 42}
"""Memory a growing cluster takes per particle, by model and dim: the memory ``dlasweep bench --full``
added growing 10^7 particles, parents included (results/bench/bench.txt; docs/performance.md, "Sweeps")."""
MEASURE_COPIES = 2
"""Copies of a grown cluster's positions its measures hold at once (box counting's bitmaps, the
prefixes' radii), beside the kernel's own."""
BASE_BYTES = 400 * 2 ** 20
"""A sweep's process before any cluster: Python, numba, the kernels, dask's embedded cluster (a quick
process's peak resident size, rounded up; docs/performance.md, "Sweeps")."""
TABLE_COPIES = 2
"""Copies of every cluster's measures held at the end: the parts' table and the dataset built from it."""
TASK_BYTES = 1000
"""Memory a cluster's bookkeeping takes while the sweep runs: its task, its key, its entry in the parts'
index, its share of a batch's future (rounded up from docs/performance.md, "Sweeps")."""
DISK_COPIES = 2
"""Copies of the stored clusters on disk at the end: the parts (uncompressed) and the file being written."""


@dataclass(frozen=True)
class Plan:
    """What a sweep will grow and take.

    Attributes
    ----------
    clusters : int
        Clusters to grow (a target sweep: at its max_seeds).
    particles : int
        Particles grown in all, every cluster to the largest count.
    stored : int
        Particles whose positions and diffusion times are stored.
    growing, table : int
        Bytes of memory for the clusters growing at once, and for every
        cluster's measures and bookkeeping.
    disk : int
        Bytes on disk: the stored clusters and the measures.
    """

    clusters: int
    particles: int
    stored: int
    growing: int
    table: int
    disk: int

    @property
    def memory(self) -> int:
        """Bytes of memory in all, at the peak."""
        return BASE_BYTES + self.growing + self.table

    def __str__(self) -> str:
        return (f"plan: {counted(self.clusters, 'cluster')}, {counted(self.particles, 'particle')} "
                f"({self.stored:,} stored); "
                f"about {size(self.memory)} of memory, {size(self.disk)} of disk")


def plan(spec: Spec, threads: int) -> Plan:
    """The plan of ``spec`` grown ``threads`` clusters at a time (at most: no more than it has).

    A target sweep is planned at its ``max_seeds``, the most it may grow.
    """
    seeds = spec.max_seeds or len(spec.seeds)
    configurations = math.prod(spec.shape[:-1])
    clusters = configurations * seeds
    n_max = spec.counts[-1]
    stored_seeds = seeds if spec.store_clusters is None else min(spec.store_clusters, seeds)
    resolved = spec.parameters
    models, dims = [p["model"] for p in resolved], [p["dim"] for p in resolved]
    columns = schema.ragged_columns(models, dims)
    per_particle = sum(np.dtype(dtype).itemsize for dtype in columns.values())
    largest = max(KERNEL_BYTES[p["model"], p["dim"]] + MEASURE_COPIES * per_particle for p in resolved)
    measures = clusters * _measure_bytes(spec)
    stored = configurations * stored_seeds * n_max
    return Plan(clusters=clusters, particles=clusters * n_max, stored=stored,
                growing=min(threads, clusters) * largest * n_max,
                table=TABLE_COPIES * measures + clusters * TASK_BYTES,
                disk=DISK_COPIES * stored * per_particle + measures)


def _measure_bytes(spec) -> int:
    """Bytes of one cluster's measures (``schema.SCHEMA``'s per-task variables, at their stored types)."""
    lengths = {"n_particles": len(spec.counts), "history": len(growth_counts(spec.counts)),
               "scale": len(sweep_scales(spec)), "q": len(schema.HARMONIC_Q)}
    total = 0
    for name in (*schema.SCIENCE, "wall_time", *(schema.HARMONIC if spec.harmonic_walkers else ())):
        var = schema.SCHEMA[name]
        total += np.dtype(var.dtype).itemsize * math.prod(lengths.get(dim, 1) for dim in var.dims)
    return total


@dataclass(frozen=True)
class Room:
    """Memory and disk there are for a sweep, in bytes (None: not known)."""

    memory: int | None
    disk: int | None


def room(folder) -> Room:
    """Memory available now (``MemAvailable`` of /proc/meminfo, else psutil's) and free disk in ``folder``."""
    return Room(_available_memory(), shutil.disk_usage(Path(folder)).free)


def _available_memory():
    try:
        with open("/proc/meminfo") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        import psutil
    except ImportError:
        return None
    return psutil.virtual_memory().available


def check(the_plan: Plan, spec: Spec, there: Room, local=True):
    """Refuse a plan that does not fit: ``SpecError`` naming the key that makes it large.

    ``local``: whether the clusters grow in this machine's memory (not on a
    scheduler's workers); the disk is this machine's either way.
    """
    seeds_key = "run.max_seeds" if spec.max_seeds is not None else "grid.seeds"
    if local and there.memory is not None and the_plan.memory > there.memory:
        key = "grid.n_particles" if the_plan.growing > the_plan.table else seeds_key
        raise SpecError(f"{key}: the sweep needs about {size(the_plan.memory)} of memory, {size(there.memory)} "
                        f"available ({the_plan.clusters:,} clusters of up to {spec.counts[-1]:,} particles)")
    if there.disk is not None and the_plan.disk > there.disk:
        raise SpecError(f"{seeds_key}: the sweep needs about {size(the_plan.disk)} of disk, {size(there.disk)} free "
                        f"there ({the_plan.stored:,} particles stored; run.store_clusters stores fewer)")


def size(n: int) -> str:
    """Bytes as a user reads them: ``1.2 GB``."""
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6)):
        if n >= scale:
            return f"{n / scale:.1f} {unit}"
    return f"{n / 1e3:.1f} kB"
