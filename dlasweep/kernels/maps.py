"""Bit-packed occupancy grids and hierarchical distance maps (Ossadnik).

A grid covers the cube ``[-off, W - off)^dim`` of unit cells. Segment 0 is a
plain occupancy bit per cell; segment ``s >= 1`` is a *dilated* map of cells
of side ``2**s``: a cell is set when a particle lies in it or in one of its
``3**dim - 1`` neighbours. A walker whose level-``s`` cell is clear is more
than ``2**s`` (Chebyshev, so also Euclidean) from every particle, and because
the dilated sets are nested, the largest clear level is found by a local
search from the walker's previous level (``free_bound``).

Bits are packed 8x8 (2D) or 4x4x4 (3D) per 64-bit word, so a 2D grid costs
about 1.3 bits per cell in all, and memory follows the cluster, not a canvas.
Near the cluster a coarse Chebyshev distance field (``field_*``, one byte per
4x4 cells) gives a sharper bound than the power-of-two maps.
"""

import numpy as np

from .._jit import jit


@jit
def layout(dim, width):
    """Start word, blocks per axis and cells per axis of every segment."""
    block = 8 if dim == 2 else 4
    nseg = 1
    while (width >> nseg) >= 2:
        nseg += 1
    start = np.zeros(nseg + 1, np.int64)
    blocks = np.zeros(nseg, np.int64)
    cells = np.zeros(nseg, np.int64)
    for s in range(nseg):
        w = (width + (1 << s) - 1) >> s
        nb = (w + block - 1) // block
        cells[s] = w
        blocks[s] = nb
        start[s + 1] = start[s] + nb**dim
    return start, blocks, cells


@jit
def _index(dim, base, nb, i, j, k):
    """Word and bit of cell (i, j, k) in a segment starting at word ``base``, ``nb`` blocks a side."""
    if dim == 2:
        return base + (i >> 3) + nb * (j >> 3), (i & 7) | ((j & 7) << 3)
    return base + (i >> 2) + nb * ((j >> 2) + nb * (k >> 2)), (i & 3) | ((j & 3) << 2) | ((k & 3) << 4)


@jit
def _locate(dim, start, blocks, s, i, j, k):
    return _index(dim, start[s], blocks[s], i, j, k)


@jit
def bit(words, dim, base, nb, i, j, k):
    """``test`` with the segment given by scalars (``start[s]``, ``blocks[s]``).

    Hot loops call this: a call that passes fewer arrays does less atomic
    reference counting when numba does not inline it.
    """
    w, b = _index(dim, base, nb, i, j, k)
    return (words[w] >> np.uint64(b)) & np.uint64(1) != np.uint64(0)


@jit
def test(words, dim, start, blocks, s, i, j, k):
    """Whether cell (i, j, k) of segment ``s`` is set (indices already offset)."""
    return bit(words, dim, start[s], blocks[s], i, j, k)


@jit
def _set(words, dim, start, blocks, s, i, j, k):
    w, b = _locate(dim, start, blocks, s, i, j, k)
    words[w] |= np.uint64(1) << np.uint64(b)


@jit
def mark(words, dim, start, blocks, cells, i, j, k):
    """Record a particle in cell (i, j, k): occupancy and every dilated level."""
    _set(words, dim, start, blocks, 0, i, j, k)
    for s in range(1, len(cells)):
        w = cells[s]
        ci, cj, ck = i >> s, j >> s, k >> s
        for di in range(-1, 2):
            a = ci + di
            if a < 0 or a >= w:
                continue
            for dj in range(-1, 2):
                b = cj + dj
                if b < 0 or b >= w:
                    continue
                if dim == 2:
                    _set(words, dim, start, blocks, s, a, b, 0)
                    continue
                for dk in range(-1, 2):
                    c = ck + dk
                    if 0 <= c < w:
                        _set(words, dim, start, blocks, s, a, b, c)


@jit
def allocate(dim, width):
    """An empty grid of side ``width``: (words, start, blocks, cells)."""
    start, blocks, cells = layout(dim, width)
    return np.zeros(start[-1], np.uint64), start, blocks, cells


@jit
def free_bound(words, dim, start, blocks, cells, i, j, k, guess):
    """Largest clear level about cell (i, j, k) and the distance it guarantees.

    The search starts at ``guess`` (a walker's previous level) and moves one
    level at a time, which beats bisection for walkers that move locally.
    A clear level ``s`` means no particle in the 3**dim block of level-``s``
    cells around the walker's, so every particle is at least as far as the
    nearest face of that block: ``2**s`` plus the walker's offset in its cell.

    Returns
    -------
    level : int, 0 when even level 1 is set
    bound : float, a lower bound on the distance from the centre of cell
        (i, j, k) to the nearest marked cell (0 when level is 0)
    """
    top = len(cells) - 1
    s = min(max(guess, 1), top)
    if test(words, dim, start, blocks, s, i >> s, j >> s, k >> s):
        s -= 1
        while s >= 1 and test(words, dim, start, blocks, s, i >> s, j >> s, k >> s):
            s -= 1
    else:
        while s < top and not test(words, dim, start, blocks, s + 1, i >> (s + 1), j >> (s + 1), k >> (s + 1)):
            s += 1
    # one exit: numba then drops the reference counting of the arrays
    side = 1 << s
    mask = side - 1
    near = min(i & mask, side - 1 - (i & mask), j & mask, side - 1 - (j & mask))
    if dim == 3:
        near = min(near, k & mask, side - 1 - (k & mask))
    return s, float(side + near) + 0.5 if s > 0 else 0.0


FIELD_SHIFT = 2
"""The distance field works on coarse cells of side ``2**FIELD_SHIFT``."""


@jit
def field_allocate(dim, width, cap):
    """A coarse Chebyshev distance field, every cell at the cap (nothing near)."""
    fw = (width + (1 << FIELD_SHIFT) - 1) >> FIELD_SHIFT
    return np.full(fw**dim, np.uint8(cap), np.uint8)


@jit
def field_mark(field, dim, width, i, j, k, cap):
    """Record a particle in cell (i, j, k): lower the distances within ``cap``.

    ``field[c]`` is the Chebyshev distance, in coarse cells and capped, from
    cell ``c`` to the nearest coarse cell holding a particle; sharper than the
    dilated maps near the cluster, where most jumps happen.
    """
    fw = (width + (1 << FIELD_SHIFT) - 1) >> FIELD_SHIFT
    ci, cj, ck = i >> FIELD_SHIFT, j >> FIELD_SHIFT, (k >> FIELD_SHIFT if dim == 3 else 0)
    here = ci + fw * (cj + fw * ck)
    if field[here] == 0:
        return
    reach = cap - 1
    klo, khi = (max(ck - reach, 0), min(ck + reach, fw - 1)) if dim == 3 else (0, 0)
    for c in range(klo, khi + 1):
        dk = abs(c - ck)
        for b in range(max(cj - reach, 0), min(cj + reach, fw - 1) + 1):
            dj = max(dk, abs(b - cj))
            row = fw * (b + fw * c)
            for a in range(max(ci - reach, 0), min(ci + reach, fw - 1) + 1):
                d = max(dj, abs(a - ci))
                if d < field[row + a]:
                    field[row + a] = d


@jit
def field_get(field, dim, width, i, j, k):
    """The field's value at site (i, j, k): coarse cells to the nearest particle's, capped."""
    fw = (width + (1 << FIELD_SHIFT) - 1) >> FIELD_SHIFT
    ck = k >> FIELD_SHIFT if dim == 3 else 0
    return np.int64(field[(i >> FIELD_SHIFT) + fw * ((j >> FIELD_SHIFT) + fw * ck)])
