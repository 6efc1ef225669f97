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
def _mark_images(words, dim, start, blocks, cells, width, off, q, period):
    """Mark a particle at site q, with its periodic images for substrates."""
    reach = 1 if period > 0 else 0
    zreach = reach if dim == 3 else 0
    for a in range(-reach, reach + 1):
        for b in range(-zreach, zreach + 1):
            i = q[0] + a * period + off
            j = q[1] + (b * period if dim == 3 else 0) + off
            k = q[2] + off
            if 0 <= i < width and 0 <= j < width and 0 <= k < width:
                maps.mark(words, dim, start, blocks, cells, i, j, k)


@jit
def _rebuild(points, count, dim, width, off, period):
    words, start, blocks, cells = maps.allocate(dim, width)
    q = np.zeros(3, np.int64)
    for p in range(count):
        for a in range(dim):
            q[a] = points[p, a]
        _mark_images(words, dim, start, blocks, cells, width, off, q, period)
    return words, start, blocks, cells


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
    words, start, blocks, cells = _rebuild(points, count, dim, width, off, period)

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

    alive = np.zeros(max(walkers, 1), np.bool_)
    wpos = np.zeros((max(walkers, 1), 3), np.int64)
    if walkers > 1:
        box_hi = hi if not line else size - 1
        box_lo = lo if not line else 0
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
            # a walker left on a site another one just filled must move off it
            stepped = not _occupied(words, dim, start, blocks, width, off, q[0], q[1], q[2])
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
            # beyond the kill radius, or above/outside the launch boundary
            if kill_factor > 0.0 and r > kill_factor * launch_r:
                need_launch = True
                continue
            # any threshold beyond the launch circle is exact; a unit gap avoids re-returning
            # a walker that rounding put a hair outside it
            if kill_factor == 0.0 and not boxed and not launch_box and r > launch_r + 1.0:
                total += 1
                pending += 1
                if line:
                    return_to_plane(rng, dim, pos, launch_r, size)
                elif not return_to_sphere(rng, dim, pos, launch_r, scratch):
                    need_launch = True
                continue
            for a in range(3):
                q[a] = _site(pos[a])
            if boxed or (line and launch_box):
                outside = False
                for a in range(dim):
                    if line and a != up:
                        continue
                    if q[a] < (0 if line else lo) or q[a] > hi + (size // 2 if line else 0):
                        outside = True
                if outside:
                    need_launch = True
                    continue
            # lower bound on the distance to the nearest particle
            free = r - (h_max if line else r_max)
            i, j, k = q[0] + off, q[1] + off, q[2] + off
            level = 0
            if 0 <= i < width and 0 <= j < width and 0 <= k < width:
                level = maps.clear_level(words, dim, start, blocks, cells, i, j, k)
                # unmarked periodic images lie at least one period away
                bound = float(1 << level) if level > 0 else 0.0
                free = max(free, min(bound, float(period)) if line else bound)
            if line:
                free = min(free, pos[up] + 1.0)
            reach = free - JUMP_MARGIN
            if kill_factor > 0.0:
                reach = min(reach, kill_factor * launch_r - r)
            if boxed:
                for a in range(dim):
                    reach = min(reach, pos[a] - lo, hi - pos[a])
            elif line and launch_box:
                reach = min(reach, size - 1 - pos[up])
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
            stepped = level == 0 or (line and q[up] == 0)
        # single-site dynamics at q: stick with probability s on contact, else step
        if stepped and _in_contact(words, dim, start, blocks, width, off, q, moves, period):
            if stickiness >= 1.0 or rng.random() < stickiness:
                for a in range(dim):
                    points[count, a] = q[a]
                steps[count] = pending
                pending = 0
                count += 1
                rq = np.sqrt(float(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]))
                r_max = max(r_max, rq)
                h_max = max(h_max, float(q[up]))
                extent = 0
                for a in range(dim):
                    extent = max(extent, abs(q[a]))
                if line:
                    grow_grid = q[up] + off + 4 >= width
                else:
                    grow_grid = extent + 4 >= off
                if grow_grid:
                    width *= 2
                    if not line:
                        off = width // 2
                    words, start, blocks, cells = _rebuild(points, count, dim, width, off, period)
                else:
                    _mark_images(words, dim, start, blocks, cells, width, off, q, period)
                while mi < len(marks) and marks[mi] <= count:
                    times[mi] = clock() - t0
                    mi += 1
                if walkers > 1:
                    alive[w] = False
                    live -= 1
                else:
                    need_launch = True
                if launch_box and walkers == 1:
                    for a in range(dim):
                        if line:
                            if a == up and q[a] >= size - 2:
                                status = BOUNDARY
                        elif q[a] <= lo + 1 or q[a] >= hi - 1:
                            status = BOUNDARY
                    if status != OK:
                        break
                continue
        m = below(rng, moves.shape[0])
        n0, n1, n2 = q[0] + moves[m, 0], q[1] + moves[m, 1], q[2] + moves[m, 2]
        if line:
            n0 = n0 % period
            if dim == 3:
                n1 = n1 % period
        total += 1
        pending += 1
        if (line and (n0, n1, n2)[up] < 0) or _occupied(words, dim, start, blocks, width, off, n0, n1, n2):
            n0, n1, n2 = q[0], q[1], q[2]
        if walkers > 1:
            wpos[w, 0], wpos[w, 1], wpos[w, 2] = n0, n1, n2
            lo_w = 0 if line else lo
            for a in range(dim):
                if line and a != up:
                    continue
                hi_w = size - 1 if line else hi
                if (n0, n1, n2)[a] < lo_w or (n0, n1, n2)[a] > hi_w:
                    alive[w] = False
                    live -= 1
                    break
        else:
            pos[0], pos[1], pos[2] = n0, n1, n2
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
    points = np.zeros((n, 3), np.int64)
    steps = np.zeros(n, np.int64)
    times = np.full(len(marks), np.nan)
    count, status = _grow(
        n, dim, _moves(dim, p["neighbours"] != 2 * dim), p["stickiness"],
        ("point", "block", "line").index(p["seed_shape"]), p["size"], p["launch"] == "box",
        p["launch_factor"], p["launch_margin"], p["kill_factor"], p["jumps"], p["walkers"],
        p["max_steps"], marks, rng, points, steps, times,
    )
    return np.ascontiguousarray(points[:count, :dim]), steps[:count].copy(), int(status), times
