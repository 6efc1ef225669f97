"""The off-lattice grid's geometry: where the cell list and the maps lie, in two small arrays.

``layout`` returns ``gi`` (integers) and ``gf`` (floats), read through the
named slots below (numba freezes them into the kernels as constants). The
cell list (``celllist``) and the maps and distance bounds (``grid``) share them.
"""

import numpy as np

from ..._jit import jit
from ..centres import FCAP, FS
from ..model import GRID_GROWTH

LINE_PAD = 32
"""Periodic images are marked in the maps up to this distance (line seed)."""
CELL_SIDE = (8, 4)
"""Side of the cell list's cells (diameters), 2D and 3D: a power of two, a multiple of the coarse
cells' ``2**FS``. A larger side puts more area under a tile's 64 heads, so that fewer tiles (and
less memory) follow the cluster, while a gather reads more particles a cell: 4 is the balance in
3D; 2D's 8 saves memory for some time a gather (the sides tried: docs/performance.md)."""
GROW = GRID_GROWTH["offlattice"]
"""The grids' growth (``model.GRID_GROWTH``), a module constant that numba freezes into the kernels."""

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
def layout(dim, line, size, need):
    """Grid geometry covering a cluster of extent ``need`` (max |coordinate|
    for point seeds, h_max for a substrate), with room to grow: ``gi`` and ``gf``.

    ``dim`` is 2 or 3; ``line`` whether the seed is a substrate, whose
    period is ``size``; else ``size`` is the box's side (0: no box), which
    bounds the grid."""
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

