"""The host's memory as a growing cluster meets it: the time of a read that waits on the one before.

A walker reads the grids near it at places it cannot know ahead, each read
waiting on the last. While the grids fit the caches such a read costs a few
nanoseconds; once they outgrow them, a trip to memory. Where that happens
and what it costs are the host's, not the kernel's, and they move a cost
exponent (``targets.cost_exponent``) by more than its targets' margins
(docs/performance.md, "Benchmark and host"). ``dlasweep bench`` and
``workflows/cost_exponent.py`` read it in the same run as their clusters, so
that rows from different hosts can be told apart.
"""

from __future__ import annotations

import time

import numpy as np

from .._jit import jit

LINE = 64
"""Bytes of a cache line: the chain visits one word in each."""
WORKING_SETS = (0.25, 1.0, 2.0, 4.0, 8.0, 16.0, 64.0)
"""MiB: from inside a core's level-2 cache to well past any last-level cache."""
READS = 1_000_000
"""Reads timed at each working set (a round), after as many untimed ones that bring it in."""
ROUNDS = 3
"""Timed walks at each working set, of which the median is kept: one slowed by another process is dropped."""


def read_latency(working_sets=WORKING_SETS, reads: int = READS, rounds: int = ROUNDS, seed: int = 0) -> dict:
    """Nanoseconds a read, by working set in MiB: the median of ``rounds`` timed walks of ``reads``
    steps along one chain through every cache line of the set, in random order.

    Each read's address is the value the one before returned, so the processor
    can neither overlap them nor guess the next: a walker's own reads of a grid
    it has outgrown. The arrays come from numpy, which asks Linux for huge
    pages where it may.

    A whole lap of the cycle comes first, and each walk goes on where the last
    ended, so that every timed read is of the line the chain read longest ago:
    the set read is the whole set even where ``reads`` is fewer than its lines
    (a walk that starts again at the chain's start reads only its first
    ``reads`` lines, a set that may fit a cache the whole set does not).

    Parameters
    ----------
    working_sets : sequence of float
        The sizes of the sets read, in MiB, each timed apart.
    reads : int
        Reads timed in each walk (a round).
    rounds : int
        Timed walks at each set; their median is kept.
    seed : int
        Seed of the random order of the chain's lines.

    Returns
    -------
    dict
        Nanoseconds a read (float) by working set in MiB (float).
    """
    rng = np.random.default_rng(seed)
    latency = {}
    for mib in working_sets:
        lines = max(int(mib * 2**20) // LINE, 2)
        chain = one_cycle(lines, rng)
        at = _walk(chain, 0, max(reads, lines))
        walks = []
        for _ in range(rounds):
            ns, at = _timed_walk(chain, at, reads)
            walks.append(ns)
        latency[float(mib)] = float(np.median(walks)) / reads
    return latency


RUN_SET = 16.0
"""MiB: the working set ``dlasweep bench`` reads just before and after each run (``shared_cache``)."""
MEMORY_SET = 64.0
"""MiB: the working set past any last-level cache that ``dlasweep bench`` also reads beside each run:
the memory a grid that outgrew the cache waits on. The two reads tell which runs shared their host,
not by how much (docs/performance.md, "Benchmark and host")."""


def shared_cache(mib: float = RUN_SET, reads: int = READS // 10) -> float:
    """Nanoseconds a read within ``mib`` MiB: whether the last-level cache is the process's, now (past
    it, ``MEMORY_SET``: what a read from memory costs, now).

    The share of the last-level cache a process gets moves with the other
    processes of its host, and a large cluster's speed with it (docs/performance.md,
    "Benchmark and host"). Read beside a long run, this tells a quiet machine
    from a shared one.

    Parameters
    ----------
    mib : float
        The working set read, in MiB.
    reads : int
        Reads timed in each of ``read_latency``'s walks.

    Returns
    -------
    float
        Nanoseconds a read.
    """
    return read_latency((mib,), reads=reads)[float(mib)]


def one_cycle(lines: int, rng) -> np.ndarray:
    """A chain through ``lines`` cache lines in random order: at each line's first word, the first word of
    the next line on one cycle that visits them all (``LINE // 8`` int64 words a line)."""
    stride = LINE // 8
    order = rng.permutation(lines) * stride
    chain = np.zeros(lines * stride, np.int64)
    chain[order] = np.roll(order, -1)
    return chain


@jit
def _walk(chain, at, reads):
    """Follow the chain ``reads`` steps from word ``at``; returns where it ends."""
    for _ in range(reads):
        at = chain[at]
    return at


def _timed_walk(chain, at, reads):
    """Nanoseconds of ``reads`` steps of the chain from word ``at``, compiled code only, and where they end."""
    start = time.perf_counter_ns()
    end = _walk(chain, at, reads)
    return float(time.perf_counter_ns() - start), end


def latency_line(latency: dict) -> str:
    """One line of ``read_latency``'s figures: 'host memory, ns a read waiting on the last: 0.25 MiB <ns>, ...'."""
    return "host memory, ns a read waiting on the last: " + ", ".join(
        f"{mib:g} MiB {ns:.1f}" for mib, ns in latency.items())
