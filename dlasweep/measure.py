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
"""Most bits (256 MiB) a stack of bitmaps (a side's grids, or its strips) may take; a grid larger than this
alone is counted by sorting its boxes."""

_STRIP_WORDS_PER_SITE = 2
"""Integer sites are put in strips when a strip has fewer words than this per site. Measured: a grid costs
about 4 ns a site when marked from the sites, 1.7 ns a strip word when merged from the strips."""

_EVEN = np.uint64(0x5555555555555555)
"""The even bits of a word."""

_TOP = np.uint64(63)
"""Shift that brings a word's top bit to the bottom."""


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
def _mark_sites(points, offsets, scale, cells, strips):
    """Put integer sites in their boxes on the last axis: bit b of row x[:-1] of ``strips[j]``.

    Box b is the one of side ``scale`` at offset ``offsets[j]`` that holds
    the site, found as in ``_mark_boxes``. The rows are numbered row-major
    over the sites of the leading axes, ``cells`` of them on each (a tuple,
    so the loop over axes unrolls).
    """
    dim = points.shape[1]
    for i in range(len(points)):
        row = 0
        for a in range(dim - 1):
            row = row * cells[a] + points[i, a]
        for j in range(len(offsets)):
            last = np.int64(np.floor((points[i, dim - 1] - (-_HALF - offsets[j])) / scale))
            strips[j, row, last >> 6] |= np.uint64(1) << np.uint64(last & 63)


@jit
def _mark_boxes(points, offsets, scale, radius, shape, first, bitmaps, out):
    """Set the bit of every box a particle touches in grids ``first``, ``first + 1``, ...; count the visits.

    Grid g has boxes of side ``scale`` and its corner at -1/2 - offsets[i]
    on an axis where its offset index is i: the digits of g in base
    ``len(offsets)``, axis 0 the most significant. ``radius == 0`` puts each
    particle in the one box holding its centre; ``radius > 0`` in every box
    its ball overlaps. ``shape`` is the grids' shape on three axes (see
    ``_slab``): ``bitmaps[k]`` is grid ``first + k``'s bitmap, a row per box
    of the leading axes (row-major), a bit per box of the last axis. With no
    ``bitmaps`` grid ``first``'s every visit (its box on the three axes) is
    written to ``out`` instead.
    """
    pad = 3 - points.shape[1]
    grids = len(bitmaps) if len(bitmaps) > 0 else 1
    many = len(offsets)
    r2 = radius * radius
    # A particle's boxes on each axis for each offset, shared by the grids:
    # its home box, then the one across the nearer face when the ball
    # reaches it (with s >= 2r it reaches no further), at squared distance
    # gap2. A 2D set has an axis 0 of one box, with one offset.
    box = np.zeros((3, many, 2), np.int64)
    reach = np.ones((3, many), np.int64)
    gap2 = np.zeros((3, many))
    visits = 0
    for i in range(len(points)):
        for a in range(pad, 3):
            for j in range(many):
                u = points[i, a - pad] - (-_HALF - offsets[j])
                home = np.int64(np.floor(u / scale))
                box[a, j, 0] = home
                if radius > 0.0:
                    below = u - home * scale
                    above = (home + 1) * scale - u
                    gap2[a, j] = min(below, above) ** 2
                    box[a, j, 1] = home - 1 if below <= above else home + 1
                    reach[a, j] = 2 if gap2[a, j] < r2 else 1
        # A box across faces on several axes is reached when the squared
        # distances, added axis by axis in order, stay below r2 (the order
        # of the additions is part of the rule: it fixes the rounding).
        for j0 in range(1 if pad else many):
            for e0 in range(reach[0, j0]):
                d0 = gap2[0, j0] if e0 else 0.0
                for j1 in range(many):
                    base = (j0 * many + j1) * many - first
                    if base + many <= 0 or base >= grids:
                        continue
                    for e1 in range(reach[1, j1]):
                        d1 = d0 + gap2[1, j1] if e1 else d0
                        if e1 and d1 >= r2:
                            continue
                        row = box[0, j0, e0] * shape[1] + box[1, j1, e1]
                        for j2 in range(max(-base, 0), min(grids - base, many)):
                            for e2 in range(reach[2, j2]):
                                if e2 and d1 + gap2[2, j2] >= r2:
                                    continue
                                last = box[2, j2, e2]
                                if len(bitmaps) > 0:
                                    bitmaps[base + j2, row, last >> 6] |= np.uint64(1) << np.uint64(last & 63)
                                else:
                                    out[visits] = box[0, j0, e0], box[1, j1, e1], last
                                    visits += 1
    return visits


@jit
def _coarsen(fine, fine_shape, part, shift, factor, coarse, shape):
    """Fill ``coarse``, grids whose boxes are unions of ``fine``'s boxes, and return their least count.

    Both are stacks of bitmaps laid out as in ``_mark_boxes``, one per grid,
    their shapes on three axes. Coarse grid g has offset index i_a on axis a,
    digit a of g (axis 0 most significant) in base ``shift.shape[1]``, and
    takes its boxes from fine grid sum_a part[a, i_a]. On a leading axis its
    box b is the union of fine boxes factor[a] b - shift[a, i_a] + k, k <
    factor[a]. On the last axis factor is 1 (box b is fine box b) or 2 (fine
    boxes 2b - shift and 2b + 1 - shift).
    """
    bases, words, pair = shift.shape[1], fine.shape[2], factor[2] == 2
    step = np.zeros(3, np.int64)
    # The fine boxes under each coarse box of the leading axes, clipped to the fine grid.
    first = np.zeros((2, max(shape[0], shape[1])), np.int64)
    stop = np.zeros((2, max(shape[0], shape[1])), np.int64)
    merged = np.zeros(words, np.uint64)
    best = -1
    for g in range(coarse.shape[0]):
        rest, grid = g, 0
        for a in range(2, -1, -1):
            grid += part[a, rest % bases]
            step[a] = shift[a, rest % bases]
            rest //= bases
        for a in range(2):
            for b in range(shape[a]):
                first[a, b] = max(factor[a] * b - step[a], 0)
                stop[a, b] = min(factor[a] * (b + 1) - step[a], fine_shape[a])
        rows, out, up = fine[grid], coarse[g], np.uint64(step[2])
        count = 0
        for b0 in range(shape[0]):
            run0, run1 = first[0, b0] * fine_shape[1], stop[0, b0] * fine_shape[1]
            for b1 in range(shape[1]):
                # The fine rows under this coarse row: a run of consecutive rows
                # per fine box of axis 0. Short rows (3D) are ORed word by word
                # in a register, long ones (2D) row by row, which vectorises;
                # each way is twice as fast as the other on its rows.
                lo, hi = first[1, b1], stop[1, b1]
                runs = range(run0, run1, fine_shape[1])
                if words <= 2:
                    for w in range(words):
                        acc = np.uint64(0)
                        for run in runs:
                            for r in range(run + lo, run + hi):
                                acc |= rows[r, w]
                        merged[w] = acc
                else:
                    merged[:] = 0
                    for run in runs:
                        for r in range(run + lo, run + hi):
                            for w in range(words):
                                merged[w] |= rows[r, w]
                row = b0 * shape[1] + b1
                carry = np.uint64(0)
                for w in range(out.shape[1]):
                    if pair:
                        # Fine words 2w and 2w + 1, moved up a bit when shifted
                        # (the top bit of word 2w - 1 coming in), halved unless
                        # empty (as most are in sparse sets).
                        low = merged[2 * w] if 2 * w < words else np.uint64(0)
                        high = merged[2 * w + 1] if 2 * w + 1 < words else np.uint64(0)
                        if up:
                            low, high, carry = (low << up) | carry, (high << up) | (low >> _TOP), high >> _TOP
                        word = _pairs(low) | (_pairs(high) << np.uint64(32)) if low | high else np.uint64(0)
                    else:
                        word = merged[w]
                    out[row, w] = word
                    count += _ones(word)
        best = count if best < 0 else min(best, count)
    return best


@jit
def _least_count(bitmaps):
    """Fewest set bits in a bitmap of the stack."""
    best = -1
    for g in range(len(bitmaps)):
        count = 0
        for row in range(bitmaps.shape[1]):
            for w in range(bitmaps.shape[2]):
                count += _ones(bitmaps[g, row, w])
        best = count if best < 0 else min(best, count)
    return best


def _slab(shape):
    """``shape`` on three axes, as the kernels take it: a 2D grid is a 3D one with a single box on axis 0."""
    return (1,) * (3 - len(shape)) + tuple(int(n) for n in shape)


def _bitmap_words(shape):
    """Words of one grid's bitmap: a row per box of the leading axes, a bit per box of the last."""
    return math.prod(int(n) for n in shape[:-1]) * -(-int(shape[-1]) // 64)


def _grids_within_cap(shape):
    """How many grids of ``shape`` have bitmaps within ``_BITMAP_CAP`` bits together."""
    return _BITMAP_CAP // (64 * _bitmap_words(shape))


def _empty_bitmaps(shape, grids, make=np.zeros):
    """Bitmaps for ``grids`` grids of ``shape``, laid out as in ``_mark_boxes`` (``make=np.empty``: unset)."""
    return make((grids, math.prod(int(n) for n in shape[:-1]), -(-int(shape[-1]) // 64)), np.uint64)


def _from_points(points, high, offsets, scale, radius, keep):
    """Least count over the grids of side ``scale`` with per-axis ``offsets``, from the particles.

    Also returns their stacked bitmaps (None unless ``keep`` and they fit the
    cap together) and the grids' common shape. Integer sites are put in
    strips that the grids are merged from (when that is cheaper); otherwise
    the grids are marked in as few passes over the particles as the cap
    allows, and a grid too large for a bitmap alone is counted by sorting
    its boxes.
    """
    dim, grids = points.shape[1], len(offsets) ** points.shape[1]
    # Anchored at -1/2 - offset: the largest offset needs the most boxes.
    shape = np.floor((high + radius + _HALF + offsets[-1]) / scale).astype(np.int64) + 1
    per_pass = _grids_within_cap(shape)
    # Integer sites need no marking per grid. They are put in their boxes on
    # the last axis only, in one strip per offset there, a row per site of
    # the leading axes. On those the site x is in box floor((x + 1/2 + o) / s)
    # = floor((x + o) / s) (the quotient, in floating point too, is at least
    # 1/2s from a whole number), so a box at offset o holds the sites
    # s b - o, ..., s b - o + s - 1, and each grid's row is the union of
    # s**(dim-1) strip rows: a grid costs a pass over a strip's words, not
    # over the sites.
    cells = np.r_[high[:-1] + 1, shape[-1]]
    if (radius == 0.0 and points.dtype.kind == "i" and per_pass >= grids
            and _grids_within_cap(cells) >= len(offsets)
            and (scale == 1 or _bitmap_words(cells) < _STRIP_WORDS_PER_SITE * len(points))):
        strips = _empty_bitmaps(cells, len(offsets))
        _mark_sites(points, np.array(offsets, np.int64), float(scale), tuple(int(n) for n in cells[:-1]), strips)
        if scale == 1:  # one offset, and boxes that are sites: the strip is the grid
            return _least_count(strips), strips if keep else None, shape
        stack = _empty_bitmaps(shape, grids, np.empty)
        part, shift = np.zeros((3, len(offsets)), np.int64), np.zeros((3, len(offsets)), np.int64)
        part[2], shift[3 - dim : 2] = np.arange(len(offsets)), offsets
        factor = _slab((int(scale),) * (dim - 1) + (1,))
        best = _coarsen(strips, _slab(cells), part, shift, factor, stack, _slab(shape))
        return best, stack if keep else None, shape
    args = (points, np.array(offsets, np.int64), float(scale), radius, _slab(shape))
    if per_pass == 0:
        visits = np.empty((len(points) * (2**dim if radius > 0.0 else 1), 3), np.int64)
        counts = [len(np.unique(visits[: _mark_boxes(*args, g, np.empty((0, 0, 0), np.uint64), visits)], axis=0))
                  for g in range(grids)]
        return min(counts), None, shape
    best = None
    for first in range(0, grids, per_pass):
        stack = _empty_bitmaps(shape, min(per_pass, grids - first))
        _mark_boxes(*args, first, stack, np.empty((0, 0), np.int64))
        count = _least_count(stack)
        best = count if best is None else min(best, count)
    return best, stack if keep and per_pass >= grids else None, shape


def _halve(fine, fine_shape, fine_offsets, side, offsets):
    """Least count over the grids of side ``side`` with per-axis ``offsets``, from the grids of half that side.

    ``fine`` holds the bitmaps of the grids of side s = side / 2 with
    per-axis ``fine_offsets``, among them o % s for every o in ``offsets``.
    Returns the count, the grids' stacked bitmaps and their shape, or None
    when those bitmaps would exceed the cap together.
    """
    dim, half = len(fine_shape), side // 2
    shape = fine_shape // 2 + 1
    if _grids_within_cap(shape) < len(offsets) ** dim:
        return None
    # The box of side 2s at offset o is the union of 2**dim boxes of the
    # grid of side s at offset o % s, shifted by one where o >= s. Fine grids
    # are numbered by their offset indices, axis 0 the most significant digit.
    part, shift = np.zeros((3, len(offsets)), np.int64), np.zeros((3, len(offsets)), np.int64)
    for a in range(dim):
        part[3 - dim + a] = [fine_offsets.index(o % half) * len(fine_offsets) ** (dim - 1 - a) for o in offsets]
        shift[3 - dim + a] = [o >= half for o in offsets]
    stack = _empty_bitmaps(shape, len(offsets) ** dim, np.empty)
    count = _coarsen(fine, _slab(fine_shape), part, shift, _slab((2,) * dim), stack, _slab(shape))
    return count, stack, shape


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
    if p.dtype.kind == "f" and not np.isfinite(p).all():
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
        halved = None if finer is None else _halve(*finer, side, own)
        counts[k], stack, shape = halved or _from_points(p, high, own, side, radius, keep=bool(kids))
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


def anisotropy(points, counts) -> np.ndarray:
    """Square/cubic anisotropy of the outer half of the mass about the seed, at each count.

    For the particles of the first m whose distance from the seed (the first
    point) is at least the median distance, the mean of
    ``(sum_a u_a**4 - c) / (1 - c)`` over their unit directions u, with
    ``c = 3 / (dim + 2)`` its mean over isotropic directions. In 2D this is
    <cos 4 theta>: 1 when the mass lies along the axes, -1 along the
    diagonals, 0 for an isotropic cluster; in 3D the cubic harmonic scaled
    the same way (1 along the axes, -2/3 along the body diagonals). Square-
    lattice DLA grows arms along the axes; off-lattice DLA stays near 0.

    Parameters
    ----------
    points : array_like, (n, dim)
        Positions in attachment order.
    counts : array_like of int
        Prefix lengths m, each in 1..n.

    Returns
    -------
    ndarray of float64, shaped like ``counts``; NaN for a prefix with no particle off the seed.
    """
    p = np.asarray(points, dtype=np.float64)
    counts = np.asarray(counts, dtype=np.int64)
    if p.ndim != 2 or len(p) == 0 or counts.size and not (1 <= counts.min() and counts.max() <= len(p)):
        raise ValueError("points, counts: expected a non-empty (n, dim) array and counts in 1..n")
    offset = p - p[0]
    r2 = (offset**2).sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        quartic = (offset**4).sum(axis=1) / r2**2
    isotropic = 3.0 / (p.shape[1] + 2)
    out = np.full(counts.shape, np.nan)
    for i, m in np.ndenumerate(counts):
        outer = r2[1:m] >= np.median(r2[1:m]) if m > 1 else np.zeros(0, bool)
        if outer.any():
            out[i] = (quartic[1:m][outer].mean() - isotropic) / (1 - isotropic)
    return out


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
