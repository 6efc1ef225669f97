"""The dask session of a sweep: the client it runs on, and the process's tuning while tasks run.

A sweep runs on the client given, on a scheduler named by address or
scheduler file, or on an embedded ``LocalCluster`` of one in-process worker
with a thread per core (``connected``). While it runs, threads hand over the
GIL sooner (``SWITCH_INTERVAL``) and the garbage collector runs less often
(``collector_eased``). distributed is imported inside these functions, so
that ``dlasweep grow`` and ``info`` never load it.
"""

from __future__ import annotations

import contextlib
import gc
import json
import logging
import math
import os
import sys
import threading
from pathlib import Path

from ..growth.cluster import STOP

SWITCH_INTERVAL = 0.0005
"""Seconds a thread may hold the GIL while another waits, in the embedded cluster
(Python's default: 0.005). A thread back from a kernel then waits less for the GIL; a sweep of many
small clusters, where those waits add up, runs faster (docs/performance.md, "Sweeps")."""


COLLECT_EVERY = 20_000
"""Allocations between the garbage collector's young collections while a sweep runs (Python's default: 700).

A sweep allocates many short-lived objects; each collection holds the GIL, and fewer collections
leave more of it to the threads that hand results on (docs/performance.md, "Sweeps")."""


@contextlib.contextmanager
def collector_eased():
    """Collect garbage less often while the tasks run; as before afterwards, also after a failure.

    What the imports, kernels and cluster made (about 200,000 objects)
    outlives the sweep, so it is frozen out of the full collections, which
    would scan all of it each time; young collections run every
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
def connected(client, scheduler_file, workers, n_tasks, load):
    """A client: the one given, one for an address or scheduler file, or an embedded cluster.

    ``load`` is called in a thread while the embedded cluster starts (``precompile.load_kernels``).
    """
    # distributed loads here, not with the module: ``dlasweep grow`` and ``info`` never need it
    import dask
    from distributed import Client, LocalCluster

    if isinstance(client, Client):
        yield client
        return
    if client is not None or scheduler_file is not None:
        with Client(scheduler_address(client, scheduler_file)) as remote:
            yield remote
        return
    threads = embedded_threads(workers, n_tasks)
    # The kernels release the GIL, so one in-process worker with a thread per
    # core runs them in parallel, starts in milliseconds instead of a second
    # per spawned process, and loads the compiled kernels once, not per process.
    # Its worker shares this process: no memory limit to watch (memory_limit=0),
    # and no statistical profiler sampling the threads under the GIL.
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
