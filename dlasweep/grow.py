"""Grow one cluster: the single entry point to the kernels."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import params as _params
from .kernels.lattice import grow_lattice
from .kernels.offlattice import grow_offlattice


@dataclass
class Cluster:
    """One grown cluster.

    Attributes
    ----------
    points : ndarray, (n_grown, dim)
        Positions in attachment order (int32 on a lattice, float64 off it),
        the seed particle(s) first.
    steps : ndarray, (n_grown,)
        Diffusion time of each particle: walk steps (or exact jumps) taken by
        every walker released between the previous attachment and this one.
    status : str
        ``ok``, ``boundary``, ``step_limit`` or ``exhausted``.
    params : dict
        Every model parameter, defaults filled in.
    checkpoints, times : ndarray
        Particle counts and the seconds spent growing to each (NaN when the
        count was not reached).
    """

    points: np.ndarray
    steps: np.ndarray
    status: str
    params: dict
    checkpoints: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    times: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def n(self) -> int:
        return len(self.points)


def rng_for(seed) -> np.random.Generator:
    """A PCG64 generator from an int or a ``numpy.random.SeedSequence``."""
    if not isinstance(seed, np.random.SeedSequence):
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"seed: expected a non-negative integer, got {seed!r}")
        seed = np.random.SeedSequence(int(seed))
    return np.random.Generator(np.random.PCG64(seed))


def grow(n: int, seed=0, *, checkpoints=None, **params) -> Cluster:
    """Grow one DLA cluster of up to ``n`` particles.

    Parameters
    ----------
    n : int
        Target number of particles, seed particles included.
    seed : int or numpy.random.SeedSequence
        Root of the cluster's random stream. Growth never depends on ``n``:
        the cluster grown to ``n`` is a prefix of the one grown further.
    checkpoints : sequence of int, optional
        Counts at which to record elapsed time (default: ``[n]``).
    **params
        Model parameters (see ``dlasweep.params.DEFAULTS``).

    Returns
    -------
    Cluster
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n: expected an integer >= 1, got {n!r}")
    p = _params.resolve(**params)
    rng = rng_for(seed)
    marks = np.unique(np.asarray([n] if checkpoints is None else checkpoints, dtype=np.int64))
    if len(marks) and (marks[0] < 1 or marks[-1] > n):
        raise ValueError(f"checkpoints: every count must lie in [1, {n}]")
    kernel = grow_lattice if p["model"] == "lattice" else grow_offlattice
    points, steps, code, times = kernel(int(n), p, marks, rng)
    return Cluster(points, steps, _params.STATUSES[code], p, marks, times)
