"""Off-lattice DLA: unit-diameter disks (2D) and spheres (3D).

Two particles touch when their centres are exactly one diameter apart.

Far from the cluster a walker moves by walk-on-spheres jumps: it jumps
uniformly onto the sphere whose radius is a lower bound on its free distance:
near the cluster a coarse Chebyshev distance field (a byte per cell of side
``2**FS``, capped at ``FCAP`` cells), elsewhere the largest clear level of the
dilated maps of ``maps`` (levels 1 and up: unit-cell occupancy is never
needed off-lattice), each refined by the walker's place in its cell, and the
bounding circle of the cluster. Outside the launch circle it returns exactly
(``walk.return_to_sphere``; above a substrate's launch line,
``walk.return_to_plane``).

Near the cluster, exact nearest distances come from a cell list (cells of
side 2 in tiles of 64 cells, allocated only where particles are, so memory
follows the cluster) cached as a neighbour list of radius ``LIST_RADIUS`` around an
anchor point: while
the walker stays near the anchor its exact free distance is a minimum over a
handful of centres. When the free distance (surface gap) drops below ``EPS``
the walker moves by ``RAY`` along a uniform direction with an exact ray cast,
so it stops exactly at contact (centre distance 1 to rounding, never less)
and never passes through a branch. The contact point is biased by O(EPS).

``step > 0`` replaces the end game by fixed Gaussian steps with an end-point
overlap check (``_gauss_move``), the naive scheme, kept to show where it
fails.

Rules where the model table leaves a choice:

* Stickiness: at each contact the walker sticks with probability s; if not,
  it moves away by a ray-cast move of length ``REJECT`` = 1 along a uniform
  direction of the outward half-space (step > 0: it stays at the contact and
  takes its next Gaussian step from there).
* Box (size > 0): absorbing walls at +-size/2 (a walker within ``EPS`` of a
  wall is removed). Circle launch stops with ``boundary`` when the launch
  circle comes within one diameter of the walls; box launch releases walkers
  uniformly on the surface one diameter inside the walls and stops with
  ``boundary`` when a particle centre comes within 2 of the walls.
  ``kill_factor`` is ignored with box launch (the walls kill).
* Substrate (seed_shape line): centres touch it at up-coordinate 0; periodic
  sides of width ``size`` (stored coordinates in [0, size)). Circle launch:
  launch line/plane at launch_factor*h_max + launch_margin, no ceiling. Box
  launch: walkers released at height size-1, absorbing ceiling at size,
  ``boundary`` when h_max >= size - 2.
* walkers > 1: walkers start uniformly in the box (not overlapping the seed),
  take single steps in turn (length 1 with a ray cast, or Gaussian), and are
  removed at the walls; a walker found overlapping a newly attached particle
  merges into it (is removed).
* step > 0 with jumps: walk-on-spheres while the free distance exceeds
  ``GAUSS_JUMP * step``, fixed Gaussian steps nearer than that.

Random numbers: the numpy Generator passed in seeds a xoshiro256+ stream
kept in registers for the walk's directions; the Generator itself draws the
exact returns, stickiness and Gaussian steps. Both are deterministic given
the Generator, so a cluster is a function of its seed.

Memory: besides the points (16 or 24 bytes each), the diffusion times (8)
and the cell-list links (4), the grids take about a bit per unit cell
(maps), a byte per cell of side ``2**FS`` (field) and 4 bytes per tile of
64 cell-list cells (directory) over a square ``GROW`` times the cluster's
extent, and 256 bytes per tile that holds particles. When the cluster outgrows them they are
dropped before the larger ones are built, so the two are never held at once.

Speed note: helpers that take arrays and branch must not be called from the
hot loop (numba then wraps each call in atomic NRT incref/decref, which cost
a third of the run time); the hot loop in ``_walk`` therefore spells out the
map query, the direction draw, the gather of the neighbour list and the list
scans, and calls out only for rare events.
"""

import numpy as np

from .._jit import clock, inline, jit
from . import maps
from .walk import return_to_plane, return_to_sphere, seed_stream, unit_vector, xdir

POINT, BLOCK, LINE = 0, 1, 2
OK, BOUNDARY, STEP_LIMIT, EXHAUSTED = 0, 1, 2, 3

EPS = 1e-3
"""Surface gap (diameters) below which a walker ray-casts to contact."""
RAY = 2e-3
"""Length of the ray-cast moves inside the EPS shell."""
REJECT = 1.0
"""Length of the move away from a contact that did not stick."""
LIST_RADIUS = 3.0
"""Radius (centre distance) of the cached neighbour list. Longer lists give
longer exact jumps and serve longer, but a gather visits (r + 1)**dim cells
of linked lists: side by side at 2D 1e6, radius 6 took 99 steps per particle
against 107 at radius 3, in the same time (15.2 against 15.5 s, two rounds),
and radius 4 made 3D 1e5 slower (4.2 against 3.0 s)."""
LCAP = 1024
"""Capacity of the neighbour lists (a packing within radius 6 in 2D or 3 in
3D holds < 200)."""
GAUSS_JUMP = 4.0
"""With step > 0 and jumps, walk-on-spheres only beyond this many step stds."""
LINE_PAD = 32
"""Periodic images are marked in the maps up to this distance (line seed)."""
FS = maps.FIELD_SHIFT
"""The distance field's coarse cells have side 2**FS (the lattice kernel's field is the same)."""
FCAP = (16, 4)
"""Cap of the distance field (coarse cells), 2D and 3D; beyond it the maps
bound. A new coarse cell costs (2 cap - 1)**dim updates, hence 3D's small cap."""
GROW = 1.3
"""Growth factor of the grids when the cluster outgrows them."""
INF = np.inf


# ---------------------------------------------------------------- grid -----
#
# gi: 0-2 index cells per axis, 3-5 tiles per axis, 6-8 map offsets,
#     9 map width, 10-12 periodic axes, 13 tile bits, 14 tiles used,
#     15 largest usable map level, 16 covered half-width (point) or height (line),
#     17 distance field cap (coarse cells)
# gf: 0-2 index origin, 3-5 index inverse cell side, 6 period


@jit
def _layout(dim, line, size, need):
    """Grid geometry covering a cluster of extent ``need`` (max |coordinate|
    for point seeds, h_max for a substrate), with room to grow."""
    gi = np.zeros(18, np.int64)
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
        gi[17] = FCAP[dim - 2]
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
        gi[17] = LINE_PAD >> FS  # likewise the field's reach, (cap - 1) * 2**FS + 2**(FS-1) < LINE_PAD
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


@jit
def _insert(i, pts, nxt, dim, gi, gf, dirr, heads):
    """Push particle i on its cell's list; returns heads (grown if needed)."""
    c0 = min(max(int(np.floor((pts[i, 0] - gf[0]) * gf[3])), 0), gi[0] - 1)
    c1 = min(max(int(np.floor((pts[i, 1] - gf[1]) * gf[4])), 0), gi[1] - 1)
    c2 = 0
    if dim == 3:
        c2 = min(max(int(np.floor((pts[i, 2] - gf[2]) * gf[5])), 0), gi[2] - 1)
    tb = gi[13]
    m = (1 << tb) - 1
    t = (c0 >> tb) + gi[3] * ((c1 >> tb) + gi[4] * (c2 >> tb))
    loc = (c0 & m) | ((c1 & m) << tb) | ((c2 & m) << (2 * tb))
    tile = dirr[t]
    if tile < 0:
        tile = gi[14]
        gi[14] += 1
        if (tile + 1) * 64 > len(heads):
            bigger = maps.filled(len(heads) + len(heads) // 2, -1, np.int32)  # 1.5x: old and new are held at once
            bigger[: len(heads)] = heads
            heads = bigger
        dirr[t] = tile
    h = tile * 64 + loc
    nxt[i] = heads[h]
    heads[h] = i
    return heads


@jit
def _mark(i, pts, dim, size, gi, words, start, blocks, cells, field):
    """Mark particle i in the maps and the field, with its periodic images
    near the edges."""
    W = gi[9]
    reach = 1 if gi[10] == 1 else 0
    reach2 = reach if dim == 3 else 0
    for a in range(-reach, reach + 1):
        for b in range(-reach2, reach2 + 1):
            i0 = int(np.floor(pts[i, 0] + a * size)) + gi[6]
            i1 = int(np.floor(pts[i, 1] + (b * size if dim == 3 else 0.0))) + gi[7]
            i2 = int(np.floor(pts[i, 2])) + gi[8] if dim == 3 else 0
            if 0 <= i0 < W and 0 <= i1 < W and 0 <= i2 < W:
                # a coarse cell that already holds a particle has every level from
                # 2 up (cells of side >= 2**FS) and the field marked: only level 1 is left
                fw = (W + (1 << FS) - 1) >> FS
                ci, cj, ck = i0 >> FS, i1 >> FS, i2 >> FS
                fresh = field[ci + fw * (cj + fw * ck)] != 0
                _mark_levels(words, dim, start, blocks, cells, i0, i1, i2, len(cells) if fresh else FS)
                if fresh:
                    maps.field_lower(field, dim, fw, gi[17], ci, cj, ck)


@jit
def _allocate_maps(dim, width):
    """The dilated maps of ``maps`` for a grid of side ``width``, levels 1 and up.

    Level 0 (plain occupancy, a bit per unit cell and three quarters of the
    bits) is never queried here: contacts come from the cell list. ``start``
    is shifted so that level s still begins at ``start[s]``.
    """
    start, blocks, cells = maps.layout(dim, width)
    start -= start[min(1, len(cells) - 1)]
    return maps.filled(start[-1], 0, np.uint64), start, blocks, cells


@jit
def _mark_levels(words, dim, start, blocks, cells, i, j, k, top):
    """Set cell (i, j, k) and its neighbours in the dilated levels 1 to top - 1."""
    bs = 3 if dim == 2 else 2
    bm = (1 << bs) - 1
    for s in range(1, top):
        w = cells[s]
        nb = blocks[s]
        ci, cj, ck = i >> s, j >> s, k >> s
        klo, khi = (max(ck - 1, 0), min(ck + 1, w - 1)) if dim == 3 else (0, 0)
        for c in range(klo, khi + 1):
            for b in range(max(cj - 1, 0), min(cj + 1, w - 1) + 1):
                for a in range(max(ci - 1, 0), min(ci + 1, w - 1) + 1):
                    q = start[s] + (a >> bs) + nb * ((b >> bs) + nb * (c >> bs))
                    words[q] |= np.uint64(1) << np.uint64((a & bm) | ((b & bm) << bs) | ((c & bm) << (2 * bs)))


@jit
def _build_grid(dim, line, size, need, pts, count, nxt, tiles):
    """Maps and cell list for particles 0..count-1, sized for ``need``, with
    room for ``tiles`` cell-list tiles (the old grid's count: few change)."""
    gi, gf = _layout(dim, line, size, need)
    words, start, blocks, cells = _allocate_maps(dim, gi[9])
    ntiles = gi[3] * gi[4] * gi[5]
    dirr = maps.filled(ntiles, -1, np.int32)
    heads = maps.filled(64 * (tiles + tiles // 4 + 64), -1, np.int32)
    field = maps.filled(((gi[9] + (1 << FS) - 1) >> FS) ** dim, gi[17], np.uint8)
    for i in range(count):
        heads = _insert(i, pts, nxt, dim, gi, gf, dirr, heads)
        _mark(i, pts, dim, size, gi, words, start, blocks, cells, field)
    return gi, gf, words, start, blocks, cells, dirr, heads, field


@jit
def _map_dist(w, dim, size, gi, words, start, blocks, cells, field):
    """Lower bound on the centre distance from w to every particle, from the
    distance field and the maps.

    A field value d > 1 puts every particle centre d - 1 whole coarse cells
    beyond w's coarse cell, so (d - 1) 2**FS plus w's distance to its own
    coarse cell's faces bounds it. Where the field says little (d <= 1, or at
    its cap), the largest clear map level s puts every particle outside the
    3**dim block of level-s cells around w: 2**s plus w's distance to its
    level-s cell's faces. Returns 0 when the level-1 cell is set (look
    closer), -1 off the map. (``_walk`` spells this out inline.)
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
    fw = (W + (1 << FS) - 1) >> FS
    fd = np.int64(field[(i0 >> FS) + fw * ((i1 >> FS) + fw * (i2 >> FS))])
    dm = 0.0
    if fd > 1:
        side = float(1 << FS)
        c = float((i0 >> FS) << FS)
        f = min(X0 - c, c + side - X0)
        c = float((i1 >> FS) << FS)
        f = min(f, X1 - c, c + side - X1)
        if dim == 3:
            c = float((i2 >> FS) << FS)
            f = min(f, X2 - c, c + side - X2)
        dm = (fd - 1) * side + f
    if 1 < fd < gi[17]:
        return dm
    bs = 3 if dim == 2 else 2
    bm = (1 << bs) - 1
    lo, hi = 0, min(len(cells) - 1, gi[15]) + 1  # clear at lo, set at hi
    while hi - lo > 1:
        s = (lo + hi) >> 1
        j0, j1, j2 = i0 >> s, i1 >> s, i2 >> s
        nb = blocks[s]
        word = words[start[s] + (j0 >> bs) + nb * ((j1 >> bs) + nb * (j2 >> bs))]
        if (word >> np.uint64((j0 & bm) | ((j1 & bm) << bs) | ((j2 & bm) << (2 * bs)))) & np.uint64(1):
            hi = s
        else:
            lo = s
    s = lo
    if s == 0:
        return dm
    side = float(1 << s)
    c = float((i0 >> s) << s)
    f = min(X0 - c, c + side - X0)
    c = float((i1 >> s) << s)
    f = min(f, X1 - c, c + side - X1)
    if dim == 3:
        c = float((i2 >> s) << s)
        f = min(f, X2 - c, c + side - X2)
    return max(dm, side + f)


@inline
def _span(v, r, nc, periodic, origin, inv):
    """Index cells covering [v - r, v + r] on one axis (may wrap if periodic)."""
    lo = int(np.floor((v - r - origin) * inv))
    hi = int(np.floor((v + r - origin) * inv))
    if periodic:
        return lo, min(hi, lo + nc - 1)
    return max(lo, 0), min(hi, nc - 1)


@inline
def _gather(c, r, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li):
    """Particles with centres within r of point c, as the images nearest c.

    Fills lx, ly, lz (coordinates) and li (indices); returns the count and
    the smallest squared centre distance among them (inf when none). Inlined,
    so that the walk's hot loop pays no reference counting for its arrays.
    """
    r2 = r * r
    nl = 0
    near2 = INF
    lo0, hi0 = _span(c[0], r, gi[0], gi[10] == 1, gf[0], gf[3])
    lo1, hi1 = _span(c[1], r, gi[1], gi[11] == 1, gf[1], gf[4])
    lo2, hi2 = 0, 0
    if dim == 3:
        lo2, hi2 = _span(c[2], r, gi[2], False, gf[2], gf[5])
    p0 = gi[10] == 1
    p1 = gi[11] == 1
    n0, n1, t0, t1 = gi[0], gi[1], gi[3], gi[4]
    tb = gi[13]
    m = (1 << tb) - 1
    half = 0.5 * size
    for k2 in range(lo2, hi2 + 1):
        for k1 in range(lo1, hi1 + 1):
            c1 = k1 % n1 if p1 else k1
            for k0 in range(lo0, hi0 + 1):
                c0 = k0 % n0 if p0 else k0
                tile = dirr[(c0 >> tb) + t0 * ((c1 >> tb) + t1 * (k2 >> tb))]
                if tile < 0:
                    continue
                h = heads[tile * 64 + ((c0 & m) | ((c1 & m) << tb) | ((k2 & m) << (2 * tb)))]
                while h >= 0:
                    d0 = pts[h, 0] - c[0]
                    d1 = pts[h, 1] - c[1]
                    d2 = pts[h, 2] - c[2] if dim == 3 else 0.0
                    if p0:
                        if d0 > half:
                            d0 -= size
                        elif d0 < -half:
                            d0 += size
                    if p1:
                        if d1 > half:
                            d1 -= size
                        elif d1 < -half:
                            d1 += size
                    q = d0 * d0 + d1 * d1 + d2 * d2
                    if q < r2 and nl < len(lx):
                        lx[nl] = c[0] + d0
                        ly[nl] = c[1] + d1
                        lz[nl] = c[2] + d2
                        li[nl] = h
                        nl += 1
                        near2 = min(near2, q)
                    h = nxt[h]
    return nl, near2


@jit
def _ray(w, u, length, nl, lx, ly, lz, line, dim):
    """First contact along w + t u, 0 <= t <= length: (t, k).

    k indexes the listed centres, -2 is the substrate (line seed: centres
    touch it at up = 0), -1 means no contact.
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
    if line:
        up = dim - 1
        if u[up] < 0.0:
            t = max(0.0, -w[up] / u[up])
            if t <= best:
                best = t
                hit = -2
    return best, hit


@jit
def _settle(w, u, t, hit, dim, lx, ly, lz, normal):
    """Move w to w + t u and put it at distance 1 exactly from what it hit;
    ``normal`` gets the outward unit normal at the contact."""
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

    Long rays go in pieces of at most 2 so the gathered lists stay short.
    Returns True on contact (w then at contact, ``normal`` set).
    """
    c = normal  # scratch until a contact sets it
    left = length
    while left > 0.0:
        piece = min(left, 2.0)
        left -= piece
        for a in range(3):
            c[a] = w[a] + 0.5 * piece * u[a]
        nl = _gather(c, 0.5 * piece + 1.0, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li)[0]
        t, hit = _ray(w, u, piece, nl, lx, ly, lz, line, dim)
        if hit != -1:
            _settle(w, u, t, hit, dim, lx, ly, lz, normal)
            return True
        for a in range(3):
            w[a] += piece * u[a]
    return False


@jit
def _gauss_move(w, sigma, dim, size, line, rng, pts, nxt, gi, gf, dirr, heads, words, start, blocks,
                cells, field, lx, ly, lz, li, e, u, normal):
    """One Gaussian step with the naive end-point check; True on contact.

    The step is proposed from w; if its end point is free it is taken, even
    when the straight path crosses a branch (tunnelling). If the end point
    overlaps, the walker is put back along the step to where it first touches
    one of the particles it overlaps there (exact contact); should that spot
    overlap another particle, a full ray cast along the step decides.
    """
    up = dim - 1
    for a in range(dim):
        e[a] = w[a] + sigma * rng.normal()
    sub = line and e[up] < 0.0
    if not sub and _map_dist(e, dim, size, gi, words, start, blocks, cells, field) > 0.0:
        for a in range(dim):
            w[a] = e[a]
        return False
    nov = _gather(e, 1.0, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li)[0]
    if nov == 0 and not sub:
        for a in range(dim):
            w[a] = e[a]
        return False
    length = 0.0
    for a in range(3):
        u[a] = e[a] - w[a] if a < dim else 0.0
        length += u[a] * u[a]
    length = np.sqrt(length)
    for a in range(dim):
        u[a] /= length
    t, hit = _ray(w, u, length * (1.0 + 1e-9) + 1e-12, nov, lx, ly, lz, sub, dim)
    if hit != -1:
        p = np.empty(3)
        for a in range(3):
            p[a] = w[a]
        _settle(p, u, t, hit, dim, lx, ly, lz, normal)
        if _gather(p, 1.0 - 1e-12, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li)[0] == 0:
            for a in range(3):
                w[a] = p[a]
            return True
    return _cast(w, u, length, dim, size, line, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li, normal)


@jit
def _contact(w, u, normal, dim, size, line, stick, rng, rs, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li):
    """A walker at contact: sticks with probability ``stick`` (True), else
    moves away by ``REJECT`` into the outward half-space, ray-cast, and
    tries again at every new contact. Returns (stuck, moves made)."""
    moves = 0
    while True:
        if stick >= 1.0 or rng.random() < stick:
            return True, moves
        unit_vector(rs, dim, u)
        dot = u[0] * normal[0] + u[1] * normal[1] + u[2] * normal[2]
        if dot < 0.0:
            for a in range(3):
                u[a] -= 2.0 * dot * normal[a]
        moves += 1
        if not _cast(w, u, REJECT, dim, size, line, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li, normal):
            return False, moves


# --------------------------------------------------------------- growth -----


@jit
def _walk(w, u, normal, scratch, anchor, lx, ly, lz, li, mx, my, mz, mi, pts, nxt, gi, gf, words, start,
          blocks, cells, dirr, heads, field, geo, ip, fp, cnt, rs, rng):
    """Release walkers until one sticks (returns 1, w at its place) or the
    step budget runs out (returns 2).

    Every array is an argument (borrowed, no reference counting) and the hot
    path calls no array-taking helper; see the module note. ``cnt`` holds
    the total steps and the steps since the last attachment.
    """
    dim, line, size = ip[0], ip[1] == 1, ip[2]
    launch_box, boxed, ceiling = ip[3] == 1, ip[4] == 1, ip[5] == 1
    ret, kill, jumps, max_steps = ip[6] == 1, ip[7] == 1, ip[8] == 1, ip[9]
    R, Rk, hb, sigma, stick = fp[0], fp[1], fp[2], fp[3], fp[4]
    R2 = R * R
    RL = LIST_RADIUS
    if line:
        RL = min(RL, hb)  # a ball of radius <= size/2 holds one image of each particle
    RL2 = RL * RL
    up = dim - 1
    rmax, cmax, hmax = geo[0], geo[1], geo[2]
    # map geometry
    W = float(gi[9])
    m0, m1, m2 = float(gi[6]), float(gi[7]), float(gi[8])
    per = gi[10] == 1
    ftop = min(len(cells) - 1, gi[15]) + 1
    bs = 3 if dim == 2 else 2
    bm = (1 << bs) - 1
    fw = (gi[9] + (1 << FS) - 1) >> FS
    fcap = gi[17]
    fside = float(1 << FS)
    # a field at its cap puts every particle (cap - 1) coarse cells away, so
    # the map levels whose 3**dim blocks fit inside that are clear
    flo = 1
    while flo + 1 < ftop and (2 << (flo + 1)) <= (fcap - 1) << FS:
        flo += 1
    s0, s1, s2, s3 = rs[0], rs[1], rs[2], rs[3]
    total = cnt[0]
    since = cnt[1]
    code = 0
    while code == 0:
        # ---- release
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
            s0, s1, s2, s3, u0, u1, u2 = xdir(s0, s1, s2, s3, dim)
            w[0] = R * u0
            w[1] = R * u1
            w[2] = R * u2
        list_ok = False
        nl = 0
        while True:
            if max_steps > 0 and total >= max_steps:
                code = 2
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
                ggeo = h - hmax - 1.0
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
                ggeo = max(r - rmax, ch - cmax) - 1.0
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
                # the field and the maps (as _map_dist, spelled out)
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
                if 0.0 <= X0 < W and 0.0 <= X1 < W and 0.0 <= X2 < W:
                    i0, i1, i2 = int(X0), int(X1), int(X2)
                    fd = np.int64(field[(i0 >> FS) + fw * ((i1 >> FS) + fw * (i2 >> FS))])
                    dm = 0.0
                    if fd > 1:
                        # no particle in the coarse cells within fd - 1 of the walker's
                        c = float((i0 >> FS) << FS)
                        f = min(X0 - c, c + fside - X0)
                        c = float((i1 >> FS) << FS)
                        f = min(f, X1 - c, c + fside - X1)
                        if dim == 3:
                            c = float((i2 >> FS) << FS)
                            f = min(f, X2 - c, c + fside - X2)
                        dm = (fd - 1) * fside + f
                    # the maps where the field says little: a particle within two
                    # coarse cells sets every level from 3 up; at the cap, levels
                    # up to flo are clear
                    lo, hi = 0, 0
                    if fd <= 1:
                        hi = min(ftop, 3)
                    elif fd >= fcap:
                        lo, hi = flo, ftop
                    while hi - lo > 1:
                        s = (lo + hi) >> 1
                        j0, j1, j2 = i0 >> s, i1 >> s, i2 >> s
                        nb = blocks[s]
                        word = words[start[s] + (j0 >> bs) + nb * ((j1 >> bs) + nb * (j2 >> bs))]
                        bit = (j0 & bm) | ((j1 & bm) << bs) | ((j2 & bm) << (2 * bs))
                        if (word >> np.uint64(bit)) & np.uint64(1):
                            hi = s
                        else:
                            lo = s
                    if lo > 0:
                        side = float(1 << lo)
                        c = float((i0 >> lo) << lo)
                        f = min(X0 - c, c + side - X0)
                        c = float((i1 >> lo) << lo)
                        f = min(f, X1 - c, c + side - X1)
                        if dim == 3:
                            c = float((i2 >> lo) << lo)
                            f = min(f, X2 - c, c + side - X2)
                        dm = max(dm, side + f)
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
                    nl, dl2 = _gather(anchor, RL, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li)
                    g = (np.sqrt(dl2) if dl2 < RL2 else RL) - 1.0
            if line:
                g = min(g, w[up])
            g = min(g, gb)
            # ---- move
            if sigma == 0.0 and jumps and g >= EPS:
                s0, s1, s2, s3, u0, u1, u2 = xdir(s0, s1, s2, s3, dim)
                w[0] += g * u0
                w[1] += g * u1
                w[2] += g * u2
                total += 1
                since += 1
                continue
            contact = False
            if sigma == 0.0 and jumps:
                # inside the shell: a short exact ray cast against the list
                d0 = w[0] - anchor[0]
                d1 = w[1] - anchor[1]
                d2 = w[2] - anchor[2]
                if not list_ok or RL - np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) < 1.0 + RAY + 1e-9:
                    anchor[0] = w[0]
                    anchor[1] = w[1]
                    anchor[2] = w[2]
                    nl = _gather(anchor, RL, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li)[0]
                    list_ok = True
                s0, s1, s2, s3, u0, u1, u2 = xdir(s0, s1, s2, s3, dim)
                total += 1
                since += 1
                best = RAY
                hit = -1
                for k in range(nl):
                    d0 = w[0] - lx[k]
                    d1 = w[1] - ly[k]
                    d2 = w[2] - lz[k]
                    b = u0 * d0 + u1 * d1 + u2 * d2
                    if b >= 0.0:
                        continue
                    cc = d0 * d0 + d1 * d1 + d2 * d2 - 1.0
                    disc = b * b - cc
                    if disc < 0.0:
                        continue
                    t = max(0.0, cc / (np.sqrt(disc) - b))
                    if t <= best:
                        best = t
                        hit = k
                uu = u2 if dim == 3 else u1
                if line and uu < 0.0:
                    t = max(0.0, -w[up] / uu)
                    if t <= best:
                        best = t
                        hit = -2
                u[0], u[1], u[2] = u0, u1, u2
                if hit == -1:
                    for a in range(3):
                        w[a] += best * u[a]
                    continue
                _settle(w, u, best, hit, dim, lx, ly, lz, normal)  # once per contact: a call is cheap here
                contact = True
            elif sigma == 0.0:
                # single unit steps everywhere (jumps=false)
                s0, s1, s2, s3, u[0], u[1], u[2] = xdir(s0, s1, s2, s3, dim)
                total += 1
                since += 1
                if g > 1.0:
                    for a in range(3):
                        w[a] += u[a]
                    continue
                contact = _cast(w, u, 1.0, dim, size, line, pts, nxt, gi, gf, dirr, heads, mx, my, mz, mi, normal)
            else:
                if jumps and g > GAUSS_JUMP * sigma:
                    s0, s1, s2, s3, u0, u1, u2 = xdir(s0, s1, s2, s3, dim)
                    w[0] += g * u0
                    w[1] += g * u1
                    w[2] += g * u2
                    total += 1
                    since += 1
                    continue
                total += 1
                since += 1
                list_ok = False
                if _gauss_move(w, sigma, dim, size, line, rng, pts, nxt, gi, gf, dirr, heads, words, start,
                               blocks, cells, field, mx, my, mz, mi, scratch, u, normal):
                    if stick >= 1.0 or rng.random() < stick:
                        code = 1
                        break
                continue
            if not contact:
                continue
            if stick >= 1.0:
                code = 1
                break
            rs[0], rs[1], rs[2], rs[3] = s0, s1, s2, s3
            stuck, moves = _contact(w, u, normal, dim, size, line, stick, rng, rs, pts, nxt, gi, gf, dirr, heads,
                                    mx, my, mz, mi)
            s0, s1, s2, s3 = rs[0], rs[1], rs[2], rs[3]
            total += moves
            since += moves
            list_ok = False
            if stuck:
                code = 1
                break
    rs[0], rs[1], rs[2], rs[3] = s0, s1, s2, s3
    cnt[0] = total
    cnt[1] = since
    return code


@jit
def _attach(w, count, since, pts, steps, nxt, geo, dim, line, size, grid):
    """Add the walker at w to the cluster; returns the new count, the grid
    and whether the cluster outgrew it (then the particle is not yet in it:
    the caller drops the grid and builds a larger one)."""
    gi, gf, words, start, blocks, cells, dirr, heads, field = grid
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
        return count, grid, True
    heads = _insert(count - 1, pts, nxt, dim, gi, gf, dirr, heads)
    _mark(count - 1, pts, dim, size, gi, words, start, blocks, cells, field)
    return count, (gi, gf, words, start, blocks, cells, dirr, heads, field), False


@jit
def _no_grid():
    """An empty grid: the caller drops its old grid's arrays by taking this
    before it builds the new one, so the two are never held at once."""
    z = np.zeros(1, np.int64)
    return (np.zeros(18, np.int64), np.zeros(8), np.zeros(0, np.uint64), z, z, z, np.zeros(0, np.int32),
            np.zeros(0, np.int32), np.zeros(0, np.uint8))


@jit
def _grow(n, dim, shape, size, launch_box, lf, lm, kf, jumps, sigma, nwalk, max_steps, stick, marks, rng, times):
    t0 = clock()
    line = shape == LINE
    nm = len(marks)
    nseed = 0 if line else (1 if shape == POINT else 1 << dim)
    cap = max(n, 1)
    pts = maps.filled(cap * dim, 0.0, np.float64).reshape((cap, dim))
    steps = maps.filled(cap, 0, np.int64)
    nxt = maps.filled(cap, -1, np.int32)
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
    grid = _build_grid(dim, line, size, max(geo[2], 0.0) if line else geo[1], pts, count, nxt, 0)
    rs = seed_stream(rng)
    km = 0
    while km < nm and marks[km] <= count:
        times[km] = clock() - t0
        km += 1
    if nwalk > 1:
        return _lockstep(n, dim, line, size, sigma, nwalk, max_steps, stick, marks, rng, rs, t0, times, km,
                         pts, steps, nxt, count, geo, grid)
    w = np.zeros(3)
    u = np.zeros(3)
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
    hb = 0.5 * size
    boxed = size > 0 and not line
    ret = kf == 0.0 and not launch_box and (line or size == 0)
    kill = kf > 0.0 and not launch_box
    ip = np.array([dim, line, size, launch_box, boxed, line and launch_box, ret, kill, jumps, max_steps], np.int64)
    fp = np.array([0.0, 0.0, hb, sigma, stick])
    cnt = np.zeros(2, np.int64)
    status = OK
    while count < n:
        R = lf * (max(geo[2], 0.0) if line else geo[0]) + lm
        if launch_box:
            if (line and geo[2] >= size - 2.0) or (not line and geo[1] >= hb - 2.0):
                status = BOUNDARY
                break
        elif boxed and R > hb - 1.0:
            status = BOUNDARY
            break
        fp[0] = R
        fp[1] = kf * R
        gi, gf, words, start, blocks, cells, dirr, heads, field = grid
        code = _walk(w, u, normal, scratch, anchor, lx, ly, lz, li, mx, my, mz, mi, pts, nxt, gi, gf, words, start,
                     blocks, cells, dirr, heads, field, geo, ip, fp, cnt, rs, rng)
        if code == 2:
            status = STEP_LIMIT
            break
        count, grid, full = _attach(w, count, cnt[1], pts, steps, nxt, geo, dim, line, size, grid)
        if full:
            tiles = gi[14]
            grid = _no_grid()
            gi, gf, words, start, blocks, cells, dirr, heads, field = grid
            grid = _build_grid(dim, line, size, geo[2] if line else geo[1], pts, count, nxt, tiles)
        cnt[1] = 0
        while km < nm and marks[km] <= count:
            times[km] = clock() - t0
            km += 1
    return pts, steps, count, status, times


@jit
def _lockstep(n, dim, line, size, sigma, nwalk, max_steps, stick, marks, rng, rs, t0, times, km,
              pts, steps, nxt, count, geo, grid):
    """Finite concentration: ``nwalk`` walkers start uniformly in the box and
    take single steps in turn; none is relaunched."""
    up = dim - 1
    nm = len(marks)
    hb = 0.5 * size
    gi, gf, words, start, blocks, cells, dirr, heads, field = grid
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
            if _gather(pos[k], 1.0, dim, size, pts, nxt, gi, gf, dirr, heads, mx, my, mz, mi)[0] == 0:
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
            dm = _map_dist(w, dim, size, gi, words, start, blocks, cells, field)
            if dm == 0.0 and _gather(w, 1.0 - 1e-12, dim, size, pts, nxt, gi, gf, dirr, heads, mx, my, mz, mi)[0] > 0:
                alive[k] = False  # a particle attached on top of it: merged
                live -= 1
                continue
            total += 1
            since += 1
            if sigma == 0.0:
                unit_vector(rs, dim, u)
                if dm > 2.0:
                    for a in range(3):
                        w[a] += u[a]
                    contact = False
                else:
                    contact = _cast(w, u, 1.0, dim, size, line, pts, nxt, gi, gf, dirr, heads, mx, my, mz, mi, normal)
            else:
                contact = _gauss_move(w, sigma, dim, size, line, rng, pts, nxt, gi, gf, dirr, heads, words, start,
                                      blocks, cells, field, mx, my, mz, mi, e, u, normal)
            stuck = False
            if contact:
                if sigma > 0.0:
                    stuck = stick >= 1.0 or rng.random() < stick
                else:
                    stuck, moves = _contact(w, u, normal, dim, size, line, stick, rng, rs, pts, nxt, gi, gf, dirr,
                                            heads, mx, my, mz, mi)
                    total += moves
                    since += moves
            if stuck:
                count, grid, full = _attach(w, count, since, pts, steps, nxt, geo, dim, line, size, grid)
                if full:
                    tiles = gi[14]
                    grid = _no_grid()
                    gi, gf, words, start, blocks, cells, dirr, heads, field = grid
                    grid = _build_grid(dim, line, size, geo[2] if line else geo[1], pts, count, nxt, tiles)
                gi, gf, words, start, blocks, cells, dirr, heads, field = grid
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


def grow_offlattice(n, p, marks, rng, times=None):
    """Grow an off-lattice cluster; see ``dlasweep.grow`` for the meaning.

    ``times``, if given, is filled as the marks pass (NaN before), so that
    another thread can watch the growth.

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
        np.asarray(marks, np.int64), rng, np.full(len(marks), np.nan) if times is None else times,
    )
    if count < len(pts):
        pts = pts[:count].copy()
        steps = steps[:count].copy()
    return pts, steps, int(status), times
