"""Who stuck to whom on the lattice: each particle's parent.

The rule: a particle's parent is, among the occupied sites it touched when
it stuck (its neighbours under the model's contacts, ``exits.unit_moves``),
the one attached earliest; a particle that touches a substrate (a line or
plane seed: its height is 0) has parent -1, the substrate being there
first, and so have the seed particles. The sites occupied when particle i
stuck are those of particles 0..i-1 (a site is never filled twice), so the
parents follow from the positions alone: this pass over them finds exactly
what the walk touched, and the walk's hot loop keeps no record of contacts.

Throughout, ``dim`` is the dimension (2 or 3).
"""

import numpy as np

from ..._jit import inline, jit
from ..maps import tiled, untiled, zeroed

TILE_SHIFT = (3, 2)
"""Tiles of the site index have side 2**shift (2D: 8, 3D: 4): 64 sites, one bit each in a word."""
DIRECTORY_BITS = (5, 3)
"""The directory of tiles is stored in squares (cubes) of 2**bits tiles (2D: 32x32 int32, a 4 KiB page),
so that its pages along the cluster are the only ones written (``maps.zeroed``)."""


@jit
def _box(points, dim, period):
    """Lowest site and tiles a side of a square (cubic) box one site larger than the sites
    (a substrate's sides: its period).

    ``points`` are the sites, int32 (n, dim); ``dim`` is the dimension, 2 or 3; ``period`` a substrate's
    period (0 without one).
    """
    shift = TILE_SHIFT[dim - 2]
    lo = np.zeros(3, np.int64)
    side = 1
    for a in range(dim):
        if period > 0 and a < dim - 1:
            low, high = 0, period - 1
        else:
            low, high = points[0, a], points[0, a]
            for i in range(len(points)):
                low, high = min(low, points[i, a]), max(high, points[i, a])
            low, high = low - 1, high + 1
        lo[a] = low
        side = max(side, ((high - low) >> shift) + 1)
    return lo, side


@jit
def _slot(q0, q1, q2, dim, lo, side):
    """Where site q lives: (its tile's directory entry, its bit in the tile's word), or (-1, 0) off the box.

    q is (``q0``, ``q1``, ``q2``), ``q2`` 0 in 2D; ``dim`` is the dimension, 2 or 3; ``lo`` and ``side``
    are the box's lowest site and its tiles a side (``_box``).
    """
    shift = TILE_SHIFT[dim - 2]
    mask = (1 << shift) - 1
    r0, r1, r2 = q0 - lo[0], q1 - lo[1], q2 - lo[2]
    t0, t1, t2 = r0 >> shift, r1 >> shift, r2 >> shift
    if r0 < 0 or r1 < 0 or r2 < 0 or t0 >= side or t1 >= side or t2 >= side:
        return -1, 0
    return (tiled(dim, DIRECTORY_BITS[dim - 2], side, t0, t1, t2),
            (r0 & mask) | ((r1 & mask) << shift) | ((r2 & mask) << (2 * shift)))


@jit
def _site(points, i, dim, period, q):
    """Particle i's site into q, its periodic coordinates in [0, period).

    ``points`` are the sites, int32 (n, dim); ``dim`` is the dimension, 2 or 3; ``q`` is an int64 (3,)
    written in place.
    """
    for a in range(dim):
        q[a] = points[i, a]
    if period > 0:  # a site on a periodic side has one name
        for a in range(dim - 1):
            q[a] = q[a] % period


@jit
def _ones(word):
    """How many bits of ``word`` are set (a population count)."""
    x = word - ((word >> np.uint64(1)) & np.uint64(0x5555555555555555))
    x = (x & np.uint64(0x3333333333333333)) + ((x >> np.uint64(2)) & np.uint64(0x3333333333333333))
    x = (x + (x >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return np.int64((x * np.uint64(0x0101010101010101)) >> np.uint64(56))


@jit
def _below(word, bit):
    """How many of ``word``'s set bits lie below ``bit``: a site's place among its tile's particles."""
    return _ones(word & ((np.uint64(1) << np.uint64(bit)) - np.uint64(1)))


@jit
def _site_index(points, period, tile):
    """The index of the occupied sites of ``points`` (n >= 1) that ``lattice_parents`` describes:
    the box's lowest site and side in tiles, the directory of tiles, which of its squares (cubes)
    hold one, each held tile's word and offset, and the particles' indices in tile order.

    Parameters
    ----------
    points : int32 (n, dim)
        The sites, n >= 1.
    period : int
        A substrate's period (its periodic coordinates indexed in [0, period)); 0 without one.
    tile : int32 (n,)
        Receives each particle's tile number (the caller may pass an array it reuses).

    Returns
    -------
    lo, side, directory, used, words, offsets, index
        As above, in that order.
    """
    n, dim = points.shape
    lo, side = _box(points, dim, period)
    bits = DIRECTORY_BITS[dim - 2]
    cubes = (side + (1 << bits) - 1) >> bits  # the directory's squares (cubes) of tiles, a side
    per_cube = 1 << (dim * bits)
    directory = zeroed((cubes << bits) ** dim, np.int32)  # a held tile's number + 1; 0: no particle there
    used = np.zeros(cubes ** dim, np.uint8)  # whether a square (cube) of the directory holds a tile
    q = np.zeros(3, np.int64)
    for i in range(n):
        _site(points, i, dim, period, q)
        t, _ = _slot(q[0], q[1], q[2], dim, lo, side)
        directory[t] = 1
        used[t // per_cube] = 1
    held = 0
    for c in range(len(used)):
        if used[c]:
            for t in range(c * per_cube, (c + 1) * per_cube):
                if directory[t] != 0:
                    held += 1
                    directory[t] = held
    words = np.zeros(held, np.uint64)
    for i in range(n):
        _site(points, i, dim, period, q)
        t, k = _slot(q[0], q[1], q[2], dim, lo, side)
        tile[i] = directory[t] - 1
        words[tile[i]] |= np.uint64(1) << np.uint64(k)
    offsets = np.zeros(held + 1, np.int64)
    for u in range(held):
        offsets[u + 1] = offsets[u] + _ones(words[u])
    index = np.empty(n, np.int32)
    for i in range(n):
        _site(points, i, dim, period, q)
        _, k = _slot(q[0], q[1], q[2], dim, lo, side)
        index[offsets[tile[i]] + _below(words[tile[i]], k)] = i
    return lo, side, directory, used, words, offsets, index


@jit
def lattice_parents(points, moves, nseed, period):
    """Each particle's parent (the rule in the module docstring).

    The sites are indexed by tiles of ``TILE_SHIFT`` (64 sites): a directory
    over the box numbers the tiles that hold particles, each such tile has a
    word of its occupied sites and an offset into one array of the particles'
    indices in tile order, a site's index at its tile's offset plus the
    occupied bits below its own. That costs 4 bytes a particle and 16 a tile
    held, about 5 bytes a particle in all (a dense int32 per site of each
    tile costs several times that), and neighbours share a tile or two (a
    hash table costs a cache miss per neighbour: docs/performance.md).

    The tiles are numbered in the directory's order, and the neighbours are
    looked up site after site in that order, each site read from its tile's
    word: the lookups then read memory close to where they last read, where
    in attachment order each particle's are a cache miss or more apart. The
    tile numbers are kept in ``parents`` until the last pass overwrites them.
    ``_earliest_neighbour`` is inlined (``_jit.inline``): called, it costs a
    call per particle, and reference counting of its arrays under ``jit``.
    The times, and a variant that prefetches in attachment order and does no
    better: docs/performance.md.

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
    parents = np.empty(n, np.int32)
    if n == 0:
        return parents
    lo, side, directory, used, words, offsets, index = _site_index(points, period, parents)
    bits, shift = DIRECTORY_BITS[dim - 2], TILE_SHIFT[dim - 2]
    cubes = (side + (1 << bits) - 1) >> bits  # the directory's squares (cubes) of tiles, a side
    per_cube = 1 << (dim * bits)
    for c in range(len(used)):
        if used[c] == 0:
            continue
        c0, c1, c2 = c % cubes, (c // cubes) % cubes, c // (cubes * cubes) if dim == 3 else 0
        for e in range(per_cube):
            u = directory[c * per_cube + e] - 1
            if u < 0:
                continue
            t0, t1, t2 = untiled(dim, bits, c0, c1, c2, e)
            rest = words[u]
            for at in range(offsets[u], offsets[u + 1]):
                k = _ones((rest & (~rest + np.uint64(1))) - np.uint64(1))  # the lowest set bit's place
                rest &= rest - np.uint64(1)
                i = index[at]
                r0, r1, r2 = untiled(dim, shift, t0, t1, t2, k)  # the site, from the box's lowest
                q0, q1, q2 = lo[0] + r0, lo[1] + r1, lo[2] + r2
                parents[i] = -1 if i < nseed or (period > 0 and (q2 if dim == 3 else q1) == 0) else \
                    _earliest_neighbour(i, q0, q1, q2, moves, dim, period, lo, side, directory, words, offsets, index)
    return parents


@inline
def _earliest_neighbour(i, q0, q1, q2, moves, dim, period, lo, side, directory, words, offsets, index):
    """The earliest particle before particle i, at site q = (q0, q1, q2), among q's neighbours
    (``moves``); -1 for none.

    ``period`` wraps a substrate's sides; ``lo`` and ``side`` are the box (``_box``);
    ``directory``, ``words``, ``offsets`` and ``index`` the site index that ``lattice_parents``
    builds: each tile's number, its occupied sites' bits, its start in ``index``, and the
    particles' numbers in tile order.

    ``dim`` is the dimension, 2 or 3.
    """
    best = -1
    for m in range(moves.shape[0]):
        n0, n1, n2 = q0 + moves[m, 0], q1 + moves[m, 1], q2 + moves[m, 2]
        if period > 0:
            n0 = n0 % period
            if dim == 3:
                n1 = n1 % period
        t, k = _slot(n0, n1, n2, dim, lo, side)
        if t < 0 or directory[t] == 0:
            continue
        u = directory[t] - 1
        if (words[u] >> np.uint64(k)) & np.uint64(1):
            j = index[offsets[u] + _below(words[u], k)]
            if j < i and (best < 0 or j < best):
                best = j
    return best


@jit
def touched(points, sites, moves, period):
    """The particle of ``points`` that each of ``sites`` touches under the rule of the module
    docstring, as if it stuck there after every particle: of its occupied neighbours (``moves``) the
    earliest attached; -1 for a site that touches the substrate (height 0; the substrate is first)
    or no particle.

    The walkers against a frozen cluster (``kernels.harmonic``) stick at ``sites``: this names the
    particle each would have become the child of, from the same index as ``lattice_parents``.

    Parameters
    ----------
    points : int (n, dim)
        The cluster's sites in attachment order.
    sites : int (W, dim)
        The walkers' sites, each next to the cluster.
    moves : int64 (M, 3)
        The contacts (``exits.unit_moves``).
    period : int
        Width of a substrate's periodic sides; 0: no substrate.

    Returns
    -------
    int32 (W,)
    """
    n, dim = points.shape
    out = np.full(len(sites), -1, np.int32)
    if n == 0:
        return out
    lo, side, directory, used, words, offsets, index = _site_index(points, period, np.empty(n, np.int32))
    q = np.zeros(3, np.int64)
    for w in range(len(sites)):
        _site(sites, w, dim, period, q)
        if period > 0 and q[dim - 1] == 0:
            continue
        out[w] = _earliest_neighbour(n, q[0], q[1], q[2], moves, dim, period, lo, side, directory, words, offsets,
                                     index)
    return out
