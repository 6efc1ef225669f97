"""Mass-radius and shape measures of point sets, the diffusion times of a cluster by depth, and everything a
sweep records of one cluster at once.

Pure functions of an ``(n, dim)`` point array (dim 2 or 3) in attachment
order; no I/O. Lengths are in lattice units (off-lattice: particle diameters).
Box counting is ``boxes``'s; ``cluster_measures`` gathers both into one
compiled call per cluster.
"""

from __future__ import annotations

import numpy as np

from .._jit import jit
from .boxes import PrefixBoxes, _prefix_counts, checked_points


def cluster_measures(points, ends, history, lattice: bool = True, scales=None, offsets: int = 4) -> dict:
    """Everything a sweep records of one cluster's prefixes, in one compiled call that releases the GIL.

    Equal, bit for bit, to the functions it gathers (a test holds them
    together); one call instead of five keeps a thread's Python time per
    cluster small next to the growth of a small cluster. It reads the points
    as they are (int32 sites, float64 centres) and keeps no array of a value
    per particle: at 1e7 particles and more, the measurement must stay
    within the memory the growth needed.

    Parameters
    ----------
    points, ends
        As for ``prefix_box_counts``.
    history : array_like of int
        Prefix lengths >= 1 at which to record the radius of gyration; NaN beyond n.
    lattice, scales, offsets
        As for ``box_counts``.

    Returns
    -------
    dict
        ``box_count`` (``prefix_box_counts``'s counts), and at ``ends``:
        ``radius_gyration``, ``max_radius``, ``anisotropy``; at ``history``:
        ``radius_gyration_history``.
    """
    boxes = PrefixBoxes(points, ends, lattice, scales, offsets)
    history = np.asarray(history, np.int64).ravel()
    if history.size and history.min() < 1:
        raise ValueError("history: expected prefix lengths >= 1")
    n_ends = len(boxes.ends)
    rg, rg_history, radius, shape = np.empty(n_ends), np.empty(len(history)), np.empty(n_ends), np.empty(n_ends)
    _cluster_measures(boxes.points, boxes.ends, history, rg, rg_history, radius, shape, *boxes.args)
    boxes.finish()
    return {"box_count": boxes.counts, "radius_gyration": rg, "radius_gyration_history": rg_history,
            "max_radius": radius, "anisotropy": shape}


@jit
def _cluster_measures(positions, ends, history, rg, rg_history, radius, shape, points, box_ends, integer, box_radius,
                      sides, own, n_own, order, parent, part, shift, cap, strip_words, piece, counts, routes):
    """``cluster_measures``' figures, into the arrays given (the box counts as ``_prefix_counts`` leaves them)."""
    past = history > len(positions)
    _prefix_radii(positions, ends, rg, radius)
    _prefix_radii(positions, np.minimum(history, len(positions)), rg_history, np.empty(len(history)))
    for c in range(len(history)):
        if past[c]:
            rg_history[c] = np.nan
    shape[:] = _anisotropy(positions, ends, MEDIAN_GATHER)
    _prefix_counts(points, box_ends, integer, box_radius, sides, own, n_own, order, parent, part, shift, cap,
                   strip_words, piece, counts, routes)


@jit
def _prefix_radii(points, lengths, rg, radius):
    """The radius of gyration and the largest distance from the first point (the seed) of the prefixes of
    ``lengths`` (each in 1..n, in any order), into ``rg`` and ``radius``: one pass, no array per point.

    Rg by Welford's update of the running mean and sum of squares (each
    increment is delta**2 * k/(k+1) >= 0: no cancellation), in float64.
    """
    n, dim = points.shape
    order = np.argsort(lengths)
    mean = np.zeros(dim)
    spread, farthest = 0.0, 0.0
    at = 0
    for k in range(n):
        if at == len(order):
            break
        for a in range(dim):
            x = float(points[k, a])
            delta = x - mean[a]
            mean[a] += delta / (k + 1)
            spread += delta * (x - mean[a])
        farthest = max(farthest, _seed_distance(points, k))
        while at < len(order) and lengths[order[at]] == k + 1:
            rg[order[at]] = np.sqrt(spread / (k + 1))
            radius[order[at]] = farthest
            at += 1


@jit
def _seed_distance(points, i):
    """The distance of point i from the first (the seed), in float64 whatever the points' type."""
    r2 = 0.0
    for a in range(points.shape[1]):
        r2 += (float(points[i, a]) - float(points[0, a])) ** 2
    return np.sqrt(r2)


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
    return _every_prefix(points)[0]


def max_radius(points) -> np.ndarray:
    """Largest centre distance from the first point (the seed) in every prefix.

    Returns
    -------
    ndarray of float64, (n,)
    """
    return _every_prefix(points)[1]


def _every_prefix(points):
    """``_prefix_radii`` of every prefix: (rg, radius)."""
    p = np.ascontiguousarray(checked_points(points, np.float64))
    rg, radius = np.empty(len(p)), np.empty(len(p))
    _prefix_radii(p, np.arange(1, len(p) + 1), rg, radius)
    return rg, radius


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
    p = checked_points(points, np.float64)
    counts = np.asarray(counts, dtype=np.int64)
    if counts.size and not (1 <= counts.min() and counts.max() <= len(p)):
        raise ValueError(f"counts: expected prefix lengths in 1..{len(p)}")
    return _anisotropy(np.ascontiguousarray(p), counts.ravel(), MEDIAN_GATHER).reshape(counts.shape)


def time_depth_pairs(points, times, edges):
    """The distinct keys ``time * bins + depth bin`` of particles 1.. of one cluster, sorted, and their counts.

    The depth is the distance from the seed over the largest (at least 1),
    binned by ``edges`` (``len(edges) - 1`` bins, as ``np.digitize`` gives
    them, clipped). ``np.unique``'s answer without an array of keys: a 1e8
    cluster's would take 8e8 bytes, and its sort as much again.

    Parameters
    ----------
    points : ndarray, (n, dim)
    times : ndarray of unsigned int, (n,)
        The particles' diffusion times.
    edges : ndarray, ascending from 0 to 1

    Returns
    -------
    keys, counts : ndarray of int64
    """
    # a count per (time, bin) up to a time the cluster's size bounds; the rare longer times one by one
    dense = min(int(times.max()) + 1, max(1024, 4 * len(times)))
    table, tail = _time_depth_counts(points, times, np.asarray(edges, np.float64), dense)
    keys = np.flatnonzero(table)
    tail_keys, tail_counts = np.unique(tail, return_counts=True)
    return np.r_[keys, tail_keys], np.r_[table.ravel()[keys], tail_counts]


@jit
def _time_depth_counts(points, times, edges, dense):
    """``time_depth_pairs``' counts: of (time, bin) in a table for times below ``dense``, and the keys of
    the others. Distances in float64 as numpy takes them; the bin as ``np.digitize`` gives it, clipped."""
    n, dim = points.shape
    bins = len(edges) - 1
    far = 1.0
    for i in range(n):
        far = max(far, _seed_distance(points, i))
    table = np.zeros((dense, bins), np.int64)
    late = 0
    for i in range(1, n):
        late += times[i] >= dense
    tail = np.empty(late, np.int64)
    late = 0
    for i in range(1, n):
        slot = min(max(np.searchsorted(edges, _seed_distance(points, i) / far, side="right") - 1, 0), bins - 1)
        t = np.int64(times[i])
        if t < dense:
            table[t, slot] += 1
        else:
            tail[late] = t * bins + slot
            late += 1
    return table, tail


MEDIAN_GATHER = 1 << 16
"""``_kth_smallest`` sorts the candidates once at most this many are left."""


@jit
def _squared_distance_and_quartic(points, i):
    """|u|**2 of point i from the seed, and sum_a u_a**4 / |u|**4: ``_anisotropy``'s two figures of it."""
    r2, quartic = 0.0, 0.0
    for a in range(points.shape[1]):
        u2 = (float(points[i, a]) - float(points[0, a])) ** 2
        r2 += u2
        quartic += u2 * u2
    return r2, quartic / r2**2


@jit
def _anisotropy(points, counts, gather):
    dim = points.shape[1]
    isotropic = 3.0 / (dim + 2)
    out = np.full(len(counts), np.nan)
    for c in range(len(counts)):
        m = counts[c]
        if m > 1:
            # the median of the m - 1 squared distances, as np.median takes it
            half = (m - 1) // 2
            median = _kth_smallest(points, m, half, gather)
            if (m - 1) % 2 == 0:
                median = (_kth_smallest(points, m, half - 1, gather) + median) / 2
            total, outer = 0.0, 0
            for i in range(1, m):
                r2, quartic = _squared_distance_and_quartic(points, i)
                if r2 >= median:
                    total += quartic
                    outer += 1
            if outer:
                out[c] = (total / outer - isotropic) / (1 - isotropic)
    return out


@jit
def _kth_smallest(points, m, k, gather):
    """The k-th smallest (from 0) squared distance from the seed of points 1..m-1, exactly, without an
    array of them all: histograms narrow the range of values that holds it until at most ``gather``
    remain, which are then sorted. Bins are monotone in the value, so whole bins below it only count."""
    bins = 4096
    lo, hi = np.inf, -np.inf
    for i in range(1, m):
        r2, _ = _squared_distance_and_quartic(points, i)
        lo, hi = min(lo, r2), max(hi, r2)
    below, inside = 0, m - 1  # values under lo; values within [lo, hi]
    hist = np.zeros(bins, np.int64)
    while True:
        if lo == hi:
            return lo
        if inside <= gather:
            break
        scale = bins / (hi - lo)
        if not np.isfinite(scale):  # a range too narrow to split
            break
        hist[:] = 0
        for i in range(1, m):
            r2, _ = _squared_distance_and_quartic(points, i)
            if lo <= r2 <= hi:
                hist[min(np.int64((r2 - lo) * scale), bins - 1)] += 1
        b, under = 0, below
        while under + hist[b] <= k:
            under += hist[b]
            b += 1
        new_lo, new_hi = np.inf, -np.inf
        for i in range(1, m):
            r2, _ = _squared_distance_and_quartic(points, i)
            if lo <= r2 <= hi and min(np.int64((r2 - lo) * scale), bins - 1) == b:
                new_lo, new_hi = min(new_lo, r2), max(new_hi, r2)
        if hist[b] == inside:  # no narrower: sort them all
            break
        below, inside, lo, hi = under, hist[b], new_lo, new_hi
    values = np.empty(inside)
    j = 0
    for i in range(1, m):
        r2, _ = _squared_distance_and_quartic(points, i)
        if lo <= r2 <= hi:
            values[j] = r2
            j += 1
    values.sort()
    return values[k - below]
