"""The off-lattice grid: the cell list and the maps that bound a walker's free distance.

The dilated maps of ``maps`` (level 1, and the levels above it only where no
pyramid is: ``_allocate_maps``), a centre field (a byte per coarse cell of
side ``2**FS``: the distance from its centre to the nearest particle's unit
cell, to ``CCAP`` cells, ``_centre_lower``) and the centre pyramid above it
(each level's cell holds the distance from its centre to the nearest held
cell of the level below, to ``FCAP`` cells, ``centres.pyramid_lower``) bound
the distance to the nearest particle from below (``map_dist``). The centre
field is the pyramid's level 0, in the same array (``maps.pyramid_starts``'
layout).

A grid is the tuple ``(gi, gf, words, start, blocks, cells, dirr, heads,
field)`` that ``build_grid`` returns: the geometry (``geometry.layout``), the
maps, the cell list's directory and heads (``celllist``), and the field.

Throughout, ``dim`` is the dimension (2 or 3).
"""

import numpy as np

from ..._jit import borrow, jit, owning
from .. import maps
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
from .celllist import empty_heads, insert_all
from .geometry import (
    FIELD_CAP,
    GF_SLOTS,
    GI_SLOTS,
    MAP_OFFSET,
    MAP_WIDTH,
    PERIODIC,
    PYRAMID_LEVELS,
    TILES,
    TOP_LEVEL,
    layout,
)


@borrow
def mark(i, pts, dim, size, gi, words, start, blocks, cells, field):
    """Mark particle i in the maps, the centre field and the centre pyramid above
    it (where its coarse cell is newly held), with its periodic images near the edges.

    Parameters
    ----------
    i : int
        The particle's row.
    pts : float64 (n, dim)
        The particles' centres.
    dim : int
        2 or 3.
    size : int
        A substrate's period.
    gi : int64 (GI_SLOTS,)
        The grid's integer geometry (``geometry.layout``).
    words : uint64 (...)
        The dilated maps (``_allocate_maps``).
    start, blocks, cells : int64 (S + 1,), int64 (S,), int64 (S,)
        The maps' layout: where each level starts, its words and its cells a side.
    field : uint8 (...)
        The centre field with the centre pyramid above it.
    """
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
    maps and their marks (the memory saved: docs/performance.md). ``start`` is shifted so that level s still begins at
    ``start[s]``.

    ``dim`` is the dimension, 2 or 3; ``gi`` the grid's integer geometry (``geometry.layout``).
    """
    pyramid = maps.pyramid_levels(dim, gi[MAP_WIDTH], gi[FIELD_CAP], gi[PYRAMID_LEVELS]) > 1
    start, blocks, cells = maps.layout(dim, gi[MAP_WIDTH], FS if pyramid else 64)
    start -= start[min(1, len(cells) - 1)]
    return maps.zeroed(start[-1], np.uint64), start, blocks, cells


@borrow
def _mark_levels(words, dim, start, blocks, cells, i, j, k, top):
    """Set cell (i, j, k) and its neighbours in the dilated levels 1 to top - 1.

    ``words``, ``start``, ``blocks`` and ``cells`` are the maps (``maps.allocate``); ``dim`` is the
    dimension, 2 or 3 (``k`` is 0 in 2D).
    """
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
    """A grid sized for ``need`` that holds no particle, with room for ``tiles`` cell-list tiles.

    ``dim``, ``line``, ``size`` and ``need`` are as ``geometry.layout`` takes them: the dimension,
    whether the seed is a substrate, its period or the box's side, and the extent to cover.
    """
    gi, gf = layout(dim, line, size, need)
    words, start, blocks, cells = _allocate_maps(dim, gi)
    ntiles = gi[TILES] * gi[TILES + 1] * gi[TILES + 2]
    dirr = maps.zeroed(ntiles, np.int32)
    heads = empty_heads(dim, tiles)
    field = maps.pyramid_allocate(dim, gi[MAP_WIDTH], gi[FIELD_CAP], gi[PYRAMID_LEVELS])
    return gi, gf, words, start, blocks, cells, dirr, heads, field


@jit
def build_grid(dim, line, size, need, pts, count, nxt, tiles):
    """Maps and cell list for particles 0..count-1, sized for ``need``, with
    room for ``tiles`` cell-list tiles (the old grid's count: few change).

    Parameters
    ----------
    dim : int
        2 or 3.
    line : bool
        Whether the seed is a substrate.
    size : int
        The box's side, or a substrate's period.
    need : float
        The cluster's extent to cover: max |coordinate|, or h_max above a substrate.
    pts : float64 (n, dim)
        The particles' centres.
    count : int
        Particles to put in the grid.
    nxt : int32 (n,)
        Receives the cell list's links.
    tiles : int
        Cell-list tiles to make room for.

    Returns
    -------
    gi, gf, words, start, blocks, cells, dirr, heads, field
        The grid (the module docstring).
    """
    gi, gf, words, start, blocks, cells, dirr, heads, field = _empty_grid(dim, line, size, need, tiles)
    heads = insert_all(pts, count, nxt, dim, gi, gf, dirr, heads)
    for i in range(count):
        mark(i, pts, dim, size, gi, words, start, blocks, cells, field)
    return gi, gf, words, start, blocks, cells, dirr, heads, field


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
    over particles or held cells, so the order does not matter. A rebuild
    costs a particle its insert, its level-1 marks and the reads of the copy,
    not the (2 ``FCAP`` - 1)**dim cells of the first level that marking its
    coarse cell again would lower (the rebuilds' times: docs/performance.md).
    ``old_field``'s pages go
    back to the OS once copied. Without a first level in both grids each coarse
    cell lowers the pyramid once (from the first particle pushed on its cell
    list's cell of those in it). Substrates (whose cell list's cells are not
    coarse cells) are built anew.

    Parameters
    ----------
    dim, line, size, need, pts, count, nxt, tiles
        As ``build_grid`` takes them; ``tiles`` is the old grid's count.
    old_gi : int64 (GI_SLOTS,)
        The outgrown grid's geometry.
    old_field : uint8 (...)
        The outgrown grid's centre field and pyramid; its pages go back to the OS.
    """
    if line:
        return build_grid(dim, line, size, need, pts, count, nxt, tiles)
    gi, gf, words, start, blocks, cells, dirr, heads, field = _empty_grid(dim, line, size, need, tiles)
    heads = insert_all(pts, count, nxt, dim, gi, gf, dirr, heads)
    W, old_W = gi[MAP_WIDTH], old_gi[MAP_WIDTH]
    shift = gi[MAP_OFFSET] - old_gi[MAP_OFFSET]  # sites, a multiple of 16 (``geometry.layout``)
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
    on that list of those in its coarse cell (of side ``2**FS``): none further down the list shares it.

    ``pts`` are the positions, float64 (n, dim), and ``nxt`` the cell lists' links
    (``celllist.insert``); ``dim`` is the dimension, 2 or 3; ``gi`` the grid's integer geometry.
    """
    while j >= 0:
        if ((int(np.floor(pts[j, 0])) + gi[MAP_OFFSET]) >> FS == i0 >> FS
                and (int(np.floor(pts[j, 1])) + gi[MAP_OFFSET + 1]) >> FS == i1 >> FS
                and (dim == 2 or (int(np.floor(pts[j, 2])) + gi[MAP_OFFSET + 2]) >> FS == i2 >> FS)):
            return False
        j = nxt[j]
    return True


@jit
def face_gap(X0, X1, X2, dim, s):
    """Distance from the grid point X = (X0, X1, X2) to the nearest face of its cell of side ``2**s``
    (X2 read only where ``dim`` is 3).

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
bound and ball, the same clusters: the field's cells about the cluster's far walkers outgrow the
caches, so a large cluster's far walkers gain the most from not reading them (docs/performance.md)."""
NEAR = 2.0
"""Where the centre field bounds no more than this, the level-1 map decides:
clear, every centre lies 2 or more away; set, the walker takes the neighbour list."""


@owning
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
    (``pyramid_dist``). (``walker.walk_to_contact`` spells this out inline.)

    Parameters
    ----------
    w : float64 (3,)
        The point (z 0 in 2D).
    dim : int
        2 or 3.
    size : int
        A substrate's period.
    gi : int64 (GI_SLOTS,)
        The grid's integer geometry.
    words : uint64 (...)
        The dilated maps (``_allocate_maps``).
    start, blocks, cells : int64 (S + 1,), int64 (S,), int64 (S,)
        The maps' layout: where each level starts, its words and its cells a side.
    field : uint8 (...)
        The centre field with the centre pyramid above it.
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
    """The scalar constants of the grid ``gi`` (its maps' ``cells`` a side by level) that
    ``walk_bound`` takes, worked out once per walk:
    (periodic, m0, m1, m2, W, fw, flo, ftop). (The centre pyramid's
    level starts, an array, come from
    ``level_starts`` once per grid: the walk allocates nothing.)

    ``dim`` is the dimension, 2 or 3.
    """
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
    """Where each level of the distance pyramid of the grid ``gi`` (its geometry) in ``dim``
    dimensions starts (``maps.pyramid_starts``)."""
    return maps.pyramid_starts(dim, gi[MAP_WIDTH], gi[FIELD_CAP], gi[PYRAMID_LEVELS])


@jit
def walk_bound(w, dim, size, per, m0, m1, m2, W, words, start, blocks, field, fw, flo, ftop, pstart, far):
    """``map_dist`` as the walk's hot loop computes it: the grid's constants
    from ``walk_geometry``, and w's periodic coordinates wrapped in place.

    ``walker.walk_to_contact`` holds a copy of this body, spelled out (a call would cost
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

    Parameters
    ----------
    w : float64 (3,)
        The walker's centre; its periodic coordinates are wrapped in place.
    dim : int
        2 or 3.
    size : int
        A substrate's period.
    per : bool
        Whether the grid is periodic (``walk_geometry``).
    m0, m1, m2 : float
        Where coordinate 0 falls in the maps, per axis.
    W : float
        The maps' side in unit cells.
    words : uint64 (...)
        The dilated maps (``_allocate_maps``).
    start, blocks : int64 (S + 1,), int64 (S,)
        The maps' layout: where each level starts, and its words a side.
    field : uint8 (...)
        The centre field with the centre pyramid above it.
    fw : int
        The centre field's side in coarse cells.
    flo : int
        The highest map level known clear where the field is at its cap.
    ftop : int
        One past the highest map level searched.
    pstart : int64 (L + 1,)
        Where each level starts in ``field`` (``level_starts``).
    far : bool
        Whether the walker comes from far: then the pyramid is read first.
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


@jit
def no_grid():
    """An empty grid: the caller drops its old grid's arrays by taking this
    before it builds the new one (in a later pass of its loop; see the package docstring)."""
    z = np.zeros(1, np.int64)
    return (np.zeros(GI_SLOTS, np.int64), np.zeros(GF_SLOTS), np.zeros(0, np.uint64), z, z, z, np.zeros(0, np.int32),
            np.zeros(0, np.int32), np.zeros(0, np.uint8))

