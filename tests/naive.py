"""Slow, obviously right references the suite checks the package against, in one place.

Each computes one documented quantity the direct way, one point (one box,
one prefix) at a time, for small inputs, reusing nothing of the package.
Among them the kernels' references: a lattice walk of single steps, a
walk-on-spheres, an off-lattice growth by drifted Gaussian steps, and the
contact checks of grown clusters (every particle rests on an earlier one, none
overlap).
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


# ------------------------------------------------- drifted Gaussian steps, off the lattice -----

GAUSS_FIELD_CAP = 8
"""Cells about a new particle (Chebyshev radius) whose bound on the distance to the nearest centre
``gaussian_drift_cluster`` lowers; farther cells keep the cap, itself then a bound."""
GAUSS_SHRINK = 6.0
"""A step's spread and its drift are each at most the walker's free distance g over this: its path strays
beyond g only if the Brownian part exceeds 5 spreads (a chance of about 3e-5 a step in 3D, less in 2D), and
only then can it touch a particle that its end point does not."""
GAUSS_NEAR = 0.02
"""The smallest step's spread (diameters), every step's within 0.12 (``GAUSS_SHRINK`` of it) of contact: an
end-point check misses the contacts of a step's path between its ends, which moves the absorbing surface in by
about 0.58 spreads (Siegmund's correction), 0.012 of a diameter."""


def drift_mu(params):
    """The drift vector (x, y, z; z 0 in 2D) as the parameter table defines it: ``drift`` (v / 2D) along
    the unit vector ``drift_angle`` degrees from down (-y in 2D, -z in 3D) towards +x, turned
    ``drift_azimuth`` degrees about the vertical from +x towards +y in 3D."""
    theta, phi = math.radians(params["drift_angle"]), math.radians(params["drift_azimuth"])
    if params["dim"] == 2:
        unit = (math.sin(theta), -math.cos(theta), 0.0)
    else:
        unit = (math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), -math.cos(theta))
    return np.array(unit) * params["drift"]


def gaussian_drift_cluster(n, params, seed):
    """An off-lattice cluster of ``n`` grown by walkers that take Gaussian steps of drifted Brownian motion.

    In the time unit where D is 1/2 the drift's velocity is mu (``drift_mu``), so a step of spread s an axis
    lasts s**2 and moves by mu s**2 plus N(0, s**2) an axis: exact in free space, whatever s. The spread
    adapts to a lower bound g on the walker's free distance (a distance field, exact centre distances within
    two cells, the cluster's bounding circle or height, the kill circle, the substrate): s = min(g, sqrt(g /
    |mu|)) / ``GAUSS_SHRINK``, at least ``GAUSS_NEAR``. A step whose end overlaps a particle (or goes below
    the substrate) stops where its straight path first touches, and the walker sticks. The geometry is the
    package's: a point seed at the origin, walkers released uniformly on the circle (sphere) of radius
    ``launch_factor`` * r_max + ``launch_margin`` and killed at ``kill_factor`` times it; over a substrate at
    height 0 with sides of period ``size``, released uniformly at ``launch_factor`` * max(h_max, 0) +
    ``launch_margin``, and above it walking on (the exact return's law, not drawn). Nothing of the package:
    numba, a cell list of unit cells.

    Returns the centres, (n, dim).
    """
    dim, line = params["dim"], params["seed_shape"] == "line"
    size = params["size"] if line else 0
    # the grid's extent: wide enough for the cluster, its field's reach and the scans (checked as it grows)
    half = 16 + GAUSS_FIELD_CAP + int(3 * n ** (1 / (dim - 0.3)))
    height = 64 + GAUSS_FIELD_CAP + int(16 * n / size ** (dim - 1)) if line else 0
    points = _gaussian_drift_cluster(n, dim, drift_mu(params), line, size, half, height, params["launch_factor"],
                                     params["launch_margin"], params["kill_factor"], np.random.default_rng(seed))
    return points[:, :dim]


def _njit(f):
    import numba

    return numba.njit(f)


@_njit
def _gaussian_drift_cluster(n, dim, mu, line, size, half, height, launch_factor, launch_margin, kill_factor, rng):
    up = dim - 1
    widths = np.ones(3, np.int64)  # unit cells: periodic sides over a substrate, a box of ``half`` about a point
    offsets = np.zeros(3, np.int64)
    periodic = np.zeros(3, np.bool_)
    for a in range(dim):
        if line and a < up:
            widths[a], periodic[a] = size, True
        elif line:
            widths[a] = height
        else:
            widths[a], offsets[a] = 2 * half, half
    heads = np.full(widths[0] * widths[1] * widths[2], -1, np.int64)
    field = np.full(widths[0] * widths[1] * widths[2], float(GAUSS_FIELD_CAP))
    pts = np.zeros((n, 3))
    nxt = np.full(n, -1, np.int64)
    grid = (pts, nxt, heads, widths, offsets, periodic, dim, size)
    count, r_max, h_max = 0, 0.0, -1.0
    if not line:
        count = 1  # the seed, at the origin
        _gauss_insert(grid, 0, field)
    mu_abs = np.sqrt(mu[0] ** 2 + mu[1] ** 2 + mu[2] ** 2)
    w, e = np.zeros(3), np.zeros(3)
    while count < n:
        launch_r = launch_factor * (max(h_max, 0.0) if line else r_max) + launch_margin
        kill_r = kill_factor * launch_r
        if line:
            for a in range(up):
                w[a] = rng.random() * size
            w[up] = launch_r
        else:
            norm = 0.0
            for a in range(dim):
                w[a] = rng.standard_normal()
                norm += w[a] * w[a]
            for a in range(dim):
                w[a] *= launch_r / np.sqrt(norm)
        stuck = False
        while True:
            # g, a lower bound on the free distance
            cell = _gauss_cell(grid, w)
            g = 0.0
            if cell >= 0:
                g = field[cell] - 1.0
                if g < 1.0:  # exact within two cells
                    g = min(np.sqrt(_gauss_nearest2(grid, w, 2)), 2.0) - 1.0
            if line:
                g = min(max(g, w[up] - h_max - 1.0), w[up])
            else:
                r = np.sqrt(w[0] ** 2 + w[1] ** 2 + w[2] ** 2)
                g = min(max(g, r - r_max - 1.0), kill_r - r)
            s = g if mu_abs == 0.0 else min(g, np.sqrt(g / mu_abs))
            s = max(s / GAUSS_SHRINK, GAUSS_NEAR)
            moved = 0.0
            for a in range(dim):
                e[a] = w[a] + mu[a] * s * s + s * rng.standard_normal()
                moved += (e[a] - w[a]) ** 2
            if moved >= g * g:  # only a step beyond g can end in contact
                t = _gauss_first_touch(grid, w, e, line)
                if t <= 1.0:
                    for a in range(dim):
                        w[a] += t * (e[a] - w[a])
                    if line:
                        w[up] = max(w[up], 0.0)  # on the substrate, not below it by rounding
                    stuck = True
                    break
                if not line and e[0] ** 2 + e[1] ** 2 + e[2] ** 2 >= kill_r * kill_r:
                    break  # killed: a new walker
            for a in range(dim):
                w[a] = e[a] % size if periodic[a] else e[a]
        if not stuck:
            continue
        for a in range(dim):
            pts[count, a] = w[a]
            c = int(np.floor(w[a])) + offsets[a]
            if not periodic[a] and not (0 if line else 3 + GAUSS_FIELD_CAP) <= c < widths[a] - 3 - GAUSS_FIELD_CAP:
                raise ValueError("the cluster outgrew the reference's grid")
        _gauss_insert(grid, count, field)
        r_max = max(r_max, np.sqrt(w[0] ** 2 + w[1] ** 2 + w[2] ** 2))
        h_max = max(h_max, w[up])
        count += 1
    return pts


@_njit
def _gauss_cell(grid, x):
    """The index of x's cell, -1 outside the grid."""
    _, _, _, widths, offsets, periodic, dim, _ = grid
    k = 0
    for a in range(3):
        c = int(np.floor(x[a])) + offsets[a] if a < dim else 0
        c = c % widths[a] if periodic[a] else c
        if not 0 <= c < widths[a]:
            return -1
        k = k * widths[a] + c
    return k


@_njit
def _gauss_cells(grid, x, reach):
    """The cells within ``reach`` (Chebyshev) of x's, each as (index, offsets along the three axes)."""
    _, _, _, widths, offsets, periodic, dim, _ = grid
    out = []
    r2 = reach if dim == 3 else 0
    c0 = int(np.floor(x[0])) + offsets[0]
    c1 = int(np.floor(x[1])) + offsets[1]
    c2 = int(np.floor(x[2])) + offsets[2] if dim == 3 else 0
    for d0 in range(-reach, reach + 1):
        for d1 in range(-reach, reach + 1):
            for d2 in range(-r2, r2 + 1):
                k = 0
                for a, c in ((0, c0 + d0), (1, c1 + d1), (2, c2 + d2)):
                    c = c % widths[a] if periodic[a] else c
                    if not 0 <= c < widths[a]:
                        k = -1
                        break
                    k = k * widths[a] + c
                if k >= 0:
                    out.append((k, d0, d1, d2))
    return out


@_njit
def _gauss_insert(grid, i, field):
    """Link particle i into its cell, and lower the distance field about it: a cell k cells along an axis
    is at least max(k - f, 0, f - k - 1) away on it, f the particle's place in its own cell."""
    pts, nxt, heads, _, _, _, dim, _ = grid
    k = _gauss_cell(grid, pts[i])
    nxt[i] = heads[k]
    heads[k] = i
    f = pts[i] - np.floor(pts[i])
    for k, d0, d1, d2 in _gauss_cells(grid, pts[i], GAUSS_FIELD_CAP):
        gap = 0.0
        for a, d in ((0, d0), (1, d1), (2, d2)):
            if a < dim:
                gap += max(d - f[a], 0.0, f[a] - d - 1.0) ** 2
        field[k] = min(field[k], np.sqrt(gap))


@_njit
def _gauss_offset(grid, x, j):
    """x minus particle j's centre, the nearest image across periodic sides."""
    pts, _, _, _, _, periodic, dim, size = grid
    d = np.zeros(3)
    for a in range(dim):
        d[a] = x[a] - pts[j, a]
        if periodic[a]:
            d[a] -= size * np.round(d[a] / size)
    return d


@_njit
def _gauss_nearest2(grid, x, reach):
    """The squared centre distance from x to the nearest particle within ``reach`` cells (inf if none)."""
    _, nxt, heads, _, _, _, _, _ = grid
    best = np.inf
    for k, _, _, _ in _gauss_cells(grid, x, reach):
        j = heads[k]
        while j >= 0:
            best = min(best, (_gauss_offset(grid, x, j) ** 2).sum())
            j = nxt[j]
    return best


@_njit
def _gauss_first_touch(grid, w, e, line):
    """Where along the step from w to e, as a fraction, the walker first touches a particle or the
    substrate, when e overlaps one (else 2): the end point decides contact, the straight path places it."""
    _, nxt, heads, _, _, _, dim, _ = grid
    up = dim - 1
    below = line and e[up] < 0.0
    if not below and (_gauss_cell(grid, e) < 0 or _gauss_nearest2(grid, e, 1) >= 1.0):
        return 2.0
    best = w[up] / (w[up] - e[up]) if below else 1.0
    step = e - w
    a2 = (step ** 2).sum()
    for k, _, _, _ in _gauss_cells(grid, w, int(np.sqrt(a2)) + 2):
        j = heads[k]
        while j >= 0:
            d = _gauss_offset(grid, w, j)  # |d + t step| = 1, its smaller root
            b = 2.0 * (step * d).sum()
            disc = b * b - 4.0 * a2 * ((d ** 2).sum() - 1.0)
            if disc >= 0.0:
                t = (-b - np.sqrt(disc)) / (2.0 * a2)
                if 0.0 <= t < best:
                    best = t
            j = nxt[j]
    return best
