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


_SLOTS = 4
"""Slabs of marks kept along the first axis: boxes arrive at most 2 slabs behind the furthest one seen."""

_DENSE_CAP = 1 << 22
"""Largest slab (boxes across the other axes) or first-axis range handled with dense arrays; beyond, sorting."""


@jit
def _first_axis_order(points, top):
    """``points`` sorted by the integer part of the first coordinate (a stable counting sort)."""
    n = len(points)
    start = np.zeros(top + 2, np.int64)
    for i in range(n):
        start[np.int64(np.floor(points[i, 0])) + 1] += 1
    for c in range(1, top + 2):
        start[c] += start[c - 1]
    out = np.empty_like(points)
    for i in range(n):
        c = np.int64(np.floor(points[i, 0]))
        out[start[c]] = points[i]
        start[c] += 1
    return out


@jit
def _occupied_boxes(points, origin, scale, radius, shape, marks, out):
    """Count the boxes of side ``scale`` that the particles touch; write them to ``out``.

    ``radius == 0`` puts each particle in the one box holding its centre;
    ``radius > 0`` in every box its ball overlaps. With ``marks`` of shape
    ``(_SLOTS, boxes across axes 1..)`` filled with -1, each box is counted
    and written once; this needs ``points`` ordered along the first axis
    (see ``_first_axis_order``). With empty ``marks`` every visit is counted.
    Writing stops when ``out`` is full; the count goes on.
    """
    n, dim = points.shape
    dedup = marks.shape[0] > 0
    stride = np.ones(dim, np.int64)
    for a in range(dim - 2, 0, -1):
        stride[a] = stride[a + 1] * shape[a + 1]
    # The first-axis box each slab currently holds marks for; a mark equal to
    # it means "counted", so slabs are reused without clearing.
    owner = np.full(max(marks.shape[0], 1), -1, np.int64)
    lo = np.empty(dim, np.int64)
    hi = np.empty(dim, np.int64)
    box = np.empty(dim, np.int64)
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
            new = inside
            if inside and dedup:
                slot = box[0] % _SLOTS
                if owner[slot] != box[0]:
                    if owner[slot] > box[0]:
                        raise RuntimeError("box_counts: points not ordered along the first axis")
                    owner[slot] = box[0]
                rest = np.int64(0)
                for a in range(1, dim):
                    rest += box[a] * stride[a]
                new = marks[slot, rest] != box[0]
                marks[slot, rest] = box[0]
            if new:
                if count < len(out):
                    out[count] = box
                count += 1
            # Odometer over the (at most 2 per axis) candidate boxes.
            a = dim - 1
            while a >= 0 and box[a] == hi[a]:
                box[a] = lo[a]
                a -= 1
            if a < 0:
                break
            box[a] += 1
    return count


def _grid_shape(high, origin, scale, radius):
    return np.floor((high + radius - origin) / scale).astype(np.int64) + 1


def _boxes(points, high, origin, scale, radius, ordered, index, capacity):
    """Count the distinct boxes of one grid; also return them when there are at most ``capacity``.

    ``high`` is the componentwise maximum of ``points``. Marks per slab of
    the first axis (``_occupied_boxes``) need ``ordered`` points and a slab
    of at most ``_DENSE_CAP`` boxes; otherwise every visit is written and
    sorted. The boxes come back as an (m, dim) array of grid indices, or None.
    """
    shape = _grid_shape(high, origin, scale, radius)
    slab = int(np.prod(shape[1:].astype(object)))
    if ordered and slab <= _DENSE_CAP:
        marks = np.full((_SLOTS, slab), -1, index)
        out = np.empty((capacity, len(shape)), index)
        count = _occupied_boxes(points, origin, scale, radius, shape, marks, out)
        return count, (out[:count].copy() if count <= capacity else None)
    visits = 2 ** len(shape) if radius > 0.0 else 1
    out = np.empty((len(points) * visits, len(shape)), index)
    boxes = np.unique(out[: _occupied_boxes(points, origin, scale, radius, shape, np.empty((0, 0), index), out)], axis=0)
    return len(boxes), (boxes if len(boxes) <= capacity else None)


def _coarsening_parents(scales, offsets):
    """Map each scale that is ``r`` times a smaller one (r >= 2, a multiple of ``offsets``) to the largest such.

    Every grid of side ``r * t``, at any of the offsets, coarsens the
    unshifted grid of side t, since its shift ``j * r / offsets`` is a whole
    number of t-boxes: its count follows exactly from the occupied t-boxes.
    """
    parent = {}
    for k, s in enumerate(scales):
        ratio = np.round(s / scales)
        fits = (ratio >= 2) & (ratio % offsets == 0) & np.isclose(scales * ratio, s, rtol=1e-9, atol=0.0)
        if fits.any():
            candidates = np.flatnonzero(fits)
            parent[k] = int(candidates[np.argmax(scales[candidates])])
    return parent


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
    # (not within rounding) half a particle inside the first box.
    p = p - p.min(axis=0)
    high = p.max(axis=0)
    extent = float(high.max()) + 2 * _HALF
    scales = default_scales(extent) if scales is None else np.asarray(scales, dtype=np.float64).ravel()
    if len(scales) == 0 or not (scales >= 1.0).all():
        raise ValueError("scales: expected box sides >= 1 (the particle size)")
    radius = 0.0 if lattice else _HALF
    # Box indices in int32 halve the memory traffic; int64 only for huge extents.
    index = np.int32 if extent + 2 < 2**31 else np.int64
    if p.dtype.kind == "i":
        p = p.astype(index)
    ordered = high[0] <= max(_DENSE_CAP, len(p))
    if ordered:
        p = _first_axis_order(p, int(high[0]))
    parent = _coarsening_parents(scales, offsets)
    children = {}
    for k, m in parent.items():
        children.setdefault(m, []).append(k)
    counts = np.empty(len(scales), np.int64)
    # Depth first, so that only the occupied boxes on the current chain of
    # coarsenings are held; None means "from the points".
    pending = [(k, None) for k in range(len(scales)) if k not in parent]
    while pending:
        k, boxes = pending.pop()
        if boxes is None:
            grids = [(p, high, np.full(p.shape[1], -_HALF - (j / offsets) * scales[k]), scales[k], radius, ordered)
                     for j in range(offsets)]
        else:
            ratio = round(scales[k] / scales[parent[k]])
            # Box centres in units of the finer box, the finer grid's corner at
            # 0. The boxes arrive in first-axis order (sorted, or as written).
            grids = [(boxes, boxes.max(axis=0), np.full(p.shape[1], -_HALF - j * ratio // offsets), float(ratio), 0.0, True)
                     for j in range(offsets)]
        # Coarser scales start from these boxes only while they are fewer than the points.
        capacity = len(p) if k in children else 0
        results = [_boxes(*grid, index, capacity if j == 0 else 0) for j, grid in enumerate(grids)]
        counts[k] = min(count for count, _ in results)
        pending += [(child, results[0][1]) for child in children.get(k, [])]
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
