"""The bitmaps of grids of boxes that box counting marks and counts (``boxes``).

A grid of side s at a per-axis offset is a bitmap, a row of words per box of
its leading axes and a bit per box of the last; a stack holds a side's grids.
Here the particles are handed out in pieces in first-axis order (``pieces``,
``nth_piece``), marked into the grids (``mark_boxes``; integer sites into strips,
``mark_sites``), the grids of side 2s made from those of side s
(``coarsen``), and the fewest set bits of a stack found (``least_count``).
"""

from __future__ import annotations

import numpy as np

from .._jit import inline, jit

HALF = 0.5
"""Half-width of a particle: a lattice site is a unit cell, a disk/sphere has unit diameter."""

_EVEN = np.uint64(0x5555555555555555)
"""The even bits of a word."""

_TOP = np.uint64(63)
"""Shift that brings a word's top bit to the bottom."""


_CACHED_BYTES = 1 << 18
"""Unit-box bitmaps up to this size stay in a core's cache however the particles visit them: below it they
are marked in attachment order, above it in first-axis order (``ordered``)."""


@jit
def ordered(points, high):
    """Whether to mark ``points`` (from the low corner, up to ``high``) in first-axis order.

    In that order the bits a particle sets lie in rows near the previous
    particle's, so the bitmaps are read from cache, not memory; a set whose
    bitmaps are small is not worth the sort, which is a noticeable share of
    a small cluster's measurement (docs/performance.md, "Measures").
    """
    rows = 1
    for a in range(len(high) - 1):
        rows *= np.int64(high[a]) + 1
    unit_bytes = 8 * rows * (np.int64(high[-1]) // 64 + 1)
    return high[0] <= max(len(points), 1 << 22) and unit_bytes > _CACHED_BYTES


@jit
def pieces(prefix, low, top, ordered, most):
    """How ``_count_prefix`` hands a prefix, shifted by ``low``, to the marking: in pieces of at most
    ``most`` particles (more only where one integer first coordinate holds more).

    In first-axis order (``ordered``) a piece is the particles of a range of
    integer first coordinates, sorted by it (a stable counting sort up to
    ``top``), and ``nth_piece`` fills it anew for each marking; otherwise one
    piece, the whole prefix. One piece is filled here, once. A copy of a
    1e8 cluster would outweigh what its growth left free.

    Returns
    -------
    cuts : int64 (K + 1,), the pieces' first coordinates (ordered) or [0, 1]
    start : int64, where each first coordinate's particles start in order (empty when not ordered)
    buffer : the one piece, or room for the largest
    """
    n, dim = prefix.shape
    if not ordered:
        buffer = np.empty_like(prefix)
        for i in range(n):
            for a in range(dim):
                buffer[i, a] = prefix[i, a] - low[a]
        return np.array([0, 1], np.int64), np.empty(0, np.int64), buffer
    start = np.zeros(top + 2, np.int64)
    for i in range(n):
        start[np.int64(np.floor(prefix[i, 0] - low[0])) + 1] += 1
    for c in range(1, top + 2):
        start[c] += start[c - 1]
    cuts = [0]
    largest = 0
    for x in range(1, top + 1):
        if start[x] > start[cuts[-1]] and start[x + 1] - start[cuts[-1]] > most:
            largest = max(largest, start[x] - start[cuts[-1]])
            cuts.append(x)
    largest = max(largest, n - start[cuts[-1]])
    cuts.append(top + 1)
    buffer = np.empty((largest, dim), prefix.dtype)
    if len(cuts) == 2:
        _fill_piece(prefix, low, start, 0, top + 1, buffer)
    return np.array(cuts, np.int64), start, buffer


@jit
def nth_piece(prefix, low, start, cuts, c, buffer):
    """Piece ``c`` of ``pieces``: the one piece it filled, or piece c filled into ``buffer``."""
    if len(cuts) == 2:
        return buffer
    return _fill_piece(prefix, low, start, cuts[c], cuts[c + 1], buffer)


@jit
def _fill_piece(prefix, low, start, x0, x1, buffer):
    """The particles of ``prefix`` whose integer first coordinate (shifted by ``low``) is in [x0, x1),
    shifted, in first-axis order (stable), into the start of ``buffer``; that part."""
    at = start[x0:x1 + 1] - start[x0]
    for i in range(len(prefix)):
        x = np.int64(np.floor(prefix[i, 0] - low[0]))
        if x0 <= x < x1:
            for a in range(prefix.shape[1]):
                buffer[at[x - x0], a] = prefix[i, a] - low[a]
            at[x - x0] += 1
    return buffer[:start[x1] - start[x0]]


@inline
def _pairs(word):
    """Halve a word: bit k (k < 32) of the result is set when bit 2k or 2k + 1 of ``word`` is."""
    x = (word | (word >> np.uint64(1))) & _EVEN
    x = (x | (x >> np.uint64(1))) & np.uint64(0x3333333333333333)
    x = (x | (x >> np.uint64(2))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    x = (x | (x >> np.uint64(4))) & np.uint64(0x00FF00FF00FF00FF)
    x = (x | (x >> np.uint64(8))) & np.uint64(0x0000FFFF0000FFFF)
    return (x | (x >> np.uint64(16))) & np.uint64(0x00000000FFFFFFFF)


@inline
def _ones(word):
    """Number of set bits."""
    x = word - ((word >> np.uint64(1)) & _EVEN)
    x = (x & np.uint64(0x3333333333333333)) + ((x >> np.uint64(2)) & np.uint64(0x3333333333333333))
    x = (x + (x >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return np.int64((x * np.uint64(0x0101010101010101)) >> np.uint64(56))


@jit
def mark_sites(points, offsets, scale, cells, strips):
    """Put integer sites in their boxes on the last axis: bit b of row x[:-1] of ``strips[j]``.

    Box b is the one of side ``scale`` at offset ``offsets[j]`` that holds
    the site, found as in ``mark_boxes``. The rows are numbered row-major
    over the sites of the leading axes, ``cells`` of them on each (a tuple,
    so the loop over axes unrolls).
    """
    dim = points.shape[1]
    for i in range(len(points)):
        row = 0
        for a in range(dim - 1):
            row = row * cells[a] + np.int64(points[i, a])  # integers only: no rounding
        for j in range(len(offsets)):
            last = np.int64(np.floor((points[i, dim - 1] - (-HALF - offsets[j])) / scale))
            strips[j, row, last >> 6] |= np.uint64(1) << np.uint64(last & 63)


@jit
def mark_boxes(points, offsets, scale, radius, shape, first, bitmaps, out, row0=0):
    """Set the bit of every box a particle touches in grids ``first``, ``first + 1``, ...; count the visits.

    Grid g has boxes of side ``scale`` and its corner at -1/2 - offsets[i]
    on an axis where its offset index is i: the digits of g in base
    ``len(offsets)``, axis 0 the most significant. ``radius == 0`` puts each
    particle in the one box holding its centre; ``radius > 0`` in every box
    its ball overlaps. ``shape`` is the grids' shape on three axes (see
    ``_slab``): ``bitmaps[k]`` is grid ``first + k``'s bitmap, a row per box
    of the leading axes (row-major), a bit per box of the last axis, its
    rows those from ``row0`` on (boxes in other rows are left out). With no
    ``bitmaps`` grid ``first``'s every visit (its box on the three axes) is
    written to ``out`` instead.
    """
    pad = 3 - points.shape[1]
    grids = len(bitmaps) if len(bitmaps) > 0 else 1
    many = len(offsets)
    r2 = radius * radius
    # A particle's boxes on each axis for each offset, shared by the grids:
    # its home box, then the one across the nearer face when the ball
    # reaches it (with s >= 2r it reaches no further), at squared distance
    # gap2. A 2D set has an axis 0 of one box, with one offset.
    box = np.zeros((3, many, 2), np.int64)
    reach = np.ones((3, many), np.int64)
    gap2 = np.zeros((3, many))
    visits = 0
    for i in range(len(points)):
        for a in range(pad, 3):
            for j in range(many):
                u = points[i, a - pad] - (-HALF - offsets[j])
                home = np.int64(np.floor(u / scale))
                box[a, j, 0] = home
                if radius > 0.0:
                    below = u - home * scale
                    above = (home + 1) * scale - u
                    gap2[a, j] = min(below, above) ** 2
                    box[a, j, 1] = home - 1 if below <= above else home + 1
                    reach[a, j] = 2 if gap2[a, j] < r2 else 1
        # A box across faces on several axes is reached when the squared
        # distances, added axis by axis in order, stay below r2 (the order
        # of the additions is part of the rule: it fixes the rounding).
        for j0 in range(1 if pad else many):
            for e0 in range(reach[0, j0]):
                d0 = gap2[0, j0] if e0 else 0.0
                for j1 in range(many):
                    base = (j0 * many + j1) * many - first
                    if base + many <= 0 or base >= grids:
                        continue
                    for e1 in range(reach[1, j1]):
                        d1 = d0 + gap2[1, j1] if e1 else d0
                        if e1 and d1 >= r2:
                            continue
                        row = box[0, j0, e0] * shape[1] + box[1, j1, e1] - row0
                        if len(bitmaps) > 0 and not 0 <= row < bitmaps.shape[1]:
                            continue
                        for j2 in range(max(-base, 0), min(grids - base, many)):
                            for e2 in range(reach[2, j2]):
                                if e2 and d1 + gap2[2, j2] >= r2:
                                    continue
                                last = box[2, j2, e2]
                                if len(bitmaps) > 0:
                                    bitmaps[base + j2, row, last >> 6] |= np.uint64(1) << np.uint64(last & 63)
                                else:
                                    out[visits] = box[0, j0, e0], box[1, j1, e1], last
                                    visits += 1
    return visits


@jit
def coarsen(fine, fine_shape, part, shift, factor, coarse, shape):
    """Fill ``coarse``, grids whose boxes are unions of ``fine``'s boxes, and return their least count.

    Both are stacks of bitmaps laid out as in ``mark_boxes``, one per grid,
    their shapes on three axes. Coarse grid g has offset index i_a on axis a,
    digit a of g (axis 0 most significant) in base ``shift.shape[1]``, and
    takes its boxes from fine grid sum_a part[a, i_a]. On a leading axis its
    box b is the union of fine boxes factor[a] b - shift[a, i_a] + k, k <
    factor[a]. On the last axis factor is 1 (box b is fine box b) or 2 (fine
    boxes 2b - shift and 2b + 1 - shift).
    """
    bases, words, pair = shift.shape[1], fine.shape[2], factor[2] == 2
    step = np.zeros(3, np.int64)
    # The fine boxes under each coarse box of the leading axes, clipped to the fine grid.
    first = np.zeros((2, max(shape[0], shape[1])), np.int64)
    stop = np.zeros((2, max(shape[0], shape[1])), np.int64)
    merged = np.zeros(words, np.uint64)
    best = -1
    for g in range(coarse.shape[0]):
        rest, grid = g, 0
        for a in range(2, -1, -1):
            grid += part[a, rest % bases]
            step[a] = shift[a, rest % bases]
            rest //= bases
        for a in range(2):
            for b in range(shape[a]):
                first[a, b] = max(factor[a] * b - step[a], 0)
                stop[a, b] = min(factor[a] * (b + 1) - step[a], fine_shape[a])
        rows, out, up = fine[grid], coarse[g], np.uint64(step[2])
        count = 0
        for b0 in range(shape[0]):
            for b1 in range(shape[1]):
                # The fine rows under this coarse row: a run of consecutive rows
                # per fine box of axis 0. Short rows (3D) are ORed word by word
                # in a register, long ones (2D) row by row, which vectorises;
                # each way is twice as fast as the other on its rows. (The runs
                # are counted by fine box, not stepped by row: a range with a
                # step costs a division, which cost as much as the rest.)
                lo, hi = first[1, b1], stop[1, b1]
                if words <= 2:
                    for w in range(words):
                        acc = np.uint64(0)
                        for f0 in range(first[0, b0], stop[0, b0]):
                            run = f0 * fine_shape[1]
                            for r in range(run + lo, run + hi):
                                acc |= rows[r, w]
                        merged[w] = acc
                else:
                    merged[:] = 0
                    for f0 in range(first[0, b0], stop[0, b0]):
                        run = f0 * fine_shape[1]
                        for r in range(run + lo, run + hi):
                            for w in range(words):
                                merged[w] |= rows[r, w]
                row = b0 * shape[1] + b1
                carry = np.uint64(0)
                for w in range(out.shape[1]):
                    if pair:
                        # Fine words 2w and 2w + 1, moved up a bit when shifted
                        # (the top bit of word 2w - 1 coming in), halved unless
                        # empty (as most are in sparse sets).
                        low = merged[2 * w] if 2 * w < words else np.uint64(0)
                        high = merged[2 * w + 1] if 2 * w + 1 < words else np.uint64(0)
                        if up:
                            low, high, carry = (low << up) | carry, (high << up) | (low >> _TOP), high >> _TOP
                        word = _pairs(low) | (_pairs(high) << np.uint64(32)) if low | high else np.uint64(0)
                    else:
                        word = merged[w]
                    out[row, w] = word
                    count += _ones(word)
        best = count if best < 0 else min(best, count)
    return best


@jit
def least_count(bitmaps):
    """Fewest set bits in a bitmap of the stack."""
    best = -1
    for g in range(len(bitmaps)):
        count = 0
        for row in range(bitmaps.shape[1]):
            for w in range(bitmaps.shape[2]):
                count += _ones(bitmaps[g, row, w])
        best = count if best < 0 else min(best, count)
    return best
