"""Off-lattice growth at a finite concentration: many walkers at once, in lockstep."""

import numpy as np

from ..._jit import jit
from .. import model as codes
from ..model import checkpoint, sticks
from ..walk import unit_vector
from .celllist import gather
from .contact import cast, gauss_move, rebound
from .grid import map_dist, no_grid, regrow_grid
from .walker import HEADS_FULL, attach, index_late, neighbour_list


@jit
def grow_in_lockstep(n, model, marks, rng, rs, t0, times, passed, pts, order, steps, parents, nxt, count, geo, grid):
    """Grow with ``model.walkers`` walkers at once: a finite concentration.

    They start uniformly in the box (not on a particle) and take single
    steps in turn (unit ray casts, or Gaussian steps); none is relaunched, a
    wall removes it, and one that a new particle covers merges into it.
    Takes over from ``offlattice_growth._grow`` once the seed is placed (its
    arguments are ``_grow``'s state) and returns (count, status).

    Parameters
    ----------
    n : int
        Most particles to grow.
    model : Model
        The model (``kernels.model.Model``).
    marks : int64 (K,)
        Particle counts at which to read the clock.
    rng : numpy.random.Generator
        Draws the walkers' places, the sticking and the Gaussian steps.
    rs : uint64 (4,)
        The xoshiro256+ stream of the walkers' directions.
    t0 : float
        The clock at the growth's start (``_jit.clock``).
    times : float64 (K,)
        Receives the seconds at each mark.
    passed : int
        Marks passed already (``model.checkpoint``).
    pts : float64 (n, dim)
        The particles' centres, the seed's filled.
    order : int32 (0,)
        Empty: with many walkers the rows stay in attachment order.
    steps : uint32 (n,)
        Receives the diffusion times.
    parents : int32 (n,)
        Receives the parents.
    nxt : int32 (n,)
        The cell list's links.
    count : int
        Particles so far (the seed's).
    geo : float64 (3,)
        The cluster's r_max, Chebyshev extent and h_max.
    grid : tuple
        ``(gi, gf, words, start, blocks, cells, dirr, heads, field)``, as ``grid.build_grid`` returns it.
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
    mx, my, mz, mi = neighbour_list()
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
                                     blocks, cells, field, mx, my, mz, mi, e, u, normal, 0.0, 0.0, 0.0)  # no drift
            stuck = False
            if contact:
                if step > 0.0:
                    stuck = sticks(stickiness, rng)
                else:
                    stuck, moves = rebound(w, u, normal, dim, size, line, stickiness, rng, rs, pts, nxt, gi, gf, dirr,
                                           heads, mx, my, mz, mi, 0.0, 0.0, 0.0, 0.0)
                    total += moves
                    pending += moves
            if stuck:
                count, tiles = attach(w, normal[3], count, pending, pts, order, steps, parents, nxt, geo, dim, line,
                                      size, gi, gf, words, start, blocks, cells, dirr, heads, field)
                if tiles == HEADS_FULL:
                    heads = index_late(count - 1, pts, nxt, dim, size, gi, gf, words, start, blocks, cells, dirr,
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
