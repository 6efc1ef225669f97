"""Who stuck to whom on the lattice: each particle's parent.

The rule: a particle's parent is, among the occupied sites it touched when
it stuck (its neighbours under the model's contacts, ``exits.unit_moves``),
the one attached earliest; a particle that touches a substrate (a line or
plane seed: its height is 0) has parent -1, the substrate being there
first, and so have the seed particles. The sites occupied when particle i
stuck are those of particles 0..i-1 (a site is never filled twice), so the
parents follow from the positions alone: this pass over them finds exactly
what the walk touched, and the walk's hot loop stays as it was.
"""

import numpy as np

from ..._jit import jit

TILE_SHIFT = (3, 2)
"""Tiles of the site index have side 2**shift (2D: 8, 3D: 4): 64 sites, a particle's neighbours mostly in one."""


@jit
def _box(points, dim, period):
    """Lowest site and tiles per axis of a box one site larger than the sites (a substrate's sides: its period)."""
    shift = TILE_SHIFT[dim - 2]
    lo = np.zeros(3, np.int64)
    tiles = np.ones(3, np.int64)
    for a in range(dim):
        if period > 0 and a < dim - 1:
            low, high = 0, period - 1
        else:
            low, high = points[0, a], points[0, a]
            for i in range(len(points)):
                low, high = min(low, points[i, a]), max(high, points[i, a])
            low, high = low - 1, high + 1
        lo[a] = low
        tiles[a] = ((high - low) >> shift) + 1
    return lo, tiles


@jit
def _slot(q0, q1, q2, dim, lo, tiles, directory):
    """Where site q's particle index lives: (directory entry, place in its tile), or (-1, 0) off the box."""
    shift = TILE_SHIFT[dim - 2]
    mask = (1 << shift) - 1
    r0, r1, r2 = q0 - lo[0], q1 - lo[1], q2 - lo[2]
    t0, t1, t2 = r0 >> shift, r1 >> shift, r2 >> shift
    if r0 < 0 or r1 < 0 or r2 < 0 or t0 >= tiles[0] or t1 >= tiles[1] or t2 >= tiles[2]:
        return -1, 0
    return t0 + tiles[0] * (t1 + tiles[1] * t2), (r0 & mask) | ((r1 & mask) << shift) | ((r2 & mask) << (2 * shift))


@jit
def _site(points, i, dim, period, q):
    """Particle i's site into q, its periodic coordinates in [0, period)."""
    for a in range(dim):
        q[a] = points[i, a]
    if period > 0:  # a site on a periodic side has one name
        for a in range(dim - 1):
            q[a] = q[a] % period


@jit
def lattice_parents(points, moves, nseed, period):
    """Each particle's parent (the rule in the module docstring).

    The particles' indices go into tiles of ``TILE_SHIFT`` sites, allocated
    where there are particles (a dense directory of them over the box):
    neighbours share a tile or two, so the pass reads memory close to where
    it last read (a hash table took 3x as long in 2D and 5x in 3D at 1e6: a cache miss per neighbour).

    Parameters
    ----------
    points : int (n, dim)
        Sites in attachment order.
    moves : int64 (M, 3)
        The contacts (``exits.unit_moves``).
    nseed : int
        How many seed particles lead ``points`` (parent -1).
    period : int
        Width of a substrate's periodic sides; 0: no substrate.

    Returns
    -------
    int32 (n,)
    """
    n, dim = points.shape
    up = dim - 1
    parents = np.full(n, -1, np.int32)
    if n == 0:
        return parents
    size = 1 << (dim * TILE_SHIFT[dim - 2])
    lo, tiles = _box(points, dim, period)
    directory = np.full(tiles[0] * tiles[1] * tiles[2], -1, np.int32)
    q = np.zeros(3, np.int64)
    used = 0
    for i in range(n):
        _site(points, i, dim, period, q)
        t, _ = _slot(q[0], q[1], q[2], dim, lo, tiles, directory)
        if directory[t] < 0:
            directory[t] = used
            used += 1
    index = np.full(used * size, -1, np.int32)
    for i in range(n):
        _site(points, i, dim, period, q)
        if i >= nseed and not (period > 0 and q[up] == 0):
            best = -1
            for m in range(moves.shape[0]):
                n0, n1, n2 = q[0] + moves[m, 0], q[1] + moves[m, 1], q[2] + moves[m, 2]
                if period > 0:
                    n0 = n0 % period
                    if dim == 3:
                        n1 = n1 % period
                t, k = _slot(n0, n1, n2, dim, lo, tiles, directory)
                if t >= 0 and directory[t] >= 0:
                    j = index[directory[t] * size + k]
                    if j >= 0 and (best < 0 or j < best):
                        best = j
            parents[i] = best
        t, k = _slot(q[0], q[1], q[2], dim, lo, tiles, directory)
        index[directory[t] * size + k] = i
    return parents
