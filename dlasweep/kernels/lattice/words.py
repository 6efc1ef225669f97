"""The lattice's bit-packed occupancy: marking particles, testing sites, and
exact Chebyshev distances a few sites out from whole 64-bit words.

The grid is ``maps``' (segment 0 a bit per site, 8x8 or 4x4x4 sites per
word, then dilated level 1, which tells a walker within two sites) with a
coarse Chebyshev distance field beside it (``field.field_lower``), and above
the field the centre pyramid (``centres.pyramid_lower``) in the same array; a
site q of the lattice is cell q + ``off`` of the grid, whose side is
``width``. A substrate's periodic images are marked too. A grid is built
for a cluster's particles (``rebuild``), or, when the cluster outgrows it,
carried over into a larger one (``regrow``).
"""

import numpy as np

from ..._jit import jit
from .. import maps
from ..centres import FCAP, level_lower, levels_from_held, pyramid_lower
from .field import FIELD_CAP, FIELD_PACKED, field_fill, field_lower, field_value


@jit
def mark_images(words, dim, start, blocks, cells, field, width, off, q, period, cap, held):
    """Mark a particle at site q, with its periodic images for substrates.

    ``cap`` 1 marks only the particle's own cell of the distance field (for
    ``field.field_fill`` to complete, flagging its tiles in ``held``; growth
    passes an empty array), else ``FIELD_CAP[dim]``. A coarse cell newly
    held is recorded in the centre pyramid above the field.

    Parameters
    ----------
    words : uint64 (...)
        The grid's words: the occupancy (segment 0), then level 1.
    dim : int
        2 or 3.
    start, blocks : int64 (S + 1,), int64 (S,)
        The words' layout (``maps.layout``).
    cells : int64 (S,)
        Cells a side of each segment.
    field : uint8 (...)
        The Chebyshev field with the centre pyramid above it.
    width, off : int
        The grid's side in sites, and its offset: site q is cell q + ``off``.
    q : int64 (3,)
        The particle's site.
    period : int
        A substrate's period (its images one period to each side are marked); 0: none.
    cap : int
        1 or ``FIELD_CAP[dim]``, as above.
    held : uint8 (T,) or (0,)
        Flags of the field's tiles that hold a particle, for ``field_fill``.
    """
    fw = (width + (1 << maps.FIELD_SHIFT) - 1) >> maps.FIELD_SHIFT
    levels = maps.pyramid_levels(dim, width, FIELD_CAP[dim])
    reach = 1 if period > 0 else 0
    zreach = reach if dim == 3 else 0
    for a in range(-reach, reach + 1):
        for b in range(-zreach, zreach + 1):
            i = q[0] + a * period + off
            j = q[1] + (b * period if dim == 3 else 0) + off
            k = q[2] + off
            if 0 <= i < width and 0 <= j < width and 0 <= k < width:
                maps.mark(words, dim, start, blocks, cells, i, j, k)
                s = maps.FIELD_SHIFT
                ci, cj, ck = i >> s, j >> s, (k >> s if dim == 3 else 0)
                if len(held) > 0:
                    held[maps.field_tile(dim, fw, ci, cj, ck)] = 1
                # a held cell has its distances marked already
                if field_value(field, dim, maps.field_cell(dim, fw, ci, cj, ck)) != FIELD_CAP[dim]:
                    pyramid_lower(field, dim, width, i, j, k, levels)
                    field_lower(field, dim, fw, FIELD_CAP[dim], cap, ci, cj, ck)


@jit
def rebuild(points, count, dim, width, off, period):
    """A grid for the first ``count`` particles: the occupancy and level-1 words, the
    Chebyshev field (filled from the held cells: ``field.field_fill``) and the centre pyramid.

    Parameters
    ----------
    points : int32 (n, dim)
        The sites, attachment order.
    count : int
        Particles to mark.
    dim : int
        2 or 3.
    width, off : int
        The grid's side in sites, and its offset: site q is cell q + ``off``.
    period : int
        A substrate's period; 0: none.

    Returns
    -------
    words, start, blocks, cells, field
        The grid (``maps.allocate`` with two segments, ``maps.pyramid_allocate``).
    """
    words, start, blocks, cells = maps.allocate(dim, width, 2)  # occupancy and level 1: the near test
    field = maps.pyramid_allocate(dim, width, FIELD_CAP[dim])
    q = np.zeros(3, np.int64)
    fw = (width + (1 << maps.FIELD_SHIFT) - 1) >> maps.FIELD_SHIFT
    held = np.zeros(maps.field_tile(dim, fw, fw - 1, fw - 1, fw - 1) + 1, np.uint8)
    for p in range(count):
        for a in range(dim):
            q[a] = points[p, a]
        mark_images(words, dim, start, blocks, cells, field, width, off, q, period, 1, held)
    field_fill(field, dim, fw, FIELD_CAP[dim], held)
    return words, start, blocks, cells, field


@jit
def regrow(points, count, dim, width, off, period, old):
    """``rebuild``'s grid, bit for bit, for a cluster that outgrew the grid ``old``
    (words, start, blocks, cells, field, width, off), every particle but the last
    marked in it: the words, the field and the centre pyramid's first level are
    carried over (``maps.carry``) instead of marked again, and the old grid's
    pages go back to the OS.

    The grids' cells line up (the offsets differ by half the old side, 32 sites
    or more: whole words of both segments, whole cells of both levels). Every
    value is a union or a maximum over particles or held cells, so only what the
    old grid could not hold is added: the field and the first level beyond its
    edge, lowered again about the particles whose reach crossed it, the levels
    above the first from the held cells of the level below, and the last
    particle. Substrates, whose grids grow upwards only, are built anew.

    This costs less than ``rebuild``, most in 2D, whose pyramid levels are four
    times as wide as the one below (3D: twice, so more of its levels are built
    anew); the times: docs/performance.md.

    Parameters
    ----------
    points : int32 (n, dim)
        The cluster's sites, attachment order.
    count : int
        Particles in the cluster, the last not yet marked in ``old``.
    dim : int
        2 or 3.
    width : int
        The new grid's side in sites.
    off : int
        The new grid's offset: site q is cell q + ``off``.
    period : int
        A substrate's period; 0: none.
    old : tuple
        The outgrown grid, (words, start, blocks, cells, field, width, off).

    Returns
    -------
    words, start, blocks, cells, field
        The new grid, as ``rebuild`` returns it.
    """
    o_words, o_start, o_blocks, _, o_field, o_width, o_off = old
    step = maps.PYRAMID_STEP[dim]
    shift = off - o_off
    block = 8 if dim == 2 else 4
    cap, fcap = FIELD_CAP[dim], FCAP[dim - 2]
    o_levels = maps.pyramid_starts(dim, o_width, cap)
    levels = maps.pyramid_starts(dim, width, cap)
    sides = np.zeros(2, np.int64)  # cells a side of the field and the first level, the new grid's and the old's
    o_sides = np.zeros(2, np.int64)
    for level in range(2):
        s = maps.FIELD_SHIFT + step * level
        sides[level] = (width + (1 << s) - 1) >> s
        o_sides[level] = (o_width + (1 << s) - 1) >> s
    carried = period == 0 and shift > 0 and shift % max(2 * block, 1 << (maps.FIELD_SHIFT + step)) == 0 \
        and len(o_levels) > 2 and len(levels) > 2
    if carried:
        words, start, blocks, cells = maps.allocate(dim, width, 2)
        field = maps.pyramid_allocate(dim, width, cap)
        for s in range(2):
            maps.carry(o_words[o_start[s]:o_start[s + 1]], o_blocks[s], words[start[s]:start[s + 1]], blocks[s],
                       maps.TILE_BITS[dim], (shift >> s) // block, dim)
        for level in range(2):
            maps.carry(o_field[o_levels[level]:o_levels[level + 1]], o_sides[level],
                       field[levels[level]:levels[level + 1]], sides[level], maps.FIELD_TILE[dim],
                       shift >> (maps.FIELD_SHIFT + step * level), dim, level == 0 and FIELD_PACKED[dim])
    # every whole page, those the segments and levels share too: not held beside the new grid
    maps.release(o_words, 0, len(o_words) * o_words.itemsize)
    maps.release(o_field, 0, len(o_field))
    if not carried:
        return rebuild(points, count, dim, width, off, period)
    level1 = field[levels[1]:levels[2]]
    g = np.zeros(3, np.int64)  # a particle's site in the old grid
    for p in range(count - 1):
        for a in range(dim):
            g[a] = points[p, a] + o_off
        edge0 = edge1 = False
        for a in range(dim):
            c0, c1 = g[a] >> maps.FIELD_SHIFT, g[a] >> (maps.FIELD_SHIFT + step)
            edge0 = edge0 or c0 < cap - 1 or c0 >= o_sides[0] - (cap - 1)
            edge1 = edge1 or c1 < fcap - 1 or c1 >= o_sides[1] - (fcap - 1)
        ci, cj = (g[0] + shift) >> maps.FIELD_SHIFT, (g[1] + shift) >> maps.FIELD_SHIFT
        ck = (g[2] + shift) >> maps.FIELD_SHIFT if dim == 3 else 0
        if edge0:
            field_lower(field, dim, sides[0], cap, cap, ci, cj, ck)
        if edge1:
            level_lower(level1, dim, sides[1], ci, cj, ck)
    levels_from_held(field, levels, width, dim)
    q = np.zeros(3, np.int64)
    for a in range(dim):
        q[a] = points[count - 1, a]
    mark_images(words, dim, start, blocks, cells, field, width, off, q, period, cap, field[:0])
    return words, start, blocks, cells, field


@jit
def occupied(words, dim, start, blocks, width, off, q0, q1, q2):
    """Whether site (q0, q1, q2) holds a particle; False outside the grid of side ``width``
    and offset ``off`` (``words``, ``start``, ``blocks``: its words and their layout; ``dim`` 2 or 3)."""
    i, j, k = q0 + off, q1 + off, q2 + off
    if i < 0 or j < 0 or k < 0 or i >= width or j >= width or k >= width:
        return False
    return maps.test(words, dim, start, blocks, 0, i, j, k)


@jit
def site_word(dim, nb, width, off, q0, q1, q2):
    """Word and bit of site q in the occupancy segment, word -1 outside the grid.

    Scalars only, for the hot loop, which reads the word itself: a helper
    that takes the array costs atomic reference counting per call.

    Parameters
    ----------
    dim : int
        2 or 3.
    nb : int
        Words a side of the occupancy segment.
    width, off : int
        The grid's side in sites, and its offset.
    q0, q1, q2 : int
        The site.
    """
    i, j, k = q0 + off, q1 + off, q2 + off
    if i < 0 or j < 0 or k < 0 or i >= width or j >= width or k >= width:
        return -1, 0
    return maps.index(dim, 0, nb, i, j, k)


@jit
def in_contact(words, dim, start, blocks, width, off, q, moves, period):
    """Whether site q (int64 (3,)) touches a particle (or the substrate) under ``moves``
    (int64 (M, 3)): ``occupied`` of each neighbour in the grid ``words``, ``dim``, ``start``,
    ``blocks``, ``width``, ``off``, its first coordinates wrapped by ``period`` (0: none)."""
    for m in range(moves.shape[0]):
        n0, n1, n2 = q[0] + moves[m, 0], q[1] + moves[m, 1], q[2] + moves[m, 2]
        if period > 0:
            if (n2 if dim == 3 else n1) < 0:
                return True
            n0 = n0 % period
            if dim == 3:
                n1 = n1 % period
        if occupied(words, dim, start, blocks, width, off, n0, n1, n2):
            return True
    return False


@jit
def _row2(w0, w1, w2, t):
    """Row t (0..7) of the three 8x8 words ``w0``, ``w1``, ``w2`` side by side: 24 sites as bits."""
    shift = np.uint64(8 * t)
    return (
        ((w0 >> shift) & np.uint64(255))
        | (((w1 >> shift) & np.uint64(255)) << np.uint64(8))
        | (((w2 >> shift) & np.uint64(255)) << np.uint64(16))
    )


@jit
def word_at(words, dim, nb, x, y, z):
    """Word (x, y, z) of the occupancy segment of ``words`` (``nb`` words a side, ``dim`` 2 or 3),
    empty outside the grid."""
    inside = 0 <= x < nb and 0 <= y < nb and 0 <= z < nb
    return words[maps.block_word(dim, 0, nb, x, y, z)] if inside else np.uint64(0)


@jit
def fine2(a0, a1, a2, b0, b1, b2, c0, c1, c2, x, y):
    """Chebyshev distance from site (x, y) of word b1 to the nearest particle, capped at 9.

    ``a0``, ``a1``, ``a2``, ``b0``, ``b1``, ``b2``, ``c0``, ``c1``, ``c2`` are the 3x3 words
    (8x8 sites each, rows a below) around the walker's, which cover 8 sites on every side, so the result is
    exact below the cap. Rows of 24 sites are OR-ed outwards from the
    walker's row; the square of half-width r is hit when the OR of its rows
    has a bit within r columns. Scalars only: a call that passes arrays costs
    atomic reference counting when numba does not inline it.
    """
    x += 8
    seen = _row2(b0, b1, b2, y)
    found = 9
    for r in range(9):
        if r > 0:
            lo, hi = y - r, y + r
            seen |= _row2(a0, a1, a2, lo + 8) if lo < 0 else _row2(b0, b1, b2, lo)
            seen |= _row2(c0, c1, c2, hi - 8) if hi > 7 else _row2(b0, b1, b2, hi)
        if (seen >> np.uint64(x - r)) & ((np.uint64(1) << np.uint64(2 * r + 1)) - np.uint64(1)) != 0:
            found = r
            break
    return found


@jit
def _band(x, r, a, width):
    """Sites x - r..x + r (of the 12 across three words) within word a, as
    groups of ``width`` bits, one group per site of the word's 4."""
    lo = max(x - r - 4 * a, 0)
    hi = min(x + r - 4 * a, 3)
    if lo > hi:
        return np.uint64(0)
    ones = np.uint64(0xFFFFFFFFFFFFFFFF) >> np.uint64(64 - (hi - lo + 1) * width)
    return ones << np.uint64(lo * width)


@jit
def _masks(x, r, width, repeat):
    """Masks of sites x - r..x + r along one axis in its three words: ``_band``
    (groups of ``width`` bits) repeated by the multiplier ``repeat`` (the axis's stride in the word)."""
    return (
        _band(x, r, 0, width) * np.uint64(repeat),
        _band(x, r, 1, width) * np.uint64(repeat),
        _band(x, r, 2, width) * np.uint64(repeat),
    )


@jit
def fine3(words, nb, i, j, k):
    """Chebyshev distance from site (i, j, k) to the nearest particle, capped at 5,
    where it is known to be 3 or more (the walk's clear level-1 cell).

    The 3x3x3 words (4x4x4 sites each, bit x + 4 y + 16 z) around the
    walker's cover 4 sites on every side; the cube of half-width r is hit
    when a word AND-ed with the masks of its x, y and z ranges is nonzero.
    One pass over the words tests half-widths 3 and 4 at once: a bisection
    over words gathered first is slower, and so are the variants that take
    the level-1 cell's test from these words, or this bound from the level-1
    map, or ask the level-1 map first (docs/performance.md).

    Parameters
    ----------
    words : uint64 (...)
        The grid's words; segment 0, the occupancy, comes first.
    nb : int
        Words a side of segment 0.
    i, j, k : int
        The site's cell in the grid (site + ``off``).
    """
    bx, by, bz = i >> 2, j >> 2, k >> 2
    inside = 1 <= bx < nb - 1 and 1 <= by < nb - 1 and 1 <= bz < nb - 1
    t = maps.TILE_BITS[3]
    tm = (1 << t) - 1
    # the 27 words within one tile, a frequent case: at fixed steps from the first
    one_tile = inside and 0 < bx & tm < tm and 0 < by & tm < tm and 0 < bz & tm < tm
    first = np.uint64(0)  # word (bx - 1, by - 1, bz - 1)
    if one_tile:
        first = np.uint64(maps.block_word(3, 0, nb, bx, by, bz) - 1 - (1 << t) - (1 << (2 * t)))
    x, y, z = (i & 3) + 4, (j & 3) + 4, (k & 3) + 4
    # x30, x31, x32: the sites within 3 of x along x in the three words' columns; and so on
    x30, x31, x32 = _masks(x, 3, 1, 0x1111111111111111)
    y30, y31, y32 = _masks(y, 3, 4, 0x0001000100010001)
    z30, z31, z32 = _masks(z, 3, 16, 1)
    x40, x41, x42 = _masks(x, 4, 1, 0x1111111111111111)
    y40, y41, y42 = _masks(y, 4, 4, 0x0001000100010001)
    z40, z41, z42 = _masks(z, 4, 16, 1)
    hit3 = np.uint64(0)
    hit4 = np.uint64(0)
    for c in range(3):
        z3 = z30 if c == 0 else (z31 if c == 1 else z32)
        z4 = z40 if c == 0 else (z41 if c == 1 else z42)
        for b in range(3):
            yz3 = z3 & (y30 if b == 0 else (y31 if b == 1 else y32))
            yz4 = z4 & (y40 if b == 0 else (y41 if b == 1 else y42))
            for a in range(3):
                if one_tile:
                    w = words[first + np.uint64(a + (b << t) + (c << (2 * t)))]
                elif inside:  # away from the grid's faces, no bounds to check
                    w = words[maps.block_word(3, 0, nb, bx + a - 1, by + b - 1, bz + c - 1)]
                else:
                    w = word_at(words, 3, nb, bx + a - 1, by + b - 1, bz + c - 1)
                hit3 |= w & yz3 & (x30 if a == 0 else (x31 if a == 1 else x32))
                hit4 |= w & yz4 & (x40 if a == 0 else (x41 if a == 1 else x42))
    return 3 if hit3 != 0 else (4 if hit4 != 0 else 5)
