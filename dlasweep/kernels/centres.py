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
"""

import math

import numpy as np

from .._jit import borrow, inline, jit
from . import maps

FS = maps.FIELD_SHIFT
"""The centre field's coarse cells have side 2**FS (the lattice kernel's field is the same)."""
FCAP = (16, 6)
"""Cap of the centre pyramid's levels (their cells), 2D and 3D. A newly held cell of
the level below costs (2 cap - 1)**dim updates, hence 3D's smaller cap; larger 3D caps
did not shorten the walk: a 3D lattice cluster of 1e6 (seed 1) took 98.7 steps a
particle with a cap of 8 and 99.2 with 10, against 99.8 with 6.

The levels hold Euclidean distances from their cells' centres, where the
Chebyshev pyramid before them held whole cells between cells: the bound far from
the cluster went from about 0.72 of the distance to about 0.9, and a walker's way
in from the launch circle takes fewer jumps, a difference that grows with the
cluster. Side by side (seed 1; 3D 1e5 seeds 1 and 2): 2D 1e6 4.94 s against 5.32
(54.9 steps a particle against 61.4), 2D 1e7 64.37 against 74.80 (58.5 against
72.3), 3D 1e5 2.30 against 2.34 (112.2 against 124.0), 3D 1e6 15.31 against 18.19
(125.7 against 143.8).

A yet tighter bound saves few steps, and in 2D none of their growth with N
(the far jumps, 3.7 a particle at 2D 1e5 and 13.7 at 1e7, cross gaps that widen
with the cluster). Caps of (64, 16), the bound within a few percent of the
distance (lattice, seed 1): 2D 1e6 38.9 steps a particle against 40.1, 2D 1e7
43.8 against 45.2 (12.6% more than at 1e6 with either); 3D 1e6 98.1 against
99.8, 3D 1e7 107.9 against 116.1, but in 280 s, not side by side, where the
present caps took 197 to 232 beside other runs (a newly held cell rewrites
31**3 cells of a level, against 11**3). The exact distance to the nearest held
coarse cell in the pyramid's place (a brute-force measurement, not a kernel)
at 1e5: 2D 33.5 against 34.6 (the pyramid's bound 0.93 of it on average), 3D
84.6 against 86.3 (0.84). A larger cap on levels 2 and up alone (12 in 3D, where a
newly held cell is rare): 3D lattice 1e7, seeds 1 and 2, 109.4 and 110.1 steps against 116.1
and 112.3 in 0.914 and 1.035 times the time; 3D off-lattice 1e5, seeds 1 to 6, 98.1 steps
against 96.3 (coarser units a level cell). Again on a host whose last-level cache holds 8 MiB
at 15 ns a read (3D lattice, seed 1, side by side, the cores swapped): 1e7 109.4 steps against
116.1 in 0.994 and 1.011 times the time, 1e5 84.4 against 86.3 in 0.998 and 0.980; a cap of 12
on levels 3 and up alone, 1e7 113.4 steps in 0.951 and 1.043 times, 1e5 unchanged. Not kept."""
CCAP = (8, 4)
"""Cap of the centre field (coarse cells), 2D and 3D: each particle lowers the
(2 cap - 1)**dim cells about its own, 30 sites (3D 14) from their centres.
Near the cluster the Chebyshev field it replaced bounded the distance by whole
cells: with it, 207 steps a particle at 3D 1e5 and 79 at 2D 1e5, with the
exact nearest distance in its place (a measurement, not a kernel) 115 and
47, with this field 124 and 54. Caps measured (``GRID_GROWTH`` 2.0): 2D 1e6
6, 8, 11: 6.25, 5.97, 6.33 s; 3D 1e5 3, 4, 6: 2.87, 2.72, 3.06 s. Its bytes hold values to 255,
so it is not packed as the lattice's field is (``lattice.field.FIELD_PACKED``), and its size tells less:
the field and the pyramid stored in two bytes a cell, 3D off-lattice 1e6 took 1.043 and 1.031
times the time, 3e6 1.059 and 1.013 (seed 1, side by side, the cores swapped), where the 3D
lattice took 1.08 and 1.06 at 1e6."""


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
    tile's stretch at a time."""
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
    """
    _lower_rows(field, dim, fw, CENTRE_ROWS_2D if dim == 2 else CENTRE_ROWS_3D, CCAP[dim - 2], FS, i, j, k)


@borrow
def level_lower(level, dim, fw, bi, bj, bk):
    """Record held cell (bi, bj, bk) of the level below in ``level``, a level of the centre
    pyramid ``fw`` cells a side: its cells within ``FCAP - 1`` take the distance from their
    centres to it (``_level_rows``)."""
    _lower_rows(level, dim, fw, LEVEL_ROWS_2D if dim == 2 else LEVEL_ROWS_3D, FCAP[dim - 2], _STEP[dim], bi, bj, bk)


@borrow
def levels_from_held(field, starts, width, dim):
    """Build the centre pyramid's levels above the first (``starts``: ``maps.pyramid_starts`` of a
    grid of side ``width``), each in one pass about every held cell of the level below: what
    ``pyramid_lower`` builds a held cell at a time, for a grid whose first level is whole."""
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

    Its cost grows little with the cluster (3D lattice, seed 1, clocks about it and about
    the field's lowering in a timing copy): 0.148 newly held coarse cells a particle at 1e5,
    1e6 and 3e6; this recording 0.27, 0.31 and 0.32 us a particle, the field's lowering
    0.28, 0.28 and 0.29, the whole attachment (clocks included) 0.99, 1.06 and 1.10."""
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
    """Distance from the grid point X to the centre of its cell of side ``2**shift``."""
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
    is loose by up to half a cell's diagonal, and near the cluster every jump is
    shorter for it: 2D 1e6 (4 seeds side by side) 55.0 walk steps a particle
    against 48.5 with the surrounding centres, 1e7 60.6 against 54.6; 3D 1e7 137.3
    against 119.4. The same above the field (``pyramid_dist``) took fewer steps
    (2D 1e6: 46.3; 3D lattice 1e6: 98.1 against 100.0) but no less time (2D 1.05
    to 1.15 times; 3D 0.96 to 1.11; 3D lattice 1e7, seeds 1 and 2: 112.2 and 109.4
    against 116.1 and 112.3 steps, 1.018 and 1.095 times), and is not done. The cells
    are spelled out, with fixed strides within a tile: as a loop over them with
    ``field_cell`` (the same walks) 2D 1e6 took 1.02 and 1.04 times the time.

    Measured and not kept: the walker's exit from the ball about the centre of
    the cell that gives the bound (``walk.ball_exit``, as the pyramid's), that
    cell tracked here. Side by side against the pyramid's exits alone: 2D 1e6
    40.8 and 39.9 steps a particle against 45.6 and 45.7, 0.85 to 1.42 times the
    time (6 pairs, median 0.94); 2D 1e7 44.3 against 50.4, 1.053 times; 3D 1e6
    83.1 and 81.2 against 100.7 and 102.4, 0.948 and 0.988 times; 3D 1e7 92.1
    against 109.7, 1.054 times (seed 1). The steps saved are near ones, cheap;
    the cell's tracking costs every bound step.
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
    ball (``pyramid_ball``): 2D 1e6, seeds 1 and 2, 45.6 and 45.7 steps a
    particle against 47.8 and 48.6, in 0.85 and 0.84 times the time (side by
    side, one core each); in ``workflows/cost_exponent.py`` (its rounds against
    the rows they replaced, run on an earlier day), 2D 1e7 7495 and
    8257 ns a particle against 9043 and 9466 (50.4 and 50.9 steps against
    54.6 and 53.1), 1e5 5414 and 5814 against 6276 and 6340; 3D 1e7 28863 and
    29352 against 33407 and 34867 (109.7 and 111.9 steps against 120.6 and
    119.7), 1e5 15640 and 15868 against 17856 and 19234. The lattice walk
    does not: its circle jumps where the pyramid's bound reached farthest,
    made such exits (seed 1, side by side), took 43.2 steps a particle against
    45.2 at 2D 1e7 in 1.072 times the time, 107.2 against 116.1 at 3D 1e7 in
    1.108 times; again with the field packed (``lattice.field.FIELD_PACKED``; side by side, the
    cores swapped), 3D 1e5 85.1 against 86.3 in 1.064 and 1.039 times, 1e6 94.8 against
    99.8 in 1.025 and 1.035, 1e7 107.2 in 0.999 and 1.070: an exit costs more than the
    jumps it saves. Measured and not done (2D
    lattice, side by side): the largest such disk of the 5x5 cells about X's
    took 31.7 steps a particle at 1e5 against 34.6, and 1.05 to 1.28 times the
    time at 1e6 (6 seeds); the disk of the cell two cells up the pyramid's
    gradient, 32.1, 35.7 and 39.9 steps at 1e5, 1e6 and 1e7 against 34.6, 40.1
    and 45.3, a slower growth with N, and 1.01 times the time at 1e6 (geometric
    mean of 16 seeds), 1.10 at 1e7 (2 seeds); the disk of the cell three cells
    out along the walker's radius, read in the same pass as this bound, 31.9
    and 36.6 steps at 1e5 and 1e6 against 34.6 and 39.9, and 1.05 times the
    time at 1e6 (16 seeds). The cells read cost more than the jumps saved.
    Nor do the levels below the answer cost: the search started at the level
    the walker's previous far jump used (the same clusters) took 0.82 to 1.27
    times the time at 3D lattice 1e6 (10 seeds, median 1.02), 1.002 and 0.952
    at 1e7 (2 seeds). Nor in the off-lattice walk, its far walkers past the field
    (``offlattice.grid.FAR_CLEAR``): the search from the level of the walker's last
    ball exit, down only while the level below might not be at its cap (a level whose
    value puts the one below at least its cap away, less the way between their
    centres, ends it unread), took 1.027 and 1.096 times the time at 2D 1e7, 0.968
    and 1.027 at 3D 3e6 (seeds 1 and 2, the same clusters, side by side)."""
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

    Most of its time at 3D lattice 3e6 waits on the level's read (80% of its
    samples, perf). Measured and not done: level 2 read first, and level 1's read
    skipped where level 2's value puts level 1 at its cap beneath X (each held cell
    below lies in a held cell above; the same clusters): 3D lattice 3e6 (seed 1,
    side by side, the cores swapped) 70.1 and 69.0 s against 66.8 and 67.1. Nor levels 1
    and 2 read together, both loads issued before either is tested so that their misses
    overlap (the same clusters, side by side, the cores swapped): 3D lattice 3e6 0.937 and
    0.989 times the time (seed 1), 1.025 and 1.072 (seed 2); 3D off-lattice 3e6 0.958 and
    1.048; 2D lattice 1e7 1.043 and 1.069."""
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
