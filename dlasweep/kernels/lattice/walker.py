"""The lattice walker's pieces: the site a point rounds to, the box, single
exact steps near the cluster (``near_step``, ``near_walk``; ``touches`` and
``step_to``, which ``lattice_growth._grow`` spells out in its hot loop), the
release, the lower bounds of the distance to the cluster (``distance_bound``,
spelled out there too) and the attachment of a particle.
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
a site on every axis): a walker from a far jump reads the pyramid alone (``distance_bound``). Below this the field is
read too: leaving it unread at lower thresholds gains nothing, as the field's read is not what a
far walker waits on (docs/performance.md)."""
GROWTH = GRID_GROWTH["lattice"]  # a module constant: numba freezes it into attach


@jit
def site(x):
    """The lattice site nearest the point x (one coordinate)."""
    return np.int64(np.floor(x + 0.5))


@borrow
def outside(q, dim, line, lo, hi):
    """Whether site q (int64 (3,)) has left the box, sites ``lo`` to ``hi`` on each of ``dim`` axes
    (with ``line``, a substrate's: through the top)."""
    if line:
        return q[dim - 1] > hi
    for a in range(dim):
        if q[a] < lo or q[a] > hi:
            return True
    return False


@borrow
def drifted_move(moves, u, mu0, mu1, mu2):
    """The move a uniform ``u`` picks under the drift mu = (mu0, mu1, mu2): move m with probability
    (1 + mu.m) / M, so that the mean step is mu times the per-axis variance (the drift's v / (2 D)).

    The moves come in opposite pairs, m and M - 1 - m (``exits.unit_moves``); ``u`` picks a pair
    uniformly and its fractional part, a second uniform, the pair's sign.

    Parameters
    ----------
    moves : int64 (M, 3)
        Unit moves.
    u : float
        A uniform in [0, 1).
    mu0, mu1, mu2 : float
        The drift vector (``params.drift_vector``), with 1 + mu.m >= 0 for every move.
    """
    v = u * (moves.shape[0] >> 1)
    m = np.int64(v)
    tilt = mu0 * moves[m, 0] + mu1 * moves[m, 1] + mu2 * moves[m, 2]
    return m if 2.0 * (v - m) < 1.0 + tilt else moves.shape[0] - 1 - m


@borrow
def occupied_neighbours(words, dim, start, blocks, width, off, q, moves, period):
    """How many of site q's neighbours under ``moves`` are occupied, the substrate's
    sites (below height 0) counted as occupied: B of the ``neighbour_alpha`` law.

    Parameters
    ----------
    words : uint64 (...)
        The grid's words: the occupancy (segment 0), then level 1.
    dim : int
        2 or 3.
    start, blocks : int64 (S + 1,), int64 (S,)
        The words' layout (``maps.layout``).
    width, off : int
        The grid's side in sites, and its offset: site q is cell q + ``off``.
    q : int64 (3,)
        The site whose neighbours are counted.
    moves : int64 (M, 3)
        Unit moves: the neighbourhood.
    period : int
        A substrate's period; 0: none (no substrate, nothing wraps).
    """
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
    one), and the stream's new state (registers, as ``model.sticks_xo``).

    Parameters
    ----------
    words, dim, start, blocks, width, off, q, moves, period
        As ``occupied_neighbours`` takes them.
    stickiness : float
        The probability of sticking with B_full or more occupied neighbours.
    alpha : float
        The law's ``neighbour_alpha``, in (0, 1]: each occupied neighbour short of
        B_full multiplies ``stickiness`` by it.
    s0, s1, s2, s3 : uint64
        The xoshiro256+ state (``walk.xo``).
    """
    b = occupied_neighbours(words, dim, start, blocks, width, off, q, moves, period)
    return sticks_xo(neighbour_stickiness(stickiness, alpha, b, moves.shape[0] - 1), s0, s1, s2, s3)


@borrow
def near_step(words, dim, start, blocks, width, off, q, moves, period, stickiness, rs, near, alpha, mu0, mu1, mu2):
    """One site of the exact lattice walk: stick, or step to a random neighbour.

    The walker first sticks if it touches the cluster, with probability
    ``stickiness`` (under the ``neighbour_alpha`` law, ``alpha`` < 1: scaled by
    the occupied neighbours, ``contact_sticks``), else it steps (staying put
    when the neighbour is occupied).
    ``near`` False promises that no particle is within two sites, which
    spares the contact and occupancy tests. Returns whether it stuck.

    Parameters
    ----------
    words : uint64 (...)
        The grid's words: the occupancy (segment 0), then level 1.
    dim : int
        2 or 3.
    start, blocks : int64 (S + 1,), int64 (S,)
        The words' layout (``maps.layout``).
    width, off : int
        The grid's side in sites, and its offset: site q is cell q + ``off``.
    q : int64 (3,)
        The walker's site, moved.
    moves : int64 (M, 3)
        Unit moves, which are also the contacts.
    period : int
        A substrate's period; 0: none.
    stickiness : float
        The probability of sticking at a contact.
    rs : uint64 (4,)
        The xoshiro256+ stream.
    near : bool
        Whether a particle may lie within two sites.
    alpha : float
        The ``neighbour_alpha`` law's alpha, in (0, 1] (``model.neighbour_stickiness``);
        1: every contact sticks with ``stickiness``, and the neighbours go uncounted.
    mu0, mu1, mu2 : float
        The drift vector (``drifted_move``); all 0: uniform moves.
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
    u = uniform(rs)
    m = np.int64(u * moves.shape[0])
    if mu0 != 0.0 or mu1 != 0.0 or mu2 != 0.0:
        m = drifted_move(moves, u, mu0, mu1, mu2)
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
    boxed, lo, hi, radius, budget, alpha, mu0, mu1, mu2,
):
    """Single lattice steps from site q until the walker sticks or may leave.

    It stops, without sticking, after ``budget`` steps (0: no limit), on
    leaving the box or beyond ``radius`` (0: none).

    Parameters
    ----------
    words : uint64 (...)
        The grid's words: the occupancy (segment 0), then level 1.
    dim : int
        2 or 3.
    start, blocks : int64 (S + 1,), int64 (S,)
        The words' layout (``maps.layout``).
    width, off : int
        The grid's side in sites, and its offset: site q is cell q + ``off``.
    q : int64 (3,)
        The walker's site, moved.
    moves : int64 (M, 3)
        Unit moves, which are also the contacts.
    period : int
        A substrate's period; 0: none.
    stickiness : float
        The probability of sticking at a contact.
    rs : uint64 (4,)
        The xoshiro256+ stream.
    boxed : bool
        Whether the box's walls end the walk.
    lo, hi : int
        The box's lowest and highest site on each axis.
    radius : float
        Kill (or return) radius beyond which the walk ends; 0: none.
    budget : int
        Most steps; 0: no limit.
    alpha : float
        The ``neighbour_alpha`` law's alpha, as ``near_step`` takes it.
    mu0, mu1, mu2 : float
        The drift vector, as ``near_step`` takes it.

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
        if near_step(words, dim, start, blocks, width, off, q, moves, period, stickiness, rs, near, alpha, mu0, mu1,
                     mu2):
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
    where ``_grow`` holds a copy of this body, spelled out.

    Parameters
    ----------
    words : uint64 (...)
        The grid's words, the occupancy first.
    dim : int
        2 or 3.
    nb0 : int
        Words a side of the occupancy segment.
    width, off : int
        The grid's side in sites, and its offset.
    q : int64 (3,)
        The site.
    moves : int64 (M, 3)
        The contacts.
    nm : int
        ``len(moves)``.
    line : bool
        Whether the seed is a substrate.
    period : int
        A substrate's period.
    """
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
def step_to(words, dim, nb0, width, off, q, pos, moves, nm, line, period, drifted, mu0, mu1, mu2, s0, s1, s2, s3):
    """One lattice step from site q to a random neighbour, into ``pos``
    unless the neighbour is occupied (or below the substrate); the stream
    in registers, returned. ``_grow`` holds a copy of this body, spelled out.

    Parameters
    ----------
    words, dim, nb0, width, off, q
        As ``touches`` takes them.
    pos : float64 (3,)
        Receives the new site.
    moves, nm, line, period
        As ``touches`` takes them.
    drifted : None or True
        Whether a drift tilts the move (``model.drift_flag``); None: uniform moves, compiled without the tilt.
    mu0, mu1, mu2 : float
        The drift vector (``drifted_move``).
    s0, s1, s2, s3 : uint64
        The xoshiro256+ state (``walk.xo``).
    """
    s0, s1, s2, s3, u = xo(s0, s1, s2, s3)
    m = np.int64(u * nm)
    if drifted is not None:
        m = drifted_move(moves, u, mu0, mu1, mu2)
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

    Parameters
    ----------
    points : int32 (n, dim)
        Receives the site in row ``count``.
    steps : uint32 (n,)
        Receives the diffusion time.
    count : int
        Particles before this one.
    pending : int
        Its steps since the last attachment.
    q : int64 (3,)
        The site.
    dim : int
        2 or 3.
    period : int
        A substrate's period; 0: none.
    r_max, h_max : float
        The cluster's radius and height so far.
    grid : tuple
        The grid.
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

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws the place.
    dim : int
        2 or 3.
    line : bool
        Whether the seed is a substrate.
    launch_box : bool
        Whether walkers start on the box's surface.
    size : int
        The box's side in sites (a substrate's period).
    box_lo, box_hi : int
        The box's lowest and highest site on each axis.
    launch_r : float
        The launch radius (a substrate's: launch height).
    pos : float64 (3,)
        Receives the place.
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
    ``FAR_CLEAR``: the same bounds, with fewer reads of the field for the
    walkers far from the cluster (docs/performance.md).

    Parameters
    ----------
    words : uint64 (...)
        The grid's words: the occupancy (segment 0), then level 1.
    field : uint8 (...)
        The Chebyshev field with the centre pyramid above it.
    levels : int64 (L + 1,)
        Where each level starts in ``field`` (``maps.pyramid_starts``).
    dim : int
        2 or 3.
    width : int
        The grid's side in sites.
    nb0 : int
        Words a side of the occupancy segment.
    base1 : int
        Where level 1 starts in ``words``.
    nb1 : int
        Words a side of level 1.
    fw0 : int
        The field's side in cells.
    cap : int
        The field's cap, ``FIELD_CAP[dim]``.
    i, j, k : int
        The site's cell in the grid (site + ``off``; k 0 in 2D).
    from_far : bool
        Whether the walker comes from far: then the pyramid is read first.

    Returns
    -------
    d : int
        Chebyshev bound in sites (0: a particle may lie within two sites).
    far : float
        Euclidean bound in sites from the pyramid, 0.0 where it gives none.
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
