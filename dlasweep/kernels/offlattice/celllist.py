"""The off-lattice cell list: which particles lie near a point.

Cells of side ``geometry.CELL_SIDE`` in tiles of 64 cells, allocated only
where particles are, so memory follows the cluster: a directory over the
tiles of the grid (``geometry.layout``) numbers the tiles in use, and each
used tile holds its cells' heads, the first of a linked list through ``nxt``
of the particles' rows. The rows may be stored cell after cell
(``sort_cells``, ``sort_tail``): the lists then link rows, and the caller
keeps each row's attachment number.

Throughout, ``dim`` is the dimension (2 or 3).
"""

import numpy as np

from ..._jit import borrow, inline, jit, prefetch
from .. import maps
from .geometry import CELLS, GROW, INV_SIDE, ORIGIN, PERIODIC, TILE_SHIFT, TILES, TILES_USED

HEADS_RESERVE = 2.0
"""The cell list's heads are reserved for this many times the tiles the cluster would hold after
growing by ``GROW``: its pages cost memory only once a tile is used (``maps.zeroed``), and a
cell list that outgrows them is copied, the old and new held at once."""
INF = np.inf


@borrow
def _cell_of(i, pts, dim, gi, gf):
    """Particle i's cell in the cell list: its tile's place in the directory and its place in the tile.

    ``pts`` are the positions, float64 (n, dim); ``dim`` is the dimension, 2 or 3; ``gi`` and ``gf`` the
    grid's integer and float geometry (``geometry.layout``).
    """
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
    its tile is new and the heads are full (give them ``more_heads``).

    Parameters
    ----------
    i : int
        The particle's row.
    pts : float64 (n, dim)
        The particles' centres.
    nxt : int32 (n,)
        The links through the rows; ``nxt[i]`` receives the list's old first row.
    dim : int
        2 or 3.
    gi, gf : int64 (GI_SLOTS,), float64 (GF_SLOTS,)
        The grid's geometry (``geometry.layout``).
    dirr, heads : int32 (...)
        The directory of tiles and the cells' heads.
    """
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
    permutation is followed cycle by cycle in place. The tiles keep the
    numbers they were given as they filled (renumbering them in the
    directory's order first gains nothing: docs/performance.md).

    Parameters
    ----------
    pts : float64 (n, dim)
        The particles' centres, moved row by row.
    order : int32 (n,)
        Each row's attachment number, moved with its row.
    nxt : int32 (n,)
        Scratch, then the links through the sorted rows.
    count : int
        Particles to sort.
    dim : int
        2 or 3.
    gi, gf : int64 (GI_SLOTS,), float64 (GF_SLOTS,)
        The grid's geometry (``geometry.layout``).
    dirr, heads : int32 (...)
        The directory of tiles, and the cells' heads (scratch, then the lists' first rows).
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
    place, cycle by cycle (``nxt`` of each then names its own row).

    Each swap waits on the read before it; that costs little here, as a sort's rows move a
    short way, most of them sorted already (a copy through free rows past ``count``, whose
    reads do not wait, is faster on a random permutation but not in a growth:
    docs/performance.md).

    ``dim`` is the dimension, 2 or 3: the columns of ``pts`` moved.
    """
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
    ``grid.regrow_grid``). Sorting these alone costs the rows attached since
    ``first``, not the cluster, and their runs replace a gather's reads of
    one scattered row each. ``nxt`` of those rows serves as scratch; three
    arrays of at most ``count - first`` int32 are allocated.

    Parameters
    ----------
    pts : float64 (n, dim)
        The particles' centres; rows ``first`` to ``count - 1`` are moved.
    order : int32 (n,)
        Each row's attachment number, moved with its row.
    nxt : int32 (n,)
        The links through the rows.
    first : int
        The rows below it are sorted already.
    count : int
        Particles in the cluster.
    dim : int
        2 or 3.
    gi, gf : int64 (GI_SLOTS,), float64 (GF_SLOTS,)
        The grid's geometry (``geometry.layout``).
    dirr, heads : int32 (...)
        The directory of tiles and the cells' heads.
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
    """Put the first ``count`` rows of ``pts`` back in attachment order (undo ``sort_cells``), in place,
    from ``order``, each row's attachment number."""
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


@jit
def empty_heads(dim, tiles):
    """Heads for ``tiles`` tiles in use, reserved for the tiles after growing by ``GROW`` (``HEADS_RESERVE``).

    ``dim`` is the dimension, 2 or 3: the reserve grows as ``GROW ** dim``.
    """
    return maps.zeroed(64 * (int(HEADS_RESERVE * GROW ** dim * tiles) + 64), np.int32)


@jit
def insert_all(pts, count, nxt, dim, gi, gf, dirr, heads):
    """Push particles 0..count-1 on their cells' lists; returns the heads (more of them if they filled).

    Parameters
    ----------
    pts : float64 (n, dim)
        The particles' centres.
    count : int
        Particles to push.
    nxt : int32 (n,)
        Receives the links through the rows.
    dim : int
        2 or 3.
    gi, gf : int64 (GI_SLOTS,), float64 (GF_SLOTS,)
        The grid's geometry (``geometry.layout``).
    dirr, heads : int32 (...)
        The directory of tiles and the cells' heads.
    """
    for i in range(count):
        while not insert(i, pts, nxt, dim, gi, gf, dirr, heads):
            heads = more_heads(heads)
    return heads


@inline
def _span(v, r, nc, periodic, origin, inv):
    """Index cells covering [v - r, v + r] on one axis (may wrap if periodic).

    ``v`` is the coordinate and ``r`` the half-width; ``nc`` the cells on the axis, ``periodic`` whether
    the axis wraps, ``origin`` its low edge and ``inv`` one over a cell's side.
    """
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

    The heads of the window's cells are found first (kept at the end of
    ``li``), then their lists walked one after the other, every cell of the
    window whole; in 3D the first row of each list, and its link, are
    prefetched as its head is found
    (``_jit.prefetch``), so that the lists' first reads overlap (in 2D, whose
    rows lie in attachment order, the prefetch gains nothing). The gathers are
    where a large off-lattice cluster's walk time grows; the breakdown, and the
    ways of reading the lists that were tried, are in docs/performance.md.

    Parameters
    ----------
    c : float64 (3,)
        The point (z 0 in 2D).
    r : float
        The radius, centre distance.
    dim : int
        2 or 3.
    size : int
        A substrate's period (its images are wrapped to the nearest c); else unused.
    pts : float64 (n, dim)
        The particles' centres.
    nxt : int32 (n,)
        The cell list's links through the rows.
    gi : int64 (GI_SLOTS,)
        The grid's integer geometry (``geometry.layout``).
    gf : float64 (GF_SLOTS,)
        The grid's float geometry.
    dirr : int32 (...)
        The directory of tiles.
    heads : int32 (...)
        The cells' heads, 64 a tile in use.
    lx, ly, lz : float64 (LCAP,)
        Receive the centres found (lz 0 in 2D).
    li : int64 (LCAP,)
        Receive their rows.

    Returns
    -------
    count : int
        Particles found.
    nearest2 : float
        The smallest squared centre distance among them (inf when none).
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
    # reads of the lists' first particles do not wait on one another
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
                    if dim == 3:
                        prefetch(pts, h)
                        prefetch(nxt, h)
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
