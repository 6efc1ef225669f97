"""Mass-radius and shape measures of point sets, and everything a sweep records of one cluster at once.

Pure functions of an ``(n, dim)`` point array (dim 2 or 3) in attachment
order; no I/O. Lengths are in lattice units (off-lattice: particle diameters).
Box counting is ``boxes``'s; ``cluster_measures`` gathers both into one
compiled call per cluster.
"""

from __future__ import annotations

import numpy as np

from ._jit import jit
from .boxes import PrefixBoxes, _prefix_counts, checked_points


def cluster_measures(points, ends, history, lattice: bool = True, scales=None, offsets: int = 4) -> dict:
    """Everything a sweep records of one cluster's prefixes, in one compiled call that releases the GIL.

    Equal, bit for bit, to the functions it gathers (a test holds them
    together); one call instead of five keeps a thread's Python time per
    cluster small next to the growth of a small cluster.

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
    positions = np.ascontiguousarray(boxes.points, dtype=np.float64)
    rg, rg_history, radius, shape = np.empty(len(boxes.ends)), np.empty(len(history)), np.empty(len(boxes.ends)), \
        np.empty(len(boxes.ends))
    _cluster_measures(positions, boxes.ends, history, rg, rg_history, radius, shape, *boxes.args)
    boxes.finish()
    return {"box_count": boxes.counts, "radius_gyration": rg, "radius_gyration_history": rg_history,
            "max_radius": radius, "anisotropy": shape}


@jit
def _cluster_measures(positions, ends, history, rg, rg_history, radius, shape, points, box_ends, integer, box_radius,
                      sides, own, n_own, order, parent, part, shift, cap, strip_words, counts, routes):
    """``cluster_measures``' figures, into the arrays given (the box counts as ``_prefix_counts`` leaves them)."""
    gyration = _prefix_gyration(positions)
    distances = _distances(positions)
    for c in range(1, len(distances)):
        distances[c] = max(distances[c], distances[c - 1])
    for c in range(len(ends)):
        rg[c], radius[c] = gyration[ends[c] - 1], distances[ends[c] - 1]
    for c in range(len(history)):
        rg_history[c] = gyration[history[c] - 1] if history[c] <= len(gyration) else np.nan
    shape[:] = _anisotropy(positions, ends)
    _prefix_counts(points, box_ends, integer, box_radius, sides, own, n_own, order, parent, part, shift, cap,
                   strip_words, counts, routes)


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
    return _prefix_gyration(np.ascontiguousarray(checked_points(points, np.float64)))


def _seed_distances(points) -> np.ndarray:
    return _distances(np.ascontiguousarray(checked_points(points, np.float64)))


@jit
def _distances(points):
    out = np.empty(len(points))
    for i in range(len(points)):
        r2 = 0.0
        for a in range(points.shape[1]):
            r2 += (points[i, a] - points[0, a]) ** 2
        out[i] = np.sqrt(r2)
    return out


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
    p = checked_points(points, np.float64)
    counts = np.asarray(counts, dtype=np.int64)
    if counts.size and not (1 <= counts.min() and counts.max() <= len(p)):
        raise ValueError(f"counts: expected prefix lengths in 1..{len(p)}")
    return _anisotropy(np.ascontiguousarray(p), counts.ravel()).reshape(counts.shape)


@jit
def _anisotropy(points, counts):
    dim = points.shape[1]
    top = counts.max() if len(counts) else 1
    r2, quartic = np.zeros(top), np.zeros(top)
    for i in range(1, top):
        for a in range(dim):
            u2 = (points[i, a] - points[0, a]) ** 2
            r2[i] += u2
            quartic[i] += u2 * u2
        quartic[i] /= r2[i] ** 2
    isotropic = 3.0 / (dim + 2)
    out = np.full(len(counts), np.nan)
    for c in range(len(counts)):
        m = counts[c]
        if m > 1:
            median = np.median(r2[1:m])
            total, outer = 0.0, 0
            for i in range(1, m):
                if r2[i] >= median:
                    total += quartic[i]
                    outer += 1
            if outer:
                out[c] = (total / outer - isotropic) / (1 - isotropic)
    return out
