"""The harmonic measure of a frozen cluster: where the next particle would land.

``harmonic_measure`` fires walkers at a grown cluster, each released, moved
and stuck exactly as in growth (``kernels.harmonic``), and records the
particle each would have stuck to without attaching it: the hits per
particle sample the growth probabilities of the cluster's sites. From them
``dlasweep.stats.multifractal`` fits the generalised dimensions D(q) and the
spectrum f(alpha); the landing places give the deposition depth.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from .. import params as _params

KEY = 0x48415252
"""The first entry of every block's spawn key (``SeedSequence(seed, spawn_key=(KEY, b))``): a measurement's
streams are never those of a growth (``growth.cluster.rng_for``) or a sweep's children from the same seed."""


@dataclass(frozen=True)
class HarmonicMeasure:
    """Walkers fired at a frozen cluster, and where each would have stuck.

    Attributes
    ----------
    points : ndarray, (n, dim)
        The cluster's points (not copied).
    hits : ndarray, (n,) int64
        Walkers that would have stuck to each particle (the growth's parent rule: off the
        lattice the disk touched, on it the earliest attached of the occupied neighbours).
    touched : ndarray, (walkers,) int32
        The particle each walker would have stuck to, in walker order; -1 for the substrate.
    where : ndarray, (walkers,) float64
        Each walker's distance from the origin where it stuck (above a substrate: its height).
    steps : ndarray, (walkers,) uint32
        Each walker's moves from its release (``kernels.model.diffusion_time``).
    radius : float
        The cluster's radius: its largest distance of a particle from the origin (above a
        substrate: its height).
    walkers : int
        Walkers that stuck: all asked for unless ``status`` is ``step_limit``.
    substrate : int
        Walkers that would have stuck to the substrate.
    seed : int
        The measurement's seed.
    status : str
        ``ok``, or ``step_limit`` when a walker spent the model's ``max_steps`` moves
        (the walkers before it are kept).
    params : dict
        The cluster's model parameters.
    seconds : float
        The walks' time.
    """

    points: np.ndarray
    hits: np.ndarray
    touched: np.ndarray
    where: np.ndarray
    steps: np.ndarray
    radius: float
    walkers: int
    substrate: int
    seed: int
    status: str
    params: dict = field(repr=False)
    seconds: float = np.nan

    @property
    def probabilities(self) -> np.ndarray:
        """Each particle's share of the walkers that stuck to a particle: the sampled harmonic measure."""
        stuck = self.hits.sum()
        return self.hits / stuck if stuck else self.hits.astype(np.float64)

    @property
    def depth(self) -> tuple[float, float]:
        """The deposition depth: the mean and standard deviation of ``where`` over ``radius``.

        Where the walkers land, as a fraction of the cluster's radius: near 1 they
        land on its tips, lower the deeper they reach into its fjords.
        """
        if self.walkers == 0 or not self.radius > 0:
            return np.nan, np.nan
        x = self.where / self.radius
        return float(x.mean()), float(x.std(ddof=1)) if len(x) > 1 else np.nan

    def renyi_entropies(self, q, first=None) -> np.ndarray:
        """The Renyi entropies of the sampled measure at the particles, one for each order in ``q``.

        H_q = log(sum_i p_i**q) / (1 - q), Shannon's -sum_i p_i log p_i at q = 1, with p_i the share of
        particle i in the walkers that stuck to a particle. They are taken at the particles, the
        scale of the growth's own probabilities, because their growth with the cluster's size is what
        the generalised dimensions of DLA's growth measure name: sum_i p_i**q ~ R**(-(q - 1) D(q)), so
        that H_q grows as D(q) log R (``stats.multifractal.size_scaling``). Of the ``first`` walkers
        only, the same sums show the finite sample's bias: it halves as the walkers double.

        Parameters
        ----------
        q : array_like
            The orders, q >= 0.
        first : int, optional
            Use only the first ``first`` walkers (``touched[:first]``); all of them when None.

        Returns
        -------
        ndarray
            H_q for each q; NaN when no walker stuck to a particle.
        """
        q = np.atleast_1d(np.asarray(q, np.float64))
        if first is None:
            counts = self.hits
        else:
            touched = self.touched[:first]
            counts = np.bincount(touched[touched >= 0], minlength=len(self.points))
        counts = counts[counts > 0]
        if not len(counts):
            return np.full(len(q), np.nan)
        p = counts / counts.sum()
        logp = np.log(p)
        one = np.isclose(q, 1.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            sums = np.log(np.exp(np.outer(np.where(one, 0.0, q), logp)).sum(axis=1))
            return np.where(one, -(p * logp).sum(), sums / np.where(one, 1.0, 1.0 - q))


def harmonic_measure(cluster, walkers: int, seed: int = 0) -> HarmonicMeasure:
    """Fire ``walkers`` walkers at the frozen ``cluster`` and count where each would stick.

    Every walker is released, moved and stuck exactly as in the cluster's growth
    (its model: launch circle or box, exact return or kill circle, jumps, stickiness,
    the contact rule), but nothing attaches: the cluster stays as it is, and each
    walker's particle is the one it would have become the child of. The counts
    sample the harmonic measure (the growth probability) of each particle.

    Walkers come in blocks of ``kernels.harmonic.BLOCK``, block b from the stream
    ``SeedSequence(seed, spawn_key=(KEY, b))``: the first k walkers of a
    measurement are those of any larger one with the same seed, and blocks
    walked apart (``blocks``, ``kernels.harmonic.frozen_walks``) give the same
    walkers, so that a measurement can be shared between workers.

    A model of many walkers at once (``walkers > 1`` in its parameters) has
    its walkers released one at a time here, as its single walker would be:
    against a frozen cluster its walkers do not meet. A walker that spends
    the model's ``max_steps`` moves ends the measurement (``status``).

    Parameters
    ----------
    cluster : Cluster
        A grown cluster (``dlasweep.grow``); its ``points`` and ``params`` are read.
    walkers : int
        Walkers to fire, >= 1.
    seed : int
        Root of the walkers' streams, >= 0.

    Returns
    -------
    HarmonicMeasure
    """
    from ..growth.cluster import _waited
    from ..kernels.harmonic import frozen_walks

    if not _params.is_integer(walkers) or walkers < 1:
        raise ValueError(f"walkers: expected an integer >= 1, got {walkers!r}")
    if not _params.is_integer(seed) or seed < 0:
        raise ValueError(f"seed: expected a non-negative integer, got {seed!r}")
    points = np.asarray(cluster.points)
    if len(points) == 0:
        raise ValueError("cluster: no particles to fire walkers at")
    p = _params.resolve(**cluster.params)
    walkers, seed = int(walkers), int(seed)
    start = time.perf_counter()
    # in a thread while this one waits, as growth's kernels run: Ctrl-C reaches the caller at once
    touched, where, steps, code = _waited(lambda: frozen_walks(points, p, blocks(seed, walkers), walkers))
    seconds = time.perf_counter() - start
    line = p["seed_shape"] == "line"
    x = points.astype(np.float64)
    radius = float(x[:, -1].max() if line else np.sqrt((x ** 2).sum(axis=1)).max())
    on = touched >= 0
    hits = np.bincount(touched[on], minlength=len(points)).astype(np.int64)
    return HarmonicMeasure(points, hits, touched, where, steps, radius, len(touched), int((~on).sum()), seed,
                           _params.Status(code).name, dict(p), seconds)


def blocks(seed: int, walkers: int, first: int = 0) -> list:
    """The Generators of the blocks of walkers ``first`` to ``walkers - 1`` (``first`` a multiple of the block).

    Parameters
    ----------
    seed : int
        The measurement's seed.
    walkers : int
        One past the last walker.
    first : int
        The first walker.

    Returns
    -------
    list of numpy.random.Generator
    """
    from ..kernels.harmonic import BLOCK

    return [np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(KEY, b))))
            for b in range(first // BLOCK, -(-walkers // BLOCK))]
