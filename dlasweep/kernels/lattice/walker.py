"""The lattice walker's pieces: the site a point rounds to, the box, single
exact steps near the cluster (``near_step``, ``near_walk``; ``touches`` and
``step_to``, which ``grow._grow`` spells out in its hot loop), the release,
the lower bounds of the distance to the cluster (``distance_bound``, spelled
out there too) and the attachment of a particle.
"""

import numpy as np

from ..._jit import borrow, jit
from .. import maps
from ..centres import pyramid_dist
from ..model import GRID_GROWTH, diffusion_time, neighbour_stickiness, sticks_xo
from ..walk import below, direction, uniform, xo
from .field import FIELD_CAP, FIELD_MASK, field_place
from .words import fine2, fine3, in_contact, mark_images, occupied, site_word, word_at

FAR_CLEAR = tuple(((FIELD_CAP[d] << maps.FIELD_SHIFT) - 1) * np.sqrt(d) + 1.0 if d > 1 else 0.0 for d in range(4))
"""By dimension: where the centre pyramid bounds a site's distance by this much, no held coarse cell
lies within the field's cap of the site's (a particle in one would lie within cap coarse cells less
a site on every axis): a walker from a far jump reads the pyramid alone (``distance_bound``).

Measured and not kept: the field left unread, and a Brownian jump taken, wherever the pyramid's bound
alone reaches ``CIRCLE_MIN`` (3D, seed 1, side by side, the cores swapped): 1e5 89.2 steps a particle
against 86.3 in 1.044 and 1.097 times the time, 1e6 102.9 against 99.8 in 0.980 and 0.991; only where
it reaches beyond the field's largest bound (21 sites), 1e5 86.8 steps in 1.023 and 1.006 times, 1e6
100.2 in 0.999 and 1.003. Again at 1e7, the field unread wherever the pyramid's bound gives a jump
beyond the largest cube the field allows (22.9 sites: its largest bound, 21, less one, plus the
rounding and ``JUMP_MARGIN``), the pyramid's bound kept as a Chebyshev one there (3D lattice, seed
1, side by side, the cores swapped; other clusters): 1.019 and 0.997 times the time, 116.5 steps a
particle against 116.1; with a threshold of 23 sites and the field's largest bound in its place,
0.978 and 0.974 times, 115.3 steps; at 1e5, seeds 1 to 8, 86.0 steps a particle on average against
84.0, 5.55 s in all against 5.65. Within the spread that other clusters alone bring. The field's
read is not what a far walker waits on."""
GROWTH = GRID_GROWTH["lattice"]  # a module constant: numba freezes it into attach


@jit
def site(x):
    """The lattice site nearest the point x (one coordinate)."""
    return np.int64(np.floor(x + 0.5))


@borrow
def outside(q, dim, line, lo, hi):
    """Whether site q has left the box (for substrates: through the top)."""
    if line:
        return q[dim - 1] > hi
    for a in range(dim):
        if q[a] < lo or q[a] > hi:
            return True
    return False


@borrow
def occupied_neighbours(words, dim, start, blocks, width, off, q, moves, period):
    """How many of site q's neighbours under ``moves`` are occupied, the substrate's
    sites (below height 0) counted as occupied: B of the ``neighbour_alpha`` law."""
    b = 0
    for m in range(moves.shape[0]):
        n0, n1, n2 = q[0] + moves[m, 0], q[1] + moves[m, 1], q[2] + moves[m, 2]
        if period > 0:
            if (n2 if dim == 3 else n1) < 0:
                b += 1
                continue
            n0 = n0 % period
            if dim == 3:
                n1 = n1 % period
        if occupied(words, dim, start, blocks, width, off, n0, n1, n2):
            b += 1
    return b


@borrow
def contact_sticks(words, dim, start, blocks, width, off, q, moves, period, stickiness, alpha, s0, s1, s2, s3):
    """Whether a walker at site q, which touches the cluster, sticks under the ``neighbour_alpha`` law
    (``model.neighbour_stickiness``, B from ``occupied_neighbours``, B_full the neighbourhood less
    one), and the stream's new state (registers, as ``model.sticks_xo``)."""
    b = occupied_neighbours(words, dim, start, blocks, width, off, q, moves, period)
    return sticks_xo(neighbour_stickiness(stickiness, alpha, b, moves.shape[0] - 1), s0, s1, s2, s3)


@borrow
def near_step(words, dim, start, blocks, width, off, q, moves, period, stickiness, rs, near, alpha):
    """One site of the exact lattice walk: stick, or step to a random neighbour.

    The walker first sticks with probability ``stickiness`` if it touches the
    cluster, else it steps (staying put when the neighbour is occupied).
    ``near`` False promises that no particle is within two sites, which
    spares the contact and occupancy tests. Returns whether it stuck.
    """
    up = dim - 1
    line = period > 0
    if (near or (line and q[up] <= 1)) and in_contact(words, dim, start, blocks, width, off, q, moves, period):
        if alpha < 1.0:  # the neighbour_alpha law
            stuck, rs[0], rs[1], rs[2], rs[3] = contact_sticks(words, dim, start, blocks, width, off, q, moves,
                                                               period, stickiness, alpha, rs[0], rs[1], rs[2], rs[3])
        else:
            stuck, rs[0], rs[1], rs[2], rs[3] = sticks_xo(stickiness, rs[0], rs[1], rs[2], rs[3])
        if stuck:
            return True
    m = np.int64(uniform(rs) * moves.shape[0])
    n0, n1, n2 = q[0] + moves[m, 0], q[1] + moves[m, 1], q[2] + moves[m, 2]
    if line:
        n0 = n0 % period
        if dim == 3:
            n1 = n1 % period
    blocked = near and occupied(words, dim, start, blocks, width, off, n0, n1, n2)
    if not blocked and not (line and (n2 if dim == 3 else n1) < 0):
        q[0], q[1], q[2] = n0, n1, n2
    return False


@borrow
def near_walk(
    words, dim, start, blocks, width, off, q, moves, period, stickiness, rs,
    boxed, lo, hi, radius, budget, alpha,
):
    """Single lattice steps from site q until the walker sticks or may leave.

    It stops, without sticking, after ``budget`` steps (0: no limit), on
    leaving the box or beyond ``radius`` (0: none).

    Returns
    -------
    stuck : bool
    taken : int, the steps taken
    """
    up = dim - 1
    line = period > 0
    taken = 0
    while True:
        i, j, k = q[0] + off, q[1] + off, q[2] + off
        ingrid = 0 <= i < width and 0 <= j < width and 0 <= k < width
        # a clear level-1 cell: no particle within two sites
        near = ingrid and maps.test(words, dim, start, blocks, 1, i >> 1, j >> 1, k >> 1)
        if near_step(words, dim, start, blocks, width, off, q, moves, period, stickiness, rs, near, alpha):
            return True, taken
        taken += 1
        if taken == budget:
            return False, taken
        if boxed and outside(q, dim, line, lo, hi):
            return False, taken
        if radius > 0.0:
            r2 = float(q[up] * q[up]) if line else float(q[0] * q[0] + q[1] * q[1] + q[2] * q[2])
            if r2 > radius * radius:
                return False, taken


@borrow
def touches(words, dim, nb0, width, off, q, moves, nm, line, period):
    """Whether site q touches a particle (or the substrate) under ``moves``:
    ``words.in_contact`` as the single walker's hot loop reads the words,
    where ``_grow`` holds a copy of this body, spelled out."""
    touch = False
    for m in range(nm):
        n0, n1, n2 = q[0] + moves[m, 0], q[1] + moves[m, 1], q[2] + moves[m, 2]
        if line:
            if (n2 if dim == 3 else n1) < 0:
                touch = True
                break
            n0 = n0 % period
            if dim == 3:
                n1 = n1 % period
        cw, cb = site_word(dim, nb0, width, off, n0, n1, n2)
        if cw >= 0 and (words[cw] >> np.uint64(cb)) & np.uint64(1) != np.uint64(0):
            touch = True
            break
    return touch


@borrow
def step_to(words, dim, nb0, width, off, q, pos, moves, nm, line, period, s0, s1, s2, s3):
    """One lattice step from site q to a random neighbour, into ``pos``
    unless the neighbour is occupied (or below the substrate); the stream
    in registers, returned. ``_grow`` holds a copy of this body, spelled out."""
    s0, s1, s2, s3, u = xo(s0, s1, s2, s3)
    m = np.int64(u * nm)
    n0, n1, n2 = q[0] + moves[m, 0], q[1] + moves[m, 1], q[2] + moves[m, 2]
    if line:
        n0 = n0 % period
        if dim == 3:
            n1 = n1 % period
    cw, cb = site_word(dim, nb0, width, off, n0, n1, n2)
    filled = cw >= 0 and (words[cw] >> np.uint64(cb)) & np.uint64(1) != np.uint64(0)
    if not filled and not (line and (n2 if dim == 3 else n1) < 0):
        pos[0], pos[1], pos[2] = n0, n1, n2
    return s0, s1, s2, s3


@jit
def attach(points, steps, count, pending, q, dim, period, r_max, h_max, grid):
    """Add the particle at site q, marked in the grid unless the cluster nears its edge.

    ``grid`` is (words, start, blocks, cells, field, width, off). Returns the
    new count, r_max, h_max, the grid's width and offset, and whether it was
    outgrown: the caller then builds a larger one from it (``words.regrow``), which marks
    this one.
    """
    words, start, blocks, cells, field, width, off = grid
    line = period > 0
    up = dim - 1
    for a in range(dim):
        points[count, a] = q[a]
    steps[count] = diffusion_time(pending)
    count += 1
    r_max = max(r_max, np.sqrt(float(q[0] * q[0] + q[1] * q[1] + q[2] * q[2])))
    h_max = max(h_max, float(q[up]))
    extent = 0
    for a in range(dim):
        extent = max(extent, abs(q[a]))
    if (q[up] + off + 4 >= width) if line else (extent + 4 >= off):
        # room for the cluster, in whole words (8 or 4 sites) of the field's cells
        width = (int(width * GROWTH) + 15) // 16 * 16
        if not line:
            off = width // 2
        return count, r_max, h_max, width, off, True
    mark_images(words, dim, start, blocks, cells, field, width, off, q, period, FIELD_CAP[dim], field[:0])
    return count, r_max, h_max, width, off, False


@borrow
def release(rng, dim, line, launch_box, size, box_lo, box_hi, launch_r, pos):
    """Release a walker: fill ``pos[:dim]`` with a uniform point of where walkers start.

    That is a uniform site of the surface of the box, sites ``box_lo`` to
    ``box_hi`` (``size`` of them) on each axis (``launch_box``; a substrate's
    box: its top), else a uniform point at height ``launch_r`` above the
    substrate, else of the launch circle (sphere) of radius ``launch_r``.
    """
    up = dim - 1
    if launch_box:
        ax = below(rng, dim)
        for a in range(dim):
            pos[a] = box_lo + below(rng, size)
        if line:
            pos[up] = box_hi
        else:
            pos[ax] = box_lo if rng.random() < 0.5 else box_hi
    elif line:
        for a in range(up):
            pos[a] = rng.random() * size
        pos[up] = launch_r
    else:
        direction(rng, dim, pos)
        for a in range(dim):
            pos[a] = launch_r * pos[a]


@borrow
def distance_bound(words, field, levels, dim, width, nb0, base1, nb1, fw0, cap, i, j, k, from_far):
    """Lower bounds of the distance from grid site (i, j, k) to the cluster:
    Chebyshev, 0 when a particle may lie within two sites, and Euclidean from
    beyond the field's reach, 0 within it.

    The Chebyshev bound is exact within a few sites (the words: ``fine2``,
    ``fine3``), else the coarse field's (whole cells of ``2**FIELD_SHIFT``
    between), 5 off the grid; where the field is at its cap, the centre pyramid
    above it bounds the Euclidean distance (``centres.pyramid_dist``). ``_grow``
    holds a copy of this body, spelled out. With ``from_far`` (the walker was
    released, returned or took a Brownian jump) the pyramid is read first, and
    the field's cell only where the pyramid's bound falls short of
    ``FAR_CLEAR`` (the same bounds, the same clusters): side by side (seeds 1
    and 2), 2D 1e7 0.939 and 0.922 times the time, 3D 3e6 0.913 and 0.995, 3D
    1e7 1.015 (seed 1), on a host whose memory slows the large clusters more
    (2D 1e7 on an earlier host: 1.010 and 0.984).

    Returns
    -------
    d : int
    far : float
    """
    d = np.int64(5)  # off the grid: every particle lies 4 sites inside it
    far = 0.0
    if 0 <= i < width and 0 <= j < width and 0 <= k < width:
        if from_far and len(levels) > 2:
            far = pyramid_dist(field, levels, dim, width, float(i), float(j), float(k))
        cell = cap
        if far < FAR_CLEAR[dim]:
            ck = k >> maps.FIELD_SHIFT if dim == 3 else 0
            ci, cj = i >> maps.FIELD_SHIFT, j >> maps.FIELD_SHIFT
            at, shift = field_place(dim, maps.field_cell(dim, fw0, ci, cj, ck))
            cell = cap - ((np.int64(field[at]) >> shift) & FIELD_MASK[dim])
            if cell < cap:
                far = 0.0
            elif not from_far and len(levels) > 2:
                far = pyramid_dist(field, levels, dim, width, float(i), float(j), float(k))
        if cell > 1:
            d = ((cell - 1) << maps.FIELD_SHIFT) + 1
        else:
            cw, cb = maps.index(dim, base1, nb1, i >> 1, j >> 1, k >> 1)
            if (words[cw] >> np.uint64(cb)) & np.uint64(1) != np.uint64(0):
                d = 0  # a set level-1 cell: a particle may lie within two sites
            elif dim == 2:
                bx, by = i >> 3, j >> 3
                d = fine2(
                    word_at(words, 2, nb0, bx - 1, by - 1, 0), word_at(words, 2, nb0, bx, by - 1, 0),
                    word_at(words, 2, nb0, bx + 1, by - 1, 0), word_at(words, 2, nb0, bx - 1, by, 0),
                    words[maps.block_word(2, 0, nb0, bx, by, 0)], word_at(words, 2, nb0, bx + 1, by, 0),
                    word_at(words, 2, nb0, bx - 1, by + 1, 0), word_at(words, 2, nb0, bx, by + 1, 0),
                    word_at(words, 2, nb0, bx + 1, by + 1, 0), i & 7, j & 7,
                )
            else:
                d = fine3(words, nb0, i, j, k)
    return d, far
