"""Lattice growth at a finite concentration: many walkers at once, in lockstep."""

import numpy as np

from ..._jit import jit
from .. import model as codes
from ..model import checkpoint
from ..walk import below
from .walker import attach, near_walk, outside
from .words import occupied, regrow


@jit
def grow_in_lockstep(n, model, moves, marks, rng, rs, t0, times, passed, points, steps, count, r_max, h_max, grid):
    """Grow with ``model.walkers`` walkers at once: a finite concentration.

    They start on free sites uniformly in the box and take single steps in
    turn; none is relaunched, one that leaves the box is removed, and one
    whose site another walker just filled coalesces with it. Takes over from
    ``_grow`` once the seed is placed (its arguments are ``_grow``'s state)
    and returns (count, status).

    Parameters
    ----------
    n : int
        Most particles to grow.
    model : Model
        The model (``kernels.model.Model``).
    moves : int64 (M, 3)
        Unit moves, which are also the contacts (``exits.unit_moves``).
    marks : int64 (K,)
        Particle counts at which to read the clock.
    rng : numpy.random.Generator
        Draws the walkers' starting sites.
    rs : uint64 (4,)
        The xoshiro256+ stream of the steps and the sticking (``walker.near_walk``).
    t0 : float
        The clock at the growth's start (``_jit.clock``).
    times : float64 (K,)
        Receives the seconds at each mark.
    passed : int
        Marks passed already (``model.checkpoint``).
    points : int32 (n, dim)
        The sites, the seed's filled; receives the particles grown.
    steps : uint32 (n,)
        Receives the diffusion times.
    count : int
        Particles so far (the seed's).
    r_max, h_max : float
        The cluster's radius and height so far.
    grid : tuple
        ``(words, start, blocks, cells, field, width, off)``, as ``words.rebuild`` builds it.
    """
    dim, size, walkers, max_steps, stickiness = model.dim, model.size, model.walkers, model.max_steps, model.stickiness
    line = model.seed_shape == codes.LINE
    period = size if line else 0
    lo = -(size // 2)
    # the box: sites lo..hi on every axis; a substrate's box is 0..size-1 high
    box_lo = 0 if line else lo
    box_hi = size - 1 if line else size - 1 + lo
    words, start, blocks, cells, field, width, off = grid
    q = np.zeros(3, np.int64)
    alive = np.zeros(walkers, np.bool_)
    wpos = np.zeros((walkers, 3), np.int64)
    placed = 0
    while placed < walkers:
        for a in range(dim):
            wpos[placed, a] = box_lo + below(rng, box_hi - box_lo + 1)
        if not occupied(words, dim, start, blocks, width, off, wpos[placed, 0], wpos[placed, 1], wpos[placed, 2]):
            alive[placed] = True
            placed += 1
    live = walkers
    turn = 0
    total = np.int64(0)
    pending = np.int64(0)  # steps since the previous attachment
    status = codes.OK
    regrid = False
    while count < n:
        if regrid:  # as in ``_grow``
            words, start, blocks, cells, field = regrow(points, count, dim, width, off, period, grid)
            grid = (words, start, blocks, cells, field, width, off)
            regrid = False
        if max_steps > 0 and total >= max_steps:
            status = codes.STEP_LIMIT
            break
        if live == 0:
            status = codes.EXHAUSTED
            break
        w = turn
        turn = (turn + 1) % walkers
        if not alive[w]:
            continue
        for a in range(3):
            q[a] = wpos[w, a]
        if occupied(words, dim, start, blocks, width, off, q[0], q[1], q[2]):
            # another walker just filled this site: the two coalesce
            alive[w] = False
            live -= 1
            continue
        stuck, taken = near_walk(
            words, dim, start, blocks, width, off, q, moves, period, stickiness, rs,
            True, box_lo, box_hi, 0.0, 1, model.neighbour_alpha, 0.0, 0.0, 0.0,  # no drift: params refuses it
        )
        total += taken
        pending += taken
        for a in range(3):
            wpos[w, a] = q[a]
        if stuck:
            count, r_max, h_max, width, off, regrid = attach(points, steps, count, pending, q, dim, period,
                                                             r_max, h_max, grid)
            pending = 0
            passed = checkpoint(marks, times, passed, count, t0)
            alive[w] = False
            live -= 1
        elif outside(q, dim, line, box_lo, box_hi):
            alive[w] = False
            live -= 1
    return count, status
