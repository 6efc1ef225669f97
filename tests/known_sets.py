"""Point sets whose dimension is known exactly, built here: the yardstick of every fit.

``KNOWN[name]`` is a ``KnownSet``. Deterministic self-similar sets are built
on the lattice by iterating a generator (``iterated``); random ones keep each
sub-block of a generator with a fixed probability (a random Cantor set,
whose dimension is log(expected children) / log(base) on survival), or fill
a region uniformly. Off-lattice versions are the same sets with continuous
positions: jittered within their cells, so that particles straddle boxes.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import cached_property

import numpy as np


def iterated(pieces, level):
    """Lattice points of a self-similar set: ``pieces`` are the kept sub-blocks of a base**dim block."""
    pieces = np.array(pieces)
    base = pieces.max() + 1
    points = np.zeros((1, pieces.shape[1]), np.int64)
    for _ in range(level):
        points = (points[:, None, :] * base + pieces[None]).reshape(-1, pieces.shape[1])
    return points


def random_cantor(base, dim, keep, level, seed):
    """Random Cantor set: every sub-block of every block survives with probability ``keep``.

    Redrawn (with the next seed) until it survives to the last level, so it is never empty.
    """
    children = np.array(list(itertools.product(range(base), repeat=dim)))
    rng = np.random.default_rng(seed)
    while True:
        points = np.zeros((1, dim), np.int64)
        for _ in range(level):
            points = (points[:, None, :] * base + children[None]).reshape(-1, dim)
            points = points[rng.random(len(points)) < keep]
            if len(points) == 0:
                break
        if len(points):
            return points


def sierpinski_gasket(level):
    """Pascal's triangle mod 2: the sites (x, y) of a 2**level square with x & y == 0."""
    x, y = np.meshgrid(np.arange(2**level), np.arange(2**level))
    keep = (x & y) == 0
    return np.c_[x[keep], y[keep]]


def pascal_gasket(level):
    """Pascal's triangle mod 2 on 2**level rows: C(i, j) is odd iff j's bits are among i's (Lucas).

    ``sierpinski_gasket`` mirrored (i = 2**level - 1 - x), in row order.
    """
    i, j = np.mgrid[0 : 2**level, 0 : 2**level]
    return np.argwhere((i & j) == j)


CARPET = [p for p in itertools.product(range(3), repeat=2) if p != (1, 1)]
VICSEK = [(0, 0), (0, 2), (1, 1), (2, 0), (2, 2)]
DUST_2D = list(itertools.product((0, 2), repeat=2))
DUST_3D = list(itertools.product((0, 2), repeat=3))
MENGER = [p for p in itertools.product(range(3), repeat=3) if sum(c == 1 for c in p) < 2]
TETRAHEDRON = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
"""A base-2 generator keeping 4 of 8 sub-cubes: dimension exactly 2 in 3D."""
T_BASE4 = [(x, y) for x in range(4) for y in range(4) if y == 3 or x in (1, 2)]
"""A base-4 'T' generator keeping 10 of 16: dimension log 10 / log 4."""


@dataclass(frozen=True)
class KnownSet:
    """A set of known dimension.

    Attributes
    ----------
    build : callable
        Returns the lattice points, (n, dim) int64.
    D : float
        The exact dimension.
    exact : bool
        Exactly self-similar on the lattice (a deterministic generator or a filled block of 2**k).
    """

    build: object
    D: float
    exact: bool

    @cached_property
    def points(self):
        return self.build()

    def offlattice(self, seed=0):
        """The same set with continuous positions, each jittered uniformly within +-0.3 of its site."""
        jitter = np.random.default_rng(seed).uniform(-0.3, 0.3, self.points.shape)
        return self.points + jitter

    @property
    def extent(self):
        return int(np.ptp(self.points, axis=0).max()) + 1


def _log(a, b):
    return float(np.log(a) / np.log(b))


KNOWN = {
    "line": KnownSet(lambda: np.c_[np.arange(1024), np.zeros(1024, np.int64)], 1.0, True),
    "diagonal": KnownSet(lambda: np.c_[np.arange(1500), np.arange(1500)], 1.0, False),
    "square 256": KnownSet(lambda: np.argwhere(np.ones((256, 256))), 2.0, True),
    "square 300": KnownSet(lambda: np.argwhere(np.ones((300, 300))), 2.0, False),
    "cube 64": KnownSet(lambda: np.argwhere(np.ones((64, 64, 64))), 3.0, True),
    "gasket": KnownSet(lambda: sierpinski_gasket(10), _log(3, 2), True),
    "carpet": KnownSet(lambda: iterated(CARPET, 5), _log(8, 3), True),
    "vicsek": KnownSet(lambda: iterated(VICSEK, 5), _log(5, 3), True),
    "cantor dust 2d": KnownSet(lambda: iterated(DUST_2D, 6), _log(4, 3), True),
    "t base 4": KnownSet(lambda: iterated(T_BASE4, 4), _log(10, 4), True),
    "tetrahedron": KnownSet(lambda: iterated(TETRAHEDRON, 8), 2.0, True),
    "menger sponge": KnownSet(lambda: iterated(MENGER, 4), _log(20, 3), True),
    "cantor dust 3d": KnownSet(lambda: iterated(DUST_3D, 5), _log(8, 3), True),
    "random cantor 2d": KnownSet(lambda: random_cantor(3, 2, 0.7, 6, 1), _log(9 * 0.7, 3), False),
    "random cantor 3d": KnownSet(lambda: random_cantor(3, 3, 0.5, 5, 2), _log(27 * 0.5, 3), False),
    "uniform random 2d": KnownSet(lambda: np.argwhere(np.random.default_rng(3).random((400, 400)) < 0.5), 2.0,
                                  False),
    "uniform random 3d": KnownSet(lambda: np.argwhere(np.random.default_rng(4).random((80, 80, 80)) < 0.5), 3.0,
                                  False),
}
