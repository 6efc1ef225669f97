"""The centre field and the centre pyramid: distances from cells' centres to
the nearest particle, which bound a walker's distance to the cluster from
below (``offlattice.grid.map_dist``, ``lattice.walker.distance_bound``).

Level 0 is the kernel's own field. Off-lattice it is the centre field, a
byte per coarse cell of side ``2**FS``: the distance from its centre to the
nearest particle's unit cell, to ``CCAP`` cells (``_centre_lower``, at every
particle); the lattice keeps a Chebyshev field there (``lattice.words``).
A coarse cell is held when a particle lies in it. Each level above, cells
``2**PYRAMID_STEP`` times wider, holds the distance from its cells' centres to
the nearest held cell of the level below, to ``FCAP`` cells
(``pyramid_lower``, where a cell below is newly held). Less a walker's way to
a cell's centre, each cell's value bounds the walker's distance: the centre
field's, from the ``2**dim`` cells about the walker (``centre_bound``), the
pyramid's above it, from the walker's own (``centre_gap``, ``pyramid_dist``).
Values are stored as the cap less the
distance, so that an unwritten page means the cap and costs no memory; the
levels share one array laid out by ``maps.pyramid_starts``.

Throughout, ``dim`` is the dimension (2 or 3).
"""

import math

import numpy as np

from .._jit import borrow, inline, jit
from . import maps

FS = maps.FIELD_SHIFT
"""The centre field's coarse cells have side 2**FS (the lattice kernel's field is the same)."""
FCAP = (16, 6)
"""Cap of the centre pyramid's levels (their cells), 2D and 3D. A newly held cell of
the level below costs (2 cap - 1)**dim updates, hence 3D's smaller cap; larger caps,
on every level or on the upper ones alone, shorten the walk little and cost their
updates (docs/performance.md).

The levels hold Euclidean distances from their cells' centres, not whole cells between
cells as a Chebyshev pyramid would: the bound far from the cluster is closer to the
distance, and a walker's way in from the launch circle takes fewer jumps, a difference
that grows with the cluster."""
CCAP = (8, 4)
"""Cap of the centre field (coarse cells), 2D and 3D: each particle lowers the
(2 cap - 1)**dim cells about its own, 30 sites (3D 14) from their centres.
Near the cluster it bounds the distance by Euclidean distances from the cells'
centres, closer than a Chebyshev field's whole cells. The caps balance the
bound's reach against each particle's updates (the caps tried:
docs/performance.md). Its bytes hold values to 255, so it is not packed as the
lattice's field is (``lattice.field.FIELD_PACKED``), and off-lattice its size
matters less to the walk's time than the lattice field's does."""


def field_reach(cap):
    """Sites from a coarse cell's centre within which the centre field sees
    every particle: a particle ``cap`` cells away or more lies this far."""
    return ((cap - 1) << FS) + (1 << (FS - 1))


def _centre_rows(dim):
    """The centre field's values about a particle (``_centre_lower``), by the
    place of its unit cell in its coarse cell, row after row of coarse cells.

    A coarse cell ``d`` cells along an axis from the particle's, whose unit cell
    lies ``s`` sites into its own, has its centre ``max((d << FS) + h - 1 - s,
    s - (d << FS) - h, 0)`` whole sites (h half a coarse cell) beyond that unit
    cell's faces; the value is the distance in ``CENTRE_UNITS`` a site, rounded
    down (``int(sqrt(...))`` of a whole number: exact where it is a square and
    otherwise far from one), capped, stored as ``CENTRE_TOP - distance``.
    """
    cap = CCAP[dim - 2]
    units = 255 // field_reach(cap)
    top = units * field_reach(cap)
    side, span, h = 1 << FS, 2 * cap - 1, 1 << (FS - 1)
    d = np.arange(-(cap - 1), cap)
    gaps = np.stack([np.maximum(np.maximum((d << FS) + h - 1 - s, s - (d << FS) - h), 0) for s in range(side)])
    rows = np.zeros((side,) * dim + (span,) * dim, np.uint8)
    for sub in np.ndindex(*(side,) * dim):
        n = sum(np.ix_(*[gaps[s] ** 2 for s in sub[::-1]]))  # axes (z,) y, x: a row runs along x
        q = np.minimum(np.sqrt(units * units * n.astype(float)).astype(np.int64), top)
        rows[sub[::-1]] = top - q
    return units, top, rows.reshape(-1)


_units2, _top2, CENTRE_ROWS_2D = _centre_rows(2)
_units3, _top3, CENTRE_ROWS_3D = _centre_rows(3)
_STEP = maps.PYRAMID_STEP


def _level_rows(dim):
    """The centre pyramid's values about a newly held cell of the level below
    (``pyramid_lower``), by its place in its cell of the level, row after row
    of the level's cells: the distance from each cell's centre to the held cell
    (a box), in ``LEVEL_UNITS`` a level cell, rounded down, capped at ``FCAP``
    cells, stored as ``LEVEL_TOP - distance``. The gaps are whole in halves of
    a held cell, so the rounding is exact (an integer square root)."""
    cap = FCAP[dim - 2]
    sub = 1 << _STEP[dim]
    units = int(255 // (cap - 0.5))
    top = int(units * (cap - 0.5))
    span = 2 * cap - 1
    # in halves of a held cell: the level cells' centres from the low corner of the box's level cell
    centre = 2 * sub * np.arange(-(cap - 1), cap) + sub
    gaps = np.stack([np.maximum(np.maximum(2 * s - centre, centre - 2 * (s + 1)), 0) for s in range(sub)])
    rows = np.zeros((sub,) * dim + (span,) * dim, np.uint8)
    for place in np.ndindex(*(sub,) * dim):
        n = sum(np.ix_(*[gaps[s] ** 2 for s in place[::-1]]))
        q = np.minimum([math.isqrt(v) for v in (units * units * n.reshape(-1) // (4 * sub * sub)).tolist()], top)
        rows[place[::-1]] = top - q.reshape(n.shape)
    return units, top, rows.reshape(-1)


_lunits2, _ltop2, LEVEL_ROWS_2D = _level_rows(2)
_lunits3, _ltop3, LEVEL_ROWS_3D = _level_rows(3)
LEVEL_UNITS = (0, 0, _lunits2, _lunits3)
"""By dimension: the centre pyramid's units a level cell."""
LEVEL_TOP = (0, 0, _ltop2, _ltop3)
"""By dimension: the centre pyramid's cap, in its units (a stored zero)."""
LEVEL_HELD = (0, 0, _ltop2 - _lunits2 // 2 + 1, _ltop3 - _lunits3 // 2 + 1)
"""By dimension: above this stored value a level cell holds a held cell of the level below
(its centre lies within half a cell of it; a box outside lies half a cell away or more)."""
CENTRE_UNITS = (0, 0, _units2, _units3)
"""By dimension: the centre field's units a site, as fine as a byte holds up to ``field_reach``."""
CENTRE_TOP = (0, 0, _top2, _top3)
"""By dimension: the centre field's cap, in its units (a stored zero)."""
CENTRE_OWN = tuple(top - int(np.sqrt(float(units * units * dim))) if units else 0
                   for dim, units, top in zip(range(4), CENTRE_UNITS, CENTRE_TOP))
"""By dimension: at or above this value a coarse cell holds a particle's unit cell itself: such a
particle is at most sqrt(dim) from its centre (whole sites: a particle in any other cell, 2 or more)."""


@borrow
def _lower_rows(field, dim, fw, rows, cap, shift, i, j, k):
    """Lower a field of ``fw`` cells a side about cell (i, j, k) of the grid
    ``2**shift`` times finer: each cell within ``cap - 1`` takes the maximum of
    its value and the row table's (``rows``, by the place of (i, j, k) in its
    cell). Each row is a stretch of the table taken by a branch-free maximum
    the compiler vectorises (unsigned indices, as in ``lattice.field.field_lower``), a
    tile's stretch at a time.

    ``dim`` is the dimension, 2 or 3 (``k`` is 0 in 2D).
    """
    reach, span = cap - 1, 2 * cap - 1
    m = (1 << shift) - 1
    last = (1 << maps.FIELD_TILE[dim]) - 1
    ci, cj, ck = i >> shift, j >> shift, k >> shift
    sub = ((((k & m) << shift) if dim == 3 else 0) + (j & m)) * (m + 1) + (i & m)  # the place's table
    klo, khi = (max(ck - reach, 0), min(ck + reach, fw - 1)) if dim == 3 else (0, 0)
    alo, ahi = max(ci - reach, 0), min(ci + reach, fw - 1)
    for c in range(klo, khi + 1):
        for b in range(max(cj - reach, 0), min(cj + reach, fw - 1) + 1):
            row = sub * span + c - ck + reach if dim == 3 else sub
            row = (row * span + b - cj + reach) * span + reach - ci
            a = alo
            while a <= ahi:
                end = min(ahi, a | last)
                fb, rb = np.uint64(maps.field_cell(dim, fw, a, b, c)), np.uint64(row + a)
                for x in range(np.uint64(end + 1 - a)):
                    field[fb + x] = max(field[fb + x], rows[rb + x])
                a = end + 1


@borrow
def _centre_lower(field, dim, fw, i, j, k):
    """Lower the centre field about a particle in unit cell (i, j, k) of the maps.

    Each coarse cell within ``CCAP - 1`` of the particle's holds the distance from
    its centre to the nearest particle's unit cell, rounded down and capped
    (``_centre_rows``), so that zero is the cap and an unwritten page costs no
    memory.

    ``field`` is the centre field, ``fw`` coarse cells a side; ``dim`` is the dimension, 2 or 3 (``k``
    is 0 in 2D).
    """
    _lower_rows(field, dim, fw, CENTRE_ROWS_2D if dim == 2 else CENTRE_ROWS_3D, CCAP[dim - 2], FS, i, j, k)


@borrow
def level_lower(level, dim, fw, bi, bj, bk):
    """Record held cell (bi, bj, bk) of the level below in ``level``, a level of the centre
    pyramid ``fw`` cells a side: its cells within ``FCAP - 1`` take the distance from their
    centres to it (``_level_rows``).

    ``dim`` is the dimension, 2 or 3 (``bk`` is 0 in 2D).
    """
    _lower_rows(level, dim, fw, LEVEL_ROWS_2D if dim == 2 else LEVEL_ROWS_3D, FCAP[dim - 2], _STEP[dim], bi, bj, bk)


@borrow
def levels_from_held(field, starts, width, dim):
    """Build the centre pyramid's levels above the first (``starts``: ``maps.pyramid_starts`` of a
    grid of side ``width``), each in one pass about every held cell of the level below: what
    ``pyramid_lower`` builds a held cell at a time, for a grid whose first level is whole.

    ``field`` is the whole pyramid, its levels one after the other from ``starts``; ``dim`` is the
    dimension, 2 or 3.
    """
    bits = maps.FIELD_TILE[dim]
    per_tile = 1 << (dim * bits)
    for upper in range(2, len(starts) - 1):
        below, level = field[starts[upper - 1]:starts[upper]], field[starts[upper]:starts[upper + 1]]
        shift = FS + _STEP[dim] * upper
        side_below = (width + (1 << (shift - _STEP[dim])) - 1) >> (shift - _STEP[dim])
        side = (width + (1 << shift) - 1) >> shift
        tiles = (side_below + (1 << bits) - 1) >> bits
        base = 0
        for tk in range(tiles if dim == 3 else 1):
            for tj in range(tiles):
                for ti in range(tiles):
                    for inner in range(per_tile):
                        if np.int64(below[base + inner]) > LEVEL_HELD[dim]:
                            a, b, c = maps.untiled(dim, bits, ti, tj, tk, inner)
                            level_lower(level, dim, side, a, b, c)
                    base += per_tile


@borrow
def pyramid_lower(field, dim, W, i, j, k, levels):
    """Record a newly held coarse cell, that of unit cell (i, j, k), in the
    centre pyramid's levels 1 to ``levels - 1``: each level's cells within
    ``FCAP - 1`` take the distance from their centres to the held cell of the
    level below (``_level_rows``), up to the first level whose cell held one
    already. Returns that level, -1 when none did.

    A coarse cell is newly held about once every few particles, so this costs
    a particle about what the field's lowering does, and grows little with the
    cluster (docs/performance.md).

    Parameters
    ----------
    field : uint8 (...)
        The field with the pyramid's levels above it (``maps.pyramid_starts``' layout).
    dim : int
        2 or 3.
    W : int
        The grid's side in unit cells.
    i, j, k : int
        The unit cell (k 0 in 2D).
    levels : int
        Levels of the pyramid, the field's included (``maps.pyramid_levels``).
    """
    base = 0
    step = _STEP[dim]
    for level in range(levels):
        shift = FS + step * level
        fw = (W + (1 << shift) - 1) >> shift
        size = maps.field_size(dim, fw)
        if level > 0:
            bi, bj, bk = i >> (shift - step), j >> (shift - step), (k >> (shift - step) if dim == 3 else 0)
            here = base + maps.field_cell(dim, fw, bi >> step, bj >> step, bk >> step)
            held = np.int64(field[here]) > LEVEL_HELD[dim]
            level_lower(field[base:base + size], dim, fw, bi, bj, bk)
            if held:
                return level
        base += size
    return -1


@inline
def cell_centre(X, shift):
    """Where, along one axis, the grid point X's cell of side ``2**shift`` has its centre."""
    return float((int(X) >> shift) << shift) + float(1 << (shift - 1))


@jit
def centre_gap(X0, X1, X2, dim, shift):
    """Distance from the grid point X to the centre of its cell of side ``2**shift``.

    X is (``X0``, ``X1``, ``X2``), ``X2`` 0 in 2D; ``dim`` is the dimension, 2 or 3.
    """
    d0 = X0 - cell_centre(X0, shift)
    d1 = X1 - cell_centre(X1, shift)
    d2 = X2 - cell_centre(X2, shift) if dim == 3 else 0.0
    return np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)


@inline
def centre_bound(field, dim, fw, X0, X1, X2):
    """The centre field's value at grid point X's coarse cell (0: at the cap), and
    its lower bound on the distance from X to every particle centre: the largest,
    over the ``2**dim`` coarse cells whose centres surround X, of a cell's distance
    (a capped cell's: the cap's, ``field_reach``) less X's way to its centre.

    Each cell's centre gives a bound (the distance is 1-Lipschitz); X's own alone
    is loose by up to half a cell's diagonal, and near the cluster every jump
    would be shorter for it. The pyramid above the field (``pyramid_dist``) reads
    X's own cell only: the surrounding cells there save steps but no time. The
    cells are spelled out, with fixed strides within a tile, rather than a loop
    over them with ``field_cell``. The cell that gives the bound is not
    tracked for a ball exit (as the pyramid's is): the steps it would save are
    near ones, cheap, and its tracking would cost every bound step. The figures:
    docs/performance.md.

    Parameters
    ----------
    field : uint8 (...)
        The centre field (level 0 of the pyramid's array).
    dim : int
        2 or 3.
    fw : int
        The field's side in coarse cells (at least 2).
    X0, X1, X2 : float
        The point in grid coordinates (X2 0 in 2D).

    Returns
    -------
    e : int64
        The stored value of X's coarse cell (0: at the cap).
    bound : float
        The lower bound on the distance from X to every particle centre.
    """
    side = float(1 << FS)
    scale, top = 1.0 / CENTRE_UNITS[dim], CENTRE_TOP[dim]
    e = np.int64(field[maps.field_cell(dim, fw, int(X0) >> FS, int(X1) >> FS, int(X2) >> FS)])
    # the cells c..c + 1 on each axis, inside the field (fw >= 2: the grid is wider than a cell)
    c0 = min(max(int(X0 / side - 0.5), 0), fw - 2)
    c1 = min(max(int(X1 / side - 0.5), 0), fw - 2)
    c2 = min(max(int(X2 / side - 0.5), 0), fw - 2) if dim == 3 else 0
    t = maps.FIELD_TILE[dim]
    last = (1 << t) - 1
    inside = (c0 & last) != last and (c1 & last) != last and (dim == 2 or (c2 & last) != last)
    f000 = maps.field_cell(dim, fw, c0, c1, c2)
    if inside:  # within one tile a step along an axis is a fixed stride
        f100, f010, f110 = f000 + 1, f000 + (1 << t), f000 + 1 + (1 << t)
    else:
        f100 = maps.field_cell(dim, fw, c0 + 1, c1, c2)
        f010 = maps.field_cell(dim, fw, c0, c1 + 1, c2)
        f110 = maps.field_cell(dim, fw, c0 + 1, c1 + 1, c2)
    g0 = X0 - side * (c0 + 0.5)
    g1 = X1 - side * (c1 + 0.5)
    g2 = X2 - side * (c2 + 0.5) if dim == 3 else 0.0
    a0, b0 = g0 * g0, (g0 - side) * (g0 - side)
    a1, b1 = g1 * g1, (g1 - side) * (g1 - side)
    a2, b2 = g2 * g2, (g2 - side) * (g2 - side)
    best = max(max((top - np.int64(field[f000])) * scale - np.sqrt(a0 + a1 + a2),
                   (top - np.int64(field[f100])) * scale - np.sqrt(b0 + a1 + a2)),
               max((top - np.int64(field[f010])) * scale - np.sqrt(a0 + b1 + a2),
                   (top - np.int64(field[f110])) * scale - np.sqrt(b0 + b1 + a2)))
    if dim == 3:
        if inside:
            up = 1 << (2 * t)
            f001, f101, f011, f111 = f000 + up, f100 + up, f010 + up, f110 + up
        else:
            f001 = maps.field_cell(dim, fw, c0, c1, c2 + 1)
            f101 = maps.field_cell(dim, fw, c0 + 1, c1, c2 + 1)
            f011 = maps.field_cell(dim, fw, c0, c1 + 1, c2 + 1)
            f111 = maps.field_cell(dim, fw, c0 + 1, c1 + 1, c2 + 1)
        best = max(best,
                   max(max((top - np.int64(field[f001])) * scale - np.sqrt(a0 + a1 + b2),
                           (top - np.int64(field[f101])) * scale - np.sqrt(b0 + a1 + b2)),
                       max((top - np.int64(field[f011])) * scale - np.sqrt(a0 + b1 + b2),
                           (top - np.int64(field[f111])) * scale - np.sqrt(b0 + b1 + b2))))
    return e, best


@borrow
def pyramid_dist(field, pstart, dim, W, X0, X1, X2):
    """Lower bound on the centre distance from grid point X to every particle
    from the centre pyramid's levels above the field, 0 when all are at their
    cap: the first level below its cap puts every particle its value from the
    centre of X's cell, less X's way to that centre.

    That cell's disk, or a neighbour's, holds X off its centre and may be
    larger than the one about X; the walker's exit from it has a closed form
    (``walk.ball_exit``). The off-lattice walk jumps out of X's own cell's
    ball (``pyramid_ball``); the lattice walk does not, as there an exit costs
    more than the jumps it saves. Larger disks of nearby cells, and a search
    that starts at the level the walker's last far jump used, cost more than
    they save too (docs/performance.md).

    Parameters
    ----------
    field : uint8 (...)
        The field with the pyramid's levels above it.
    pstart : int64 (L + 1,)
        Where each level starts in ``field`` (``maps.pyramid_starts``).
    dim : int
        2 or 3.
    W : int
        The grid's side in unit cells.
    X0, X1, X2 : float
        The point in grid coordinates (X2 0 in 2D).
    """
    centre, _, gap = pyramid_ball(field, pstart, dim, W, X0, X1, X2)
    return centre - gap


@borrow
def pyramid_ball(field, pstart, dim, W, X0, X1, X2):
    """The distance from the centre of grid point X's cell in the first level of the centre
    pyramid above the field below its cap to every particle, that level's shift (its cells
    have side ``2**shift``) and X's distance to that centre (``centre_gap``); 0.0, 0 and 0.0
    when all are at their cap.

    A ball about that centre holds no particle: the off-lattice walk jumps out of it
    (``walk.ball_exit``) where it is larger than the ball about X.

    Most of its time waits on the level's read; reading level 2 first, or
    levels 1 and 2 together so that their misses overlap, does not shorten
    that wait (docs/performance.md).

    Parameters
    ----------
    field : uint8 (...)
        The field with the pyramid's levels above it.
    pstart : int64 (L + 1,)
        Where each level starts in ``field`` (``maps.pyramid_starts``).
    dim : int
        2 or 3.
    W : int or float
        The grid's side in unit cells.
    X0, X1, X2 : float
        The point in grid coordinates (X2 0 in 2D).
    """
    step = _STEP[dim]
    for level in range(1, len(pstart) - 1):
        shift = FS + step * level
        fw = (int(W) + (1 << shift) - 1) >> shift
        e = np.int64(field[pstart[level] + maps.field_cell(dim, fw, int(X0) >> shift, int(X1) >> shift,
                                                           (int(X2) >> shift) if dim == 3 else 0)])
        if e > 0:
            centre = (LEVEL_TOP[dim] - e) * (float(1 << shift) / LEVEL_UNITS[dim])
            return centre, shift, centre_gap(X0, X1, X2, dim, shift)
    return 0.0, 0, 0.0
