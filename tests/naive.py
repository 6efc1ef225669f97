"""Slow, obviously right references the suite checks the package against, in one place.

Each computes one documented quantity the direct way, one point (one box,
one prefix) at a time, for small inputs, reusing nothing of the package.
Among them the kernels' references: a lattice walk of single steps and a
walk-on-spheres, and the contact checks of grown clusters (every particle
rests on an earlier one, none overlap).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from scipy.spatial import cKDTree


def grid_offsets(scales, offsets=4):
    """O(s) of every side s: floor(t s / offsets) for t < offsets, joined with O(s/2) when s/2 is a side too."""
    out = {}
    for s in sorted({int(s) for s in scales}):
        out[s] = {t * s // offsets for t in range(offsets)} | (out.get(s // 2, set()) if s % 2 == 0 else set())
    return out


def box_count(points, scale, lattice, offsets):
    """The documented rule, one grid, one point and one box at a time.

    Every grid anchored at ``min(points) - 1/2 - o`` is tried, o taking each
    value of ``offsets`` (O(scale)) on each axis independently.
    """
    points = np.asarray(points, float)
    points = points - points.min(axis=0)  # so the extreme disks touch the first box's edge exactly
    best = None
    for o in itertools.product(sorted(offsets), repeat=points.shape[1]):
        origin = [-0.5 - a for a in o]
        boxes = set()
        for p in points.tolist():
            u = [x - c for x, c in zip(p, origin)]  # in the grid's frame, box b spans [b * scale, (b + 1) * scale)
            if lattice:
                boxes.add(tuple(math.floor(x / scale) for x in u))
                continue
            # Every box meeting the disk's bounding box; kept if its nearest point lies closer than 1/2.
            near = [range(math.floor((x - 0.5) / scale), math.floor((x + 0.5) / scale) + 1) for x in u]
            for box in itertools.product(*near):
                if sum((x - min(max(x, b * scale), (b + 1) * scale)) ** 2 for x, b in zip(u, box)) < 0.25:
                    boxes.add(box)
        best = len(boxes) if best is None else min(best, len(boxes))
    return best


def anisotropy(points, m):
    """<cos 4 theta> (2D) of the outer half of the first m points, from angles, one point at a time."""
    seed = points[0]
    distance = [np.hypot(*(p - seed)) for p in points[1:m]]
    cut = np.median(distance)
    values = [np.cos(4 * np.arctan2(*(p - seed)[::-1])) for p, d in zip(points[1:m], distance) if d >= cut]
    return np.mean(values)


def radius_of_gyration(points):
    """Rg of every prefix: the root mean square distance from the prefix's centre of mass."""
    points = np.asarray(points, float)
    return np.array([np.sqrt(((points[:k] - points[:k].mean(axis=0)) ** 2).sum(axis=1).mean())
                     for k in range(1, len(points) + 1)])


def max_radius(points):
    """Largest distance from the seed (the first point) of every prefix."""
    distance = np.sqrt(((np.asarray(points, float) - points[0]) ** 2).sum(axis=1))
    return np.array([distance[:k].max() for k in range(1, len(points) + 1)])


def lattice_exits(moves, r, walks, rng):
    """Where ``walks`` walks of single steps (``moves``, rows of unit moves) from the origin first reach
    half-width ``r``, the square (cube) of sites with max |x_a| = r: an (walks, dim) array."""
    x = np.zeros((walks, moves.shape[1]), np.int64)
    alive = np.ones(walks, bool)
    while alive.any():
        idx = np.flatnonzero(alive)
        x[idx] += moves[rng.integers(len(moves), size=len(idx))]
        alive[idx] = np.abs(x[idx]).max(1) < r
    return x


def brownian_square_exits(dim, n, rng, eps=1e-7):
    """Where ``n`` Brownian paths from the centre first leave the square (cube) [-1, 1]^dim, by
    walk-on-spheres: jump to a uniform point of the largest sphere inside, until within ``eps`` of a
    face, then onto it. Returns (n, dim) points of the boundary."""
    x = np.zeros((n, dim))
    alive = np.ones(n, bool)
    while alive.any():
        idx = np.flatnonzero(alive)
        gap = 1.0 - np.abs(x[idx]).max(1)
        done = gap < eps
        out = idx[done]
        axis = np.abs(x[out]).argmax(1)
        x[out, axis] = np.sign(x[out, axis])
        alive[out] = False
        idx = idx[~done]
        u = rng.normal(size=(len(idx), dim))
        x[idx] += gap[~done, None] * u / np.linalg.norm(u, axis=1, keepdims=True)
    return x


def walk_on_spheres_exterior(dim, r0, far, n, rng, eps=1e-7):
    """Brownian paths from radius ``r0`` by walk-on-spheres in the shell 1 < r < ``far``.

    Returns where each walker stopped, projected on the unit sphere, and a
    mask of those that reached it (within ``eps``) before ``far``.
    """
    x = np.zeros((n, dim))
    x[:, 0] = r0
    alive = np.ones(n, bool)
    hit = np.zeros(n, bool)
    while alive.any():
        idx = np.flatnonzero(alive)
        r = np.linalg.norm(x[idx], axis=1)
        back = r - 1 < eps
        out = r > far * (1 - 1e-9)
        hit[idx[back]] = True
        alive[idx[back | out]] = False
        idx = idx[~(back | out)]
        r = r[~(back | out)]
        u = rng.normal(size=(len(idx), dim))
        u /= np.linalg.norm(u, axis=1)[:, None]
        x[idx] += np.minimum(r - 1, far - r)[:, None] * u + 1e-12
    return x / np.linalg.norm(x, axis=1)[:, None], hit


def walk_on_spheres_interior(dim, start, n, rng, eps=1e-7):
    """Where Brownian paths from ``start`` (inside the unit ball about 0) leave the ball, by
    walk-on-spheres until within ``eps`` of its sphere, projected on it."""
    x = np.tile(np.asarray(start, float), (n, 1))
    alive = np.ones(n, bool)
    while alive.any():
        idx = np.flatnonzero(alive)
        gap = 1.0 - np.linalg.norm(x[idx], axis=1)
        alive[idx[gap < eps]] = False
        idx, gap = idx[gap >= eps], gap[gap >= eps]
        u = rng.normal(size=(len(idx), dim))
        x[idx] += gap[:, None] * u / np.linalg.norm(u, axis=1)[:, None]
    return x / np.linalg.norm(x, axis=1)[:, None]


def _lattice_contacts(dim, moore):
    for d in itertools.product((-1, 0, 1), repeat=dim):
        a = np.abs(d)
        if (a.max() == 1) if moore else (a.sum() == 1):
            yield np.array(d)


def seed_count(params):
    """Particles placed before growth starts."""
    return {"point": 1, "block": 2 ** params["dim"], "line": 0}[params["seed_shape"]]


def assert_lattice_connected(points, params):
    """Every particle is a neighbour of an earlier one (or of the substrate)."""
    dim = params["dim"]
    line = params["seed_shape"] == "line"
    period = params["size"]
    seeds = seed_count(params)
    contacts = list(_lattice_contacts(dim, params["neighbours"] == 3**dim - 1))
    index = {}
    for i, p in enumerate(map(tuple, points)):
        assert p not in index, f"site {p} used twice (particles {index.get(p)} and {i})"
        if line:
            assert all(0 <= c < period for c in p[:-1]) and p[-1] >= 0
        if i >= seeds and not (line and p[-1] == 0):
            touching = False
            for d in contacts:
                q = np.array(p) + d
                if line:
                    q[:-1] %= period
                if tuple(q) in index:
                    touching = True
                    break
            assert touching, f"particle {i} at {p} touches no earlier particle"
        index[p] = i


def _periodic_tree(points, params):
    if params["seed_shape"] == "line":
        box = np.full(params["dim"], np.inf)
        box[:-1] = params["size"]
        shifted = points.copy()
        shifted[:, -1] -= points[:, -1].min()  # cKDTree wants coordinates in [0, box)
        return cKDTree(shifted, boxsize=np.where(np.isinf(box), shifted[:, -1].max() + 10, box)), shifted
    return cKDTree(points), points


def assert_offlattice_contacts(points, params, exact):
    """No overlaps; each particle rests on an earlier one at distance 1."""
    tree, pts = _periodic_tree(points, params)
    seeds = seed_count(params)
    dist, _ = tree.query(pts, k=2)
    assert dist[:, 1].min() >= 1 - 1e-9, f"overlap: closest pair at {dist[:, 1].min()}"
    if not exact:
        return
    for i in range(seeds, len(pts)):
        if params["seed_shape"] == "line" and abs(points[i, -1]) < 1e-9:
            continue
        near = tree.query_ball_point(pts[i], 1 + 1e-9)
        assert any(j < i for j in near), f"particle {i} touches no earlier particle"


def contacts(points, params):
    """Distance of each particle to the nearest earlier one (or substrate)."""
    p = np.asarray(points)
    line = params["seed_shape"] == "line"
    out = []
    for i in range(seed_count(params), len(p)):
        d = p[:i] - p[i]
        if line:
            L = params["size"]
            d[:, :-1] -= L * np.round(d[:, :-1] / L)
        near = np.sqrt((d**2).sum(1)).min() if i else np.inf
        if line:
            near = min(near, 1.0 + p[i, -1])  # substrate: contact at up = 0
        out.append(near)
    return np.array(out)


def min_pair(points, params):
    """Distance of the closest pair of particles (across the periodic sides of a substrate)."""
    p = np.asarray(points)
    if params["seed_shape"] == "line":  # periodic sides: add images
        L = params["size"]
        shifts = [np.zeros(p.shape[1])]
        for a in range(p.shape[1] - 1):
            for s in (-L, L):
                e = np.zeros(p.shape[1])
                e[a] = s
                shifts.append(e)
        tree = cKDTree(p)
        return min(tree.query(p + s, k=2)[0][:, 1 if not s.any() else 0].min() for s in shifts)
    return cKDTree(p).query(p, k=2)[0][:, 1].min()


def field_distances(field, dim, fw, cap, packed=False):
    """The distances a kernel's distance field (``maps.field_cell``'s tiles,
    ``cap - distance`` stored; ``packed``: two cells a byte, the even one in the low
    four bits) holds, as an array of ``fw`` cells a side, axes in order."""
    from dlasweep.kernels import maps

    out = np.zeros((fw,) * dim, np.int64)
    for c in np.ndindex(*out.shape):
        cell = maps.field_cell(dim, fw, *c, *([0] * (3 - dim)))
        value = (int(field[cell // 2]) >> (4 * (cell % 2))) % 16 if packed else int(field[cell])
        out[c] = cap - value
    return out


def centre_distances(unit, dim, fw, side, units, top):
    """The centre field a kernel should hold, as an array of ``fw`` coarse cells a side:
    the distance from each cell's centre (cells of ``side`` sites) to the nearest of the
    unit cells ``unit`` (whole sites, one a row), in ``units`` a site rounded down, at
    most ``top``. Brute force over every cell and unit cell."""
    axes = np.meshgrid(*[np.arange(fw)] * dim, indexing="ij")
    centres = np.stack(axes, -1).reshape(-1, dim) * side + side / 2
    best = np.empty(len(centres))
    for lo in range(0, len(centres), 256):
        gaps = np.maximum(np.abs(centres[lo:lo + 256, None, :] - (unit[None] + 0.5)) - 0.5, 0.0)
        best[lo:lo + 256] = (gaps**2).sum(-1).min(1)
    return np.minimum(np.floor(np.sqrt(units * units * best)), top).astype(np.int64).reshape((fw,) * dim)
