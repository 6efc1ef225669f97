"""Square and simple-cubic lattice DLA.

A walker far from the cluster moves by walk-on-circles/spheres jumps whose
radius is a lower bound on its free distance (hierarchical maps and the
cluster's bounding circle); within a few sites of the cluster it takes single
lattice steps, so every contact is a lattice contact. Outside the launch
circle it returns exactly (Poisson kernel) instead of wandering off. The
far-field jump treats the lattice walk as Brownian motion at scales of four
sites and more, the usual approximation of fast lattice DLA codes.
"""

import numpy as np

from .._jit import clock, jit
from . import maps
from .walk import below, direction, return_to_plane, return_to_sphere

POINT, BLOCK, LINE = 0, 1, 2
OK, BOUNDARY, STEP_LIMIT, EXHAUSTED = 0, 1, 2, 3
JUMP_MARGIN = 2.0  # sites kept between a jump's circle and the nearest particle
FIELD_CAP = (0, 0, 16, 6)  # by dimension: reach of the coarse distance field, in cells of 4 sites


def _moves(dim, moore):
    """Unit moves (and contacts): nearest neighbours or the Moore set."""
    grid = np.stack(np.meshgrid(*([np.arange(-1, 2)] * dim), indexing="ij"), -1).reshape(-1, dim)
    norm = np.abs(grid).sum(1)
    keep = norm > 0 if moore else norm == 1
    out = np.zeros((int(keep.sum()), 3), np.int64)
    out[:, :dim] = grid[keep]
    return out


@jit
def _site(x):
    return np.int64(np.floor(x + 0.5))


@jit
def _mark_images(words, dim, start, blocks, cells, field, width, off, q, period):
    """Mark a particle at site q, with its periodic images for substrates."""
    reach = 1 if period > 0 else 0
    zreach = reach if dim == 3 else 0
    cap = FIELD_CAP[dim]
    for a in range(-reach, reach + 1):
        for b in range(-zreach, zreach + 1):
            i = q[0] + a * period + off
            j = q[1] + (b * period if dim == 3 else 0) + off
            k = q[2] + off
            if 0 <= i < width and 0 <= j < width and 0 <= k < width:
                maps.mark(words, dim, start, blocks, cells, i, j, k)
                maps.field_mark(field, dim, width, i, j, k, cap)


@jit
def _rebuild(points, count, dim, width, off, period):
    words, start, blocks, cells = maps.allocate(dim, width)
    field = maps.field_allocate(dim, width, FIELD_CAP[dim])
    q = np.zeros(3, np.int64)
    for p in range(count):
        for a in range(dim):
            q[a] = points[p, a]
        _mark_images(words, dim, start, blocks, cells, field, width, off, q, period)
    return words, start, blocks, cells, field


@jit
def _occupied(words, dim, start, blocks, width, off, q0, q1, q2):
    i, j, k = q0 + off, q1 + off, q2 + off
    if i < 0 or j < 0 or k < 0 or i >= width or j >= width or k >= width:
        return False
    return maps.test(words, dim, start, blocks, 0, i, j, k)


@jit
def _in_contact(words, dim, start, blocks, width, off, q, moves, period):
    """Whether site q touches a particle (or the substrate) under ``moves``."""
    up = dim - 1
    for m in range(moves.shape[0]):
        n0, n1, n2 = q[0] + moves[m, 0], q[1] + moves[m, 1], q[2] + moves[m, 2]
        if period > 0:
            if (n0, n1, n2)[up] < 0:
                return True
            n0 = n0 % period
            if dim == 3:
                n1 = n1 % period
        if _occupied(words, dim, start, blocks, width, off, n0, n1, n2):
            return True
    return False


@jit
def _outside(q, dim, line, lo, hi):
    """Whether site q has left the box (for substrates: through the top)."""
    if line:
        return q[dim - 1] > hi
    for a in range(dim):
        if q[a] < lo or q[a] > hi:
            return True
    return False


@jit
def _near_walk(
    words, dim, start, blocks, width, off, q, moves, period, stickiness, rng,
    jumps, boxed, lo, hi, radius, budget,
):
    """Single lattice steps from site q until the walker sticks or may leave.

    At each site the walker first sticks with probability ``stickiness`` if it
    touches the cluster, else it steps to a random neighbour (staying put when
    that is occupied). It stops, without sticking, after ``budget`` steps (0:
    no limit), on leaving the box, beyond ``radius`` (0: none) or, when
    ``jumps``, where a jump becomes possible again (level-2 map clear).

    Returns
    -------
    stuck : bool
    taken : int, the steps taken
    """
    up = dim - 1
    line = period > 0
    taken = 0
    nm = moves.shape[0]
    while True:
        i, j, k = q[0] + off, q[1] + off, q[2] + off
        ingrid = 0 <= i < width and 0 <= j < width and 0 <= k < width
        # the level-1 map is clear unless a particle is within two sites
        near = ingrid and maps.test(words, dim, start, blocks, 1, i >> 1, j >> 1, k >> 1)
        if near or (line and q[up] <= 1):
            if _in_contact(words, dim, start, blocks, width, off, q, moves, period):
                if stickiness >= 1.0 or rng.random() < stickiness:
                    return True, taken
        m = below(rng, nm)
        n0, n1, n2 = q[0] + moves[m, 0], q[1] + moves[m, 1], q[2] + moves[m, 2]
        if line:
            n0 = n0 % period
            if dim == 3:
                n1 = n1 % period
        taken += 1
        blocked = near and _occupied(words, dim, start, blocks, width, off, n0, n1, n2)
        if not blocked and not (line and (n0, n1, n2)[up] < 0):
            q[0], q[1], q[2] = n0, n1, n2
        if taken == budget:
            return False, taken
        if boxed and _outside(q, dim, line, lo, hi):
            return False, taken
        if radius > 0.0:
            r2 = float(q[up] * q[up]) if line else float(q[0] * q[0] + q[1] * q[1] + q[2] * q[2])
            if r2 > radius * radius:
                return False, taken
        if jumps:
            i, j, k = q[0] + off, q[1] + off, q[2] + off
            if not (0 <= i < width and 0 <= j < width and 0 <= k < width):
                return False, taken
            if not maps.test(words, dim, start, blocks, 2, i >> 2, j >> 2, k >> 2):
                return False, taken


@jit
def _grow(
    n, dim, moves, stickiness, seed_shape, size, launch_box, launch_factor, launch_margin,
    kill_factor, jumps, walkers, max_steps, marks, rng, points, steps, times,
):
    t0 = clock()
    up = dim - 1
    line = seed_shape == LINE
    period = size if line else 0
    boxed = size > 0 and not line
    lo = -(size // 2)
    hi = size - 1 + lo

    width = 64 if not line else 4 * size
    off = width // 2 if not line else size
    count = 0
    r_max = 0.0
    h_max = -1.0
    if seed_shape == POINT:
        count = min(n, 1)
    elif seed_shape == BLOCK:
        count = min(n, 1 << dim)
        for p in range(count):
            for a in range(dim):
                points[p, a] = (p >> a) & 1
    for p in range(count):
        r_max = max(r_max, np.sqrt(np.sum(points[p].astype(np.float64) ** 2)))
    words, start, blocks, cells, field = _rebuild(points, count, dim, width, off, period)

    mi = 0
    while mi < len(marks) and marks[mi] <= count:
        times[mi] = clock() - t0
        mi += 1

    pos = np.zeros(3)
    q = np.zeros(3, np.int64)
    scratch = np.zeros(3)
    total = np.int64(0)
    pending = np.int64(0)  # steps since the previous attachment
    status = OK

    # the box: sites lo..hi on every axis; a substrate's box is 0..size-1 high
    box_lo = 0 if line else lo
    box_hi = size - 1 if line else hi
    alive = np.zeros(max(walkers, 1), np.bool_)
    wpos = np.zeros((max(walkers, 1), 3), np.int64)
    if walkers > 1:
        placed = 0
        while placed < walkers:
            for a in range(dim):
                wpos[placed, a] = box_lo + below(rng, box_hi - box_lo + 1)
            if not _occupied(words, dim, start, blocks, width, off, wpos[placed, 0], wpos[placed, 1], wpos[placed, 2]):
                alive[placed] = True
                placed += 1
    live = walkers
    turn = 0
    w = 0
    need_launch = True
    stuck = False
    level = 1

    while count < n:
        if max_steps > 0 and total >= max_steps:
            status = STEP_LIMIT
            break
        launch_r = launch_factor * (max(h_max, 0.0) if line else r_max) + launch_margin
        if boxed and not launch_box and walkers == 1 and launch_r > -lo - 1:
            status = BOUNDARY
            break

        if walkers > 1:
            # lockstep: walkers take single steps in turn, none relaunched
            if live == 0:
                status = EXHAUSTED
                break
            w = turn
            turn = (turn + 1) % walkers
            if not alive[w]:
                continue
            for a in range(3):
                q[a] = wpos[w, a]
            if _occupied(words, dim, start, blocks, width, off, q[0], q[1], q[2]):
                # another walker just filled this site: the two coalesce
                alive[w] = False
                live -= 1
                continue
            stuck, taken = _near_walk(
                words, dim, start, blocks, width, off, q, moves, period, stickiness, rng,
                False, True, box_lo, box_hi, 0.0, 1,
            )
            for a in range(3):
                wpos[w, a] = q[a]
            if not stuck and _outside(q, dim, line, box_lo, box_hi):
                alive[w] = False
                live -= 1
        else:
            if need_launch:
                need_launch = False
                if launch_box:
                    ax = below(rng, dim)
                    for a in range(dim):
                        pos[a] = (0 if line else lo) + below(rng, size)
                    if line:
                        pos[up] = size - 1
                    else:
                        pos[ax] = lo if rng.random() < 0.5 else hi
                elif line:
                    for a in range(up):
                        pos[a] = rng.random() * size
                    pos[up] = launch_r
                else:
                    direction(rng, dim, scratch)
                    for a in range(dim):
                        pos[a] = launch_r * scratch[a]
            r = pos[up] if line else np.sqrt(pos[0] ** 2 + pos[1] ** 2 + pos[2] ** 2)
            kill_r = kill_factor * launch_r
            # any radius beyond the launch circle is exact for the return; a
            # unit gap spares a walker that rounding put a hair outside it
            return_r = launch_r + 1.0 if kill_factor == 0.0 and not boxed and not launch_box else 0.0
            if kill_factor > 0.0 and r > kill_r:
                need_launch = True
                continue
            if return_r > 0.0 and r > return_r:
                total += 1
                pending += 1
                if line:
                    return_to_plane(rng, dim, pos, launch_r, size)
                elif not return_to_sphere(rng, dim, pos, launch_r, scratch):
                    need_launch = True
                continue
            for a in range(3):
                q[a] = _site(pos[a])
            if (boxed or launch_box) and _outside(q, dim, line, box_lo, box_hi):
                need_launch = True
                continue
            # lower bound on the distance to the nearest particle
            free = r - (h_max if line else r_max)
            i, j, k = q[0] + off, q[1] + off, q[2] + off
            if 0 <= i < width and 0 <= j < width and 0 <= k < width:
                level, bound = maps.free_bound(words, dim, start, blocks, cells, i, j, k, level)
                # the site rounds the walker's position by at most half a site per axis
                bound = max(bound, maps.field_bound(field, dim, width, i, j, k) - 0.5 * np.sqrt(dim))
                # unmarked periodic images lie at least one period away
                free = max(free, min(bound, float(period)) if line else bound)
            if line:
                free = min(free, pos[up] + 1.0)
            reach = free - JUMP_MARGIN
            if kill_factor > 0.0:
                reach = min(reach, kill_r - r)
            if boxed:
                for a in range(dim):
                    reach = min(reach, pos[a] - lo, hi - pos[a])
            elif line and launch_box:
                reach = min(reach, box_hi - pos[up])
            if jumps and reach >= 2.0:
                direction(rng, dim, scratch)
                for a in range(dim):
                    pos[a] += reach * scratch[a]
                if line:
                    for a in range(up):
                        pos[a] = pos[a] % period
                total += 1
                pending += 1
                continue
            stuck, taken = _near_walk(
                words, dim, start, blocks, width, off, q, moves, period, stickiness, rng,
                jumps, boxed or launch_box, box_lo, box_hi, kill_r if kill_factor > 0.0 else return_r,
                max_steps - total if max_steps > 0 else 0,
            )
            total += taken
            pending += taken
            for a in range(3):
                pos[a] = q[a]
        if stuck:
            for a in range(dim):
                points[count, a] = q[a]
            steps[count] = pending
            pending = 0
            count += 1
            r_max = max(r_max, np.sqrt(float(q[0] * q[0] + q[1] * q[1] + q[2] * q[2])))
            h_max = max(h_max, float(q[up]))
            extent = 0
            for a in range(dim):
                extent = max(extent, abs(q[a]))
            if (q[up] + off + 4 >= width) if line else (extent + 4 >= off):
                width *= 2
                if not line:
                    off = width // 2
                words, start, blocks, cells, field = _rebuild(points, count, dim, width, off, period)
            else:
                _mark_images(words, dim, start, blocks, cells, field, width, off, q, period)
            while mi < len(marks) and marks[mi] <= count:
                times[mi] = clock() - t0
                mi += 1
            if walkers > 1:
                alive[w] = False
                live -= 1
            else:
                need_launch = True
            # with box launch, growth ends where the cluster meets the box
            if launch_box and walkers == 1 and _outside(q, dim, line, box_lo + 2, box_hi - 2):
                status = BOUNDARY
                break
    return count, status


def grow_lattice(n, p, marks, rng):
    """Grow a lattice cluster; see ``dlasweep.grow`` for the meaning.

    Returns
    -------
    points : int64 (n_grown, dim)
    steps : int64 (n_grown,)
    status : int code into ``dlasweep.params.STATUSES``
    times : float64 seconds at each of ``marks`` (NaN when not reached)
    """
    dim = p["dim"]
    points = np.zeros((n, dim), np.int64)
    steps = np.zeros(n, np.int64)
    times = np.full(len(marks), np.nan)
    count, status = _grow(
        n, dim, _moves(dim, p["neighbours"] != 2 * dim), p["stickiness"],
        ("point", "block", "line").index(p["seed_shape"]), p["size"], p["launch"] == "box",
        p["launch_factor"], p["launch_margin"], p["kill_factor"], p["jumps"], p["walkers"],
        p["max_steps"], marks, rng, points, steps, times,
    )
    if count < n:  # don't keep the unused tail alive
        points, steps = points[:count].copy(), steps[:count].copy()
    return points, steps, int(status), times
