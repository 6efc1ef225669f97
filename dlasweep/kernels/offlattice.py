"""Off-lattice DLA: unit-diameter disks (2D) and spheres (3D).

Two particles touch when their centres are exactly one diameter apart.

Far from the cluster a walker moves by walk-on-spheres jumps: it jumps
uniformly onto the sphere whose radius is a lower bound on its free distance
(the largest clear level of the hierarchical occupancy maps, refined by the
walker's place in its map cell, and the bounding circle of the cluster).
Outside the launch circle it returns exactly (``walk.return_to_sphere``) or,
above the launch line of a substrate, ``walk.return_to_plane``.

Near the cluster, exact nearest distances come from a cell list (cells of
side 2, in tiles of 64 cells allocated where particles are, so memory follows
the cluster) cached as a neighbour list around an anchor point: while the
walker stays near the anchor, its exact free distance is a minimum over a
handful of centres. When that free distance drops below ``EPS`` the walker
moves by ``RAY`` along a uniform direction with an exact ray cast, so it
stops exactly at contact (centre distance 1 to within rounding, never less)
and never passes through a branch. The bias of this shell is O(EPS) in the
contact point. ``step > 0`` replaces the end game by fixed Gaussian steps
with an end-point overlap check (see ``_gauss_move``).

Rules where the model table leaves a choice:

* Stickiness: at each contact the walker sticks with probability s; if not,
  it moves away from the contact by a ray-cast move of length 1 along a
  uniform direction of the outward half-space (step > 0: it stays at the
  contact and takes its next Gaussian step from there).
* Box (size > 0): absorbing walls at +-size/2 (a walker that comes within
  ``EPS`` of a wall is removed). Circle launch stops with ``boundary`` when
  the launch circle comes within one diameter of the walls; box launch
  releases walkers uniformly on the surface one diameter inside the walls
  and stops with ``boundary`` when a particle comes within one diameter of
  that surface. ``kill_factor`` is ignored with box launch (the walls kill).
* Substrate (seed_shape line): centres touch it at up-coordinate 0;
  periodic sides of width ``size`` (coordinates kept in [0, size)).
  Circle launch: launch line/plane at height launch_factor*h_max +
  launch_margin, no ceiling. Box launch: walkers released at height size-1,
  absorbing ceiling at size, ``boundary`` when h_max >= size - 2.
* walkers > 1: walkers start uniformly in the box (not overlapping the
  seed), take single steps in turn (step 1 with a ray cast, or Gaussian),
  and are removed at the walls; a walker found overlapping a newly attached
  particle merges into it (is removed).
* step > 0 with jumps: walk-on-spheres while the free distance exceeds
  ``GAUSS_JUMP * step``, fixed Gaussian steps nearer than that.
"""

import numba
import numpy as np

from .._jit import clock, jit
from . import maps
from .walk import return_to_plane, return_to_sphere

ijit = numba.njit(cache=True, nogil=True, fastmath=False, error_model="numpy", inline="always")
"""``_jit.jit`` inlined at numba level into its callers: hot helpers that take
arrays must be inlined, or every call pays atomic NRT incref/decref on each
array argument (a third of the run time when they were plain calls)."""

POINT, BLOCK, LINE = 0, 1, 2
OK, BOUNDARY, STEP_LIMIT, EXHAUSTED = 0, 1, 2, 3

EPS = 1e-3
"""Surface gap (diameters) below which a walker ray-casts to contact."""
RAY = 2e-3
"""Length of the ray-cast moves inside the EPS shell."""
REJECT = 1.0
"""Length of the move away from a contact that did not stick."""
RL = 3.0
"""Radius (centre distance) of the cached neighbour list."""
LCAP = 1024
"""Capacity of the neighbour list (a packing of radius RL holds far fewer)."""
GAUSS_JUMP = 4.0
"""With step > 0 and jumps, walk-on-spheres only beyond this many step stds."""
LINE_PAD = 32
"""Periodic images marked in the maps up to this distance (line seed)."""
GROW = 1.3
"""Grid growth factor."""
INF = np.inf


# ---------------------------------------------------------------- grid -----
#
# gi: 0-2 index cells per axis, 3-5 tiles per axis, 6-8 map offsets,
#     9 map width, 10-12 periodic axes, 13 tile bits, 14 tiles used,
#     15 largest usable map level, 16 covered half-width (point) or height (line)
# gf: 0-2 index origin, 3-5 index inverse cell side, 6 period


@jit
def _layout(dim, line, size, need):
    """Grid geometry covering a cluster of extent ``need`` (r_max or h_max)."""
    gi = np.zeros(17, np.int64)
    gf = np.zeros(8)
    tb = 3 if dim == 2 else 2
    gi[13] = tb
    up = dim - 1
    gf[6] = float(size)
    if not line:
        half = int(np.ceil(GROW * (need + 8.0) / 16.0)) * 16
        if size > 0:
            half = min(half, ((size // 2 + 8) // 16 + 1) * 16)
        gi[16] = half
        gi[9] = 2 * half
        gi[15] = 1 << 30
        for a in range(dim):
            gi[a] = half
            gi[6 + a] = half
            gf[a] = -float(half)
            gf[3 + a] = 0.5
    else:
        top = int(np.ceil(GROW * (need + 8.0) / 16.0)) * 16
        gi[16] = top
        gi[9] = max(size + 2 * LINE_PAD, top + 2)
        gi[15] = 4  # 2**(4+1) = LINE_PAD: a clear cell's neighbourhood stays within the pad
        m = size // 2
        for a in range(up):
            gi[a] = m
            gi[6 + a] = LINE_PAD
            gi[10 + a] = 1
            gf[a] = 0.0
            gf[3 + a] = m / float(size)
        gi[up] = (top + 2) // 2 + 1
        gi[6 + up] = 2
        gf[up] = -2.0
        gf[3 + up] = 0.5
    for a in range(3):
        if a >= dim:
            gi[a] = 1
            gi[3 + a] = 1
        else:
            gi[3 + a] = (gi[a] + (1 << tb) - 1) >> tb
    return gi, gf


@ijit
def _cell(v, a, gi, gf):
    c = int(np.floor((v - gf[a]) * gf[3 + a]))
    if c < 0:
        c = 0
    if c >= gi[a]:
        c = gi[a] - 1
    return c


@ijit
def _slot(gi, c0, c1, c2):
    """(tile, cell-within-tile) of index cell (c0, c1, c2)."""
    tb = gi[13]
    m = (1 << tb) - 1
    t = (c0 >> tb) + gi[3] * ((c1 >> tb) + gi[4] * (c2 >> tb))
    return t, (c0 & m) | ((c1 & m) << tb) | ((c2 & m) << (2 * tb))


@jit
def _insert(i, pts, nxt, dim, gi, gf, dirr, heads):
    c0 = _cell(pts[i, 0], 0, gi, gf)
    c1 = _cell(pts[i, 1], 1, gi, gf)
    c2 = _cell(pts[i, 2], 2, gi, gf) if dim == 3 else 0
    t, loc = _slot(gi, c0, c1, c2)
    tile = dirr[t]
    if tile < 0:
        tile = gi[14]
        gi[14] += 1
        if (tile + 1) * 64 > len(heads):
            bigger = np.full(2 * len(heads), -1, np.int32)
            bigger[: len(heads)] = heads
            heads = bigger
        dirr[t] = tile
    h = tile * 64 + loc
    nxt[i] = heads[h]
    heads[h] = i
    return heads


@jit
def _mark(i, pts, dim, size, gi, words, start, blocks, cells):
    """Mark particle i in the maps, with its periodic images near the edges."""
    W = gi[9]
    per = gi[10] == 1
    reach = 1 if per else 0
    reach2 = reach if dim == 3 else 0
    z = pts[i, 2] if dim == 3 else 0.0
    for a in range(-reach, reach + 1):
        for b in range(-reach2, reach2 + 1):
            i0 = int(np.floor(pts[i, 0] + a * size)) + gi[6]
            i1 = int(np.floor(pts[i, 1] + (b * size if dim == 3 else 0.0))) + gi[7]
            i2 = int(np.floor(z)) + gi[8] if dim == 3 else 0
            if 0 <= i0 < W and 0 <= i1 < W and 0 <= i2 < W:
                maps.mark(words, dim, start, blocks, cells, i0, i1, i2)


@jit
def _build_grid(dim, line, size, need, pts, count, nxt):
    gi, gf = _layout(dim, line, size, need)
    words, start, blocks, cells = maps.allocate(dim, gi[9])
    ntiles = gi[3] * gi[4] * gi[5]
    dirr = np.full(ntiles, -1, np.int32)
    heads = np.full(64 * max(64, min(ntiles, count + 16)), -1, np.int32)
    for i in range(count):
        heads = _insert(i, pts, nxt, dim, gi, gf, dirr, heads)
        _mark(i, pts, dim, size, gi, words, start, blocks, cells)
    return gi, gf, words, start, blocks, cells, dirr, heads


@ijit
def _bit(words, dim, start, blocks, s, i, j, k):
    """Bit (i, j, k) of map segment s (``maps.test``, inlined)."""
    nb = blocks[s]
    if dim == 2:
        word = start[s] + (i >> 3) + nb * (j >> 3)
        b = (i & 7) | ((j & 7) << 3)
    else:
        word = start[s] + (i >> 2) + nb * ((j >> 2) + nb * (k >> 2))
        b = (i & 3) | ((j & 3) << 2) | ((k & 3) << 4)
    return (words[word] >> np.uint64(b)) & np.uint64(1) != np.uint64(0)


@ijit
def _map_dist(w, dim, size, gi, words, start, blocks, cells):
    """Lower bound on the centre distance from w to every particle, from the maps.

    The largest clear level s (bisection, as ``maps.clear_level``) puts every
    particle outside the 3**dim block of level-s cells around w, so the
    distance to that block's surface, 2**s plus w's distance to its own
    cell's faces, bounds it. Returns 0 when the level-1 cell is set (look
    closer) and -1 when w is off the map.
    """
    W = gi[9]
    x0 = w[0]
    x1 = w[1]
    if gi[10] == 1:
        x0 = x0 - size * np.floor(x0 / size)
        if dim == 3:
            x1 = x1 - size * np.floor(x1 / size)
    X0 = x0 + gi[6]
    X1 = x1 + gi[7]
    X2 = w[2] + gi[8] if dim == 3 else 0.0
    if not (0.0 <= X0 < W and 0.0 <= X1 < W and 0.0 <= X2 < W):
        return -1.0
    i0, i1, i2 = int(X0), int(X1), int(X2)
    if _bit(words, dim, start, blocks, 1, i0 >> 1, i1 >> 1, i2 >> 1):
        return 0.0
    top = min(len(cells) - 1, gi[15])
    if not _bit(words, dim, start, blocks, top, i0 >> top, i1 >> top, i2 >> top):
        s = top
    else:
        lo, hi = 1, top  # clear at lo, set at hi
        while hi - lo > 1:
            mid = (lo + hi) >> 1
            if _bit(words, dim, start, blocks, mid, i0 >> mid, i1 >> mid, i2 >> mid):
                hi = mid
            else:
                lo = mid
        s = lo
    side = float(1 << s)
    lo_ = float((i0 >> s) << s)
    f = min(X0 - lo_, lo_ + side - X0)
    lo_ = float((i1 >> s) << s)
    f = min(f, X1 - lo_, lo_ + side - X1)
    if dim == 3:
        lo_ = float((i2 >> s) << s)
        f = min(f, X2 - lo_, lo_ + side - X2)
    return side + f


@ijit
def _dir(rng, dim, out):
    """Uniform unit vector into out[:3] (``walk.direction``, inlined)."""
    if dim == 2:
        a = 2.0 * np.pi * rng.random()
        out[0] = np.cos(a)
        out[1] = np.sin(a)
        out[2] = 0.0
        return
    cz = 2.0 * rng.random() - 1.0
    a = 2.0 * np.pi * rng.random()
    sz = np.sqrt(max(0.0, 1.0 - cz * cz))
    out[0] = sz * np.cos(a)
    out[1] = sz * np.sin(a)
    out[2] = cz


@ijit
def _crange(v, r, a, gi, gf):
    """Index cells covering [v - r, v + r] on axis a (may wrap if periodic)."""
    lo = int(np.floor((v - r - gf[a]) * gf[3 + a]))
    hi = int(np.floor((v + r - gf[a]) * gf[3 + a]))
    nc = gi[a]
    if gi[10 + a] == 1:
        if hi - lo + 1 > nc:
            hi = lo + nc - 1
    else:
        lo = max(lo, 0)
        hi = min(hi, nc - 1)
    return lo, hi


@ijit
def _image(d, per, size):
    if per:
        if d > 0.5 * size:
            d -= size
        elif d < -0.5 * size:
            d += size
    return d


@ijit
def _gather(c, r, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li):
    """Particles with centres within r of point c, as images nearest to c.

    Fills lx, ly, lz (coordinates) and li (indices); returns the count.
    """
    r2 = r * r
    nl = 0
    lo0, hi0 = _crange(c[0], r, 0, gi, gf)
    lo1, hi1 = _crange(c[1], r, 1, gi, gf)
    lo2, hi2 = 0, 0
    if dim == 3:
        lo2, hi2 = _crange(c[2], r, 2, gi, gf)
    p0 = gi[10] == 1
    p1 = gi[11] == 1
    n0, n1 = gi[0], gi[1]
    for k2 in range(lo2, hi2 + 1):
        for k1 in range(lo1, hi1 + 1):
            c1 = k1 % n1 if p1 else k1
            for k0 in range(lo0, hi0 + 1):
                c0 = k0 % n0 if p0 else k0
                t, loc = _slot(gi, c0, c1, k2)
                tile = dirr[t]
                if tile < 0:
                    continue
                h = heads[tile * 64 + loc]
                while h >= 0:
                    d0 = _image(pts[h, 0] - c[0], p0, size)
                    d1 = _image(pts[h, 1] - c[1], p1, size)
                    d2 = pts[h, 2] - c[2] if dim == 3 else 0.0
                    if d0 * d0 + d1 * d1 + d2 * d2 < r2 and nl < len(lx):
                        lx[nl] = c[0] + d0
                        ly[nl] = c[1] + d1
                        lz[nl] = c[2] + d2
                        li[nl] = h
                        nl += 1
                    h = nxt[h]
    return nl


@ijit
def _ray(w, u, length, nl, lx, ly, lz):
    """First contact along w + t u, 0 <= t <= length, with listed centres: (t, k).

    k indexes the list, or is -1 when nothing is touched.
    """
    best = length
    hit = -1
    for k in range(nl):
        d0 = w[0] - lx[k]
        d1 = w[1] - ly[k]
        d2 = w[2] - lz[k]
        b = u[0] * d0 + u[1] * d1 + u[2] * d2
        if b >= 0.0:
            continue
        cc = d0 * d0 + d1 * d1 + d2 * d2 - 1.0
        disc = b * b - cc
        if disc < 0.0:
            continue
        t = cc / (np.sqrt(disc) - b)  # the smaller root, without cancellation
        if t < 0.0:
            t = 0.0
        if t <= best:
            best = t
            hit = k
    return best, hit


@ijit
def _ray_sub(w, u, dim, best, hit):
    """Add the substrate (centres touch it at up = 0) to a ray cast."""
    up = dim - 1
    if u[up] < 0.0:
        t = -w[up] / u[up]
        if t < 0.0:
            t = 0.0
        if t <= best:
            return t, -2
    return best, hit


@ijit
def _settle(w, u, t, hit, dim, lx, ly, lz, normal):
    """Move to w + t u and put the contact at distance 1 exactly; store the normal."""
    for a in range(3):
        w[a] += t * u[a]
    if hit == -2:
        w[dim - 1] = 0.0
        for a in range(3):
            normal[a] = 0.0
        normal[dim - 1] = 1.0
        return
    d0 = w[0] - lx[hit]
    d1 = w[1] - ly[hit]
    d2 = w[2] - lz[hit]
    r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    normal[0] = d0 / r
    normal[1] = d1 / r
    normal[2] = d2 / r
    w[0] = lx[hit] + normal[0]
    w[1] = ly[hit] + normal[1]
    w[2] = lz[hit] + normal[2]


@jit
def _cast(w, u, length, dim, size, line, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li, normal):
    """Ray cast of w along u straight from the cell list; moves w.

    Long rays are cast in pieces of at most 2 so the gathered lists stay
    short. Returns True on contact (w then at contact, ``normal`` set).
    """
    c = np.empty(3)
    left = length
    while left > 0.0:
        piece = min(left, 2.0)
        left -= piece
        for a in range(3):
            c[a] = w[a] + 0.5 * piece * u[a]
        nl = _gather(c, 0.5 * piece + 1.0, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li)
        t, hit = _ray(w, u, piece, nl, lx, ly, lz)
        if line:
            t, hit = _ray_sub(w, u, dim, t, hit)
        if hit != -1:
            _settle(w, u, t, hit, dim, lx, ly, lz, normal)
            return True
        for a in range(3):
            w[a] += piece * u[a]
    return False


@jit
def _gauss_move(w, sigma, dim, size, line, rng, pts, nxt, gi, gf, dirr, heads, words, start, blocks,
                cells, lx, ly, lz, li, e, u, normal):
    """One Gaussian step with the naive end-point check; True on contact.

    The step is proposed from w; if its end point is free it is taken, even
    when the straight path crosses a branch (tunnelling). If it overlaps, the
    walker is put back along the step to where it first touches one of the
    particles it overlaps at the end point (exact contact); should that spot
    overlap another particle, a full ray cast along the step decides.
    """
    up = dim - 1
    for a in range(dim):
        e[a] = w[a] + sigma * rng.normal()
    sub = line and e[up] < 0.0
    if not sub and _map_dist(e, dim, size, gi, words, start, blocks, cells) > 0.0:
        for a in range(dim):
            w[a] = e[a]
        return False
    nov = _gather(e, 1.0, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li)
    if nov == 0 and not sub:
        for a in range(dim):
            w[a] = e[a]
        return False
    length = 0.0
    for a in range(dim):
        u[a] = e[a] - w[a]
        length += u[a] * u[a]
    length = np.sqrt(length)
    for a in range(dim):
        u[a] /= length
    t, hit = _ray(w, u, length * (1.0 + 1e-9) + 1e-12, nov, lx, ly, lz)
    if sub:
        t, hit = _ray_sub(w, u, dim, t, hit)
    if hit != -1:
        p = np.empty(3)
        for a in range(3):
            p[a] = w[a]
        _settle(p, u, t, hit, dim, lx, ly, lz, normal)
        n_close = _gather(p, 1.0 - 1e-12, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li)
        if n_close == 0:
            for a in range(3):
                w[a] = p[a]
            return True
    return _cast(w, u, length, dim, size, line, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li, normal)


# --------------------------------------------------------------- growth -----


@jit
def _attach(w, count, since, pts, steps, nxt, geo, dim, line, size, grid):
    """Add the walker at w to the cluster; returns the new count and grid."""
    gi, gf, words, start, blocks, cells, dirr, heads = grid
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
    steps[count] = since
    geo[0] = max(geo[0], np.sqrt(r2))
    geo[1] = max(geo[1], ch)
    geo[2] = max(geo[2], w[up])
    count += 1
    need = geo[2] if line else geo[1]
    if need + 8.0 > gi[16]:
        return count, _build_grid(dim, line, size, need, pts, count, nxt)
    heads = _insert(count - 1, pts, nxt, dim, gi, gf, dirr, heads)
    _mark(count - 1, pts, dim, size, gi, words, start, blocks, cells)
    return count, (gi, gf, words, start, blocks, cells, dirr, heads)


@jit
def _grow(n, dim, shape, size, launch_box, lf, lm, kf, jumps, sigma, nwalk, max_steps, stick, marks, rng):
    t0 = clock()
    up = dim - 1
    line = shape == LINE
    nm = len(marks)
    times = np.full(nm, np.nan)
    nseed = 0 if line else (1 if shape == POINT else 1 << dim)
    cap = max(n, 1)
    pts = np.zeros((cap, dim))
    steps = np.zeros(cap, np.int64)
    nxt = np.full(cap, -1, np.int32)
    count = min(n, nseed)
    geo = np.zeros(3)  # r_max, Chebyshev extent, h_max
    geo[2] = -1.0
    for q in range(count):
        r2 = 0.0
        for a in range(dim):
            if shape == BLOCK:
                pts[q, a] = float((q >> a) & 1)
            r2 += pts[q, a] ** 2
            geo[1] = max(geo[1], abs(pts[q, a]))
        geo[0] = max(geo[0], np.sqrt(r2))
    grid = _build_grid(dim, line, size, max(geo[2], 0.0) if line else geo[1], pts, count, nxt)
    km = 0
    while km < nm and marks[km] <= count:
        times[km] = clock() - t0
        km += 1

    w = np.zeros(3)
    u = np.zeros(3)
    e = np.zeros(3)
    normal = np.zeros(3)
    scratch = np.zeros(3)
    anchor = np.zeros(3)
    lx = np.empty(LCAP)
    ly = np.empty(LCAP)
    lz = np.zeros(LCAP)
    li = np.empty(LCAP, np.int64)
    mx = np.empty(LCAP)
    my = np.empty(LCAP)
    mz = np.zeros(LCAP)
    mi = np.empty(LCAP, np.int64)
    total = np.int64(0)
    since = np.int64(0)
    status = OK
    hb = 0.5 * size
    boxed = size > 0 and not line
    ceiling = line and launch_box
    ret = kf == 0.0 and not launch_box and (line or size == 0)
    kill = kf > 0.0 and not launch_box
    RL2 = RL * RL

    if nwalk > 1:
        return _lockstep(n, dim, line, size, sigma, nwalk, max_steps, stick, marks, rng, t0, times, km,
                         pts, steps, nxt, count, geo, grid)

    while count < n:
        # one walker, from release to attachment or removal
        R = lf * (max(geo[2], 0.0) if line else geo[0]) + lm
        if launch_box:
            if (line and geo[2] >= size - 2.0) or (not line and geo[1] >= hb - 2.0):
                status = BOUNDARY
                break
        elif boxed and R > hb - 1.0:
            status = BOUNDARY
            break
        R2 = R * R
        Rk = kf * R
        gi, gf, words, start, blocks, cells, dirr, heads = grid
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
            w[up] = R
        else:
            _dir(rng, dim, u)
            for a in range(3):
                w[a] = R * u[a]
        list_ok = False
        nl = 0
        stuck = False
        while True:
            if max_steps > 0 and total >= max_steps:
                status = STEP_LIMIT
                break
            # ---- outer boundaries: exact return, kill sphere, walls
            if line:
                h = w[up]
                if ret and h > R:
                    return_to_plane(rng, dim, w, R, size)
                    total += 1
                    since += 1
                    list_ok = False
                    continue
                gb = INF
                if kill:
                    gb = Rk - h
                if ceiling:
                    gb = min(gb, size - h)
                ggeo = h - geo[2] - 1.0
            else:
                r2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2]
                if ret and r2 > R2 * (1.0 + 1e-12):  # returned walkers sit on R, to rounding
                    total += 1
                    since += 1
                    list_ok = False
                    if not return_to_sphere(rng, dim, w, R, scratch):
                        break  # escaped (3D): release a new walker
                    continue
                r = np.sqrt(r2)
                gb = INF
                if kill:
                    gb = Rk - r
                ch = max(abs(w[0]), abs(w[1]), abs(w[2]))
                if boxed:
                    gb = min(gb, hb - ch)
                ggeo = max(r - geo[0], ch - geo[1]) - 1.0
            if gb < EPS:
                break  # absorbed: release a new walker
            # ---- free distance g (a lower bound; exact near the cluster)
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
                if line:
                    for a in range(up):
                        w[a] = w[a] - size * np.floor(w[a] / size)
                dm = _map_dist(w, dim, size, gi, words, start, blocks, cells)
                if dm > 0.0:
                    g = max(ggeo, dm - 1.0)
                elif dm < 0.0:
                    g = ggeo
                else:
                    for a in range(3):
                        anchor[a] = w[a]
                    nl = _gather(anchor, RL, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li)
                    list_ok = True
                    dl2 = INF
                    for k in range(nl):
                        d0 = w[0] - lx[k]
                        d1 = w[1] - ly[k]
                        d2 = w[2] - lz[k]
                        dl2 = min(dl2, d0 * d0 + d1 * d1 + d2 * d2)
                    g = (np.sqrt(dl2) if dl2 < RL2 else RL) - 1.0
            if line:
                g = min(g, w[up])
            g = min(g, gb)
            # ---- move
            contact = False
            if sigma == 0.0:
                if jumps and g >= EPS:
                    _dir(rng, dim, u)
                    for a in range(3):
                        w[a] += g * u[a]
                    total += 1
                    since += 1
                    continue
                if jumps:
                    # inside the shell: short exact ray casts against the list
                    d0 = w[0] - anchor[0]
                    d1 = w[1] - anchor[1]
                    d2 = w[2] - anchor[2]
                    if not list_ok or RL - np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) < 1.0 + RAY + 1e-9:
                        for a in range(3):
                            anchor[a] = w[a]
                        nl = _gather(anchor, RL, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li)
                        list_ok = True
                    _dir(rng, dim, u)
                    total += 1
                    since += 1
                    t, hit = _ray(w, u, RAY, nl, lx, ly, lz)
                    if line:
                        t, hit = _ray_sub(w, u, dim, t, hit)
                    if hit == -1:
                        for a in range(3):
                            w[a] += RAY * u[a]
                        continue
                    _settle(w, u, t, hit, dim, lx, ly, lz, normal)
                    contact = True
                else:
                    _dir(rng, dim, u)
                    total += 1
                    since += 1
                    if g > 1.0:
                        for a in range(3):
                            w[a] += u[a]
                        continue
                    contact = _cast(w, u, 1.0, dim, size, line, pts, nxt, gi, gf, dirr, heads, mx, my, mz, mi, normal)
                    if not contact:
                        continue
                while contact:
                    if stick >= 1.0 or rng.random() < stick:
                        stuck = True
                        break
                    _dir(rng, dim, u)
                    dot = u[0] * normal[0] + u[1] * normal[1] + u[2] * normal[2]
                    if dot < 0.0:
                        for a in range(3):
                            u[a] -= 2.0 * dot * normal[a]
                    total += 1
                    since += 1
                    list_ok = False
                    contact = _cast(w, u, REJECT, dim, size, line, pts, nxt, gi, gf, dirr, heads, mx, my, mz, mi, normal)
                if stuck:
                    break
            else:
                if jumps and g > GAUSS_JUMP * sigma:
                    _dir(rng, dim, u)
                    for a in range(3):
                        w[a] += g * u[a]
                    total += 1
                    since += 1
                    continue
                total += 1
                since += 1
                list_ok = False
                if _gauss_move(w, sigma, dim, size, line, rng, pts, nxt, gi, gf, dirr, heads, words, start,
                               blocks, cells, mx, my, mz, mi, e, u, normal):
                    if stick >= 1.0 or rng.random() < stick:
                        stuck = True
                        break
        if status != OK:
            break
        if stuck:
            count, grid = _attach(w, count, since, pts, steps, nxt, geo, dim, line, size, grid)
            since = 0
            while km < nm and marks[km] <= count:
                times[km] = clock() - t0
                km += 1
    return pts, steps, count, status, times


@jit
def _lockstep(n, dim, line, size, sigma, nwalk, max_steps, stick, marks, rng, t0, times, km,
              pts, steps, nxt, count, geo, grid):
    """Finite concentration: ``nwalk`` walkers start uniformly in the box and
    take single steps in turn; none is relaunched."""
    up = dim - 1
    nm = len(marks)
    hb = 0.5 * size
    gi, gf, words, start, blocks, cells, dirr, heads = grid
    pos = np.zeros((nwalk, 3))
    alive = np.ones(nwalk, np.bool_)
    w = np.zeros(3)
    u = np.zeros(3)
    e = np.zeros(3)
    normal = np.zeros(3)
    mx = np.empty(LCAP)
    my = np.empty(LCAP)
    mz = np.zeros(LCAP)
    mi = np.empty(LCAP, np.int64)
    for k in range(nwalk):
        while True:
            for a in range(dim):
                if line:
                    pos[k, a] = rng.random() * size
                else:
                    pos[k, a] = (2.0 * rng.random() - 1.0) * hb
            if _gather(pos[k], 1.0, dim, size, pts, nxt, gi, gf, dirr, heads, mx, my, mz, mi) == 0:
                break
    live = nwalk
    total = np.int64(0)
    since = np.int64(0)
    status = OK
    while count < n and status == OK:
        if live == 0:
            status = EXHAUSTED
            break
        for k in range(nwalk):
            if not alive[k]:
                continue
            if max_steps > 0 and total >= max_steps:
                status = STEP_LIMIT
                break
            for a in range(3):
                w[a] = pos[k, a]
            dm = _map_dist(w, dim, size, gi, words, start, blocks, cells)
            if dm == 0.0 and _gather(w, 1.0 - 1e-12, dim, size, pts, nxt, gi, gf, dirr, heads, mx, my, mz, mi) > 0:
                alive[k] = False  # a particle attached on top of it: merged
                live -= 1
                continue
            total += 1
            since += 1
            if sigma == 0.0:
                _dir(rng, dim, u)
                if dm > 2.0:
                    for a in range(3):
                        w[a] += u[a]
                    contact = False
                else:
                    contact = _cast(w, u, 1.0, dim, size, line, pts, nxt, gi, gf, dirr, heads, mx, my, mz, mi, normal)
            else:
                contact = _gauss_move(w, sigma, dim, size, line, rng, pts, nxt, gi, gf, dirr, heads, words, start,
                                      blocks, cells, mx, my, mz, mi, e, u, normal)
            stuck = False
            while contact:
                if stick >= 1.0 or rng.random() < stick:
                    stuck = True
                    break
                if sigma > 0.0:
                    break
                _dir(rng, dim, u)
                dot = u[0] * normal[0] + u[1] * normal[1] + u[2] * normal[2]
                if dot < 0.0:
                    for a in range(3):
                        u[a] -= 2.0 * dot * normal[a]
                total += 1
                since += 1
                contact = _cast(w, u, REJECT, dim, size, line, pts, nxt, gi, gf, dirr, heads, mx, my, mz, mi, normal)
            if stuck:
                count, grid = _attach(w, count, since, pts, steps, nxt, geo, dim, line, size, grid)
                gi, gf, words, start, blocks, cells, dirr, heads = grid
                since = 0
                alive[k] = False
                live -= 1
                while km < nm and marks[km] <= count:
                    times[km] = clock() - t0
                    km += 1
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
    return pts, steps, count, status, times


def grow_offlattice(n, p, marks, rng):
    """Grow an off-lattice cluster; see ``dlasweep.grow`` for the meaning.

    Returns
    -------
    points : float64 (n_grown, dim)
    steps : int64 (n_grown,)
    status : int code into ``dlasweep.params.STATUSES``
    times : float64 seconds at each of ``marks`` (NaN when not reached)
    """
    pts, steps, count, status, times = _grow(
        int(n), int(p["dim"]), ("point", "block", "line").index(p["seed_shape"]), int(p["size"]),
        p["launch"] == "box", float(p["launch_factor"]), float(p["launch_margin"]), float(p["kill_factor"]),
        bool(p["jumps"]), float(p["step"]), int(p["walkers"]), int(p["max_steps"]), float(p["stickiness"]),
        np.asarray(marks, np.int64), rng,
    )
    if count < len(pts):
        pts = pts[:count].copy()
        steps = steps[:count].copy()
    return pts, steps, int(status), times
