"""Geometry of point sets: box counts and mass-radius measures.

Pure functions of an ``(n, dim)`` point array (dim 2 or 3) in attachment
order; no I/O. Lengths are in lattice units (off-lattice: particle diameters).
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import inline, jit

_HALF = 0.5
"""Half-width of a particle: a lattice site is a unit cell, a disk/sphere has unit diameter."""


def default_scales(max_extent: float, per_octave: int = 4) -> np.ndarray:
    """Box sides ``2**(k/per_octave)``, k = 0, 1, ..., from 1 up to ``max_extent``.

    The last scale is the first one >= ``max_extent``, so a set of that extent
    fits in one box there. A sweep passes one shared series to every cluster.

    Parameters
    ----------
    max_extent : float
        Largest extent (in particle sizes) the scales must reach.
    per_octave : int
        Scales per factor of two.

    Returns
    -------
    ndarray of float64
    """
    if per_octave < 1:
        raise ValueError(f"per_octave: {per_octave} is below 1")
    # The tolerance keeps an exact power of two from gaining one extra scale.
    top = max(int(np.ceil(per_octave * np.log2(max(float(max_extent), 1.0)) - 1e-9)), 0)
    return 2.0 ** (np.arange(top + 1) / per_octave)


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
def _halve(fine, fine_shape, shift, coarse, shape):
    """Fill ``coarse``, the bitmap of boxes twice the side of ``fine``'s, and count its boxes.

    Coarse box b covers fine boxes 2b - shift and 2b + 1 - shift on every axis
    (``shift`` 0 or 1); bitmaps are laid out as in ``_mark_boxes``.
    """
    dim = len(shape)
    merged = np.zeros(2 * coarse.shape[1], np.uint64)
    index = np.zeros(dim, np.int64)
    count = 0
    for row in range(coarse.shape[0]):
        rest = row
        for a in range(dim - 2, -1, -1):
            index[a] = rest % shape[a]
            rest //= shape[a]
        # OR of the fine rows under this coarse row, moved one bit up when
        # shifted so that fine bits 2b - shift, 2b + 1 - shift pair up.
        merged[:] = 0
        for corner in range(1 << (dim - 1)):
            source = 0
            for a in range(dim - 1):
                r = 2 * index[a] - shift + ((corner >> a) & 1)
                if r < 0 or r >= fine_shape[a]:
                    source = -1
                    break
                source = source * fine_shape[a] + r
            if source >= 0:
                for w in range(fine.shape[1]):
                    merged[w] |= fine[source, w]
        if shift:
            carry = np.uint64(0)
            for w in range(len(merged)):
                merged[w], carry = (merged[w] << np.uint64(1)) | carry, merged[w] >> np.uint64(63)
        for w in range(coarse.shape[1]):
            word = _pairs(merged[2 * w]) | (_pairs(merged[2 * w + 1]) << np.uint64(32))
            coarse[row, w] = word
            count += _ones(word)
    return count


def _grid_shape(high, origin, scale, radius):
    return np.floor((high + radius - origin) / scale).astype(np.int64) + 1


def _empty_bitmap(shape):
    """A zeroed bitmap for a grid of ``shape``, or None when it would exceed ``_BITMAP_CAP`` bits."""
    rows, words = math.prod(int(n) for n in shape[:-1]), -(-int(shape[-1]) // 64)
    return np.zeros((rows, words), np.uint64) if rows * words * 64 <= _BITMAP_CAP else None


def _from_points(points, high, origin, scale, radius):
    """Count the boxes of one grid that the particles touch; also return its bitmap (None if too large)."""
    shape = _grid_shape(high, origin, scale, radius)
    bitmap = _empty_bitmap(shape)
    args = (points, tuple(origin), float(scale), radius, tuple(shape))
    if bitmap is not None:
        return _mark_boxes(*args, bitmap, np.empty((0, 0), np.int64)), bitmap, shape
    visits = np.empty((len(points) * (2 ** len(shape) if radius > 0.0 else 1), len(shape)), np.int64)
    return len(np.unique(visits[: _mark_boxes(*args, np.empty((0, 0), np.uint64), visits)], axis=0)), None, shape


def _halvings(scales):
    """Map each scale that is twice another to that one."""
    twice = np.isclose(2 * scales[None, :], scales[:, None], rtol=1e-9, atol=0.0)
    return {int(k): int(np.argmax(twice[k])) for k in np.flatnonzero(twice.any(axis=1))}


def box_counts(points, lattice: bool = True, scales=None, offsets: int = 4):
    """Number of boxes of side s that the set occupies, for a series of s.

    Rules: with ``lattice=True`` each point is a unit cell centred on its
    coordinates and counts in the one box holding its centre (for integer s
    on an aligned grid that box covers the whole cell). With ``lattice=False``
    each point is a disk/sphere of unit diameter and counts in every box its
    interior overlaps (nearest point of the box closer than 1/2 to the
    centre), so one particle may count in up to 2**dim boxes.

    Boxes are placed to minimise the count: the grid's corner sits at
    ``min(points) - 1/2 - (j / offsets) * s`` on every axis, j = 0 ..
    offsets-1 (shifts along the diagonal), and the smallest count is kept.

    Parameters
    ----------
    points : array_like, (n, dim)
        Any point set, dim 2 or 3.
    lattice : bool
        Lattice sites (True) or off-lattice unit-diameter particles (False).
    scales : array_like, optional
        Box sides, each >= 1. Default: ``default_scales`` up to the set's
        extent. Scales beyond the extent give a count of 1.
    offsets : int
        Number of grid placements tried per scale.

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
    if len(scales) == 0 or not (scales >= 1.0).all():
        raise ValueError("scales: expected box sides >= 1 (the particle size)")
    radius = 0.0 if lattice else _HALF
    if p.dtype.kind == "i" and extent < 2**31:
        p = p.astype(np.int32)  # half the memory traffic
    # In first-axis order the bits a particle sets lie in rows near the
    # previous particle's: the bitmaps are read from cache, not memory.
    if high[0] <= max(len(p), 1 << 22):
        p = _first_axis_order(p, int(high[0]))
    # Grid j of side 2t is made of boxes of grid (2j) % offsets of side t,
    # its corner (2j) // offsets t-boxes lower: its count follows from that
    # grid's bitmap, word by word, instead of from the particles.
    parent = _halvings(scales)
    needed, children = {}, {}
    for k, m in parent.items():
        needed.setdefault(m, set()).update(2 * j % offsets for j in range(offsets))
        children.setdefault(m, []).append(k)
    # One box of a side >= extent, placed at the low corner, holds the whole
    # set; a small cluster measured at a sweep's scales skips most of them.
    counts = np.ones(len(scales), np.int64)
    # Depth first, so that only the bitmaps on the current chain of halvings
    # are held; None means "from the particles".
    pending = [(k, None) for k in range(len(scales)) if k not in parent and scales[k] < extent]
    while pending:
        k, finer = pending.pop()
        kept, best = {}, None
        for j in range(offsets):
            if finer is None:
                origin = np.full(p.shape[1], -_HALF - (j / offsets) * scales[k])
                count, bitmap, shape = _from_points(p, high, origin, scales[k], radius)
            else:
                fine, fine_shape = finer[2 * j % offsets]
                shift = 2 * j // offsets
                shape = (fine_shape - 1 + shift) // 2 + 1
                bitmap = _empty_bitmap(shape)
                count = _halve(fine, tuple(fine_shape), shift, bitmap, tuple(shape))
            best = count if best is None else min(best, count)
            if bitmap is not None and j in needed.get(k, ()):
                kept[j] = (bitmap, shape)
        counts[k] = best
        complete = needed.get(k, set()) <= set(kept)
        pending += [(child, kept if complete else None) for child in children.get(k, []) if scales[child] < extent]
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
