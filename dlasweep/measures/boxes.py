"""Box counting of point sets: how many boxes of side s a set occupies, for a series of whole s.

Pure functions of an ``(n, dim)`` point array (dim 2 or 3) in attachment
order; no I/O. Lengths are in lattice units (off-lattice: particle diameters).
``box_counts`` measures one set, ``prefix_box_counts`` every prefix of one
at once: both with one traversal (``_count_prefix``), compiled, releasing the
GIL; the grids of sparse sets too large to count in bands of rows are then
counted by sorting their boxes (``PrefixBoxes.finish``).
"""

from __future__ import annotations

import functools

import numpy as np

from .._jit import jit
from .bitmaps import (
    HALF,
    coarsen,
    least_count,
    mark_boxes,
    mark_sites,
    nth_piece,
    ordered,
    pieces,
)


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
alone is counted in bands of its rows."""

_PIECE_BYTES = 1 << 29
"""Most bytes (512 MiB) of a prefix's shifted, first-axis ordered copy that the marking takes at a time
(``pieces``); a larger prefix is marked in pieces, each copied anew from the prefix for each marking.
Filling a piece takes a pass over the whole prefix, so pieces are as large as memory allows
(docs/performance.md, "Measures")."""

_BANDS_MOST = 64
"""Most bands a grid is counted in (a pass over the particles each); a grid that needs more belongs to a
sparse set, whose boxes are sorted instead."""

_STRIP_WORDS_PER_SITE = 2
"""Integer sites are put in strips when a strip has fewer words than this per site: a strip word merged
costs about half what a site marked does (docs/performance.md, "Measures")."""

ROUTES = ("one box", "halved", "strips of sites", "one pass", "a few grids a pass", "sorted", "bands")
"""How a side is counted, by code (``PrefixBoxes.routes``): the set fits one box; its grids halved from those
of half the side; merged from strips of sites; marked from the particles in one pass, or a few grids a pass;
a grid too large for a bitmap, in bands of its rows, a pass each; a sparse set's grid that would need more
than ``_BANDS_MOST`` bands, its boxes sorted."""
ONE_BOX, HALVED, STRIPS, ONE_PASS, PASSES, SORTED, BANDS = range(len(ROUTES))

def _slab(shape):
    """``shape`` on three axes, as the kernels take it: a 2D grid is a 3D one with a single box on axis 0."""
    return (1,) * (3 - len(shape)) + tuple(int(n) for n in shape)


def _halving(fine_offsets, half, offsets, dim):
    """``coarsen``'s ``part`` and ``shift`` that make the grids of side 2 ``half`` from those of side ``half``.

    The box of side 2s at offset o is the union of 2**dim boxes of the
    grid of side s at offset o % s, shifted by one where o >= s. Fine grids
    are numbered by their offset indices, axis 0 the most significant digit.
    """
    part, shift = np.zeros((3, len(offsets)), np.int64), np.zeros((3, len(offsets)), np.int64)
    for a in range(dim):
        part[3 - dim + a] = [fine_offsets.index(o % half) * len(fine_offsets) ** (dim - 1 - a) for o in offsets]
        shift[3 - dim + a] = [o >= half for o in offsets]
    return part, shift


def _families(sides: tuple, offsets: int):
    """Which side each side is halved from, and every side's offsets.

    Returns ``parent`` (side index -> index of the first side of half its
    length, where there is one), ``children`` (its inverse, lists in order)
    and ``grid_offsets`` (side index -> sorted offsets O(s), see ``box_counts``).
    """
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
    return parent, children, grid_offsets


def checked_points(points, dtype=None) -> np.ndarray:
    """``points`` checked for every measure: a non-empty (n, 2) or (n, 3) array of finite coordinates.

    Returned as ``dtype``, by default int64 for integers and float64 otherwise.

    Raises
    ------
    ValueError
        One line, naming ``points``.
    """
    p = np.asarray(points)
    if p.ndim != 2 or p.shape[1] not in (2, 3) or len(p) == 0:
        raise ValueError(f"points: expected a non-empty (n, 2) or (n, 3) array, got shape {p.shape}")
    p = p.astype(dtype or (np.int64 if p.dtype.kind in "iub" else np.float64), copy=False)
    if p.dtype.kind == "f" and not np.isfinite(p).all():
        raise ValueError("points: every coordinate must be finite")
    return p


def _checked_scales(scales, extent):
    """``scales`` as float64, checked; ``default_scales(extent)`` when None."""
    scales = default_scales(extent) if scales is None else np.asarray(scales, dtype=np.float64).ravel()
    # Whole sides and integer offsets put every lattice cell in one box, and
    # make a box of side 2s an exact union of boxes of side s.
    if len(scales) == 0 or not (np.isfinite(scales) & (scales >= 1.0) & (scales == np.floor(scales))).all():
        raise ValueError("scales: expected whole box sides >= 1 (the particle size)")
    return scales


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

    The sides are visited depth first along each family s, 2s, 4s, ...: a
    side's grids are halved from those of half the side while their bitmaps
    fit ``_BITMAP_CAP`` together, else marked from the particles (integer
    sites in strips, one per offset, that the grids are merged from, when
    that is cheaper; else as many grids a pass as the cap allows); a grid too
    large for a bitmap alone is counted in bands of its rows (a sparse set's,
    by sorting its boxes). ``ROUTES`` names these ways; each gives the same
    count.

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
    boxes = PrefixBoxes(points, None, lattice, scales, offsets)
    boxes.count()
    return boxes.scales.copy(), boxes.counts[0]


def prefix_box_counts(points, ends, lattice: bool = True, scales=None, offsets: int = 4):
    """``box_counts(points[:m], lattice, scales, offsets)`` for every m in ``ends``, in one call.

    The same traversal as ``box_counts``, one prefix after the other in one
    compiled call that releases the GIL, so threads measure clusters in
    parallel.

    Parameters
    ----------
    points : array_like, (n, dim)
        Positions in attachment order.
    ends : array_like of int
        Prefix lengths, each in 1..n.
    lattice, scales, offsets
        As for ``box_counts``; the default scales reach the longest prefix's extent.

    Returns
    -------
    scales : ndarray of float64
    counts : ndarray of int64, (len(ends), len(scales))
    """
    boxes = PrefixBoxes(points, ends, lattice, scales, offsets)
    boxes.count()
    return boxes.scales.copy(), boxes.counts


class PrefixBoxes:
    """The checked inputs of ``_prefix_counts`` for prefixes of one set, and the counts it fills in.

    ``ends`` None: the whole set. ``routes`` records how each side of each
    prefix was counted (``ROUTES``).
    """

    def __init__(self, points, ends, lattice, scales, offsets):
        # int32 sites (the lattice kernel's) are kept as they are: a copy of a
        # 1e8 cluster would cost more memory than its growth left free
        p = checked_points(points, np.int32 if np.asarray(points).dtype == np.int32 else None)
        if offsets < 1:
            raise ValueError(f"offsets: {offsets} is below 1")
        ends = np.array([len(p)] if ends is None else ends, np.int64).ravel()
        if not (ends.size and 1 <= ends.min() and ends.max() <= len(p)):
            raise ValueError(f"ends: expected prefix lengths in 1..{len(p)}")
        self.points, self.ends, self.radius = p, ends, 0.0 if lattice else HALF
        p = p[: ends.max()]
        low, side = _corner(p)
        extent = float(side) + 2 * HALF
        if scales is None:
            scales = default_scales(extent)
        # A sweep measures every cluster at the same scales: checked and planned once.
        self.scales, self.plan = _plan(np.asarray(scales, np.float64).ravel().tobytes(), offsets, p.shape[1])
        self.counts = np.ones((len(ends), len(self.scales)), np.int64)
        self.routes = np.zeros((len(ends), len(self.scales)), np.int8)
        integer = p.dtype.kind == "i"
        if integer and p.dtype != np.int32:  # from the low corner, exactly: each prefix is shifted again to its own
            p = p - low
            if extent < 2**31:
                p = p.astype(np.int32)  # half the memory traffic
        self.args = (p, ends, integer, self.radius, *self.plan, _BITMAP_CAP, _STRIP_WORDS_PER_SITE,
                     max(1, _PIECE_BYTES // p[:1].nbytes),
                     self.counts, self.routes)

    def count(self):
        """Fill in ``counts``: in compiled code, then ``finish``."""
        _prefix_counts(*self.args)
        self.finish()

    def finish(self):
        """Count the grids ``_prefix_counts`` left (-1: a sparse set's, too large for bands) by sorting their boxes."""
        sides, own, n_own = self.plan[:3]
        for c, k in zip(*np.nonzero(self.counts < 0)):
            self.counts[c, k] = _sorted_count(self.args[0][: self.ends[c]], sides[k], own[k, : n_own[k]], self.radius)


def _sorted_count(prefix, side, offsets, radius):
    """Least count over the grids of ``side`` with per-axis ``offsets``, by sorting each grid's boxes.

    For grids too large for a bitmap: sparse sets, not clusters. The prefix
    is placed as ``_count_prefix`` places it, from its low corner.
    """
    points = prefix - np.array([c.min() for c in prefix.T])
    high = np.array([c.max() for c in points.T])
    dim = points.shape[1]
    shape = np.floor((high + radius + HALF + offsets[-1]) / side).astype(np.int64) + 1
    visits = np.empty((len(points) * (2**dim if radius > 0.0 else 1), 3), np.int64)
    none = np.empty((0, 0, 0), np.uint64)
    return min(len(np.unique(visits[: mark_boxes(points, offsets, float(side), radius, _slab(shape), g, none, visits)],
                             axis=0)) for g in range(len(offsets) ** dim))


@jit
def _corner(points):
    """The low corner of a non-empty set and its longest side (max - min over the axes).

    Compiled: numpy's reductions along an axis of an (n, 2) array cost a
    sweep of small clusters more than the rest of their measurement's Python.
    """
    low, high = points[0].copy(), points[0].copy()
    for i in range(1, len(points)):
        for a in range(points.shape[1]):
            low[a] = min(low[a], points[i, a])
            high[a] = max(high[a], points[i, a])
    return low, (high - low).max()


@functools.lru_cache(maxsize=32)
def _plan(scales: bytes, offsets: int, dim: int):
    """The scales (float64 bytes) checked, and ``box_counts``'s families of their sides as arrays.

    Returns the scales and, for ``_prefix_counts``: the sides; ``own`` and
    ``n_own`` (row k holds the ``n_own[k]`` offsets of side k); ``order``,
    the sides in the order ``box_counts`` visits them (depth first along
    each family); ``parent`` (-1: none); and ``part``, ``shift``
    (``_halving``'s, for side k from its parent).
    """
    scales = _checked_scales(np.frombuffer(scales), None)
    sides = tuple(int(s) for s in scales)
    parent, children, grid_offsets = _families(sides, offsets)
    order, pending = [], [k for k in range(len(sides)) if k not in parent]
    while pending:
        order.append(pending.pop())
        pending += children.get(order[-1], [])
    width = max(map(len, grid_offsets.values()))
    own = np.zeros((len(sides), width), np.int64)
    part, shift = np.zeros((2, len(sides), 3, width), np.int64)
    for k, offs in grid_offsets.items():
        own[k, : len(offs)] = offs
        if k in parent:
            halving = _halving(grid_offsets[parent[k]], sides[k] // 2, offs, dim)
            part[k, :, : len(offs)], shift[k, :, : len(offs)] = halving
    n_own = np.array([len(grid_offsets[k]) for k in range(len(sides))], np.int64)
    parents = np.array([parent.get(k, -1) for k in range(len(sides))], np.int64)
    return scales, (np.array(sides, np.int64), own, n_own, np.array(order, np.int64), parents, part, shift)


@jit
def _words(shape):
    """Words of one grid's bitmap, ``shape`` on three axes: a row per box of the leading axes, a bit per box of
    the last."""
    return shape[0] * shape[1] * ((shape[2] + 63) // 64)


@jit
def _grids_within(cap, shape):
    """How many grids of ``shape`` (three axes) have bitmaps within ``cap`` bits together.

    The size is checked in floating point first: the grids of a sparse set's
    finest sides can have more words than an int64 holds.
    """
    if 64.0 * shape[0] * shape[1] * ((shape[2] + 63) // 64) > cap:
        return 0
    return cap // (64 * _words(shape))


@jit
def _prefix_counts(points, ends, integer, radius, sides, own, n_own, order, parent, part, shift, cap, strip_words,
                   piece, counts, routes):
    """``counts[c]``: the counts of ``points[:ends[c]]``, and ``routes[c]`` how each side was counted.

    ``counts`` comes filled with ones (the sides a prefix fits in); a side
    whose grids are left to sorting is left at -1 (``PrefixBoxes.finish``).
    """
    for c in range(len(ends)):
        _count_prefix(points[: ends[c]], integer, radius, sides, own, n_own, order, parent, part, shift, cap,
                      strip_words, piece, counts[c], routes[c])


@jit
def _count_prefix(prefix, integer, radius, sides, own, n_own, order, parent, part, shift, cap, strip_words, piece, out,
                  route):
    """``_prefix_counts`` for one prefix: the traversal of ``box_counts``' docstring, a route per side (``ROUTES``)."""
    n, dim = prefix.shape
    low = prefix[0].copy()
    for i in range(n):
        for a in range(dim):
            low[a] = min(low[a], prefix[i, a])
    high = np.zeros(dim, prefix.dtype)
    for i in range(n):
        for a in range(dim):
            high[a] = max(high[a], prefix[i, a] - low[a])
    extent = float(high.max()) + 2 * HALF
    cuts, start, buffer = pieces(prefix, low, np.int64(high[0]), ordered(prefix, high), piece)
    pad = 3 - dim
    kids = np.zeros(len(sides), np.int64)  # of each side, those below the extent
    for k in range(len(sides)):
        if parent[k] >= 0 and sides[k] < extent:
            kids[parent[k]] += 1
    stacks = [np.empty((0, 0, 0), np.uint64) for _ in range(len(sides))]
    shapes = np.ones((len(sides), 3), np.int64)
    halves = (2 if dim == 3 else 1, 2, 2)
    for k in order:
        side = sides[k]
        if side >= extent:
            continue
        offsets = own[k, : n_own[k]].copy()
        grids = len(offsets) ** dim
        m = parent[k]
        count, stack, shape = -1, stacks[k], shapes[k]
        if m >= 0 and len(stacks[m]) > 0:  # halved from the parent's grids
            fine = shapes[m]
            shape = fine // 2 + 1
            shape[:pad] = 1
            if _grids_within(cap, shape) >= grids:
                stack = np.empty((grids, shape[0] * shape[1], (shape[2] + 63) // 64), np.uint64)
                route[k] = HALVED
                count = coarsen(stacks[m], (fine[0], fine[1], fine[2]), part[k, :, : len(offsets)].copy(),
                                shift[k, :, : len(offsets)].copy(), halves, stack, (shape[0], shape[1], shape[2]))
        if count < 0:  # from the particles
            shape = np.ones(3, np.int64)
            for a in range(dim):
                shape[pad + a] = np.int64(np.floor((high[a] + radius + HALF + offsets[-1]) / side)) + 1
            per_pass = _grids_within(cap, shape)
            # Integer sites need no marking per grid. They are put in their boxes on
            # the last axis only, in one strip per offset there, a row per site of
            # the leading axes. On those the site x is in box floor((x + 1/2 + o) / s)
            # = floor((x + o) / s) (the quotient, in floating point too, is at least
            # 1/2s from a whole number), so a box at offset o holds the sites
            # s b - o, ..., s b - o + s - 1, and each grid's row is the union of
            # s**(dim-1) strip rows: a grid costs a pass over a strip's words, not
            # over the sites.
            cells = shape.copy()
            for a in range(dim - 1):
                cells[pad + a] = high[a] + 1
            if (radius == 0.0 and integer and per_pass >= grids and _grids_within(cap, cells) >= len(offsets)
                    and (side == 1 or _words(cells) < strip_words * n)):
                route[k] = STRIPS
                strips = np.zeros((len(offsets), cells[0] * cells[1], (cells[2] + 63) // 64), np.uint64)
                for c in range(len(cuts) - 1):
                    points = nth_piece(prefix, low, start, cuts, c, buffer)
                    if dim == 2:
                        mark_sites(points, offsets, float(side), (cells[1],), strips)
                    else:
                        mark_sites(points, offsets, float(side), (cells[0], cells[1]), strips)
                if side == 1:
                    count, stack = least_count(strips), strips
                else:
                    stack = np.empty((grids, shape[0] * shape[1], (shape[2] + 63) // 64), np.uint64)
                    merge, moved = np.zeros((3, len(offsets)), np.int64), np.zeros((3, len(offsets)), np.int64)
                    merge[2] = np.arange(len(offsets))
                    for a in range(pad, 2):
                        moved[a] = offsets
                    count = coarsen(strips, (cells[0], cells[1], cells[2]), merge, moved,
                                    (side if dim == 3 else 1, side, 1), stack, (shape[0], shape[1], shape[2]))
            elif per_pass == 0:
                row_words = (shape[2] + 63) // 64
                rows, band = shape[0] * shape[1], cap // (64 * row_words)
                stack = np.empty((0, 0, 0), np.uint64)
                if band == 0 or rows > band * _BANDS_MOST:
                    route[k] = SORTED  # counted by ``PrefixBoxes.finish``; count stays -1
                else:
                    route[k] = BANDS
                    bits = np.empty((1, band, row_words), np.uint64)
                    for g in range(grids):
                        total = 0
                        for row0 in range(0, rows, band):
                            bits[:] = 0
                            for c in range(len(cuts) - 1):
                                mark_boxes(nth_piece(prefix, low, start, cuts, c, buffer), offsets, float(side), radius,
                                           (shape[0], shape[1], shape[2]), g, bits, np.empty((0, 0), np.int64), row0)
                            total += least_count(bits)
                        count = total if count < 0 else min(count, total)
            else:
                route[k] = ONE_PASS if per_pass >= grids else PASSES
                for first in range(0, grids, per_pass):
                    stack = np.zeros((min(per_pass, grids - first), shape[0] * shape[1], (shape[2] + 63) // 64),
                                     np.uint64)
                    for c in range(len(cuts) - 1):
                        mark_boxes(nth_piece(prefix, low, start, cuts, c, buffer), offsets, float(side), radius,
                                   (shape[0], shape[1], shape[2]), first, stack, np.empty((0, 0), np.int64))
                    least = least_count(stack)
                    count = least if count < 0 else min(count, least)
                if per_pass < grids:
                    stack = np.empty((0, 0, 0), np.uint64)
        out[k] = count
        if kids[k] > 0:
            stacks[k], shapes[k] = stack, shape
        if m >= 0:
            kids[m] -= 1
            if kids[m] == 0:
                stacks[m] = np.empty((0, 0, 0), np.uint64)
