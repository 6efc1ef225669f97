"""The lattice's coarse Chebyshev distance field: for each cell of ``2**maps.FIELD_SHIFT`` sites a
side, the cap less its distance in cells to the nearest cell that holds a particle, to the cap.

Marked particle by particle (``field_lower``) or filled from the held cells at a rebuild
(``field_fill``); stored in the tiles of ``maps.field_cell``, in whole bytes or two cells a byte
(``FIELD_PACKED``). The centre pyramid (``centres``) stacks its levels above it in one array.

Throughout, ``dim`` is the dimension (2 or 3).
"""

import numpy as np

from ..._jit import borrow, inline, jit
from .. import maps

FIELD_CAP = (0, 0, 16, 6)
"""By dimension: reach of the coarse distance field, in cells of 4 sites. 3D's cap is 6: a cap of 8
(walkers to 28 sites out taking cube exits, not far jumps) does not shorten the walk
(docs/performance.md), and keeps the field from being packed (``FIELD_PACKED``)."""
FIELD_PACKED = tuple(0 < cap < 8 for cap in FIELD_CAP)
"""By dimension: whether the lattice's Chebyshev field (``field_lower``) holds two cells a byte,
the even cell in the low four bits: wherever the cap is below 8 (``PAIR_ROWS``' SWAR maximum holds
values below 8), 3D's cap of 6, not 2D's of 16. The packed cells
take the first half of the level's bytes, and the second half is never written (no memory):
the pyramid's levels above stay where ``maps.pyramid_starts`` puts them. The field is what a 3D
walk's steps near the cluster read first, and its size is what they feel: packed, it spans about
half the cache lines, and the large 3D growths are faster for it; ``PAIR_ROWS`` raises two cells
a byte at once, so that the packing costs the small ones nothing (docs/performance.md)."""


def _pair_rows():
    """``field_lower``'s rows in a packed field (``FIELD_PACKED``), by cap (to 7: the halves'
    maximum takes values below 8), a row's Chebyshev distance ``dj`` from the particle's cell
    across the rows and the parity of ``s``, the place of the row's first byte's low cell from
    the particle's cell less the reach, plus 1: byte ``s // 2 + x`` of the table is byte ``x`` of
    the row, both halves, 0 beyond the reach."""
    rows = np.zeros((8, 8, 2, 8), np.uint8)
    for cap, dj, par, j in np.ndindex(rows.shape):
        if dj < cap:
            # the byte's two cells, counted from the particle's cell less the reach
            low, high = [cap - max(dj, abs(k - cap + 1)) if 0 <= k <= 2 * cap - 2 else 0
                         for k in (2 * j + par - 1, 2 * j + par)]
            rows[cap, dj, par, j] = low | (high << 4)
    return rows.reshape(-1)


PAIR_ROWS = _pair_rows()
FIELD_MASK = (0, 0, 255, 15)
"""By dimension: the bits of a lattice field's cell in its byte, shifted down (``field_place``)."""


@inline
def field_place(dim, cell):
    """The byte that holds the lattice field's ``cell`` (``maps.field_cell``) and the shift down to
    its value, to be masked with ``FIELD_MASK`` (``FIELD_PACKED``).

    ``dim`` is the dimension, 2 or 3: it sets whether the field is packed two cells a byte.
    """
    if FIELD_PACKED[dim]:
        return cell >> 1, (cell & 1) << 2
    return cell, cell & 0


@jit
def field_value(field, dim, cell):
    """The value the lattice field holds for ``cell``: ``cap`` less its distance.

    ``field`` is the field's bytes; ``dim`` is the dimension, 2 or 3.
    """
    at, shift = field_place(dim, cell)
    return (np.int64(field[at]) >> shift) & FIELD_MASK[dim]


@jit
def field_raise(field, dim, cell, value):
    """Store ``value`` for the lattice field's ``cell`` where it is larger than the value held.

    ``field`` is the field's bytes; ``dim`` is the dimension, 2 or 3.
    """
    at, shift = field_place(dim, cell)
    old = np.int64(field[at])
    if value > (old >> shift) & FIELD_MASK[dim]:
        field[at] = np.uint8((old & ~(FIELD_MASK[dim] << shift)) | (value << shift))


@borrow
def field_lower(field, dim, fw, cap, reach, ci, cj, ck):
    """Lower the distances within ``reach`` (at most ``cap``) about a particle in cell (ci, cj, ck).

    A field stores ``cap - distance``: zero is the cap, so a page that no
    particle came within reach of is never written and takes no memory.
    Each row is taken a tile's stretch at a time, whose cells lie side by
    side, by a branch-free maximum the compiler vectorises, which is faster
    than rings about the cell that stop where nothing drops. The indices are
    unsigned: numba wraps a negative signed index around, and that branch
    keeps LLVM from vectorising the rows (docs/performance.md).

    Parameters
    ----------
    field : uint8 (...)
        The field (level 0 of the pyramid's array), stored as ``field_place`` reads it.
    dim : int
        2 or 3.
    fw : int
        The field's side in cells.
    cap : int
        The field's cap, ``FIELD_CAP[dim]``.
    reach : int
        Cells to lower about the particle's, at most ``cap``: below it, a
        rebuild's own cells (``field_fill`` completes them), a cell at a time.
    ci, cj, ck : int
        The particle's cell (ck 0 in 2D).
    """
    reach -= 1
    last = (1 << maps.FIELD_TILE[dim]) - 1
    klo, khi = (max(ck - reach, 0), min(ck + reach, fw - 1)) if dim == 3 else (0, 0)
    alo, ahi = max(ci - reach, 0), min(ci + reach, fw - 1)
    for c in range(klo, khi + 1):
        dk = abs(c - ck)
        for b in range(max(cj - reach, 0), min(cj + reach, fw - 1) + 1):
            dj = max(dk, abs(b - cj))
            a = alo
            while a <= ahi:
                end = min(ahi, a | last)
                fb = np.uint64(maps.field_cell(dim, fw, a, b, c))
                if reach < cap - 1:  # a rebuild's own cells (``field_fill``): a cell a row
                    for x in range(a, end + 1):
                        field_raise(field, dim, fb + np.uint64(x - a), cap - max(dj, abs(x - ci)))
                elif FIELD_PACKED[dim]:
                    # the bytes from a's, a row of the table from the byte's low cell's place
                    s = np.int64(a & ~1) - (ci - reach) + 1
                    rb = np.uint64((((cap << 3) + dj) * 2 + (s & 1)) * 8 + (s >> 1))
                    first = fb >> np.uint64(1)
                    for x in range(np.uint64((end >> 1) - (a >> 1) + 1)):
                        old, new = field[first + x], PAIR_ROWS[rb + x]
                        keep = (((old | np.uint8(0x88)) - new) & np.uint8(0x88)) >> np.uint8(3)
                        keep *= np.uint8(15)  # the halves where the old value is the larger
                        field[first + x] = (old & keep) | (new & ~keep)
                else:
                    for x in range(end + 1 - a):
                        u = np.uint64(x)
                        field[fb + u] = max(field[fb + u], np.uint8(cap - max(dj, abs(x + a - ci))))
                a = end + 1


@jit
def field_fill(field, dim, fw, cap, held):
    """Fill in the distances of a field of side ``fw`` cells from its zero
    cells (the rest at ``cap``), stored as ``field_lower`` stores them.

    Two raster passes, each taking the minimum over the half of the
    3**dim - 1 neighbours already visited, give the exact Chebyshev distance;
    a whole grid costs a few operations per cell instead of ``field_lower``'s
    ``(2 cap - 1)**dim`` per particle, so a rebuild uses this. Only cells
    within the cap are written.

    ``held`` flags each tile (``maps.field_tile``) that holds a zero-distance
    cell. A distance reaches at most ``cap`` cells, less than a
    tile, so the passes visit only the tiles beside a held one, in the same
    order: a rebuild's grid is mostly empty, and filling it whole would cost
    a visible share of a growth (docs/performance.md).
    """
    t = maps.FIELD_TILE[dim]
    n = maps.field_tiles(dim, fw)
    nzt = n if dim == 3 else 1
    near = np.zeros(len(held), np.bool_)
    for tz in range(nzt):
        for ty in range(n):
            for tx in range(n):
                if held[maps.tile_number(dim, n, tx, ty, tz)]:
                    for z in range(max(tz - 1, 0), min(tz + 1, nzt - 1) + 1):
                        for y in range(max(ty - 1, 0), min(ty + 1, n - 1) + 1):
                            for x in range(max(tx - 1, 0), min(tx + 1, n - 1) + 1):
                                near[maps.tile_number(dim, n, x, y, z)] = True
    nz = fw if dim == 3 else 1
    for sweep in range(2):
        g = 1 - 2 * sweep  # +1 forward, -1 backward
        for cc in range(nz):
            c = cc if g > 0 else nz - 1 - cc
            for bb in range(fw):
                b = bb if g > 0 else fw - 1 - bb
                for tt in range(n):
                    tx = tt if g > 0 else n - 1 - tt
                    if not near[maps.tile_number(dim, n, tx, b >> t, c >> t)]:
                        continue
                    lo, hi = tx << t, min(fw, (tx + 1) << t)
                    for aa in range(lo, hi):
                        a = aa if g > 0 else lo + hi - 1 - aa
                        here = maps.field_cell(dim, fw, a, b, c)
                        u = field_value(field, dim, here)
                        if u == cap:
                            continue
                        # neighbours (dc, db, da) before this cell in the pass's order
                        for dc in range(-1 if dim == 3 else 0, 1):
                            for db in range(-1, 2 if dc < 0 else 1):
                                for da in range(-1, 2 if dc < 0 or db < 0 else 0):
                                    n0, n1, n2 = a + g * da, b + g * db, c + g * dc
                                    if 0 <= n0 < fw and 0 <= n1 < fw and 0 <= n2 < nz:
                                        u = max(u, field_value(field, dim, maps.field_cell(dim, fw, n0, n1, n2)) - 1)
                        field_raise(field, dim, here, u)
