"""Off-lattice growth: one walker at a time from release to contact
(``walker``), or many in lockstep (``lockstep``), the cluster's rows kept
in cell order as it grows, and ``grow_offlattice``, the entry point.
"""

import time

import numpy as np
from numba import literally

from ..._jit import cached, clock, jit, literal_entry
from .. import maps
from .. import model as codes
from ..model import STEPS_DTYPE, checkpoint, gaussian_flag, grown, lockstep_flag, model_from
from ..walk import seed_stream
from .celllist import attachment_order, sort_cells, sort_tail
from .grid import build_grid, level_starts, no_grid, regrow_grid
from .lockstep import grow_in_lockstep
from .walker import HEADS_FULL, attach, index_late, neighbour_list, walk_to_contact

BY_CELL = (False, False, False, True)
"""By dimension: whether the particles' rows are stored cell after cell while the cluster grows
(``celllist.sort_cells``), at 4 bytes a particle for their attachment numbers. 3D only: a 3D
gather reads several cells' lists, which then lie in a stretch or two of rows; in 2D the sorts
cost more time than they save (docs/performance.md)."""
SORT_FIRST = 4096
"""Particles at the first sort (fewer fit in the caches whatever their order)."""
SORT_GROWTH = 1.25
"""The rows are sorted again each time the cluster has grown by this factor: the newest
particles, sorted apart (``TAIL_SORT``), are a fifth of all at most. A smaller factor sorts too
often, a larger one leaves too many rows to the tail sorts (the factors tried: docs/performance.md)."""
TAIL_SORT = 32
"""Between sorts, the rows attached since the last are sorted by cell (``celllist.sort_tail``) each
time the cluster has grown by a ``TAIL_SORT``-th: walkers arrive where the cluster grows, so
without these sorts a gather reads more than half its particles from rows attached since the last
full sort, one scattered row each; with them, few (the counts, the gain and the divisors tried:
docs/performance.md)."""


@jit
def _grow(dimension, lockstep, gaussian, n, model, marks, rng, times):
    """Grow an off-lattice cluster of up to ``n`` particles.

    After the seed, ``walker.walk_to_contact`` brings one walker at a time to
    contact and ``walker.attach`` adds it; with more than one walker
    ``lockstep.grow_in_lockstep`` takes over instead. The rows are sorted by
    cell as the cluster grows (``BY_CELL``, ``SORT_GROWTH``, ``TAIL_SORT``) and
    put back in attachment order at the end. A grid the cluster outgrows is
    dropped at once and the larger one built at the top of the next pass, where
    numba has freed the old arrays (its centre field carried over:
    ``grid.regrow_grid``).

    Parameters
    ----------
    dimension : int
        The model's dimension, a literal that ``walker.walk_to_contact`` is compiled for.
    lockstep : None or True
        ``model.lockstep_flag(model.walkers)``: the lockstep walk is compiled in only where it runs.
    gaussian : None or True
        ``model.gaussian_flag(model.step)``, as ``walker.walk_to_contact`` takes it.
    n : int
        Most particles to grow, the seed's included.
    model : Model
        The model (``kernels.model.Model``).
    marks : int64 (K,)
        Particle counts at which to read the clock, ascending.
    rng : numpy.random.Generator
        Seeds the walk's xoshiro256+ stream (``walk.seed_stream``) and draws
        what the walk draws from it (``walker.walk_to_contact``'s ``rng``).
    times : float64 (K,)
        Filled with the seconds at each mark as it passes.

    Returns
    -------
    points : float64 (n, dim), the first ``count`` rows grown
    steps : uint32 (n,)
    parents : int32 (n,)
    count : int
    status : int, a code of ``dlasweep.params.STATUSES``
    """
    literally(dimension)
    t0 = clock()
    dim, seed_shape, size = model.dim, model.seed_shape, model.size
    line = seed_shape == codes.LINE
    nseed = 0 if line else (1 if seed_shape == codes.POINT else 1 << dim)
    cap = max(n, 1)
    pts = maps.filled(cap * dim, 0.0, np.float64).reshape((cap, dim))
    steps = maps.filled(cap, 0, STEPS_DTYPE)
    parents = maps.filled(cap, -1, np.int32)
    nxt = maps.filled(cap, -1, np.int32)
    order = np.arange(cap if BY_CELL[dim] and model.walkers == 1 else 0, dtype=np.int32)
    next_sort = SORT_FIRST
    sorted_rows = 0
    next_tail = SORT_FIRST
    count = min(n, nseed)
    geo = np.zeros(3)  # r_max, Chebyshev extent, h_max
    geo[2] = -1.0
    for q in range(count):
        r2 = 0.0
        for a in range(dim):
            if seed_shape == codes.BLOCK:
                pts[q, a] = float((q >> a) & 1)
            r2 += pts[q, a] ** 2
            geo[1] = max(geo[1], abs(pts[q, a]))
        geo[0] = max(geo[0], np.sqrt(r2))
    gi, gf, words, start, blocks, cells, dirr, heads, field = build_grid(
        dim, line, size, max(geo[2], 0.0) if line else geo[1], pts, count, nxt, 0)
    pstart = level_starts(gi, dim)
    old_gi, old_field = gi, field  # the grid's field, carried over when it is outgrown
    rs = seed_stream(rng)
    passed = checkpoint(marks, times, 0, count, t0)
    if lockstep is not None:
        count, status = grow_in_lockstep(n, model, marks, rng, rs, t0, times, passed, pts, order, steps, parents, nxt,
                                         count, geo, (gi, gf, words, start, blocks, cells, dirr, heads, field))
        return pts, steps, parents, count, status
    w = np.zeros(3)
    u = np.zeros(3)
    normal = np.zeros(4)  # and the particle touched (``contact.settle``)
    scratch = np.zeros(3)
    anchor = np.zeros(3)
    lx, ly, lz, li = neighbour_list(model.contact_distance)
    mx, my, mz, mi = neighbour_list(model.contact_distance)
    hb = 0.5 * size
    boxed = size > 0 and not line
    total = np.int64(0)
    pending = np.int64(0)
    status = codes.OK
    regrid = -1
    while count < n:
        if regrid >= 0:
            # Built here, not where the old grid was outgrown: numba frees an array
            # held across a loop's passes only when the pass ends.
            gi, gf, words, start, blocks, cells, dirr, heads, field = regrow_grid(
                dim, line, size, geo[2] if line else geo[1], pts, count, nxt, regrid, old_gi, old_field)
            old_gi, old_field = gi, field
            pstart = level_starts(gi, dim)
            regrid = -1
        if len(order) > 0 and count >= next_tail:
            if count >= next_sort:
                sort_cells(pts, order, nxt, count, dim, gi, gf, dirr, heads)
                sorted_rows = count
                next_sort = int(count * SORT_GROWTH)
            else:
                sort_tail(pts, order, nxt, sorted_rows, count, dim, gi, gf, dirr, heads)
            next_tail = count + count // TAIL_SORT
        launch_r = model.launch_factor * (max(geo[2], 0.0) if line else geo[0]) + model.launch_margin
        if model.launch_box:
            if (line and geo[2] >= size - 2.0) or (not line and geo[1] >= hb - 2.0):
                status = codes.BOUNDARY
                break
        elif boxed and launch_r > hb - 1.0:
            status = codes.BOUNDARY
            break
        stuck, total, pending = walk_to_contact(dimension, gaussian, model, launch_r, model.kill_factor * launch_r,
                                                total, pending, w, u, normal, scratch, anchor, lx, ly, lz, li, mx, my,
                                                mz, mi, pts, nxt, gi, gf, words, start, blocks, cells, dirr, heads,
                                                field, pstart, geo, rs, rng)
        if not stuck:
            status = codes.STEP_LIMIT
            break
        if model.contact_distance < 1.0 and normal[3] >= 0.0:
            # noise reduction (``contact_distance``): moved along the line of centres, at contact_distance
            # from the particle (its image) touched; a walker at the substrate stays
            for a in range(dim):
                w[a] -= (1.0 - model.contact_distance) * normal[a]
        count, tiles = attach(w, normal[3], count, pending, pts, order, steps, parents, nxt, geo, dim, line, size, gi,
                              gf, words, start, blocks, cells, dirr, heads, field)
        if tiles == HEADS_FULL:
            heads = index_late(count - 1, pts, nxt, dim, size, gi, gf, words, start, blocks, cells, dirr, heads, field)
        elif tiles >= 0:  # dropped now (every name but the field's), the larger one built at the next pass's top
            gi, gf, words, start, blocks, cells, dirr, heads, field = no_grid()
            regrid = tiles
        pending = 0
        passed = checkpoint(marks, times, passed, count, t0)
    if len(order) > 0:
        attachment_order(pts, order, count)
    return pts, steps, parents, count, status


def grow_offlattice(n, p, marks, rngs, times=None):
    """Grow off-lattice clusters, one with each generator; see ``dlasweep.grow``.

    Takes (``n``, ``p``, ``marks``, ``rngs``, ``times``) and returns what
    ``lattice.grow_lattice`` does, but ``points`` are
    the float64 centres of unit-diameter disks (spheres), (n_grown, dim), and
    a parent is the particle touched at contact (``contact.settle``).
    The growth kernel, compiled once for the batch's argument types
    (``_jit.literal_entry``), is called for each generator: a batch compiles the same one kernel as a
    single cluster, and a call from Python costs less than a small cluster's growth (docs/performance.md).
    """
    if not rngs:
        return []
    times = np.full((len(rngs), len(marks)), np.nan) if times is None else times
    model = model_from(p)
    args = (lockstep_flag(model.walkers), gaussian_flag(model.step), int(n), model, np.asarray(marks, np.int64))
    kernel = literal_entry(_grow, model.dim, *args, rngs[0], times[0])
    out = []
    for rng, row in zip(rngs, times):
        start = time.perf_counter()
        pts, steps, parents, count, status = kernel(model.dim, *args, rng, row)
        out.append(grown(pts, steps, parents, count, status, row, time.perf_counter() - start))
    return out


def compiled(dim, walkers=1, step=0.0) -> bool:
    """Whether numba's on-disk cache holds this growth kernel for ``dim``, ``walkers`` and ``step`` (most of its
    compile time)."""
    return cached(_grow, dim, lockstep_flag(walkers), gaussian_flag(step))
