"""Geometry of point sets: box counts and mass-radius measures.

Pure functions of an ``(n, dim)`` point array (dim 2 or 3) in attachment
order; no I/O. Lengths are in lattice units (off-lattice: particle diameters).
"""

from __future__ import annotations

import numpy as np

from ._jit import jit

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


@jit
def _occupied_boxes(points, origin, scale, radius, shape, bitmap, keys):
    """Write the row-major index of every box of side ``scale`` a particle touches to ``keys``.

    ``radius == 0`` puts each particle in the one box holding its centre;
    ``radius > 0`` puts it in every box its ball overlaps. With a non-empty
    ``bitmap`` (one zeroed bit per box) each box is written once and the bitmap
    is zeroed again on return; with an empty one every visit is written.
    Returns the number of keys written.
    """
    n, dim = points.shape
    stride = np.ones(dim, np.int64)
    for a in range(dim - 2, -1, -1):
        stride[a] = stride[a + 1] * shape[a + 1]
    lo = np.empty(dim, np.int64)
    hi = np.empty(dim, np.int64)
    box = np.empty(dim, np.int64)
    use_bitmap = bitmap.size > 0
    r2 = radius * radius
    count = 0
    for i in range(n):
        for a in range(dim):
            u = points[i, a] - origin[a]
            if radius > 0.0:
                # Boxes whose interior meets [u - r, u + r] along this axis.
                lo[a] = np.int64(np.floor((u - radius) / scale))
                hi[a] = np.int64(np.ceil((u + radius) / scale)) - 1
            else:
                lo[a] = np.int64(np.floor(u / scale))
                hi[a] = lo[a]
            box[a] = lo[a]
        while True:
            inside = True
            if radius > 0.0:
                # A ball overlaps a box iff the box's nearest point is within r;
                # this drops the corner boxes that only the bounding cube reaches.
                d2 = 0.0
                for a in range(dim):
                    u = points[i, a] - origin[a]
                    gap = max(box[a] * scale - u, u - (box[a] + 1) * scale, 0.0)
                    d2 += gap * gap
                inside = d2 < r2
            if inside:
                key = np.int64(0)
                for a in range(dim):
                    key += box[a] * stride[a]
                if use_bitmap:
                    bit = np.uint8(1 << (key & 7))
                    if (bitmap[key >> 3] & bit) == 0:
                        bitmap[key >> 3] |= bit
                        keys[count] = key
                        count += 1
                else:
                    keys[count] = key
                    count += 1
            # Odometer over the (at most 2 per axis) candidate boxes.
            a = dim - 1
            while a >= 0 and box[a] == hi[a]:
                box[a] = lo[a]
                a -= 1
            if a < 0:
                break
            box[a] += 1
    # Clearing only what was set keeps one bitmap reusable for every grid.
    if use_bitmap:
        for c in range(count):
            bitmap[keys[c] >> 3] = 0
    return count


def _grid_shape(high, origin, scale, radius):
    return np.floor((high + radius - origin) / scale).astype(np.int64) + 1


def _boxes(points, high, origin, scale, radius, bitmap, keys, keep):
    """Count the distinct boxes the particles touch; with ``keep`` also return them.

    ``high`` is the componentwise maximum of ``points``; ``bitmap`` and
    ``keys`` are scratch space (see ``_occupied_boxes``), the bitmap used when
    the grid fits in it, a sort of all visits otherwise. The boxes come back
    as an (m, dim) array of grid indices.
    """
    shape = _grid_shape(high, origin, scale, radius)
    if int(np.prod(shape.astype(object))) <= 8 * bitmap.size:
        unique = keys[: _occupied_boxes(points, origin, scale, radius, shape, bitmap, keys)]
    else:
        visited = np.sort(keys[: _occupied_boxes(points, origin, scale, radius, shape, bitmap[:0], keys)])
        unique = visited[np.r_[True, visited[1:] != visited[:-1]]]
    return len(unique), (np.stack(np.unravel_index(unique, tuple(shape)), axis=1) if keep else None)


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
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] not in (2, 3) or len(p) == 0:
        raise ValueError(f"points: expected a non-empty (n, 2) or (n, 3) array, got shape {p.shape}")
    if not np.isfinite(p).all():
        raise ValueError("points: every coordinate must be finite")
    if offsets < 1:
        raise ValueError(f"offsets: {offsets} is below 1")
    # Coordinates from the low corner, so the extreme particles sit exactly
    # (not within rounding) half a particle inside the first box.
    p = p - p.min(axis=0)
    high = p.max(axis=0)
    extent = float(high.max()) + 2 * _HALF
    scales = default_scales(extent) if scales is None else np.asarray(scales, dtype=np.float64).ravel()
    if len(scales) == 0 or not (scales >= 1.0).all():
        raise ValueError("scales: expected box sides >= 1 (the particle size)")
    radius = 0.0 if lattice else _HALF
    # Row-major order of the unit cells keeps the bitmap accesses local.
    p = np.ascontiguousarray(p[np.lexsort(np.floor(p).T[::-1])])
    # Scratch: one bit per box of the finest grid (capped; larger grids are
    # sorted instead) and room for every particle's candidate boxes.
    finest = _grid_shape(high, -_HALF - scales.min(), scales.min(), radius)
    bitmap = np.zeros(min(int(np.prod(finest.astype(object))), 2**30) // 8 + 1, np.uint8)
    keys = np.empty(len(p) * (2 ** p.shape[1] if radius > 0.0 else 1), np.int64)
    # Every grid of side s = ratio * t, at any of the offsets, coarsens the
    # unshifted grid of side t, since its shift is a whole number of t-boxes.
    # Counting such a scale from the (far fewer) occupied t-boxes is exact and
    # costs a fraction of a pass over the points.
    ratio = offsets * int(np.ceil(2 / offsets))
    finer = {}
    for k, s in enumerate(scales):
        match = np.flatnonzero(np.isclose(scales[:k] * ratio, s, rtol=1e-9, atol=0.0))
        if len(match):
            finer[k] = int(match[0])
    coarser = {t: k for k, t in finer.items()}
    counts = np.empty(len(scales), np.int64)
    for k in range(len(scales)):
        if k in finer:
            continue
        occupied = None
        while k is not None:
            if occupied is None:
                grids = [(p, high, np.full(p.shape[1], -_HALF - (j / offsets) * scales[k]), scales[k], radius)
                         for j in range(offsets)]
            else:
                centres = occupied + 0.5
                top = centres.max(axis=0)
                grids = [(centres, top, np.full(p.shape[1], -j * ratio / offsets), float(ratio), 0.0) for j in range(offsets)]
            keep = k in coarser
            results = [_boxes(*grid, bitmap, keys, keep and j == 0) for j, grid in enumerate(grids)]
            counts[k] = min(count for count, _ in results)
            occupied = results[0][1]
            k = coarser.get(k)
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
