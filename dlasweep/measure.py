"""Geometry of point sets: box counts and mass-radius measures.

Pure functions of an ``(n, dim)`` point array (dim 2 or 3) in attachment
order; no I/O. Lengths are in lattice units (off-lattice: particle diameters).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from ._jit import inline, jit

_HALF = 0.5
"""Half-width of a particle: a lattice site is a unit cell, a disk/sphere has unit diameter."""


def default_scales(max_extent: float, per_octave: int = 4) -> np.ndarray:
    """Whole box sides ``b * 2**j`` (b odd, below ``2 * per_octave``), from 1 up to ``max_extent``.

    For ``per_octave=4``: 1, 2, ..., 8, 10, 12, 14, 16, 20, 24, 28, 32, 40, ...
    (every integer up to ``2 * per_octave``, then ``per_octave`` sides per
    factor of two). The last side is the first one >= ``max_extent``, so a set
    of that extent fits in one box there. Every side but the largest few has
    its double in the series: the series is made of the families
    (b, 2b, 4b, ...) that ``box_counts`` measures by halving bitmaps. A sweep
    passes one shared series to every cluster.

    Parameters
    ----------
    max_extent : float
        Largest extent (in particle sizes) the sides must reach.
    per_octave : int
        Sides per factor of two from ``per_octave`` on; a power of two.

    Returns
    -------
    ndarray of float64
        Whole numbers, increasing, starting at 1.
    """
    if per_octave < 1 or per_octave & (per_octave - 1):
        raise ValueError(f"per_octave: {per_octave} is not a power of two")
    sides = [1]
    while sides[-1] < max_extent:
        # The next b * 2**j: the integers up to 2p, then steps of 2**j in [p 2**j, 2p 2**j).
        sides.append(sides[-1] + (1 << max((sides[-1] // per_octave).bit_length() - 1, 0)))
    return np.array(sides, np.float64)


_BITMAP_CAP = 1 << 31
"""Most bits (256 MiB) a grid's occupancy bitmap may take; larger grids are counted by sorting their boxes."""

_EVEN = np.uint64(0x5555555555555555)
"""The even bits of a word."""


@jit
def _first_axis_order(points, top):
    """``points`` sorted by the integer part of the first coordinate (a stable counting sort)."""
    start = np.zeros(top + 2, np.int64)
    for i in range(len(points)):
        start[np.int64(np.floor(points[i, 0])) + 1] += 1
    for c in range(1, top + 2):
        start[c] += start[c - 1]
    out = np.empty_like(points)
    for i in range(len(points)):
        c = np.int64(np.floor(points[i, 0]))
        out[start[c]] = points[i]
        start[c] += 1
    return out


@jit
def _mark_boxes(points, origin, scale, radius, shape, bitmap, out):
    """Set the bit of every box of side ``scale`` that a particle touches; return how many were new.

    ``radius == 0`` puts each particle in the one box holding its centre;
    ``radius > 0`` in every box its ball overlaps. ``origin`` and ``shape``
    are tuples (so the loops over axes unroll). ``bitmap`` has a row per box
    of the leading axes (row-major) and a bit per box of the last axis. With
    an empty ``bitmap`` every visit is written to ``out`` and counted instead.
    """
    dim = len(origin)
    home = np.zeros(dim, np.int64)
    step = np.zeros(dim, np.int64)
    gap2 = np.zeros(dim)
    r2 = radius * radius
    corners = 1 << dim if radius > 0.0 else 1
    dense = bitmap.shape[0] > 0
    count = 0
    for i in range(len(points)):
        for a in range(dim):
            u = points[i, a] - origin[a]
            home[a] = np.int64(np.floor(u / scale))
            if radius > 0.0:
                # With s >= 2r a ball reaches at most across the nearer face of
                # its home box on each axis; this is that face's distance.
                below = u - home[a] * scale
                above = (home[a] + 1) * scale - u
                step[a] = -1 if below <= above else 1
                gap2[a] = min(below, above) ** 2
        # Home box, then the neighbours across the near faces (and edges and
        # corners) whose nearest point lies within r.
        for corner in range(corners):
            d2 = 0.0
            for a in range(dim):
                if (corner >> a) & 1:
                    d2 += gap2[a]
            if corner > 0 and d2 >= r2:
                continue
            row = 0
            for a in range(dim - 1):
                row = row * shape[a] + home[a] + (step[a] if (corner >> a) & 1 else 0)
            last = home[dim - 1] + (step[dim - 1] if (corner >> (dim - 1)) & 1 else 0)
            if dense:
                word = bitmap[row, last >> 6]
                bit = np.uint64(1) << np.uint64(last & 63)
                count += (word & bit) == 0
                bitmap[row, last >> 6] = word | bit
            else:
                for a in range(dim):
                    out[count, a] = home[a] + (step[a] if (corner >> a) & 1 else 0)
                count += 1
    return count


@inline
def _pairs(word):
    """Halve a word: bit k (k < 32) of the result is set when bit 2k or 2k + 1 of ``word`` is."""
    x = (word | (word >> np.uint64(1))) & _EVEN
    x = (x | (x >> np.uint64(1))) & np.uint64(0x3333333333333333)
    x = (x | (x >> np.uint64(2))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    x = (x | (x >> np.uint64(4))) & np.uint64(0x00FF00FF00FF00FF)
    x = (x | (x >> np.uint64(8))) & np.uint64(0x0000FFFF0000FFFF)
    return (x | (x >> np.uint64(16))) & np.uint64(0x00000000FFFFFFFF)


@inline
def _ones(word):
    """Number of set bits."""
    x = word - ((word >> np.uint64(1)) & _EVEN)
    x = (x & np.uint64(0x3333333333333333)) + ((x >> np.uint64(2)) & np.uint64(0x3333333333333333))
    x = (x + (x >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return np.int64((x * np.uint64(0x0101010101010101)) >> np.uint64(56))


@jit
def _halve(fine, fine_shape, fine_per_axis, source, shift, coarse, shape):
    """Fill ``coarse``, the bitmaps of grids of twice the side of ``fine``'s, and return their least count.

    Both are stacks of bitmaps laid out as in ``_mark_boxes``, one per grid;
    grid g's offset on axis a is digit a of g (axis 0 most significant) in
    base ``len(source)`` for ``coarse``, ``fine_per_axis`` for ``fine``. On an
    axis where a coarse grid has offset i, its box b covers boxes
    2b - shift[i] and 2b + 1 - shift[i] of the fine grid of offset source[i].
    """
    dim = len(shape)
    merged = np.zeros(2 * coarse.shape[2], np.uint64)
    index = np.zeros(dim, np.int64)
    step = np.zeros(dim, np.int64)
    best = -1
    for g in range(coarse.shape[0]):
        rest, grid, unit = g, 0, 1
        for a in range(dim - 1, -1, -1):
            i = rest % len(source)
            rest //= len(source)
            step[a] = shift[i]
            grid += source[i] * unit
            unit *= fine_per_axis
        count = 0
        for row in range(coarse.shape[1]):
            rest = row
            for a in range(dim - 2, -1, -1):
                index[a] = rest % shape[a]
                rest //= shape[a]
            # OR of the fine rows under this coarse row, moved one bit up when
            # shifted so that fine bits 2b - shift, 2b + 1 - shift pair up.
            merged[:] = 0
            for corner in range(1 << (dim - 1)):
                fine_row = 0
                for a in range(dim - 1):
                    r = 2 * index[a] - step[a] + ((corner >> a) & 1)
                    if r < 0 or r >= fine_shape[a]:
                        fine_row = -1
                        break
                    fine_row = fine_row * fine_shape[a] + r
                if fine_row >= 0:
                    for w in range(fine.shape[2]):
                        merged[w] |= fine[grid, fine_row, w]
            if step[dim - 1]:
                carry = np.uint64(0)
                for w in range(len(merged)):
                    merged[w], carry = (merged[w] << np.uint64(1)) | carry, merged[w] >> np.uint64(63)
            for w in range(coarse.shape[2]):
                word = _pairs(merged[2 * w]) | (_pairs(merged[2 * w + 1]) << np.uint64(32))
                coarse[g, row, w] = word
                count += _ones(word)
        best = count if best < 0 else min(best, count)
    return best


def _empty_bitmaps(shape, grids):
    """Zeroed bitmaps for ``grids`` grids of ``shape``, or None when they would exceed ``_BITMAP_CAP`` bits."""
    rows, words = math.prod(int(n) for n in shape[:-1]), -(-int(shape[-1]) // 64)
    return np.zeros((grids, rows, words), np.uint64) if grids * rows * words * 64 <= _BITMAP_CAP else None


def _from_points(points, high, offsets, scale, radius, keep):
    """Least count over the grids of side ``scale`` with per-axis ``offsets``, from the particles.

    Also returns their stacked bitmaps (None unless ``keep`` and they fit the
    cap) and the grids' common shape. A grid too large for a bitmap is
    counted by sorting its boxes.
    """
    dim = points.shape[1]
    # Anchored at -1/2 - offset: the largest offset needs the most boxes.
    shape = np.floor((high + radius + _HALF + offsets[-1]) / scale).astype(np.int64) + 1
    grids = list(itertools.product(offsets, repeat=dim))
    stack = _empty_bitmaps(shape, len(grids)) if keep else None
    best = None
    for g, offset in enumerate(grids):
        args = (points, tuple(-_HALF - o for o in offset), float(scale), radius, tuple(shape))
        bitmap = stack[g : g + 1] if stack is not None else _empty_bitmaps(shape, 1)
        if bitmap is not None:
            count = _mark_boxes(*args, bitmap[0], np.empty((0, 0), np.int64))
        else:
            visits = np.empty((len(points) * (2**dim if radius > 0.0 else 1), dim), np.int64)
            count = len(np.unique(visits[: _mark_boxes(*args, np.empty((0, 0), np.uint64), visits)], axis=0))
        best = count if best is None else min(best, count)
    return best, stack, shape


def box_counts(points, lattice: bool = True, scales=None, offsets: int = 4):
    """Number of boxes of side s that the set occupies, for a series of whole s.

    Rules: with ``lattice=True`` each point is a unit cell centred on its
    coordinates and counts in the one box holding its centre (for integer
    points that box holds the whole cell). With ``lattice=False`` each point
    is a disk/sphere of unit diameter and counts in every box its interior
    overlaps (nearest point of the box closer than 1/2 to the centre), so one
    particle may count in up to 2**dim boxes.

    Boxes are placed to minimise the count: a grid's corner sits at
    ``min(points) - 1/2 - o``, o an integer offset chosen on each axis from
    O(s) = {floor(t s / offsets) : t < offsets}, joined with O(s/2) when s/2
    is among the scales; every combination of per-axis offsets is tried and
    the smallest count kept. As O(2s) holds O(s) and a 2s-box is a union of
    s-boxes, the count never rises from s to 2s.

    Parameters
    ----------
    points : array_like, (n, dim)
        Any point set, dim 2 or 3.
    lattice : bool
        Lattice sites (True) or off-lattice unit-diameter particles (False).
    scales : array_like, optional
        Box sides, whole numbers >= 1. Default: ``default_scales`` up to the
        set's extent. Scales beyond the extent give a count of 1.
    offsets : int
        Number of t in a side's own offsets floor(t s / offsets) per axis.

    Returns
    -------
    scales : ndarray of float64
    counts : ndarray of int64
    """
    p = np.asarray(points)
    if p.ndim != 2 or p.shape[1] not in (2, 3) or len(p) == 0:
        raise ValueError(f"points: expected a non-empty (n, 2) or (n, 3) array, got shape {p.shape}")
    p = p.astype(np.int64 if p.dtype.kind in "iub" else np.float64, copy=False)
    if not np.isfinite(p).all():
        raise ValueError("points: every coordinate must be finite")
    if offsets < 1:
        raise ValueError(f"offsets: {offsets} is below 1")
    # Coordinates from the low corner, so the extreme particles sit exactly
    # (not within rounding) half a particle inside the first box. Column by
    # column: numpy reduces an (n, 2) array along axis 0 ten times slower.
    p = p - np.array([c.min() for c in p.T])
    high = np.array([c.max() for c in p.T])
    extent = float(high.max()) + 2 * _HALF
    scales = default_scales(extent) if scales is None else np.asarray(scales, dtype=np.float64).ravel()
    # Whole sides and integer offsets put every lattice cell in one box, and
    # make a box of side 2s an exact union of boxes of side s.
    if len(scales) == 0 or not (np.isfinite(scales) & (scales >= 1.0) & (scales == np.floor(scales))).all():
        raise ValueError("scales: expected whole box sides >= 1 (the particle size)")
    radius = 0.0 if lattice else _HALF
    if p.dtype.kind == "i" and extent < 2**31:
        p = p.astype(np.int32)  # half the memory traffic
    # In first-axis order the bits a particle sets lie in rows near the
    # previous particle's: the bitmaps are read from cache, not memory.
    if high[0] <= max(len(p), 1 << 22):
        p = _first_axis_order(p, int(high[0]))
    dim = p.shape[1]
    sides = [int(s) for s in scales]
    first = {}
    for k, s in enumerate(sides):
        first.setdefault(s, k)
    parent = {k: first[s // 2] for k, s in enumerate(sides) if s % 2 == 0 and s // 2 in first}
    children = {}
    for k, m in parent.items():
        children.setdefault(m, []).append(k)
    grid_offsets = {}
    for k in sorted(range(len(sides)), key=sides.__getitem__):
        own = {t * sides[k] // offsets for t in range(offsets)}
        grid_offsets[k] = sorted(own.union(grid_offsets[parent[k]] if k in parent else ()))
    # One box of a side >= extent, placed at the low corner, holds the whole
    # set; a small cluster measured at a sweep's scales skips most of them.
    counts = np.ones(len(scales), np.int64)
    # Depth first along each family s, 2s, 4s, ..., so that only the bitmaps
    # of one side and its double are held; None means "from the particles".
    pending = [(k, None) for k in range(len(sides)) if k not in parent and sides[k] < extent]
    while pending:
        k, finer = pending.pop()
        side, own = sides[k], grid_offsets[k]
        kids = [c for c in children.get(k, ()) if sides[c] < extent]
        stack = None
        if finer is not None:
            # The box of side 2s at offset o is the union of 2**dim boxes of
            # the grid of side s at offset o % s, shifted by one where o >= s.
            fine, fine_shape, fine_own = finer
            shape = fine_shape // 2 + 1
            stack = _empty_bitmaps(shape, len(own) ** dim)
        if stack is None:
            counts[k], stack, shape = _from_points(p, high, own, side, radius, keep=bool(kids))
        else:
            half = side // 2
            source = np.array([fine_own.index(o % half) for o in own], np.int64)
            shift = np.array([o >= half for o in own], np.int64)
            counts[k] = _halve(fine, tuple(fine_shape), len(fine_own), source, shift, stack, tuple(shape))
        pending += [(c, None if stack is None else (stack, shape, own)) for c in kids]
    return scales, counts


@jit
def _prefix_gyration(points):
    n, dim = points.shape
    mean = np.zeros(dim)
    spread = 0.0
    out = np.empty(n)
    for k in range(n):
        for a in range(dim):
            delta = points[k, a] - mean[a]
            mean[a] += delta / (k + 1)
            # Welford: each increment is delta**2 * k/(k+1) >= 0, no cancellation.
            spread += delta * (points[k, a] - mean[a])
        out[k] = np.sqrt(spread / (k + 1))
    return out


def radius_of_gyration(points) -> np.ndarray:
    """Radius of gyration of every prefix of the set, in O(n).

    ``rg[k-1] = sqrt(mean_i |x_i - xbar_k|**2)`` over the first k points, each
    a point mass (no own moment of inertia), accumulated in float64 with
    Welford's update of the running mean and sum of squares.

    Parameters
    ----------
    points : array_like, (n, dim)
        Positions in attachment order.

    Returns
    -------
    ndarray of float64, (n,)
    """
    p = np.ascontiguousarray(points, dtype=np.float64)
    if p.ndim != 2:
        raise ValueError(f"points: expected an (n, dim) array, got shape {p.shape}")
    return _prefix_gyration(p)


def _seed_distances(points) -> np.ndarray:
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or len(p) == 0:
        raise ValueError(f"points: expected a non-empty (n, dim) array, got shape {p.shape}")
    return np.sqrt(((p - p[0]) ** 2).sum(axis=1))


def max_radius(points) -> np.ndarray:
    """Largest centre distance from the first point (the seed) in every prefix.

    Returns
    -------
    ndarray of float64, (n,)
    """
    return np.maximum.accumulate(_seed_distances(points))


def mass_within(points, radii) -> np.ndarray:
    """N(r): number of particles whose centre lies within r of the seed (first point).

    Parameters
    ----------
    points : array_like, (n, dim)
    radii : array_like
        Radii r; the seed itself is counted for every r >= 0.

    Returns
    -------
    ndarray of int64, shaped like ``radii``
    """
    distances = np.sort(_seed_distances(points))
    return np.searchsorted(distances, np.asarray(radii, dtype=np.float64), side="right").astype(np.int64)
