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
"""Slabs of marks along the first axis: a box arrives at most 3 boxes behind the furthest one seen (see ``box_counts``)."""

_DENSE_CAP = 1 << 22
"""Largest slab (boxes across the other axes) or first-axis range handled with dense arrays; beyond, sorting."""


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
def _occupied_boxes(points, origin, scale, radius, shape, marks, out):
    """Count the boxes of side ``scale`` that the particles touch; write them to ``out``.

    ``origin`` and ``shape`` are tuples (so the loops over axes unroll).
    ``radius == 0`` puts each particle in the one box holding its centre;
    ``radius > 0`` in every box its ball overlaps. With ``marks`` of shape
    ``(_SLOTS, boxes across axes 1..)`` filled with -1, each box is counted
    and written once; this needs the first-axis boxes to arrive less than
    ``_SLOTS`` behind the largest so far. With empty ``marks`` every visit is
    counted. Writing stops when ``out`` is full; the count goes on.
    """
    dim = len(origin)
    dedup = marks.shape[0] > 0
    # The first-axis box each slab holds marks for; a mark equal to it means
    # "counted", so a slab is reused for a new box without clearing.
    owner = np.full(_SLOTS, -1, np.int64)
    home = np.zeros(dim, np.int64)
    step = np.zeros(dim, np.int64)
    gap2 = np.zeros(dim)
    r2 = radius * radius
    corners = 1 << dim if radius > 0.0 else 1
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
            write = count < len(out)
            first = home[0] + (step[0] if corner & 1 else 0)
            if write:
                out[count, 0] = first
            rest = 0
            for a in range(1, dim):
                b = home[a] + (step[a] if (corner >> a) & 1 else 0)
                rest = rest * shape[a] + b
                if write:
                    out[count, a] = b
            new = True
            if dedup:
                slot = first % _SLOTS
                if owner[slot] != first:
                    if owner[slot] > first:
                        raise RuntimeError("box_counts: boxes arrived out of order")
                    owner[slot] = first
                new = marks[slot, rest] != first
                marks[slot, rest] = first
            count += new
    return count


def _grid_shape(high, origin, scale, radius):
    return np.floor((high + radius - origin) / scale).astype(np.int64) + 1


def _boxes(points, high, origin, scale, radius, ordered, index, capacity):
    """Count the distinct boxes of one grid; also return them when there are at most ``capacity``.

    ``high`` bounds ``points`` componentwise. Marks per slab of the first
    axis (``_occupied_boxes``) need ``ordered`` points and a slab of at most
    ``_DENSE_CAP`` boxes; otherwise every visit is written and sorted.
    Returns the count, the boxes as an (m, dim) array of grid indices of
    dtype ``index`` (or None) and the grid's shape.
    """
    shape = _grid_shape(high, origin, scale, radius)
    slab = int(np.prod(shape[1:].astype(object)))
    args = (points, tuple(origin), float(scale), radius, tuple(shape))
    if ordered and slab <= _DENSE_CAP:
        # Pages of ``out`` beyond the count are never touched, so never resident.
        out = np.empty((capacity, len(shape)), index)
        count = _occupied_boxes(*args, np.full((_SLOTS, slab), -1, index), out)
        return count, (out[:count] if count <= capacity else None), shape
    out = np.empty((len(points) * (2 ** len(shape) if radius > 0.0 else 1), len(shape)), index)
    boxes = np.unique(out[: _occupied_boxes(*args, np.empty((0, 0), index), out)], axis=0)
    return len(boxes), (boxes if len(boxes) <= capacity else None), shape


def _coarsening_parents(scales):
    """Map each scale that is a whole multiple (>= 2) of smaller ones to the largest of those."""
    parent = {}
    for k, s in enumerate(scales):
        ratio = np.round(s / scales)
        fits = np.flatnonzero((ratio >= 2) & np.isclose(scales * ratio, s, rtol=1e-9, atol=0.0))
        if len(fits):
            parent[k] = int(fits[np.argmax(scales[fits])])
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
    # (not within rounding) half a particle inside the first box. Column by
    # column: numpy reduces an (n, 2) array along axis 0 ten times slower.
    p = p - np.array([c.min() for c in p.T])
    high = np.array([c.max() for c in p.T])
    extent = float(high.max()) + 2 * _HALF
    scales = default_scales(extent) if scales is None else np.asarray(scales, dtype=np.float64).ravel()
    if len(scales) == 0 or not (scales >= 1.0).all():
        raise ValueError("scales: expected box sides >= 1 (the particle size)")
    radius = 0.0 if lattice else _HALF
    index = np.int32 if extent + 2 < 2**31 else np.int64
    if p.dtype.kind == "i":
        p = p.astype(index)  # half the memory traffic
    # In order of the first coordinate's integer part, the first-axis boxes a
    # particle touches (home box +-1) lie at most 3 behind any touched before.
    ordered = high[0] <= max(_DENSE_CAP, len(p))
    if ordered:
        p = _first_axis_order(p, int(high[0]))
    # Grid j of side r * t is a union of boxes of grid (j * r) % offsets of
    # side t (whole r), since the two corners are (j * r // offsets) t-boxes
    # apart: its count follows exactly from those boxes, which are fewer
    # than the particles, and which keep their first-axis order.
    parent = _coarsening_parents(scales)
    ratio = {k: round(scales[k] / scales[m]) for k, m in parent.items()}
    needed, children = {}, {}
    for k, m in parent.items():
        needed.setdefault(m, set()).update(j * ratio[k] % offsets for j in range(offsets))
        children.setdefault(m, []).append(k)
    # Keeping at most this many boxes per grid bounds the memory to a few copies of the points.
    capacity = len(p) * (2 ** (p.shape[1] - 1) if radius > 0.0 else 1)
    counts = np.empty(len(scales), np.int64)
    # Depth first, so that only the boxes on the current chain of
    # coarsenings are held; None means "from the particles".
    pending = [(k, None) for k in range(len(scales)) if k not in parent]
    while pending:
        k, finer = pending.pop()
        kept, best = {}, None
        for j in range(offsets):
            if finer is None:
                source = (p, high, np.full(p.shape[1], -_HALF - (j / offsets) * scales[k]), scales[k], radius, ordered)
            else:
                # Centres of the t-boxes in t units, their grid's corner at 0.
                boxes, top = finer[j * ratio[k] % offsets]
                source = (boxes, top, np.full(p.shape[1], -_HALF - j * ratio[k] // offsets), float(ratio[k]), 0.0, True)
            count, boxes, shape = _boxes(*source, index, capacity if j in needed.get(k, ()) else 0)
            best = count if best is None else min(best, count)
            if boxes is not None:
                kept[j] = (boxes, shape - 1)
        counts[k] = best
        complete = needed.get(k, set()) <= set(kept)
        pending += [(child, kept if complete else None) for child in children.get(k, [])]
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
