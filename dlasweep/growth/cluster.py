"""Grow one cluster: the single entry point to the kernels."""

from __future__ import annotations

import io
import reprlib
import threading
import time
from dataclasses import dataclass, field, replace

import numpy as np

from .. import params as _params
from ..kernels import lattice, offlattice

KERNELS = {"lattice": lattice.grow_lattice, "offlattice": offlattice.grow_offlattice}
WATCH_MARKS = 200
"""Counts at which a watched growth reports progress: every n / WATCH_MARKS particles."""
WATCH_SECONDS = 0.2
"""How often a watched growth calls its ``progress`` and looks at ``STOP``."""
STOP = threading.Event()
"""Set while an interrupted sweep closes its embedded cluster: a growth waiting in a worker's thread
then raises ``Interrupted`` within ``WATCH_SECONDS``, so that closing, which joins those threads,
does not wait for the kernels, which run for as long as a cluster takes to grow (docs/performance.md, "Growth")."""


class Interrupted(Exception):
    """A growth given up because ``STOP`` was set; its kernel runs on until the process ends."""


INLINE_INCHES, INLINE_DPI = 4.5, 100
"""A cluster's inline picture in a notebook (``Cluster._repr_png_``): 450 pixels square, tens of KB."""


@dataclass
class Cluster:
    """One grown cluster.

    ``grow`` makes it, and ``read_cluster`` from a sweep's file; its fields
    are its constructor's parameters.

    Parameters
    ----------
    points : ndarray, (n_grown, dim)
        Positions in attachment order (int32 on a lattice, float64 off it),
        the seed particle(s) first.
    steps : ndarray, (n_grown,) uint32
        Diffusion time of each particle: walk steps (or exact jumps) taken by
        every walker released between the previous attachment and this one
        (2^32 - 1 means at least that many: ``kernels.model.STEPS_DTYPE``).
    status : str
        ``ok``, ``boundary``, ``step_limit`` or ``exhausted``.
    params : dict
        Every model parameter, defaults filled in.
    checkpoints, times : ndarray
        Particle counts and the seconds spent growing to each (NaN when the
        count was not reached).
    seconds : float
        The whole growth (NaN when not known).
    parents : ndarray, (n_grown,) int32
        Index of the particle each one stuck to, -1 for the seed particles
        and for those that stuck to a substrate: the cluster as a tree. Off
        the lattice, the disk (sphere) touched at contact; on it, of the
        occupied neighbours touched, the earliest attached, the substrate
        first (``kernels.lattice.parents``). None when not known.
    """

    points: np.ndarray
    steps: np.ndarray
    status: str
    params: dict
    checkpoints: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    seconds: float = np.nan
    parents: np.ndarray | None = None

    @property
    def n(self) -> int:
        """Particles in the cluster (``len(points)``), the seed particles included."""
        return len(self.points)

    def prefix(self, m: int) -> Cluster:
        """The cluster as it was at ``m`` particles: its first ``m``, in attachment order (views, not copies).

        Growth only adds particles, so the first m of a cluster are the cluster it was at m, with the
        same model; its status and clock readings are the grown cluster's.

        Parameters
        ----------
        m : int
            Particles to keep, from the first.

        Returns
        -------
        Cluster
        """
        parents = None if self.parents is None else self.parents[:m]
        return replace(self, points=self.points[:m], steps=self.steps[:m], parents=parents)

    def _repr_png_(self) -> bytes:
        """The cluster's picture (``pictures.cluster_figure``) as PNG bytes: how Jupyter shows a ``Cluster``.

        At ``INLINE_INCHES`` and ``INLINE_DPI`` whatever its size, so a
        large cluster shows blocks of sites (or disks under a pixel) rather
        than a picture of megabytes.
        """
        from ..reporting.pictures import cluster_figure  # here: growing a cluster needs no matplotlib

        fig = cluster_figure(self.points, self.params, status=self.status, inches=INLINE_INCHES, dpi=INLINE_DPI)
        png = io.BytesIO()
        fig.savefig(png, format="png", dpi=fig.dpi)
        return png.getvalue()


def rng_for(seed) -> np.random.Generator:
    """A PCG64 generator from an int or a ``numpy.random.SeedSequence``."""
    if not isinstance(seed, np.random.SeedSequence):
        if not _params.is_integer(seed) or seed < 0:
            raise ValueError(f"seed: expected a non-negative integer, got {seed!r}")
        seed = np.random.SeedSequence(int(seed))
    return np.random.Generator(np.random.PCG64(seed))


def kernel_of(params: dict) -> tuple:
    """(model, dim, lockstep, gaussian): what tells apart the growth kernels numba compiles for the resolved
    parameters ``params``: one walker and lockstep walkers are compiled apart
    (``kernels.model.lockstep_flag``), and so, off the lattice, are exact moves and Gaussian steps
    (``kernels.model.gaussian_flag``)."""
    return params["model"], params["dim"], params["walkers"] > 1, params["step"] > 0.0


def compiled(params: dict) -> bool:
    """Whether numba's cache holds the growth kernel of the resolved parameters ``params`` (``kernel_of``;
    it takes most of the compile time).

    Only this process's cache is looked at: the embedded cluster's too.
    """
    if params["model"] == "lattice":
        return lattice.lattice_growth.compiled(params["dim"], params["walkers"])
    return offlattice.offlattice_growth.compiled(params["dim"], params["walkers"], params["step"])


def grow(n: int, seed=0, *, checkpoints=None, progress=None, **params) -> Cluster:
    """Grow one DLA cluster of up to ``n`` particles.

    Parameters
    ----------
    n : int
        Target number of particles, seed particles included.
    seed : int or numpy.random.SeedSequence
        Root of the cluster's random stream. Growth never depends on ``n``:
        the cluster grown to ``n`` is a prefix of the one grown further.
    checkpoints : sequence of int, optional
        Counts at which to record elapsed time, whole numbers in [1, n] (default: ``[n]``).
    progress : callable, optional
        Called as ``progress(particles, seconds)`` every ``WATCH_SECONDS``
        while the cluster grows, and once at the end; the cluster is the same.
    **params
        Model parameters (see ``dlasweep.params.DEFAULTS``).

    Returns
    -------
    Cluster

    Notes
    -----
    The kernel runs in another thread (it releases the GIL) while this one
    waits for it, so that Ctrl-C (``KeyboardInterrupt``) reaches the caller at
    once, not when growth ends. The interrupted kernel is not stopped: the
    ``dlasweep`` command exits, which ends it; in a Python session it
    finishes in the background.
    """
    p, marks = _checked(n, checkpoints, params)
    result = _watched(KERNELS[p["model"]], int(n), p, marks, rng_for(seed), progress)
    return _cluster(result, p, marks)


def grow_many(n: int, seeds, *, checkpoints=None, **params) -> list:
    """``grow`` with each of ``seeds``, in one compiled call: the same clusters, in order.

    A sweep's batches of small clusters grow this way; one call for each
    cluster cost more than growing one of 10^3 particles. Parameters are those of
    ``grow`` (``seeds``: a sequence of its ``seed``), without ``progress``.

    Returns
    -------
    list of Cluster
    """
    p, marks = _checked(n, checkpoints, params)
    rngs = [rng_for(seed) for seed in seeds]
    results = _waited(lambda: KERNELS[p["model"]](int(n), p, marks, rngs))
    return [_cluster(result, p, marks) for result in results]


def _checked(n, checkpoints, params):
    """The resolved parameters and the sorted checkpoints of a growth to ``n``, checked."""
    if not _params.is_integer(n) or n < 1:
        raise ValueError(f"n: expected an integer >= 1, got {n!r}")
    p = _params.resolve(**params)
    given = np.asarray([n] if checkpoints is None else checkpoints)
    # a whole count written as a float (1e3) is one; 10.5, a table or a word is not
    if given.ndim != 1 or given.dtype.kind not in "iuf" or not np.all(np.isfinite(given) & (given == np.round(given))):
        raise ValueError(f"checkpoints: expected a list of whole counts, got {reprlib.repr(checkpoints)}")
    marks = np.unique(given.astype(np.int64))
    if len(marks) and (marks[0] < 1 or marks[-1] > n):
        raise ValueError(f"checkpoints: every count must lie in [1, {n}]")
    return p, marks


def _cluster(result, p, marks):
    points, steps, parents, code, times, seconds = result
    return Cluster(points, steps, _params.Status(code).name, dict(p), marks, times, seconds, parents)


def _waited(call, between=None):
    """``call()`` run in a thread while this one waits, and its result; ``between()`` after each wait.

    Python runs a signal's handler here, between joins, never inside a compiled kernel, so that
    Ctrl-C reaches the caller at once; ``STOP`` reaches a caller that is not the main thread.
    """
    result = []

    def run():
        try:
            result.append(call())
        except BaseException as err:  # noqa: BLE001 (raised again in the caller's thread)
            result.append(err)

    worker = threading.Thread(target=run, name="dlasweep-grow", daemon=True)
    worker.start()
    while worker.is_alive():
        worker.join(WATCH_SECONDS)
        if STOP.is_set() and worker.is_alive():  # a growth that ended meanwhile is kept
            raise Interrupted("growth given up: the sweep was interrupted")
        if between is not None:
            between()
    if isinstance(result[0], BaseException):
        raise result[0]
    return result[0]


def _watched(kernel, n, p, marks, rng, progress=None):
    """``kernel(n, p, marks, [rng])`` run in a thread while this one waits, interruptible; the counts it
    passes reported to ``progress`` (when given).

    Growth does not depend on the marks (they only read a clock), so more
    marks are passed, every n / ``WATCH_MARKS``, and the times it fills are
    read as it goes, so that watching a large growth costs it nothing. Without
    ``progress`` only ``marks`` are passed: setting up and reading the watch
    marks would weigh on a small cluster's ``grow`` (docs/performance.md, "Growth").
    """
    if progress is None:
        (result,) = _waited(lambda: kernel(n, p, marks, [rng]))
        return result
    watch = np.union1d(marks, np.linspace(0, n, WATCH_MARKS + 1)[1:].astype(np.int64)).astype(np.int64)
    times = np.full((1, len(watch)), np.nan)
    start = time.perf_counter()

    def report():
        passed = np.flatnonzero(~np.isnan(times[0]))
        progress(int(watch[passed[-1]]) if len(passed) else 0, time.perf_counter() - start)

    (result,) = _waited(lambda: kernel(n, p, watch, [rng], times), report if progress is not None else None)
    points, steps, parents, code, _, seconds = result
    if progress is not None:
        progress(len(points), time.perf_counter() - start)
    return points, steps, parents, code, times[0, np.isin(watch, marks)], seconds
