"""Walkers against a frozen cluster: where each would stick, the cluster left as it is.

The walkers are the growth kernels' own: off the lattice each is
``offlattice.walker.walk_to_contact`` (release on the launch circle, exact
return, jumps, the ray cast to contact, the rebound of a walker that does
not stick), on it ``lattice.lattice_growth._grow`` with its ``frozen``
argument, the single walker's loop that records the site from which a walker
would stick instead of attaching it. The grids are built once from the cluster's points,
as growth builds them (``offlattice.grid.build_grid``, ``lattice.words.rebuild``
at the side that ``lattice.walker.attach`` would have grown to), and only
read. With lockstep walkers (``walkers > 1``) each is released and walks as
the single walker does: against a frozen cluster they are independent.

Random numbers: walkers come in blocks of ``BLOCK``, each block from its own
numpy Generator (the caller's, ``dlasweep.measures.harmonic`` draws block b's
from ``SeedSequence(seed, spawn_key=(KEY, b))``), that seeds the xoshiro
stream of its walks (``walk.seed_stream``) as a growth's does; a walker's path
depends only on its block's Generator and its place in the block, so the
measurement does not depend on how blocks are shared between calls.
"""

import numpy as np
from numba import literally

from .._jit import call_literal, jit
from . import model as codes
from .lattice.exits import exit_tables, unit_moves
from .lattice.lattice_growth import _grow
from .lattice.parents import touched
from .lattice.walker import GROWTH
from .lattice.words import rebuild
from .model import diffusion_time, gaussian_flag, model_from
from .offlattice.grid import build_grid, level_starts
from .offlattice.walker import neighbour_list, walk_to_contact
from .walk import seed_stream

BLOCK = 4096
"""Walkers a Generator: block b of a measurement holds walkers ``b * BLOCK`` to ``(b + 1) * BLOCK - 1``.
Seeding a block's stream costs about what one walk does; a block is thousands of walks."""


@jit
def _offlattice_walk(dimension, gaussian, model, points, rngs, walkers, hits, where, steps):
    """Walk ``walkers`` walkers against the off-lattice cluster ``points``, ``BLOCK`` to each Generator of ``rngs``.

    Parameters
    ----------
    dimension : int
        The model's dimension, a literal (``walker.walk_to_contact`` is compiled for it).
    gaussian : None or True
        ``model.gaussian_flag(model.step)``, as ``walker.walk_to_contact`` takes it.
    model : Model
        The model (``kernels.model.Model``).
    points : float64 (n, dim)
        The frozen cluster's centres; a walker's particle is its row.
    rngs : list of numpy.random.Generator
        One a block, ``ceil(walkers / BLOCK)`` of them.
    walkers : int
    hits : int32 (walkers,)
        Receives the row of the particle each walker touched when it stuck (-1: the substrate).
    where : float64 (walkers,)
        Receives its distance from the origin where it stuck (above a substrate: its height).
    steps : uint32 (walkers,)
        Receives its moves from its first release (``model.diffusion_time``).

    Returns
    -------
    done : int
        Walkers that stuck (all unless one spent ``max_steps`` moves: then the first that did).
    status : int, ``OK`` or ``STEP_LIMIT``
    """
    literally(dimension)
    dim = np.int64(2) if dimension == 2 else np.int64(3)
    count = len(points)
    line = model.seed_shape == codes.LINE
    up = dim - 1
    pts = np.zeros((max(count, 1), dim))
    pts[:count] = points
    geo = np.zeros(3)  # r_max, Chebyshev extent, h_max, as growth keeps them
    geo[2] = -1.0
    for q in range(count):
        r2 = 0.0
        for a in range(dim):
            r2 += pts[q, a] ** 2
            geo[1] = max(geo[1], abs(pts[q, a]))
        geo[0] = max(geo[0], np.sqrt(r2))
        geo[2] = max(geo[2], pts[q, up])
    nxt = np.full(max(count, 1), -1, np.int32)
    gi, gf, words, start, blocks, cells, dirr, heads, field = build_grid(
        dim, line, model.size, max(geo[2], 0.0) if line else geo[1], pts, count, nxt, 0)
    pstart = level_starts(gi, dim)
    w = np.zeros(3)
    u = np.zeros(3)
    normal = np.zeros(4)
    scratch = np.zeros(3)
    anchor = np.zeros(3)
    lx, ly, lz, li = neighbour_list(model.contact_distance)
    mx, my, mz, mi = neighbour_list(model.contact_distance)
    launch_r = model.launch_factor * (max(geo[2], 0.0) if line else geo[0]) + model.launch_margin
    for b in range(len(rngs)):
        rng = rngs[b]
        rs = seed_stream(rng)
        for i in range(b * BLOCK, min((b + 1) * BLOCK, walkers)):
            stuck, total, pending = walk_to_contact(dimension, gaussian, model, launch_r,
                                                    model.kill_factor * launch_r, np.int64(0), np.int64(0), w, u,
                                                    normal, scratch, anchor, lx, ly, lz, li, mx, my, mz, mi, pts, nxt,
                                                    gi, gf, words, start, blocks, cells, dirr, heads, field, pstart,
                                                    geo, rs, rng)
            if not stuck:
                return i, codes.STEP_LIMIT
            hits[i] = np.int32(normal[3])
            where[i] = w[up] if line else np.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
            steps[i] = diffusion_time(pending)
    return walkers, codes.OK


@jit
def _lattice_walk(dimension, model, moves, points, rngs, walkers, sites, steps, t_start, t_cut, t_alias, t_off):
    """Walk ``walkers`` walkers against the lattice cluster ``points``, ``BLOCK`` to each Generator of ``rngs``.

    The grid is ``words.rebuild``'s at the side growth would have reached (``walker.attach``'s rule),
    and each block is ``lattice_growth._grow``'s single walker with it frozen.

    Parameters
    ----------
    dimension : int
        The model's dimension, a literal (``lattice_growth._grow`` is compiled for it).
    model : Model
        The model (``kernels.model.Model``).
    moves : int64 (M, 3)
        Unit moves, which are also the contacts (``exits.unit_moves``).
    points : int32 (n, dim)
        The frozen cluster's sites.
    rngs : list of numpy.random.Generator
        One a block, ``ceil(walkers / BLOCK)`` of them.
    walkers : int
        Walkers to walk.
    sites : int32 (walkers, dim)
        Receives the site from which each walker would stick.
    steps : uint32 (walkers,)
        Receives its moves from its first release (``model.diffusion_time``).
    t_start, t_cut, t_alias, t_off
        The exit tables (``exits.exit_tables``), as ``lattice_growth._grow`` takes them.

    Returns
    -------
    done : int
        Walkers that stuck, as ``_offlattice_walk`` returns them.
    status : int, ``OK`` or ``STEP_LIMIT``
    """
    literally(dimension)
    dim = np.int64(2) if dimension == 2 else np.int64(3)
    count = len(points)
    line = model.seed_shape == codes.LINE
    period = model.size if line else 0
    up = dim - 1
    r_max, h_max, extent, top = 0.0, -1.0, 0, 0
    for p in range(count):
        r2 = 0.0
        for a in range(dim):
            r2 += float(points[p, a]) ** 2
            extent = max(extent, abs(np.int64(points[p, a])))
        r_max = max(r_max, np.sqrt(r2))
        h_max = max(h_max, float(points[p, up]))
        top = max(top, np.int64(points[p, up]))
    width = 64 if not line else 4 * model.size
    off = width // 2 if not line else model.size
    while (top + off + 4 >= width) if line else (extent + 4 >= off):
        width = (int(width * GROWTH) + 15) // 16 * 16
        if not line:
            off = width // 2
    words, start, blocks, cells, field = rebuild(points, count, dim, width, off, period)
    frozen = (words, start, blocks, cells, field, width, off, r_max, h_max)
    marks = np.zeros(0, np.int64)
    times = np.zeros(0)
    for b in range(len(rngs)):
        lo, hi = b * BLOCK, min((b + 1) * BLOCK, walkers)
        done, status = _grow(dimension, None, None, hi - lo, model, moves, marks, rngs[b], sites[lo:hi], steps[lo:hi],
                             times, t_start, t_cut, t_alias, t_off, frozen)
        if status != codes.OK:
            return lo + done, status
    return walkers, codes.OK


def frozen_walks(points, p, rngs, walkers):
    """Walk ``walkers`` walkers against the frozen cluster ``points`` of the model ``p``; see the module docstring.

    Parameters
    ----------
    points : ndarray (n, dim)
        The cluster's points in attachment order (int32 sites on the lattice, float64 centres off it).
    p : dict
        Model parameters as ``dlasweep.params.resolve`` returns them.
    rngs : list of numpy.random.Generator
        One for each block of ``BLOCK`` walkers, ``ceil(walkers / BLOCK)`` of them.
    walkers : int

    Returns
    -------
    hits : int32 (done,)
        The particle each walker would have stuck to (the growth's parent rule), -1 for the substrate.
    where : float64 (done,)
        Distance from the origin at which each stuck (above a substrate: height).
    steps : uint32 (done,)
    status : int, a code of ``dlasweep.params.STATUSES``
    """
    model = model_from(p)
    if len(rngs) != -(-walkers // BLOCK):
        raise ValueError(f"rngs: {len(rngs)} generators for {walkers} walkers, need {-(-walkers // BLOCK)}")
    steps = np.zeros(walkers, codes.STEPS_DTYPE)
    if p["model"] == "offlattice":
        hits = np.full(walkers, -1, np.int32)
        where = np.zeros(walkers)
        done, status = call_literal(_offlattice_walk, model.dim, gaussian_flag(model.step), model,
                                    np.ascontiguousarray(points, np.float64), list(rngs), int(walkers), hits, where,
                                    steps)
        return hits[:done], where[:done], steps[:done], int(status)
    moore = model.neighbours != 2 * model.dim
    moves = unit_moves(model.dim, moore)
    sites = np.zeros((walkers, model.dim), np.int32)
    lattice_points = np.ascontiguousarray(points, np.int32)
    done, status = call_literal(_lattice_walk, model.dim, model, moves, lattice_points, list(rngs), int(walkers), sites,
                                steps, *exit_tables(model.dim, moore))
    sites = sites[:done]
    line = model.seed_shape == codes.LINE
    where = sites[:, -1].astype(np.float64) if line else np.sqrt((sites.astype(np.float64) ** 2).sum(axis=1))
    return touched(lattice_points, sites, moves, model.size if line else 0), where, steps[:done], int(status)
