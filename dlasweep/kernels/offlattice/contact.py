"""Off-lattice contact geometry: the exact ray cast to contact, the settle onto
a particle's surface, the Gaussian step with its end-point check, and the
rebound of a walker that did not stick.

A walker moving along a ray stops exactly at contact (centre distance 1 to
rounding, never less) and never passes through a branch.
"""

import numpy as np

from ..._jit import borrow, inline, jit
from ..model import sticks
from ..walk import drift_dir
from .celllist import gather
from .grid import map_dist

EPS = 1e-3
"""Surface gap (diameters) below which a walker ray-casts to contact."""
RAY = 2e-3
"""Length of the ray-cast moves inside the EPS shell."""
REJECT = 1.0
"""Length of the move away from a contact that did not stick."""


@inline
def ray_to(w, u0, u1, u2, length, nl, lx, ly, lz, line, dim):
    """First contact along w + t u, 0 <= t <= length: (t, k).

    k indexes the listed centres, -2 is the substrate (line seed: centres
    touch it at up = 0), -1 means no contact. The direction comes as scalars
    and the helper is inlined, so that the walk's hot loop casts its short
    rays with no call and no reference counting.

    Parameters
    ----------
    w : float64 (3,)
        The walker's centre (z 0 in 2D).
    u0, u1, u2 : float
        The ray's unit direction.
    length : float
        How far the ray reaches.
    nl : int
        How many centres of the list to test.
    lx, ly, lz : float64 (LCAP,)
        The listed centres (``celllist.gather``).
    line : bool
        Whether a substrate lies at up = 0.
    dim : int
        2 or 3.
    """
    best = length
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
        t = max(0.0, cc / (np.sqrt(disc) - b))  # the smaller root, without cancellation
        if t <= best:
            best = t
            hit = k
    uu = u2 if dim == 3 else u1
    if line and uu < 0.0:
        t = max(0.0, -w[dim - 1] / uu)
        if t <= best:
            best = t
            hit = -2
    return best, hit


@borrow
def ray(w, u, length, nl, lx, ly, lz, line, dim):
    """``ray_to`` along the direction ``u[:3]``; ``w``, ``length``, ``nl``, ``lx``, ``ly``, ``lz``,
    ``line`` and ``dim`` are ``ray_to``'s."""
    return ray_to(w, u[0], u[1], u[2], length, nl, lx, ly, lz, line, dim)


@borrow
def settle(w, u, t, hit, dim, lx, ly, lz, li, normal):
    """Move w to w + t u and put it at distance 1 exactly from what it hit;
    ``normal`` gets the outward unit normal at the contact in its first
    three entries and, in the fourth, the particle touched (``li[hit]``;
    -1: the substrate), which becomes the parent of a walker that sticks.

    Parameters
    ----------
    w : float64 (3,)
        The walker's centre, moved to contact.
    u : float64 (3,)
        The ray's unit direction.
    t : float
        How far along ``u`` the contact lies (``ray_to``).
    hit : int
        What the ray hit: an index into the list, or -2 for the substrate.
    dim : int
        2 or 3.
    lx, ly, lz : float64 (LCAP,)
        The listed centres.
    li : int64 (LCAP,)
        Their rows.
    normal : float64 (4,)
        Receives the normal and the particle touched.
    """
    for a in range(3):
        w[a] += t * u[a]
    if hit == -2:
        w[dim - 1] = 0.0
        for a in range(3):
            normal[a] = 0.0
        normal[dim - 1] = 1.0
        normal[3] = -1.0
        return
    normal[3] = li[hit]
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


@borrow
def cast(w, u, length, dim, size, line, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li, normal):
    """Ray cast of w along u straight from the cell list; moves w.

    Long rays go in pieces of at most 2 so the gathered lists stay short.
    Returns True on contact (w then at contact, ``normal`` set).

    Parameters
    ----------
    w : float64 (3,)
        The walker's centre, moved along the ray.
    u : float64 (3,)
        The ray's unit direction.
    length : float
        How far to cast.
    dim : int
        2 or 3.
    size : int
        A substrate's period (``celllist.gather``).
    line : bool
        Whether a substrate lies at up = 0.
    pts : float64 (n, dim)
        The particles' centres.
    nxt : int32 (n,)
        The cell list's links through the rows (``celllist``).
    gi, gf : int64 (GI_SLOTS,), float64 (GF_SLOTS,)
        The grid's geometry (``geometry.layout``).
    dirr, heads : int32 (...)
        The cell list's directory of tiles and its heads.
    lx, ly, lz : float64 (LCAP,)
        Scratch for the centres gathered about the ray (``celllist.gather``).
    li : int64 (LCAP,)
        Scratch for their rows.
    normal : float64 (4,)
        Scratch for the pieces' midpoints; at a contact, receives the normal
        and the particle touched (``settle``).
    """
    c = normal  # scratch until a contact sets it
    left = length
    while left > 0.0:
        piece = min(left, 2.0)
        left -= piece
        for a in range(3):
            c[a] = w[a] + 0.5 * piece * u[a]
        nl = gather(c, 0.5 * piece + 1.0, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li)[0]
        t, hit = ray(w, u, piece, nl, lx, ly, lz, line, dim)
        if hit != -1:
            settle(w, u, t, hit, dim, lx, ly, lz, li, normal)
            return True
        for a in range(3):
            w[a] += piece * u[a]
    return False


@jit
def gauss_move(w, step, dim, size, line, rng, pts, nxt, gi, gf, dirr, heads, words, start, blocks,
               cells, field, lx, ly, lz, li, e, u, normal, m0, m1, m2):
    """One Gaussian step with the naive end-point check; True on contact.

    The step is proposed from w; if its end point is free it is taken, even
    when the straight path crosses a branch (tunnelling). If the end point
    overlaps, the walker is put back along the step to where it first touches
    one of the particles it overlaps there (exact contact); should that spot
    overlap another particle, a full ray cast along the step decides.
    ``e`` and ``u`` are scratch (3,): it allocates nothing, as numba compiles it
    without reference counting when the first caller to need it borrows (``_jit.borrow``).

    Parameters
    ----------
    w : float64 (3,)
        The walker's centre, moved.
    step : float
        The Gaussian step's standard deviation per axis (``model.step``).
    dim : int
        2 or 3.
    size : int
        A substrate's period, read where the axes wrap (``celllist.gather``, ``grid.map_dist``).
    line : bool
        Whether a substrate lies at up = 0.
    rng : numpy.random.Generator
        Draws the step.
    pts : float64 (n, dim)
        The particles' centres.
    nxt : int32 (n,)
        The cell list's links through the rows (``celllist``).
    gi, gf : int64 (GI_SLOTS,), float64 (GF_SLOTS,)
        The grid's geometry (``geometry.layout``).
    dirr, heads : int32 (...)
        The cell list's directory of tiles and its heads.
    words : uint64 (...)
        The dilated maps (``grid.map_dist``).
    start, blocks, cells : int64 (S + 1,), int64 (S,), int64 (S,)
        The maps' layout (``maps.layout``).
    field : uint8 (...)
        The centre field with the pyramid above it.
    lx, ly, lz : float64 (LCAP,)
        Scratch for the centres gathered about the ray (``celllist.gather``).
    li : int64 (LCAP,)
        Scratch for their rows.
    e : float64 (3,)
        Scratch: the proposed end point, then the contact tried.
    u : float64 (3,)
        Scratch: the step's direction.
    normal : float64 (4,)
        At a contact, receives the normal and the particle touched (``settle``).
    m0, m1, m2 : float
        The step's mean: under a drift mu (v / (2 D)) a Gaussian step of variance step**2 an axis
        lasts step**2 / (2 D), in which the walker drifts by mu step**2; 0 without one.
    """
    up = dim - 1
    e[0], e[1], e[2] = m0, m1, m2
    for a in range(dim):
        e[a] = w[a] + e[a] + step * rng.normal()
    sub = line and e[up] < 0.0
    if not sub and map_dist(e, dim, size, gi, words, start, blocks, cells, field) > 0.0:
        for a in range(dim):
            w[a] = e[a]
        return False
    nov = gather(e, 1.0, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li)[0]
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
    t, hit = ray(w, u, length * (1.0 + 1e-9) + 1e-12, nov, lx, ly, lz, sub, dim)
    if hit != -1:
        for a in range(3):  # e, done with, holds the contact tried
            e[a] = w[a]
        settle(e, u, t, hit, dim, lx, ly, lz, li, normal)
        if gather(e, 1.0 - 1e-12, dim, size, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li)[0] == 0:
            for a in range(3):
                w[a] = e[a]
            return True
    return cast(w, u, length, dim, size, line, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li, normal)


@borrow
def rebound(w, u, normal, dim, size, line, stickiness, rng, rs, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li,
            kappa, a0, a1, a2):
    """A walker at contact: sticks with probability ``stickiness`` (True), else
    moves away by ``REJECT`` into the outward half-space, ray-cast, and
    tries again at every new contact. Returns (stuck, moves made). Under a
    drift the move's direction is the sphere's exit law (``walk.drift_dir``,
    concentration ``kappa``), reflected into the outward half-space as the
    uniform one is.

    Parameters
    ----------
    w : float64 (3,)
        The walker's centre, at contact; moved.
    u : float64 (3,)
        Scratch for the move's direction.
    normal : float64 (4,)
        The contact's normal and particle (``settle``), renewed at each new contact.
    dim : int
        2 or 3.
    size : int
        A substrate's period (``celllist.gather``).
    line : bool
        Whether a substrate lies at up = 0.
    stickiness : float
        The probability of sticking at a contact.
    rng : numpy.random.Generator
        Draws the sticking (``model.sticks``).
    rs : uint64 (4,)
        The xoshiro256+ stream that draws the directions (``walk.drift_dir``).
    pts : float64 (n, dim)
        The particles' centres.
    nxt : int32 (n,)
        The cell list's links through the rows (``celllist``).
    gi, gf : int64 (GI_SLOTS,), float64 (GF_SLOTS,)
        The grid's geometry (``geometry.layout``).
    dirr, heads : int32 (...)
        The cell list's directory of tiles and its heads.
    lx, ly, lz : float64 (LCAP,)
        Scratch for the centres gathered about the ray (``celllist.gather``).
    li : int64 (LCAP,)
        Scratch for their rows.
    kappa : float
        The drift times ``REJECT``; 0: uniform directions.
    a0, a1, a2 : float
        The drift's unit direction.
    """
    moves = 0
    while True:
        if sticks(stickiness, rng):
            return True, moves
        rs[0], rs[1], rs[2], rs[3], u[0], u[1], u[2] = drift_dir(rs[0], rs[1], rs[2], rs[3], dim, kappa, a0, a1, a2)
        dot = u[0] * normal[0] + u[1] * normal[1] + u[2] * normal[2]
        if dot < 0.0:
            for a in range(3):
                u[a] -= 2.0 * dot * normal[a]
        moves += 1
        if not cast(w, u, REJECT, dim, size, line, pts, nxt, gi, gf, dirr, heads, lx, ly, lz, li, normal):
            return False, moves


