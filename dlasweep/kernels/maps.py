"""Bit-packed occupancy grids, hierarchical maps and distance fields (Ossadnik).

A grid covers the cube ``[-off, W - off)^dim`` of unit cells. Segment 0 is a
plain occupancy bit per cell; segment ``s >= 1`` is a *dilated* map of cells
of side ``2**s``: a cell is set when a particle lies in it or in one of its
``3**dim - 1`` neighbours. A walker whose level-``s`` cell is clear is more
than ``2**s`` (Chebyshev, so also Euclidean) from every particle.

Bits are packed 8x8 (2D) or 4x4x4 (3D) per 64-bit word, words in square
tiles (``TILE_BITS``), and a grid's pages take memory only once written
(``zeroed``): a 2D grid costs 1.3 bits per cell of the pages along the
cluster (the lattice keeps segments 0 and 1 only), not of its bounding square.
Near the cluster a coarse Chebyshev distance field (one byte per 4x4 cells, half a
byte per 4x4x4: ``lattice.field``) gives a sharper bound than the power-of-two
maps; the centre pyramid (``centres``) stacks coarser fields above it in the
same array (``pyramid_starts``), so that a walker far from the cluster reads
a bound from a small array (beside periodic sides the off-lattice walk
searches the maps instead).

Throughout, ``dim`` is the dimension (2 or 3).
"""

import mmap
import sys

import numpy as np
from numba import objmode, types

from .._jit import borrow, inline, jit

HUGE_PAGE = 2 << 20
"""Size of a transparent huge page (x86-64 and most Linux arm64)."""
_MADV_HUGEPAGE = 14
_madvise = types.ExternalFunction("madvise", types.int32(types.uintp, types.uintp, types.int32))


@jit
def _advise_huge_pages(address, nbytes):
    """Ask Linux to back the whole huge pages in [address, address + nbytes) with huge pages."""
    lo = (address + np.uintp(HUGE_PAGE - 1)) & ~np.uintp(HUGE_PAGE - 1)
    hi = (address + np.uintp(nbytes)) & ~np.uintp(HUGE_PAGE - 1)
    if hi > lo:
        _madvise(lo, hi - lo, np.int32(_MADV_HUGEPAGE))  # advice only: a refusal changes nothing


@jit
def _no_advice(address, nbytes):
    """Elsewhere than Linux: no advice (``madvise``'s flag numbers differ).

    It takes ``address`` and ``nbytes``, as the Linux advice does, and ignores them.
    """


_advise = _advise_huge_pages if sys.platform.startswith("linux") else _no_advice

PAGE = 4096
"""The memory page that ``zeroed`` hands back to the OS (x86-64 Linux; where pages are larger,
``madvise`` refuses the unaligned range and ``zeroed`` writes its zeros)."""
_MADV_DONTNEED = 4


@jit
def _release(address, nbytes):
    """Hand the whole pages in [address, address + nbytes) back to Linux: they read
    as zeros and take no memory until written. Returns the released range."""
    lo = (address + np.uintp(PAGE - 1)) & ~np.uintp(PAGE - 1)
    hi = (address + np.uintp(nbytes)) & ~np.uintp(PAGE - 1)
    if hi > lo and _madvise(lo, hi - lo, np.int32(_MADV_DONTNEED)) == 0:
        return lo - address, hi - address
    return np.uintp(0), np.uintp(0)


@jit
def _keep(address, nbytes):
    """Elsewhere than Linux: nothing released.

    It takes ``address`` and ``nbytes``, as the Linux release does, and ignores them.
    """
    return np.uintp(0), np.uintp(0)


_release_pages = _release if sys.platform.startswith("linux") else _keep


@jit
def filled(n, value, dtype):
    """``np.full(n, value, dtype)``, in transparent huge pages where the OS allows.

    numpy advises huge pages for its large arrays, numba's allocator does
    not: a large array read at random then costs a TLB miss per read on
    small pages. The advice must come before the first write.
    """
    a = np.empty(n, dtype)
    if a.nbytes >= 2 * HUGE_PAGE:
        _advise(np.uintp(a.ctypes.data), np.uintp(a.nbytes))
    a[:] = value
    return a


TILE_BITS = (0, 0, 4, 3)
"""By dimension: words are stored in tiles of ``2**TILE_BITS`` words a side
(2D 16x16 words, 128x128 sites, 2 KiB; 3D 8x8x8 words, 32**3 sites, 4 KiB),
so that the words near a site share a few memory pages and a cluster
touches the pages along it, not every row of the grid. Within a tile the
words lie row after row, a cache line 32x4x4 sites in 3D (Morton order
within the tile, which puts fewer lines along the cluster, is slower:
docs/performance.md)."""


UNRESERVED = sys.platform.startswith("linux")
"""Whether ``zeroed`` may take large arrays from ``_unreserved`` (Linux's ``MAP_NORESERVE``)."""
RESERVE_MIN = 1 << 28
"""Bytes from which ``zeroed`` maps its array with ``_unreserved`` (256 MiB: a 3D
lattice grid of side 2**11 and up is mapped so; a small cluster's grids, which a sweep builds by the
thousand, are not)."""
_MAP_NORESERVE = 0x4000  # Linux's flag; Python's mmap module does not name it


def _unreserved(nbytes):
    """``nbytes`` zero bytes, a private anonymous mapping that Linux does not count against the memory it
    may promise (``MAP_NORESERVE``): only the pages written take memory.

    A grid spans the cluster's bounding cube, and a plain allocation of it is refused once it exceeds the
    machine's memory (``MemoryError`` from numba's allocator), though its written pages are a small part:
    a large 3D lattice cluster's grid holds more words than a machine has memory (the case that
    showed it: docs/performance.md). Where overcommit is strict (``vm.overcommit_memory`` 2) Linux counts
    such a mapping all the same.
    Called from the kernels in object mode; the array keeps the mapping, unmapped when numba drops its
    last reference.
    """
    return np.frombuffer(mmap.mmap(-1, nbytes, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS | _MAP_NORESERVE),
                         np.uint8)


@jit
def zeroed(n, dtype):
    """``np.zeros(n, dtype)`` whose pages take memory only once written.

    numba's ``np.zeros`` writes every byte. Here the whole pages go back to
    the OS (``madvise(MADV_DONTNEED)``), which maps them to zeros on demand:
    a grid over the cluster's bounding square costs the pages the cluster
    and its walkers write, not the square. These pages stay small: huge
    pages would back whole stretches of empty space with memory, and make
    the large growths slower where the grids outgrow the caches
    (docs/performance.md). Small pages also map every unwritten page to one
    zero page, so the walk's reads of empty space stay in the caches.

    From ``RESERVE_MIN`` bytes on Linux the array is a mapping the OS does not
    reserve memory for (``_unreserved``), already zero.
    """
    nbytes = n * np.empty(0, dtype).itemsize
    if UNRESERVED and nbytes >= RESERVE_MIN:
        with objmode(b="uint8[::1]"):
            b = _unreserved(nbytes)
        return b.view(dtype)
    a = np.empty(n, dtype)
    lo, hi = _release_pages(np.uintp(a.ctypes.data), np.uintp(a.nbytes))
    if hi > lo:
        b = a.view(np.uint8)
        b[:lo] = 0
        b[hi:] = 0
    else:
        a[:] = 0
    return a


@borrow
def release(a, lo, hi):
    """Hand the whole pages of the bytes ``lo`` to ``hi`` of the array ``a`` back to
    the OS (they read as zeros after); returns where the released pages end, ``lo``
    when none was whole, so that a caller releasing stretch after stretch passes it on."""
    rlo, rhi = _release_pages(np.uintp(a.ctypes.data) + np.uintp(lo), np.uintp(hi - lo))
    return lo + np.int64(rhi) if rhi > rlo else lo


@jit
def layout(dim, width, most=64):
    """Start word, blocks per axis and cells per axis of every segment (at most ``most``),
    each segment a whole number of tiles.

    ``dim`` is the dimension, 2 or 3 (blocks of 8x8 or 4x4x4 cells, a word each); ``width`` is segment
    0's cells a side.
    """
    block = 8 if dim == 2 else 4
    nseg = 1
    while (width >> nseg) >= 2 and nseg < most:
        nseg += 1
    start = np.zeros(nseg + 1, np.int64)
    blocks = np.zeros(nseg, np.int64)
    cells = np.zeros(nseg, np.int64)
    for s in range(nseg):
        w = (width + (1 << s) - 1) >> s
        nb = (w + block - 1) // block
        cells[s] = w
        blocks[s] = nb
        tiles = (nb + (1 << TILE_BITS[dim]) - 1) >> TILE_BITS[dim]
        start[s + 1] = start[s] + (tiles << TILE_BITS[dim]) ** dim
    return start, blocks, cells


@inline
def tile_number(dim, tiles, ti, tj, tk):
    """Number of tile (ti, tj, tk) of a grid of ``tiles`` tiles a side, tile after tile in raster order.

    ``dim`` is the dimension, 2 or 3 (``tk`` is 0 in 2D).
    """
    return ti + tiles * (tj + (tiles * tk if dim == 3 else 0))


@inline
def tiled(dim, bits, side, i, j, k):
    """Position of cell (i, j, k) of a grid of ``side`` cells a side stored in
    square (cubic) tiles of ``2**bits`` cells a side, tile after tile.

    ``dim`` is the dimension, 2 or 3 (``k`` is 0 in 2D).
    """
    last = (1 << bits) - 1
    tile = tile_number(dim, (side + last) >> bits, i >> bits, j >> bits, k >> bits)
    inner = (i & last) | ((j & last) << bits)
    if dim == 3:
        inner |= (k & last) << (2 * bits)
    return (tile << (dim * bits)) + inner


@jit
def block_word(dim, base, nb, bx, by, bz):
    """The word holding block (bx, by, bz) of a segment starting at ``base``, ``nb`` blocks a side.

    ``dim`` is the dimension, 2 or 3 (``bz`` is 0 in 2D).
    """
    return base + tiled(dim, TILE_BITS[dim], nb, bx, by, bz)


@jit
def index(dim, base, nb, i, j, k):
    """Word and bit of cell (i, j, k) in a segment starting at word ``base``, ``nb`` blocks a side.

    ``dim`` is the dimension, 2 or 3 (``k`` is 0 in 2D).
    """
    if dim == 2:
        return block_word(2, base, nb, i >> 3, j >> 3, 0), (i & 7) | ((j & 7) << 3)
    return block_word(3, base, nb, i >> 2, j >> 2, k >> 2), (i & 3) | ((j & 3) << 2) | ((k & 3) << 4)


@borrow
def carry(old, old_side, new, new_side, bits, shift, dim, packed=False):
    """Copy grid ``old``, ``old_side`` cells a side in tiles of ``2**bits`` (``tiled``), into
    ``new``, ``new_side`` a side, each cell ``shift`` cells further along every axis; with
    ``packed``, two cells a byte (``lattice.field.FIELD_PACKED``).

    Only nonzero cells are written (unwritten pages stay free), a tile (a page or
    less) at a time, and each row of old tiles goes back to the OS once copied, so
    that the two grids take little more memory than the larger one.

    ``dim`` is the dimension, 2 or 3.
    """
    tiles = (old_side + (1 << bits) - 1) >> bits
    cells = 2 if packed else 1  # cells an element
    per_tile = (1 << (dim * bits)) // cells  # elements a tile
    size = old.itemsize
    base = 0
    done = 0
    for tk in range(tiles if dim == 3 else 1):
        for tj in range(tiles):
            for ti in range(tiles):
                for inner in range(per_tile):
                    v = old[base + inner]
                    if v == 0:
                        continue
                    for half in range(cells):
                        if packed:
                            u = (np.int64(v) >> (4 * half)) & 15  # the half's cell
                            if u == 0:
                                continue
                        a, b, c = untiled(dim, bits, ti, tj, tk, cells * inner + half)
                        cell = tiled(dim, bits, new_side, a + shift, b + shift, c + shift if dim == 3 else 0)
                        if packed:
                            new[cell >> 1] |= np.uint8(u << ((cell & 1) << 2))
                        else:
                            new[cell] = v
                base += per_tile
            done = release(old, done, base * size)
    release(old, done, len(old) * size)


@inline
def untiled(dim, bits, ti, tj, tk, inner):
    """The cell at place ``inner`` of tile (ti, tj, tk) of tiles ``2**bits`` cells a side (``tiled``'s inverse).

    ``dim`` is the dimension, 2 or 3 (the third index returned is 0 in 2D).
    """
    m = (1 << bits) - 1
    return (ti << bits) | (inner & m), (tj << bits) | ((inner >> bits) & m), \
        ((tk << bits) | (inner >> (2 * bits))) if dim == 3 else 0


@jit
def test(words, dim, start, blocks, s, i, j, k):
    """Whether cell (i, j, k) of segment ``s`` is set (indices already offset).

    Parameters
    ----------
    words : uint64 array
        The map's words, every segment one after the other (``allocate``).
    dim : int
        The dimension, 2 or 3.
    start, blocks : int64 arrays
        Each segment's first word and its blocks a side (``layout``).
    s : int
        The segment read.
    i, j, k : int
        The cell (k is 0 in 2D).
    """
    w, b = index(dim, start[s], blocks[s], i, j, k)
    return (words[w] >> np.uint64(b)) & np.uint64(1) != np.uint64(0)


@jit
def mark(words, dim, start, blocks, cells, i, j, k):
    """Record a particle in cell (i, j, k): occupancy and every dilated level.

    A word of segment 0 is one cell of level 3 (2D) or 2 (3D): when it
    already holds a particle, that particle marked the same cells on every
    level from there up, so only the levels below are marked. Words are
    indexed here with scalars (``index``): a helper call that passes the
    arrays would cost atomic reference counting per cell.

    Parameters
    ----------
    words : uint64 array
        The map's words, every segment one after the other (``allocate``).
    dim : int
        The dimension, 2 or 3.
    start, blocks : int64 arrays
        Each segment's first word and its blocks a side (``layout``).
    cells : int64 array
        Each segment's cells a side (``layout``): how many segments there are.
    i, j, k : int
        The particle's cell (k is 0 in 2D).
    """
    w, b = index(dim, 0, blocks[0], i, j, k)
    fresh = words[w] == np.uint64(0)
    words[w] |= np.uint64(1) << np.uint64(b)
    for s in range(1, len(cells) if fresh else min(len(cells), 4 if dim == 2 else 3)):
        base, nb, n = start[s], blocks[s], cells[s]
        ci, cj, ck = i >> s, j >> s, k >> s
        for a in range(max(ci - 1, 0), min(ci + 1, n - 1) + 1):
            for bb in range(max(cj - 1, 0), min(cj + 1, n - 1) + 1):
                if dim == 2:
                    w, b = index(dim, base, nb, a, bb, 0)
                    words[w] |= np.uint64(1) << np.uint64(b)
                    continue
                for c in range(max(ck - 1, 0), min(ck + 1, n - 1) + 1):
                    w, b = index(dim, base, nb, a, bb, c)
                    words[w] |= np.uint64(1) << np.uint64(b)


@jit
def allocate(dim, width, most=64):
    """An empty grid of side ``width`` with at most ``most`` segments: (words, start, blocks, cells).

    ``dim`` is the dimension, 2 or 3 (``layout``).
    """
    start, blocks, cells = layout(dim, width, most)
    return zeroed(start[-1], np.uint64), start, blocks, cells


FIELD_SHIFT = 2
"""The distance field works on coarse cells of side ``2**FIELD_SHIFT``."""
FIELD_TILE = (0, 0, 6, 4)
"""By dimension: a field's cells are stored in tiles of ``2**FIELD_TILE`` cells
a side, 4 KiB each (a memory page), so that the cells within a cap of the
cluster share pages and the rest are never written. Within a tile the cells
lie row after row (cache-line bricks within the tile, or tiles of a cache
line, are no faster: docs/performance.md)."""


@jit
def field_cell(dim, fw, ci, cj, ck):
    """Index of cell (ci, cj, ck) in a field of ``fw`` cells a side, stored by tiles.

    ``dim`` is the dimension, 2 or 3 (``ck`` is 0 in 2D).
    """
    return tiled(dim, FIELD_TILE[dim], fw, ci, cj, ck)


@inline
def field_tiles(dim, fw):
    """Tiles a side of a field of ``fw`` cells a side.

    ``dim`` is the dimension, 2 or 3: it sets the tile's side (``FIELD_TILE``).
    """
    return (fw + (1 << FIELD_TILE[dim]) - 1) >> FIELD_TILE[dim]


@jit
def field_size(dim, fw):
    """Cells a field of ``fw`` cells a side holds, whole tiles.

    ``dim`` is the dimension, 2 or 3: it sets the tile's side (``FIELD_TILE``).
    """
    return (field_tiles(dim, fw) << FIELD_TILE[dim]) ** dim


@jit
def field_tile(dim, fw, ci, cj, ck):
    """The tile of cell (ci, cj, ck) in a field of ``fw`` cells a side (``field_fill``'s ``held``).

    ``dim`` is the dimension, 2 or 3 (``ck`` is 0 in 2D).
    """
    t = FIELD_TILE[dim]
    return tile_number(dim, field_tiles(dim, fw), ci >> t, cj >> t, ck >> t)


PYRAMID_STEP = (0, 0, 2, 1)
"""By dimension: each level of the pyramid above a field has cells ``2**PYRAMID_STEP``
times wider than the level below; level 0 is the field (cells of
``2**FIELD_SHIFT``). 3D's field has a smaller cap, hence finer steps; a 2D step
of 1 saves no steps and takes more levels (docs/performance.md)."""


@jit
def pyramid_levels(dim, width, cap, most=64):
    """Levels of the pyramid of a grid of side ``width``: enough that the top
    one's capped distance spans the grid, at most ``most``.

    ``dim`` is the dimension, 2 or 3 (``PYRAMID_STEP``); ``cap`` is the cap of every level's distances,
    in its own cells.
    """
    levels = 1
    while ((cap - 1) << (FIELD_SHIFT + PYRAMID_STEP[dim] * (levels - 1))) < width and levels < most:
        levels += 1
    return levels


@jit
def pyramid_starts(dim, width, cap, most=64):
    """Where each level of the pyramid of a grid of side ``width`` starts in
    its array (and the end).

    ``dim``, ``cap`` and ``most`` are as ``pyramid_levels`` takes them: the dimension, the levels' cap
    and the most levels.
    """
    levels = pyramid_levels(dim, width, cap, most)
    start = np.zeros(levels + 1, np.int64)
    for level in range(levels):
        shift = FIELD_SHIFT + PYRAMID_STEP[dim] * level
        start[level + 1] = start[level] + field_size(dim, (width + (1 << shift) - 1) >> shift)
    return start


@jit
def pyramid_allocate(dim, width, cap, most=64):
    """The field with coarser fields above it, one array, every cell at the cap.

    Level l has cells of side ``2**(FIELD_SHIFT + PYRAMID_STEP[dim] * l)`` and
    starts at ``pyramid_starts(...)[l]``; level 0, the field, comes first. It
    is in small pages, as every ``zeroed`` array is (huge pages for this
    array alone gain nothing: docs/performance.md).

    ``dim``, ``width``, ``cap`` and ``most`` are as ``pyramid_levels`` takes them: the dimension, the
    grid's side, the levels' cap (every cell's first value) and the most levels.
    """
    return zeroed(pyramid_starts(dim, width, cap, most)[-1], np.uint8)
