"""Off-lattice growth: the walk of one walker from release to contact, the
attachment of particles, and the lockstep walkers.

Far from the cluster a walker moves by walk-on-spheres jumps onto the
sphere whose radius is a lower bound on its free distance (``grid``:
field, maps, and the cluster's bounding circle); where the centre pyramid
gives that bound, out of the larger ball about the centre of its cell that
holds no particle, by the exact exit law (``walk.ball_exit``). Near it, exact nearest
distances come from a neighbour list of radius ``LIST_RADIUS`` gathered
around an anchor point: while the walker stays near the anchor its free
distance is a minimum over a handful of centres. Inside the ``EPS`` shell
it moves by ``RAY`` with an exact ray cast (``contact``).
"""

import numpy as np
from numba import literally

from ..._jit import borrow, cached, call_literal, clock, jit
from .. import maps
from .. import model as codes
from ..centres import FS, cell_centre, centre_bound, pyramid_ball
from ..model import STEPS_DTYPE, checkpoint, diffusion_time, grown, lockstep_flag, model_from, sticks
from ..walk import ball_exit, return_to_plane, return_to_sphere, seed_stream, unit_vector, xdir
from .celllist import INF, attachment_order, gather, insert, more_heads, sort_cells, sort_tail
from .contact import EPS, RAY, cast, gauss_move, ray_to, rebound, settle
from .geometry import COVERED, TILES_USED
from .grid import (FAR_CLEAR, NEAR, build_grid, face_gap, level_starts, map_dist, mark, no_grid, regrow_grid,
                   walk_geometry)

LIST_RADIUS = 3.0
"""Radius (centre distance) of the cached neighbour list. Longer lists give
longer exact jumps and serve longer, but a gather visits (r + 1)**dim cells
of linked lists: side by side at 2D 1e6, radius 6 took 99 steps per particle
against 107 at radius 3, in the same time (15.2 against 15.5 s, two rounds),
and radius 4 made 3D 1e5 slower (4.2 against 3.0 s). Against radius 3, side by side (seeds 1
and 2): 2D 1e7, radius 4 1.113 and 1.014 times the time, radius 2 1.059 and 1.053 (55.4 steps a
particle against 50.4); 3D 3e6, radius 4 1.070 and 1.088, radius 2.5 1.079 and 0.923."""
LCAP = 1024
"""Capacity of the neighbour lists (a packing within radius 6 in 2D or 3 in
3D holds < 200)."""
BY_CELL = (False, False, False, True)
"""By dimension: whether the particles' rows are stored cell after cell while the cluster grows
(``celllist.sort_cells``), at 4 bytes a particle for their attachment numbers. 2D rows by cell,
1e7 side by side (seeds 1 and 2): 1.056 and 1.048 times the time (the same clusters); again with
the tail sorts (``TAIL_SORT``), seed 1: 1e6 1.031, 1e7 1.059 times, the peak 18 MB higher."""
SORT_FIRST = 4096
"""Particles at the first sort (fewer fit in the caches whatever their order)."""
SORT_GROWTH = 1.25
"""The rows are sorted again each time the cluster has grown by this factor: the newest
particles, sorted apart (``TAIL_SORT``), are a fifth of all at most. 3D 3e6, one after the other on one
core (a benchmark on the other): 1.1 took 64.0 s against 60.9, 1.5 60.3 against 58.5."""
TAIL_SORT = 32
"""Between sorts, the rows attached since the last are sorted by cell (``celllist.sort_tail``) each
time the cluster has grown by a ``TAIL_SORT``-th: walkers arrive where the cluster grows, and a
gather read more than half its particles (3D 1e6, 14 of 27; 3e6, 16) from rows attached since the
last sort, one scattered row each; with these sorts, 3 of 27 are read from rows stored since
the last. 3D 1e7 side by side (seeds 1 and 2, the same clusters): 0.973
and 0.945 times the time, the sorts 7.6 s of 219 (alone on a core), the peak 18 MB higher."""
GAUSS_JUMP = 4.0
"""With step > 0 and jumps, walk-on-spheres only beyond this many step stds."""


@jit
def _neighbour_list():
    """Empty arrays for ``celllist.gather`` to fill: x, y, z (z stays 0 in 2D) and indices."""
    return np.empty(LCAP), np.empty(LCAP), np.zeros(LCAP), np.empty(LCAP, np.int64)


@borrow
def _release(w, dim, size, line, launch_box, launch_r, rng, s0, s1, s2, s3):
    """Put a new walker at w: uniformly on the launch circle (sphere), on the
    launch line (plane) above a substrate, or, with ``launch_box``, on the
    box's faces (its top face above a substrate). Returns the stream state
    (registers: see ``walk.xdir``)."""
    up = dim - 1
    hb = 0.5 * size
    if launch_box:
        if line:
            for a in range(up):
                w[a] = rng.random() * size
            w[up] = size - 1.0
        else:
            face = int(rng.random() * 2 * dim)
            for a in range(dim):
                w[a] = (2.0 * rng.random() - 1.0) * (hb - 1.0)
            w[face >> 1] = (hb - 1.0) if face & 1 else -(hb - 1.0)
    elif line:
        for a in range(up):
            w[a] = rng.random() * size
        w[up] = launch_r
    else:
        s0, s1, s2, s3, u0, u1, u2 = xdir(s0, s1, s2, s3, dim)
        w[0] = launch_r * u0
        w[1] = launch_r * u1
        w[2] = launch_r * u2
    return s0, s1, s2, s3


@borrow
def _walk(dimension, model, launch_r, kill_r, total, pending, w, u, normal, scratch, anchor, lx, ly, lz, li, mx, my, mz,
          mi, pts, nxt, gi, gf, words, start, blocks, cells, dirr, heads, field, pstart, geo, rs, rng):
    """Release walkers until one sticks or the step budget runs out.

    One walker at a time. Two in flight, their steps interleaved so that one's memory
    reads overlap the other's (a timing prototype: the second walker on its own stream,
    released again when the new particle lands within 40 of it, 0.3% of particles at
    2D 1e7), took per walk step, 2D seed 1 side by side at 1e6 and 1e7, 109.2 and 150.3
    ns against 103.4 and 146.9, 122.0 and 160.1 against 127.6 and 151.7; with a
    prefetch of the next step's field or pyramid cell, 103.5 and 131.3 against 93.8
    and 124.6; 3D, 24.7 us a particle at 3e6 against 22.2 (108.0 steps a particle
    against 103.0: 0.9% of walkers released again, 10% at 1e5). Keeping two walkers'
    state costs what their overlapped reads save: the step's own reads are not where
    a large cluster's time grows (``celllist.gather``).

    Parameters
    ----------
    dimension : int
        The model's dimension, a literal: each is compiled apart, its
        branches on ``dim`` folded away: 2D 1e6, six runs side by side on
        the two cores, 0.83 to 1.02 of the time (median 0.955); 3D 3e5, 0.95 to 1.00.
    model : Model
        The model (``kernels.model.Model``).
    launch_r, kill_r : float
        Launch radius (height above a substrate) and kill radius now.
    total, pending : int
        Steps taken in all, and since the last attachment.
    w : float64 (3,)
        Receives the walker's place where it sticks.
    rs : uint64 (4,)
        The xoshiro256+ stream; ``rng`` the numpy Generator.
    The rest: scratch arrays, the neighbour lists and the grid (``grid``),
    ``pstart`` the centre pyramid's level starts (``grid.level_starts``);
    ``geo`` holds r_max, the Chebyshev extent and h_max.

    Returns
    -------
    stuck : bool
        True when a walker stuck at w, False when the budget ran out.
    total, pending : int

    Every array is an argument, borrowed (``_jit.borrow``: no reference
    counting, and nothing allocated here); see the package note.
    """
    literally(dimension)
    dim = np.int64(2) if dimension == 2 else np.int64(3)  # a constant, not a literal (``_jit``)
    size, step, stickiness = model.size, model.step, model.stickiness
    jumps, max_steps, ret, kill = model.jumps, model.max_steps, model.exact_return, model.kill
    line = model.seed_shape == codes.LINE
    launch_box = model.launch_box
    boxed = size > 0 and not line
    ceiling = line and launch_box
    hb = 0.5 * size
    launch_r2 = launch_r * launch_r
    RL = LIST_RADIUS
    if line:
        RL = min(RL, hb)  # a ball of radius <= size/2 holds one image of each particle
    RL2 = RL * RL
    up = dim - 1
    r_max, extent, h_max = geo[0], geo[1], geo[2]
    per, m0, m1, m2, W, fw, flo, ftop = walk_geometry(gi, cells, dim)
    s0, s1, s2, s3 = rs[0], rs[1], rs[2], rs[3]
    code = 0
    r2, ch, ggeo = 0.0, 0.0, 0.0
    while code == 0:
        s0, s1, s2, s3 = _release(w, dim, size, line, launch_box, launch_r, rng, s0, s1, s2, s3)
        list_ok = False
        nl = 0
        far = True  # from the launch circle, a return to it or a ball's exit: the pyramid first (``grid.FAR_CLEAR``)
        while True:
            if max_steps > 0 and total >= max_steps:
                code = 2
                break
            # ---- outer boundaries: exact return, kill sphere, walls
            if line:
                h = w[up]
                if ret and h > launch_r:
                    return_to_plane(rng, dim, w, launch_r, size)
                    total += 1
                    pending += 1
                    list_ok = False
                    continue
                gb = INF
                if kill:
                    gb = kill_r - h
                if ceiling:
                    gb = min(gb, size - h)
                ggeo = h - h_max - 1.0
            else:
                r2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2]
                if ret and r2 > launch_r2 * (1.0 + 1e-12):  # returned walkers sit on launch_r, to rounding
                    total += 1
                    pending += 1
                    list_ok = False
                    far = True
                    if not return_to_sphere(rng, dim, w, launch_r, scratch):
                        break  # escaped (3D): release a new walker
                    continue
                gb = INF
                if kill:
                    gb = kill_r - np.sqrt(r2)
                ch = max(abs(w[0]), abs(w[1]), abs(w[2]))
                if boxed:
                    gb = min(gb, hb - ch)
            if gb < EPS:
                break  # absorbed: release a new walker
            # ---- free distance g: a lower bound, exact near the cluster
            exact = False
            g = 0.0
            if list_ok:
                d0 = w[0] - anchor[0]
                d1 = w[1] - anchor[1]
                d2 = w[2] - anchor[2]
                dout = RL - np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
                dl2 = INF
                for k in range(nl):
                    d0 = w[0] - lx[k]
                    d1 = w[1] - ly[k]
                    d2 = w[2] - lz[k]
                    dl2 = min(dl2, d0 * d0 + d1 * d1 + d2 * d2)
                if dout > 0.0 and dl2 <= dout * dout:
                    g = np.sqrt(dl2) - 1.0
                    exact = True
                else:
                    list_ok = False
            if not exact:
                if not line:  # a square root (6% of the walk at 2D 1e6) only where the list does not decide
                    ggeo = max(np.sqrt(r2) - r_max, ch - extent) - 1.0
                # >>> walk_bound, spelled out: inlined by numba it made the walk 13% slower (a test
                # holds the two texts together, and walk_bound to map_dist)
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
                # <<< walk_bound
                if dm > 0.0:
                    g = max(ggeo, dm - 1.0)
                elif dm < 0.0:
                    g = ggeo
                else:
                    # the neighbour list around w, and the nearest distance
                    anchor[0] = w[0]
                    anchor[1] = w[1]
                    anchor[2] = w[2]
                    list_ok = True
                    nl, dl2 = gather(anchor, RL, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li)
                    g = (np.sqrt(dl2) if dl2 < RL2 else RL) - 1.0
            if line:
                g = min(g, w[up])
            g = min(g, gb)
            far = False
            # ---- move
            if not exact and ball > 0.0 and g == ball - gap - 1.0 and gb >= ball + gap and step == 0.0 and jumps:
                # out of the ball about the pyramid cell's centre, which holds the one about w
                c0 = cell_centre(X0, shift) - m0
                c1 = cell_centre(X1, shift) - m1
                c2 = cell_centre(X2, shift) - m2 if dim == 3 else 0.0
                s0, s1, s2, s3 = ball_exit(s0, s1, s2, s3, dim, w, c0, c1, c2, ball - 1.0)
                far = True
                total += 1
                pending += 1
                continue
            if step == 0.0 and jumps and g >= EPS:
                # >>> jump onto the sphere of radius g, as below for Gaussian steps (a test
                # holds the copies together): one condition for both timed 25% slower at
                # 2D 1e6 once (even at 3e5, on a loaded machine), so the tested shape stays
                s0, s1, s2, s3, u0, u1, u2 = xdir(s0, s1, s2, s3, dim)
                w[0] += g * u0
                w[1] += g * u1
                w[2] += g * u2
                total += 1
                pending += 1
                # <<< jump
                continue
            contact = False
            if step == 0.0 and jumps:
                # inside the shell: a short exact ray cast against the list
                d0 = w[0] - anchor[0]
                d1 = w[1] - anchor[1]
                d2 = w[2] - anchor[2]
                if not list_ok or RL - np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) < 1.0 + RAY + 1e-9:
                    anchor[0] = w[0]
                    anchor[1] = w[1]
                    anchor[2] = w[2]
                    nl = gather(anchor, RL, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li)[0]
                    list_ok = True
                s0, s1, s2, s3, u0, u1, u2 = xdir(s0, s1, s2, s3, dim)
                total += 1
                pending += 1
                best, hit = ray_to(w, u0, u1, u2, RAY, nl, lx, ly, lz, line, dim)
                u[0], u[1], u[2] = u0, u1, u2
                if hit == -1:
                    for a in range(3):
                        w[a] += best * u[a]
                    continue
                settle(w, u, best, hit, dim, lx, ly, lz, li, normal)  # once per contact: a call is cheap here
                contact = True
            elif step == 0.0:
                # single unit steps everywhere (jumps=false)
                s0, s1, s2, s3, u[0], u[1], u[2] = xdir(s0, s1, s2, s3, dim)
                total += 1
                pending += 1
                if g > 1.0:
                    for a in range(3):
                        w[a] += u[a]
                    continue
                contact = cast(w, u, 1.0, dim, size, line, pts, nxt, gi, gf, dirr, heads, mx, my, mz, mi, normal)
            else:
                if jumps and g > GAUSS_JUMP * step:
                    # >>> jump
                    s0, s1, s2, s3, u0, u1, u2 = xdir(s0, s1, s2, s3, dim)
                    w[0] += g * u0
                    w[1] += g * u1
                    w[2] += g * u2
                    total += 1
                    pending += 1
                    # <<< jump
                    continue
                total += 1
                pending += 1
                list_ok = False
                if gauss_move(w, step, dim, size, line, rng, pts, nxt, gi, gf, dirr, heads, words, start,
                              blocks, cells, field, mx, my, mz, mi, scratch, u, normal) and sticks(stickiness, rng):
                    code = 1
                    break
                continue
            if not contact:
                continue
            rs[0], rs[1], rs[2], rs[3] = s0, s1, s2, s3
            stuck, moves = rebound(w, u, normal, dim, size, line, stickiness, rng, rs, pts, nxt, gi, gf, dirr, heads,
                                   mx, my, mz, mi)
            s0, s1, s2, s3 = rs[0], rs[1], rs[2], rs[3]
            total += moves
            pending += moves
            list_ok = False
            if stuck:
                code = 1
                break
    rs[0], rs[1], rs[2], rs[3] = s0, s1, s2, s3
    return code == 1, total, pending


IN_GRID = -1
"""``_attach``: the particle is in the grid."""
HEADS_FULL = -2
"""``_attach``: the particle waits for the cell list's heads to grow (``_index_late``)."""


@borrow
def _attach(w, parent, count, pending, pts, order, steps, parents, nxt, geo, dim, line, size, gi, gf, words, start,
            blocks, cells, dirr, heads, field):
    """Add the walker at w to the cluster, its parent the particle it touched
    (``contact.settle`` records its row of ``pts``; ``order`` holds each row's
    attachment number where the rows are stored by cell, ``celllist.sort_cells``).
    Returns the new count and ``IN_GRID``, ``HEADS_FULL``, or, when the cluster outgrew the grid, its count of
    cell-list tiles (then the particle is not yet in the grid: the caller
    drops it and builds a larger one). It takes the grid's arrays one by one
    and returns none: a tuple of them cost reference counting at each particle."""
    up = dim - 1
    if line:
        for a in range(up):
            w[a] = w[a] - size * np.floor(w[a] / size)
            if w[a] >= size:
                w[a] -= size
    r2 = 0.0
    ch = 0.0
    for a in range(dim):
        pts[count, a] = w[a]
        r2 += w[a] * w[a]
        ch = max(ch, abs(w[a]))
    steps[count] = diffusion_time(pending)
    row = int(parent)
    parents[count] = order[row] if row >= 0 and len(order) > 0 else row  # a new row's number is its own
    geo[0] = max(geo[0], np.sqrt(r2))
    geo[1] = max(geo[1], ch)
    geo[2] = max(geo[2], w[up])
    count += 1
    need = geo[2] if line else geo[1]
    if need + 8.0 > gi[COVERED]:
        return count, gi[TILES_USED]
    if not insert(count - 1, pts, nxt, dim, gi, gf, dirr, heads):
        return count, np.int64(HEADS_FULL)
    mark(count - 1, pts, dim, size, gi, words, start, blocks, cells, field)
    return count, np.int64(IN_GRID)


@jit
def _index_late(i, pts, nxt, dim, size, gi, gf, words, start, blocks, cells, dirr, heads, field):
    """Put particle i, which found the heads full, in the grid; returns the larger heads."""
    heads = more_heads(heads)
    insert(i, pts, nxt, dim, gi, gf, dirr, heads)
    mark(i, pts, dim, size, gi, words, start, blocks, cells, field)
    return heads


@jit
def _grow(dimension, lockstep, n, model, marks, rng, times):
    """Grow an off-lattice cluster of up to ``n`` particles.

    Parameters
    ----------
    dimension : int
        The model's dimension, a literal that ``_walk`` is compiled for.
    lockstep : None or True
        ``model.lockstep_flag(model.walkers)``: the lockstep walk is compiled in only where it runs.
    n : int
    model : Model
        The model (``kernels.model.Model``).
    marks : int64 (K,)
        Particle counts at which to read the clock, ascending.
    rng : numpy.random.Generator
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
        count, status = _lockstep(n, model, marks, rng, rs, t0, times, passed, pts, order, steps, parents, nxt, count,
                                  geo, (gi, gf, words, start, blocks, cells, dirr, heads, field))
        return pts, steps, parents, count, status
    w = np.zeros(3)
    u = np.zeros(3)
    normal = np.zeros(4)  # and the particle touched (``contact.settle``)
    scratch = np.zeros(3)
    anchor = np.zeros(3)
    lx, ly, lz, li = _neighbour_list()
    mx, my, mz, mi = _neighbour_list()
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
        stuck, total, pending = _walk(dimension, model, launch_r, model.kill_factor * launch_r, total, pending, w, u,
                                      normal, scratch, anchor, lx, ly, lz, li, mx, my, mz, mi, pts, nxt, gi, gf, words,
                                      start, blocks, cells, dirr, heads, field, pstart, geo, rs, rng)
        if not stuck:
            status = codes.STEP_LIMIT
            break
        count, tiles = _attach(w, normal[3], count, pending, pts, order, steps, parents, nxt, geo, dim, line, size, gi,
                               gf, words, start, blocks, cells, dirr, heads, field)
        if tiles == HEADS_FULL:
            heads = _index_late(count - 1, pts, nxt, dim, size, gi, gf, words, start, blocks, cells, dirr, heads, field)
        elif tiles >= 0:  # dropped now (every name but the field's), the larger one built at the next pass's top
            gi, gf, words, start, blocks, cells, dirr, heads, field = no_grid()
            regrid = tiles
        pending = 0
        passed = checkpoint(marks, times, passed, count, t0)
    if len(order) > 0:
        attachment_order(pts, order, count)
    return pts, steps, parents, count, status


@jit
def _lockstep(n, model, marks, rng, rs, t0, times, passed, pts, order, steps, parents, nxt, count, geo, grid):
    """Grow with ``model.walkers`` walkers at once: a finite concentration.

    They start uniformly in the box (not on a particle) and take single
    steps in turn (unit ray casts, or Gaussian steps); none is relaunched, a
    wall removes it, and one that a new particle covers merges into it.
    Takes over from ``_grow`` once the seed is placed (its arguments are
    ``_grow``'s state) and returns (count, status).
    """
    dim, size, step, stickiness = model.dim, model.size, model.step, model.stickiness
    walkers, max_steps = model.walkers, model.max_steps
    line = model.seed_shape == codes.LINE
    up = dim - 1
    hb = 0.5 * size
    gi, gf, words, start, blocks, cells, dirr, heads, field = grid
    grid = no_grid()  # held by the names above alone, so that a rebuild frees the old arrays
    pos = np.zeros((walkers, 3))
    alive = np.ones(walkers, np.bool_)
    w = np.zeros(3)
    u = np.zeros(3)
    e = np.zeros(3)
    normal = np.zeros(4)  # and the particle touched (``contact.settle``)
    mx, my, mz, mi = _neighbour_list()
    for k in range(walkers):
        while True:
            for a in range(dim):
                if line:
                    pos[k, a] = rng.random() * size
                else:
                    pos[k, a] = (2.0 * rng.random() - 1.0) * hb
            if gather(pos[k], 1.0, dim, size, pts, nxt, gi, gf, dirr, heads, mx, my, mz, mi)[0] == 0:
                break
    live = walkers
    total = np.int64(0)
    pending = np.int64(0)
    status = codes.OK
    while count < n and status == codes.OK:
        if live == 0:
            status = codes.EXHAUSTED
            break
        for k in range(walkers):
            if not alive[k]:
                continue
            if max_steps > 0 and total >= max_steps:
                status = codes.STEP_LIMIT
                break
            for a in range(3):
                w[a] = pos[k, a]
            dm = map_dist(w, dim, size, gi, words, start, blocks, cells, field)
            if dm == 0.0 and gather(w, 1.0 - 1e-12, dim, size, pts, nxt, gi, gf, dirr, heads, mx, my, mz, mi)[0] > 0:
                alive[k] = False  # a particle attached on top of it: merged
                live -= 1
                continue
            total += 1
            pending += 1
            if step == 0.0:
                unit_vector(rs, dim, u)
                if dm > 2.0:
                    for a in range(3):
                        w[a] += u[a]
                    contact = False
                else:
                    contact = cast(w, u, 1.0, dim, size, line, pts, nxt, gi, gf, dirr, heads, mx, my, mz, mi, normal)
            else:
                contact = gauss_move(w, step, dim, size, line, rng, pts, nxt, gi, gf, dirr, heads, words, start,
                                     blocks, cells, field, mx, my, mz, mi, e, u, normal)
            stuck = False
            if contact:
                if step > 0.0:
                    stuck = sticks(stickiness, rng)
                else:
                    stuck, moves = rebound(w, u, normal, dim, size, line, stickiness, rng, rs, pts, nxt, gi, gf, dirr,
                                           heads, mx, my, mz, mi)
                    total += moves
                    pending += moves
            if stuck:
                count, tiles = _attach(w, normal[3], count, pending, pts, order, steps, parents, nxt, geo, dim, line,
                                       size, gi, gf, words, start, blocks, cells, dirr, heads, field)
                if tiles == HEADS_FULL:
                    heads = _index_late(count - 1, pts, nxt, dim, size, gi, gf, words, start, blocks, cells, dirr,
                                        heads, field)
                elif tiles >= 0:
                    old_gi, old_field = gi, field
                    gi, gf, words, start, blocks, cells, dirr, heads, field = no_grid()
                    gi, gf, words, start, blocks, cells, dirr, heads, field = regrow_grid(
                        dim, line, size, geo[2] if line else geo[1], pts, count, nxt, tiles, old_gi, old_field)
                pending = 0
                alive[k] = False
                live -= 1
                passed = checkpoint(marks, times, passed, count, t0)
                if count >= n:
                    break
                continue
            if line:
                for a in range(up):
                    w[a] = w[a] - size * np.floor(w[a] / size)
                gone = w[up] >= size
            else:
                gone = max(abs(w[0]), abs(w[1]), abs(w[2])) >= hb
            if gone:
                alive[k] = False
                live -= 1
            for a in range(3):
                pos[k, a] = w[a]
    return count, status


@jit
def _grow_each(dimension, lockstep, n, model, marks, rngs, times):
    """``_grow`` with each generator of the list ``rngs`` in turn (row i of ``times``); its results and seconds.

    ``dimension`` (the model's) is a literal: each is compiled apart, and only when used."""
    literally(dimension)
    out = []
    for i in range(len(rngs)):
        start = clock()
        pts, steps, parents, count, status = _grow(dimension, lockstep, n, model, marks, rngs[i], times[i])
        out.append((pts, steps, parents, count, status, times[i], clock() - start))
    return out


def grow_offlattice(n, p, marks, rngs, times=None):
    """Grow off-lattice clusters, one with each generator, in one compiled call; see ``dlasweep.grow``.

    Takes and returns what ``lattice.grow_lattice`` does, but ``points`` are
    the float64 centres of unit-diameter disks (spheres), (n_grown, dim), and
    a parent is the particle touched at contact (``contact.settle``).
    """
    times = np.full((len(rngs), len(marks)), np.nan) if times is None else times
    model = model_from(p)
    grown_each = call_literal(_grow_each, model.dim, lockstep_flag(model.walkers), int(n), model,
                              np.asarray(marks, np.int64), list(rngs), times)
    return [grown(*result) for result in grown_each]


def compiled(dim, walkers=1) -> bool:
    """Whether numba's on-disk cache holds this growth kernel for ``dim`` and ``walkers`` (most of its compile
    time)."""
    return cached(_grow_each, dim, lockstep_flag(walkers))
