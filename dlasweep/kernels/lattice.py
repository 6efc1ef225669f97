"""Square and simple-cubic lattice DLA.

Near the cluster the walk is an exact lattice random walk. A walker whose
nearest particle is at Chebyshev distance ``d >= 3`` jumps to where the
lattice walk first leaves the square (cube) of half-width ``d - 1`` around it:
one draw picks a symmetry class of exit sites (``exit_tables``), a second a
uniform symmetry of the square (cube). No site inside touches the cluster, so
this is exact, and every contact is still a lattice contact. Within two sites
it takes single steps. ``d`` comes from the bit-packed occupancy words near the
walker, a coarse Chebyshev distance field and the hierarchical maps (``maps``).
Far from the cluster (beyond the distances the tables cover) the walker moves
by walk-on-circles/spheres jumps, which treat the lattice walk as Brownian at
scales of ``CIRCLE_MIN`` sites and more; outside the launch circle it returns
exactly (Poisson kernel) instead of wandering off.
"""

from functools import lru_cache

import numpy as np

from .._jit import clock, jit
from . import maps
from .stored import kept_on_disk
from .walk import below, direction, return_to_plane, return_to_sphere, seed_stream, uniform, xdir, xo

POINT, BLOCK, LINE = 0, 1, 2
OK, BOUNDARY, STEP_LIMIT, EXHAUSTED = 0, 1, 2, 3
JUMP_MARGIN = 2.0  # sites kept between a circle jump and the nearest particle
CIRCLE_MIN = 16.0  # smallest circle jump: below it the exact square jumps do the work
FIELD_CAP = (0, 0, 16, 6)  # by dimension: reach of the coarse distance field, in cells of 4 sites
TABLE_MAX = (0, 0, 64, 24)  # by dimension: largest square (cube) half-width with an exit table
GROWTH = 1.25  # the grid's side grows by this factor when the cluster outgrows it


@lru_cache(maxsize=None)
def _moves(dim, moore):
    """Unit moves (and contacts): nearest neighbours or the Moore set (built once: a 1e3 cluster grows in 2 ms)."""
    grid = np.stack(np.meshgrid(*([np.arange(-1, 2)] * dim), indexing="ij"), -1).reshape(-1, dim)
    norm = np.abs(grid).sum(1)
    keep = norm > 0 if moore else norm == 1
    out = np.zeros((int(keep.sum()), 3), np.int64)
    out[:, :dim] = grid[keep]
    return out


def exit_law(dim, moore, r):
    """Where the lattice walk from the centre first leaves the square (cube) of half-width r.

    The Green's function of the walk killed on the boundary is diagonal in the
    sine basis (the walk's generator is a sum, NN, or a product, Moore, of 1D
    shift operators), so it is exact up to rounding for every r; the exit
    probability of a boundary site is the Green's function summed over the
    interior sites one move away, over the number of moves.

    Returns
    -------
    offsets : int (K, dim), the boundary sites reachable in one move
    probs : float (K,), their exit probabilities (summing to 1)
    """
    n = 2 * r - 1
    m = np.arange(1, n + 1)
    theta = np.pi * m / (n + 1)
    basis = np.sqrt(2.0 / (n + 1)) * np.sin(np.outer(m, theta))  # [site, mode]
    cos = np.meshgrid(*([np.cos(theta)] * dim), indexing="ij")
    if moore:
        eig = (np.prod([1.0 + 2.0 * c for c in cos], axis=0) - 1.0) / (3**dim - 1)
    else:
        eig = sum(cos) / dim
    green = 1.0 / (1.0 - eig)
    for a in range(dim):  # times the centre's coordinates in the basis
        green = green * basis[r - 1].reshape([-1 if b == a else 1 for b in range(dim)])
    for a in range(dim):  # back to sites
        green = np.moveaxis(np.tensordot(basis, green, axes=([1], [a])), 0, a)
    padded = np.zeros((2 * r + 1,) * dim)
    padded[(slice(1, -1),) * dim] = green  # the boundary holds zero
    hits = np.zeros_like(padded)
    for v in _moves(dim, moore)[:, :dim]:
        hits += np.roll(padded, tuple(v), axis=tuple(range(dim)))
    sites = np.indices(padded.shape).reshape(dim, -1).T - r
    probs = hits.reshape(-1) / len(_moves(dim, moore))
    keep = (np.abs(sites).max(1) == r) & (probs > 0.0)  # NN: corners are never hit first
    return sites[keep], probs[keep]


@jit
def _alias(probs):
    """Walker's alias table (Vose) for O(1) sampling from ``probs``."""
    k = len(probs)
    scaled = probs * (k / probs.sum())
    cut = np.ones(k)
    alias = np.arange(k).astype(np.int32)
    small = np.zeros(k, np.int64)
    large = np.zeros(k, np.int64)
    ns = nl = 0
    for a in range(k):
        if scaled[a] < 1.0:
            small[ns] = a
            ns += 1
        else:
            large[nl] = a
            nl += 1
    while ns > 0 and nl > 0:
        ns -= 1
        s = small[ns]
        g = large[nl - 1]
        cut[s] = scaled[s]
        alias[s] = g
        scaled[g] -= 1.0 - scaled[s]
        if scaled[g] < 1.0:
            nl -= 1
            small[ns] = g
            ns += 1
    return cut, alias


def symmetry_classes(sites, probs):
    """Pool an exit law by orbits of the square's (cube's) symmetry group.

    The law is invariant under axis permutations and reflections, so it is
    the law of a class (its orbit's total) followed by a uniform symmetry
    applied to the class's representative, the sorted absolute coordinates.

    Returns
    -------
    reps : int (C, dim), representatives, sorted
    probs : float (C,), the classes' probabilities
    """
    keys = np.sort(np.abs(sites), axis=1)
    reps, inverse = np.unique(keys, axis=0, return_inverse=True)
    return reps, np.bincount(inverse.reshape(-1), weights=probs, minlength=len(reps))


@kept_on_disk
def exit_tables(dim, moore):
    """Alias tables of ``exit_law`` by symmetry class (``symmetry_classes``) for
    half-widths 0..TABLE_MAX[dim] (0 and 1 empty).

    One class per orbit keeps the tables 8 (2D) or 48 (3D) times smaller, so
    they stay in cache though the jumps read them at random.

    Returns
    -------
    start : int64 (R + 2,), entries of half-width r are start[r]:start[r + 1]
    cut, alias : float64, int32 (K,), the alias table (alias indices are local to r)
    offsets : int8 (K, 3), the classes' representatives
    """
    top = TABLE_MAX[dim]
    start = np.zeros(top + 2, np.int64)
    cuts, aliases, offsets = [], [], []
    for r in range(2, top + 1):
        reps, probs = symmetry_classes(*exit_law(dim, moore, r))
        cut, alias = _alias(probs)
        cuts.append(cut)
        aliases.append(alias)
        off = np.zeros((len(probs), 3), np.int8)
        off[:, :dim] = reps
        offsets.append(off)
        start[r + 1:] = start[r] + len(probs)
    return start, np.concatenate(cuts), np.concatenate(aliases), np.concatenate(offsets)


@jit
def _symmetry(g, dim, o0, o1, o2):
    """Symmetry ``g`` (0..7 in 2D, 0..47 in 3D) of the square (cube) applied to (o0, o1, o2).

    Bits 0..dim-1 of ``g`` reflect the axes; the rest pick one of the dim!
    axis permutations (a cyclic shift, then perhaps a swap).
    """
    p = g >> dim
    if dim == 3:
        for _ in range(p >> 1):
            o0, o1, o2 = o1, o2, o0
        p &= 1
    if p:
        o0, o1 = o1, o0
    if g & 1:
        o0 = -o0
    if g & 2:
        o1 = -o1
    if dim == 3 and g & 4:
        o2 = -o2
    return o0, o1, o2


@jit
def _site(x):
    return np.int64(np.floor(x + 0.5))


@jit
def _mark_images(words, dim, start, blocks, cells, field, width, off, q, period, cap):
    """Mark a particle at site q, with its periodic images for substrates.

    ``cap`` 1 marks only the particle's own cell of the field (for
    ``maps.field_fill`` to complete), else ``FIELD_CAP[dim]``.
    """
    reach = 1 if period > 0 else 0
    zreach = reach if dim == 3 else 0
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
        _mark_images(words, dim, start, blocks, cells, field, width, off, q, period, 1)
    maps.field_fill(field, dim, width, FIELD_CAP[dim])
    return words, start, blocks, cells, field


@jit
def _occupied(words, dim, start, blocks, width, off, q0, q1, q2):
    i, j, k = q0 + off, q1 + off, q2 + off
    if i < 0 or j < 0 or k < 0 or i >= width or j >= width or k >= width:
        return False
    return maps.test(words, dim, start, blocks, 0, i, j, k)


@jit
def _cell(dim, nb, width, off, q0, q1, q2):
    """Word and bit of site q in the occupancy segment, word -1 outside the grid.

    Scalars only, for the hot loop, which reads the word itself: a helper
    that takes the array costs atomic reference counting per call.
    """
    i, j, k = q0 + off, q1 + off, q2 + off
    if i < 0 or j < 0 or k < 0 or i >= width or j >= width or k >= width:
        return -1, 0
    return maps.index(dim, 0, nb, i, j, k)


@jit
def _in_contact(words, dim, start, blocks, width, off, q, moves, period):
    """Whether site q touches a particle (or the substrate) under ``moves``."""
    for m in range(moves.shape[0]):
        n0, n1, n2 = q[0] + moves[m, 0], q[1] + moves[m, 1], q[2] + moves[m, 2]
        if period > 0:
            if (n2 if dim == 3 else n1) < 0:
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
def _near_step(words, dim, start, blocks, width, off, q, moves, period, stickiness, rs, near):
    """One site of the exact lattice walk: stick, or step to a random neighbour.

    The walker first sticks with probability ``stickiness`` if it touches the
    cluster, else it steps (staying put when the neighbour is occupied).
    ``near`` False promises that no particle is within two sites, which
    spares the contact and occupancy tests. Returns whether it stuck.
    """
    up = dim - 1
    line = period > 0
    if near or (line and q[up] <= 1):
        if _in_contact(words, dim, start, blocks, width, off, q, moves, period):
            if stickiness >= 1.0 or uniform(rs) < stickiness:
                return True
    m = np.int64(uniform(rs) * moves.shape[0])
    n0, n1, n2 = q[0] + moves[m, 0], q[1] + moves[m, 1], q[2] + moves[m, 2]
    if line:
        n0 = n0 % period
        if dim == 3:
            n1 = n1 % period
    blocked = near and _occupied(words, dim, start, blocks, width, off, n0, n1, n2)
    if not blocked and not (line and (n2 if dim == 3 else n1) < 0):
        q[0], q[1], q[2] = n0, n1, n2
    return False


@jit
def _near_walk(
    words, dim, start, blocks, width, off, q, moves, period, stickiness, rs,
    boxed, lo, hi, radius, budget,
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
        # the level-1 map is clear unless a particle is within two sites
        near = ingrid and maps.test(words, dim, start, blocks, 1, i >> 1, j >> 1, k >> 1)
        if _near_step(words, dim, start, blocks, width, off, q, moves, period, stickiness, rs, near):
            return True, taken
        taken += 1
        if taken == budget:
            return False, taken
        if boxed and _outside(q, dim, line, lo, hi):
            return False, taken
        if radius > 0.0:
            r2 = float(q[up] * q[up]) if line else float(q[0] * q[0] + q[1] * q[1] + q[2] * q[2])
            if r2 > radius * radius:
                return False, taken


@jit
def _row2(w0, w1, w2, t):
    """Row t (0..7) of three 8x8 words side by side: 24 sites as bits."""
    shift = np.uint64(8 * t)
    return (
        ((w0 >> shift) & np.uint64(255))
        | (((w1 >> shift) & np.uint64(255)) << np.uint64(8))
        | (((w2 >> shift) & np.uint64(255)) << np.uint64(16))
    )


@jit
def _word(words, nb, x, y, z):
    """Word (x, y, z) of the occupancy segment, empty outside the grid."""
    inside = 0 <= x < nb and 0 <= y < nb and 0 <= z < nb
    return words[x + nb * (y + nb * z)] if inside else np.uint64(0)


@jit
def _fine2(a0, a1, a2, b0, b1, b2, c0, c1, c2, x, y):
    """Chebyshev distance from site (x, y) of word b1 to the nearest particle, capped at 9.

    ``a*``, ``b*``, ``c*`` are the 3x3 words (8x8 sites each, rows a below)
    around the walker's, which cover 8 sites on every side, so the result is
    exact below the cap. Rows of 24 sites are OR-ed outwards from the
    walker's row; the square of half-width r is hit when the OR of its rows
    has a bit within r columns. Scalars only: a call that passes arrays costs
    atomic reference counting when numba does not inline it.
    """
    x += 8
    seen = _row2(b0, b1, b2, y)
    found = 9
    for r in range(9):
        if r > 0:
            lo, hi = y - r, y + r
            seen |= _row2(a0, a1, a2, lo + 8) if lo < 0 else _row2(b0, b1, b2, lo)
            seen |= _row2(c0, c1, c2, hi - 8) if hi > 7 else _row2(b0, b1, b2, hi)
        if (seen >> np.uint64(x - r)) & ((np.uint64(1) << np.uint64(2 * r + 1)) - np.uint64(1)) != 0:
            found = r
            break
    return found


@jit
def _band(x, r, a, width):
    """Sites x - r..x + r (of the 12 across three words) within word a, as
    groups of ``width`` bits, one group per site of the word's 4."""
    lo = max(x - r - 4 * a, 0)
    hi = min(x + r - 4 * a, 3)
    if lo > hi:
        return np.uint64(0)
    ones = np.uint64(0xFFFFFFFFFFFFFFFF) >> np.uint64(64 - (hi - lo + 1) * width)
    return ones << np.uint64(lo * width)


@jit
def _masks(x, r, width, repeat):
    """Masks of sites x - r..x + r along one axis in its three words: ``_band``
    repeated by the multiplier ``repeat`` (the axis's stride in the word)."""
    return (
        _band(x, r, 0, width) * np.uint64(repeat),
        _band(x, r, 1, width) * np.uint64(repeat),
        _band(x, r, 2, width) * np.uint64(repeat),
    )


@jit
def _fine3(words, nb, i, j, k, cube):
    """Chebyshev distance from site (i, j, k) to the nearest particle, capped at 5.

    The 3x3x3 words (4x4x4 sites each, bit x + 4 y + 16 z) around the
    walker's cover 4 sites on every side; the cube of half-width r is hit
    when a word AND-ed with the masks of its x, y and z ranges is nonzero.
    Whole words at a time, and a bisection over r: three rounds at most.
    """
    bx, by, bz = i >> 2, j >> 2, k >> 2
    inside = 1 <= bx < nb - 1 and 1 <= by < nb - 1 and 1 <= bz < nb - 1
    any_set = np.uint64(0)
    for c in range(3):
        for b in range(3):
            row = bx - 1 + nb * (by + b - 1 + nb * (bz + c - 1))
            for a in range(3):
                # away from the grid's faces, no bounds to check
                w = words[row + a] if inside else _word(words, nb, bx + a - 1, by + b - 1, bz + c - 1)
                cube[a + 3 * (b + 3 * c)] = w
                any_set |= w
    if any_set == 0:
        return 5
    x = (i & 3) + 4
    y = (j & 3) + 4
    z = (k & 3) + 4
    lo, hi = 0, 5  # the distance (5: none within 4) is in lo..hi
    while lo < hi:
        r = (lo + hi) >> 1
        mx0, mx1, mx2 = _masks(x, r, 1, 0x1111111111111111)
        my0, my1, my2 = _masks(y, r, 4, 0x0001000100010001)
        mz0, mz1, mz2 = _masks(z, r, 16, 1)
        hit = np.uint64(0)
        for c in range(3):
            mz = mz0 if c == 0 else (mz1 if c == 1 else mz2)
            for b in range(3):
                myz = mz & (my0 if b == 0 else (my1 if b == 1 else my2))
                w = 3 * (b + 3 * c)
                hit |= myz & ((cube[w] & mx0) | (cube[w + 1] & mx1) | (cube[w + 2] & mx2))
        if hit != 0:
            hi = r
        else:
            lo = r + 1
    return lo


@jit
def _grow(
    n, dim, moves, stickiness, seed_shape, size, launch_box, launch_factor, launch_margin,
    kill_factor, jumps, walkers, max_steps, marks, rng, points, steps, times,
    t_start, t_cut, t_alias, t_off,
):
    t0 = clock()
    up = dim - 1
    line = seed_shape == LINE
    period = size if line else 0
    boxed = size > 0 and not line
    lo = -(size // 2)
    hi = size - 1 + lo
    rs = seed_stream(rng)
    top = TABLE_MAX[dim]
    group = 8 if dim == 2 else 48  # symmetries of the square (cube)
    rounding = 0.5 * np.sqrt(dim)
    field_far = ((FIELD_CAP[dim] - 1) << maps.FIELD_SHIFT) + 1  # the field's largest bound  # how far a site can be from the point it rounds

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
    nb0, base1, nb1 = blocks[0], start[1], blocks[1]
    nm = moves.shape[0]
    cube = np.zeros(27, np.uint64)

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
                words, dim, start, blocks, width, off, q, moves, period, stickiness, rs,
                True, box_lo, box_hi, 0.0, 1,
            )
            total += taken
            pending += taken
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
            kill_r = kill_factor * launch_r
            # any radius beyond the launch circle is exact for the return; a
            # unit gap spares a walker that rounding put a hair outside it
            return_r = launch_r + 1.0 if kill_factor == 0.0 and not boxed and not launch_box else 0.0
            budget = max_steps - total if max_steps > 0 else np.int64(-1)
            # one walker's moves until it sticks, leaves, or spends the budget;
            # the stream's state lives in registers meanwhile
            s0, s1, s2, s3 = rs[0], rs[1], rs[2], rs[3]
            while budget != 0:
                r = pos[up] if line else np.sqrt(pos[0] ** 2 + pos[1] ** 2 + pos[2] ** 2)
                if kill_factor > 0.0 and r > kill_r:
                    need_launch = True
                    break
                if return_r > 0.0 and r > return_r:
                    total += 1
                    pending += 1
                    budget -= 1
                    if line:
                        return_to_plane(rng, dim, pos, launch_r, size)
                    elif not return_to_sphere(rng, dim, pos, launch_r, scratch):
                        need_launch = True
                        break
                    continue
                for a in range(3):
                    q[a] = _site(pos[a])
                if (boxed or launch_box) and _outside(q, dim, line, box_lo, box_hi):
                    need_launch = True
                    break
                if not jumps:
                    rs[0], rs[1], rs[2], rs[3] = s0, s1, s2, s3
                    stuck, taken = _near_walk(
                        words, dim, start, blocks, width, off, q, moves, period, stickiness, rs,
                        boxed or launch_box, box_lo, box_hi, kill_r if kill_factor > 0.0 else return_r,
                        max(budget, 0),
                    )
                    s0, s1, s2, s3 = rs[0], rs[1], rs[2], rs[3]
                    total += taken
                    pending += taken
                    for a in range(3):
                        pos[a] = q[a]
                    break
                i, j, k = q[0] + off, q[1] + off, q[2] + off
                ingrid = 0 <= i < width and 0 <= j < width and 0 <= k < width
                # the level-1 map is clear unless a particle is within three sites
                near = False
                if ingrid:
                    cw, cb = maps.index(dim, base1, nb1, i >> 1, j >> 1, k >> 1)
                    near = (words[cw] >> np.uint64(cb)) & np.uint64(1) != np.uint64(0)
                if near or (line and q[up] <= 1):
                    # a single lattice step, written out: calls that pass
                    # arrays would cost atomic reference counting
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
                        cw, cb = _cell(dim, nb0, width, off, n0, n1, n2)
                        if cw >= 0 and (words[cw] >> np.uint64(cb)) & np.uint64(1) != np.uint64(0):
                            touch = True
                            break
                    if touch and stickiness < 1.0:
                        s0, s1, s2, s3, u = xo(s0, s1, s2, s3)
                        touch = u < stickiness
                    if touch:
                        stuck = True
                        break
                    s0, s1, s2, s3, u = xo(s0, s1, s2, s3)
                    m = np.int64(u * nm)
                    n0, n1, n2 = q[0] + moves[m, 0], q[1] + moves[m, 1], q[2] + moves[m, 2]
                    if line:
                        n0 = n0 % period
                        if dim == 3:
                            n1 = n1 % period
                    cw, cb = _cell(dim, nb0, width, off, n0, n1, n2)
                    filled = cw >= 0 and (words[cw] >> np.uint64(cb)) & np.uint64(1) != np.uint64(0)
                    if not filled and not (line and (n2 if dim == 3 else n1) < 0):
                        pos[0], pos[1], pos[2] = n0, n1, n2
                    total += 1
                    pending += 1
                    budget -= 1
                    continue
                # Chebyshev distance to the cluster, at least 2 here: exact
                # within a few sites (the words), then the field, then the maps
                if ingrid:
                    cell = maps.field_get(field, dim, width, i, j, k)
                    if cell > 1:
                        d = ((cell - 1) << maps.FIELD_SHIFT) + 1
                    elif dim == 2:
                        bx, by = i >> 3, j >> 3
                        d = _fine2(
                            _word(words, nb0, bx - 1, by - 1, 0), _word(words, nb0, bx, by - 1, 0),
                            _word(words, nb0, bx + 1, by - 1, 0), _word(words, nb0, bx - 1, by, 0),
                            words[bx + nb0 * by], _word(words, nb0, bx + 1, by, 0),
                            _word(words, nb0, bx - 1, by + 1, 0), _word(words, nb0, bx, by + 1, 0),
                            _word(words, nb0, bx + 1, by + 1, 0), i & 7, j & 7,
                        )
                    else:
                        d = _fine3(words, nb0, i, j, k, cube)
                    if d >= field_far:
                        level, bound = maps.free_bound(words, dim, start, blocks, cells, i, j, k, level)
                        d = max(d, np.int64(bound + 0.5))
                else:
                    d = 5  # every particle lies 4 sites inside the grid
                free = r - (h_max if line else r_max)  # Euclidean, from the float position
                if line:
                    d = min(max(d, np.int64(free)), period, q[up] + 1)
                free = max(free, d - rounding)
                if line:
                    free = min(free, pos[up] + 1.0)
                reach = free - JUMP_MARGIN
                half = min(d - 1, top)
                if kill_factor > 0.0:
                    reach = min(reach, kill_r - r)
                    qr = np.sqrt(float(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]))
                    half = min(half, np.int64((kill_r - qr) / np.sqrt(dim)) + 1)
                if boxed:
                    for a in range(dim):
                        reach = min(reach, pos[a] - lo, hi - pos[a])
                        half = min(half, q[a] - lo + 1, hi - q[a] + 1)
                elif line and launch_box:
                    reach = min(reach, box_hi - pos[up])
                    half = min(half, box_hi - q[up] + 1)
                total += 1
                pending += 1
                budget -= 1
                if reach >= CIRCLE_MIN and reach > half:
                    s0, s1, s2, s3, u0, u1, u2 = xdir(s0, s1, s2, s3, dim)
                    pos[0] += reach * u0
                    pos[1] += reach * u1
                    pos[2] += reach * u2
                elif half >= 2:
                    # exact: where the lattice walk first leaves the square of half-width `half`
                    s0, s1, s2, s3, u = xo(s0, s1, s2, s3)
                    u *= t_start[half + 1] - t_start[half]
                    e = np.int64(u)
                    if u - e >= t_cut[t_start[half] + e]:
                        e = t_alias[t_start[half] + e]
                    e += t_start[half]
                    # a uniform symmetry of the square spreads the class over its orbit
                    s0, s1, s2, s3, u = xo(s0, s1, s2, s3)
                    o0, o1, o2 = _symmetry(np.int64(u * group), dim, t_off[e, 0], t_off[e, 1], t_off[e, 2])
                    pos[0], pos[1], pos[2] = q[0] + o0, q[1] + o1, q[2] + o2
                else:
                    # no particle within two sites: a plain step
                    s0, s1, s2, s3, u = xo(s0, s1, s2, s3)
                    m = np.int64(u * nm)
                    for a in range(dim):
                        pos[a] = q[a] + moves[m, a]
                if line:
                    for a in range(up):
                        pos[a] = pos[a] % period
            rs[0], rs[1], rs[2], rs[3] = s0, s1, s2, s3
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
                # room for the cluster, in whole words (8 or 4 sites) of the field's cells
                width = (int(width * GROWTH) + 15) // 16 * 16
                if not line:
                    off = width // 2
                words, start, blocks, cells, field = _rebuild(points, count, dim, width, off, period)
                nb0, base1, nb1 = blocks[0], start[1], blocks[1]
            else:
                _mark_images(words, dim, start, blocks, cells, field, width, off, q, period, FIELD_CAP[dim])
            while mi < len(marks) and marks[mi] <= count:
                times[mi] = clock() - t0
                mi += 1
            if walkers > 1:
                alive[w] = False
                live -= 1
            else:
                need_launch = True
            stuck = False
            # with box launch, growth ends where the cluster meets the box
            if launch_box and walkers == 1 and _outside(q, dim, line, box_lo + 2, box_hi - 2):
                status = BOUNDARY
                break
    return count, status


def grow_lattice(n, p, marks, rng, times=None):
    """Grow a lattice cluster; see ``dlasweep.grow`` for the meaning.

    ``times``, if given, is filled as the marks pass (NaN before), so that
    another thread can watch the growth.

    Returns
    -------
    points : int32 (n_grown, dim)
    steps : int64 (n_grown,)
    status : int code into ``dlasweep.params.STATUSES``
    times : float64 seconds at each of ``marks`` (NaN when not reached)
    """
    dim = p["dim"]
    moore = p["neighbours"] != 2 * dim
    points = np.zeros((n, dim), np.int32)
    steps = np.zeros(n, np.int64)
    times = np.full(len(marks), np.nan) if times is None else times
    count, status = _grow(
        n, dim, _moves(dim, moore), p["stickiness"],
        ("point", "block", "line").index(p["seed_shape"]), p["size"], p["launch"] == "box",
        p["launch_factor"], p["launch_margin"], p["kill_factor"], p["jumps"], p["walkers"],
        p["max_steps"], marks, rng, points, steps, times, *exit_tables(dim, moore),
    )
    if count < n:  # don't keep the unused tail alive
        points, steps = points[:count].copy(), steps[:count].copy()
    return points, steps, int(status), times
