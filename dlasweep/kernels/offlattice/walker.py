"""The off-lattice walker: its release, its walk from release to contact
(``walk``), and the attachment of the particle it becomes.

Far from the cluster a walker moves by walk-on-spheres jumps onto the
sphere whose radius is a lower bound on its free distance (``grid``:
field, maps, and the cluster's bounding circle); where the centre pyramid
gives that bound, out of the larger ball about the centre of its cell that
holds no particle, by the exact exit law (``walk.ball_exit``). Near it, exact nearest
distances come from a neighbour list of radius ``LIST_RADIUS`` gathered
around an anchor point: while the walker stays near the anchor its free
distance is a minimum over a handful of centres. Inside the ``EPS`` shell
it moves by ``RAY`` with an exact ray cast (``contact``). Under a drift
(``model.drift``) every move from a sphere's centre draws its direction from
the drifted exit law (``walk.drift_dir``), and the off-centre ball exit gives
way to the sphere about the walker.
"""

import numpy as np
from numba import literally

from ..._jit import borrow, jit
from .. import maps
from .. import model as codes
from ..centres import FS, cell_centre, centre_bound, pyramid_ball
from ..model import diffusion_time, sticks
from ..walk import ball_exit, drift_dir, drift_to_plane, return_to_plane, return_to_sphere, xdir
from .celllist import INF, gather, insert, more_heads
from .contact import EPS, RAY, REJECT, cast, gauss_move, ray_to, rebound, settle
from .geometry import COVERED, TILES_USED
from .grid import FAR_CLEAR, NEAR, face_gap, mark, walk_geometry

LIST_RADIUS = 3.0
"""Radius (centre distance) of the cached neighbour list. Longer lists give
longer exact jumps and serve longer, but a gather visits (r + 1)**dim cells
of linked lists; 3 is where the two balance in 2D and 3D (the radii tried:
docs/performance.md)."""
LCAP = 1024
"""Capacity of the neighbour lists (a packing within radius 6 in 2D or 3 in
3D holds < 200)."""
LCAP_CLOSE = 4096
"""Capacity of the neighbour lists where particles lie closer than a diameter (``contact_distance`` below 1,
at least ``params.MIN_CONTACT_DISTANCE``, 0.5): centres at least 0.5 apart, within radius 3 in 3D, number
about 8 times a unit packing's (under 200), with room for the cells' heads."""
GAUSS_JUMP = 4.0
"""With step > 0 and jumps, walk-on-spheres only beyond this many step stds."""


@jit
def neighbour_list(contact_distance=1.0):
    """Empty arrays for ``celllist.gather`` to fill: x, y, z (z stays 0 in 2D) and indices.

    Parameters
    ----------
    contact_distance : float
        The model's ``contact_distance``: below 1 particles lie closer than a diameter, and the
        lists hold ``LCAP_CLOSE`` entries, else ``LCAP``.
    """
    cap = LCAP if contact_distance == 1.0 else LCAP_CLOSE
    return np.empty(cap), np.empty(cap), np.zeros(cap), np.empty(cap, np.int64)


@borrow
def release(w, dim, size, line, launch_box, launch_r, rng, s0, s1, s2, s3):
    """Put a new walker at w: uniformly on the launch circle (sphere), on the
    launch line (plane) above a substrate, or, with ``launch_box``, on the
    box's faces (its top face above a substrate). Returns the stream state
    (registers: see ``walk.xdir``).

    Parameters
    ----------
    w : float64 (3,)
        Receives the walker's place.
    dim : int
        2 or 3.
    size : int
        The box's side, or a substrate's period.
    line : bool
        Whether the seed is a substrate.
    launch_box : bool
        Whether walkers start on the box's faces.
    launch_r : float
        The launch radius (a substrate's: launch height).
    rng : numpy.random.Generator
        Draws the place on a line or box.
    s0, s1, s2, s3 : uint64
        The xoshiro256+ state that draws a direction on the launch circle.
    """
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
def walk_to_contact(dimension, gaussian, model, launch_r, kill_r, total, pending, w, u, normal, scratch, anchor,
                    lx, ly, lz, li, mx, my, mz, mi, pts, nxt, gi, gf, words, start, blocks, cells, dirr, heads,
                    field, pstart, geo, rs, rng):
    """Release walkers until one sticks or the step budget runs out.

    One walker at a time, released (``release``) and walked to contact; a
    walker absorbed by the kill sphere or a wall, or escaped in 3D, is
    replaced by a new one. Each pass of the loop finds a lower bound ``g`` on
    the walker's free distance (surface gap): exact from the cached neighbour
    list while the walker stays within it, else from the map query
    (``grid.walk_bound``, spelled out inline and pinned by
    ``tests/test_pins.py``), the centre pyramid's ball and the cluster's
    bounding circle, and then moves: out of the pyramid cell's ball
    (``walk.ball_exit``), onto the sphere of radius ``g``, by a ray cast of
    length ``RAY`` inside the ``EPS`` shell, by a unit step (no jumps), or by a
    Gaussian step (``model.step`` > 0).

    It is shaped for its speed: every array is an argument, borrowed
    (``_jit.borrow``: no reference counting, nothing allocated here: see the
    package note); the stream's state stays in registers (``s0`` .. ``s3``)
    and is written back to ``rs`` around the calls that draw from it; the map
    query is spelled out rather than called. One walker is in flight at a
    time: interleaving two walkers' steps, so that their memory reads
    overlap, would save no more than keeping their two states costs
    (docs/performance.md).

    Parameters
    ----------
    dimension : int
        The model's dimension (2 or 3), a literal (``numba.literally``): each
        dimension is compiled apart, so that LLVM folds the branches on
        ``dim`` away (``_jit``; docs/performance.md has the gain).
    gaussian : None or True
        ``model.gaussian_flag(model.step)``: the Gaussian step (``contact.gauss_move``) is compiled in
        only where it runs.
    model : Model
        The model (``kernels.model.Model``): size, step, stickiness, jumps,
        step budget, exact return, kill, seed shape and launch.
    launch_r : float
        Launch radius now (a substrate's: launch height).
    kill_r : float
        Kill radius now (a substrate's: kill height); read only with ``model.kill``.
    total : int
        Steps taken in all before this call; the budget ``model.max_steps`` counts these.
    pending : int
        Steps since the last attachment: the new particle's diffusion time.
    w : float64 (3,)
        Scratch for the walker's place; receives where it sticks (z 0 in 2D).
    u : float64 (3,)
        Scratch for a move's direction; holds the last ray's direction at a contact.
    normal : float64 (4,)
        Receives, at a contact, the outward unit normal and, in ``normal[3]``,
        the row of the particle touched (-1: the substrate; ``contact.settle``).
    scratch : float64 (3,)
        Scratch for the exact return (``walk.return_to_sphere``) and the Gaussian step.
    anchor : float64 (3,)
        Scratch: the point the neighbour list was gathered about.
    lx, ly, lz : float64 (LCAP,)
        The neighbour list's centres, the images nearest ``anchor``
        (``neighbour_list``, filled by ``celllist.gather``).
    li : int64 (LCAP,)
        The neighbour list's rows of ``pts``.
    mx, my, mz : float64 (LCAP,)
        A second list's centres, scratch for the casts straight from the cell
        list (``contact.cast``, ``contact.gauss_move``, ``contact.rebound``).
    mi : int64 (LCAP,)
        The second list's rows.
    pts : float64 (n, dim)
        The particles' centres, row by row (rows by cell in 3D: ``celllist.sort_cells``).
    nxt : int32 (n,)
        The cell list's links through the rows (``celllist``).
    gi : int64 (GI_SLOTS,)
        The grid's integer geometry (``geometry.layout``).
    gf : float64 (GF_SLOTS,)
        The grid's float geometry.
    words : uint64 (...)
        The dilated maps (``grid._allocate_maps``).
    start : int64 (S + 1,)
        Where each map level starts in ``words``.
    blocks : int64 (S,)
        Words a side of each map level.
    cells : int64 (S,)
        Cells a side of each map level.
    dirr : int32 (...)
        The cell list's directory of tiles (``celllist``).
    heads : int32 (...)
        The cell list's heads, 64 a tile in use.
    field : uint8 (...)
        The centre field with the centre pyramid above it (``centres``).
    pstart : int64 (L + 1,)
        Where each level of ``field`` starts (``grid.level_starts``).
    geo : float64 (3,)
        The cluster's r_max, Chebyshev extent and h_max.
    rs : uint64 (4,)
        The xoshiro256+ stream of the walk's directions, read at the start and written back.
    rng : numpy.random.Generator
        Draws the releases on a line or box, the exact returns, the sticking
        and the Gaussian steps.

    Returns
    -------
    stuck : bool
        True when a walker stuck at w, False when the budget ran out.
    total : int
        Steps taken in all.
    pending : int
        Steps since the last attachment.
    """
    literally(dimension)
    dim = np.int64(2) if dimension == 2 else np.int64(3)  # a constant, not a literal (``_jit``)
    size, step, stickiness = model.size, model.step, model.stickiness
    jumps, max_steps, ret, kill = model.jumps, model.max_steps, model.exact_return, model.kill
    line = model.seed_shape == codes.LINE
    launch_box = model.launch_box
    drift, mu0, mu1, mu2 = model.drift, model.drift_x, model.drift_y, model.drift_z
    a0, a1, a2 = (mu0 / drift, mu1 / drift, mu2 / drift) if drift > 0.0 else (0.0, 0.0, 0.0)  # its direction
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
        s0, s1, s2, s3 = release(w, dim, size, line, launch_box, launch_r, rng, s0, s1, s2, s3)
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
                    if drift > 0.0:
                        drift_to_plane(rng, dim, w, launch_r, size, mu0, mu1, mu2)
                    else:
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
                if not line:  # a square root, taken only where the list does not decide (docs/performance.md)
                    ggeo = max(np.sqrt(r2) - r_max, ch - extent) - 1.0
                # >>> walk_bound, spelled out: numba's inlining of it is slower (docs/performance.md; a
                # test holds the two texts together, and walk_bound to map_dist)
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
            if (not exact and ball > 0.0 and g == ball - gap - 1.0 and gb >= ball + gap and step == 0.0 and jumps
                    and drift == 0.0):
                # out of the ball about the pyramid cell's centre, which holds the one about w (not from its
                # centre: under a drift, the sphere about w below instead)
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
                # holds the copies together): one condition for both is slower
                # (docs/performance.md), so the tested shape stays
                s0, s1, s2, s3, u0, u1, u2 = drift_dir(s0, s1, s2, s3, dim, drift * g, a0, a1, a2)
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
                s0, s1, s2, s3, u0, u1, u2 = drift_dir(s0, s1, s2, s3, dim, drift * RAY, a0, a1, a2)
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
                s0, s1, s2, s3, u[0], u[1], u[2] = drift_dir(s0, s1, s2, s3, dim, drift, a0, a1, a2)
                total += 1
                pending += 1
                if g > 1.0:
                    for a in range(3):
                        w[a] += u[a]
                    continue
                contact = cast(w, u, 1.0, dim, size, line, pts, nxt, gi, gf, dirr, heads, mx, my, mz, mi, normal)
            elif gaussian is not None:  # numba prunes the branch for step 0 (``model.gaussian_flag``)
                if jumps and g > GAUSS_JUMP * step:
                    # >>> jump
                    s0, s1, s2, s3, u0, u1, u2 = drift_dir(s0, s1, s2, s3, dim, drift * g, a0, a1, a2)
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
                              blocks, cells, field, mx, my, mz, mi, scratch, u, normal, mu0 * step * step,
                              mu1 * step * step, mu2 * step * step) and sticks(stickiness, rng):
                    code = 1
                    break
                continue
            if not contact:
                continue
            rs[0], rs[1], rs[2], rs[3] = s0, s1, s2, s3
            stuck, moves = rebound(w, u, normal, dim, size, line, stickiness, rng, rs, pts, nxt, gi, gf, dirr, heads,
                                   mx, my, mz, mi, drift * REJECT, a0, a1, a2)
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
"""``attach``: the particle is in the grid."""
HEADS_FULL = -2
"""``attach``: the particle waits for the cell list's heads to grow (``index_late``)."""


@borrow
def attach(w, parent, count, pending, pts, order, steps, parents, nxt, geo, dim, line, size, gi, gf, words, start,
           blocks, cells, dirr, heads, field):
    """Add the walker at w to the cluster, its parent the particle it touched
    (``contact.settle`` records its row of ``pts``; ``order`` holds each row's
    attachment number where the rows are stored by cell, ``celllist.sort_cells``).
    Returns the new count and ``IN_GRID``, ``HEADS_FULL``, or, when the cluster outgrew the grid, its count of
    cell-list tiles (then the particle is not yet in the grid: the caller
    drops it and builds a larger one). It takes the grid's arrays one by one
    and returns none: a tuple of them would cost reference counting at each particle.

    Parameters
    ----------
    w : float64 (3,)
        The walker's centre at contact; wrapped onto a substrate's period.
    parent : float
        The row of ``pts`` it touched, -1 for the substrate (``normal[3]``).
    count : int
        Particles before this one: its row.
    pending : int
        Its steps since the last attachment, stored as its diffusion time.
    pts : float64 (n, dim)
        Receives its centre in row ``count``.
    order : int32 (n,) or (0,)
        Each row's attachment number where the rows are stored by cell; empty otherwise.
    steps : uint32 (n,)
        Receives its diffusion time.
    parents : int32 (n,)
        Receives its parent's attachment number.
    nxt : int32 (n,)
        The cell list's links through the rows.
    geo : float64 (3,)
        The cluster's r_max, Chebyshev extent and h_max, updated.
    dim : int
        2 or 3.
    line : bool
        Whether the seed is a substrate.
    size : int
        A substrate's period.
    gi, gf : int64 (GI_SLOTS,), float64 (GF_SLOTS,)
        The grid's geometry (``geometry.layout``); ``attach`` reads the extent
        it covers and its count of tiles.
    words : uint64 (...)
        The dilated maps.
    start, blocks, cells : int64 (S + 1,), int64 (S,), int64 (S,)
        The maps' layout (``maps.layout``).
    dirr, heads : int32 (...)
        The cell list's directory of tiles and its heads (``celllist``).
    field : uint8 (...)
        The centre field with the centre pyramid above it.
    """
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
def index_late(i, pts, nxt, dim, size, gi, gf, words, start, blocks, cells, dirr, heads, field):
    """Put particle i, which found the heads full, in the grid; returns the larger heads.

    Parameters
    ----------
    i : int
        The particle's row.
    pts, nxt : float64 (n, dim), int32 (n,)
        The centres and the cell list's links.
    dim : int
        2 or 3.
    size : int
        A substrate's period.
    gi, gf : int64 (GI_SLOTS,), float64 (GF_SLOTS,)
        The grid's geometry (``geometry.layout``); ``attach`` reads the extent
        it covers and its count of tiles.
    words : uint64 (...)
        The dilated maps.
    start, blocks, cells : int64 (S + 1,), int64 (S,), int64 (S,)
        The maps' layout (``maps.layout``).
    dirr, heads : int32 (...)
        The cell list's directory of tiles and its heads (``celllist``).
    field : uint8 (...)
        The centre field with the centre pyramid above it.
    """
    heads = more_heads(heads)
    insert(i, pts, nxt, dim, gi, gf, dirr, heads)
    mark(i, pts, dim, size, gi, words, start, blocks, cells, field)
    return heads
