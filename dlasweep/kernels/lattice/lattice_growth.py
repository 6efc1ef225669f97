"""Lattice growth: the walk of one walker from release to contact (its pieces
in ``walker``; many walkers at once: ``lockstep``).

Near the cluster the walk is an exact lattice random walk. A walker whose
nearest particle is at Chebyshev distance ``d >= 3`` jumps to where the
lattice walk first leaves the square (cube) of half-width ``d - 1`` around it
(``exits``): no site inside touches the cluster, so this is exact, and every
contact is still a lattice contact. Within two sites it takes single steps.
``d`` comes from the bit-packed occupancy words near the walker (``words``),
else from a coarse Chebyshev distance field (cells of 4 sites, to 64 sites;
3D 24). Beyond it the centre pyramid (``centres``: distances from the
centres of cells four, 3D two, times wider at each level to the nearest held
cell of the level below) bounds the Euclidean distance, from arrays that stay
in cache.
Far from the cluster (beyond the distances the tables cover) the walk is
taken as Brownian at scales of ``CIRCLE_MIN`` sites and more: the walker
jumps to where Brownian motion leaves the square (cube) free of particles
about it (``exits.square_exit``), or the circle (sphere) where that reaches
farther (outside the cluster's circle); outside the launch circle it returns
exactly (Poisson kernel) instead of wandering off.
Under a drift (``model.drift``) the steps are tilted (``walker.drifted_move``),
the circle jumps draw the drifted exit law (``walk.drift_dir``) and the exact
square tables and square exits, which have none, give way to single steps.

The single walker's loop (``_grow``) spells out its per-step helpers
(``walker.distance_bound``, ``touches``, ``step_to``): a call that passes
arrays would count their references at every step, and so would numba's own
inlining of them; ``tests/test_pins.py`` holds each copy to its twin.
Where a large cluster's time goes (steps and jumps by kind, the grids' cache
footprint) and the ways of overlapping the walk's reads that were tried are
in docs/performance.md.
"""

import time

import numpy as np
from numba import literally, types
from numba.typed import Dict

from ..._jit import cached, clock, jit, literal_entry
from .. import maps
from .. import model as codes
from ..centres import pyramid_dist
from ..model import STEPS_DTYPE, checkpoint, diffusion_time, drift_flag, grown, lockstep_flag, model_from, sticks_xo
from ..walk import drift_dir, drift_to_plane, return_to_plane, return_to_sphere, seed_stream, xdir, xo
from .exits import TABLE_MAX, exit_tables, square_exit, symmetry, unit_moves
from .field import FIELD_CAP, FIELD_MASK, field_place
from .lockstep import grow_in_lockstep
from .parents import lattice_parents
from .walker import FAR_CLEAR, attach, contact_sticks, drifted_move, near_walk, outside, release, site
from .words import fine2, fine3, rebuild, regrow, site_word, word_at

JUMP_MARGIN = 2.0  # sites kept between a Brownian jump (square or circle) and the nearest particle
CIRCLE_MIN = 16.0  # smallest Brownian jump: below it the exact square jumps do the work


@jit
def _grow(dimension, lockstep, drifted, n, model, moves, marks, rng, points, steps, times, t_start, t_cut, t_alias,
          t_off, frozen):
    """Grow a lattice cluster of up to ``n`` particles.

    After the seed, one walker at a time is released on the launch circle
    (or the box's surface: ``release``) and walks, by jumps as far as its
    distance to the cluster allows (``distance_bound``, spelled out in the
    loop), until it sticks or leaves; with more than one walker ``lockstep.grow_in_lockstep``
    takes over instead. The single walker's loop stays in this function
    rather than a function of its own: a split gains nothing (see
    docs/performance.md). The grid is rebuilt larger (``words.regrow``) at the
    top of the pass after the one whose attachment outgrew it.

    Parameters
    ----------
    dimension : int
        The model's dimension (2 or 3), a literal (``numba.literally``): each
        dimension is compiled apart, so that LLVM folds the branches on
        ``dim`` away (``_jit``; docs/performance.md has the gain).
    lockstep : None or True
        ``model.lockstep_flag(model.walkers)``: the lockstep walk is compiled in only where it runs.
    drifted : None or True
        ``model.drift_flag(model.drift)``: the drift's moves are compiled in only where it is on,
        as the lockstep walk is.
    n : int
        Most particles to grow, the seed's included.
    model : Model
        The model (``kernels.model.Model``).
    moves : int64 (M, 3)
        Unit moves, which are also the contacts (``exits.unit_moves``).
    marks : int64 (K,)
        Particle counts at which to read the clock, ascending.
    rng : numpy.random.Generator
        Seeds the walk's xoshiro256+ stream (``walk.seed_stream``) and draws
        the releases and exact returns.
    points : int32 (n, dim)
        Filled with the sites of the particles grown, in attachment order.
    steps : uint32 (n,)
        Filled with their diffusion times (``model.diffusion_time``).
    times : float64 (K,)
        Filled with the seconds at each mark as it passes.
    t_start : int64 (R + 2,)
        Where the exit table of each square half-width starts in the others
        (``exits.exit_tables``).
    t_cut : float64 (C,)
        The alias tables' cut probabilities.
    t_alias : int32 (C,)
        The alias tables' aliases, local to their half-width.
    t_off : int8 (C, 3)
        Each symmetry class's representative exit site.
    frozen : None or tuple
        None to grow. Else a frozen cluster's grid, ``(words, start, blocks, cells, field, width,
        off, r_max, h_max)`` as ``rebuild`` and ``attach`` leave them, and ``n`` walkers are
        walked against it, left unattached: ``points`` receives the site from which each
        would have stuck and ``steps`` its moves (``kernels.harmonic``, the harmonic measure).
        numba prunes the branches on ``frozen is None``: growth is compiled without them.

    Returns
    -------
    count : int
        Particles grown.
    status : int
        A code of ``dlasweep.params.STATUSES``.
    """
    literally(dimension)
    t0 = clock()
    dim = np.int64(2) if dimension == 2 else np.int64(3)  # a constant, not a literal (``_jit``)
    size = model.size
    line = model.seed_shape == codes.LINE
    period = size if line else 0
    rs = seed_stream(rng)
    width = 64 if not line else 4 * size
    off = width // 2 if not line else size
    count = 0
    r_max = 0.0
    h_max = -1.0
    if model.seed_shape == codes.POINT:
        count = min(n, 1)
    elif model.seed_shape == codes.BLOCK:
        count = min(n, 1 << dim)
        for p in range(count):
            for a in range(dim):
                points[p, a] = (p >> a) & 1
    for p in range(count):
        r_max = max(r_max, np.sqrt(np.sum(points[p].astype(np.float64) ** 2)))
    if frozen is None:
        words, start, blocks, cells, field = rebuild(points, count, dim, width, off, period)
    else:  # walkers against a frozen cluster: ``count`` counts those that would stick
        words, start, blocks, cells, field, width, off, r_max, h_max = frozen
        count = 0
    grid = (words, start, blocks, cells, field, width, off)
    passed = checkpoint(marks, times, 0, count, t0)
    if lockstep is not None:
        return grow_in_lockstep(n, model, moves, marks, rng, rs, t0, times, passed, points, steps, count, r_max, h_max,
                                grid)
    stickiness, max_steps, jumps = model.stickiness, model.max_steps, model.jumps
    alpha, noise = model.neighbour_alpha, model.noise_reduction
    drift, mu0, mu1, mu2 = model.drift, model.drift_x, model.drift_y, model.drift_z
    a0, a1, a2 = (mu0 / drift, mu1 / drift, mu2 / drift) if drift > 0.0 else (0.0, 0.0, 0.0)  # its direction
    no_tables = drifted is not None  # under a drift: no exact square tables (they have no drifted law)
    hits = Dict.empty(key_type=types.int64, value_type=types.int64)  # noise reduction's touches by site
    launch_box, kill, kill_factor = model.launch_box, model.kill, model.kill_factor
    up = dim - 1
    boxed = size > 0 and not line
    lo = -(size // 2)
    hi = size - 1 + lo
    top = TABLE_MAX[dim]
    group = 8 if dim == 2 else 48  # symmetries of the square (cube)
    rounding = 0.5 * np.sqrt(dim)  # how far a site can be from the point it rounds
    cap = FIELD_CAP[dim]
    levels = maps.pyramid_starts(dim, width, FIELD_CAP[dim])
    fw0 = (width + (1 << maps.FIELD_SHIFT) - 1) >> maps.FIELD_SHIFT  # the field's side
    nb0, base1, nb1 = blocks[0], start[1], blocks[1]
    nm = moves.shape[0]
    pos = np.zeros(3)
    q = np.zeros(3, np.int64)
    scratch = np.zeros(3)
    total = np.int64(0)
    pending = np.int64(0)  # steps since the previous attachment
    status = codes.OK
    # the box: sites lo..hi on every axis; a substrate's box is 0..size-1 high
    box_lo = 0 if line else lo
    box_hi = size - 1 if line else hi
    need_launch = True
    stuck = False
    regrid = False
    while count < n:
        if regrid:
            # Built here, at the top of a pass, from the old grid, whose pages ``regrow``
            # hands back as it carries them over: the two grids are never held whole
            # at once, which would raise the peak memory (docs/performance.md).
            words, start, blocks, cells, field = regrow(points, count, dim, width, off, period, grid)
            grid = (words, start, blocks, cells, field, width, off)
            nb0, base1, nb1 = blocks[0], start[1], blocks[1]
            levels = maps.pyramid_starts(dim, width, FIELD_CAP[dim])
            fw0 = (width + (1 << maps.FIELD_SHIFT) - 1) >> maps.FIELD_SHIFT
            regrid = False
        if max_steps > 0 and total >= max_steps:
            status = codes.STEP_LIMIT
            break
        launch_r = model.launch_factor * (max(h_max, 0.0) if line else r_max) + model.launch_margin
        if boxed and not launch_box and launch_r > -lo - 1:
            status = codes.BOUNDARY
            break

        if need_launch:
            need_launch = False
            release(rng, dim, line, launch_box, size, box_lo, box_hi, launch_r, pos)
        kill_r = kill_factor * launch_r
        # any radius beyond the launch circle is exact for the return; a
        # unit gap spares a walker that rounding put a hair outside it
        return_r = launch_r + 1.0 if model.exact_return else 0.0
        budget = max_steps - total if max_steps > 0 else np.int64(-1)
        # one walker's moves until it sticks, leaves, or spends the budget;
        # the stream's state lives in registers meanwhile
        s0, s1, s2, s3 = rs[0], rs[1], rs[2], rs[3]
        from_far = True  # released, returned, or past a Brownian jump: the pyramid first (``FAR_CLEAR``)
        while budget != 0:
            r = pos[up] if line else np.sqrt(pos[0] ** 2 + pos[1] ** 2 + pos[2] ** 2)
            if kill and r > kill_r:
                need_launch = True
                break
            if return_r > 0.0 and r > return_r:
                total += 1
                pending += 1
                budget -= 1
                if line:
                    if drifted is not None:
                        drift_to_plane(rng, dim, pos, launch_r, size, mu0, mu1, mu2)
                    else:
                        return_to_plane(rng, dim, pos, launch_r, size)
                elif not return_to_sphere(rng, dim, pos, launch_r, scratch):
                    need_launch = True
                    break
                from_far = True
                continue
            for a in range(3):
                q[a] = site(pos[a])
            if (boxed or launch_box) and outside(q, dim, line, box_lo, box_hi):
                need_launch = True
                break
            if not jumps:
                rs[0], rs[1], rs[2], rs[3] = s0, s1, s2, s3
                stuck, taken = near_walk(
                    words, dim, start, blocks, width, off, q, moves, period, stickiness, rs,
                    boxed or launch_box, box_lo, box_hi, kill_r if kill else return_r,
                    max(budget, 0), alpha, mu0, mu1, mu2,
                )
                s0, s1, s2, s3 = rs[0], rs[1], rs[2], rs[3]
                total += taken
                pending += taken
                for a in range(3):
                    pos[a] = q[a]
                break
            i, j, k = q[0] + off, q[1] + off, q[2] + off
            # >>> distance_bound, spelled out: a call, or numba's inlining of it, would add
            # reference counting of its arrays at every step (docs/performance.md)
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
            # <<< distance_bound
            from_far = False
            if d == 0 or (line and q[up] <= 1):
                # >>> touches, then step_to, spelled out: calls that pass arrays
                # would cost reference counting (a test holds the texts together)
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
                # <<< touches
                if touch:
                    if alpha < 1.0:  # the neighbour_alpha law
                        touch, s0, s1, s2, s3 = contact_sticks(words, dim, start, blocks, width, off, q, moves,
                                                               period, stickiness, alpha, s0, s1, s2, s3)
                    else:
                        touch, s0, s1, s2, s3 = sticks_xo(stickiness, s0, s1, s2, s3)
                if touch:
                    stuck = True
                    break
                # >>> step_to
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
                # <<< step_to
                total += 1
                pending += 1
                budget -= 1
                continue
            # no particle within two sites here: d >= 3
            free = r - (h_max if line else r_max)  # Euclidean, from the float position
            if line:
                # the substrate (the row, plane, of height -1) bounds every jump as a particle does:
                # the cluster's grids and pyramid do not hold it
                d = min(max(d, np.int64(free)), period, q[up] + 1)
                free = min(free, pos[up] + 1.0)
                far = min(far, pos[up] + 1.0)
            square = d - rounding - JUMP_MARGIN  # half-width of the square (cube) free of particles
            reach = max(free - JUMP_MARGIN, square, far - rounding - JUMP_MARGIN)
            half = min(d - 1, top)
            if kill:
                reach = min(reach, kill_r - r)
                square = min(square, (kill_r - r) / np.sqrt(dim))  # its corners inside the kill circle
                qr = np.sqrt(float(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]))
                half = min(half, np.int64((kill_r - qr) / np.sqrt(dim)) + 1)
            if boxed:
                for a in range(dim):
                    reach = min(reach, pos[a] - lo, hi - pos[a])
                    square = min(square, pos[a] - lo, hi - pos[a])
                    half = min(half, q[a] - lo + 1, hi - q[a] + 1)
            elif line and launch_box:
                reach = min(reach, box_hi - pos[up])
                square = min(square, box_hi - pos[up])
                half = min(half, box_hi - q[up] + 1)
            total += 1
            pending += 1
            budget -= 1
            # under a drift the lattice square's exit tables and Brownian motion's square exit do not hold:
            # circle jumps (``walk.drift_dir``) from CIRCLE_MIN on, single drifted steps below
            from_far = reach >= CIRCLE_MIN and (reach > half or no_tables)
            if from_far:
                if drifted is not None:
                    s0, s1, s2, s3, u0, u1, u2 = drift_dir(s0, s1, s2, s3, dim, drift * reach, a0, a1, a2)
                elif square >= reach:  # the square (cube) reaches as far as the circle, and holds more
                    s0, s1, s2, s3, u0, u1, u2 = square_exit(s0, s1, s2, s3, dim)
                else:
                    s0, s1, s2, s3, u0, u1, u2 = xdir(s0, s1, s2, s3, dim)
                pos[0] += reach * u0
                pos[1] += reach * u1
                pos[2] += reach * u2
            elif half >= 2 and not no_tables:
                # exact: where the lattice walk first leaves the square of half-width `half`
                s0, s1, s2, s3, u = xo(s0, s1, s2, s3)
                u *= t_start[half + 1] - t_start[half]
                e = np.int64(u)
                if u - e >= t_cut[t_start[half] + e]:
                    e = t_alias[t_start[half] + e]
                e += t_start[half]
                # a uniform symmetry of the square spreads the class over its orbit
                s0, s1, s2, s3, u = xo(s0, s1, s2, s3)
                o0, o1, o2 = symmetry(np.int64(u * group), dim, t_off[e, 0], t_off[e, 1], t_off[e, 2])
                pos[0], pos[1], pos[2] = q[0] + o0, q[1] + o1, q[2] + o2
            else:
                # no particle within two sites: a plain step
                s0, s1, s2, s3, u = xo(s0, s1, s2, s3)
                m = np.int64(u * nm)
                if drifted is not None:
                    m = drifted_move(moves, u, mu0, mu1, mu2)
                for a in range(dim):
                    pos[a] = q[a] + moves[m, a]
            if line:
                for a in range(up):
                    pos[a] = pos[a] % period
        rs[0], rs[1], rs[2], rs[3] = s0, s1, s2, s3
        if frozen is not None:
            if stuck:  # where it would stick, recorded; the cluster stays as it is
                for a in range(dim):
                    points[count, a] = q[a]
                steps[count] = diffusion_time(pending)
                count += 1
                pending = 0
                total = 0  # ``max_steps`` bounds each walker's moves
                need_launch = True
                stuck = False
        if stuck and noise > 1 and not occupy(hits, q, noise):
            stuck = False  # a touch counted at q: the walker is relaunched
            need_launch = True
        if stuck:
            count, r_max, h_max, width, off, regrid = attach(points, steps, count, pending, q, dim, period,
                                                             r_max, h_max, grid)
            pending = 0
            passed = checkpoint(marks, times, passed, count, t0)
            need_launch = True
            stuck = False
            # with box launch, growth ends where the cluster meets the box
            if launch_box and outside(q, dim, line, box_lo + 2, box_hi - 2):
                status = codes.BOUNDARY
                break
    return count, status



@jit
def occupy(hits, q, noise):
    """Count a touch of site q in ``hits`` (site key to touches); whether it is the ``noise``-th, which
    occupies the site (its count then dropped). Lattice noise reduction (``noise_reduction``): a
    perimeter site is occupied after ``noise`` walkers touched it; sites are keyed by 21 bits an axis,
    which hold every site of a cluster of ``spec.MAX_PARTICLES``."""
    key = ((q[0] + (1 << 20)) << 42) | ((q[1] + (1 << 20)) << 21) | (q[2] + (1 << 20))
    touches = hits.get(key, 0) + 1
    if touches < noise:
        hits[key] = touches
        return False
    if touches > 1:
        hits.pop(key)
    return True


def grow_lattice(n, p, marks, rngs, times=None):
    """Grow lattice clusters, one with each generator; see ``dlasweep.grow`` for the meaning.

    The growth kernel, compiled once for the batch's argument types (``_jit.literal_entry``), is
    called for each generator: a batch compiles the same one kernel as a single cluster, and a call
    from Python costs less than a small cluster's growth (docs/performance.md).

    Parameters
    ----------
    n : int
        Most particles a cluster, the seed's included.
    p : dict
        Model parameters as ``dlasweep.params.resolve`` returns them.
    marks : int64 (K,)
        Particle counts at which to record the time.
    rngs : list of numpy.random.Generator
        One generator a cluster: the cluster is a function of it.
    times : float64 (len(rngs), K), optional
        Filled as the marks pass (NaN before), so that another thread can
        watch the growth.

    Returns
    -------
    list, for each generator, of
        points : int32 (n_grown, dim)
        steps : uint32 (n_grown,), saturated (``model.diffusion_time``)
        parents : int32 (n_grown,), the particle each one stuck to (``parents.lattice_parents``), -1 for none
        status : int code into ``dlasweep.params.STATUSES``
        times : float64 seconds at each of ``marks`` (NaN when not reached)
        seconds : float, the whole growth
    """
    if not rngs:
        return []
    model = model_from(p)
    moore = model.neighbours != 2 * model.dim
    points = np.zeros((len(rngs), n, model.dim), np.int32)
    steps = np.zeros((len(rngs), n), STEPS_DTYPE)
    times = np.full((len(rngs), len(marks)), np.nan) if times is None else times
    counts, statuses = np.zeros((2, len(rngs)), np.int64)
    seconds = np.zeros(len(rngs))
    moves = unit_moves(model.dim, moore)
    tables = exit_tables(model.dim, moore)
    args = (lockstep_flag(model.walkers), drift_flag(model.drift), n, model, moves, np.asarray(marks, np.int64))
    kernel = literal_entry(_grow, model.dim, *args, rngs[0], points[0], steps[0], times[0], *tables, None)
    for i, rng in enumerate(rngs):
        start = time.perf_counter()
        counts[i], statuses[i] = kernel(model.dim, *args, rng, points[i], steps[i], times[i], *tables, None)
        seconds[i] = time.perf_counter() - start
    nseed = {codes.POINT: 1, codes.BLOCK: 1 << model.dim, codes.LINE: 0}[model.seed_shape]
    period = model.size if model.seed_shape == codes.LINE else 0
    return [grown(pts, st, lattice_parents(pts[:count], moves, nseed, period), count, *rest)
            for pts, st, count, *rest in zip(points, steps, counts, statuses, times, seconds)]


def compiled(dim, walkers=1) -> bool:
    """Whether numba's on-disk cache holds this growth kernel for ``dim`` and ``walkers`` (most of its compile
    time): compiled to grow (``frozen`` None), not only for the harmonic measure."""
    return cached(_grow, dim, lockstep_flag(walkers), last=None)
