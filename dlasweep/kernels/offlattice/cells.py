"""The off-lattice grid: a cell list of the particles and the hierarchical maps.

A cell list (cells of side ``CELL_SIDE`` in tiles of 64 cells, allocated only where
particles are, so memory follows the cluster) answers which particles lie
near a point (``gather``). The dilated maps of ``maps`` (level 1, and the
levels above it only where no pyramid is: ``_allocate_maps``), a centre
field (a byte per coarse cell of side ``2**FS``: the distance from its centre to the nearest
particle's unit cell, to ``CCAP`` cells, ``_centre_lower``) and the centre
pyramid above it (each level's cell holds the distance from its centre to the
nearest held cell of the level below, to ``FCAP`` cells, ``centres.pyramid_lower``)
bound the distance to the nearest particle from below (``map_dist``). The
centre field is the pyramid's level 0, in the same array (``maps.pyramid_starts``'
layout).

The grid's geometry is two small arrays built by ``_layout``, ``gi``
(integers) and ``gf`` (floats), read through the named slots below (numba
freezes them into the kernels as constants).

A grid is the tuple ``(gi, gf, words, start, blocks, cells, dirr, heads,
field)`` that ``build_grid`` returns. The particles' rows may be stored cell
after cell (``sort_cells``): the cell list then links rows, and the caller
keeps each row's attachment number.
"""

import numpy as np

from ..._jit import borrow, inline, jit
from .. import maps
from ..model import GRID_GROWTH
from ..centres import (
    CCAP,
    CENTRE_OWN,
    FCAP,
    FS,
    _centre_lower,
    centre_bound,
    field_reach,
    level_lower,
    levels_from_held,
    pyramid_ball,
    pyramid_dist,
    pyramid_lower,
)

LINE_PAD = 32
"""Periodic images are marked in the maps up to this distance (line seed)."""
CELL_SIDE = (8, 4)
"""Side of the cell list's cells (diameters), 2D and 3D: a power of two, a multiple of the coarse
cells' ``2**FS``. A side of 4 puts four times the area under a tile's 64 heads: memory added by
growth, 2D 1e7 37.8 -> 29.3 B/particle, 3D 3e5 53.4 -> 44.8, against a side of 2, with the same
particles gathered (the same clusters) in the same time (2D 1e6, A/B: 10.53 s against 10.61).
A side of 8 in 2D again: 2D 1e7 32.24 -> 30.62, the same clusters, 6% slower (61.1 s against
57.5, side by side), as a gather reads twice the particles; cells of 8 by 4 saved half as much
memory in the same time (62.9 s against 59.4)."""
GROW = GRID_GROWTH["offlattice"]
"""The grids' growth (``model.GRID_GROWTH``), a module constant that numba freezes into the kernels."""
HEADS_RESERVE = 2.0
"""The cell list's heads are reserved for this many times the tiles the cluster would hold after
growing by ``GROW``: its pages cost memory only once a tile is used (``maps.zeroed``), and a
cell list that outgrows them is copied, the old and new held at once."""
INF = np.inf

# Slots of gi, the grid's integer geometry (a mutable array: the cell list counts its tiles in it).
CELLS = 0  # 0-2: cell-list cells per axis
TILES = 3  # 3-5: cell-list tiles per axis
MAP_OFFSET = 6  # 6-8: where coordinate 0 falls in the maps, per axis
MAP_WIDTH = 9  # cells a side of the maps
PERIODIC = 10  # 10-12: 1 on a substrate's periodic axes
TILE_SHIFT = 13  # cell-list tiles have 2**TILE_SHIFT cells a side
TILES_USED = 14  # cell-list tiles allocated
TOP_LEVEL = 15  # largest usable map level
COVERED = 16  # half-width (point seeds) or height (substrate) the grid covers
FIELD_CAP = 17  # the distance field's cap, in coarse cells
PYRAMID_LEVELS = 18  # most levels of the centre pyramid
GI_SLOTS = 19
# Slots of gf, the grid's float geometry.
ORIGIN = 0  # 0-2: the cell list's origin per axis
INV_SIDE = 3  # 3-5: inverse cell side per axis
PERIOD = 6  # a substrate's period
GF_SLOTS = 8


@jit
def _layout(dim, line, size, need):
    """Grid geometry covering a cluster of extent ``need`` (max |coordinate|
    for point seeds, h_max for a substrate), with room to grow."""
    gi = np.zeros(GI_SLOTS, np.int64)
    gf = np.zeros(GF_SLOTS)
    tb = 3 if dim == 2 else 2
    gi[TILE_SHIFT] = tb
    side = CELL_SIDE[dim - 2]
    up = dim - 1
    gf[PERIOD] = float(size)
    if not line:
        half = int(np.ceil(GROW * (need + 8.0) / 16.0)) * 16
        if size > 0:
            half = min(half, ((size // 2 + 8) // 16 + 1) * 16)
        gi[COVERED] = half
        gi[MAP_WIDTH] = 2 * half
        gi[TOP_LEVEL] = 1 << 30
        gi[FIELD_CAP] = FCAP[dim - 2]
        gi[PYRAMID_LEVELS] = 64
        for a in range(dim):
            gi[CELLS + a] = 2 * half // side
            gi[MAP_OFFSET + a] = half
            gf[ORIGIN + a] = -float(half)
            gf[INV_SIDE + a] = 1.0 / side
    else:
        top = int(np.ceil(GROW * (need + 8.0) / 16.0)) * 16
        gi[COVERED] = top
        gi[MAP_WIDTH] = max(size + 2 * LINE_PAD, top + 2)
        gi[TOP_LEVEL] = 4  # 2**(4+1) = LINE_PAD: a clear cell's neighbourhood stays within the pad
        gi[FIELD_CAP] = LINE_PAD >> FS
        gi[PYRAMID_LEVELS] = 1  # the centre field alone (its reach within the pad): a pyramid level would reach beyond
        m = max(size // side, 1)
        for a in range(up):
            gi[CELLS + a] = m
            gi[MAP_OFFSET + a] = LINE_PAD
            gi[PERIODIC + a] = 1
            gf[ORIGIN + a] = 0.0
            gf[INV_SIDE + a] = m / float(size)
        gi[CELLS + up] = (top + 2) // side + 1
        gi[MAP_OFFSET + up] = 2
        gf[ORIGIN + up] = -2.0
        gf[INV_SIDE + up] = 1.0 / side
    for a in range(3):
        if a >= dim:
            gi[CELLS + a] = 1
            gi[TILES + a] = 1
        else:
            gi[TILES + a] = (gi[CELLS + a] + (1 << tb) - 1) >> tb
    return gi, gf


@borrow
def _cell_of(i, pts, dim, gi, gf):
    """Particle i's cell in the cell list: its tile's place in the directory and its place in the tile."""
    c0 = min(max(int(np.floor((pts[i, 0] - gf[ORIGIN]) * gf[INV_SIDE])), 0), gi[CELLS] - 1)
    c1 = min(max(int(np.floor((pts[i, 1] - gf[ORIGIN + 1]) * gf[INV_SIDE + 1])), 0), gi[CELLS + 1] - 1)
    c2 = 0
    if dim == 3:
        c2 = min(max(int(np.floor((pts[i, 2] - gf[ORIGIN + 2]) * gf[INV_SIDE + 2])), 0), gi[CELLS + 2] - 1)
    tb = gi[TILE_SHIFT]
    m = (1 << tb) - 1
    t = (c0 >> tb) + gi[TILES] * ((c1 >> tb) + gi[TILES + 1] * (c2 >> tb))
    return t, (c0 & m) | ((c1 & m) << tb) | ((c2 & m) << (2 * tb))


@borrow
def insert(i, pts, nxt, dim, gi, gf, dirr, heads):
    """Push particle i on its cell's list. False, and nothing changed, when
    its tile is new and the heads are full (give them ``more_heads``)."""
    t, loc = _cell_of(i, pts, dim, gi, gf)
    tile = dirr[t] - 1
    if tile < 0:
        tile = gi[TILES_USED]
        if (tile + 1) * 64 > len(heads):  # beyond build_grid's reserve: rare
            return False
        gi[TILES_USED] += 1
        dirr[t] = tile + 1
    h = tile * 64 + loc
    nxt[i] = heads[h] - 1
    heads[h] = i + 1
    return True


@jit
def sort_cells(pts, order, nxt, count, dim, gi, gf, dirr, heads):
    """Store particles 0..count-1 cell after cell, and their lists in that order.

    A gather then reads each cell's particles from one stretch of ``pts``
    instead of one cache line each, scattered in attachment order. Rows of
    ``pts`` and ``order`` (the attachment number of the particle in each row)
    move together; ``nxt`` and ``heads`` serve as scratch, then hold the lists
    again, each cell's rows in ascending order. Nothing is allocated: the
    permutation is followed cycle by cycle in place. The tiles renumbered in the
    directory's order first (neighbouring tiles' heads and rows together) took 1.014
    and 1.000 times the time at 3D 1e7 (seeds 1 and 2, the same clusters).
    """
    used = gi[TILES_USED] * 64
    heads[:used] = 0
    for i in range(count):
        t, loc = _cell_of(i, pts, dim, gi, gf)
        nxt[i] = (dirr[t] - 1) * 64 + loc  # the particle's cell, until its row replaces it
        heads[nxt[i]] += 1
    run = 0
    for h in range(used):
        here = heads[h]
        heads[h] = run
        run += here
    for i in range(count):
        h = nxt[i]
        nxt[i] = heads[h]  # the row particle i moves to
        heads[h] += 1
    _move_rows(pts, order, nxt, 0, count, dim)
    first = 0
    for h in range(used):
        end = heads[h]  # one past the cell's last row
        heads[h] = first + 1 if end > first else 0
        for i in range(first, end):
            nxt[i] = i + 1 if i + 1 < end else -1
        first = end


@borrow
def _move_rows(pts, order, nxt, first, count, dim):
    """Move the rows first..count-1 of ``pts`` and ``order`` to the rows ``nxt`` names, in
    place, cycle by cycle (``nxt`` of each then names its own row)."""
    for i in range(first, count):
        while nxt[i] != i:
            j = nxt[i]
            for a in range(dim):
                pts[i, a], pts[j, a] = pts[j, a], pts[i, a]
            order[i], order[j] = order[j], order[i]
            nxt[i], nxt[j] = nxt[j], j


@jit
def sort_tail(pts, order, nxt, first, count, dim, gi, gf, dirr, heads):
    """Store rows first..count-1 cell after cell, each cell's run linked ahead of its rows below ``first``.

    The rows below ``first`` were stored by ``sort_cells``; those attached
    since then sit in attachment order and are pushed on their cells' lists
    ahead of them (as is every row at or past ``first`` after a
    ``regrow_grid``). Sorting these alone costs the rows attached since
    ``first``, not the cluster, and their runs replace a gather's reads of
    one scattered row each. ``nxt`` of those rows serves as scratch; three
    arrays of at most ``count - first`` int32 are allocated.
    """
    n = count - first
    below = np.empty(n, np.int32)  # per cell of the tail: its list's first row below ``first``
    cell = np.empty(n, np.int32)  # per cell of the tail: its place in ``heads``
    run = np.zeros(n, np.int32)  # per cell of the tail: its count, then where its run ends
    seen = 0
    for i in range(first, count):
        t, loc = _cell_of(i, pts, dim, gi, gf)
        h = (dirr[t] - 1) * 64 + loc
        k = -heads[h] - 1  # a cell already met holds -(its number + 1)
        if k < 0:
            j = heads[h] - 1
            while j >= first:  # the cell's rows at or past ``first`` come first on its list
                j = nxt[j]
            k = seen
            seen += 1
            below[k] = j
            cell[k] = h
            heads[h] = -(k + 1)
        run[k] += 1
        nxt[i] = k  # the row's cell, until its new row replaces it (its list is walked already)
    end = first
    for k in range(seen):
        here = run[k]
        run[k] = end
        end += here
    for i in range(first, count):
        k = nxt[i]
        nxt[i] = run[k]  # the row particle i moves to
        run[k] += 1
    _move_rows(pts, order, nxt, first, count, dim)
    begin = first
    for k in range(seen):
        end = run[k]
        for i in range(begin, end - 1):
            nxt[i] = i + 1
        nxt[end - 1] = below[k]
        heads[cell[k]] = begin + 1
        begin = end


@jit
def attachment_order(pts, order, count):
    """Put the rows of ``pts`` back in attachment order (undo ``sort_cells``), in place."""
    for i in range(count):
        while order[i] != i:
            j = order[i]
            for a in range(pts.shape[1]):
                pts[i, a], pts[j, a] = pts[j, a], pts[i, a]
            order[i], order[j] = order[j], j


@jit
def more_heads(heads):
    """The cell list's heads with room for half as many tiles again."""
    bigger = maps.zeroed(len(heads) + len(heads) // 2, np.int32)
    bigger[: len(heads)] = heads
    return bigger


@borrow
def mark(i, pts, dim, size, gi, words, start, blocks, cells, field):
    """Mark particle i in the maps, the centre field and the centre pyramid above
    it (where its coarse cell is newly held), with its periodic images near the edges."""
    W = gi[MAP_WIDTH]
    reach = 1 if gi[PERIODIC] == 1 else 0
    reach2 = reach if dim == 3 else 0
    fw = (W + (1 << FS) - 1) >> FS
    for a in range(-reach, reach + 1):
        for b in range(-reach2, reach2 + 1):
            i0 = int(np.floor(pts[i, 0] + a * size)) + gi[MAP_OFFSET]
            i1 = int(np.floor(pts[i, 1] + (b * size if dim == 3 else 0.0))) + gi[MAP_OFFSET + 1]
            i2 = int(np.floor(pts[i, 2])) + gi[MAP_OFFSET + 2] if dim == 3 else 0
            if 0 <= i0 < W and 0 <= i1 < W and 0 <= i2 < W:
                held = np.int64(field[maps.field_cell(dim, fw, i0 >> FS, i1 >> FS, i2 >> FS)]) >= CENTRE_OWN[dim]
                _centre_lower(field, dim, fw, i0, i1, i2)
                # a coarse cell (a pyramid level's) that already held a particle has that
                # particle's coarser levels marked: only the finer ones are left
                top = min(len(cells), FS)
                if not held:
                    levels = maps.pyramid_levels(dim, W, gi[FIELD_CAP], gi[PYRAMID_LEVELS])
                    level = pyramid_lower(field, dim, W, i0, i1, i2, levels)
                    top = len(cells) if level < 0 else min(len(cells), FS + maps.PYRAMID_STEP[dim] * level)
                _mark_levels(words, dim, start, blocks, cells, i0, i1, i2, top)


@jit
def _allocate_maps(dim, gi):
    """The dilated maps of ``maps`` for the grid ``gi``, levels 1 and up, or level 1 alone.

    Level 0 (plain occupancy, a bit per unit cell and three quarters of the
    bits) is never queried here: contacts come from the cell list. Levels
    ``FS`` and up are read only where the field is at its cap with no
    pyramid above it (a substrate, a small grid): where the walk is near,
    level ``FS`` is set. With a pyramid they are left out, a quarter of the
    maps and their marks (memory added by growth, 2D 1e7: 32.52 -> 32.25
    bytes a particle). ``start`` is shifted so that level s still begins at
    ``start[s]``.
    """
    pyramid = maps.pyramid_levels(dim, gi[MAP_WIDTH], gi[FIELD_CAP], gi[PYRAMID_LEVELS]) > 1
    start, blocks, cells = maps.layout(dim, gi[MAP_WIDTH], FS if pyramid else 64)
    start -= start[min(1, len(cells) - 1)]
    return maps.zeroed(start[-1], np.uint64), start, blocks, cells


@borrow
def _mark_levels(words, dim, start, blocks, cells, i, j, k, top):
    """Set cell (i, j, k) and its neighbours in the dilated levels 1 to top - 1."""
    bs = 3 if dim == 2 else 2
    bm = (1 << bs) - 1
    for s in range(1, top):
        w = cells[s]
        nb = blocks[s]
        ci, cj, ck = i >> s, j >> s, k >> s
        klo, khi = (max(ck - 1, 0), min(ck + 1, w - 1)) if dim == 3 else (0, 0)
        for c in range(klo, khi + 1):
            for b in range(max(cj - 1, 0), min(cj + 1, w - 1) + 1):
                for a in range(max(ci - 1, 0), min(ci + 1, w - 1) + 1):
                    q = maps.block_word(dim, start[s], nb, a >> bs, b >> bs, c >> bs)
                    words[q] |= np.uint64(1) << np.uint64((a & bm) | ((b & bm) << bs) | ((c & bm) << (2 * bs)))


@jit
def _empty_grid(dim, line, size, need, tiles):
    """A grid sized for ``need`` that holds no particle, with room for ``tiles`` cell-list tiles."""
    gi, gf = _layout(dim, line, size, need)
    words, start, blocks, cells = _allocate_maps(dim, gi)
    ntiles = gi[TILES] * gi[TILES + 1] * gi[TILES + 2]
    dirr = maps.zeroed(ntiles, np.int32)
    heads = maps.zeroed(64 * (int(HEADS_RESERVE * GROW ** dim * tiles) + 64), np.int32)
    field = maps.pyramid_allocate(dim, gi[MAP_WIDTH], gi[FIELD_CAP], gi[PYRAMID_LEVELS])
    return gi, gf, words, start, blocks, cells, dirr, heads, field


@jit
def build_grid(dim, line, size, need, pts, count, nxt, tiles):
    """Maps and cell list for particles 0..count-1, sized for ``need``, with
    room for ``tiles`` cell-list tiles (the old grid's count: few change)."""
    gi, gf, words, start, blocks, cells, dirr, heads, field = _empty_grid(dim, line, size, need, tiles)
    heads = _insert_all(pts, count, nxt, dim, gi, gf, dirr, heads)
    for i in range(count):
        mark(i, pts, dim, size, gi, words, start, blocks, cells, field)
    return gi, gf, words, start, blocks, cells, dirr, heads, field


@jit
def _insert_all(pts, count, nxt, dim, gi, gf, dirr, heads):
    """Push particles 0..count-1 on their cells' lists; returns the heads (more of them if they filled)."""
    for i in range(count):
        while not insert(i, pts, nxt, dim, gi, gf, dirr, heads):
            heads = more_heads(heads)
    return heads


@jit
def regrow_grid(dim, line, size, need, pts, count, nxt, tiles, old_gi, old_field):
    """``build_grid``'s grid, bit for bit, for a cluster that outgrew the grid
    ``old_gi`` (every particle but the last marked in it), its centre field and
    the centre pyramid's first level carried over from ``old_field`` instead of
    marked again.

    The grids' coarse cells and first-level cells line up (their offsets are
    multiples of 16 sites), so the old cells are copied (``maps.carry``), and
    only the particles whose reach crossed the old grid's edge lower them again
    (the last, outside it, among them); the levels above the first are built
    from the held cells of the level below (``centres.levels_from_held``), as in
    the lattice's ``words.regrow``. Every stored value is a maximum or a union
    over particles or held cells, so the order does not matter. Before, each
    coarse cell lowered the pyramid about it, (2 ``FCAP`` - 1)**dim cells of the
    first level; a rebuild now costs a particle its insert, its level-1 marks and
    the reads of the copy: the last rebuild of a cluster of 1e6 (from the grid
    of two thirds of its extent), 2D 0.101 s against 0.271, 3D 0.252 against
    0.634; of 1e5 0.014 against 0.039 and 0.035 against 0.055. The growth, the
    same clusters: 2D 1e7 side by side 0.92 and 0.98 times the time; 3D 1e6 on
    one core, three runs each, 25.33 s against 25.34. ``old_field``'s pages go
    back to the OS once copied. Without a first level in both grids each coarse
    cell lowers the pyramid once (from the first particle pushed on its cell
    list's cell of those in it). Substrates (whose cell list's cells are not
    coarse cells) are built anew.
    """
    if line:
        return build_grid(dim, line, size, need, pts, count, nxt, tiles)
    gi, gf, words, start, blocks, cells, dirr, heads, field = _empty_grid(dim, line, size, need, tiles)
    heads = _insert_all(pts, count, nxt, dim, gi, gf, dirr, heads)
    W, old_W = gi[MAP_WIDTH], old_gi[MAP_WIDTH]
    shift = gi[MAP_OFFSET] - old_gi[MAP_OFFSET]  # sites, a multiple of 16 (``_layout``)
    step = maps.PYRAMID_STEP[dim]
    levels = maps.pyramid_starts(dim, W, gi[FIELD_CAP], gi[PYRAMID_LEVELS])
    old_levels = maps.pyramid_starts(dim, old_W, old_gi[FIELD_CAP], old_gi[PYRAMID_LEVELS])
    # the pyramid's first level too, where both grids have one and its cells line up
    pyramid = len(old_levels) > 2 and len(levels) > 2 and shift % (1 << (FS + step)) == 0
    for level in range(2 if pyramid else 1):
        s = FS + step * level
        maps.carry(old_field[old_levels[level]:old_levels[level + 1]], (old_W + (1 << s) - 1) >> s,
                   field[levels[level]:levels[level + 1]], (W + (1 << s) - 1) >> s, maps.FIELD_TILE[dim],
                   shift >> s, dim)
    maps.release(old_field, 0, len(old_field))  # every whole page, the levels above too: not held beside the new
    fw = (W + (1 << FS) - 1) >> FS
    s1 = FS + step
    old_sides = ((old_W + (1 << FS) - 1) >> FS, (old_W + (1 << s1) - 1) >> s1)
    reach = (CCAP[dim - 2] - 1, FCAP[dim - 2] - 1)  # of a held coarse cell, in cells of the field and of level 1
    level1 = field[levels[1]:levels[2]] if pyramid else field[:0]
    side1 = (W + (1 << s1) - 1) >> s1
    for i in range(count):
        i0 = int(np.floor(pts[i, 0])) + gi[MAP_OFFSET]
        i1 = int(np.floor(pts[i, 1])) + gi[MAP_OFFSET + 1]
        i2 = int(np.floor(pts[i, 2])) + gi[MAP_OFFSET + 2] if dim == 3 else 0
        # a particle whose field (first level) reached beyond the old grid's edge (the
        # last, outside it, among them) has cells there the old grid lacked
        edge0 = edge1 = False
        for a in range(dim):
            o = int(np.floor(pts[i, a])) + old_gi[MAP_OFFSET + a]
            c0, c1 = o >> FS, o >> s1
            edge0 = edge0 or c0 < reach[0] or c0 >= old_sides[0] - reach[0]
            edge1 = edge1 or c1 < reach[1] or c1 >= old_sides[1] - reach[1]
        if edge0:
            _centre_lower(field, dim, fw, i0, i1, i2)
        top = min(len(cells), FS)
        if pyramid:
            if edge1:
                level_lower(level1, dim, side1, i0 >> FS, i1 >> FS, i2 >> FS)
        elif _first_in_coarse_cell(i0, i1, i2, nxt[i], pts, nxt, dim, gi):
            level = pyramid_lower(field, dim, W, i0, i1, i2, len(levels) - 1)
            top = len(cells) if level < 0 else min(len(cells), FS + step * level)
        _mark_levels(words, dim, start, blocks, cells, i0, i1, i2, top)
    if pyramid:
        levels_from_held(field, levels, W, dim)
    return gi, gf, words, start, blocks, cells, dirr, heads, field


@borrow
def _first_in_coarse_cell(i0, i1, i2, j, pts, nxt, dim, gi):
    """Whether a particle at map cell (i0, i1, i2), its cell's list going on at j, was the first pushed
    on that list of those in its coarse cell (of side ``2**FS``): none further down the list shares it."""
    while j >= 0:
        if ((int(np.floor(pts[j, 0])) + gi[MAP_OFFSET]) >> FS == i0 >> FS
                and (int(np.floor(pts[j, 1])) + gi[MAP_OFFSET + 1]) >> FS == i1 >> FS
                and (dim == 2 or (int(np.floor(pts[j, 2])) + gi[MAP_OFFSET + 2]) >> FS == i2 >> FS)):
            return False
        j = nxt[j]
    return True


@jit
def face_gap(X0, X1, X2, dim, s):
    """Distance from the grid point X to the nearest face of its cell of side ``2**s``.

    Scalars only, so that the walk's hot loop pays no reference counting.
    """
    side = float(1 << s)
    c = float((int(X0) >> s) << s)
    f = min(X0 - c, c + side - X0)
    c = float((int(X1) >> s) << s)
    f = min(f, X1 - c, c + side - X1)
    if dim == 3:
        c = float((int(X2) >> s) << s)
        f = min(f, X2 - c, c + side - X2)
    return f


FAR_CLEAR = tuple(field_reach(CCAP[d - 2]) + (1 << FS) * np.sqrt(d) + 1.0 if d > 1 else 0.0 for d in range(4))
"""By dimension: where the centre pyramid bounds w's distance by this much, the coarse cells whose
centres lie within a cell's diagonal of w (w's own and those ``centre_bound`` reads) are at the
centre field's cap, every particle ``field_reach`` or more from their centres, and the field
bounds less than the pyramid. A walker that comes from far (the launch circle, a return to it, a
ball's exit) reads the pyramid first and, beyond this, not the field (``walk_bound``): the same
bound and ball, the same clusters. Side by side (one core each, seeds 1 and 2): 2D 1e7 0.864 and
0.918 times the time, 3D 3e6 0.877 (seed 1); 2D 1e6 1.012 and 1.014, 3D 1e6 1.002 and 1.091: the
field's cells about the cluster's far walkers outgrow the caches."""
NEAR = 2.0
"""Where the centre field bounds no more than this, the level-1 map decides:
clear, every centre lies 2 or more away; set, the walker takes the neighbour list."""


@jit
def map_dist(w, dim, size, gi, words, start, blocks, cells, field):
    """Lower bound on the centre distance from w to every particle, from the
    centre field and the maps.

    The centre field puts every particle centre its value (``_centre_lower``)
    from a coarse cell's centre, so that less w's distance to that centre
    bounds it: the largest such bound of the cells about w
    (``centres.centre_bound``). Where that says little (``NEAR`` or less, or
    at the field's cap), the largest clear map level s puts every particle
    outside the 3**dim block of level-s cells around w: 2**s plus w's
    distance to its level-s cell's faces. Returns 0 when the level-1 cell is
    set (look closer), -1 off the map. At the field's cap, away from periodic
    sides, the centre pyramid above the field bounds instead of the maps
    (``pyramid_dist``). (``_walk`` spells this out inline.)
    """
    W = gi[MAP_WIDTH]
    x0 = w[0]
    x1 = w[1]
    if gi[PERIODIC] == 1:
        x0 = x0 - size * np.floor(x0 / size)
        if dim == 3:
            x1 = x1 - size * np.floor(x1 / size)
    X0 = x0 + gi[MAP_OFFSET]
    X1 = x1 + gi[MAP_OFFSET + 1]
    X2 = w[2] + gi[MAP_OFFSET + 2] if dim == 3 else 0.0
    if not (0.0 <= X0 < W and 0.0 <= X1 < W and 0.0 <= X2 < W):
        return -1.0
    i0, i1, i2 = int(X0), int(X1), int(X2)
    fw = (W + (1 << FS) - 1) >> FS
    e, dm = centre_bound(field, dim, fw, X0, X1, X2)
    if e > 0 and dm > NEAR:
        return dm
    if e == 0 and gi[PYRAMID_LEVELS] > 1:
        pstart = level_starts(gi, dim)
        return max(dm, pyramid_dist(field, pstart, dim, W, X0, X1, X2))
    if dm <= NEAR:
        dm = 0.0
    bs = 3 if dim == 2 else 2
    bm = (1 << bs) - 1
    lo, hi = 0, min(len(cells) - 1, gi[TOP_LEVEL]) + 1  # clear at lo, set at hi
    while hi - lo > 1:
        s = (lo + hi) >> 1
        j0, j1, j2 = i0 >> s, i1 >> s, i2 >> s
        nb = blocks[s]
        word = words[maps.block_word(dim, start[s], nb, j0 >> bs, j1 >> bs, j2 >> bs)]
        if (word >> np.uint64((j0 & bm) | ((j1 & bm) << bs) | ((j2 & bm) << (2 * bs)))) & np.uint64(1):
            hi = s
        else:
            lo = s
    s = lo
    if s == 0:
        return dm
    side = float(1 << s)
    f = face_gap(X0, X1, X2, dim, s)
    return max(dm, side + f)


@jit
def walk_geometry(gi, cells, dim):
    """The grid's scalar constants that ``walk_bound`` takes, worked out once per walk:
    (periodic, m0, m1, m2, W, fw, flo, ftop). (The centre pyramid's
    level starts, an array, come from
    ``level_starts`` once per grid: the walk allocates nothing.)"""
    ftop = min(len(cells) - 1, gi[TOP_LEVEL]) + 1
    # the centre field at its cap puts every particle about (cap - 1) coarse cells
    # away, so the map levels whose 3**dim blocks fit well inside that are clear
    flo = 1
    while flo + 1 < ftop and (2 << (flo + 1)) <= (CCAP[dim - 2] - 1) << FS:
        flo += 1
    fw = (gi[MAP_WIDTH] + (1 << FS) - 1) >> FS
    return (gi[PERIODIC] == 1, float(gi[MAP_OFFSET]), float(gi[MAP_OFFSET + 1]), float(gi[MAP_OFFSET + 2]),
            float(gi[MAP_WIDTH]), fw, flo, ftop)


@jit
def level_starts(gi, dim):
    """Where each level of the grid's distance pyramid starts (``maps.pyramid_starts``)."""
    return maps.pyramid_starts(dim, gi[MAP_WIDTH], gi[FIELD_CAP], gi[PYRAMID_LEVELS])


@jit
def walk_bound(w, dim, size, per, m0, m1, m2, W, words, start, blocks, field, fw, flo, ftop, pstart, far):
    """``map_dist`` as the walk's hot loop computes it: the grid's constants
    from ``walk_geometry``, and w's periodic coordinates wrapped in place.

    ``grow._walk`` holds a copy of this body, spelled out (a call would cost
    reference counting, and numba's inlining cost as much).

    With ``far`` (the walker comes from far) it reads the centre pyramid first, and the
    centre field only where the pyramid's bound falls short of ``FAR_CLEAR``.
    It searches the map levels only where the field leaves them open: within
    ``NEAR`` only level 1, as a particle then lies in the coarse cells about
    w's and level FS is set; at the field's cap the pyramid bounds, or where
    the grid is periodic the map levels above ``flo`` (those up to it are
    clear). A test holds it to ``map_dist`` on random grids.

    Returns the bound, and where the pyramid gives it, the radius of the ball about the centre
    of w's cell of the pyramid level that holds no particle centre, w's distance to that centre
    and the level's shift, from which the walk jumps out of that ball; elsewhere a radius of 0.0
    (the distance and shift are then those of a pyramid read that gave no bound, or 0.0 and 0).
    """
    bs = 3 if dim == 2 else 2
    bm = (1 << bs) - 1
    x0 = w[0]
    x1 = w[1]
    if per:
        x0 = x0 - size * np.floor(x0 / size)
        w[0] = x0
        if dim == 3:
            x1 = x1 - size * np.floor(x1 / size)
            w[1] = x1
    X0 = x0 + m0
    X1 = x1 + m1
    X2 = w[2] + m2 if dim == 3 else 0.0
    dm = -1.0
    ball = 0.0  # the centre pyramid's particle-free ball about the centre of w's cell, where it bounds
    gap = 0.0
    shift = 0
    if 0.0 <= X0 < W and 0.0 <= X1 < W and 0.0 <= X2 < W:
        i0, i1, i2 = int(X0), int(X1), int(X2)
        lo, hi = 0, 0
        centre = 0.0
        if far and len(pstart) > 2:
            centre, shift, gap = pyramid_ball(field, pstart, dim, int(W), X0, X1, X2)
        if shift > 0 and centre - gap >= FAR_CLEAR[dim]:  # the field about w at its cap bounds less
            dm = centre - gap
            ball = centre
        else:
            e, dm = centre_bound(field, dim, fw, X0, X1, X2)
            if dm <= NEAR:  # a particle in the coarse cells about w's: level FS set, level 1 alone open
                dm = 0.0
                hi = min(ftop, FS)
            elif e == 0:
                if len(pstart) > 2:
                    if not far:
                        centre, shift, gap = pyramid_ball(field, pstart, dim, int(W), X0, X1, X2)
                    if shift > 0 and centre - gap > dm:
                        dm = centre - gap
                        ball = centre
                else:
                    lo, hi = flo, ftop
        while hi - lo > 1:
            s = (lo + hi) >> 1
            j0, j1, j2 = i0 >> s, i1 >> s, i2 >> s
            nb = blocks[s]
            word = words[maps.block_word(dim, start[s], nb, j0 >> bs, j1 >> bs, j2 >> bs)]
            bit = (j0 & bm) | ((j1 & bm) << bs) | ((j2 & bm) << (2 * bs))
            if (word >> np.uint64(bit)) & np.uint64(1):
                hi = s
            else:
                lo = s
        if lo > 0:
            side = float(1 << lo)
            f = face_gap(X0, X1, X2, dim, lo)
            dm = max(dm, side + f)
    return dm, ball, gap, shift


@inline
def _span(v, r, nc, periodic, origin, inv):
    """Index cells covering [v - r, v + r] on one axis (may wrap if periodic)."""
    lo = int(np.floor((v - r - origin) * inv))
    hi = int(np.floor((v + r - origin) * inv))
    if periodic:
        return lo, min(hi, lo + nc - 1)
    return max(lo, 0), min(hi, nc - 1)


@inline
def gather(c, r, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li):
    """Particles with centres within r of point c, as the images nearest c.

    Fills lx, ly, lz (coordinates) and li (indices); returns the count and
    the smallest squared centre distance among them (inf when none). Inlined
    into the walk, which borrows (``_jit.borrow``): inlined into a function
    that counts references, it counted those of its 11 arrays at every call.

    A gather of the walk reads 27 particles in 5 of 16 cells to keep 2 (3D 1e5
    to 1e6, 10 to 14 of them stored since the last ``sort_cells``, before ``sort_tail``); the lists
    walked in turn, a particle of each at a time so that their reads overlap,
    took 0.97 to 1.18 times the time at 3D 1e6 (4 seeds, the same clusters).
    Skipping the window's cells that lie outside the ball (their box's distance
    from c, on the axes that do not wrap) took 1.041 and 1.063 times the time at
    3D 1e7 (seeds 1 and 2, the same clusters).

    Where a large cluster's time goes: 2D, 4.4 gathers a particle at 1e5, 1e6 and 1e7
    (seed 1, clocked about each call) took 219, 301 and 586 ns each, 22% of the walk's
    time at 1e5 and 37% at 1e7, 59% of the walk's growth in time a particle from 1e5 to
    1e7 (the rest of a walk step: 78 ns at 1e5, 88 at 1e7); 3D, 11 a particle, 417, 603
    and 660 ns at 1e5, 1e6 and 3e6, 34% of the walk's time at each and 35% of its growth
    from 1e5 to 3e6 (the rest of a walk step: 98 ns at 1e5, 134 at 3e6). The
    round-robin walk above at 2D 1e7, side by side (seeds 1 and 2, the same clusters):
    28.07 and 24.53 s of gathers against 28.07 and 24.88; the lists walked first for
    their rows, the rows read after (reads that no longer wait on one another), 31.26
    and 31.24 s against 34.25 and 29.57. A gather reads 18.8 particles from 1.9 cells
    in 2D (1e5 and 1e6), 26.8 from 5.2 in 3D. Rows by cell (``grow.BY_CELL``)
    cut 2D 1e7's gathers to 20.19 s from 28.29, and their sorts took 10.30 s of grid
    work against 3.25. The particles' numbers by cell instead, the rows left in place
    (each cell's run of numbers, rebuilt by a counting sort each time the cluster grew
    by a 32nd, the newer particles from the lists): 2D 1e7 (seeds 1 and 2, the same
    clusters), 575 and 544 ns a gather against 719 and 681, 1e5 331 and 298 against
    259 and 261; the rebuilds took 10.68 s of grid work against 3.41. Rebuilt each
    time it grew by a quarter: 647 and 629 ns against 674 and 640 at 1e7, as the
    walkers' gathers read mostly the particles attached since.
    """
    r2 = r * r
    nl = 0
    near2 = INF
    lo0, hi0 = _span(c[0], r, gi[CELLS], gi[PERIODIC] == 1, gf[ORIGIN], gf[INV_SIDE])
    lo1, hi1 = _span(c[1], r, gi[CELLS + 1], gi[PERIODIC + 1] == 1, gf[ORIGIN + 1], gf[INV_SIDE + 1])
    lo2, hi2 = 0, 0
    if dim == 3:
        lo2, hi2 = _span(c[2], r, gi[CELLS + 2], False, gf[ORIGIN + 2], gf[INV_SIDE + 2])
    p0 = gi[PERIODIC] == 1
    p1 = gi[PERIODIC + 1] == 1
    n0, n1, t0, t1 = gi[CELLS], gi[CELLS + 1], gi[TILES], gi[TILES + 1]
    tb = gi[TILE_SHIFT]
    m = (1 << tb) - 1
    half = 0.5 * size
    # first the heads of the window's cells, kept at the end of li, then their lists: the
    # reads of the lists' first particles no longer wait on one another
    top = len(li) - 1
    nh = 0
    for k2 in range(lo2, hi2 + 1):
        for k1 in range(lo1, hi1 + 1):
            c1 = k1 % n1 if p1 else k1
            for k0 in range(lo0, hi0 + 1):
                c0 = k0 % n0 if p0 else k0
                tile = dirr[(c0 >> tb) + t0 * ((c1 >> tb) + t1 * (k2 >> tb))] - 1
                if tile < 0:
                    continue
                h = heads[tile * 64 + ((c0 & m) | ((c1 & m) << tb) | ((k2 & m) << (2 * tb)))] - 1
                if h >= 0:
                    li[top - nh] = h
                    nh += 1
    for cell in range(nh):
        h = li[top - cell]
        while h >= 0:
            d0 = pts[h, 0] - c[0]
            d1 = pts[h, 1] - c[1]
            d2 = pts[h, 2] - c[2] if dim == 3 else 0.0
            if p0:
                if d0 > half:
                    d0 -= size
                elif d0 < -half:
                    d0 += size
            if p1:
                if d1 > half:
                    d1 -= size
                elif d1 < -half:
                    d1 += size
            q = d0 * d0 + d1 * d1 + d2 * d2
            if q < r2 and nl <= top - nh:
                lx[nl] = c[0] + d0
                ly[nl] = c[1] + d1
                lz[nl] = c[2] + d2
                li[nl] = h
                nl += 1
                near2 = min(near2, q)
            h = nxt[h]
    return nl, near2



@jit
def no_grid():
    """An empty grid: the caller drops its old grid's arrays by taking this
    before it builds the new one (in a later pass of its loop; see the package docstring)."""
    z = np.zeros(1, np.int64)
    return (np.zeros(GI_SLOTS, np.int64), np.zeros(GF_SLOTS), np.zeros(0, np.uint64), z, z, z, np.zeros(0, np.int32),
            np.zeros(0, np.int32), np.zeros(0, np.uint8))

